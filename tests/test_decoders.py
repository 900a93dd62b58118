"""Static decoders: iterative solvers against cvxpy, exact decoders against brute force."""

import inspect
import itertools

import cvxpy as cp
import numpy as np
import pytest
from scipy.optimize import linprog

from ssecert import System, sparse_observability
from ssecert.estimators import decoders, support_decoders
from ssecert.estimators.decoders import (
    elastic_net_cvxpy,
    fista,
    ijam,
    ista,
    partial_lasso_cvxpy,
)
from ssecert.estimators.shrinkage import soft_threshold
from ssecert.estimators.support_decoders import l0_decoder, l1_decoder

VARIANTS = {
    "ista": (ista, {}),
    "ista-orthonormal": (ista, {"orthonormalize": True}),
    "fista": (fista, {}),
    "fista-restart": (fista, {"restart": True}),
    "fista-orthonormal-restart": (fista, {"orthonormalize": True, "restart": True}),
    "ijam": (ijam, {}),
}


def relative_error(estimate, reference):
    return np.linalg.norm(estimate - reference) / max(np.linalg.norm(reference), 1e-300)


def signed_uniform(rng, low, high, size):
    return rng.uniform(low, high, size) * rng.choice([-1.0, 1.0], size)


def static_instance(rng, m, n, s, *, noise=0.0):
    """y = M x + a with a Gaussian M, s attacked rows; magnitudes as in the Lasso paper."""
    M = rng.standard_normal((m, n))
    x = signed_uniform(rng, 2.0, 3.0, n)
    support = np.sort(rng.choice(m, s, replace=False))
    a = np.zeros(m)
    a[support] = signed_uniform(rng, 4.0, 5.0, s)
    y = M @ x + a + noise * rng.uniform(-1.0, 1.0, m)
    return M, y, x, a, tuple(int(i) for i in support)


def random_plant(rng, n, p):
    A = rng.standard_normal((n, n))
    A /= np.abs(np.linalg.eigvals(A)).max()  # spectral radius 1
    return System(A, rng.standard_normal((p, n)))


def stacked_instance(rng, n, p, s, tau, *, noise=0.0):
    """y = O_tau x + a, attack on s sensors at every step (time-invariant support)."""
    system = random_plant(rng, n, p)
    O = system.observability_matrix(tau)
    x = signed_uniform(rng, 2.0, 3.0, n)
    sensors = np.sort(rng.choice(p, s, replace=False))
    a = np.zeros((tau, p))
    a[:, sensors] = signed_uniform(rng, 4.0, 5.0, (tau, s))
    y = O @ x + a.ravel() + noise * rng.uniform(-1.0, 1.0, tau * p)
    return system, O, y, x, a.ravel(), tuple(int(i) for i in sensors)


def lasso_instance(kind, seed):
    rng = np.random.default_rng(seed)
    if kind == "static":
        M, y, *_ = static_instance(rng, 30, 10, 4, noise=1e-3)
    else:
        _, M, y, *_ = stacked_instance(rng, 4, 6, 1, 4, noise=1e-3)
    return M, y


def partial_lasso_kkt(M, y, lam, x, a):
    """Optimality residuals of (x, a), relative to the data.

    Stationarity M'r = 0 and r_i = -lam sign(a_i) on the support (relative to
    ||y||), and the largest |r_i| / lam off the support (at most 1), with
    r = M x + a - y.
    """
    r = M @ x + a - y
    on = np.abs(a) > 0
    scale = np.linalg.norm(y)
    return (
        np.linalg.norm(M.T @ r) / (np.linalg.norm(M, 2) * scale),
        np.max(np.abs(r[on] + lam * np.sign(a[on])), initial=0.0) / scale,
        np.max(np.abs(r[~on]), initial=0.0) / lam,
    )


# ---------------------------------------------------------------------------
# partial Lasso: cvxpy is optimal, and every iterative solver reaches it


@pytest.mark.parametrize("kind", ["static", "stacked"])
@pytest.mark.parametrize("seed", range(4))
def test_cvxpy_partial_lasso_meets_optimality_conditions(kind, seed):
    M, y = lasso_instance(kind, seed)
    lam = 0.1
    x, a = partial_lasso_cvxpy(M, y, lam)
    a = np.where(np.abs(a) > 1e-7 * np.abs(a).max(), a, 0.0)  # interior-point zeros
    stationarity, on_support, off_support = partial_lasso_kkt(M, y, lam, x, a)
    assert stationarity < 1e-9
    assert on_support < 1e-9
    assert off_support <= 1.0 + 1e-6


@pytest.mark.parametrize("method", sorted(VARIANTS))
@pytest.mark.parametrize("kind", ["static", "stacked"])
@pytest.mark.parametrize("seed", range(4))
def test_iterative_solvers_reach_the_cvxpy_solution(method, kind, seed):
    M, y = lasso_instance(kind, seed)
    lam = 0.1
    x_ref, a_ref = partial_lasso_cvxpy(M, y, lam)
    solve, options = VARIANTS[method]
    sol = solve(M, y, lam, iterations=50_000, **options)
    assert sol.converged and sol.change <= sol.tol
    assert relative_error(sol.x, x_ref) < 1e-6
    assert relative_error(sol.a, a_ref) < 1e-6
    stationarity, on_support, off_support = partial_lasso_kkt(M, y, lam, sol.x, sol.a)
    assert stationarity < 1e-8 and on_support < 1e-8 and off_support <= 1.0 + 1e-6


@pytest.mark.parametrize("seed", range(3))
def test_ijam_is_a_jacobi_update(seed):
    """Two hand-written IJAM steps: x(k+1) uses a(k), a(k+1) uses x(k)."""
    M, y = lasso_instance("static", seed)
    lam, nu = 0.1, 0.7
    rng = np.random.default_rng(100 + seed)
    x, a = rng.standard_normal(M.shape[1]), rng.standard_normal(M.shape[0])
    sol = ijam(M, y, lam, nu=nu, iterations=2, tol=0.0, x0=x, a0=a)
    pinv = np.linalg.pinv(M)
    for _ in range(2):
        x, a = pinv @ (y - a), soft_threshold(a - nu * (M @ x + a - y), nu * lam)
    np.testing.assert_allclose(sol.x, x, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(sol.a, a, rtol=1e-12, atol=1e-12)
    assert sol.iterations == 2 and not sol.converged


@pytest.mark.parametrize("restart", [False, True])
def test_fista_follows_beck_teboulle(restart):
    """Hand-written FISTA iterations, with the gradient restart when asked for."""
    M, y = lasso_instance("static", 1)
    lam = 0.1
    nu = 1.0 / (np.linalg.norm(M, 2) ** 2 + 1.0)
    z = w = np.zeros(M.shape[1] + M.shape[0])
    n, t, restarts = M.shape[1], 1.0, 0
    for _ in range(60):
        r = M @ w[:n] + w[n:] - y
        z_new = np.r_[w[:n] - nu * (M.T @ r), soft_threshold(w[n:] - nu * r, nu * lam)]
        if restart and (w - z_new) @ (z_new - z) > 0:
            t, restarts = 1.0, restarts + 1
        t_next = (1.0 + np.sqrt(1.0 + 4.0 * t * t)) / 2.0
        z, w, t = z_new, z_new + (t - 1.0) / t_next * (z_new - z), t_next
    sol = fista(M, y, lam, iterations=60, tol=0.0, restart=restart)
    np.testing.assert_allclose(np.r_[sol.x, sol.a], z, rtol=1e-11, atol=1e-11)
    assert (restarts > 0) == restart


def test_fista_is_faster_than_ista():
    M, y = lasso_instance("static", 2)
    slow, fast = ista(M, y, 0.1, tol=1e-9), fista(M, y, 0.1, tol=1e-9, restart=True)
    assert slow.converged and fast.converged
    assert fast.iterations < slow.iterations / 2


@pytest.mark.parametrize("solve", [ista, fista])
def test_orthonormalized_iterations_on_a_rank_deficient_matrix(solve):
    """Same fit and attack as cvxpy; x is the minimum-norm one (orthogonal to null(M))."""
    rng = np.random.default_rng(21)
    M = rng.standard_normal((25, 4))
    M[:, 3] = M[:, 0] + 2.0 * M[:, 1]
    y = M @ signed_uniform(rng, 2, 3, 4) + 4.5 * np.eye(25)[[3, 17]].sum(axis=0)
    x_ref, a_ref = partial_lasso_cvxpy(M, y, 0.1)
    sol = solve(M, y, 0.1, orthonormalize=True, iterations=50_000)
    assert sol.converged and sol.step == pytest.approx(0.5, rel=1e-12)
    assert relative_error(M @ sol.x, M @ x_ref) < 1e-7
    assert relative_error(sol.a, a_ref) < 1e-7
    null = np.array([1.0, 2.0, 0.0, -1.0]) / np.sqrt(6.0)
    assert abs(null @ sol.x) < 1e-9 * np.linalg.norm(sol.x)


def test_orthonormalization_speeds_up_ill_conditioned_matrices():
    M, y = lasso_instance("static", 3)
    M = M * np.r_[1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 30.0]  # one stiff column
    x_ref, _ = partial_lasso_cvxpy(M, y, 0.1)
    plain = fista(M, y, 0.1, restart=True, iterations=50_000)
    orthonormal = fista(M, y, 0.1, restart=True, orthonormalize=True, iterations=50_000)
    assert plain.converged and orthonormal.converged
    assert orthonormal.iterations < plain.iterations / 5
    assert relative_error(orthonormal.x, x_ref) < 1e-8
    # a small step also makes the step-size stopping rule stop farther from the solution
    assert relative_error(plain.x, x_ref) > 10 * relative_error(orthonormal.x, x_ref)


def test_ijam_refuses_rank_deficient_matrices():
    M = np.random.default_rng(0).standard_normal((8, 3))
    M[:, 2] = M[:, 0] - M[:, 1]
    with pytest.raises(ValueError, match="M must have full column rank"):
        ijam(M, np.ones(8), 0.1)
    with pytest.raises(ValueError, match="M must have full column rank"):
        ijam(np.ones((2, 3)), np.ones(2), 0.1)


def test_stopping_rule_and_reported_fields():
    M, y = lasso_instance("static", 0)
    L = np.linalg.norm(M, 2) ** 2 + 1.0
    short = ista(M, y, 0.1, iterations=3)
    assert short.iterations == 3 and not short.converged and short.change > short.tol
    assert short.step == pytest.approx(1.0 / L, rel=1e-14)
    full = fista(M, y, 0.1, tol=1e-6)
    assert full.converged and full.change <= 1e-6 < short.change
    assert full.method == "fista" and full.iterations < 50_000


# ---------------------------------------------------------------------------
# batches


@pytest.mark.slow
@pytest.mark.parametrize("method", sorted(VARIANTS))
def test_batched_calls_equal_per_run_calls(method):
    rng = np.random.default_rng(7)
    M = rng.standard_normal((20, 5))
    Y = np.stack([static_instance(rng, 20, 5, 3)[1] for _ in range(4)])
    X0 = rng.standard_normal((4, 5))
    Y[3], X0[3] = 0.0, 0.0  # solution zero from the start: stops after one step
    solve, options = VARIANTS[method]
    batch = solve(M, Y, 0.2, x0=X0, **options)
    assert batch.x.shape == (4, 5) and batch.a.shape == (4, 20)
    assert batch.iterations[3] == 1 and batch.converged[3]
    for k in range(4):
        single = solve(M, Y[k], 0.2, x0=X0[k], **options)
        np.testing.assert_allclose(batch.x[k], single.x, rtol=1e-12, atol=1e-13)
        np.testing.assert_allclose(batch.a[k], single.a, rtol=1e-12, atol=1e-13)
        assert batch.iterations[k] == single.iterations
        assert batch.converged[k] == single.converged


def test_batched_starts_per_run():
    rng = np.random.default_rng(3)
    M = rng.standard_normal((12, 3))
    Y = rng.standard_normal((2, 12))
    X0 = rng.standard_normal((2, 3))
    batch = ista(M, Y, 0.1, x0=X0, iterations=5, tol=0.0)
    for k in range(2):
        single = ista(M, Y[k], 0.1, x0=X0[k], iterations=5, tol=0.0)
        np.testing.assert_allclose(batch.x[k], single.x, rtol=1e-12, atol=1e-13)


# ---------------------------------------------------------------------------
# elastic net


def elastic_net_proximal_gradient(M, y, lam, mu, iterations=50_000):
    """Proximal gradient with the prox of lam |a| + (mu / 2) a^2, written out here."""
    step = 1.0 / (np.linalg.norm(M, 2) ** 2 + 1.0)
    x, a = np.zeros(M.shape[1]), np.zeros(M.shape[0])
    for _ in range(iterations):
        r = M @ x + a - y
        x_new = x - step * (M.T @ r)
        v = a - step * r
        a_new = np.sign(v) * np.maximum(np.abs(v) - step * lam, 0.0) / (1.0 + step * mu)
        done = np.linalg.norm(np.r_[x_new - x, a_new - a]) <= 1e-13 * np.linalg.norm(np.r_[x, a])
        x, a = x_new, a_new
        if done:
            break
    return x, a


@pytest.mark.parametrize("seed", range(3))
def test_elastic_net_matches_proximal_gradient(seed):
    M, y = lasso_instance("static", seed)
    lam, mu = 0.1, 0.5
    x_ref, a_ref = elastic_net_proximal_gradient(M, y, lam, mu)
    x, a = elastic_net_cvxpy(M, y, lam, mu)
    assert relative_error(x, x_ref) < 1e-6
    assert relative_error(a, a_ref) < 1e-6
    # mu shrinks the attack estimate towards 0 relative to the Lasso
    _, a_lasso = partial_lasso_cvxpy(M, y, lam)
    assert np.linalg.norm(a) < np.linalg.norm(a_lasso)


def test_elastic_net_without_l2_is_the_partial_lasso():
    M, y = lasso_instance("static", 5)
    x, a = elastic_net_cvxpy(M, y, 0.1, 0.0)
    x_ref, a_ref = partial_lasso_cvxpy(M, y, 0.1)
    assert relative_error(x, x_ref) < 1e-7 and relative_error(a, a_ref) < 1e-7


# ---------------------------------------------------------------------------
# l0 decoder


def brute_force_l0(M, y, s, sensors, rtol=1e-9):
    """Supports by size, lexicographically; least squares on the other sensors' rows."""
    q = int(sensors.max()) + 1
    best = None
    for k in range(s + 1):
        for support in itertools.combinations(range(q), k):
            kept = ~np.isin(sensors, support)
            x = np.linalg.lstsq(M[kept], y[kept], rcond=None)[0]
            residual = np.linalg.norm(y[kept] - M[kept] @ x)
            if residual <= rtol * np.linalg.norm(y):
                return support, x, True
            if k == s and (best is None or residual < best[0]):
                best = (residual, support, x)
    return best[1], best[2], False


def static_sparse_observable(C, s):
    """Every set of p - 2s rows of C has full column rank."""
    p, n = C.shape
    return all(
        np.linalg.matrix_rank(np.delete(C, list(removed), axis=0)) == n
        for removed in itertools.combinations(range(p), 2 * s)
    )


@pytest.mark.parametrize("seed", range(6))
def test_l0_recovers_state_and_support_static(seed):
    rng = np.random.default_rng(seed)
    n, s = 3, 2
    p = 2 * s + n + seed % 3
    C, y, x, a, support = static_instance(rng, p, n, s)
    assert static_sparse_observable(C, s)
    sol = l0_decoder(C, y, s)
    assert sol.support == support and sol.consistent and sol.unique
    assert relative_error(sol.x, x) < 1e-9
    np.testing.assert_allclose(sol.a, a, atol=1e-9 * np.linalg.norm(y))


@pytest.mark.parametrize("seed", range(6))
def test_l0_recovers_state_and_support_stacked(seed):
    rng = np.random.default_rng(seed)
    n, s = 3, 2
    p = 2 * s + n
    system, O, y, x, a, sensors = stacked_instance(rng, n, p, s, n)
    assert sparse_observability(system, s).verdict.value == "holds"
    sol = l0_decoder(O, y, s, sensors_of_row=np.tile(np.arange(p), n))
    assert sol.support == sensors and sol.consistent and sol.unique
    assert relative_error(sol.x, x) < 1e-9
    np.testing.assert_allclose(sol.a, a, atol=1e-9 * np.linalg.norm(y))


@pytest.mark.parametrize("seed", range(8))
def test_l0_agrees_with_brute_force(seed):
    """Including attacks on more sensors than s and noise, where no support is consistent."""
    rng = np.random.default_rng(seed)
    n, p, tau = 2, 5, 2
    _, O, y, *_ = stacked_instance(rng, n, p, 1 + seed % 3, tau, noise=1e-3 * (seed % 2))
    sensors = np.tile(np.arange(p), tau)
    s = 2
    support, x, consistent = brute_force_l0(O, y, s, sensors)
    sol = l0_decoder(O, y, s, sensors_of_row=sensors)
    assert sol.support == support and sol.consistent == consistent
    np.testing.assert_allclose(sol.x, x, rtol=1e-9, atol=1e-12)


def test_l0_picks_the_smallest_then_lexicographically_first_support():
    M = np.ones((5, 1))
    y = np.array([1.0, 2.0, 1.0, 2.0, 3.0])
    sol = l0_decoder(M, y, 3)  # kept {1, 3} (x = 2) and kept {0, 2} (x = 1) tie
    assert sol.support == (0, 2, 4) and sol.consistent
    assert sol.x == pytest.approx([2.0], rel=1e-12)
    short = l0_decoder(M, y, 2)  # least residual sqrt(2/3), first reached removing (0, 2)
    assert not short.consistent and short.support == (0, 2)
    assert short.residual == pytest.approx(np.sqrt(2.0 / 3.0), rel=1e-12)


def test_l0_with_noise_returns_the_least_residual_support():
    rng = np.random.default_rng(11)
    C, y, x, _, support = static_instance(rng, 12, 3, 2, noise=1e-4)
    sol = l0_decoder(C, y, 2)
    assert not sol.consistent and sol.support == support
    assert relative_error(sol.x, x) < 1e-3
    assert sol.residual > sol.rtol * np.linalg.norm(y)


def test_l0_refuses_searches_beyond_the_budget():
    with pytest.raises(ValueError, match="max_supports"):
        l0_decoder(np.ones((30, 1)), np.ones(30), 5, max_supports=1000)
    sol = l0_decoder(np.ones((30, 1)), np.ones(30), 1, max_supports=31)
    assert sol.support == () and sol.checked == 1


def test_zero_sensing_matrix():
    """x does not enter the data: l0 removes the largest sensors, Lasso keeps x = 0."""
    y = np.array([0.0, 3.0, 0.0, -4.0])
    sol = l0_decoder(np.zeros((4, 2)), y, 2)
    assert sol.support == (1, 3) and sol.consistent and not sol.unique
    np.testing.assert_array_equal(sol.x, 0.0)
    lasso = fista(np.zeros((4, 2)), y, 0.5, orthonormalize=True)
    np.testing.assert_array_equal(lasso.x, 0.0)
    np.testing.assert_allclose(lasso.a, [0.0, 2.5, 0.0, -3.5], rtol=1e-9)


# ---------------------------------------------------------------------------
# l1 decoder


@pytest.mark.parametrize("seed", range(4))
def test_l1_decoder_recovers_the_state_and_matches_cvxpy(seed):
    rng = np.random.default_rng(seed)
    M, y, x, _, _ = static_instance(rng, 40, 4, 3)
    x_hat = l1_decoder(M, y)
    assert relative_error(x_hat, x) < 1e-8
    z = cp.Variable(4)
    problem = cp.Problem(cp.Minimize(cp.norm1(y - M @ z)))
    problem.solve(solver=cp.CLARABEL)
    assert np.abs(y - M @ x_hat).sum() <= problem.value * (1 + 1e-7)
    assert relative_error(z.value, x_hat) < 1e-6


def test_l1_decoder_matches_an_independent_linprog_with_dense_attacks():
    """Too many attacks to recover x; both LP forms still agree on the optimal value."""
    rng = np.random.default_rng(4)
    M, y, *_ = static_instance(rng, 15, 3, 7)
    x_hat = l1_decoder(M, y)
    m, n = M.shape
    # epigraph form: min 1't, -t <= y - M x <= t
    res = linprog(
        np.r_[np.zeros(n), np.ones(m)],
        A_ub=np.block([[-M, -np.eye(m)], [M, -np.eye(m)]]),
        b_ub=np.r_[-y, y],
        bounds=[(None, None)] * n + [(0, None)] * m,
        method="highs",
    )
    assert res.status == 0
    assert np.abs(y - M @ x_hat).sum() == pytest.approx(res.fun, rel=1e-9)


# ---------------------------------------------------------------------------
# arguments

M0 = np.random.default_rng(0).standard_normal((6, 2))
Y0 = np.ones(6)


@pytest.mark.parametrize(
    "call, error, name",
    [
        (lambda: ista("abc", Y0, 0.1), TypeError, "M"),
        (lambda: ista(M0 + 1j, Y0, 0.1), TypeError, "M"),
        (lambda: ista(M0, Y0[:-1], 0.1), ValueError, "y"),
        (lambda: ista(M0, np.zeros((2, 2, 6)), 0.1), ValueError, "y"),
        (lambda: ista(M0, [[1.0] * 6, [1.0] * 5], 0.1), ValueError, "y"),
        (lambda: ista(M0, ["a"] * 6, 0.1), TypeError, "y"),
        (lambda: ista(M0, Y0, -1.0), ValueError, "lam"),
        (lambda: ista(M0, Y0, "0.1"), TypeError, "lam"),
        (lambda: ista(M0, Y0, 0.1, step=1.0), ValueError, "step"),
        (lambda: fista(M0, Y0, 0.1, step=0.0), ValueError, "step"),
        (lambda: fista(M0, Y0, 0.1, iterations=0), ValueError, "iterations"),
        (lambda: fista(M0, Y0, 0.1, iterations=2.5), TypeError, "iterations"),
        (lambda: fista(M0, Y0, 0.1, tol=-1.0), ValueError, "tol"),
        (lambda: fista(M0, Y0, 0.1, restart="yes"), TypeError, "restart"),
        (lambda: ista(M0, Y0, 0.1, orthonormalize=1), TypeError, "orthonormalize"),
        (lambda: ista(M0, Y0, 0.1, orthonormalize=True, step=1.0), ValueError, "step"),
        (lambda: ista(M0, Y0, 0.1, x0=np.zeros(3)), ValueError, "x0"),
        (lambda: ista(M0, np.ones((2, 6)), 0.1, a0=np.zeros((3, 6))), ValueError, "a0"),
        (lambda: ijam(M0, Y0, 0.1, nu=1.5), ValueError, "nu"),
        (lambda: ijam(M0, Y0, 0.1, nu=True), TypeError, "nu"),
        (lambda: partial_lasso_cvxpy(M0, np.ones((2, 6)), 0.1), ValueError, "y"),
        (lambda: partial_lasso_cvxpy(M0, Y0, 0.0), ValueError, "lam"),
        (lambda: elastic_net_cvxpy(M0, Y0, 0.1, -1.0), ValueError, "mu"),
        (lambda: l1_decoder(M0, np.r_[Y0[:-1], np.nan]), ValueError, "y"),
        (lambda: l1_decoder([[1.0, 2.0], [3.0]], [1.0, 2.0]), ValueError, "M"),
        (lambda: l0_decoder(M0, Y0, -1), ValueError, "s"),
        (lambda: l0_decoder(M0, Y0, 6), ValueError, "s"),
        (lambda: l0_decoder(M0, Y0, True), TypeError, "s"),
        (lambda: l0_decoder(M0, Y0, 1, sensors_of_row=[0] * 5), ValueError, "sensors_of_row"),
        (
            lambda: l0_decoder(M0, Y0, 1, sensors_of_row=[0, 1, 3, 0, 1, 3]),
            ValueError,
            "sensors_of_row",
        ),
        (
            lambda: l0_decoder(M0, Y0, 1, sensors_of_row=[0, 1, 2, 0, 1, -1]),
            ValueError,
            "sensors_of_row",
        ),
        (lambda: l0_decoder(M0, Y0, 1, sensors_of_row="abcdef"), TypeError, "sensors_of_row"),
        (lambda: l0_decoder(M0, Y0, 1, sensors_of_row=[0.5] * 6), TypeError, "sensors_of_row"),
        (lambda: l0_decoder(M0, Y0, 1, max_supports=0), ValueError, "max_supports"),
        (lambda: l0_decoder(M0, Y0, 1, rtol=-1.0), ValueError, "rtol"),
        (lambda: l0_decoder(M0, Y0, 1, screen_rtol=0.0), ValueError, "screen_rtol"),
    ],
)
def test_bad_arguments_are_refused_by_name(call, error, name):
    with pytest.raises(error, match=rf"^{name}\b|\b{name} "):
        call()


@pytest.mark.parametrize(
    ("module", "name"),
    [(m, name) for m in (decoders, support_decoders) for name in m.__all__],
)
def test_public_arguments_are_documented(module, name):
    obj = getattr(module, name)
    doc = inspect.getdoc(obj) or ""
    if inspect.isclass(obj):
        assert "Attributes" in doc
        for field in obj.__dataclass_fields__:
            assert f"{field} :" in doc, (name, field)
        return
    for section in ("Parameters", "Returns", "Raises", "Examples", ">>>"):
        assert section in doc, (name, section)
    for param in inspect.signature(obj).parameters:
        assert f"{param} :" in doc, (name, param)
