"""Single-file HTML reports (jinja2 template, inline CSS and SVG, no scripts, no network)."""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from markupsafe import Markup, escape

from ..base.atomic import atomic_write_text
from ..base.format import readable
from ..design.search_messages import comparison_words
from ..results import Certificate, Check, Verdict, to_jsonable
from .cells import margin_text, number, value_text, verdict_class, verdict_label

__all__ = [
    "render_report",
    "render_fragment",
    "write_report",
    "certificate_fragment",
    "check_fragment",
]

CSS = """
.ssecert-report{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;color:#1d1d1f;
 max-width:1100px;margin:0 auto;padding:1rem 1.5rem;line-height:1.45}
.ssecert-report h1{margin:.2rem 0;font-size:1.7rem}.ssecert-report h2{margin-top:2rem;
 border-bottom:1px solid #ddd;padding-bottom:.2rem}.ssecert-report h3{margin-bottom:.3rem}
.ssecert-report .eyebrow{text-transform:uppercase;font-size:.75rem;letter-spacing:.08em;color:#666}
.ssecert-report .head{border-left:8px solid #999;padding:.6rem 1rem;background:#f7f7f8}
.ssecert-report .head.holds{border-color:#1b7f3b}.ssecert-report .head.fails{border-color:#b3261e}
.ssecert-report .head.inconclusive{border-color:#a36b00}
.ssecert-report .badge{display:inline-block;padding:.08rem .55rem;border-radius:999px;
 font-size:.8rem;font-weight:600;color:#fff;vertical-align:middle}
.ssecert-report .badge.holds{background:#1b7f3b}.ssecert-report .badge.fails{background:#b3261e}
.ssecert-report .badge.inconclusive{background:#a36b00}
.ssecert-report .badge.not-applicable{background:#6e6e76}
.ssecert-report .badge{white-space:nowrap}
.ssecert-report .qname{display:block;color:#555;font-size:.75rem}
.ssecert-report .qnum{white-space:nowrap;font-variant-numeric:tabular-nums}
.ssecert-report td.quantity{min-width:6rem;max-width:11rem}
.ssecert-report table.matrix th{font-family:ui-monospace,monospace;font-size:.75rem;
 font-weight:normal;color:#555}
.ssecert-report .params th{font-family:ui-monospace,monospace;font-weight:normal}
.ssecert-report table{border-collapse:collapse;margin:.5rem 0;font-size:.9rem}
.ssecert-report th,.ssecert-report td{border:1px solid #e1e1e4;padding:.25rem .5rem;
 text-align:left;vertical-align:top}
.ssecert-report th{background:#f2f2f4}.ssecert-report td.num{text-align:right;
 font-variant-numeric:tabular-nums;white-space:nowrap}
.ssecert-report td.finding{max-width:480px}.ssecert-report table.identity{font-size:.8rem}
.ssecert-report table.matrix td{font-family:ui-monospace,monospace;font-size:.75rem;text-align:right}
.ssecert-report figure{margin:.8rem 0}.ssecert-report figure svg{max-width:100%;height:auto}
.ssecert-report figcaption{font-size:.8rem;color:#555}
.ssecert-report details{margin:.4rem 0}.ssecert-report summary{cursor:pointer;color:#1f5fa8}
.ssecert-report .sensor-list li.breaking{color:#b3261e}
.ssecert-report pre{background:#f2f2f4;padding:.6rem;overflow-x:auto}
.ssecert-report article.check{border-top:1px solid #eee;padding-top:.4rem}
"""

MAX_ROWS = 14
MAX_COLS = 14
# the plant's and the observer's matrices: larger ones are shown truncated, with their shape
DESIGN_ROWS = 12
DESIGN_COLS = 12


def _template(name: str) -> Any:
    from jinja2 import Environment, select_autoescape

    text = resources.files("ssecert.report").joinpath("templates", name).read_text()
    env = Environment(
        autoescape=select_autoescape(default=True, default_for_string=True),
        trim_blocks=True,
        lstrip_blocks=True,
    )
    return env.from_string(text)


def _fmt(value: Any, digits: int = 6) -> str:
    """A scalar of the evidence: six significant digits (the JSON has every digit)."""
    return number(value, digits)


def _exact_title(value: Any, shown: str) -> str:
    """A title attribute with the float's every digit, when the text shown rounds it."""
    if isinstance(value, (float, np.floating)) and math.isfinite(float(value)):
        try:
            if float(shown) == float(value):
                return ""
        except ValueError:  # "1 - 3.3e-16"
            pass
        return f' title="{escape(repr(float(value)))}"'
    return ""


def _scalar(value: Any, digits: int = 6) -> str:
    """HTML of a scalar: rounded, with the exact value on hover."""
    shown = _fmt(value, digits)
    title = _exact_title(value, shown)
    return f"<span{title}>{escape(shown)}</span>" if title else str(escape(shown))


def _render(value: Any, depth: int = 0) -> str:
    """HTML for an evidence value: scalars inline, arrays as tables, mappings nested."""
    if isinstance(value, Mapping) and set(value) == {"re", "im"}:
        return escape(_fmt(value))
    if isinstance(value, (float, np.floating)):
        return _scalar(value)
    if isinstance(value, Mapping):
        if not value:
            return "-"
        rows = "".join(
            f"<tr><th>{escape(str(k))}</th><td>{_render(v, depth + 1)}</td></tr>"
            for k, v in value.items()
        )
        return f"<table class='kv'>{rows}</table>"
    if isinstance(value, (list, tuple, np.ndarray)):
        arr = None
        try:
            arr = np.asarray(value)
        except (ValueError, TypeError):
            arr = None
        if arr is not None and arr.dtype.kind in "biufc" and arr.ndim in (1, 2) and arr.size:
            return _matrix(arr)
        if arr is not None and arr.dtype.kind in "biufc" and arr.ndim > 2 and arr.size:
            return _stack(arr)
        items = list(value)
        if not items:
            return "[]"
        if all(isinstance(it, Mapping) for it in items):
            keys = list(dict.fromkeys(k for it in items for k in it))
            head = "".join(f"<th>{escape(k)}</th>" for k in keys)
            body = "".join(
                "<tr>"
                + "".join(f"<td>{_render(it.get(k), depth + 1)}</td>" for k in keys)
                + "</tr>"
                for it in items[:MAX_ROWS]
            )
            more = (
                f"<p>... {len(items) - MAX_ROWS} more rows in the JSON</p>"
                if len(items) > MAX_ROWS
                else ""
            )
            return f"<table class='kv'><tr>{head}</tr>{body}</table>{more}"
        return escape(
            ", ".join(_fmt(it) for it in items[:50]) + (" ..." if len(items) > 50 else "")
        )
    return escape(_fmt(value))


def _stack(arr: np.ndarray) -> str:
    """A stack of matrices (a numeric array of 3 or more dimensions): the first ``MAX_ROWS``
    along its first axis, each as a matrix, folded."""
    shape = " x ".join(str(d) for d in arr.shape)
    shown = "".join(_matrix(np.reshape(a, (a.shape[0], -1))) for a in arr[:MAX_ROWS])
    note = f"<p>the first {MAX_ROWS} shown, all in the JSON</p>" if arr.shape[0] > MAX_ROWS else ""
    return f"<details><summary>{shape} array</summary>{shown}{note}</details>"


def _cell(value: Any, digits: int = 6) -> str:
    """A matrix entry: rounded, with the exact value on hover."""
    if isinstance(value, np.generic):
        value = value.item()
    shown = _fmt(value, digits)
    return f"<td{_exact_title(value, shown)}>{escape(shown)}</td>"


def _matrix(arr: np.ndarray) -> str:
    if arr.ndim == 1:
        arr = arr[None, :]
    r, c = arr.shape
    shown = arr[:MAX_ROWS, :MAX_COLS]
    rows = "".join("<tr>" + "".join(_cell(v) for v in row) + "</tr>" for row in shown)
    note = ""
    if r > MAX_ROWS or c > MAX_COLS:
        note = f"<p>{r} x {c}; the first {min(r, MAX_ROWS)} x {min(c, MAX_COLS)} shown, all in the JSON</p>"
    table = f"<table class='matrix'>{rows}</table>{note}"
    if r * c > 12:
        return f"<details><summary>{r} x {c} matrix</summary>{table}</details>"
    return table


def _check_context(check: Check) -> dict[str, Any]:
    data = to_jsonable(check.to_dict())
    skip = {
        "verdict",
        "title",
        "summary",
        "required",
        "value",
        "margin",
        "method",
        "evidence",
        "tolerances",
        "witness",
    }
    skip |= {"applies", "value_name", "margin_name"}
    fields = [(k, Markup(_render(v))) for k, v in data.items() if k not in skip]
    return {
        "id": check.id,
        "title": check.title,
        "verdict": check.verdict.value,
        "label": verdict_label(check),
        "css": verdict_class(check),
        "value": value_text(check),
        "value_name": check.value_name,
        "margin": margin_text(check),
        "margin_name": check.margin_name,
        # a value in words (1 - 8.67e-19) is not the float's rounding: no float on hover
        "value_exact": "" if check.value_text else _exact_title(check.value, value_text(check)),
        "margin_exact": _exact_title(check.margin, margin_text(check)),
        "required": check.required,
        "method": check.method,
        "summary": check.summary,
        "fields": fields,
        "tolerances": [(k, _fmt(v)) for k, v in (data.get("tolerances") or {}).items()],
        "evidence": Markup(_render(data.get("evidence") or {})),
        "witness": Markup(_render(data["witness"])) if data.get("witness") else None,
    }


def _slug(text: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-") or "scenario"


def _context(result: Any, *, fragment: bool) -> dict[str, Any]:
    """What the report template shows of a ``CertifyResult``: verdict, checks, plots."""
    cert: Certificate = result.certificate
    spec = result.spec
    meta = dict(cert.meta or {})
    ctx: dict[str, Any] = {
        "fragment": fragment,
        "css": Markup(CSS),
        "name": spec.name,
        "verdict": cert.verdict.value,
        "exit_code": cert.exit_code,
        "headline": _headline(cert),
        "identity": _identity(result, meta),
        "design": _design_context(spec, cert),
        "checks": [_check_context(c) for c in cert.checks],
        "notes": list(result.notes) + list(meta.get("notes", [])),
        "command": result.command,
    }
    sparse = cert.get("sparse_observability")
    if sparse is not None and sparse.verdict is Verdict.FAILS:
        ctx.update(_breaking_set_context(spec.system, spec.max_attacked, sparse))
    if result.stealthy is not None:
        ctx.update(_stealthy_context(spec.system, result.stealthy))
    ctx["simulations"] = _simulation_rows(result.simulations)
    noise = _noise_context(spec.system, cert, result.simulations)
    if noise:
        ctx["noise"] = noise
    if result.region is not None:
        ctx["region_svg"] = _region_svg(result.region, spec.observer)
    comparison = getattr(result, "comparison", None)
    if comparison is not None:
        ctx["comparison"] = _comparison_context(comparison)
    return ctx


def _labelled_matrix(
    arr: np.ndarray, rows: list[str], cols: list[str], name: str, where: str
) -> Markup:
    """A matrix with its rows and columns named; beyond DESIGN_ROWS x DESIGN_COLS the corner
    is shown, with the shape and where the whole matrix is."""
    arr = np.atleast_2d(np.asarray(arr))
    r, c = arr.shape
    shown = arr[:DESIGN_ROWS, :DESIGN_COLS]
    head = "<tr><th></th>" + "".join(f"<th>{escape(x)}</th>" for x in cols[:DESIGN_COLS])
    head += "<th>...</th></tr>" if c > DESIGN_COLS else "</tr>"
    body = "".join(
        f"<tr><th>{escape(rows[i])}</th>"
        + "".join(_cell(v, 4) for v in row)
        + ("<td>...</td>" if c > DESIGN_COLS else "")
        + "</tr>"
        for i, row in enumerate(shown)
    )
    if r > DESIGN_ROWS:
        body += "<tr><th>...</th></tr>"
    digits = "to 4 significant digits (hover an entry for all of its digits)"
    if r > DESIGN_ROWS or c > DESIGN_COLS:
        note = (
            f"{name} is {r} x {c}: its first {min(r, DESIGN_ROWS)} x {min(c, DESIGN_COLS)} "
            f"entries are shown {digits}; every entry is in the JSON certificate, {where}."
        )
    else:
        note = f"{name} is {r} x {c}, shown {digits}; the JSON certificate has it as {where}."
    return Markup(
        f"<table class='matrix labelled' id='matrix-{escape(name)}'>{head}{body}</table>"
        f"<p class='shape'>{escape(note)}</p>"
    )


def _gain_columns(system: Any, columns: int) -> list[str]:
    """Column names of a gain: the sensors, or for a stacked window (SSO) each sensor at each
    block C A^j of O_tau."""
    p = system.p
    if columns == p:
        return list(system.sensors)
    if columns % p == 0:
        return [f"{name} [C A^{j}]" for j in range(columns // p) for name in system.sensors]
    return [str(j + 1) for j in range(columns)]


def _design_context(spec: Any, cert: Certificate) -> dict[str, Any]:
    """The plant (A, C with the sensors' names), the attack budget and the observer (its kind,
    parameters and the gain L it was built with)."""
    system = spec.system
    states = [f"x{i + 1}" for i in range(system.n)]
    out: dict[str, Any] = {
        "A": _labelled_matrix(system.A, states, states, "A", "spec.system.A"),
        "C": _labelled_matrix(system.C, list(system.sensors), states, "C", "spec.system.C"),
        "n": system.n,
        "p": system.p,
        "s": spec.max_attacked,
        "horizon": spec.horizon,
        "observer": None,
    }
    observer = spec.observer
    if not observer:
        return out
    params: list[tuple[str, Markup]] = []
    for key, value in observer.items():
        if key == "kind":
            continue
        if key == "gain" and not isinstance(value, str):
            params.append((key, Markup("a matrix given in the spec (below)")))
        elif isinstance(value, np.ndarray) and value.ndim == 2:
            rows = [str(i + 1) for i in range(value.shape[0])]
            cols = [str(j + 1) for j in range(value.shape[1])]
            params.append((key, _labelled_matrix(value, rows, cols, key, f"spec.observer.{key}")))
        elif isinstance(value, (list, tuple, np.ndarray)):
            params.append((key, Markup(escape(", ".join(number(v) for v in value)))))
        else:
            params.append((key, Markup(_scalar(value))))
    gain_check = cert.get("observer_gain")
    L = None if gain_check is None else gain_check.fields.get("L")
    gain: Markup | str
    if L is not None:
        L = np.atleast_2d(np.asarray(L, dtype=float))
        cols = _gain_columns(system, L.shape[1])
        gain = _labelled_matrix(L, states, cols, "L", "checks.observer_gain.L")
    else:
        gain = "not computed: " + gain_check.summary if gain_check is not None else "not computed"
    method = observer.get("gain")
    if method is None and gain_check is not None:  # a kind whose gain follows from its step
        method = gain_check.fields.get("gain_method")
    out["observer"] = {
        "kind": observer.get("kind"),
        "gain_method": method if isinstance(method, str) else None,
        "gain_spec": observer.get("gain") if isinstance(observer.get("gain"), str) else None,
        "params": params,
        "L": gain,
    }
    return out


def _comparison_context(comparison: Mapping[str, Any]) -> dict[str, Any]:
    """The design command's side-by-side table: each design's parameters and certified
    numbers, then per scenario the final mean error and settling step of each."""
    labels = [d["design"] for d in comparison["designs"]]
    designs = []
    for d in comparison["designs"]:
        params = ", ".join(
            f"{k} {_fmt(d[k])}" for k in ("gain", "step", "threshold", "shrink") if k in d
        )
        designs.append(
            {
                "label": "the spec's design" if d["design"] == "spec" else "synthesised",
                "kind": d.get("kind"),
                "params": params,
                "stability": d.get("observer_stability", "-"),
                "linear": _fmt(d.get("linear_radius")),
                "gamma": _fmt(d.get("iss_gain_value")) if "iss_gain_value" in d else "none",
                "radius": _fmt(d.get("region_of_attraction_value"))
                if "region_of_attraction_value" in d
                else "-",
                "noise": _fmt(d.get("observer_noise_bound_value"))
                if "observer_noise_bound_value" in d
                else "-",
            }
        )
    rows = []
    for r in comparison["scenarios"]:
        cells = []
        for label in labels:
            sim = r.get(label, {})
            if "skipped" in sim or not sim:
                cells += [sim.get("skipped", "-"), "-", "-"]
            else:
                settle = sim.get("settling_step")
                cells += [
                    _fmt(sim.get("mean_error")),
                    _fmt(sim["final_mean"]),
                    "-" if settle is None else str(settle),
                ]
        verdict = comparison_words(r["comparison"]) if "comparison" in r else "-"
        rows.append({"name": r["scenario"], "cells": cells, "verdict": verdict})
    out: dict[str, Any] = {
        "designs": designs,
        "noise_column": any("observer_noise_bound" in d for d in comparison["designs"]),
        "labels": ["the spec's design" if x == "spec" else "synthesised" for x in labels],
        "rows": rows,
        "summary": comparison["summary"],
    }
    tradeoff = comparison.get("tradeoff")
    if tradeoff:
        from .plots import tradeoff_plot

        out["tradeoff_svg"] = Markup(tradeoff_plot(tradeoff))
        out["choice"] = tradeoff.get("choice", "")
    return out


def _identity(result: Any, meta: Mapping[str, Any]) -> list[tuple[str, str]]:
    """The report's identity rows: design, spec file and hash, seed, date, versions."""
    spec = result.spec
    system = spec.system
    versions = meta.get("versions", {})
    return [
        (
            "design",
            f"{spec.name}: n = {system.n} states, p = {system.p} sensors, "
            f"s = {spec.max_attacked} attacked, horizon {spec.horizon}",
        ),
        ("spec file", spec.source),
        ("spec sha256", spec.sha256 or "-"),
        ("seed", str(result.seed)),
        ("date", meta.get("date", "-")),
        ("versions", ", ".join(f"{k} {v}" for k, v in versions.items())),
    ]


def _headline(cert: Certificate) -> str:
    """The first failing required check's finding, else the first undecided one's."""
    failing = [c for c in cert.checks if c.required and c.verdict is Verdict.FAILS]
    undecided = [c for c in cert.checks if c.required and c.verdict is Verdict.INCONCLUSIVE]
    if failing:
        return failing[0].summary
    if undecided:
        return undecided[0].summary
    return "Every required check holds."


def _noise_source_rows(cert: Certificate) -> list[tuple[str, str]]:
    """With process noise: the measurement and process noise the decoders' bounds come from,
    and what they add up to at the sensors over the window (the ``noise`` the bounds are
    certified for)."""
    for key in ("decoder_error_bound", "l1_error_bound", "lasso_error_bound"):
        check = cert.get(key)
        if check is None:
            continue
        sources = check.fields.get("noise_sources")
        if sources is None or "process" not in sources:
            continue
        seen = np.asarray(check.fields["noise"]["measurement"], dtype=float)
        return [
            ("measurement noise: largest bound", readable(float(np.max(sources["measurement"])))),
            (
                "process noise x+ = A x + G w: largest bound of an entry of w",
                readable(float(np.max(sources["process"]))),
            ),
            (
                f"both at the sensors over the window of {check.fields['horizon']} steps: "
                "largest bound",
                readable(float(np.max(seen))) if seen.size else "0",
            ),
        ]
    return []


def _noise_context(
    system: Any, cert: Certificate, simulations: dict[str, Any]
) -> dict[str, Any] | None:
    """The error bounds under noise: the decoder's (bound, lower bound, the set to harden, its
    curve) and the observer's, beside the attack-free simulations' largest errors."""
    from .plots import hardening_plot

    decoder, observer = cert.get("decoder_error_bound"), cert.get("observer_noise_bound")
    if decoder is None and observer is None and cert.get("lasso_error_bound") is None:
        return None  # the decoders' bounds come together
    rows: list[tuple[str, str]] = _noise_source_rows(cert)
    svg = None
    if decoder is not None and decoder.verdict is Verdict.HOLDS:
        kept = ", ".join(system.sensors[i] for i in decoder.fields["worst_kept_sensors"])
        rows += [
            ("l0 decoder: certified bound of ||x_hat - x||", readable(decoder.fields["bound"])),
            ("no decoder guarantees less than", readable(decoder.fields["lower_bound"])),
            ("the sensors whose bound is the largest (to harden)", kept),
            ("their noise halved: the bound", readable(decoder.fields["hardened_bound"])),
        ]
        curve = decoder.evidence.get("hardening_curve")
        if curve:
            svg = Markup(
                hardening_plot(
                    curve["scale"], curve["bound"], float(decoder.fields["lower_bound"]), kept
                )
            )
    elif decoder is not None:
        rows.append(("l0 decoder", decoder.summary))
    l1 = cert.get("l1_error_bound")
    if l1 is not None and l1.verdict is Verdict.HOLDS:
        rows += [
            ("l1 decoder: certified bound of ||x_hat - x||", readable(l1.fields["bound"])),
            ("l1 decoder: largest null-space constant", readable(l1.fields["null_space_constant"])),
        ]
        if l1.fields.get("lower_bound"):
            rows.append(
                (
                    "l1 decoder: its error on a window built for it",
                    readable(l1.fields["lower_bound"]),
                )
            )
    elif l1 is not None:
        rows.append(("l1 decoder", l1.summary))
    lasso = cert.get("lasso_error_bound")
    if lasso is not None and lasso.verdict is Verdict.HOLDS:
        f = lasso.fields
        rows += [
            (
                "Lasso decoder: certified bound of ||x_hat - x|| for every lambda > "
                f"{readable(f['lambda_min'])}",
                f"{readable(f['noise_term'])} + {readable(f['bias_per_lambda'])} lambda "
                f"({readable(f['bound'])} as lambda comes down to {readable(f['lambda_min'])})",
            ),
            (
                "Lasso decoder: largest irrepresentable constant",
                readable(f["irrepresentable_constant"]),
            ),
        ]
        if f.get("lower_bound") is not None:
            rows.append(
                (
                    "Lasso decoder: reached by an explicit attack and noise",
                    readable(f["lower_bound"]),
                )
            )
    elif lasso is not None:
        rows.append(("Lasso decoder", lasso.summary))
    if observer is not None and observer.verdict is Verdict.HOLDS:
        rows.append(
            ("observer: certified ultimate bound of ||x_hat - x||", readable(observer.value))
        )
        if observer.fields.get("region_radius") is not None:
            rows.append(
                (
                    "observer: the bound holds from the initial errors within (dead zone)",
                    readable(observer.fields["region_radius"]),
                )
            )
        if observer.fields.get("lower_bound"):
            rows.append(
                ("some noise drives a component to", readable(observer.fields["lower_bound"]))
            )
        if observer.fields.get("hardened_bound") is not None:
            worst = observer.fields.get("worst_sensor")
            rows += [
                (
                    "observer: the sensor to harden",
                    worst if worst is not None else "none singled out (several lower it alike)",
                ),
                ("its noise halved: the bound", readable(observer.fields["hardened_bound"])),
            ]
    elif observer is not None:
        rows.append(("observer", observer.summary))
    for name, res in simulations.items():
        beside = getattr(res, "certified_bound", None)
        if beside:
            if beside["within"] is None:
                verdict = (
                    f"not resolved: the simulated state's own rounding, about "
                    f"{readable(beside['state_rounding'])}, exceeds the bound"
                )
            else:
                verdict = "within the bound" if beside["within"] else "ABOVE the bound"
            rows.append(
                (
                    f"simulation {name}: largest error from step {beside['from_step']}",
                    f"{readable(beside['observed_max'])} ({verdict})",
                )
            )
    return {"rows": rows, "svg": svg}


def _breaking_set_context(system: Any, s: int, sparse: Check) -> dict[str, Any]:
    """The sensor plot, list and sentence of a failing sparse-observability check."""
    from .plots import sensor_plot

    breaking = sparse.fields.get("breaking_set") or []
    return {
        "sensors_svg": Markup(sensor_plot(system.sensors, breaking)),
        "breaking_names": ", ".join(system.sensors[i] for i in breaking) or "none",
        "sensor_rows": [
            {"name": nm, "index": i, "breaking": i in set(breaking)}
            for i, nm in enumerate(system.sensors)
        ],
        "why_sentence": _why(system, s, sparse),
    }


def _stealthy_context(system: Any, demo: dict[str, Any]) -> dict[str, Any]:
    """The stealthy attack's plot, output mismatch and sentence."""
    from .plots import stealthy_plot

    return {
        "stealthy_svg": Markup(stealthy_plot(system, demo)),
        "stealthy_residual": _fmt(demo["residual"]),
        "stealthy_text": _stealthy_text(system, demo),
    }


def _simulation_rows(simulations: Mapping[str, Any]) -> list[dict[str, Any]]:
    """One table row (with its plot) per simulated scenario, each with a unique id."""
    rows = []
    slugs: set[str] = set()
    for name, res in simulations.items():
        slug = _unique_slug(name, slugs)
        slugs.add(slug)
        if isinstance(res, Mapping):
            rows.append(_skipped_row(name, res, slug))
        else:
            rows.append(_simulation_row(name, res, slug))
    return rows


def _unique_slug(name: str, taken: set[str]) -> str:
    """The scenario's id: its slug, numbered when names differ only in punctuation."""
    slug = _slug(name)
    if slug in taken:
        slug = next(f"{slug}-{i}" for i in range(2, len(taken) + 3) if f"{slug}-{i}" not in taken)
    return slug


def _skipped_row(name: str, res: Mapping[str, Any], slug: str) -> dict[str, Any]:
    """The row of a scenario that was not simulated, with the reason."""
    return {
        "name": name,
        "attack": "-",
        "runs": "-",
        "steps": "-",
        "abs": "-",
        "initial": "-",
        "rel": "-",
        "q90": "-",
        "support": "-",
        "delay": "-",
        "svg": None,
        "skipped": res.get("skipped", ""),
        "slug": slug,
    }


def _simulation_row(name: str, res: Any, slug: str) -> dict[str, Any]:
    """The row of a simulated scenario: final-step metrics and the error plot."""
    from .plots import simulation_plot

    final = res.final()
    return {
        "name": name,
        "attack": res.attack,
        "runs": res.runs,
        "steps": res.steps,
        "abs": _fmt(final.get("absolute_error_mean")),
        "q90": _fmt(final.get("absolute_error_q90")),
        "initial": _fmt(final.get("initial_relative_error_mean")),
        "rel": _fmt(final["relative_error_mean"]),
        "support": _fmt(final["support_error_mean"]),
        "delay": _fmt(final.get("detection_delay_median")),
        "svg": Markup(simulation_plot(name, res, gid=f"sim-{slug}")),
        "slug": slug,
    }


def _region_svg(region: Any, observer: Mapping[str, Any] | None) -> Markup:
    """The certified (shrink, step) map, with the design's own point when it has a step."""
    from .plots import region_plot

    obs = observer or {}
    point = None
    if "step" in obs:
        point = (float(obs.get("shrink", 1.0)), float(obs["step"]))
    return Markup(region_plot(region, point))


def _why(system: Any, s: int, check: Check) -> str:
    breaking = check.fields.get("breaking_set") or []
    names = ", ".join(system.sensors[i] for i in breaking)
    mr = check.fields.get("max_removable")
    if mr == -1:
        return (
            "The plant is not observable even with every sensor intact, so no number of "
            "attacked sensors can be corrected."
        )
    plural = "sensor" if s == 1 else "sensors"
    if len(breaking) <= s:
        return (
            f"{s} attacked {plural} cannot be corrected because removing {names} leaves "
            f"the plant unobservable: an attacker who controls {names} can make the state "
            f"look like a different one, and no estimator can tell them apart."
        )
    return (
        f"{s} attacked {plural} cannot be corrected because removing the {len(breaking)} "
        f"sensors {names} leaves the plant unobservable: split into two groups of at most "
        f"{s}, they give two attacks that make two different states produce the same "
        f"outputs."
    )


def _stealthy_text(system: Any, demo: Mapping[str, Any]) -> str:
    a = ", ".join(system.sensors[i] for i in demo["sensors_a"]) or "no sensor"
    b = ", ".join(system.sensors[i] for i in demo["sensors_b"])
    scale = demo.get("time_scale_log2")
    units = (
        f" The plant's own signals grow beyond the floating-point range, so they are shown for "
        f"2^{scale} A: at step k each is 2^({scale} k) times the plant's (sensor by sensor, up "
        f"to a power of two)."
        if scale is not None
        else ""
    )
    if b:
        return (
            f"One plant starts at x0 with an attack on {a}; another starts at x0 + z with an "
            f"attack on {b}. Their outputs coincide at every step.{units}"
        )
    return (
        f"The plant starts at x0 and the attacker corrupts {a} only; the outputs are exactly "
        f"those of the unattacked plant started at x0 + z. The attack is undetectable.{units}"
    )


def render_report(result: Any) -> str:
    """The complete single-file HTML report of a ``CertifyResult``."""
    return _template("report.html.j2").render(**_context(result, fragment=False))


def render_fragment(result: Any) -> str:
    """The report's body as an HTML fragment with its own style (Jupyter)."""
    return _template("report.html.j2").render(**_context(result, fragment=True))


def write_report(result: Any, path: str | Path) -> Path:
    """Write the HTML report atomically."""
    return atomic_write_text(path, render_report(result))


def check_fragment(check: Check) -> str:
    """A small HTML card for one check (Jupyter)."""
    c = _check_context(check)
    value = _named_html(c["value_name"], c["value"])
    margin = _named_html(c["margin_name"], c["margin"])
    return (
        f"<div class='ssecert-report'><style>{CSS}</style><h3>{escape(c['title'])} "
        f"<span class='badge {c['css']}'>{escape(c['label'])}</span></h3>"
        f"<p>{escape(c['summary'])}</p><table class='kv'><tr><th>value</th>"
        f"<td>{value}</td></tr><tr><th>margin</th><td>{margin}</td></tr>"
        f"<tr><th>method</th><td>{escape(c['method'])}</td></tr></table>"
        f"<details><summary>evidence</summary>{c['evidence']}</details></div>"
    )


def _named_html(name: str, text: str) -> str:
    """``name = number`` with the name in small print ("-" when there is no number)."""
    if not name or text == "-":
        return str(escape(text))
    return f"<span class='qname'>{escape(name)}</span> <span class='qnum'>{escape(text)}</span>"


def certificate_fragment(cert: Certificate) -> str:
    """The summary table of a Certificate as an HTML fragment (Jupyter)."""
    rows = "".join(
        f"<tr><td>{escape(c.id)}</td><td><span class='badge {verdict_class(c)}'>"
        f"{escape(verdict_label(c))}</span></td>"
        f"<td>{_named_html(c.value_name, value_text(c))}</td>"
        f"<td>{_named_html(c.margin_name, margin_text(c))}</td><td>{escape(c.summary)}</td></tr>"
        for c in cert.checks
    )
    verdict = cert.verdict.value
    return (
        f"<div class='ssecert-report'><style>{CSS}</style><h3>{escape(cert.system.name)} "
        f"<span class='badge {verdict}'>{verdict}</span></h3><table class='checks'><tr>"
        f"<th>check</th><th>verdict</th><th>value</th><th>margin</th><th>finding</th></tr>"
        f"{rows}</table></div>"
    )
