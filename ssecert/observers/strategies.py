"""What the kinds' hypothesis strategies share (``ObserverKind.parameter_strategy``).

Each kind draws the keys of its own ``[observer]`` table; these are the
pieces several of them use: the ranges of the scalars, a gain key (named or
an explicit matrix) that can be computed for the plant, and poles on a grid.
``ssecert.testing.observer_designs`` puts the drawn tables into specs, and
its plant strategies draw their eigenvalues on the same grid
(``grid_spectrum``).

This module imports hypothesis; the kinds import it inside their
``parameter_strategy``, so that only testing needs hypothesis.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from hypothesis import strategies as st

from ..system import System

__all__ = [
    "STEP",
    "THRESHOLD",
    "SHRINK",
    "POLE_RADIUS",
    "real",
    "distinct",
    "grid_spectrum",
    "poles",
    "feasible_gains",
    "gain_drawer",
]

STEP = (0.05, 1.0)  # observer step sizes (relative to ||C||^2 for gradient gains)
THRESHOLD = (0.01, 0.5)
SHRINK = (0.1, 0.95)
POLE_RADIUS = 0.9

Draw = Callable[[st.SearchStrategy[Any]], Any]


def real(draw: Draw, bounds: tuple[float, float]) -> float:
    """A finite float in ``bounds``."""
    return float(draw(st.floats(*bounds, allow_nan=False, allow_infinity=False)))


def distinct(draw: Draw, items: Sequence[Any], k: int) -> list[Any]:
    """k distinct items, drawn without replacement (no rejected draws)."""
    remaining = list(items)
    return [remaining.pop(draw(st.integers(0, len(remaining) - 1))) for _ in range(k)]


def grid_spectrum(
    draw: Draw, n: int, radius: float, *, pairs: bool = True, dyadic: bool = False
) -> list[tuple[float, float]]:
    """n eigenvalues: reals (re, 0) and complex pairs (a, b), b > 0, counted twice.

    They lie on a grid of spacing radius / K inside the closed disc of that
    radius, so any two differ by at least radius / K; K = max(6, n), or the
    next power of two (at least 8) with ``dyadic``, so that the grid values
    are exact binary fractions.
    """
    K = max(6, n) if not dyadic else 2 ** max(3, math.ceil(math.log2(max(n, 1))))
    count = draw(st.integers(0, n // 2)) if pairs else 0
    # ordered so that draws shrink towards small eigenvalues
    values = sorted(range(-K, K + 1), key=lambda k: (abs(k), k))
    grid = sorted(
        ((a, b) for a in range(-K, K + 1) for b in range(1, K + 1) if a * a + b * b <= K * K),
        key=lambda ab: (ab[0] ** 2 + ab[1] ** 2, ab),
    )
    reals = distinct(draw, values, n - 2 * count)
    complex_ = distinct(draw, grid, count)
    return [(radius * k / K, 0.0) for k in reals] + [
        (radius * a / K, radius * b / K) for a, b in complex_
    ]


def poles(draw: Draw, n: int) -> list[Any]:
    """n distinct poles in the disc of radius 0.9, in the spec's format."""
    out: list[Any] = []
    for a, b in grid_spectrum(draw, n, POLE_RADIUS):
        if b == 0:
            out.append(a)
        else:
            out.extend([[a, b], [a, -b]])
    return out


def feasible_gains(system: System) -> dict[str, Any]:
    """Which named gains can be computed for this plant (deadbeat L when it exists)."""
    from ..design.gains import GainError, deadbeat_gain, pinv_gain

    out: dict[str, Any] = {"deadbeat": None, "pinv": False}
    try:
        out["deadbeat"] = deadbeat_gain(system).L
    except GainError:
        pass
    try:
        pinv_gain(system)
        out["pinv"] = True
    except GainError:
        pass
    return out


def gain_drawer(system: System, allowed: Sequence[str]) -> Callable[[Draw], dict[str, Any]]:
    """A function drawing the gain keys of an ``[observer]`` table (``gain``, ``poles``)
    among ``allowed`` (named gains and ``"matrix"``, in the order drawn from) that can be
    computed for ``system``: deadbeat and place for an observable plant, pinv when C has
    full column rank; the matrix is a placed (or deadbeat) gain, or step A C^T.  Which
    gains are feasible is computed once, at the first draw."""
    feasible: dict[str, Any] = {}

    def draw_gain(draw: Draw) -> dict[str, Any]:
        if not feasible:
            feasible.update(feasible_gains(system))
        return _gain(draw, system, allowed, feasible)

    return draw_gain


def _gain(
    draw: Draw, system: System, allowed: Sequence[str], feasible: dict[str, Any]
) -> dict[str, Any]:
    from ..design.gains import GainError, place_gain

    options = [
        g
        for g in allowed
        if g in ("ogd", "matrix")
        or (g in ("deadbeat", "place") and feasible["deadbeat"] is not None)
        or (g == "pinv" and feasible["pinv"])
    ]
    gain = draw(st.sampled_from(options))
    if gain == "place":
        drawn = poles(draw, system.n)
        try:
            place_gain(system, [complex(*q) if isinstance(q, list) else q for q in drawn])
        except GainError:
            # control.place refuses some pairs (e.g. rank-deficient C): use the deadbeat gain
            return {"gain": "deadbeat"}
        return {"gain": "place", "poles": drawn}
    if gain != "matrix":
        return {"gain": gain}
    if feasible["deadbeat"] is None:
        step = real(draw, STEP) / max(float(np.linalg.norm(system.C, 2)) ** 2, 1e-300)
        L = step * system.A @ system.C.T
    else:
        drawn = poles(draw, system.n)
        try:
            L = place_gain(system, [complex(*q) if isinstance(q, list) else q for q in drawn]).L
        except GainError:
            L = feasible["deadbeat"]
    return {"gain": np.asarray(L, dtype=float).tolist()}
