"""``ssecert design``: an observer synthesised against its certificate, written as a spec file."""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import warnings
from collections.abc import Sequence
from typing import Any

__all__: list[str] = []


def _kind_names() -> dict[str, str]:
    """The names ``--observer`` takes: each kind ``ssecert design`` offers, by name and by
    alias, to the kind it names."""
    from ..design.search import design_kinds
    from ..observers import get_kind

    out = {}
    for name in design_kinds():
        out.update(dict.fromkeys((name, *get_kind(name).aliases), name))
    return out


def _kinds_help() -> str:
    """The help of ``--observer``: the default kind (and those of the other objectives),
    then the others by name."""
    from ..design.search import OBJECTIVES, default_kind, design_kinds
    from ..observers import get_kind

    def shown(name: str) -> str:
        return (*get_kind(name).aliases, name)[0]

    first, *others = design_kinds()
    defaults = "".join(
        f"; {shown(default_kind(o))} with --objective {o}"
        for o in OBJECTIVES
        if default_kind(o) != first
    )
    rest = [shown(name) for name in others]
    either = " or ".join([", ".join(rest[:-1]), rest[-1]] if len(rest) > 1 else rest)
    return f"{shown(first)} (default{defaults})" + (f", {either}" if either else "")


def add_design_parser(sub: Any) -> None:
    from .options import _noise_bound, _nonnegative_int, _positive_int, _seconds

    design = sub.add_parser(
        "design",
        help="synthesise a certified observer for a spec and write it as a spec file",
        description=(
            "Search the observer of the chosen kind with the best certified guarantee for the "
            "spec's plant: the gain L comes out of the dissipation LMI that certifies it, "
            "(shrink, step) are searched on a grid within the time budget, and every candidate "
            "is certified exactly as 'ssecert analyze' certifies a spec. The best design is "
            "certified and simulated under the spec's scenarios as 'ssecert certify' does, "
            "beside the spec's own design with the same seeds. Writes DIR/NAME-design.toml (the "
            "spec with the synthesised [observer]), DIR/NAME-design.html (the report, with the "
            "comparison) and DIR/NAME-design.json (the certificate). Exit status, as for "
            "certify, from the written design's certificate: 0 every required check holds, 1 "
            "one fails (a plant that is not sparse observable, say) or no design was "
            "certified (nothing is written), 3 none fails but one is inconclusive; 2 bad "
            "input, 4 internal error."
        ),
    )
    design.add_argument("spec", metavar="SPEC", help="spec file or packaged example name")
    observer = design.add_argument("--observer", metavar="KIND")

    def complete() -> None:  # the kinds import every observer: only when design is asked
        observer.choices, observer.help = sorted(_kind_names()), _kinds_help()

    design.completions.append(complete)
    design.add_argument(
        "--objective",
        choices=("gain", "rate", "roa", "noise"),
        default="gain",
        help="smallest certified l2 gain from attack to error (default), fastest certified "
        "decay, (D-SSO) largest certified region of attraction, or smallest certified "
        "ultimate error under the noise (the spec's [noise] or --noise)",
    )
    design.add_argument(
        "--noise",
        type=_noise_bound,
        metavar="ETA",
        default=None,
        help="measurement noise within ETA on every sample of every sensor, replacing the "
        "spec's [noise] measurement bound, its process noise kept (written into "
        "NAME-design.toml): the trade-off front gains a noise axis and both designs their "
        "certified ultimate error; --objective noise picks the searched design with the "
        "smallest",
    )
    design.add_argument(
        "--out",
        default="reports",
        metavar="DIR",
        help="folder of NAME-design.toml, .html and .json (default reports)",
    )
    design.add_argument(
        "--seed",
        type=_nonnegative_int,
        metavar="N",
        help="replaces every scenario's seed (both designs get the same)",
    )
    design.add_argument(
        "--min-decay",
        type=_decay,
        metavar="ALPHA",
        help="decay per step imposed by the gain objective, V(k+1) <= (1 - ALPHA) V(k), 0 < "
        "ALPHA < 1 (default: read off the trade-off front, clearly faster than the plant's "
        "own decay; a given ALPHA is imposed even when the design is no faster than the plant)",
    )
    design.add_argument(
        "--runs", type=_positive_int, metavar="N", help="Monte Carlo runs per scenario"
    )
    design.add_argument(
        "--time-budget",
        type=_seconds,
        default=60.0,
        metavar="SECONDS",
        help="time for the search (default 60): no candidate starts when less is left than "
        "one took on average, and each synthesis stops at the time left; the first candidate "
        "always runs, and the certification and simulations of the chosen design come after",
    )
    design.add_argument(
        "--json", metavar="PATH", dest="json_path", help="write the result as JSON ('-': stdout)"
    )
    design.add_argument(
        "--max-attacked",
        type=_nonnegative_int,
        metavar="S",
        help="number of attacked sensors s (required for .npz/.mat)",
    )


def cmd_design(args: argparse.Namespace, argv: Sequence[str] | None = None) -> int:
    """Search, certify and simulate the best design, write its spec file, report and
    certificate, print the comparison; the exit status of the written design's certificate
    (1 when none was certified)."""
    import hashlib
    import tomllib

    from ..design.search import (
        default_kind,
        design_observer,
        design_report,
        design_spec_text,
        objective_refusal,
    )
    from ..report.html import render_report
    from ..report.json import certify_json
    from ..results import to_jsonable
    from ..spec import spec_from_dict
    from .files import (
        UsageError,
        load_argument,
        output_file,
        output_folder,
        separate_outputs,
        write_outputs,
    )
    from .progress import stage_display

    folder = output_folder("--out", args.out)
    target = output_file("--json", args.json_path)
    with warnings.catch_warnings(record=True) as caught:  # the spec's notes, said once
        warnings.simplefilter("always", UserWarning)
        spec = load_argument(args.spec, max_attacked=args.max_attacked, noise=args.noise)
    for warning in caught:
        sys.stderr.write(f"note: {str(warning.message).splitlines()[0]}\n")
    if args.objective == "noise" and getattr(spec, "noise", None) is None:
        raise UsageError(
            "--objective noise needs the measurement noise bound: --noise ETA or a [noise] "
            "section in the spec"
        )
    own = spec.observer or {}
    if args.observer:
        kind = _kind_names()[args.observer]
    else:
        kind = default_kind(args.objective)
    refusal = objective_refusal(args.objective, kind, option="--observer", given=args.observer)
    if refusal is not None:
        raise UsageError(str(refusal))
    threshold = float(own.get("threshold") or 0.1)
    human = sys.stderr if args.json_path == "-" else sys.stdout
    display = stage_display(json_to_stdout=args.json_path == "-")
    say = display.say

    stem = f"{spec.name}-design"
    paths = {ext: folder / f"{stem}.{ext}" for ext in ("toml", "html", "json")}
    if target is not None and any(target.resolve() == p.resolve() for p in paths.values()):
        raise UsageError(
            f"--json {args.json_path}: design writes its spec file, report and certificate "
            f"there ({', '.join(p.name for p in paths.values())}); give another path"
        )
    separate_outputs(args.spec, [(f"--out {args.out}", path) for path in paths.values()])
    separate_outputs(args.spec, [("--json", target)])
    with display.showing():  # cleared before the summary is printed
        say(f"searching {kind} designs ({args.objective})")
        result = design_observer(
            spec.system,
            kind,
            objective=args.objective,
            threshold=threshold,
            time_budget=args.time_budget,
            min_decay=args.min_decay,
            noise=getattr(spec, "noise", None),
        )
        document: dict[str, Any] = {
            "spec": spec.source,
            "kind": kind,
            "objective": args.objective,
            "design": result.observer,
            "gamma": result.gamma,
            "decay": result.decay,
            "radius": result.radius,
            "noise_bound": result.noise_bound,
            "plant_radius": result.plant_radius,
            "linear_radius": result.linear_radius,
            "choice": result.choice,
            "front": result.front,
            "candidates": result.candidates,
            "seconds": result.seconds,
            "complete": result.complete,
            "time_budget": args.time_budget,
        }
        limit = _sparse_limit(spec)
        if limit:
            document["sparse_observability"] = limit
        files: dict[Any, str] = {}
        report = None
        if result.observer is not None:
            text = design_spec_text(spec, result, kind)
            designed = spec_from_dict(
                tomllib.loads(text),
                source=str(paths["toml"]),
                sha256=hashlib.sha256(text.encode()).hexdigest(),
            )
            words = ["ssecert", "design", *(list(argv) if argv is not None else sys.argv[2:])]
            report = design_report(
                spec,
                designed,
                seed=args.seed,
                runs=args.runs,
                command=" ".join(words),
                progress=say,
                search=result,
            )
            options = "".join(
                f" --{name} {value}" for name, value in (("seed", args.seed), ("runs", args.runs))
                if value is not None
            )  # fmt: skip
            alone = (
                f"the certificate of the written spec file alone: ssecert certify {paths['toml']}"
                f"{options} --out ANOTHER_FOLDER (this one holds the design's report)"
            )
            report = dataclasses.replace(
                report, notes=(*report.notes, alone, *([limit] if limit else []))
            )
            document["comparison"] = report.comparison
            if document["noise_bound"] is None:  # the gain and rate objectives: certify's
                rows = {d["design"]: d for d in report.comparison["designs"]}
                bound = rows.get("synthesised", {}).get("observer_noise_bound_value")
                document["noise_bound"] = bound
            document["files"] = {ext: str(path) for ext, path in paths.items()}
            files = {
                paths["toml"]: text,
                paths["html"]: render_report(report),
                paths["json"]: certify_json(report),
            }
        else:
            document["reason"] = result.reason
        rendered = json.dumps(to_jsonable(document), indent=2, allow_nan=False) + "\n"
        if target is not None:
            files[target] = rendered
        if files:
            write_outputs(files)  # every file or none
    _print_design(human, spec, kind, args, result, report, limit, paths)
    if report is not None:
        verdict = report.certificate.verdict.value
        human.write(
            f"verdict of the written design's certificate: "
            f"{verdict.upper() if verdict == 'fails' else verdict} (exit status "
            f"{report.exit_code})\n"
        )
    if report is None:
        earlier = [str(path) for path in paths.values() if path.exists()]
        if earlier:  # (not this run's: say so, so that they are not read as its result)
            human.write(
                f"note: files of an earlier design are left as they were: {', '.join(earlier)}\n"
            )
    if args.json_path == "-":
        sys.stdout.write(rendered)
    # the written design's certificate decides, as for certify; nothing written: 1
    return report.exit_code if report is not None else 1


def _print_design(
    out: Any,
    spec: Any,
    kind: str,
    args: argparse.Namespace,
    result: Any,
    report: Any,
    limit: str,
    paths: dict[str, Any],
) -> None:
    """The terminal summary: the search, both designs' certified numbers, each scenario."""

    from ..base.format import one_minus
    from ..design.search_messages import comparison_words
    from ..observers import get_kind

    searched = f"{len(result.candidates)} candidates in {result.seconds:.1f} s"
    if not result.complete:
        searched += f" (the time budget of {args.time_budget:g} s ended the search)"
    out.write(f"ssecert design: {spec.name}, {kind}, objective {args.objective}: {searched}\n")
    if limit:
        out.write(f"  note: {limit}\n")
    if result.observer is None:
        out.write(f"  no design: {result.reason}\n")
        hint = get_kind(kind).design_hint(spec.system, args.objective)
        if hint:
            out.write(f"  ({hint})\n")
        return
    comparison = report.comparison
    for d in comparison["designs"]:
        label = "the spec's design" if d["design"] == "spec" else "synthesised"
        if d.get("observer_gain") not in (None, "holds"):
            out.write(f"  {label}: observer_gain {d['observer_gain']} (see the report)\n")
        params = ", ".join(
            f"{k} {d[k]:g}" for k in ("step", "threshold", "shrink") if isinstance(d.get(k), float)
        )
        words = [f"observer_stability {d.get('observer_stability', '-')}"]
        words.append(f"certified l2 gain {_num(d.get('iss_gain_value'))}")
        if "region_of_attraction_value" in d:
            words.append(f"region of attraction {_num(d['region_of_attraction_value'])}")
        if "observer_noise_bound_value" in d:
            words.append(
                f"certified ultimate error under the noise {_num(d['observer_noise_bound_value'])}"
            )
        out.write(f"  {label} ({d['kind']}, {params or 'gain only'}): {', '.join(words)}\n")
    if result.decay is not None and args.objective in ("gain", "rate", "noise"):
        out.write(f"  synthesised: certified decay {result.decay:.3g} per step (V(k+1) <= "
                  f"{one_minus(result.decay)} V(k))\n")  # fmt: skip
    if result.linear_radius is not None and result.plant_radius is not None:
        from ..design.search import FAST_PLANT, no_faster

        slow = no_faster(result.linear_radius, result.plant_radius)
        if result.plant_radius <= FAST_PLANT:
            loop = (
                f"the plant's own rho(A) = {result.plant_radius:.4g} is already fast (its error "
                f"falls by {FAST_PLANT:g} per step or faster): nothing was asked of the loop"
            )
        else:
            loop = (
                f"{'NO faster' if slow else 'faster'} than the plant's own rho(A) = "
                f"{result.plant_radius:.4g}{': it barely uses its sensors' if slow else ''}"
            )
        out.write(f"  its linear loop: rho(A - L S) = {result.linear_radius:.4g}, {loop}\n")
    if result.choice:
        out.write(f"  chosen: {result.choice}\n")
    verified = sum(1 for p in result.front if p.get("verified"))
    noisy = sum(1 for p in result.front if p.get("noise_bound") is not None)
    if verified >= 2:
        axes = "(decay, gain, noise bound)" if noisy else "(decay, gain)"
        out.write(f"  trade-off front: {verified} verified {axes} points, plotted in the report\n")
    elif args.objective in ("gain", "rate", "noise"):
        out.write(
            f"  trade-off front: {verified} verified point{'' if verified == 1 else 's'} (its "
            "synthesis solves failed, did not verify, or ran past their 30% of the time "
            "budget)\n"
        )
    for row in comparison["scenarios"]:
        cells = []
        for label in ("spec", "synthesised"):
            sim = row.get(label)
            if sim is None:
                continue
            if "skipped" in sim:
                cells.append(f"{label}: skipped")
            else:
                settle = sim["settling_step"]
                cells.append(
                    f"{label} {_num(sim['mean_error'])}, final {_num(sim['final_mean'])}"
                    + ("" if settle is None else f" (settles by step {settle})")
                )
        verdict = f" -> {comparison_words(row['comparison'])}" if "comparison" in row else ""
        out.write(
            f"  scenario {row['scenario']}: mean error ||x_hat - x|| over the horizon "
            f"{'; '.join(cells)}"
            f"{verdict}\n"
        )
    out.write(f"  {comparison['summary']}\n")
    out.write(
        f"spec file: {paths['toml']}\nreport: {paths['html']}\ncertificate: {paths['json']}\n"
    )


def _decay(text: str) -> float:
    """--min-decay: a number strictly between 0 and 1."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number in (0, 1), got {text!r}") from None
    if not 0 < value < 1:
        raise argparse.ArgumentTypeError(f"expected a number in (0, 1), got {text!r}")
    return value


def _sparse_limit(spec: Any) -> str:
    """What no observer can do on this plant ('' when it is 2s-sparse observable): the
    certified gain bounds the error under attack, it does not make it vanish."""
    from ..results import Verdict
    from ..structure.sparse import sparse_observability

    check = sparse_observability(spec.system, spec.max_attacked, time_budget=0)
    if check.verdict is not Verdict.FAILS:
        return ""
    names = [spec.system.sensors[i] for i in check.fields.get("breaking_set") or []]
    if not names:
        return (
            "the plant is not observable even with every sensor: no observer can recover the "
            "state exactly, attacked or not"
        )
    return (
        f"no observer can recover the state exactly with {spec.max_attacked} attacked "
        f"sensor(s): the plant is not {2 * spec.max_attacked}-sparse observable (removing "
        f"{', '.join(names)} leaves it unobservable); a certified gain bounds the error "
        "under attack, it does not remove it"
    )


def _num(v: Any) -> str:
    return "none" if v is None else f"{float(v):.4g}"
