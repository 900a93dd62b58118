"""SISE: Kalman-like joint estimation of the state and a sparse input.

The plant is (Fosson, Garin, Gracy, Kibangou, Swart, ECC 2019, eq. (1))

    x(k+1) = A x(k) + B u(k) + w(k),    y(k) = C x(k) + v(k),

with w ~ N(0, Q), v ~ N(0, R), and an unknown input u(k) in R^p that is
sparse (an attack injected into a few of the p vulnerable states) while
there are fewer measurements than inputs (m < p), so that C B has no full
column rank and the classical unbiased minimum-variance filter of Gillijns
and De Moor cannot be used.  SISE detects the input support with a Lasso on
the innovation and runs Gillijns and De Moor's filter with the columns of B
on that support only.

``lasso_fista`` is the batched Lasso solver used for the support detection;
``SISE`` is the estimator; ``OracleSISE`` is the paper's benchmark, the same
filter told the true input support.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..base.validation import as_float_option, as_int_option, as_real_matrix, describe
from ..observers.dynamic import DynamicObserver
from ..tolerances import EPS, default_rtol
from .shrinkage import soft_threshold

__all__ = [
    "LassoResult",
    "lasso_admm",
    "lasso_fista",
    "SISE",
    "OracleSISE",
    "recursive_input_estimate",
]


@dataclass(frozen=True)
class LassoResult:
    """Solutions of a batch of Lasso problems min_u ||y - Phi u||^2 + weight ||u||_1.

    Attributes
    ----------
    solution : ndarray, shape (runs, p) or (p,)
        The minimisers, one per row of ``y``.
    iterations : ndarray of int, shape (runs,) or ()
        FISTA iterations spent on each problem.
    converged : ndarray of bool, shape (runs,) or ()
        Whether the relative step fell below ``rtol`` within ``max_iter``.
    kkt_residual : ndarray, shape (runs,) or ()
        Achieved optimality: the largest violation of the subgradient
        condition ``2 Phi^T (y - Phi u) in weight * d||u||_1``, relative to
        ``weight`` (0 at an exact minimiser).
    weight : float
        The l1 weight lambda.
    rtol : float
        The requested relative step tolerance.
    """

    solution: np.ndarray
    iterations: np.ndarray
    converged: np.ndarray
    kkt_residual: np.ndarray
    weight: float
    rtol: float


def _lasso_kkt(Phi: np.ndarray, Y: np.ndarray, U: np.ndarray, weight: float) -> np.ndarray:
    """Largest subgradient violation of the Lasso optimality conditions, relative to weight."""
    grad = 2.0 * (Y - U @ Phi.T) @ Phi  # minus the gradient of the quadratic part
    on = U != 0
    viol = np.where(on, np.abs(grad - weight * np.sign(U)), np.maximum(np.abs(grad) - weight, 0.0))
    return viol.max(axis=1, initial=0.0) / weight


def _fista_batch(Phi, Y, weight, U0, max_iter, rtol):
    """FISTA with per-run adaptive restart and per-run stopping (rows never interact)."""
    runs, p = U0.shape
    lipschitz = 2.0 * np.linalg.norm(Phi, 2) ** 2
    step = 1.0 / lipschitz if lipschitz > 0 else 1.0
    thr = weight * step
    G = Phi.T @ Phi
    PhiTY = Y @ Phi
    # scale of a solution, so that a zero solution can stop too
    scale = np.abs(PhiTY).max(axis=1) * step
    U = U0.copy()
    converged = np.zeros(runs, dtype=bool)
    iterations = np.zeros(runs, dtype=int)
    # working copies of the rows still iterating, compacted when rows finish
    idx = np.arange(runs)
    Ua, Va, ta = U0.copy(), U0.copy(), np.ones(runs)
    Ga, scale_a = 2.0 * step * PhiTY, scale
    G2 = 2.0 * step * G
    for it in range(1, max_iter + 1):
        # gradient step on ||y - Phi u||^2 (gradient 2 (G V - Phi^T y)), then shrink
        Z = Va - Va @ G2 + Ga
        Un = soft_threshold(Z, thr)
        D = Un - Ua
        tn = 0.5 * (1.0 + np.sqrt(1.0 + 4.0 * ta * ta))
        # O'Donoghue-Candes gradient restart: drop momentum when it points uphill
        restart = np.einsum("ij,ij->i", Va - Un, D) > 0
        tn[restart] = 1.0
        mom = (ta - 1.0) / tn
        mom[restart] = 0.0
        Va = Un + mom[:, None] * D
        Ua, ta = Un, tn
        done = np.abs(D).max(axis=1) <= rtol * np.maximum(np.abs(Un).max(axis=1), scale_a)
        if done.any() or it == max_iter:
            fin = done if it < max_iter else np.ones(len(idx), dtype=bool)
            U[idx[fin]] = Un[fin]
            iterations[idx[fin]] = it
            converged[idx[done]] = True
            keep = ~fin
            idx, Ua, Va, ta = idx[keep], Ua[keep], Va[keep], ta[keep]
            Ga, scale_a = Ga[keep], scale_a[keep]
            if idx.size == 0:
                break
    return U, iterations, converged


def _lasso_inputs(
    Phi: Any, y: Any, weight: Any, max_iter: Any, rtol: Any
) -> tuple[np.ndarray, np.ndarray, bool, float, int, float]:
    """The checked arguments of a batched Lasso: Phi, y as rows, whether y was one problem,
    weight, max_iter and rtol."""
    Phi = as_real_matrix(Phi, "Phi")
    m = Phi.shape[0]
    weight = as_float_option(weight, "weight", min_value=0.0, min_inclusive=False)
    max_iter = as_int_option(max_iter, "max_iter", min_value=1)
    rtol = as_float_option(rtol, "rtol", min_value=0.0)
    single = np.ndim(y) == 1
    Y = as_real_matrix(
        y,
        "y",
        ndim=1 if single else 2,
        shape=(m,) if single else (None, m),
        shape_hint="rows of Phi",
    )
    return Phi, np.atleast_2d(Y), single, weight, max_iter, rtol


def lasso_fista(
    Phi: Any,
    y: Any,
    weight: float,
    *,
    initial: Any = None,
    max_iter: int = 5000,
    rtol: float = 1e-10,
) -> LassoResult:
    """Batched Lasso min_u ||y - Phi u||^2 + weight ||u||_1 by FISTA.

    The scaling is the ECC 2019 paper's (no 1/2 on the quadratic term), so
    its lambda = 1 is ``weight=1``.  All rows of ``y`` are solved at once;
    each stops on its own criterion, so a row's solution does not depend on
    the other rows of the batch.

    Parameters
    ----------
    Phi : array_like, shape (m, p)
        Sensing matrix (C B in SISE).
    y : array_like, shape (runs, m) or (m,)
        Right-hand sides, one problem per row.
    weight : float
        lambda > 0.
    initial : array_like, shape (runs, p) or (p,), optional
        Warm start; default zero.
    max_iter : int, default 5000
        Iteration budget per problem.
    rtol : float, default 1e-10
        Stop a problem when the largest entry change of an iteration is at
        most ``rtol`` times max(||u||_inf, ||Phi^T y||_inf / L), with L the
        Lipschitz constant 2 ||Phi||_2^2 of the gradient.

    Returns
    -------
    LassoResult
        Solutions with the same leading shape as ``y``, the iterations
        used, convergence flags and the achieved KKT residual.

    Raises
    ------
    TypeError
        If an array is not real or an option has the wrong kind.
    ValueError
        If shapes disagree, an entry is not finite, or an option is out of
        range.

    Examples
    --------
    >>> import numpy as np
    >>> Phi = np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]])
    >>> res = lasso_fista(Phi, [4.0, 0.0], 1.0)
    >>> np.round(res.solution, 6).tolist()   # u_0 = 4 - 1/2
    [3.5, 0.0, 0.0]
    >>> bool(res.converged), bool(res.kkt_residual < 1e-6)
    (True, True)
    """
    Phi, Y, single, weight, max_iter, rtol = _lasso_inputs(Phi, y, weight, max_iter, rtol)
    p = Phi.shape[1]
    if initial is None:
        U0 = np.zeros((Y.shape[0], p))
    else:
        U0 = np.atleast_2d(
            as_real_matrix(
                initial,
                "initial",
                ndim=1 if single else 2,
                shape=(p,) if single else (Y.shape[0], p),
                shape_hint="columns of Phi",
            )
        )
    U, iterations, converged = _fista_batch(
        Phi, Y, weight, np.array(U0, dtype=float), max_iter, rtol
    )
    kkt = _lasso_kkt(Phi, Y, U, weight)
    if single:
        return LassoResult(U[0], iterations[0], converged[0], kkt[0], weight, rtol)
    return LassoResult(U, iterations, converged, kkt, weight, rtol)


def lasso_admm(
    Phi: Any,
    y: Any,
    weight: float,
    *,
    rho: float | None = None,
    max_iter: int = 5000,
    rtol: float = 1e-10,
) -> LassoResult:
    """Batched Lasso min_u ||y - Phi u||^2 + weight ||u||_1 by ADMM, the solver the SISE
    paper uses (its Sec. III-IV, after Boyd et al. 2010, Sec. 6.4).

    With the splitting u = z and the scaled dual w, each iteration solves
    (2 Phi^T Phi + rho I) u = 2 Phi^T y + rho (z - w) (one Cholesky factor
    for the whole batch), then z = S_(weight / rho)(u + w) and w += u - z.
    The solution returned is z (exactly sparse).  It is the same minimiser
    ``lasso_fista`` finds (the problem is strictly convex in the entries it
    selects); ``kkt_residual`` measures how close each is, as for FISTA.

    Parameters
    ----------
    Phi : array_like, shape (m, p)
    y : array_like, shape (runs, m) or (m,)
    weight : float
        lambda > 0.
    rho : float, optional
        The penalty; default 2 ||Phi||_2^2 (the quadratic term's curvature).
    max_iter : int, default 5000
    rtol : float, default 1e-10
        Stop a problem when the primal residual ||u - z||_inf and the dual
        one rho ||z - z_prev||_inf are at most ``rtol`` times max(||z||_inf,
        ||2 Phi^T y||_inf / rho).

    Returns
    -------
    LassoResult

    Examples
    --------
    >>> import numpy as np
    >>> Phi = np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]])
    >>> res = lasso_admm(Phi, [4.0, 0.0], 1.0)
    >>> np.round(res.solution, 6).tolist()   # as lasso_fista: u_0 = 4 - 1/2
    [3.5, 0.0, 0.0]
    >>> bool(res.converged), bool(res.kkt_residual < 1e-6)
    (True, True)
    """
    Phi, Y, single, weight, max_iter, rtol = _lasso_inputs(Phi, y, weight, max_iter, rtol)
    p = Phi.shape[1]
    curvature = 2.0 * float(np.linalg.norm(Phi, 2)) ** 2
    if rho is None:
        rho = curvature if curvature > 0 else 1.0
    rho = as_float_option(rho, "rho", min_value=0.0, min_inclusive=False)
    chol = np.linalg.cholesky(2.0 * Phi.T @ Phi + rho * np.eye(p))
    rhs0 = 2.0 * Y @ Phi  # 2 Phi^T y, one row per problem
    scale = np.abs(rhs0).max(axis=1) / rho
    runs = Y.shape[0]
    U = np.zeros((runs, p))
    Z, W = np.zeros((runs, p)), np.zeros((runs, p))
    iterations = np.full(runs, max_iter)
    converged = np.zeros(runs, dtype=bool)
    active = np.ones(runs, dtype=bool)
    for it in range(1, max_iter + 1):
        a = np.flatnonzero(active)
        half = np.linalg.solve(chol, (rhs0[a] + rho * (Z[a] - W[a])).T)
        U[a] = np.linalg.solve(chol.T, half).T
        previous = Z[a].copy()
        Z[a] = soft_threshold(U[a] + W[a], weight / rho)
        W[a] += U[a] - Z[a]
        bound = rtol * np.maximum(np.abs(Z[a]).max(axis=1), scale[a])
        primal = np.abs(U[a] - Z[a]).max(axis=1)
        dual = rho * np.abs(Z[a] - previous).max(axis=1)
        done = (primal <= bound) & (dual <= bound)
        if done.any():
            finished = a[done]
            converged[finished] = True
            iterations[finished] = it
            active[finished] = False
            if not active.any():
                break
    Z += 0.0  # no negative zeros from the threshold
    kkt = _lasso_kkt(Phi, Y, Z, weight)
    if single:
        return LassoResult(Z[0], iterations[0], converged[0], kkt[0], weight, rtol)
    return LassoResult(Z, iterations, converged, kkt, weight, rtol)


def _covariance(value: Any, name: str, size: int, *, definite: bool) -> np.ndarray:
    """Symmetric positive (semi)definite matrix, checked by an eigenvalue margin."""
    M = as_real_matrix(value, name, shape=(size, size))
    scale = max(np.abs(M).max(), np.finfo(float).tiny)
    asym = np.abs(M - M.T).max()
    if asym > 100 * size * EPS * scale:
        raise ValueError(f"{name} must be symmetric, got max |{name} - {name}^T| = {asym:.3g}")
    S = 0.5 * (M + M.T)
    lowest = float(np.linalg.eigvalsh(S)[0])
    floor = 100 * size * EPS * scale
    if definite and lowest <= floor:
        raise ValueError(f"{name} must be positive definite, got smallest eigenvalue {lowest:.3g}")
    if not definite and lowest < -floor:
        raise ValueError(
            f"{name} must be positive semidefinite, got smallest eigenvalue {lowest:.3g}"
        )
    S.flags.writeable = False
    return S


class SISE(DynamicObserver):
    """Sparse-input and state estimator (SISE, Fosson et al., ECC 2019), batched over runs.

    For x(k+1) = A x(k) + B u(k) + w(k), y(k) = C x(k) + v(k) with
    w ~ N(0, Q), v ~ N(0, R) and a sparse unknown input u.  With the
    previous estimate x_hat(k-1) and covariance P(k-1), the measurement y(k)
    gives (the paper's equations; its (4) and (9) print x_hat_k and u_hat_k
    where x_hat_(k-1) and u_hat_(k-1) are meant, and its Lasso of Sec. III-A
    minimises over "m in R^n" where u in R^p is meant):

    * (2)-(3) P~ = A P(k-1) A^T + Q, R~ = C P~ C^T + R;
    * (4) innovation y~ = y(k) - C A x_hat(k-1);
    * (5)-(6) support S of the Lasso solution of y~ = C B u + e
      (min ||y~ - C B u||^2 + lambda ||u||_1), B_S its columns of B;
    * (7)-(8) M = (B_S^T C^T R~^-1 C B_S)^-1 B_S^T C^T R~^-1,
      u_hat(k-1) = M y~ (zero off S);
    * (9)-(10) x* = A x_hat(k-1) + B_S u_hat(k-1),
      P* = (I - B_S M C) P~ (I - B_S M C)^T + B_S M R M^T B_S^T;
    * (11)-(13) K = P~ C^T R~^-1, x_hat(k) = x* + K (y(k) - C x*),
      P(k) = P* - K (P* C^T - B_S M R)^T.

    With an empty support this is the Kalman filter that ignores the input.

    Parameters
    ----------
    A : array_like, shape (n, n)
    B : array_like, shape (n, p)
        Input matrix; the paper's experiments use B = [I_p; 0].
    C : array_like, shape (m, n)
    Q : array_like, shape (n, n)
        Process noise covariance (symmetric positive semidefinite).
    R : array_like, shape (m, m)
        Measurement noise covariance (symmetric positive definite).
    lasso_weight : float, default 1.0
        The paper's lambda (its Sec. IV uses 1 with Q = R = 0.01 I).
    sparsity : int or None, default None
        When given (the paper's experiments: s = 1, known), the support is
        the ``sparsity`` largest-magnitude nonzero entries of the Lasso
        solution; otherwise all of its nonzero entries.
    x0_hat : array_like, shape (n,), optional
        Prior mean of x(0); default zero.
    P0 : array_like, shape (n, n), optional
        Prior covariance of x(0), positive definite; default identity.
    lasso_max_iter : int, default 5000
        FISTA budget of each support detection.
    lasso_rtol : float, default 1e-10
        FISTA stopping tolerance (see ``lasso_fista``).
    support_rtol : float, default 1e-6
        Lasso entries with ``|u_i| <= support_rtol * ||u||_inf`` are not in
        the support (FISTA leaves entries that converge to zero slowly).
    rank_rtol : float or None, default None
        C B_S counts as rank deficient when an eigenvalue of its Jacobi-scaled
        weighted Gram matrix B_S^T C^T R~^-1 C B_S is at most ``rank_rtol``
        times the largest; default ``max(m, p) * eps``.  The paper needs full
        column rank; on a deficient support M uses the pseudo-inverse and the
        run is flagged in ``state["rank_deficient"]``.

    Attributes
    ----------
    n, m, p : int
        Numbers of states, measurements and inputs.
    delay : int
        1: the estimate produced from y(k) is of x(k) (``Trajectory.x_hat[k + 1]``
        estimates x(k); ``x_hat[0]`` is the prior mean of x(0)), and the input
        estimate produced with it is of u(k - 1) (``Trajectory.a_hat[k + 1]``
        estimates u(k - 1), zero for k = 0).

    Notes
    -----
    The first measurement y(0) gets a measurement update only (no input acts
    before x(0)).  The support is capped at the m largest entries, since C B_S
    cannot have full column rank with more than m columns (the Lasso solution
    has at most m nonzeros anyway when C B has full row rank).

    State dictionary (leading axis: runs): ``x_hat`` (n), ``P`` (n, n),
    ``u_hat`` (p), ``support`` (p, bool), ``lasso`` (p, last Lasso solution,
    the warm start of the next), ``k`` (measurements processed),
    ``rank_deficient`` (bool).

    Examples
    --------
    A scalar input on a 3-state plant, one state measured twice and the
    input entering the first state only:

    >>> import numpy as np
    >>> A = np.diag([0.5, 0.4, 0.3]); B = np.eye(3)[:, :2]
    >>> C = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    >>> sise = SISE(A, B, C, Q=1e-8 * np.eye(3), R=1e-8 * np.eye(3), sparsity=1,
    ...             lasso_weight=1e-6)
    >>> x = np.zeros(3); ys = []
    >>> for k in range(6):
    ...     ys.append(C @ x)
    ...     x = A @ x + B @ np.array([2.0, 0.0])
    >>> traj = sise.run(np.array(ys)[:, None, :])
    >>> np.round(traj.a_hat[-1, 0], 3).tolist()   # u(4) = (2, 0)
    [2.0, 0.0]
    >>> bool(np.allclose(traj.x_hat[-1, 0], ys[-1], atol=1e-3))
    True
    """

    delay = 1

    def __init__(
        self,
        A: Any,
        B: Any,
        C: Any,
        *,
        Q: Any,
        R: Any,
        lasso_weight: float = 1.0,
        sparsity: int | None = None,
        x0_hat: Any = None,
        P0: Any = None,
        lasso_max_iter: int = 5000,
        lasso_rtol: float = 1e-10,
        support_rtol: float = 1e-6,
        rank_rtol: float | None = None,
    ) -> None:
        A = as_real_matrix(A, "A")
        n = A.shape[0]
        if A.shape != (n, n):
            raise ValueError(f"A must be square, got shape {A.shape}")
        B = as_real_matrix(B, "B", shape=(n, None), shape_hint="the number of states")
        C = as_real_matrix(C, "C", shape=(None, n), shape_hint="the number of states")
        m, p = C.shape[0], B.shape[1]
        self.A, self.B, self.C = A, B, C
        self.n, self.m, self.p = n, m, p
        self.Q = _covariance(Q, "Q", n, definite=False)
        self.R = _covariance(R, "R", m, definite=True)
        self.lasso_weight = as_float_option(
            lasso_weight, "lasso_weight", min_value=0.0, min_inclusive=False
        )
        self.sparsity = (
            None
            if sparsity is None
            else as_int_option(sparsity, "sparsity", min_value=1, max_value=p)
        )
        self.x0_hat = (
            np.zeros(n)
            if x0_hat is None
            else as_real_matrix(
                x0_hat, "x0_hat", ndim=1, shape=(n,), shape_hint="the number of states"
            )
        )
        self.P0 = np.eye(n) if P0 is None else _covariance(P0, "P0", n, definite=True)
        self.lasso_max_iter = as_int_option(lasso_max_iter, "lasso_max_iter", min_value=1)
        self.lasso_rtol = as_float_option(lasso_rtol, "lasso_rtol", min_value=0.0)
        self.support_rtol = as_float_option(
            support_rtol, "support_rtol", min_value=0.0, max_value=1.0, max_inclusive=False
        )
        self.rank_rtol = (
            default_rtol(m, p)
            if rank_rtol is None
            else as_float_option(rank_rtol, "rank_rtol", min_value=0.0)
        )
        self.CB = self.C @ self.B

    # -- interface ---------------------------------------------------------

    def initial_state(self, runs: int) -> dict[str, np.ndarray]:
        """Prior of x(0) for ``runs`` runs, before any measurement."""
        runs = as_int_option(runs, "runs", min_value=1)
        return {
            "x_hat": np.tile(self.x0_hat, (runs, 1)),
            "P": np.tile(self.P0, (runs, 1, 1)),
            "u_hat": np.zeros((runs, self.p)),
            "support": np.zeros((runs, self.p), dtype=bool),
            "lasso": np.zeros((runs, self.p)),
            "k": np.zeros(runs, dtype=int),
            "rank_deficient": np.zeros(runs, dtype=bool),
        }

    def estimate(self, state: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """(x_hat(k), u_hat(k - 1)) after the measurement y(k)."""
        return state["x_hat"], state["u_hat"]

    def step(self, state: dict[str, np.ndarray], y: np.ndarray) -> dict[str, np.ndarray]:
        """Process y(k), shape (runs, m): estimates of x(k) and u(k - 1)."""
        x = state["x_hat"]
        runs = x.shape[0]
        y = as_real_matrix(
            y, "y", shape=(runs, self.m), shape_hint="runs x measurements of the state"
        )
        first = state["k"] == 0
        P_pred = self.A @ state["P"] @ self.A.T + self.Q
        x_pred = x @ self.A.T
        if first.any():  # y(0): measurement update of the prior only
            P_pred[first] = state["P"][first]
            x_pred[first] = x[first]
        innov = y - x_pred @ self.C.T
        support, lasso = self._detect_support(state, innov)
        support[first] = False
        return self._update(state, y, x_pred, P_pred, innov, support, lasso)

    # -- support detection -------------------------------------------------

    def _detect_support(
        self, state: dict[str, np.ndarray], innov: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        res = lasso_fista(
            self.CB,
            innov,
            self.lasso_weight,
            initial=state["lasso"],
            max_iter=self.lasso_max_iter,
            rtol=self.lasso_rtol,
        )
        return self.support_of(res.solution), res.solution

    def support_of(self, u: np.ndarray) -> np.ndarray:
        """Support rule applied to Lasso solutions u, shape (runs, p): boolean mask.

        Nonzero entries (above ``support_rtol`` relative to the largest),
        then the ``sparsity`` largest of them if set, at most m in any case.

        Examples
        --------
        >>> import numpy as np
        >>> sise = SISE(np.eye(2), np.eye(2), np.eye(2), Q=np.eye(2), R=np.eye(2),
        ...             sparsity=1)
        >>> sise.support_of(np.array([[0.5, -2.0], [0.0, 0.0]])).tolist()
        [[False, True], [False, False]]
        """
        mag = np.abs(np.atleast_2d(u))
        peak = mag.max(axis=1, keepdims=True)
        mask = (mag > self.support_rtol * peak) & (peak > 0)
        keep = self.m if self.sparsity is None else min(self.sparsity, self.m)
        if keep < self.p:
            order = np.argsort(-mag, axis=1, kind="stable")
            rank = np.empty_like(order)
            np.put_along_axis(rank, order, np.arange(self.p)[None, :].repeat(len(mag), 0), 1)
            mask &= rank < keep
        return mask

    # -- Gillijns-De Moor update on the support ----------------------------

    def _update(self, state, y, x_pred, P_pred, innov, support, lasso):
        n, m, p = self.n, self.m, self.p
        C, F = self.C, self.CB
        R_t = C @ P_pred @ C.T + self.R
        R_t = 0.5 * (R_t + np.swapaxes(R_t, 1, 2))
        chol = np.linalg.cholesky(R_t)
        # R~^-1 F and R~^-1 (C P~) through the Cholesky factor
        Rinv_F = _chol_solve(chol, np.broadcast_to(F, (len(y), m, p)))
        H = np.einsum("ip,rim->rpm", F, Rinv_F)  # F^T R~^-1 F, (runs, p, p)
        mask2 = support[:, :, None] & support[:, None, :]
        Hs = np.where(mask2, H, 0.0)
        d = np.sqrt(np.where(support, np.einsum("rii->ri", Hs), 1.0))
        d = np.where(d > 0, d, 1.0)
        N = Hs / (d[:, :, None] * d[:, None, :])
        N[:, np.arange(p), np.arange(p)] += ~support
        w, V = np.linalg.eigh(N)
        cut = self.rank_rtol * w[:, -1:]
        deficient = (w <= cut).any(axis=1)
        winv = np.where(w > cut, 1.0 / np.where(w > cut, w, 1.0), 0.0)
        Ninv = np.einsum("rij,rj,rkj->rik", V, winv, V)
        Hinv = np.where(mask2, Ninv / (d[:, :, None] * d[:, None, :]), 0.0)
        M = Hinv @ np.swapaxes(Rinv_F, 1, 2)  # (runs, p, m), zero rows off S
        u_hat = np.einsum("rpm,rm->rp", M, innov)
        BM = self.B @ M  # B_S M, (runs, n, m)
        x_star = x_pred + u_hat @ self.B.T
        I_BMC = np.eye(n) - BM @ C
        P_star = I_BMC @ P_pred @ np.swapaxes(I_BMC, 1, 2) + BM @ self.R @ np.swapaxes(BM, 1, 2)
        K = np.swapaxes(_chol_solve(chol, C @ P_pred), 1, 2)  # P~ C^T R~^-1
        x_new = x_star + np.einsum("rnm,rm->rn", K, y - x_star @ C.T)
        P_new = P_star - K @ np.swapaxes(P_star @ C.T - BM @ self.R, 1, 2)
        P_new = 0.5 * (P_new + np.swapaxes(P_new, 1, 2))
        return {
            "x_hat": x_new,
            "P": P_new,
            "u_hat": u_hat,
            "support": support,
            "lasso": lasso,
            "k": state["k"] + 1,
            "rank_deficient": deficient,
        }


def _chol_solve(chol: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve (L L^T) X = rhs for a batch of lower Cholesky factors L."""
    z = np.linalg.solve(chol, rhs)
    return np.linalg.solve(np.swapaxes(chol, 1, 2), z)


def _as_support(value: Any, p: int) -> np.ndarray:
    """Boolean support mask of shape (p,), (runs, p) or (steps, runs, p)."""
    arr = np.asarray(value)
    if arr.dtype != bool:
        if arr.dtype.kind in "iu" and np.isin(arr, (0, 1)).all():
            arr = arr.astype(bool)
        else:
            raise TypeError(f"support must be a boolean mask, got {describe(arr)}")
    if arr.ndim not in (1, 2, 3) or arr.shape[-1] != p:
        raise ValueError(
            f"support must have shape (p,), (runs, p) or (steps, runs, p) with p = {p} "
            f"inputs, got shape {arr.shape}"
        )
    return arr


class OracleSISE(SISE):
    """SISE told the true input support: the paper's benchmark (Gillijns-De Moor on B_S).

    Parameters
    ----------
    A : array_like, shape (n, n)
    B : array_like, shape (n, p)
    C : array_like, shape (m, n)
    Q : array_like, shape (n, n)
        Process noise covariance.
    R : array_like, shape (m, m)
        Measurement noise covariance.
    support : array_like of bool
        supp u(k): shape (p,) (same for every run and step), (runs, p)
        (constant in time) or (steps, runs, p) with ``support[k]`` the support
        of u(k) (for instance ``u != 0`` of a simulation).  Processing y(k)
        uses the support of u(k - 1).
    x0_hat : array_like, shape (n,), optional
        Prior mean of x(0); default zero.
    P0 : array_like, shape (n, n), optional
        Prior covariance of x(0); default identity.
    rank_rtol : float or None, default None
        As in ``SISE``.

    Raises
    ------
    ValueError
        If the support has the wrong shape, or a run's number of runs or
        steps does not match the measurements processed.
    TypeError
        If ``support`` is not a boolean (or 0/1) array.

    Examples
    --------
    With x(0) known and no noise, the oracle is exact from the first step:

    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> n, p, m = 4, 3, 2
    >>> A = rng.standard_normal((n, n)) / 2; B = np.eye(n)[:, :p]
    >>> C = rng.standard_normal((m, n)); x0 = rng.standard_normal(n)
    >>> u = np.zeros((5, p)); u[:, 1] = [1.0, -2.0, 0.5, 3.0, 1.0]
    >>> x = [x0]
    >>> for k in range(5):
    ...     x.append(A @ x[-1] + B @ u[k])
    >>> y = np.array([C @ xk for xk in x])[:, None, :]
    >>> oracle = OracleSISE(A, B, C, Q=1e-4 * np.eye(n), R=1e-4 * np.eye(m),
    ...                     support=[False, True, False], x0_hat=x0)
    >>> traj = oracle.run(y)
    >>> float(np.abs(traj.a_hat[2:, 0] - u).max()) < 1e-9
    True
    """

    def __init__(
        self,
        A: Any,
        B: Any,
        C: Any,
        *,
        Q: Any,
        R: Any,
        support: Any,
        x0_hat: Any = None,
        P0: Any = None,
        rank_rtol: float | None = None,
    ) -> None:
        super().__init__(A, B, C, Q=Q, R=R, x0_hat=x0_hat, P0=P0, rank_rtol=rank_rtol)
        self.support = _as_support(support, self.p)

    def _detect_support(self, state, innov):
        runs = innov.shape[0]
        s = self.support
        k = state["k"]
        if s.ndim == 1:
            mask = np.broadcast_to(s, (runs, self.p)).copy()
        elif s.ndim == 2:
            if s.shape[0] != runs:
                raise ValueError(f"support has {s.shape[0]} runs, the measurements have {runs}")
            mask = s.copy()
        else:
            if s.shape[1] != runs:
                raise ValueError(f"support has {s.shape[1]} runs, the measurements have {runs}")
            need = int(k.max())  # processing y(k) needs supp u(k - 1)
            if need > s.shape[0]:
                raise ValueError(
                    f"support covers u(0..{s.shape[0] - 1}); processing y({need}) needs "
                    f"u({need - 1})"
                )
            mask = s[np.maximum(k - 1, 0), np.arange(runs)].copy()
        return mask, np.zeros((runs, self.p))


def recursive_input_estimate(
    A: Any, B: Any, C: Any, y: Any, x0: Any
) -> tuple[np.ndarray, np.ndarray]:
    """The recursive state and sparse-input estimation of Sefati, Cowan and Vidal (ACC 2015),
    as the SISE paper summarises it (its Sec. II-C, the baseline [14] of its Fig. 4).

    From the initial state x_hat(0) = x0, at each k >= 1 the input u(k - 1)
    is the basis pursuit solution of ``min ||u||_1 s.t. C B u = y(k) - C A
    x_hat(k - 1)`` (a linear program, HiGHS), and ``x_hat(k) = A x_hat(k -
    1) + B u_hat(k - 1)``.  Without noise, and with C B fit for compressed
    sensing, it recovers the states and inputs exactly; it has no model of
    noise, which then accumulates (the SISE paper's point).

    Parameters
    ----------
    A : array_like, shape (n, n)
    B : array_like, shape (n, p)
    C : array_like, shape (m, n)
    y : array_like, shape (steps, m) or (steps, runs, m)
        y(0), ..., y(steps - 1) (y(0) is not used: x(0) is given).
    x0 : array_like, shape (n,) or (runs, n)

    Returns
    -------
    x_hat : ndarray, shape (steps, n) or (steps, runs, n)
        x_hat(0) = x0, then the estimates of x(1), ..., x(steps - 1).
    u_hat : ndarray, shape (steps - 1, p) or (steps - 1, runs, p)
        The estimates of u(0), ..., u(steps - 2).

    Examples
    --------
    >>> import numpy as np
    >>> A, B = 0.5 * np.eye(3), np.eye(3)
    >>> C = np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]])  # two measurements, three inputs
    >>> x0, u = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 2.0])  # one input active
    >>> x1 = A @ x0 + B @ u
    >>> x_hat, u_hat = recursive_input_estimate(A, B, C, [C @ x0, C @ x1], x0)
    >>> bool(np.allclose(x_hat[1], x1)) and bool(np.allclose(u_hat[0], u))
    True
    """
    import scipy.optimize
    import scipy.sparse

    A = as_real_matrix(A, "A", shape=(None, None))
    n = A.shape[0]
    if A.shape != (n, n):
        raise ValueError(f"A: expected a square matrix, got shape {A.shape}")
    B = as_real_matrix(B, "B", shape=(n, None), shape_hint="n x p")
    C = as_real_matrix(C, "C", shape=(None, n), shape_hint="m x n")
    Y = np.asarray(y, dtype=float)
    single = Y.ndim == 2
    if single:
        Y = Y[:, None, :]
    if Y.ndim != 3 or Y.shape[2] != C.shape[0]:
        raise ValueError(
            f"y: expected shape (steps, {C.shape[0]}) or (steps, runs, {C.shape[0]}), got "
            f"{describe(y)}"
        )
    X0 = np.asarray(x0, dtype=float).reshape(-1, n) if single else np.asarray(x0, dtype=float)
    if X0.shape != (Y.shape[1], n):
        raise ValueError(
            f"x0: expected {Y.shape[1]} initial states of length {n}, got {describe(x0)}"
        )
    steps, runs, p = Y.shape[0], Y.shape[1], B.shape[1]
    F = C @ B
    # the runs' basis pursuits of one step do not interact: one LP, block diagonal
    block = scipy.sparse.csr_matrix(np.hstack([F, -F]))
    A_eq = scipy.sparse.block_diag([block] * runs, format="csr")
    cost = np.ones(A_eq.shape[1])
    x_hat = np.empty((steps, runs, n))
    u_hat = np.empty((max(steps - 1, 0), runs, p))
    x_hat[0] = X0
    for k in range(1, steps):
        rhs = Y[k] - x_hat[k - 1] @ (C @ A).T
        solution = scipy.optimize.linprog(
            cost, A_eq=A_eq, b_eq=rhs.ravel(), bounds=(0, None), method="highs"
        )
        if solution.status != 0:
            raise RuntimeError(f"basis pursuit at step {k} failed: {solution.message}")
        parts = solution.x.reshape(runs, 2 * p)
        u_hat[k - 1] = parts[:, :p] - parts[:, p:]
        x_hat[k] = x_hat[k - 1] @ A.T + u_hat[k - 1] @ B.T
    if single:
        return x_hat[:, 0], u_hat[:, 0]
    return x_hat, u_hat
