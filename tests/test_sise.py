"""SISE (ECC 2019): the batched Lasso against cvxpy, the filter against its exact cases.

* the FISTA Lasso and SISE's support detection agree with cvxpy;
* the oracle (true support) and SISE are exact without noise when x(0) is
  known and C B_S has full column rank, and the oracle forgets a wrong prior;
* the covariance update (13) equals the Joseph form of the error covariance;
* with an empty support the filter is the Kalman filter that ignores u;
* with small noise SISE tracks x and u much better than that Kalman filter;
* batched runs equal one-run-at-a-time runs; bad inputs name the argument.
"""

import cvxpy as cp
import numpy as np
import pytest

from ssecert.estimators.sise import SISE, OracleSISE, lasso_fista


def plant(seed, n, p, m, *, a_scale=None):
    """The paper's random plant: A ~ N(0, 1/n) entries, B = [I_p; 0], C ~ N(0, 1)."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n)) * (a_scale if a_scale is not None else 1 / np.sqrt(n))
    B = np.eye(n)[:, :p]
    C = rng.standard_normal((m, n))
    return A, B, C


def simulate(A, B, C, *, runs, steps, seed, amplitude, q_std=0.0, r_std=0.0, support_size=1):
    """x(k+1) = A x + B u + w, y = C x + v; u has a constant random support, random signs."""
    rng = np.random.default_rng(seed)
    n, p = B.shape
    m = C.shape[0]
    x = rng.standard_normal((runs, n))
    u = np.zeros((steps, runs, p))
    for r in range(runs):
        S = rng.choice(p, support_size, replace=False)
        u[:, r, S] = amplitude * rng.choice([-1.0, 1.0], (steps, support_size))
    xs, ys = [x], []
    for k in range(steps):
        ys.append(x @ C.T + r_std * rng.standard_normal((runs, m)))
        x = x @ A.T + u[k] @ B.T + q_std * rng.standard_normal((runs, n))
        xs.append(x)
    return np.array(xs), np.array(ys), u


def kalman_ignoring_input(A, C, Q, R, y, x0_hat, P0):
    """Plain Kalman filter with u = 0 (filtered estimates of x(k) from y(0..k))."""
    runs = y.shape[1]
    x = np.tile(x0_hat, (runs, 1))
    P = P0.copy()
    out = []
    for k in range(y.shape[0]):
        if k > 0:
            x = x @ A.T
            P = A @ P @ A.T + Q
        S = C @ P @ C.T + R
        K = P @ C.T @ np.linalg.inv(S)
        x = x + (y[k] - x @ C.T) @ K.T
        P = P - K @ C @ P
        out.append(x)
    return np.array(out)


def rel(err, ref):
    return np.linalg.norm(err, axis=-1) / np.linalg.norm(ref, axis=-1)


# -- the Lasso ------------------------------------------------------------------


TIGHT = dict(tol_gap_abs=1e-12, tol_gap_rel=1e-12, tol_feas=1e-12, tol_ktratio=1e-10)


def cvx_lasso(Phi, y, weight):
    u = cp.Variable(Phi.shape[1])
    cp.Problem(cp.Minimize(cp.sum_squares(y - Phi @ u) + weight * cp.norm1(u))).solve(
        solver="CLARABEL", **TIGHT
    )
    return u.value


@pytest.mark.parametrize("weight", [0.3, 1.0, 5.0])
def test_lasso_matches_cvxpy(weight):
    rng = np.random.default_rng(7)
    Phi = rng.standard_normal((8, 15))
    u_true = np.zeros((6, 15))
    for r in range(6):
        u_true[r, rng.choice(15, 2, replace=False)] = rng.uniform(1, 3, 2)
    Y = u_true @ Phi.T + 0.1 * rng.standard_normal((6, 8))
    res = lasso_fista(Phi, Y, weight)
    assert res.converged.all()
    assert (res.kkt_residual < 1e-6).all()
    for r in range(6):
        ref = cvx_lasso(Phi, Y[r], weight)
        assert np.allclose(res.solution[r], ref, atol=1e-6 * max(1.0, np.abs(ref).max()))
        # same support, away from entries cvxpy leaves at solver precision
        assert np.array_equal(np.abs(res.solution[r]) > 1e-6, np.abs(ref) > 1e-6)


def test_lasso_rows_are_independent_and_warm_start_is_harmless():
    rng = np.random.default_rng(3)
    Phi = rng.standard_normal((5, 9))
    Y = rng.standard_normal((4, 5))
    batch = lasso_fista(Phi, Y, 0.5)
    for r in range(4):
        alone = lasso_fista(Phi, Y[r], 0.5)
        assert np.allclose(alone.solution, batch.solution[r], rtol=0, atol=1e-12)
        assert alone.iterations == batch.iterations[r]
    warm = lasso_fista(Phi, Y, 0.5, initial=batch.solution + 0.3)
    assert np.allclose(warm.solution, batch.solution, atol=1e-8)


def test_lasso_zero_below_the_critical_weight():
    rng = np.random.default_rng(4)
    Phi = rng.standard_normal((5, 9))
    y = rng.standard_normal(5)
    critical = 2 * np.abs(Phi.T @ y).max()  # above it the solution is zero
    assert np.all(lasso_fista(Phi, y, 1.01 * critical).solution == 0)
    assert np.any(lasso_fista(Phi, y, 0.9 * critical).solution != 0)


def test_sise_support_detection_is_the_cvxpy_lasso_of_the_innovation():
    A, B, C = plant(11, n=10, p=8, m=5)
    Q, R = 0.01 * np.eye(10), 0.01 * np.eye(5)
    xs, ys, u = simulate(A, B, C, runs=3, steps=6, seed=1, amplitude=3.0, q_std=0.1, r_std=0.1)
    sise = SISE(A, B, C, Q=Q, R=R, lasso_weight=0.5)
    state = sise.initial_state(3)
    for k in range(6):
        prev = state
        state = sise.step(state, ys[k])
    innov = ys[5] - prev["x_hat"] @ A.T @ C.T  # y(k) - C A x_hat(k-1)
    for r in range(3):
        ref = cvx_lasso(C @ B, innov[r], 0.5)
        assert np.allclose(state["lasso"][r], ref, atol=1e-6 * max(1.0, np.abs(ref).max()))
        assert np.array_equal(state["support"][r], np.abs(ref) > 1e-6 * np.abs(ref).max())


# -- exact cases ----------------------------------------------------------------


@pytest.mark.parametrize("seed", range(4))
def test_oracle_is_exact_without_noise_and_known_x0(seed):
    A, B, C = plant(seed, n=6, p=4, m=3)
    xs, ys, u = simulate(A, B, C, runs=2, steps=12, seed=seed, amplitude=2.0, support_size=2)
    assert np.linalg.matrix_rank(C @ B[:, np.flatnonzero(u[0, 0])]) == 2  # C B_S full rank
    oracle = OracleSISE(
        A, B, C, Q=1e-3 * np.eye(6), R=1e-3 * np.eye(3), support=u != 0, x0_hat=np.zeros(6)
    )
    state = oracle.initial_state(2)
    state["x_hat"] = xs[0].copy()  # x(0) known
    state["P"] = np.tile(1e-3 * np.eye(6), (2, 1, 1))
    traj = oracle.run(ys, state)
    scale = np.abs(xs).max()
    assert np.abs(traj.x_hat[1:] - xs[:-1]).max() < 1e-9 * scale  # x_hat[k+1] ~ x(k)
    assert np.abs(traj.a_hat[2:] - u[:-1]).max() < 1e-9 * scale  # a_hat[k+1] ~ u(k-1)


def test_oracle_forgets_a_wrong_prior_without_noise():
    A, B, C = plant(5, n=6, p=4, m=3)
    xs, ys, u = simulate(A, B, C, runs=3, steps=80, seed=5, amplitude=2.0)
    oracle = OracleSISE(A, B, C, Q=1e-6 * np.eye(6), R=1e-6 * np.eye(3), support=u[0] != 0)
    traj = oracle.run(ys)
    first = rel(traj.x_hat[1] - xs[0], xs[0]).max()
    last = rel(traj.x_hat[-1] - xs[-2], xs[-2]).max()
    assert first > 1e-2
    assert last < 1e-6 * first
    assert np.abs(traj.a_hat[-1] - u[-2]).max() < 1e-6 * 2.0


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(4))
def test_sise_is_exact_without_noise_and_known_x0(seed):
    A, B, C = plant(20 + seed, n=10, p=8, m=5)
    xs, ys, u = simulate(A, B, C, runs=3, steps=15, seed=seed, amplitude=3.0)
    sise = SISE(A, B, C, Q=1e-3 * np.eye(10), R=1e-3 * np.eye(5), sparsity=1, lasso_weight=1e-3)
    state = sise.initial_state(3)
    state["x_hat"] = xs[0].copy()
    state["P"] = np.tile(1e-3 * np.eye(10), (3, 1, 1))
    traj = sise.run(ys, state)
    scale = np.abs(xs).max()
    assert np.abs(traj.x_hat[1:] - xs[:-1]).max() < 1e-9 * scale
    assert np.abs(traj.a_hat[2:] - u[:-1]).max() < 1e-9 * scale


def test_covariance_update_is_the_joseph_form():
    A, B, C = plant(8, n=7, p=5, m=4)
    n, m = 7, 4
    Q, R = np.diag(np.linspace(0.1, 1, n)), np.diag(np.linspace(0.2, 0.5, m))
    oracle = OracleSISE(A, B, C, Q=Q, R=R, support=[False, True, False, True, False])
    xs, ys, _ = simulate(A, B, C, runs=1, steps=3, seed=0, amplitude=1.0)
    s0 = oracle.step(oracle.initial_state(1), ys[0])
    s1 = oracle.step(s0, ys[1])
    P = s0["P"][0]
    BS = B[:, [1, 3]]
    Pt = A @ P @ A.T + Q
    Rt = C @ Pt @ C.T + R
    F = C @ BS
    M = np.linalg.solve(F.T @ np.linalg.solve(Rt, F), F.T @ np.linalg.inv(Rt))
    K = Pt @ C.T @ np.linalg.inv(Rt)
    T1 = (np.eye(n) - K @ C) @ (np.eye(n) - BS @ M @ C)
    T2 = (np.eye(n) - K @ C) @ BS @ M + K
    joseph = T1 @ Pt @ T1.T + T2 @ R @ T2.T
    assert np.abs(s1["P"][0] - joseph).max() < 1e-12 * np.abs(joseph).max()
    assert np.allclose(s1["P"][0], s1["P"][0].T, rtol=0, atol=0)


def test_empty_oracle_support_is_the_kalman_filter_ignoring_the_input():
    A, B, C = plant(9, n=6, p=4, m=3)
    Q, R = 0.01 * np.eye(6), 0.02 * np.eye(3)
    xs, ys, u = simulate(A, B, C, runs=4, steps=20, seed=9, amplitude=1.0, q_std=0.1, r_std=0.1)
    oracle = OracleSISE(A, B, C, Q=Q, R=R, support=np.zeros(4, dtype=bool))
    traj = oracle.run(ys)
    kf = kalman_ignoring_input(A, C, Q, R, ys, np.zeros(6), np.eye(6))
    assert np.allclose(traj.x_hat[1:], kf, rtol=0, atol=1e-10 * np.abs(kf).max())
    assert np.all(traj.a_hat == 0)


# -- tracking with noise --------------------------------------------------------


@pytest.mark.slow
def test_sise_beats_a_kalman_filter_that_ignores_the_input():
    n, p, m = 20, 12, 10
    Q, R = 0.01 * np.eye(n), 0.01 * np.eye(m)
    amplitude = 10 * np.sqrt(np.trace(Q))  # input-to-noise ratio 20 dB, as in the paper
    steps, transient = 60, 20
    errors = []
    for seed in range(4):
        A, B, C = plant(100 + seed, n, p, m)
        xs, ys, u = simulate(
            A, B, C, runs=4, steps=steps, seed=seed, amplitude=amplitude, q_std=0.1, r_std=0.1
        )
        traj = SISE(A, B, C, Q=Q, R=R, sparsity=1).run(ys)
        kf = kalman_ignoring_input(A, C, Q, R, ys, np.zeros(n), np.eye(n))
        oracle = OracleSISE(A, B, C, Q=Q, R=R, support=u != 0).run(ys)
        x_true = xs[:-1]
        # absolute errors: ||x|| grows on these marginally stable plants
        err = [
            np.linalg.norm(e, axis=-1)[transient:].mean()
            for e in (traj.x_hat[1:] - x_true, kf - x_true, oracle.x_hat[1:] - x_true)
        ]
        err_u = rel(traj.a_hat[2:] - u[:-1], u[:-1])[transient:].mean()
        assert err[0] < 0.6 * err[1], seed
        assert err_u < 0.5, seed  # the Kalman filter's input estimate (zero) has error 1
        errors.append(err + [err_u])
    sise, kf, oracle, err_u = np.mean(errors, axis=0)
    assert sise < 0.3 * kf
    assert err_u < 0.15
    assert sise < 2.5 * oracle


@pytest.mark.slow
def test_batched_runs_equal_single_runs():
    A, B, C = plant(12, n=10, p=8, m=5)
    Q, R = 0.01 * np.eye(10), 0.01 * np.eye(5)
    xs, ys, u = simulate(A, B, C, runs=5, steps=25, seed=12, amplitude=3.0, q_std=0.1, r_std=0.1)
    for est in (SISE(A, B, C, Q=Q, R=R), SISE(A, B, C, Q=Q, R=R, sparsity=1)):
        batch = est.run(ys)
        for r in range(5):
            alone = est.run(ys[:, r : r + 1])
            assert np.allclose(alone.x_hat[:, 0], batch.x_hat[:, r], rtol=1e-9, atol=1e-9)
            assert np.allclose(alone.a_hat[:, 0], batch.a_hat[:, r], rtol=1e-9, atol=1e-9)
    oracle = OracleSISE(A, B, C, Q=Q, R=R, support=u != 0)
    batch = oracle.run(ys)
    for r in range(5):
        alone = OracleSISE(A, B, C, Q=Q, R=R, support=u[:, r : r + 1] != 0).run(ys[:, r : r + 1])
        assert np.allclose(alone.x_hat[:, 0], batch.x_hat[:, r], rtol=1e-12, atol=1e-12)


def test_rank_deficient_support_is_flagged_not_hidden():
    A = 0.5 * np.eye(3)
    B = np.array([[1.0, 1.0], [0.0, 0.0], [0.0, 0.0]])  # two identical input columns
    C = np.eye(3)
    oracle = OracleSISE(A, B, C, Q=0.01 * np.eye(3), R=0.01 * np.eye(3), support=[True, True])
    state = oracle.step(oracle.initial_state(1), np.zeros((1, 3)))
    state = oracle.step(state, np.array([[2.0, 0.0, 0.0]]))
    assert state["rank_deficient"][0]
    assert np.all(np.isfinite(state["x_hat"])) and np.all(np.isfinite(state["u_hat"]))
    # pseudo-inverse: the minimum-norm split of the input between the twin columns
    assert state["u_hat"][0, 0] == pytest.approx(state["u_hat"][0, 1], rel=1e-9)


# -- bad inputs -----------------------------------------------------------------


GOOD = dict(A=np.eye(3), B=np.eye(3)[:, :2], C=np.ones((2, 3)), Q=np.eye(3), R=np.eye(2))


@pytest.mark.parametrize(
    "change, error, name",
    [
        (dict(A=np.ones((3, 2))), ValueError, "A"),
        (dict(B=np.ones((2, 2))), ValueError, "B"),
        (dict(C=np.ones((2, 4))), ValueError, "C"),
        (dict(C=[["a", 1.0, 2.0]]), TypeError, "C"),
        (dict(Q=np.array([[1.0, 0.5, 0], [0, 1, 0], [0, 0, 1]])), ValueError, "Q"),
        (dict(Q=-np.eye(3)), ValueError, "Q"),
        (dict(R=np.zeros((2, 2))), ValueError, "R"),
        (dict(R=np.full((2, 2), np.nan)), ValueError, "R"),
        (dict(lasso_weight=0.0), ValueError, "lasso_weight"),
        (dict(lasso_weight="1"), TypeError, "lasso_weight"),
        (dict(sparsity=0), ValueError, "sparsity"),
        (dict(sparsity=1.5), TypeError, "sparsity"),
        (dict(x0_hat=np.zeros(4)), ValueError, "x0_hat"),
        (dict(P0=np.zeros((3, 3))), ValueError, "P0"),
        (dict(support_rtol=1.0), ValueError, "support_rtol"),
    ],
)
def test_bad_sise_arguments_name_the_argument(change, error, name):
    kwargs = {**GOOD, **change}
    with pytest.raises(error, match=rf"\b{name}\b"):
        SISE(kwargs.pop("A"), kwargs.pop("B"), kwargs.pop("C"), **kwargs)


def test_bad_step_and_oracle_inputs():
    sise = SISE(**{k: GOOD[k] for k in ("A", "B", "C")}, Q=GOOD["Q"], R=GOOD["R"])
    with pytest.raises(ValueError, match=r"\by\b"):
        sise.step(sise.initial_state(2), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="runs"):
        sise.initial_state(0)
    with pytest.raises(TypeError, match="support"):
        OracleSISE(GOOD["A"], GOOD["B"], GOOD["C"], Q=GOOD["Q"], R=GOOD["R"], support=[0.5, 1])
    with pytest.raises(ValueError, match="support"):
        OracleSISE(
            GOOD["A"], GOOD["B"], GOOD["C"], Q=GOOD["Q"], R=GOOD["R"], support=[True, False, True]
        )
    oracle = OracleSISE(
        GOOD["A"],
        GOOD["B"],
        GOOD["C"],
        Q=GOOD["Q"],
        R=GOOD["R"],
        support=np.ones((1, 3, 2), dtype=bool),
    )
    with pytest.raises(ValueError, match="support"):
        oracle.run(np.zeros((4, 2, 2)))  # the support is for 3 runs, y has 2
    with pytest.raises(ValueError, match="weight"):
        lasso_fista(np.eye(2), np.ones(2), -1.0)
    with pytest.raises(ValueError, match=r"\by\b"):
        lasso_fista(np.eye(2), np.ones(3), 1.0)


def test_the_recursion_of_reference_14_recovers_a_noise_free_run_and_batches():
    """[14]'s recursion (``recursive_input_estimate``): exact without noise from the exact
    x(0) when C B suits compressed sensing; runs batched give each run's own estimates."""
    from ssecert.estimators.sise import recursive_input_estimate

    rng = np.random.default_rng(14)
    n, m, p, steps, runs = 8, 6, 8, 12, 3
    A = rng.standard_normal((n, n)) / np.sqrt(n)
    B, C = np.eye(n)[:, :p], rng.standard_normal((m, n))
    x = rng.standard_normal((runs, n))
    u = np.zeros((steps, runs, p))
    u[:, np.arange(runs), rng.integers(p, size=runs)] = 3.0
    xs, ys = [x], []
    for k in range(steps):
        ys.append(x @ C.T)
        x = x @ A.T + u[k] @ B.T
        xs.append(x)
    xs, ys = np.array(xs), np.array(ys)
    x_hat, u_hat = recursive_input_estimate(A, B, C, ys, xs[0])
    assert np.allclose(x_hat, xs[:steps], atol=1e-8)
    assert np.allclose(u_hat, u[: steps - 1], atol=1e-8)
    one_x, one_u = recursive_input_estimate(A, B, C, ys[:, 1], xs[0, 1])
    assert np.allclose(one_x, x_hat[:, 1]) and np.allclose(one_u, u_hat[:, 1])
    with pytest.raises(ValueError, match="x0"):
        recursive_input_estimate(A, B, C, ys, xs[0, :2])


def test_admm_reaches_the_minimiser_fista_reaches():
    """The SISE paper solves its Lasso by ADMM; ssecert's SISE uses FISTA: both give the same
    minimiser (batched, to the KKT conditions), so the support SISE picks is the same."""
    from ssecert.estimators.sise import lasso_admm

    rng = np.random.default_rng(4)
    Phi = rng.standard_normal((20, 40))
    U = np.zeros((6, 40))
    U[np.arange(6), rng.integers(40, size=6)] = 7.0
    Y = U @ Phi.T + 0.1 * rng.standard_normal((6, 20))
    fista_res = lasso_fista(Phi, Y, 1.0, max_iter=20000, rtol=1e-12)
    admm_res = lasso_admm(Phi, Y, 1.0, max_iter=20000, rtol=1e-12)
    assert admm_res.converged.all() and fista_res.converged.all()
    assert np.all(admm_res.kkt_residual < 1e-6)
    np.testing.assert_allclose(admm_res.solution, fista_res.solution, atol=1e-6)
    assert np.array_equal(
        np.argmax(np.abs(admm_res.solution), axis=1), np.argmax(np.abs(fista_res.solution), axis=1)
    )
    with pytest.raises(ValueError, match="rho"):
        lasso_admm(Phi, Y, 1.0, rho=0.0)
