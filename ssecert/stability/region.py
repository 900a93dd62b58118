"""The certified region of a sparse observer over a (shrink, step) grid.

Each grid point is a circle-criterion certificate (``lmi.circle_certificate``),
re-verified in numpy as every certificate is; a certificate found at one point
is tried first at its neighbours before a new solve.  A point without one is
decided as observer_stability decides it when it can: it fails with the kind
of its witness (the dead zone's linear dynamics unstable, a divergent
trajectory of the large-signal loop, or a nonzero equilibrium confirmed
exactly, or a periodic orbit confirmed exactly); where the circle LMIs were
solved and failed, a Zames-Falb multiplier (``zames_falb``) may still certify
the point; otherwise the radius of initial errors its dead zone certifies
(``roa.region_of_attraction`` with Q = I) is recorded.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..budget import Budget
from ..observers import ObserverDesign
from ..observers.lure import LureModel
from ..results import Verdict
from .lmi import circle_certificate
from .outcomes import LMICode, WitnessKind
from .zames_falb import zames_falb_certificate

__all__ = ["RegionMap", "region_map"]


@dataclass(frozen=True)
class RegionMap:
    """Verdicts of the circle criterion over a (shrink, step) grid.

    ``verdicts[i, j]`` is for ``shrinks[i]`` and ``steps[j]``; ``margins``
    holds the verified margins (NaN where not certified); ``witnesses`` the
    kind of witness of each point that fails; ``radii`` the certified radius
    of initial errors (inf where certified, 0 where it fails or none is);
    ``zames_falb`` the points certified by a Zames-Falb multiplier (not by
    the circle criterion), with the multiplier's order; ``not_reached`` the points left
    undecided (inconclusive) because ``time_limit`` seconds had passed.
    """

    shrinks: np.ndarray
    steps: np.ndarray
    verdicts: np.ndarray
    margins: np.ndarray
    solves: int
    reused: int
    seconds: float
    certificates: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    witnesses: dict[tuple[int, int], WitnessKind] = field(default_factory=dict)
    radii: np.ndarray | None = None
    zames_falb: dict[tuple[int, int], int] = field(default_factory=dict)
    not_reached: int = 0
    time_limit: float | None = None

    def to_dict(self) -> dict[str, Any]:
        return {
            "zames_falb": [
                {"shrink": float(self.shrinks[i]), "step": float(self.steps[j]), "order": order}
                for (i, j), order in sorted(self.zames_falb.items())
            ],
            "witnesses": [
                {"shrink": float(self.shrinks[i]), "step": float(self.steps[j]), "kind": kind}
                for (i, j), kind in sorted(self.witnesses.items())
            ],
            "radii": self.radii,
            "shrinks": self.shrinks,
            "steps": self.steps,
            "verdicts": self.verdicts.tolist(),
            "margins": self.margins,
            "solves": self.solves,
            "reused": self.reused,
            "seconds": self.seconds,
            "certificates": [
                {
                    "shrink": float(self.shrinks[i]),
                    "step": float(self.steps[j]),
                    "P": P,
                    "multipliers_T": t,
                }
                for (i, j), (P, t) in sorted(self.certificates.items())
            ],
            **(
                {"cells_not_reached": self.not_reached, "time_limit": self.time_limit}
                if self.not_reached
                else {}
            ),
        }


def region_map(
    design: ObserverDesign,
    shrinks: ArrayLike,
    steps: ArrayLike,
    *,
    solver_options: dict[str, Any] | None = None,
    budget: Budget | None = None,
    time_limit: float | None = None,
) -> RegionMap:
    """Certified region of a sparse observer over (shrink, step).

    The gain L of ``design`` is kept; at each grid point the circle
    criterion is first tried by re-verifying the certificates of already
    certified neighbours (no solver), then by solving the block-diagonal
    LMI, then the LMI with cross terms.  ``budget`` (default ``Budget()``)
    bounds each solve, as in ``circle_certificate``: a point whose LMIs do
    not fit is inconclusive.  No point is started after ``time_limit``
    seconds: the points left are inconclusive (``not_reached``).
    """
    start = time.perf_counter()
    shrink_grid = np.asarray(shrinks, dtype=float)
    step_grid = np.asarray(steps, dtype=float)
    verdicts: np.ndarray = np.empty((shrink_grid.size, step_grid.size), dtype=object)
    margins = np.full((shrink_grid.size, step_grid.size), np.nan)
    found: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}
    witnesses: dict[tuple[int, int], WitnessKind] = {}
    radii = np.zeros((shrink_grid.size, step_grid.size))
    multipliers: dict[tuple[int, int], int] = {}
    solves = reused = not_reached = 0
    for i, q in enumerate(shrink_grid):
        for j, nu in enumerate(step_grid):
            if time_limit is not None and time.perf_counter() - start > time_limit:
                verdicts[i, j] = Verdict.INCONCLUSIVE
                not_reached += 1
                continue
            model = LureModel.from_design(replace(design, shrink=float(q), step=float(nu)))
            neighbours = [found[k] for k in ((i - 1, j), (i, j - 1), (i - 1, j - 1)) if k in found]
            cert = circle_certificate(
                model,
                structure="block-diagonal",
                solver_options=solver_options,
                reuse=neighbours,
                budget=budget,
            )
            if cert.code is LMICode.NOT_VERIFIED:
                cert = circle_certificate(
                    model, structure="cross", solver_options=solver_options, budget=budget
                )
                solves += 1
            if cert.code is LMICode.REUSED:
                reused += 1
            elif cert.code in (LMICode.VERIFIED, LMICode.NOT_VERIFIED):
                solves += 1
            if cert.code is LMICode.NOT_VERIFIED:
                zf = zames_falb_certificate(model, solver_options=solver_options, budget=budget)
                solves += 1
                if zf.verdict == Verdict.HOLDS:
                    cert, multipliers[(i, j)] = zf, int(zf.details["order"])
            verdicts[i, j] = cert.verdict
            if cert.verdict == Verdict.INCONCLUSIVE:
                kind, radii[i, j] = _undecided_point(model)
                if kind is not None:
                    verdicts[i, j], witnesses[(i, j)] = Verdict.FAILS, kind
            if cert.verdict == Verdict.HOLDS:
                radii[i, j] = np.inf
                margins[i, j] = cert.margin
                if (
                    (i, j) not in multipliers
                    and cert.P is not None
                    and cert.multipliers is not None
                ):
                    found[(i, j)] = (cert.P, cert.multipliers)
    return RegionMap(
        shrink_grid,
        step_grid,
        verdicts,
        margins,
        solves,
        reused,
        time.perf_counter() - start,
        dict(found),
        witnesses,
        radii,
        multipliers,
        not_reached,
        time_limit,
    )


def _undecided_point(model: LureModel) -> tuple[WitnessKind | None, float]:
    """(kind of witness that the point fails with, or None, and its dead zone's radius)."""
    from .divergence import divergence_witness
    from .equilibria import nonzero_equilibrium
    from .outcomes import RegionCode
    from .periodic import periodic_orbit
    from .roa import region_of_attraction

    if not model.finite():
        return None, 0.0  # beyond the float range: nothing decided at this point
    dead = region_of_attraction(model, widen=False)
    if dead.code is RegionCode.DEAD_ZONE_UNSTABLE:
        return WitnessKind.LOCAL_INSTABILITY, 0.0
    if divergence_witness(model) is not None:
        return WitnessKind.DIVERGENT_TRAJECTORY, 0.0
    if nonzero_equilibrium(model, milp=False)[0] is not None:  # a map cell: no MILP
        return WitnessKind.NONZERO_EQUILIBRIUM, 0.0
    if periodic_orbit(model)[0] is not None:
        return WitnessKind.PERIODIC_ORBIT, 0.0
    return None, dead.radius
