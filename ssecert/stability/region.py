"""The certified region of a sparse observer over a (shrink, step) grid.

Each grid point is a circle-criterion certificate (``lmi.circle_certificate``),
re-verified in numpy as every certificate is; a certificate found at one point
is tried first at its neighbours before a new solve.
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

__all__ = ["RegionMap", "region_map"]


@dataclass(frozen=True)
class RegionMap:
    """Verdicts of the circle criterion over a (shrink, step) grid.

    ``verdicts[i, j]`` is for ``shrinks[i]`` and ``steps[j]``; ``margins``
    holds the verified margins (NaN where not certified).
    """

    shrinks: np.ndarray
    steps: np.ndarray
    verdicts: np.ndarray
    margins: np.ndarray
    solves: int
    reused: int
    seconds: float
    certificates: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {
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
        }


def region_map(
    design: ObserverDesign,
    shrinks: ArrayLike,
    steps: ArrayLike,
    *,
    solver_options: dict[str, Any] | None = None,
    budget: Budget | None = None,
) -> RegionMap:
    """Certified region of a sparse observer over (shrink, step).

    The gain L of ``design`` is kept; at each grid point the circle
    criterion is first tried by re-verifying the certificates of already
    certified neighbours (no solver), then by solving the block-diagonal
    LMI, then the LMI with cross terms.  ``budget`` (default ``Budget()``)
    bounds each solve, as in ``circle_certificate``: a point whose LMIs do
    not fit is inconclusive.
    """
    start = time.perf_counter()
    shrink_grid = np.asarray(shrinks, dtype=float)
    step_grid = np.asarray(steps, dtype=float)
    verdicts: np.ndarray = np.empty((shrink_grid.size, step_grid.size), dtype=object)
    margins = np.full((shrink_grid.size, step_grid.size), np.nan)
    found: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}
    solves = reused = 0
    for i, q in enumerate(shrink_grid):
        for j, nu in enumerate(step_grid):
            model = LureModel.from_design(replace(design, shrink=float(q), step=float(nu)))
            neighbours = [found[k] for k in ((i - 1, j), (i, j - 1), (i - 1, j - 1)) if k in found]
            cert = circle_certificate(
                model,
                structure="block-diagonal",
                solver_options=solver_options,
                reuse=neighbours,
                budget=budget,
            )
            if cert.verdict == Verdict.INCONCLUSIVE and cert.details.get("attempts"):
                cert = circle_certificate(
                    model, structure="cross", solver_options=solver_options, budget=budget
                )
                solves += 1
            if cert.details.get("reused"):
                reused += 1
            elif cert.details.get("attempts"):
                solves += 1
            verdicts[i, j] = cert.verdict
            if cert.verdict == Verdict.HOLDS:
                margins[i, j] = cert.margin
                if cert.P is not None and cert.multipliers is not None:  # holds carries both
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
    )
