"""Periodic orbits of a sparse observer's error dynamics without attack.

A design can neither diverge nor settle on a wrong equilibrium and still not
converge: its error may cycle for ever.  Initial errors are simulated on the
Lur'e model (``ssecert.observers.lure``); a tail that neither converges nor
grows and repeats itself after k >= 2 steps is taken as a candidate.  Along
the candidate the soft threshold follows one active/sign pattern per step, on
which the map is affine, so the k-step map is affine too: its fixed point is
solved in exact rational arithmetic on the model's exact matrices (formed from the
spec's data), and then iterated
exactly through the true nonlinearity.  An orbit is reported only when that
exact iteration returns to its start after k steps without having been at
rest: the observer then cycles without attack and is not globally
asymptotically stable.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any

import numpy as np

from ..budget import Budget
from ..numerics.rational import product, solve
from ..observers.lure import LureModel
from .outcomes import SearchCode, Searched, WitnessKind

__all__ = ["periodic_orbit", "periodic_orbit_cost"]

SAMPLES = 64  # initial errors simulated
STEPS = 3000
MAX_PERIOD = 64
EXACT_WORK = 96  # largest period x error states confirmed in exact arithmetic


def periodic_orbit_cost(model: LureModel) -> tuple[float, float]:
    """Bytes and operations of the search: the simulated paths and their steps."""
    N, m = model.N, model.m
    return 8.0 * (STEPS + 1) * SAMPLES * N, 2.0 * STEPS * SAMPLES * (N * N + 2 * N * m)


def periodic_orbit(
    model: LureModel, *, seed: int = 0, budget: Budget | None = None
) -> tuple[dict[str, Any] | None, Searched]:
    """An exactly confirmed periodic orbit (the witness) or None, with what was searched (its
    words: ``search_messages.searched_text``); not searched when its simulations do not fit
    ``budget`` (default ``Budget()``)."""
    if model.m == 0 or model.q <= 0 or model.threshold <= 0:
        return None, Searched(SearchCode.NO_NONLINEARITY, {"periodic": True})
    nbytes, flops = periodic_orbit_cost(model)
    refusal = (budget or Budget()).check(
        f"simulating {SAMPLES} initial errors for {STEPS:,} steps of the {model.N:,}-state "
        f"error dynamics",
        nbytes=nbytes,
        flops=flops,
    )
    if refusal is not None:
        return None, Searched(SearchCode.REFUSED, {"refusal": refusal})
    rng = np.random.default_rng(seed)
    start = rng.standard_normal((SAMPLES, model.N))
    start /= np.linalg.norm(start, axis=1, keepdims=True)
    start *= model.threshold * 10.0 ** rng.uniform(-1.0, 3.0, (SAMPLES, 1))
    with np.errstate(all="ignore"):
        path = model.simulate(start, STEPS)
        size = np.linalg.norm(path[-1], axis=1)  # (inf where it overflows: not alive)
    alive = np.isfinite(size) & (size > 1e-9 * model.threshold) & (size < 1e12 * model.threshold)
    tried = 0
    for i in np.flatnonzero(alive):
        scale = max(float(size[i]), model.threshold)
        for k in range(2, MAX_PERIOD + 1):
            if np.linalg.norm(path[-1, i] - path[-1 - k, i]) <= 1e-9 * scale:
                if k * model.N > EXACT_WORK:
                    break
                tried += 1
                witness = _confirm(model, path[-1 - k : -1, i])
                if witness is not None:
                    found = {"samples": SAMPLES, "steps": STEPS, "period": k}
                    return witness, Searched(SearchCode.ORBIT_FOUND, found)
                break
    none = {"samples": SAMPLES, "steps": STEPS, "alive": int(alive.sum()), "tried": tried}
    return None, Searched(SearchCode.NO_ORBIT, none)


def _pattern(w: np.ndarray, lam: float) -> np.ndarray:
    return np.where(w > lam, 1.0, np.where(w < -lam, -1.0, 0.0))


def _confirm(model: LureModel, states: np.ndarray) -> dict[str, Any] | None:
    """Solve the fixed point of the k-step affine map of the patterns that ``states`` (k, N)
    visit, exactly; the witness when iterating the true dynamics from it, exactly, returns
    to it after k steps and not before one step."""
    N, k = model.N, states.shape[0]
    exact = model.exact()
    if exact is None:  # the spec's exact data is beyond its budget: nothing is confirmed
        return None
    lam, q = Fraction(model.threshold), Fraction(model.q)
    A, B, Cw = exact.fractions("A"), exact.fractions("B"), exact.fractions("Cw")
    M = [[Fraction(int(i == j)) for j in range(N)] for i in range(N)]
    c = [Fraction(0)] * N
    for x in states:
        s = _pattern(x @ model.Cw.T, model.threshold)
        on = [j for j in range(model.m) if s[j] != 0]
        As = [row[:] for row in A]
        if on:
            BDCw = product([[B[i][j] for j in on] for i in range(N)], [Cw[j] for j in on])
            As = [[As[i][j] + q * BDCw[i][j] for j in range(N)] for i in range(N)]
        bs = [-q * lam * sum((B[i][j] * int(s[j]) for j in on), Fraction(0)) for i in range(N)]
        M = product(As, M)
        c = [v + b for v, b in zip((row[0] for row in product(As, [[v] for v in c])), bs)]
    K = [[Fraction(int(i == j)) - M[i][j] for j in range(N)] for i in range(N)]
    x0 = solve(K, c)
    if x0 is None or not any(x0):
        return None
    x = x0
    for step in range(1, k + 1):
        x = _exact_step(x, A, B, Cw, lam, q)
        if step == 1 and x == x0:
            return None  # an equilibrium, not an orbit
    if x != x0:
        return None
    point = np.array([float(v) for v in x0])
    replay = model.simulate(point, k)
    return {
        "kind": WitnessKind.PERIODIC_ORBIT,
        "initial_error": point[: model.n_e],
        "initial_attack_estimate": point[model.n_e :],
        "period": k,
        "steps": k,
        "orbit_norms": [float(v) for v in np.linalg.norm(replay, axis=1)],
        "exact": True,
        "float_residual": float(np.linalg.norm(replay[-1] - point)),
        "replay": "iterate xi+ = A xi + B q S(Cw xi) (no attack) from (initial_error, "
        "initial_attack_estimate): it returns there every `period` steps",
    }


def _exact_step(x: list[Fraction], A: list, B: list, Cw: list, lam: Fraction, q: Fraction) -> list:
    """One step of the true dynamics in exact arithmetic."""
    w = [sum((a * b for a, b in zip(row, x)), Fraction(0)) for row in Cw]
    phi = [q * (v - lam if v > lam else v + lam if v < -lam else Fraction(0)) for v in w]
    Ax = [sum((a * b for a, b in zip(row, x)), Fraction(0)) for row in A]
    return [
        Ax[i] + sum((B[i][j] * phi[j] for j in range(len(phi))), Fraction(0)) for i in range(len(x))
    ]
