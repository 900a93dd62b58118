"""Observer gains, each returned with its own verification.

Observers are written x_hat(k+1) = A x_hat(k) + L (y(k) - y_hat(k)), so the
linear error matrix is F = A - L C (the thesis's L1 is -L).

* ``place_gain``: ``scipy.signal.place_poles`` (Tits-Yang, what ``control.place``
  calls) on the dual pair, with the closed-loop
  eigenvalues re-checked against the requested ones (``place`` can return
  gains whose poles are far off, sometimes with only a warning);
* ``deadbeat_gain``: A - L C nilpotent with the smallest possible index
  (the observability index), for any number of sensors, verified by matrix
  powers; ``exact_deadbeat_gain``: the same construction in rational
  arithmetic.  Both, and their tests ``nilpotency`` and ``verify_deadbeat``,
  live in ``ssecert.design.deadbeat`` and are re-exported here;
* ``ogd_gain`` (L = step A C^T, the online-gradient observer of the lecture
  notes) and ``pinv_gain`` (L = A C^+ when C has full column rank).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..base.validation import as_float_option
from ..system import System
from ..tolerances import EPS, NONZERO, Tolerances, classify
from ._gain import Gain, GainError, GainMethod
from .deadbeat import (
    DEADBEAT_RTOL,
    DeadbeatCheck,
    Nilpotency,
    deadbeat_gain,
    exact_deadbeat_gain,
    nilpotency,
    verify_deadbeat,
)

__all__ = [
    "Gain",
    "GainError",
    "GainMethod",
    "place_gain",
    "deadbeat_gain",
    "exact_deadbeat_gain",
    "ogd_gain",
    "pinv_gain",
    "nilpotency",
    "Nilpotency",
    "verify_deadbeat",
    "DeadbeatCheck",
    "DEADBEAT_RTOL",
]


def _match_poles(got: np.ndarray, want: np.ndarray, scale: float) -> tuple[float, np.ndarray]:
    """Largest distance after optimally pairing computed and requested poles,
    and the per-pole tolerance allowing for repeated poles."""
    # scipy.optimize is imported here: it is a quarter of a second of every command's start
    from scipy.optimize import linear_sum_assignment

    cost = np.abs(got[:, None] - want[None, :])
    rows, cols = linear_sum_assignment(cost)
    dist = cost[rows, cols]
    mult = np.array([np.count_nonzero(np.abs(want - w) <= 1e-12 * scale) for w in want[cols]])
    tol = np.maximum(100 * math.sqrt(EPS), (100 * EPS) ** (1.0 / mult)) * scale
    return float((dist / tol).max()), dist


def place_gain(system: System, poles: Sequence[complex]) -> Gain:
    """Pole placement with ``scipy.signal.place_poles`` (Tits-Yang, as ``control.place``),
    re-checked.

    Parameters
    ----------
    system : System
    poles : sequence of complex
        n requested eigenvalues of A - L C (complex ones in conjugate pairs).

    Returns
    -------
    Gain
        ``details`` holds the requested and achieved poles and the mismatch.

    Raises
    ------
    GainError
        If the placement refuses, or if the eigenvalues of A - L C miss
        the requested ones by more than about sqrt(eps) relative (more for
        repeated poles).  A miss is an error, not a result.

    Examples
    --------
    >>> from ssecert import System
    >>> g = place_gain(System([[1.0, 0.1], [0.0, 1.0]], [[1.0, 0.0]]), [0.2, 0.3])
    >>> g.verified
    True
    """
    from scipy.signal import place_poles

    wanted = np.asarray(poles, dtype=complex)
    if wanted.shape != (system.n,):
        raise GainError(f"poles: expected {system.n} poles (one per state), got {wanted.size}")
    # with the states in units far apart, placed in the balanced units (A_b = S^-1 A S,
    # C_b = C S, L = S L_b: the same poles) and re-checked there
    units = _far_state_units(system)
    unit = np.ones(system.n) if units is None else units
    A_b, C_b = system.A * (unit[None, :] / unit[:, None]), system.C * unit[None, :]
    # place_poles needs B = C^T of full column rank: place with an independent subset of
    # sensors (pivoted QR) and give the others zero gain; the poles are re-checked below
    rows = _independent_rows(C_b)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            K = place_poles(A_b.T, C_b[rows].T, wanted, method="YT").gain_matrix
        except Exception as exc:  # ValueError, LinAlgError, ...
            raise GainError(f"pole placement refused: {exc}") from None
    L_b = np.zeros((system.n, system.p))
    L_b[:, rows] = np.asarray(K, dtype=float).T
    L = unit[:, None] * L_b
    F = system.A - L @ system.C
    got = np.linalg.eigvals(F if units is None else A_b - L_b @ C_b)
    scale = max(1.0, float(np.linalg.norm(A_b, 2)), float(np.abs(wanted).max(initial=0.0)))
    ratio, dist = _match_poles(got, wanted, scale)
    notes = [str(w.message) for w in caught]
    if ratio > 1.0:
        raise GainError(
            f"pole placement returned a gain whose poles miss the requested ones by up to "
            f"{dist.max():.2e} (tolerance exceeded {ratio:.1f} times)"
            + (f"; warnings: {'; '.join(notes)}" if notes else "")
        )
    return Gain(
        L=L,
        method=GainMethod.PLACE,
        error_matrix=F,
        verified=True,
        details={
            "requested_poles": wanted,
            "achieved_poles": got,
            "sensors_used": rows,
            "max_pole_error": float(dist.max()),
            "warnings": notes,
            **({} if units is None else {"state_scaling": units}),
        },
    )


def _independent_rows(C: np.ndarray) -> list[int]:
    """Sensors whose rows of C are linearly independent and span the row space (pivoted QR)."""
    import scipy.linalg

    _, R, piv = scipy.linalg.qr(C.T, mode="economic", pivoting=True)
    diag = np.abs(np.diag(R))
    if diag.size == 0 or diag[0] == 0:
        return list(range(C.shape[0]))
    rank = int(np.count_nonzero(diag > Tolerances().rtol(*C.shape) * diag[0]))
    return sorted(int(i) for i in piv[: max(rank, 1)])


def ogd_gain(system: System, step: float) -> Gain:
    """Online-gradient gain L = step * A C^T (lecture notes, Sec. 4.2).

    Examples
    --------
    >>> from ssecert import System
    >>> ogd_gain(System([[1.0]], [[1.0], [1.0]]), 0.25).L.tolist()
    [[0.25, 0.25]]
    """
    step = as_float_option(step, "step", min_value=0.0, min_inclusive=False)
    with np.errstate(over="ignore", invalid="ignore"):  # beyond the floats: inf, as computed
        L = step * system.A @ system.C.T
        error = system.A - L @ system.C
    return Gain(
        L=L,
        method=GainMethod.OGD,
        error_matrix=error,
        verified=True,
        details={"step": step},
    )


# states whose balancing spreads them by this much are in units far apart: the gains that
# rest on a rank or an eigenvalue problem are computed in the balanced units
_FAR_STATES = 2.0**16


def _far_state_units(system: System) -> np.ndarray | None:
    """The powers of two s of the plant's canonical state balancing (``state_balancing``)
    where they spread the states by ``_FAR_STATES`` or more, else None: x = diag(s) x_b, with
    A_b = S^-1 A S and C_b = C S exact, and a gain L_b of the balanced plant is L = S L_b
    (A - L C = S (A_b - L_b C_b) S^-1)."""
    from ..numerics.linalg import state_balancing

    s = state_balancing(system.A, system.C, canonical=True)
    if s is None or float(np.max(s) / np.min(s)) < _FAR_STATES:
        return None
    return s


def pinv_gain(system: System) -> Gain:
    """Pseudo-inverse gain L = A C^+, for C of full column rank (then A - L C = 0).

    Raises
    ------
    GainError
        If C does not have full column rank.

    Examples
    --------
    >>> from ssecert import System
    >>> g = pinv_gain(System([[0.5, 1.0], [0.0, 0.5]], [[1, 0], [0, 1], [1, 1]]))
    >>> float(abs(g.error_matrix).max()) < 1e-12
    True
    """
    # with the states in units far apart, the rank and C^+ = S (C S)^+ (full column rank) of
    # the balanced C S: C's own singular values would mix the units
    units = _far_state_units(system)
    scale = np.ones(system.n) if units is None else units
    C = system.C * scale[None, :]
    s = np.linalg.svd(C, compute_uv=False)
    tol = Tolerances().rtol(*C.shape) * max(float(s[0]), np.finfo(float).tiny)
    rank = int(np.count_nonzero(classify(s, tol) == NONZERO))
    if rank < system.n:
        raise GainError(
            f"the pseudo-inverse gain A C^+ needs C of full column rank; rank(C) = {rank} < "
            f"n = {system.n}"
        )
    with np.errstate(over="ignore", invalid="ignore"):  # beyond the floats: inf, as computed
        L = (system.A * scale[None, :]) @ np.linalg.pinv(C)
        error = system.A - L @ system.C
    details: dict[str, Any] = {"rank_C": rank}
    if units is not None:
        details["state_scaling"] = units
    return Gain(
        L=L,
        method=GainMethod.PINV,
        error_matrix=error,
        verified=True,
        details=details,
    )
