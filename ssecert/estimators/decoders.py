"""Static decoders: estimate x from one measurement vector y = M x + a.

``M`` is the sensing matrix (C for one step, or the stacked O_tau whose row
``k * p + i`` is sensor ``i`` at step ``k``) and ``a`` a sparse attack.

* ``partial_lasso_cvxpy`` and ``elastic_net_cvxpy``: the reference solutions
  of the partial Lasso and of the elastic net, by an interior-point solver;
* ``ista``, ``fista`` and ``ijam``: first-order iterations for the partial
  Lasso, batched over right-hand sides (``y`` of shape (runs, m));
* the l1 and l0 decoders are in ``support_decoders``.

The iterative solvers carry the runs on the first axis, as the dynamic
observers do; a run stops as soon as it meets its own stopping rule, so a
batched call gives what one call per run gives.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..base.validation import as_float_option, as_int_option, as_real_matrix, describe
from ..tolerances import EPS, default_rtol
from .shrinkage import soft_threshold

__all__ = [
    "IterativeSolution",
    "partial_lasso_cvxpy",
    "elastic_net_cvxpy",
    "ista",
    "fista",
    "ijam",
]

DEFAULT_ITERATIONS = 10_000
DEFAULT_TOL = 1e-10
DEFAULT_SOLVER_TOL = 1e-9


@dataclass(frozen=True)
class IterativeSolution:
    """Result of ``ista``, ``fista`` or ``ijam``.

    For a single measurement vector the per-run fields are scalars; for a
    batch of ``runs`` they are arrays with one entry per run.

    Attributes
    ----------
    x : ndarray, shape (n,) or (runs, n)
        State estimate.
    a : ndarray, shape (m,) or (runs, m)
        Attack estimate.
    iterations : int or ndarray of int
        Iterations performed (each run stops on its own).
    converged : bool or ndarray of bool
        Whether the stopping rule was met within the iteration budget.
    change : float or ndarray
        Last relative step ||z(k+1) - w(k)|| / sqrt(||z(k+1)||^2 + ||y||^2),
        the tolerance achieved, with z = (x, a) and ``w`` the point the
        step was taken from (z(k) except for FISTA).
    tol : float
        Tolerance asked for.
    step : float
        Gradient step, in the orthonormal coordinates when
        ``orthonormalize`` was asked for (``nu`` for IJAM).
    method : str
        "ista", "fista" or "ijam".
    """

    x: np.ndarray
    a: np.ndarray
    iterations: int | np.ndarray
    converged: bool | np.ndarray
    change: float | np.ndarray
    tol: float
    step: float
    method: str


# ---------------------------------------------------------------------------
# argument checking


def _as_sensing_matrix(M: Any) -> np.ndarray:
    return as_real_matrix(M, "M")


def _as_measurements(y: Any, m: int, *, batched: bool) -> np.ndarray:
    """y as an array of shape (m,) or, when ``batched``, also (runs, m)."""
    hint = "the number of rows of M"
    if not batched:
        return as_real_matrix(y, "y", ndim=1, shape=(m,), shape_hint=hint)
    try:
        ndim = np.ndim(y)
    except ValueError:  # ragged nested lists: the converter names the bad row
        ndim = 2
    if ndim == 2:
        return as_real_matrix(y, "y", ndim=2, shape=(None, m), shape_hint=hint)
    if ndim == 1:
        return as_real_matrix(y, "y", ndim=1, shape=(m,), shape_hint=hint)
    as_real_matrix(y, "y", ndim=ndim, allow_empty=True)  # wrong kinds first: TypeError
    raise ValueError(
        f"y must be a 1-D array of {m} measurements or a 2-D array of shape (runs, {m}), "
        f"got {describe(np.asarray(y))}"
    )


def _as_start(value: Any, name: str, runs: int, size: int, what: str) -> np.ndarray:
    """Initial iterate of shape (runs, size); a 1-D value is shared by every run."""
    if value is None:
        return np.zeros((runs, size))
    try:
        ndim = np.ndim(value)
    except ValueError:
        ndim = 2
    if ndim == 2:
        start = as_real_matrix(value, name, ndim=2, shape=(runs, size), shape_hint=what)
        return np.array(start)
    start = as_real_matrix(value, name, ndim=1, shape=(size,), shape_hint=what)
    return np.tile(start, (runs, 1))


def _as_lam(lam: Any) -> float:
    return as_float_option(lam, "lam", min_value=0.0, min_inclusive=False)


def _as_iterations(iterations: Any) -> int:
    return as_int_option(iterations, "iterations", min_value=1)


def _as_tol(tol: Any) -> float:
    return as_float_option(tol, "tol", min_value=0.0)


def _lipschitz(M: np.ndarray) -> float:
    """||(M I)||_2^2 = ||M||_2^2 + 1, the Lipschitz constant of the gradient."""
    return float(np.linalg.norm(M, 2)) ** 2 + 1.0


# ---------------------------------------------------------------------------
# reference solutions by cvxpy


def _solve_cvxpy(problem: Any, tol: float) -> None:
    import cvxpy as cp

    problem.solve(solver=cp.CLARABEL, tol_gap_abs=tol, tol_gap_rel=tol, tol_feas=tol)
    if problem.status != cp.OPTIMAL:
        raise RuntimeError(f"CLARABEL did not solve the problem: status {problem.status!r}")


def partial_lasso_cvxpy(
    M: Any, y: Any, lam: float, *, tol: float = DEFAULT_SOLVER_TOL
) -> tuple[np.ndarray, np.ndarray]:
    """Partial Lasso by cvxpy and CLARABEL, the reference for the iterative solvers.

    Solves argmin_{x, a} (1/2) ||y - M x - a||^2 + lam ||a||_1: the
    l1 penalty is on the attack only (problem (4) of the Lasso paper).

    Parameters
    ----------
    M : array_like, shape (m, n)
        Sensing matrix (C, or the stacked O_tau).
    y : array_like, shape (m,)
        Measurements.
    lam : float
        Regularisation weight lambda > 0.
    tol : float, default 1e-9
        CLARABEL's ``tol_gap_abs``, ``tol_gap_rel`` and ``tol_feas``.

    Returns
    -------
    x : ndarray, shape (n,)
    a : ndarray, shape (m,)

    Raises
    ------
    TypeError
        If an argument has the wrong kind (non-real entries, a string ``lam``).
    ValueError
        If ``y`` does not have one entry per row of ``M``, ``lam <= 0`` or
        ``tol <= 0``.
    RuntimeError
        If CLARABEL does not report an optimal solution.

    Examples
    --------
    >>> M = [[1.0], [1.0], [1.0]]
    >>> x, a = partial_lasso_cvxpy(M, [1.0, 1.0, 5.0], 0.1)
    >>> round(float(x[0]), 6), round(float(a[2]), 6)
    (1.05, 3.85)
    """
    import cvxpy as cp

    M = _as_sensing_matrix(M)
    y = _as_measurements(y, M.shape[0], batched=False)
    lam = _as_lam(lam)
    tol = as_float_option(tol, "tol", min_value=0.0, min_inclusive=False)
    x = cp.Variable(M.shape[1])
    a = cp.Variable(M.shape[0])
    objective = 0.5 * cp.sum_squares(y - M @ x - a) + lam * cp.norm1(a)
    _solve_cvxpy(cp.Problem(cp.Minimize(objective)), tol)
    return np.array(x.value, dtype=float), np.array(a.value, dtype=float)


def elastic_net_cvxpy(
    M: Any, y: Any, lam: float, mu: float, *, tol: float = DEFAULT_SOLVER_TOL
) -> tuple[np.ndarray, np.ndarray]:
    """Elastic net for secure estimation by cvxpy and CLARABEL.

    Solves argmin_{x, a} (1/2) ||y - M x - a||^2 + lam ||a||_1 + (mu/2) ||a||^2
    (problem (4.13) of the thesis).

    Parameters
    ----------
    M : array_like, shape (m, n)
        Sensing matrix.
    y : array_like, shape (m,)
        Measurements.
    lam : float
        l1 weight lambda > 0.
    mu : float
        l2 weight mu >= 0; 0 gives the partial Lasso.
    tol : float, default 1e-9
        CLARABEL's ``tol_gap_abs``, ``tol_gap_rel`` and ``tol_feas``.

    Returns
    -------
    x : ndarray, shape (n,)
    a : ndarray, shape (m,)

    Raises
    ------
    TypeError
        If an argument has the wrong kind.
    ValueError
        If ``y`` has the wrong length, ``lam <= 0``, ``mu < 0`` or ``tol <= 0``.
    RuntimeError
        If CLARABEL does not report an optimal solution.

    Examples
    --------
    >>> x, a = elastic_net_cvxpy([[1.0], [1.0], [1.0]], [1.0, 1.0, 5.0], 0.1, 1.0)
    >>> x.round(6).tolist(), a.round(6).tolist()
    ([2.3], [-0.6, -0.6, 1.3])
    """
    import cvxpy as cp

    M = _as_sensing_matrix(M)
    y = _as_measurements(y, M.shape[0], batched=False)
    lam = _as_lam(lam)
    mu = as_float_option(mu, "mu", min_value=0.0)
    tol = as_float_option(tol, "tol", min_value=0.0, min_inclusive=False)
    x = cp.Variable(M.shape[1])
    a = cp.Variable(M.shape[0])
    objective = (
        0.5 * cp.sum_squares(y - M @ x - a) + lam * cp.norm1(a) + 0.5 * mu * cp.sum_squares(a)
    )
    _solve_cvxpy(cp.Problem(cp.Minimize(objective)), tol)
    return np.array(x.value, dtype=float), np.array(a.value, dtype=float)


# ---------------------------------------------------------------------------
# first-order iterations, batched over runs

State = tuple[np.ndarray, ...]
Advance = Callable[[State], tuple[State, np.ndarray, np.ndarray]]


def _iterate(
    advance: Advance,
    state: State,
    n: int,
    iterations: int,
    tol: float,
    single: bool,
    step: float,
    method: str,
) -> IterativeSolution:
    """Run ``advance`` until each run meets its stopping rule; finished runs are frozen.

    ``state`` holds arrays with the runs on the first axis: the iterate
    z = (x, a) of shape (runs, n + m) first, the measurements (runs, m)
    last.  ``advance`` returns the new state and, per run, the squared step
    norm and ||z(k+1)||^2.  A run stops when
    ||step|| <= tol sqrt(||z(k+1)||^2 + ||y||^2); the ||y|| term gives the
    rule a scale when the solution is zero.  Finished runs leave the
    state, so a run's iterates do not depend on the others in the batch.
    """
    runs = state[0].shape[0]
    scale2 = np.vecdot(state[-1], state[-1])
    z_out = np.empty_like(state[0])
    iters = np.zeros(runs, dtype=np.int64)
    converged = np.zeros(runs, dtype=bool)
    change = np.zeros(runs)
    active = np.arange(runs)
    tol2 = tol * tol
    for k in range(1, iterations + 1):
        state, num2, den2 = advance(state)
        den2 = den2 + scale2
        stop = num2 <= tol2 * den2
        if not (stop.any() or k == iterations):
            continue
        finished = stop if k < iterations else np.ones_like(stop)
        idx = active[finished]
        z_out[idx] = state[0][finished]
        iters[idx] = k
        converged[idx] = stop[finished]
        # the tolerance achieved; a zero iterate reached by a zero step reports 0
        den2 = den2[finished]
        change[idx] = np.sqrt(num2[finished] / np.where(den2 > 0, den2, 1.0))
        keep = ~finished
        active = active[keep]
        if active.size == 0:
            break
        scale2 = scale2[keep]
        state = tuple(part[keep] for part in state)
    x_out, a_out = z_out[:, :n], z_out[:, n:]
    if single:
        return IterativeSolution(
            x_out[0].copy(),
            a_out[0].copy(),
            int(iters[0]),
            bool(converged[0]),
            float(change[0]),
            tol,
            step,
            method,
        )
    return IterativeSolution(
        x_out.copy(), a_out.copy(), iters, converged, change, tol, step, method
    )


def _prepare(
    M: Any, y: Any, lam: Any, iterations: Any, tol: Any, x0: Any, a0: Any
) -> tuple[np.ndarray, np.ndarray, bool, float, int, float, np.ndarray]:
    """Checked arguments; measurements as (runs, m), start z = (x0, a0) as (runs, n + m)."""
    M = _as_sensing_matrix(M)
    m, n = M.shape
    y = _as_measurements(y, m, batched=True)
    single = y.ndim == 1
    Y = np.array(y, ndmin=2)
    runs = Y.shape[0]
    lam = _as_lam(lam)
    iterations = _as_iterations(iterations)
    tol = _as_tol(tol)
    X0 = _as_start(x0, "x0", runs, n, "the number of columns of M")
    A0 = _as_start(a0, "a0", runs, m, "the number of rows of M")
    return M, Y, single, lam, iterations, tol, np.concatenate([X0, A0], axis=1)


def _as_step(step: Any, M: np.ndarray, *, limit: float, limit_text: str) -> float:
    """Gradient step: default 1 / L with L = ||M||_2^2 + 1."""
    L = _lipschitz(M)
    if step is None:
        return 1.0 / L
    step = as_float_option(step, "step", min_value=0.0, min_inclusive=False)
    bound = limit / L
    if step > bound:
        raise ValueError(
            f"step must be <= {limit_text} = {bound:.6g} (L = ||M||_2^2 + 1 = {L:.6g}) "
            f"for convergence, got {step}"
        )
    return step


def _as_flag(value: Any, name: str) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False, got {describe(value)}")
    return bool(value)


def _coordinates(
    M: np.ndarray, Z0: np.ndarray, orthonormalize: bool
) -> tuple[np.ndarray, np.ndarray, Callable[[np.ndarray], np.ndarray]]:
    """Matrix the iteration runs on, the start in its coordinates, and the map back to x.

    With ``orthonormalize``, M = U S V^T (rank r) and the iteration runs in
    u = S V^T x, where the data term is (1/2) ||U u + a - y||^2: the same
    problem, since x is not penalised, with a gradient whose Lipschitz
    constant is 2 whatever the conditioning of M.  x = V S^-1 u is the
    minimum-norm state when M is rank deficient.
    """
    if not orthonormalize:
        return M, Z0, lambda x: x
    m, n = M.shape
    U, sv, Vt = np.linalg.svd(M, full_matrices=False)
    rank = int(np.sum(sv > default_rtol(m, n) * sv[0]))
    if rank == 0:  # M = 0: x does not enter the data term; its minimum-norm value is 0
        U, sv, Vt = np.zeros((m, 1)), np.ones(1), np.zeros((1, n))
    else:
        U, sv, Vt = U[:, :rank], sv[:rank], Vt[:rank]
    start = np.concatenate([(Z0[:, :n] @ Vt.T) * sv, Z0[:, n:]], axis=1)
    return np.ascontiguousarray(U), start, lambda u: (u / sv) @ Vt


def ista(
    M: Any,
    y: Any,
    lam: float,
    *,
    step: float | None = None,
    iterations: int = DEFAULT_ITERATIONS,
    tol: float = DEFAULT_TOL,
    x0: Any = None,
    a0: Any = None,
    orthonormalize: bool = False,
) -> IterativeSolution:
    """Iterative soft thresholding (ISTA) for the partial Lasso.

    Proximal gradient on (1/2) ||M x + a - y||^2 + lam ||a||_1 with step nu:

        r(k) = M x(k) + a(k) - y
        x(k+1) = x(k) - nu M^T r(k)
        a(k+1) = S_{nu lam}[a(k) - nu r(k)]

    A run stops when ||z(k+1) - z(k)|| <= tol sqrt(||z(k+1)||^2 + ||y||^2),
    z = (x, a).

    Parameters
    ----------
    M : array_like, shape (m, n)
        Sensing matrix.
    y : array_like, shape (m,) or (runs, m)
        Measurements; a 2-D array is a batch solved at once.
    lam : float
        Regularisation weight lambda > 0.
    step : float, optional
        Step nu; default 1 / L with L = ||(M I)||_2^2 = ||M||_2^2 + 1
        (L = 2 with ``orthonormalize``).  Must be < 2 / L.
    iterations : int, default 10000
        Iteration budget per run.
    tol : float, default 1e-10
        Relative step size at which a run stops; 0 runs the whole budget.
        The distance to the solution can exceed it by about L / mu (mu the
        curvature near the solution), as the steps are short where M is
        ill conditioned.
    x0 : array_like, shape (n,) or (runs, n), optional
        Initial state estimate; default zero.
    a0 : array_like, shape (m,) or (runs, m), optional
        Initial attack estimate; default zero.
    orthonormalize : bool, default False
        Iterate in the coordinates u = S V^T x of the singular value
        decomposition M = U S V^T, where M becomes U: the same minimisers
        (x carries no penalty), a step of 1/2 whatever the conditioning of
        M, and x = V S^-1 u at the end.  The stopping rule then measures u.

    Returns
    -------
    IterativeSolution

    Raises
    ------
    TypeError
        If an argument has the wrong kind.
    ValueError
        If a shape does not match ``M``, ``lam <= 0``, ``step`` is outside
        (0, 2 / L), ``iterations < 1`` or ``tol < 0``.

    Examples
    --------
    >>> sol = ista([[1.0], [1.0], [1.0]], [1.0, 1.0, 5.0], 0.1)
    >>> sol.converged, round(float(sol.x[0]), 6), round(float(sol.a[2]), 6)
    (True, 1.05, 3.85)
    """
    M, Y, single, lam, iterations, tol, Z0 = _prepare(M, y, lam, iterations, tol, x0, a0)
    M, Z0, to_x = _coordinates(M, Z0, _as_flag(orthonormalize, "orthonormalize"))
    n = M.shape[1]
    nu = _as_step(step, M, limit=2.0 * (1.0 - EPS), limit_text="2 / L")
    Mt = M.T
    threshold = nu * lam

    def advance(state: State) -> tuple[State, np.ndarray, np.ndarray]:
        z, Yk = state
        x, a = z[:, :n], z[:, n:]
        r = x @ Mt
        r += a
        r -= Yk
        z_new = np.empty_like(z)
        z_new[:, :n] = x - nu * (r @ M)
        z_new[:, n:] = soft_threshold(a - nu * r, threshold)
        dz = z_new - z
        return (z_new, Yk), np.vecdot(dz, dz), np.vecdot(z_new, z_new)

    sol = _iterate(advance, (Z0, Y), n, iterations, tol, single, nu, "ista")
    return replace(sol, x=to_x(sol.x))


def fista(
    M: Any,
    y: Any,
    lam: float,
    *,
    step: float | None = None,
    iterations: int = DEFAULT_ITERATIONS,
    tol: float = DEFAULT_TOL,
    x0: Any = None,
    a0: Any = None,
    orthonormalize: bool = False,
    restart: bool = False,
) -> IterativeSolution:
    """FISTA (Beck and Teboulle, 2009) for the partial Lasso.

    The ISTA step taken from an extrapolated point w(k):

        z(k+1) = prox_{nu lam ||a||_1}(w(k) - nu grad F(w(k)))
        t(k+1) = (1 + sqrt(1 + 4 t(k)^2)) / 2,   t(1) = 1
        w(k+1) = z(k+1) + ((t(k) - 1) / t(k+1)) (z(k+1) - z(k))

    with z = (x, a) and F = (1/2) ||M x + a - y||^2.  A run stops when
    ||z(k+1) - w(k)|| <= tol sqrt(||z(k+1)||^2 + ||y||^2) (the
    proximal-gradient step, zero only at a solution).  With ``restart``, a run's momentum restarts
    (t = 1) whenever (w(k) - z(k+1)) . (z(k+1) - z(k)) > 0, the gradient
    scheme of O'Donoghue and Candes (2015), which recovers a linear rate
    where the problem is locally strongly convex.

    Parameters
    ----------
    M : array_like, shape (m, n)
        Sensing matrix.
    y : array_like, shape (m,) or (runs, m)
        Measurements; a 2-D array is a batch solved at once.
    lam : float
        Regularisation weight lambda > 0.
    step : float, optional
        Step nu; default 1 / L with L = ||M||_2^2 + 1 (L = 2 with
        ``orthonormalize``).  Must be <= 1 / L.
    iterations : int, default 10000
        Iteration budget per run.
    tol : float, default 1e-10
        Relative step size at which a run stops; 0 runs the whole budget.
        The distance to the solution can exceed it by about L / mu (mu the
        curvature near the solution), as the steps are short where M is
        ill conditioned.
    x0 : array_like, shape (n,) or (runs, n), optional
        Initial state estimate; default zero.
    a0 : array_like, shape (m,) or (runs, m), optional
        Initial attack estimate; default zero.
    restart : bool, default False
        Adaptive (gradient) restart of the momentum; False is plain FISTA.
    orthonormalize : bool, default False
        Iterate in the coordinates u = S V^T x of the singular value
        decomposition M = U S V^T, where M becomes U: the same minimisers
        (x carries no penalty), a step of 1/2 whatever the conditioning of
        M, and x = V S^-1 u at the end.  The stopping rule then measures u.

    Returns
    -------
    IterativeSolution

    Raises
    ------
    TypeError
        If an argument has the wrong kind.
    ValueError
        If a shape does not match ``M``, ``lam <= 0``, ``step`` is outside
        (0, 1 / L], ``iterations < 1`` or ``tol < 0``.

    Examples
    --------
    >>> sol = fista([[1.0], [1.0], [1.0]], [[1.0, 1.0, 5.0], [2.0, 2.0, 2.0]], 0.1)
    >>> sol.converged.tolist(), sol.x.round(6).ravel().tolist()
    ([True, True], [1.05, 2.0])
    """
    M, Y, single, lam, iterations, tol, Z0 = _prepare(M, y, lam, iterations, tol, x0, a0)
    restart = _as_flag(restart, "restart")
    M, Z0, to_x = _coordinates(M, Z0, _as_flag(orthonormalize, "orthonormalize"))
    n = M.shape[1]
    nu = _as_step(step, M, limit=1.0, limit_text="1 / L")
    Mt = M.T
    threshold = nu * lam
    momentum = {"t": 1.0}  # shared by every run unless restarts make it per run

    def advance(state: State) -> tuple[State, np.ndarray, np.ndarray]:
        z, w, t, Yk = state
        wx, wa = w[:, :n], w[:, n:]
        r = wx @ Mt
        r += wa
        r -= Yk
        z_new = np.empty_like(z)
        z_new[:, :n] = wx - nu * (r @ M)
        z_new[:, n:] = soft_threshold(wa - nu * r, threshold)
        g = z_new - w
        dz = z_new - z
        beta: np.ndarray | float
        if restart:
            # momentum pointing against the proximal-gradient step: start again
            t = np.where(np.vecdot(g, dz) < 0, 1.0, t)
            t_next = 0.5 * (1.0 + np.sqrt(1.0 + 4.0 * t * t))
            beta = ((t - 1.0) / t_next)[:, None]
            t = t_next
        else:
            t_now = momentum["t"]
            momentum["t"] = 0.5 * (1.0 + math.sqrt(1.0 + 4.0 * t_now * t_now))
            beta = (t_now - 1.0) / momentum["t"]
        w_new = z_new + beta * dz
        return (z_new, w_new, t, Yk), np.vecdot(g, g), np.vecdot(z_new, z_new)

    start = (Z0, Z0, np.ones(Y.shape[0]), Y)
    sol = _iterate(advance, start, n, iterations, tol, single, nu, "fista")
    return replace(sol, x=to_x(sol.x))


def ijam(
    M: Any,
    y: Any,
    lam: float,
    *,
    nu: float = 0.9,
    iterations: int = DEFAULT_ITERATIONS,
    tol: float = DEFAULT_TOL,
    x0: Any = None,
    a0: Any = None,
    rank_rtol: float | None = None,
) -> IterativeSolution:
    """Inertial Jacobi alternating minimization (IJAM) for the partial Lasso.

    A Jacobi update (both lines use the previous iterates):

        x(k+1) = M^+ (y - a(k))
        a(k+1) = S_{nu lam}[a(k) - nu (M x(k) + a(k) - y)]

    Its fixed points are the partial-Lasso solutions.  A run stops when
    ||z(k+1) - z(k)|| <= tol sqrt(||z(k+1)||^2 + ||y||^2), z = (x, a).

    Parameters
    ----------
    M : array_like, shape (m, n)
        Sensing matrix with full column rank.
    y : array_like, shape (m,) or (runs, m)
        Measurements; a 2-D array is a batch solved at once.
    lam : float
        Regularisation weight lambda > 0.
    nu : float, default 0.9
        Inertial parameter in (0, 1].  Near a solution the iteration is
        linear with eigenvalues z solving z^2 = (1 - nu) z + nu q, for q < 1
        the eigenvalues of the projection onto range(M) restricted to the
        attacked rows: the slowest mode contracts by about
        1 - nu (1 - q) / (1 + nu) per step, faster for larger nu, but at
        nu = 1 the roots are +-sqrt(q) and the iterates oscillate.  0.9 took
        the fewest iterations on random Gaussian instances.
    iterations : int, default 10000
        Iteration budget per run.
    tol : float, default 1e-10
        Relative step size at which a run stops; 0 runs the whole budget.
        The distance to the solution can exceed it by a factor of order
        1 / (1 - q), with q as for ``nu``.
    x0 : array_like, shape (n,) or (runs, n), optional
        Initial state estimate; default zero.
    a0 : array_like, shape (m,) or (runs, m), optional
        Initial attack estimate; default zero.
    rank_rtol : float, optional
        M has full column rank when its smallest singular value exceeds
        ``rank_rtol`` times its largest; default ``max(m, n) * eps``.

    Returns
    -------
    IterativeSolution

    Raises
    ------
    TypeError
        If an argument has the wrong kind.
    ValueError
        If ``M`` does not have full column rank, a shape does not match
        ``M``, ``lam <= 0``, ``nu`` is outside (0, 1], ``iterations < 1`` or
        ``tol < 0``.

    Examples
    --------
    >>> sol = ijam([[1.0], [1.0], [1.0]], [1.0, 1.0, 5.0], 0.1)
    >>> sol.converged, round(float(sol.x[0]), 6), round(float(sol.a[2]), 6)
    (True, 1.05, 3.85)
    """
    M, Y, single, lam, iterations, tol, Z0 = _prepare(M, y, lam, iterations, tol, x0, a0)
    m, n = M.shape
    nu = as_float_option(nu, "nu", min_value=0.0, max_value=1.0, min_inclusive=False)
    rtol = (
        default_rtol(m, n)
        if rank_rtol is None
        else as_float_option(rank_rtol, "rank_rtol", min_value=0.0, max_value=1.0)
    )
    if m < n:
        raise ValueError(
            f"M must have full column rank for ijam, but it has fewer rows ({m}) than columns ({n})"
        )
    U, sv, Vt = np.linalg.svd(M, full_matrices=False)
    if sv[-1] <= rtol * sv[0]:
        raise ValueError(
            f"M must have full column rank for ijam: its smallest singular value {sv[-1]:.3g} "
            f"is <= rank_rtol * largest = {rtol:.3g} * {sv[0]:.3g}"
        )
    pinv_t = (U / sv) @ Vt  # (M^+)^T, as runs are rows: x = (y - a) @ (M^+)^T
    Mt = M.T
    threshold = nu * lam

    def advance(state: State) -> tuple[State, np.ndarray, np.ndarray]:
        z, Yk = state
        x, a = z[:, :n], z[:, n:]
        z_new = np.empty_like(z)
        z_new[:, :n] = (Yk - a) @ pinv_t
        z_new[:, n:] = soft_threshold(a - nu * (x @ Mt + a - Yk), threshold)
        dz = z_new - z
        return (z_new, Yk), np.vecdot(dz, dz), np.vecdot(z_new, z_new)

    return _iterate(advance, (Z0, Y), n, iterations, tol, single, nu, "ijam")
