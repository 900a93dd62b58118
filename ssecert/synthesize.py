"""An observer designed against its certificate: the gain synthesised, the scalars searched.

It sits beside ``analyze`` and ``certify`` (it certifies every candidate as they do); the
gain synthesis itself is ``ssecert.design.synthesis``.

For each (shrink, step) of a small grid (shrink 1 for the D-SSO, none for a
Luenberger observer) the gain comes from ``synthesize_gain``, and the design
built with it is certified exactly as ``ssecert analyze`` certifies a spec
(``observer_stability_check`` and ``iss_gain_check``): only verified numbers
count.  The best design by the objective is kept: the smallest certified l2
gain from attack to estimation error (``gain``) or the fastest certified
decay (``rate``).  The grid stops at the time budget, which the result
reports.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .system import System

__all__ = ["DesignResult", "certified_gain", "design_observer", "SHRINKS", "STEPS"]

SHRINKS = (0.3, 0.5, 0.7, 0.9)
STEPS = (0.1, 0.3, 0.5, 0.7, 1.0)
KINDS = ("elastic_net", "dsso", "luenberger")


@dataclass(frozen=True)
class DesignResult:
    """The synthesised ``[observer]`` section (None when no design was certified), its
    certified gain and decay, and every candidate tried."""

    observer: dict[str, Any] | None
    gamma: float | None
    decay: float | None
    objective: str
    candidates: list[dict[str, Any]] = field(default_factory=list)
    seconds: float = 0.0
    complete: bool = True
    reason: str = ""


def design_observer(
    system: System,
    kind: str = "elastic_net",
    *,
    objective: str = "gain",
    threshold: float = 0.1,
    time_budget: float = 60.0,
) -> DesignResult:
    """Search the best certified design of ``kind`` for ``system``.

    Parameters
    ----------
    system : System
    kind : {"elastic_net", "dsso", "luenberger"}
        The SSO is not offered: its gain is fixed by its step (L = step A C^T).
    objective : {"gain", "rate"}
    threshold : float, default 0.1
        The soft threshold (kept fixed: the certificates do not depend on it).
    time_budget : float, default 60
        Seconds; the grid stops there (``complete`` false).
    """
    from .design.synthesis import synthesize_gain, with_gain
    from .observers import build_observer

    if kind not in KINDS:
        raise ValueError(f"kind: expected one of {', '.join(KINDS)}, got {kind!r}")
    if objective not in ("gain", "rate"):
        raise ValueError(f"objective: expected 'gain' or 'rate', got {objective!r}")
    start = time.perf_counter()
    zero = np.zeros((system.n, system.p)).tolist()
    if kind == "luenberger":
        grid: list[dict[str, Any]] = [{"kind": kind, "gain": zero}]
    elif kind == "dsso":
        grid = [{"kind": kind, "gain": zero, "step": s, "threshold": threshold} for s in STEPS]
    else:
        grid = [
            {"kind": kind, "gain": zero, "step": s, "threshold": threshold, "shrink": q}
            for q in SHRINKS
            for s in STEPS
        ]
    candidates: list[dict[str, Any]] = []
    best: tuple[float, dict[str, Any]] | None = None
    complete = True
    for params in grid:
        if time.perf_counter() - start > time_budget:
            complete = False
            break
        template = build_observer(system, params)
        proposal = synthesize_gain(template)
        record: dict[str, Any] = {
            k: v for k, v in params.items() if k in ("step", "shrink", "threshold")
        }
        record["synthesis"] = proposal.status
        if proposal.L is None:
            candidates.append(record)
            continue
        stability, iss = certified_gain(with_gain(template, proposal.L))
        decay = stability.fields.get("decay_rate") if stability.fields else None
        record.update(
            stability=stability.verdict.value, gamma=iss.value, decay=decay, iss=iss.verdict.value
        )
        candidates.append(record)
        if stability.verdict.value != "holds" or iss.verdict.value != "holds":
            continue
        score = float(iss.value) if objective == "gain" else -float(decay or 0.0)
        observer = {**params, "gain": np.asarray(proposal.L).tolist()}
        if best is None or score < best[0]:
            best = (score, {"observer": observer, "gamma": iss.value, "decay": decay})
    seconds = round(time.perf_counter() - start, 3)
    if best is None:
        return DesignResult(
            None,
            None,
            None,
            objective,
            candidates,
            seconds,
            complete,
            reason=f"no {kind} design of the grid was certified stable with a finite gain",
        )
    chosen = best[1]
    return DesignResult(
        chosen["observer"],
        chosen["gamma"],
        chosen["decay"],
        objective,
        candidates,
        seconds,
        complete,
    )


def certified_gain(design: Any) -> tuple[Any, Any]:
    """(observer_stability, iss_gain) of a design, as ``analyze`` checks them."""
    from .stability.checks import iss_gain_check, observer_stability_check

    stability, cert = observer_stability_check(design)
    return stability, iss_gain_check(design, cert)
