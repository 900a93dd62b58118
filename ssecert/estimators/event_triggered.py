"""Event-triggered projected estimators of Shoukry and Tabuada (2016).

Y. Shoukry and P. Tabuada, "Event-triggered state observers for sparse
sensor noise/attacks", IEEE Trans. Autom. Control 61(8):2079-2091, 2016
(arXiv:1309.3511), the ETPG and ETPL baselines of the Lasso paper
(``000_54a7d7b08416ec4b.txt``, Secs. 1, 3 and 5).

With z = (x, E), the measurements are Y = M x + E = Q z, Q = [M I], and E
is block s-sparse: at most s sensors own nonzero rows of E.  Both methods
descend V(z) = (1/2) ||Y - Q z||^2 by gradient steps

    z <- z + step Q^T (Y - Q z)

alternated with the projection Pi onto R^n x S_s (Definition 4.1: the rows
of the s sensors with the largest ||E_i|| are kept, the others set to zero).
An event decides when to project: gradient steps go on until the projected
point lowers V by the factor (1 - nu) against the last projection.

* ``etpg``: Algorithm 1 (ETPG), a static decoder, batched over runs;
* ``ETPLObserver``: Algorithm 2 (ETPL), the recursive version, a dynamic
  observer on the window of the last tau samples, batched over runs;
* ``etpg_condition``: condition 2 of Theorems 4.4 and 5.2, the
  2s-restricted eigenvalue delta_2s > (4/9) lambda_max(Q^T Q), by
  enumeration.

``M`` is the sensing matrix (C, or the stacked O_tau whose row ``k * p + i``
is sensor ``i`` at step ``k``) and ``sensors_of_row`` names the sensor of
each row, as for ``l0_decoder``.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..base.validation import as_float_option, as_int_option, as_real_matrix
from ..observers.dynamic import DynamicObserver
from .decoders import _as_measurements, _as_sensing_matrix
from .support_decoders import _as_sensor_map

__all__ = [
    "RestrictedEigenvalue",
    "ETPGSolution",
    "etpg_condition",
    "etpg",
    "ETPLObserver",
]

DEFAULT_NU = 0.1
DEFAULT_TOL = 1e-10
DEFAULT_STEP_FRACTION = 0.99  # of the largest step Theorem 4.4 allows, 1 / lambda_max(Q^T Q)
DEFAULT_MAX_SETS = 1_000_000
FOUR_NINTHS = 4.0 / 9.0
_CHUNK_BYTES = 8 * 2**20


# ---------------------------------------------------------------------------
# condition 2 of Theorem 4.4: the 2s-restricted eigenvalue


@dataclass(frozen=True)
class RestrictedEigenvalue:
    """Result of ``etpg_condition``.

    Attributes
    ----------
    delta : float
        The restricted eigenvalue delta_k (Definition 3.3, k = ``size``):
        the least lambda_min(Q_G^T Q_G) over sets G of k sensors, where
        Q_G = [M I_G^T] keeps the identity columns of the rows of G.
    lambda_max : float
        lambda_max(Q^T Q) = ||M||_2^2 + 1.
    ratio : float
        delta / lambda_max, at most 1.
    holds : bool
        Whether ``ratio > 4/9``, condition 2 of Theorems 4.4 and 5.2 (with
        k = 2s).  When it fails the theorems say nothing; ETPG and ETPL may
        still converge.
    nu_bound : float
        1 - 4 / (9 ratio): with ``holds``, every trigger constant
        0 < nu < nu_bound meets the proof of Proposition 4.11 (its
        beta = 1); <= 0 when ``holds`` is False.
    worst_sensors : tuple of int
        A set of ``size`` sensors attaining ``delta``.
    size : int
        Sensors per set (2s).
    sets : int
        Sets enumerated.
    """

    delta: float
    lambda_max: float
    ratio: float
    holds: bool
    nu_bound: float
    worst_sensors: tuple[int, ...]
    size: int
    sets: int


def etpg_condition(
    M: Any,
    s: int,
    *,
    sensors_of_row: Sequence[int] | np.ndarray | None = None,
    max_sets: int = DEFAULT_MAX_SETS,
) -> RestrictedEigenvalue:
    """Condition 2 of Theorems 4.4 and 5.2: delta_2s > (4/9) lambda_max(Q^T Q).

    delta_2s is the 2s-restricted eigenvalue (Definition 3.3 and
    Proposition 3.4 of Shoukry and Tabuada, 2016), computed by enumerating
    every set of 2s sensors; Q = [M I].  The Lasso paper (Example 1) shows
    the condition failing on three equal sensors, where Lasso succeeds.

    Parameters
    ----------
    M : array_like, shape (m, n)
        Sensing matrix (C, or the stacked O_tau).
    s : int
        Largest number of attacked sensors, 0 <= s; sets have
        min(2s, number of sensors) sensors.
    sensors_of_row : sequence of int, optional
        Sensor (0-based) owning each row of ``M``; default, each row is its
        own sensor.  For O_tau with p sensors: ``numpy.tile(numpy.arange(p), tau)``.
    max_sets : int, default 1000000
        Largest number of sets to enumerate; more is refused.

    Returns
    -------
    RestrictedEigenvalue

    Raises
    ------
    TypeError
        If an argument has the wrong kind.
    ValueError
        If ``sensors_of_row`` does not match ``M``, ``s < 0`` or the
        enumeration would exceed ``max_sets``.

    Examples
    --------
    The Lasso paper's Example 1 (alpha = 2): r = (13 - sqrt(153)) / 2 < (4/9) 13.

    >>> cond = etpg_condition([[2.0], [2.0], [2.0]], 1)
    >>> round(cond.delta, 6), round(cond.lambda_max, 9), cond.holds
    (0.315342, 13.0, False)
    """
    M = _as_sensing_matrix(M)
    m, n = M.shape
    sensors, q = _as_sensor_map(sensors_of_row, m)
    s = as_int_option(s, "s", min_value=0)
    max_sets = as_int_option(max_sets, "max_sets", min_value=1)
    size = min(2 * s, q)
    total = math.comb(q, size)
    if total > max_sets:
        raise ValueError(
            f"etpg_condition would enumerate {total} sets of {size} of {q} sensors, more than "
            f"max_sets = {max_sets}; raise max_sets"
        )
    lambda_max = float(np.linalg.norm(M, 2)) ** 2 + 1.0 if M.size else 1.0
    rows_of = [np.flatnonzero(sensors == i) for i in range(q)]
    gram = M.T @ M
    best = np.inf
    worst: tuple[int, ...] = ()
    # sets whose rows number alike are stacked and decided by one batched eigvalsh
    groups: dict[int, list[tuple[int, ...]]] = {}
    for subset in itertools.combinations(range(q), size):
        groups.setdefault(sum(rows_of[i].size for i in subset), []).append(subset)
    for width, subsets in groups.items():
        chunk = max(1, _CHUNK_BYTES // (8 * (n + width) ** 2))
        for start in range(0, len(subsets), chunk):
            block = subsets[start : start + chunk]
            grams = np.empty((len(block), n + width, n + width))
            grams[:, :n, :n] = gram
            grams[:, n:, n:] = np.eye(width)
            for j, subset in enumerate(block):
                rows = np.concatenate([rows_of[i] for i in subset] or [np.zeros(0, np.int64)])
                grams[j, n:, :n] = M[rows]
                grams[j, :n, n:] = M[rows].T
            least = np.linalg.eigvalsh(grams)[:, 0]
            j = int(np.argmin(least))
            if least[j] < best:
                best, worst = float(least[j]), block[j]
    delta = max(best, 0.0)  # rounding can leave a zero eigenvalue slightly negative
    ratio = delta / lambda_max
    return RestrictedEigenvalue(
        delta=delta,
        lambda_max=lambda_max,
        ratio=ratio,
        holds=bool(ratio > FOUR_NINTHS),
        nu_bound=1.0 - FOUR_NINTHS / ratio if ratio > 0 else -np.inf,
        worst_sensors=tuple(int(i) for i in worst),
        size=size,
        sets=total,
    )


# ---------------------------------------------------------------------------
# the event-triggered descent shared by ETPG and ETPL


class _Blocks:
    """Projection Pi onto R^n x S_s (Definition 4.1) for rows grouped by sensor."""

    def __init__(self, sensors: np.ndarray, q: int, s: int) -> None:
        self.sensors, self.q, self.s = sensors, q, s
        self.member = np.zeros((sensors.size, q))
        self.member[np.arange(sensors.size), sensors] = 1.0

    def keep(self, E: np.ndarray) -> np.ndarray:
        """The s sensors with the largest ||E_i||, as a mask (runs, q).

        Ties go to the lower sensor index (a stable sort), one of the
        minimisers Remark 4.3 allows.
        """
        keep = np.zeros((E.shape[0], self.q), dtype=bool)
        if self.s > 0:
            energy = (E * E) @ self.member
            if self.s == 1:  # argmax takes the first of equal maxima, as the stable sort does
                keep[np.arange(E.shape[0]), np.argmax(energy, axis=1)] = True
            else:
                top = np.argsort(-energy, axis=1, kind="stable")[:, : self.s]
                keep[np.arange(E.shape[0])[:, None], top] = True
        return keep

    def project(self, E: np.ndarray) -> np.ndarray:
        """Pi'(E): the rows of the kept sensors, zero elsewhere."""
        return E * self.keep(E)[:, self.sensors]


def _descend(
    M: np.ndarray,
    blocks: _Blocks,
    Y: np.ndarray,
    z_pi: np.ndarray,
    v_pi: np.ndarray,
    level: np.ndarray,
    alpha: np.ndarray,
    step: float,
    nu: float,
    max_outer: int,
    max_inner: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The projected-gradient loops of Algorithms 1 and 2, all runs in lock step.

    Each run starts from its projected point z_pi (with V(z_pi) = v_pi) and, while
    v_pi > max(level, alpha), runs an inner loop of gradient steps from z_pi
    until V(Pi(z)) < (1 - nu) v_pi or V(Pi(z)) <= alpha; then z_pi = Pi(z).
    A run stops on its own, so its numbers do not depend on the batch.

    Returns the last iterate z (unprojected; z_pi for a run that made no
    step), z_pi, v_pi, the projections made, the gradient steps, and whether an
    inner loop ran out of ``max_inner`` steps (stalled; the run then keeps
    the better of its last two projections).
    """
    runs, n = Y.shape[0], M.shape[1]
    z_pi, v_pi = z_pi.copy(), v_pi.copy()
    Z = z_pi.copy()
    outer = np.zeros(runs, dtype=np.int64)
    steps = np.zeros(runs, dtype=np.int64)
    stalled = np.zeros(runs, dtype=bool)
    active = np.flatnonzero(v_pi > np.maximum(level, alpha))
    if active.size == 0:
        return Z, z_pi, v_pi, outer, steps, stalled
    x, E = z_pi[active, :n].copy(), z_pi[active, n:].copy()
    Ya, floor, guard = Y[active], alpha[active], np.maximum(level, alpha)[active]
    r = Ya - x @ M.T - E  # residual at the current iterate
    v_start = v_pi[active].copy()
    inner = np.zeros(active.size, dtype=np.int64)
    Mt = M.T
    threshold = (1.0 - nu) * v_start
    while True:
        x += step * (r @ M)
        E += step * r
        r = Ya - x @ Mt - E
        dropped = E * ~blocks.keep(E)[:, blocks.sensors]
        rp = r + dropped  # residual at Pi(z)
        v = 0.5 * np.vecdot(rp, rp)
        inner += 1
        fired = (v < threshold) | (v <= floor)
        out = ~fired & (inner >= max_inner)
        if not (fired.any() or out.any()):
            continue
        ended = fired | out
        steps[active[ended]] += inner[ended]
        better = fired | (out & (v < v_pi[active]))
        idx = active[better]
        z_pi[idx, :n] = x[better]
        z_pi[idx, n:] = E[better] - dropped[better]
        v_pi[idx] = v[better]
        Z[active[ended], :n] = x[ended]
        Z[active[ended], n:] = E[ended]
        outer[active[fired]] += 1
        stalled[active[out]] = True
        # a fired run goes on from its projection (line 3 of Algorithm 1)
        E[fired] -= dropped[fired]
        r[fired] = rp[fired]
        threshold[fired] = (1.0 - nu) * v[fired]
        inner[ended] = 0
        done = out | (fired & ((v <= guard) | (outer[active] >= max_outer)))
        if done.any():
            stay = ~done
            if not stay.any():
                break
            active, x, E, r, Ya = active[stay], x[stay], E[stay], r[stay], Ya[stay]
            floor, guard, threshold, inner = floor[stay], guard[stay], threshold[stay], inner[stay]
    return Z, z_pi, v_pi, outer, steps, stalled


def _lambda_max(M: np.ndarray) -> float:
    """lambda_max(Q^T Q) = ||M||_2^2 + 1 for Q = [M I]."""
    return (float(np.linalg.norm(M, 2)) ** 2 if M.size else 0.0) + 1.0


def _as_step(step: Any, lambda_max: float) -> float:
    """Theorem 4.4 condition 1 (and Theorem 5.2 with Sigma = step I): 0 < step < 1 / lambda_max."""
    bound = 1.0 / lambda_max
    if step is None:
        return DEFAULT_STEP_FRACTION * bound
    step = as_float_option(step, "step", min_value=0.0, min_inclusive=False)
    if step >= bound:
        raise ValueError(
            f"step must be < 1 / lambda_max(Q^T Q) = {bound:.6g} (lambda_max = ||M||_2^2 + 1 = "
            f"{lambda_max:.6g}; condition 1 of Theorem 4.4), got {step}"
        )
    return step


def _as_nu(nu: Any) -> float:
    return as_float_option(
        nu, "nu", min_value=0.0, max_value=1.0, min_inclusive=False, max_inclusive=False
    )


# ---------------------------------------------------------------------------
# Algorithm 1: ETPG


@dataclass(frozen=True)
class ETPGSolution:
    """Result of ``etpg``.

    For a single measurement vector the per-run fields are scalars (and
    ``support`` a 1-D mask); for a batch of ``runs`` they have one entry
    (row) per run.

    Attributes
    ----------
    x : ndarray, shape (n,) or (runs, n)
        State estimate, x of the last projected point z_Pi.
    a : ndarray, shape (m,) or (runs, m)
        Attack estimate E of z_Pi: zero outside the rows of ``support``.
    support : ndarray of bool, shape (q,) or (runs, q)
        The s sensors the last projection kept (some may carry a zero
        block).
    iterations : int or ndarray of int
        Outer iterations (projections) performed.
    gradient_steps : int or ndarray of int
        Gradient steps performed, over all inner loops.
    converged : bool or ndarray of bool
        Whether V(z_Pi) <= alpha = (1/2) (tol ||y||)^2 was reached: the
        termination test of Algorithm 1.
    stalled : bool or ndarray of bool
        Whether an inner loop ran ``max_inner`` steps without its trigger
        (the data admit no s-sparse fit below alpha, as with noise, or the
        conditions of Theorem 4.4 fail); the run then stopped with its best
        projection.
    residual : float or ndarray
        ||y - M x - a|| = sqrt(2 V(z_Pi)).
    tol : float
        Relative termination tolerance asked for.
    step : float
        Gradient step eta.
    nu : float
        Trigger constant.
    """

    x: np.ndarray
    a: np.ndarray
    support: np.ndarray
    iterations: int | np.ndarray
    gradient_steps: int | np.ndarray
    converged: bool | np.ndarray
    stalled: bool | np.ndarray
    residual: float | np.ndarray
    tol: float
    step: float
    nu: float


def etpg(
    M: Any,
    y: Any,
    s: int,
    *,
    sensors_of_row: Sequence[int] | np.ndarray | None = None,
    step: float | None = None,
    nu: float = DEFAULT_NU,
    tol: float = DEFAULT_TOL,
    max_outer: int = 10_000,
    max_inner: int = 1_000,
) -> ETPGSolution:
    """Event-triggered projected gradient descent (ETPG, Algorithm 1 of Shoukry and Tabuada).

    Estimates z = (x, E) in R^n x S_s from y = M x + E by

        z_Pi(0) = 0;  while V(z_Pi(k-1)) > alpha:
            z(k, 0) = z_Pi(k-1)
            repeat z(k, m+1) = z(k, m) + step Q^T (y - Q z(k, m))
            until V(Pi(z(k, m))) < (1 - nu) V(z_Pi(k-1))
            z_Pi(k) = Pi(z(k, m))

    with V(z) = (1/2) ||y - Q z||^2, Q = [M I] and Pi the projection onto
    R^n x S_s (Definition 4.1: keep the rows of the s sensors with the
    largest ||E_i||).  Theorem 4.4: when the plant is 2s-sparse observable,
    0 < step < 1 / lambda_max(Q^T Q) and delta_2s > (4/9) lambda_max(Q^T Q)
    (see ``etpg_condition``), the estimate converges to the solution for a
    small enough nu.  Followed: Algorithm 1, Definition 4.1 and Theorem
    4.4 of the paper (arXiv:1309.3511; the TAC version, 61(8), 2016); the
    public MATLAB reading of the projection in ZYblend/Resilient_Observers_Comparison
    (``Resilient_Optimizer/projection.m``) agrees.  The paper's loop guard
    V >= alpha is read as V > alpha, so that y = 0 stops at once, and the
    inner loop also ends when V(Pi(z)) <= alpha.

    Parameters
    ----------
    M : array_like, shape (m, n)
        Sensing matrix (C, or the stacked O_tau).
    y : array_like, shape (m,) or (runs, m)
        Measurements; a 2-D array is a batch solved at once.
    s : int
        Largest number of attacked sensors, 0 <= s < number of sensors.
    sensors_of_row : sequence of int, optional
        Sensor (0-based) owning each row of ``M``; default, each row is its
        own sensor.  For O_tau with p sensors: ``numpy.tile(numpy.arange(p), tau)``.
    step : float, optional
        Gradient step eta, 0 < eta < 1 / lambda_max(Q^T Q) with
        lambda_max = ||M||_2^2 + 1 (condition 1 of Theorem 4.4); default
        0.99 / lambda_max.
    nu : float, default 0.1
        Trigger constant in (0, 1): an inner loop ends when the projected
        point lowers V by the factor (1 - nu).  Proposition 4.11 proves the
        trigger is met for nu < ``etpg_condition(...).nu_bound`` when
        condition 2 holds.
    tol : float, default 1e-10
        The run stops when ||y - Q z_Pi|| <= tol ||y||, i.e. the paper's
        alpha = (1/2) (tol ||y||)^2.
    max_outer : int, default 10000
        Largest number of outer iterations (projections) per run.
    max_inner : int, default 1000
        Largest number of gradient steps in one inner loop; a run whose
        trigger is not met by then stops (``stalled``).

    Returns
    -------
    ETPGSolution

    Raises
    ------
    TypeError
        If an argument has the wrong kind.
    ValueError
        If ``y`` or ``sensors_of_row`` does not match ``M``, ``s`` is out of
        range, ``step`` is outside (0, 1 / lambda_max), ``nu`` outside
        (0, 1), ``tol < 0`` or a budget < 1.

    Examples
    --------
    Three sensors of x = 1, the third attacked by +4:

    >>> sol = etpg([[1.0], [1.0], [1.0]], [1.0, 1.0, 5.0], 1)
    >>> sol.converged, round(float(sol.x[0]), 9), sol.support.tolist()
    (True, 1.0, [False, False, True])
    """
    M = _as_sensing_matrix(M)
    m, n = M.shape
    y = _as_measurements(y, m, batched=True)
    single = y.ndim == 1
    Y = np.array(y, ndmin=2)
    sensors, q = _as_sensor_map(sensors_of_row, m)
    s = as_int_option(s, "s", min_value=0, max_value=q - 1)
    eta = _as_step(step, _lambda_max(M))
    nu = _as_nu(nu)
    tol = as_float_option(tol, "tol", min_value=0.0)
    max_outer = as_int_option(max_outer, "max_outer", min_value=1)
    max_inner = as_int_option(max_inner, "max_inner", min_value=1)

    runs = Y.shape[0]
    energy = np.vecdot(Y, Y)
    alpha = 0.5 * tol * tol * energy
    Z0 = np.zeros((runs, n + m))
    blocks = _Blocks(sensors, q, s)
    _, z_pi, v_pi, outer, steps, stalled = _descend(
        M, blocks, Y, Z0, 0.5 * energy, np.zeros(runs), alpha, eta, nu,
        max_outer, max_inner,
    )  # fmt: skip
    keep = blocks.keep(z_pi[:, n:])
    converged = v_pi <= alpha
    residual = np.sqrt(2.0 * v_pi)
    x, a = z_pi[:, :n], z_pi[:, n:]
    if single:
        return ETPGSolution(
            x[0].copy(), a[0].copy(), keep[0].copy(), int(outer[0]), int(steps[0]),
            bool(converged[0]), bool(stalled[0]), float(residual[0]), tol, eta, nu,
        )  # fmt: skip
    return ETPGSolution(
        x.copy(), a.copy(), keep, outer, steps, converged, stalled, residual, tol, eta, nu
    )


# ---------------------------------------------------------------------------
# Algorithm 2: ETPL


class ETPLObserver(DynamicObserver):
    """Event-triggered projected Luenberger observer (ETPL, Algorithm 2 of Shoukry and Tabuada).

    The recursive ETPG: the estimate z(t) = (x(t - tau + 1), E(t)) of the
    window of the last tau samples, with Q = [O_tau I] and
    V(z) = (1/2) ||Y(t) - Q z||^2, is updated at each sample by

    a) the time update z_T(t) = Abar z(t-1) + Bbar ubar(t-1) (Sec. V-A, no
       input here): x moves by A, each sensor's block of E moves one step
       (the oldest sample dropped) and its new last entry is
       y_i(t) - C_i A^tau x(t - tau);
    b) the event-triggered projected Luenberger update: from
       z_Pi(t) = Pi(z_T(t)), while V(z_Pi(t)) >= (1 - nu) V(z_Pi(t-1)),
       an inner loop of Luenberger steps z <- z + L (Y(t) - Q z) with
       L = Q^T Sigma, Sigma = step I, until V(Pi(z)) < (1 - nu) V(z_Pi(t)),
       then z_Pi(t) = Pi(z).  The estimate is the last z (Algorithm 2's
       z(t) := z^(m)(t)), or z_Pi(t) when no update was needed.

    Theorem 5.2: with 2s-sparse observability, delta_2s >
    (4/9) lambda_max(Q^T Q) (``etpg_condition(O_tau, s, ...)``) and
    step < 1 / lambda_max(Q^T Q), the estimate converges.  Followed:
    Algorithm 2, Sec. V-A and Theorem 5.2 of the paper (arXiv:1309.3511;
    the TAC version, 61(8), 2016), and the public MATLAB reading in
    ZYblend/Resilient_Observers_Comparison (``ETLO_params.m``,
    ``solver_event_luenburger.m``) for Abar.  Two readings of ours: the
    loop guard is evaluated at Pi of the point the inner loop ended on (the
    listing resets z_Pi(t) at the top of the loop, so its guard sees the
    value from one loop earlier), and both loops also stop once
    V <= alpha = (1/2) (tol ||Y(t)||)^2 (the listing's guard never ends
    once V = 0), with the budgets ``max_outer`` and ``max_inner`` per
    sample.

    Conventions follow ``WindowSSO``: Y(t) stacks the window step-major
    (row k p + i is sensor i at sample t - tau + 1 + k, as ``O_tau``), the
    estimates stay at zero until the window is full, and the state held
    after sample t is A x(t - tau + 1), so ``delay = tau - 1``: x_hat[k]
    of ``run`` estimates x(k - tau + 1).  ``a_hat`` is E(t), shape p tau.

    Parameters
    ----------
    A : array_like, shape (n, n)
    C : array_like, shape (p, n)
    s : int
        Largest number of attacked sensors, 0 <= s < p.
    window : int, optional
        tau >= 1; default n (the paper's choice; tau = 1 is the online
        observer of the Lasso paper's Fig. 4).
    step : float, optional
        Sigma = step I; 0 < step < 1 / lambda_max(Q^T Q) =
        1 / (||O_tau||_2^2 + 1) (Theorem 5.2); default 0.99 / lambda_max.
    nu : float, default 0.1
        Trigger constant in (0, 1).
    tol : float, default 1e-10
        alpha = (1/2) (tol ||Y(t)||)^2: below it V counts as zero.
    max_outer : int, default 100
        Largest number of projections per sample.
    max_inner : int, default 1000
        Largest number of Luenberger steps per inner loop.

    Raises
    ------
    TypeError
        If an argument has the wrong kind.
    ValueError
        If ``C`` does not have n columns, ``s`` or ``window`` is out of
        range, ``step`` is outside (0, 1 / lambda_max), ``nu`` outside
        (0, 1), ``tol < 0`` or a budget < 1.

    Examples
    --------
    Three sensors of a constant x = 1, the third attacked by +4:

    >>> import numpy as np
    >>> obs = ETPLObserver([[1.0]], [[1.0], [1.0], [1.0]], 1, window=1)
    >>> traj = obs.run(np.tile([1.0, 1.0, 5.0], (200, 1, 1)))
    >>> round(float(traj.x_hat[-1, 0, 0]), 6), round(float(traj.a_hat[-1, 0, 2]), 6)
    (1.0, 4.0)
    """

    def __init__(
        self,
        A: Any,
        C: Any,
        s: int,
        *,
        window: int | None = None,
        step: float | None = None,
        nu: float = DEFAULT_NU,
        tol: float = DEFAULT_TOL,
        max_outer: int = 100,
        max_inner: int = 1_000,
    ) -> None:
        self.A = as_real_matrix(A, "A")
        n = self.A.shape[0]
        if self.A.shape != (n, n):
            raise ValueError(f"A must be square, got shape {self.A.shape}")
        self.C = as_real_matrix(C, "C", shape=(None, n), shape_hint="the number of states")
        p = self.C.shape[0]
        self.n, self.m = n, p
        self.s = as_int_option(s, "s", min_value=0, max_value=p - 1)
        self.window = n if window is None else as_int_option(window, "window", min_value=1)
        self.delay = self.window - 1
        blocks = [self.C]
        for _ in range(self.window - 1):
            blocks.append(blocks[-1] @ self.A)
        self.O = np.vstack(blocks)  # (p tau, n), step-major
        self.lambda_max = _lambda_max(self.O)
        self.step_size = _as_step(step, self.lambda_max)
        self.nu = _as_nu(nu)
        self.tol = as_float_option(tol, "tol", min_value=0.0)
        self.max_outer = as_int_option(max_outer, "max_outer", min_value=1)
        self.max_inner = as_int_option(max_inner, "max_inner", min_value=1)
        self._blocks = _Blocks(np.tile(np.arange(p), self.window), p, self.s)
        self._last_row = blocks[-1]  # C A^(tau-1): the new sample from the held A x(t - tau)

    def initial_state(self, runs: int) -> dict[str, np.ndarray]:
        return {
            "x_hat": np.zeros((runs, self.n)),
            "a_hat": np.zeros((runs, self.O.shape[0])),
            "v_prev": np.zeros(runs),
            "buffer": np.zeros((runs, self.window, self.m)),
            "filled": np.zeros((), dtype=np.int64),
        }

    def step(self, state: dict[str, np.ndarray], y: np.ndarray) -> dict[str, np.ndarray]:
        y = np.asarray(y, dtype=float)
        if y.ndim != 2 or y.shape[1] != self.m:
            raise ValueError(
                f"y must have shape (runs, {self.m}) (one entry per sensor), got {y.shape}"
            )
        buffer = np.concatenate([state["buffer"][:, 1:], y[:, None, :]], axis=1)
        was_full = int(state["filled"]) >= self.window
        filled = min(int(state["filled"]) + 1, self.window)
        x, E, v_prev = state["x_hat"], state["a_hat"], state["v_prev"]
        if filled >= self.window:
            Y = buffer.reshape(buffer.shape[0], -1)
            p, n = self.m, self.n
            if was_full:  # a) time update; x_hat already holds A x(t - tau)
                E_T = np.empty_like(E)
                E_T[:, :-p] = E[:, p:]
                E_T[:, -p:] = y - x @ self._last_row.T
                x_T = x
            else:  # the first full window: start from zero, V(z_Pi(t-1)) := V(0)
                E_T = np.zeros_like(E)
                x_T = np.zeros_like(x)
                v_prev = 0.5 * np.vecdot(Y, Y)
            Ep = self._blocks.project(E_T)
            z_pi = np.concatenate([x_T, Ep], axis=1)
            r = Y - x_T @ self.O.T - Ep
            v_pi = 0.5 * np.vecdot(r, r)
            alpha = 0.5 * self.tol**2 * np.vecdot(Y, Y)
            Z, _, v_pi, _, _, _ = _descend(
                self.O, self._blocks, Y, z_pi, v_pi, (1.0 - self.nu) * v_prev, alpha,
                self.step_size, self.nu, self.max_outer, self.max_inner,
            )  # fmt: skip
            x, E, v_prev = Z[:, :n] @ self.A.T, Z[:, n:], v_pi
        return {
            "x_hat": x,
            "a_hat": E,
            "v_prev": v_prev,
            "buffer": buffer,
            "filled": np.asarray(filled),
        }
