"""An observer designed against its certificate: the gain synthesised, the scalars searched.

It sits beside ``analyze`` and ``certify`` (it certifies every candidate as they do); the
gain synthesis itself is ``ssecert.design.synthesis``.

A candidate is a point of a small grid of the scalar parameters: (shrink, step)
for the elastic-net observer, the step for the D-SSO (shrink 1), nothing for
a Luenberger observer.  Its gain comes out of the synthesis LMI of
``ssecert.design.synthesis`` (for the ``roa`` objective also the deadbeat
gain), and the design built with it is certified exactly as ``ssecert
analyze`` certifies a spec (``observer_stability_check`` and
``iss_gain_check``): only verified numbers count.  The synthesis's own
dissipation certificate is also checked in numpy (``verify_synthesis``); it is
what certifies the decay of the ``rate`` objective.

The grid is searched from its middle outwards: each round certifies the
untried neighbours of the best candidate so far and moves there when one is
better (a pattern search, each round starting from the previous best), then,
while the time budget lasts, the rest of the grid nearest-first.  A candidate
is not started when the time left is less than the candidates so far took on
average; the result reports the time spent and whether the grid was
exhausted.

Objectives: the smallest certified l2 gain from attack to estimation error
(``gain``), the fastest certified decay (``rate``: the gain synthesised for
decay by bisection), or the largest certified region of attraction (``roa``,
for the D-SSO, whose shrink 1 rarely admits a global certificate: a design
certified globally scores an infinite radius).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .system import System

__all__ = [
    "DesignResult",
    "certified_gain",
    "design_observer",
    "verify_synthesis",
    "SHRINKS",
    "STEPS",
]

SHRINKS = (0.3, 0.5, 0.7, 0.9)
STEPS = (0.1, 0.3, 0.5, 0.7, 1.0)
KINDS = ("elastic_net", "dsso", "luenberger")
OBJECTIVES = ("gain", "rate", "roa")


@dataclass(frozen=True)
class DesignResult:
    """The synthesised ``[observer]`` section (None when no design was certified), what
    certifies it, and every candidate tried.

    Attributes
    ----------
    observer : dict or None
        The ``[observer]`` section, gain as an explicit matrix.
    gamma : float or None
        Certified l2 gain from attack to estimation error, as ``ssecert analyze`` reports it.
    decay : float or None
        Certified decay per step: the synthesis certificate's alpha, verified.
    objective : str
    candidates : list of dict
        Per candidate: its parameters, the synthesis status, the verdicts and numbers.
    seconds : float
    complete : bool
        False when the time budget ended the search before the grid was exhausted.
    reason : str
        Why no design was certified.
    radius : float or None
        Certified region of attraction (``roa``; inf when observer_stability holds).
    """

    observer: dict[str, Any] | None
    gamma: float | None
    decay: float | None
    objective: str
    candidates: list[dict[str, Any]] = field(default_factory=list)
    seconds: float = 0.0
    complete: bool = True
    reason: str = ""
    radius: float | None = None


def design_observer(
    system: System,
    kind: str = "elastic_net",
    *,
    objective: str = "gain",
    threshold: float = 0.1,
    time_budget: float = 60.0,
    min_decay: float = 1e-3,
) -> DesignResult:
    """Search the best certified design of ``kind`` for ``system``.

    Parameters
    ----------
    system : System
    kind : {"elastic_net", "dsso", "luenberger"}
        The SSO is not offered: its gain is fixed by its step (L = step A C^T).
    objective : {"gain", "rate", "roa"}
        ``roa`` for the D-SSO only.
    threshold : float, default 0.1
        The soft threshold (kept fixed: the certificates of ``gain`` and ``rate`` do not
        depend on it; the region of attraction scales with it).
    time_budget : float, default 60
        Seconds; no candidate is started when fewer seconds remain than the candidates so
        far took on average (``complete`` false when some of the grid was left), and each
        synthesis solve stops at the time left (at least 1 s: the first candidate always
        runs).
    min_decay : float, default 1e-3
        Decay alpha imposed by the ``gain`` objective's synthesis (V(xi+) <= (1 - alpha)
        V(xi) without attack): on a stable plant the smallest gain from attack to error is
        often a gain near zero (the observer ignores its sensors and the plant's own decay
        does the estimation); a larger alpha asks for faster convergence.

    Examples
    --------
    >>> from ssecert.examples import load_example
    >>> result = design_observer(load_example("ugv").system, "elastic_net", time_budget=5)
    >>> result.observer["kind"], result.gamma < 1.1
    ('elastic_net', True)
    """
    if kind not in KINDS:
        raise ValueError(f"kind: expected one of {', '.join(KINDS)}, got {kind!r}")
    if objective not in OBJECTIVES:
        raise ValueError(f"objective: expected one of {', '.join(OBJECTIVES)}, got {objective!r}")
    if objective == "roa" and kind != "dsso":
        raise ValueError(
            f"objective 'roa' is for the D-SSO (shrink 1), got kind {kind!r}: the other kinds "
            "are certified globally or not at all"
        )
    start = time.perf_counter()
    rows, cols = _axes(kind, objective)
    evaluate = _evaluator(
        system,
        kind,
        objective,
        threshold,
        lambda: time_budget - (time.perf_counter() - start),
        min_decay,
    )
    tried: dict[tuple[int, int], dict[str, Any]] = {}
    kept: dict[tuple[int, int], tuple[tuple[float, float], dict[str, Any]]] = {}

    def score(cell: tuple[int, int]) -> float:
        return kept[cell][0][0] if cell in kept else math.inf

    def run(cell: tuple[int, int]) -> bool:
        """Certify one cell unless the budget is spent; False when it is."""
        elapsed = time.perf_counter() - start
        if tried and elapsed + elapsed / len(tried) > time_budget:
            return False
        record, found = evaluate(rows[cell[0]], cols[cell[1]])
        record["certified"] = found is not None
        record["seconds_since_start"] = round(time.perf_counter() - start, 3)
        tried[cell] = record
        if found is not None:
            kept[cell] = found
        return True

    complete = _search(rows, cols, tried, run, score)
    seconds = round(time.perf_counter() - start, 3)
    candidates = [tried[c] for c in sorted(tried)]
    if not kept:
        reason = _no_design_reason(kind, candidates, system)
        return DesignResult(None, None, None, objective, candidates, seconds, complete, reason)
    best = min(kept, key=lambda c: kept[c][0])
    record = tried[best]
    return DesignResult(
        kept[best][1],
        record.get("gamma"),
        record.get("decay"),
        objective,
        candidates,
        seconds,
        complete,
        radius=record.get("radius"),
    )


def _axes(kind: str, objective: str) -> tuple[list[Any], list[Any]]:
    """The grid's two axes: (shrink or gain choice, step)."""
    if kind == "luenberger":
        return [None], [None]
    if kind == "dsso":
        return (["deadbeat", "synthesised"] if objective == "roa" else [1.0]), list(STEPS)
    return list(SHRINKS), list(STEPS)


def _search(
    rows: list[Any],
    cols: list[Any],
    tried: dict[tuple[int, int], dict[str, Any]],
    run: Callable[[tuple[int, int]], bool],
    score: Callable[[tuple[int, int]], Any],
) -> bool:
    """Pattern search from the grid's middle, then the rest nearest-first; True when every
    cell was tried."""
    current = ((len(rows) - 1) // 2, (len(cols) - 1) // 2)
    if not run(current):
        return False
    while True:
        around = [
            (current[0] + di, current[1] + dj)
            for di, dj in ((-1, 0), (1, 0), (0, -1), (0, 1))
            if 0 <= current[0] + di < len(rows) and 0 <= current[1] + dj < len(cols)
        ]
        for cell in around:
            if cell not in tried and not run(cell):
                return False
        best = min(tried, key=score)
        if best == current or score(best) == math.inf:
            break
        current = best
    rest = sorted(
        ((i, j) for i in range(len(rows)) for j in range(len(cols)) if (i, j) not in tried),
        key=lambda c: abs(c[0] - current[0]) + abs(c[1] - current[1]),
    )
    return all(run(cell) for cell in rest)


Found = tuple[tuple[float, float], dict[str, Any]]


def _evaluator(
    system: System,
    kind: str,
    objective: str,
    threshold: float,
    remaining: Callable[[], float],
    min_decay: float,
) -> Callable[[Any, Any], tuple[dict[str, Any], Found | None]]:
    """The function certifying one grid cell: a record with its parameters, verdicts and
    numbers, and, when it is certified, its rank (lower is better: the objective, then a
    tie-break) and its ``[observer]`` section."""
    from .design.synthesis import synthesize_gain, synthesize_rate_gain, with_gain
    from .observers import build_observer

    zero = np.zeros((system.n, system.p)).tolist()

    def evaluate(row: Any, step: Any) -> tuple[dict[str, Any], Found | None]:
        params: dict[str, Any] = {"kind": kind, "gain": zero}
        if kind != "luenberger":
            params.update(step=step, threshold=threshold)
        if kind == "elastic_net":
            params["shrink"] = row
        record: dict[str, Any] = {
            k: v for k, v in params.items() if k in ("step", "shrink", "threshold")
        }
        template = build_observer(system, params)
        if objective == "roa" and row == "deadbeat":
            record["gain"] = "deadbeat"
            try:
                design = build_observer(system, {**params, "gain": "deadbeat"})
            except ValueError as exc:  # no deadbeat gain for this plant
                record["synthesis"] = f"no deadbeat gain: {exc}"
                return record, None
            proposal = None
        else:
            record["gain"] = "synthesised"
            limit = max(remaining(), 1.0)
            if objective == "rate":
                proposal = synthesize_rate_gain(template, time_limit=limit)
            else:
                proposal = synthesize_gain(template, alpha=min_decay, time_limit=limit)
            own = _verified_proposal(template, proposal)
            if objective == "rate" and proposal.L is not None and not own["verified"]:
                # at the edge of feasibility: a decay further inside has a margin
                proposal = synthesize_rate_gain(template, backoff=0.8, time_limit=limit)
                own = _verified_proposal(template, proposal)
            record["synthesis"] = proposal.status
            if proposal.L is None:
                record["rejected"] = f"the synthesis LMI gave no gain ({proposal.status})"
                return record, None
            record["synthesis_certificate"] = own
            design = with_gain(template, proposal.L)
        stability, iss = certified_gain(design)
        decay = None
        if proposal is not None:
            decay = own.get("alpha") if own["verified"] else None
        record.update(
            stability=stability.verdict.value,
            iss=iss.verdict.value,
            gamma=iss.value if iss.verdict.value == "holds" else None,
            decay=decay,
        )
        gain = "deadbeat" if proposal is None else np.asarray(design.L).tolist()
        observer = {**params, "gain": gain}
        if objective == "roa":
            radius = _certified_radius(design, stability)
            record["radius"] = radius
            if radius <= 0:
                record["rejected"] = "no region of attraction certified"
                return record, None
            return record, ((-radius, record["gamma"] or math.inf), observer)
        if stability.verdict.value != "holds":
            record["rejected"] = f"observer_stability {stability.verdict.value}"
            return record, None
        if iss.verdict.value != "holds":
            record["rejected"] = f"iss_gain {iss.verdict.value}"
            return record, None
        if objective == "rate":
            if decay is None:
                record["rejected"] = (
                    "the synthesis's own decay certificate did not verify in numpy "
                    f"({record['synthesis_certificate'].get('problem', '')})"
                )
                return record, None
            return record, ((-decay, float(iss.value)), observer)
        return record, ((float(iss.value), -(decay or 0.0)), observer)

    return evaluate


def _verified_proposal(template: Any, proposal: Any) -> dict[str, Any]:
    """``verify_synthesis`` on the design with the proposed gain ({} without one)."""
    from .design.synthesis import with_gain

    if proposal.L is None:
        return {"verified": False}
    return verify_synthesis(with_gain(template, proposal.L), proposal)


def _certified_radius(design: Any, stability: Any) -> float:
    """The certified region of attraction: inf when observer_stability holds, else the
    radius the region_of_attraction check proves (piecewise-quadratic included)."""
    from .stability.checks import region_of_attraction_check

    if stability.verdict.value == "holds":
        return math.inf
    if stability.verdict.value == "fails":
        return 0.0
    check = region_of_attraction_check(design, piecewise=True)
    return float(check.value or 0.0) if check is not None else 0.0


def _no_design_reason(kind: str, candidates: list[dict[str, Any]], system: System) -> str:
    why = sorted({str(rec.get("rejected", "not certified")) for rec in candidates})
    reason = f"no {kind} design of the {len(candidates)} tried was certified: {'; '.join(why)}"
    modes = _undetectable_modes(system)
    if modes:
        reason += (
            f"; the plant has an unobservable mode that is not stable (eigenvalue "
            f"{', '.join(f'{m:.4g}' for m in modes)}): no observer's error can converge"
        )
    return reason


def _undetectable_modes(system: System) -> list[complex]:
    """Eigenvalues with |lambda| >= 1 that the sensors do not see (PBH test, numerically:
    a reason's words, not a verdict)."""
    A, C = system.A, system.C
    out = []
    for lam in np.linalg.eigvals(A):
        if abs(lam) < 1 - 1e-9:
            continue
        M = np.vstack([A - lam * np.eye(system.n), C])
        s = np.linalg.svd(M, compute_uv=False)
        scale = max(float(np.linalg.norm(A, 2)), float(np.linalg.norm(C, 2)), 1e-300)
        if s[-1] <= 1e-9 * scale:
            out.append(complex(lam) if abs(np.imag(lam)) > 0 else float(np.real(lam)))
    return out


def certified_gain(design: Any) -> tuple[Any, Any]:
    """(observer_stability, iss_gain) of a design, as ``analyze`` checks them."""
    from .stability.checks import iss_gain_check, observer_stability_check

    stability, cert = observer_stability_check(design)
    return stability, iss_gain_check(design, cert)


def verify_synthesis(design: Any, proposal: Any, *, clear: float = 100.0) -> dict[str, Any]:
    """The synthesis's own dissipation certificate (P, multipliers, alpha, gamma^2) checked in
    numpy on ``design`` (the design built with the proposed gain), as every certificate is:
    ``verified``, the decay ``alpha`` and ``gamma`` it proves, the margin and its bound."""
    from .observers.lure import LureModel
    from .stability.lmi_verification import verify_certificate

    if proposal.P is None or proposal.g is None:
        return {"verified": False, "problem": proposal.status}
    model = LureModel.from_design(design)
    g = proposal.g * (1 + 1e-6) + 1e-9  # a slightly larger gain, so that the margin survives
    ok, margin, bound, problem = verify_certificate(
        model,
        proposal.P,
        proposal.multipliers if proposal.multipliers is not None else np.zeros(0),
        kind="iss",
        alpha=float(proposal.alpha or 0.0),
        g=g,
        clear=clear,
    )
    out: dict[str, Any] = {"verified": bool(ok), "margin": margin, "error_bound": bound}
    if ok:
        out.update(alpha=float(proposal.alpha or 0.0), gamma=float(np.sqrt(g)))
    else:
        out["problem"] = problem
    return out


DESIGN_HEADER = (
    "# Observer synthesised by ssecert design ({kind}, objective {objective}) for {source}:\n"
    "# {guarantee}\n"
)
WORSE_RTOL = 0.05  # a synthesised design is worse when its final mean error is 5% larger


def design_spec_text(spec: Any, result: DesignResult, kind: str) -> str:
    """The spec file of the synthesised design: ``spec`` with the synthesised ``[observer]``
    and the name NAME-design (so that ``ssecert certify`` of it writes NAME-design.html)."""
    from ._spec_write import dumps, spec_document

    if result.observer is None:
        raise ValueError("no design to write: the search certified none")
    document = spec_document(spec, result.observer)
    document["name"] = f"{spec.name}-design"
    return DESIGN_HEADER.format(
        kind=kind,
        objective=result.objective,
        source=spec.source,
        guarantee=_guarantee(result),
    ) + dumps(document)


def _guarantee(result: DesignResult) -> str:
    parts = []
    if result.gamma is not None:
        parts.append(f"certified l2 gain {result.gamma:.6g}")
    if result.decay is not None:
        parts.append(f"certified decay {result.decay:.3g} per step")
    if result.radius is not None:
        parts.append(f"certified region of attraction {result.radius:.4g}")
    return ", ".join(parts) or "certified"


def design_report(
    spec: Any,
    designed: Any,
    *,
    seed: int | None = None,
    runs: int | None = None,
    command: str = "",
    progress: Callable[[str], None] | None = None,
) -> Any:
    """``certify`` of the designed spec, with the comparison against the spec's own design
    (when it has one) under the same scenarios and seeds: a ``CertifyResult`` whose
    ``comparison`` holds both designs' verdicts and certified numbers and, per scenario, the
    final relative error (mean, q90) and the settling step of the mean error of each."""
    from dataclasses import replace

    from .certify import certify

    say = progress or (lambda message: None)
    result = certify(designed, seed=seed, runs=runs, command=command, progress=progress)
    own = None
    if spec.observer is not None:
        say("certifying and simulating the spec's own design, for the comparison")
        own = certify(spec, seed=seed, runs=runs, region=False)
    return replace(result, comparison=compare_designs(own, result))


def compare_designs(own: Any | None, designed: Any) -> dict[str, Any]:
    """Side by side: the spec's own design (a ``CertifyResult`` or None) and the synthesised
    one, their certified numbers and, per scenario both simulated, the simulated error."""
    designs = [_design_row("synthesised", designed)]
    if own is not None:
        designs.insert(0, _design_row("spec", own))
    rows = []
    worse = []
    for name, mine in designed.simulations.items():
        theirs = own.simulations.get(name) if own is not None else None
        row: dict[str, Any] = {"scenario": name, "synthesised": _sim_row(mine)}
        if theirs is not None:
            row["spec"] = _sim_row(theirs)
            row["comparison"] = _versus(row["synthesised"], row["spec"])
            if row["comparison"] == "worse":
                worse.append(name)
        rows.append(row)
    compared = [r for r in rows if r.get("comparison") in ("better", "no worse", "worse")]
    apart = [r["scenario"] for r in rows if "comparison" in r and r not in compared]
    if own is None:
        summary = "The spec has no observer of its own: the synthesised design alone is shown."
    elif not rows:
        summary = "The spec has no scenarios: the designs were not simulated."
    elif not compared:
        summary = "No scenario was simulated to a finite error for both designs."
    elif worse:
        summary = (
            f"The synthesised design's final mean error is worse than the spec's own design's "
            f"in {len(worse)} of {len(compared)} scenarios compared ({', '.join(worse)}); no "
            "worse in the others."
        )
    else:
        summary = (
            f"The synthesised design's final mean error is no worse than the spec's own "
            f"design's in every one of the {len(compared)} scenarios compared (same seeds)."
        )
    if own is not None and apart:
        summary += (
            f" Not compared ({', '.join(apart)}): a scenario skipped, or a simulation that "
            "overflowed, for at least one of the designs."
        )
    return {
        "designs": designs,
        "scenarios": rows,
        "worse_in": worse,
        "summary": summary,
        "worse_rtol": WORSE_RTOL,
    }


def _design_row(label: str, result: Any) -> dict[str, Any]:
    observer = dict(result.spec.observer or {})
    gain = observer.get("gain")
    cert = result.certificate
    row: dict[str, Any] = {
        "design": label,
        "kind": observer.get("kind"),
        "gain": gain if isinstance(gain, str) else ("LMI" if label == "synthesised" else "matrix"),
        **{k: observer.get(k) for k in ("step", "threshold", "shrink") if k in observer},
    }
    for check_id in ("observer_gain", "observer_stability", "iss_gain", "region_of_attraction"):
        check = cert.get(check_id)
        if check is not None:
            row[check_id] = check.verdict.value
            if check.value is not None and check.verdict.value == "holds":
                row[f"{check_id}_value"] = check.value
    return row


def _sim_row(res: Any) -> dict[str, Any]:
    from .simulation.metrics import settling_step

    if not hasattr(res, "relative_error"):
        return {"skipped": str(res.get("skipped", "not simulated"))}
    final = res.final()
    with np.errstate(over="ignore", invalid="ignore"):
        mean = np.mean(res.relative_error, axis=1)
    return {
        "final_mean": final["relative_error_mean"],
        "final_q90": final["relative_error_q90"],
        "settling_step": settling_step(mean),
        "runs": res.runs,
        "steps": res.steps,
        "seed": res.seed,
    }


def _versus(mine: dict[str, Any], theirs: dict[str, Any]) -> str:
    a, b = mine.get("final_mean"), theirs.get("final_mean")
    if a is None or b is None or math.isnan(a) or math.isnan(b):
        return "not compared"
    if not math.isfinite(a):
        return "worse" if math.isfinite(b) else "not compared"
    if a > b * (1 + WORSE_RTOL) + 1e-12:
        return "worse"
    return "better" if a < b * (1 - WORSE_RTOL) else "no worse"
