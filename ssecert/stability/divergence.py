"""Divergent trajectories of a sparse observer's large-signal loop.

Far from the origin the soft threshold is the identity minus a bounded
term: q S(w) = q w - delta with |delta_i| <= q * threshold.  The error
state of a Lur'e model (``ssecert.observers.lure``) then reads

    xi+ = M xi - B delta,   M = A + q B Cw   (the sector's upper end),

so along a left eigenvector w of M (w' M = mu w') the scalar s = w' xi obeys
|s+| >= |mu| |s| - beta with beta = q * threshold * ||B' w||_1.  When
|mu| > 1, every initial state with |s| > s* = beta / (|mu| - 1) gives
|s_k| - s* >= |mu|^k (|s_0| - s*): the error grows without bound and the
observer is not globally asymptotically stable.  ``divergence_witness``
finds such an initial error (with a_hat(0) = 0 when the unstable mode can
be reached from the estimation error alone) and replays it by simulating
the Lur'e model, which must show the growth before the witness is given.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..observers.lure import LureModel
from .outcomes import WitnessKind

__all__ = ["divergence_witness", "safe_norms", "GROWTH"]

GROWTH = 1000.0  # the factor by which the replayed trajectory must grow along w
MAX_STEPS = 5000  # longest replay


def divergence_witness(model: LureModel) -> dict[str, Any] | None:
    """A replayed divergent trajectory of the observer's error, or None.

    None when the model has no nonlinearity, when the large-signal loop M
    has no eigenvalue clearly outside the unit circle (beyond its
    floating-point error bound), or when the replay does not confirm the
    growth.  When nothing is found in the model's own coordinates and its states' units
    differ widely, the search runs again in balanced coordinates xi = diag(s) xi_b (exact),
    and the witness found there is mapped back and replayed in the model's own.
    """
    if model.m == 0 or model.q <= 0:
        return None
    if not model.finite():
        return None  # beyond the float range: no replay can confirm growth
    found = _in_units(model)
    if found is not None:
        return found
    s = model.balancing()
    if s is None:
        return None
    inner = _in_units(model.scaled(s))
    if inner is None:
        return None
    xi0 = np.concatenate([inner["initial_error"], inner["initial_attack_estimate"]]) * s
    w = inner["left_eigenvector"] / s  # w' xi = w_b' xi_b
    with np.errstate(over="ignore", invalid="ignore"):
        path = model.simulate(xi0, inner["steps"])
    along = np.abs(path @ w)
    if not (np.all(np.isfinite(along)) and along[-1] >= GROWTH * along[0] * 0.5):
        return None
    norms = safe_norms(path)
    return {
        **inner,
        "left_eigenvector": w,
        "initial_error": xi0[: model.n_e],
        "initial_attack_estimate": xi0[model.n_e :],
        "along_eigenvector": [float(along[0]), float(along[-1])],
        "norms": [float(norms[0]), float(norms[-1])],
        "growth": float(norms[-1] / norms[0]),
        "state_scaling": s,
        "balanced": "found in balanced coordinates xi = diag(state_scaling) xi_b (beta and "
        "escape_level are in them) and replayed in the model's own",
    }


def _in_units(model: LureModel) -> dict[str, Any] | None:
    """``divergence_witness`` in the model's own coordinates."""
    M = model.vertex(model.q)
    # M's floats are within (1 + q ||B||) d of the loop of the spec's exact data
    spread = (1.0 + model.q * float(np.linalg.norm(model.B, 2))) * model.rounding
    mu, w, error = _dominant_left_pair(M, spread)
    if mu is None or w is None or abs(mu) - 1.0 <= max(1e-9, 100.0 * error):
        return None
    beta = model.q * model.threshold * float(np.abs(model.B.T @ w).sum())
    bound = beta / (abs(mu) - 1.0)
    xi0 = _initial_state(w, model.n_e, bound)
    if xi0 is None:
        return None
    steps = min(MAX_STEPS, math.ceil(math.log(GROWTH) / math.log(abs(mu))) + 1)
    with np.errstate(over="ignore", invalid="ignore"):
        path = model.simulate(xi0, steps)
        along = np.abs(path @ w)
    # a loop eigenvalue of 1e200 leaves the float range in two steps: the replay ends at its
    # last finite step, which must show the growth
    finite = np.isfinite(along) & np.all(np.isfinite(path), axis=-1)
    steps = int(np.argmin(finite)) - 1 if not np.all(finite) else steps
    if steps < 1:
        return None
    path, along = path[: steps + 1], along[: steps + 1]
    if not along[-1] >= GROWTH * along[0] * 0.5:
        return None
    norms = safe_norms(path)
    return {
        "kind": WitnessKind.DIVERGENT_TRAJECTORY,
        "large_signal_eigenvalue": complex(mu),
        "eigenvalue_error_bound": error,
        "left_eigenvector": w,
        "beta": beta,
        "escape_level": bound,
        "initial_error": xi0[: model.n_e],
        "initial_attack_estimate": xi0[model.n_e :],
        "steps": steps,
        "along_eigenvector": [float(along[0]), float(along[-1])],
        "norms": [float(norms[0]), float(norms[-1])],
        "growth": float(norms[-1] / norms[0]),
        "verified": True,
        "replay": "simulate xi+ = A xi + B q S(Cw xi) from (initial_error, "
        "initial_attack_estimate) for `steps` steps (no attack)",
    }


def safe_norms(path: np.ndarray) -> np.ndarray:
    """The 2-norm of each state of ``path`` without overflow (entries near 1e200 square to
    inf): scaled by the largest entry first."""
    top = np.max(np.abs(path), axis=-1)
    safe = np.where(top > 0, top, 1.0)
    return top * np.linalg.norm(path / safe[..., None], axis=-1)


def _dominant_left_pair(
    M: np.ndarray, rounding: float = 0.0
) -> tuple[complex | None, np.ndarray | None, float]:
    """The eigenvalue of largest modulus, a unit left eigenvector and a first-order error bound
    of the eigenvalue ((n eps ||M|| + rounding) times its condition number; ``rounding``
    bounds the distance of M from the matrix it stands for)."""
    values, left = np.linalg.eig(M.T)  # M' w = mu w, i.e. w' M = mu w'
    if not np.all(np.isfinite(values)):
        return None, None, math.inf
    i = int(np.argmax(np.abs(values)))
    mu, w = values[i], left[:, i]
    right_values, right = np.linalg.eig(M)
    j = int(np.argmin(np.abs(right_values - mu)))
    v = right[:, j]
    overlap = float(abs(np.vdot(np.conj(w), v)))  # |w' v| with unit w and v
    condition = 1.0 / max(overlap, float(np.finfo(float).tiny))
    scale = max(float(np.linalg.norm(M, 2)), 1.0)
    error = (float(np.finfo(float).eps) * scale * M.shape[0] + rounding) * condition
    if abs(mu.imag) <= error:
        mu, w = complex(mu.real), w.real / np.linalg.norm(w.real)
    return complex(mu), w, float(error)


def _initial_state(w: np.ndarray, n_e: int, bound: float) -> np.ndarray | None:
    """A real initial state with |w' xi0| = 10 max(s*, 1): an estimation error alone (a_hat(0) = 0,
    as an observer starts) when the mode can be reached so, else with an attack estimate."""
    target = 10.0 * max(bound, 1.0)
    for block in (slice(0, n_e), slice(0, w.size)):
        best: np.ndarray | None = None
        for phase in (1.0, 1j):
            xi = np.zeros(w.size)
            xi[block] = np.real(phase * np.conj(w[block]))
            s = abs(w @ xi)
            if s > 1e-8 * np.linalg.norm(xi) and (best is None or s > abs(w @ best)):
                best = xi * (target / s)
        if best is not None:
            return best
    return None
