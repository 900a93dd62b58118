"""ETPG and ETPL (Shoukry and Tabuada, 2016) on cases whose answer is known."""

import numpy as np
import pytest

from ssecert import System, sparse_observability
from ssecert.estimators import ETPLObserver, etpg, etpg_condition, l0_decoder
from ssecert.examples import load_example


def signed_uniform(rng, low, high, size):
    return rng.uniform(low, high, size) * rng.choice([-1.0, 1.0], size)


def random_plant(rng, n, p):
    A = rng.standard_normal((n, n))
    A /= np.abs(np.linalg.eigvals(A)).max()  # spectral radius 1, as in the Lasso paper
    return A, rng.standard_normal((p, n))


def stacked_batch(rng, A, C, s, tau, runs):
    """y = O_tau x + a for ``runs`` states, each with its own s attacked sensors."""
    p = C.shape[0]
    O = System(A, C).observability_matrix(tau)
    X = signed_uniform(rng, 2.0, 3.0, (runs, A.shape[0]))
    attacks = np.zeros((runs, tau, p))
    supports = []
    for r in range(runs):
        sensors = np.sort(rng.choice(p, s, replace=False))
        attacks[r][:, sensors] = signed_uniform(rng, 4.0, 5.0, (tau, s))
        supports.append(tuple(int(i) for i in sensors))
    return O, X @ O.T + attacks.reshape(runs, -1), X, supports


def trajectories(rng, A, C, s, steps, runs):
    """States (steps + 1, runs, n) and measurements (steps, runs, p) under constant attacks."""
    n, p = A.shape[0], C.shape[0]
    x = signed_uniform(rng, 2.0, 3.0, (runs, n))
    attack = np.zeros((runs, p))
    for r in range(runs):
        sensors = rng.choice(p, s, replace=False)
        attack[r, sensors] = signed_uniform(rng, 4.0, 5.0, s)
    xs, ys = [x], []
    for _ in range(steps):
        ys.append(x @ C.T + attack)
        x = x @ A.T
        xs.append(x)
    return np.array(xs), np.array(ys), attack


def lasso_example_1():
    system = load_example("lasso-example-1").system
    return np.asarray(system.A), np.asarray(system.C)


# ---------------------------------------------------------------------------
# condition 2 of Theorem 4.4


@pytest.mark.parametrize("alpha", [0.1, 1.0, 2.0, 7.5])
def test_restricted_eigenvalue_is_the_lasso_papers_example_1(alpha):
    # Lasso paper, Example 1: lambda_max = 3 alpha^2 + 1 and, over pairs of sensors,
    # delta_2 = (3 alpha^2 + 1 - sqrt(9 alpha^4 + 2 alpha^2 + 1)) / 2 < (4/9) lambda_max
    cond = etpg_condition(alpha * np.ones((3, 1)), 1)
    q = 3 * alpha**2 + 1
    r = (q - np.sqrt(9 * alpha**4 + 2 * alpha**2 + 1)) / 2
    assert cond.lambda_max == pytest.approx(q, rel=1e-12)
    assert cond.delta == pytest.approx(r, rel=1e-9)
    assert cond.size == 2 and cond.sets == 3 and len(cond.worst_sensors) == 2
    assert not cond.holds and cond.nu_bound <= 0


def test_restricted_eigenvalue_is_the_least_over_every_set():
    rng = np.random.default_rng(3)
    M = rng.standard_normal((8, 2))
    sensors = np.repeat(np.arange(4), 2)  # two rows per sensor
    cond = etpg_condition(M, 1, sensors_of_row=sensors)
    least = np.inf
    for i in range(4):
        for j in range(i + 1, 4):
            rows = np.flatnonzero((sensors == i) | (sensors == j))
            Q = np.hstack([M, np.eye(8)[:, rows]])
            least = min(least, np.linalg.eigvalsh(Q.T @ Q)[0])
    assert cond.delta == pytest.approx(least, rel=1e-9, abs=1e-12)
    rows = np.flatnonzero(np.isin(sensors, cond.worst_sensors))
    Q = np.hstack([M, np.eye(8)[:, rows]])
    assert np.linalg.eigvalsh(Q.T @ Q)[0] == pytest.approx(cond.delta, rel=1e-9, abs=1e-12)
    assert cond.lambda_max == pytest.approx(np.linalg.norm(np.hstack([M, np.eye(8)]), 2) ** 2)


# ---------------------------------------------------------------------------
# ETPG


def test_etpg_recovers_the_attacked_sensor_of_lasso_example_1():
    # the Lasso paper's point: condition 2 fails here, yet the estimate is right
    _, C = lasso_example_1()
    x = np.array([2.5])
    for attacked in range(3):
        a = np.zeros(3)
        a[attacked] = -4.5
        sol = etpg(C, C @ x + a, 1)
        assert sol.converged and not sol.stalled
        assert sol.x == pytest.approx(x, abs=1e-8)
        assert sol.a == pytest.approx(a, abs=1e-8)
        assert np.flatnonzero(sol.support).tolist() == [attacked]
        assert sol.residual <= sol.tol * np.linalg.norm(C @ x + a)
    assert not etpg_condition(C, 1).holds


def test_etpg_without_attack_recovers_the_state():
    rng = np.random.default_rng(0)
    A, C = random_plant(rng, 3, 6)
    O, y, X, _ = stacked_batch(rng, A, C, 0, 3, 4)
    sol = etpg(O, y, 1, sensors_of_row=np.tile(np.arange(6), 3))
    assert sol.converged.all()
    assert np.abs(sol.x - X).max() <= 1e-7 * np.abs(X).max()
    # s = 0: plain gradient descent to least squares
    exact = etpg(O, y, 0, sensors_of_row=np.tile(np.arange(6), 3))
    assert exact.converged.all() and not exact.support.any()
    assert np.abs(exact.a).max() == 0.0
    assert np.abs(exact.x - X).max() <= 1e-7 * np.abs(X).max()


def test_etpg_batch_equals_one_run_at_a_time():
    rng = np.random.default_rng(1)
    A, C = random_plant(rng, 3, 6)
    O, y, _, _ = stacked_batch(rng, A, C, 1, 3, 3)
    rows = np.tile(np.arange(6), 3)
    batch = etpg(O, y, 1, sensors_of_row=rows)
    for r in range(3):
        one = etpg(O, y[r], 1, sensors_of_row=rows)
        np.testing.assert_allclose(batch.x[r], one.x, rtol=1e-12, atol=1e-13)
        np.testing.assert_allclose(batch.a[r], one.a, rtol=1e-12, atol=1e-13)
        assert one.iterations == batch.iterations[r]
        assert one.gradient_steps == batch.gradient_steps[r]
        assert np.array_equal(one.support, batch.support[r])


@pytest.mark.slow
def test_etpg_agrees_with_the_l0_decoder_on_2s_sparse_observable_plants():
    rng = np.random.default_rng(2)
    n, p, s, tau = 4, 8, 1, 4
    A, C = random_plant(rng, n, p)
    assert sparse_observability(System(A, C), s).verdict.value == "holds"
    O, y, X, supports = stacked_batch(rng, A, C, s, tau, 4)
    rows = np.tile(np.arange(p), tau)
    sol = etpg(O, y, s, sensors_of_row=rows)
    assert sol.converged.all()
    for r in range(4):
        exact = l0_decoder(O, y[r], s, sensors_of_row=rows)
        assert tuple(np.flatnonzero(sol.support[r])) == exact.support == supports[r]
        assert sol.x[r] == pytest.approx(exact.x, abs=1e-7)
        assert sol.x[r] == pytest.approx(X[r], abs=1e-7)


@pytest.mark.slow
def test_etpg_converges_where_theorem_4_4_applies():
    # 200 equal sensors of a scalar state, ||M||^2 = 1: delta_2 > (4/9) lambda_max holds
    q = 200
    M = np.full((q, 1), 1.0 / np.sqrt(q))
    cond = etpg_condition(M, 1)
    assert cond.holds and 0 < cond.nu_bound < 0.05
    a = np.zeros(q)
    a[17] = 40.0
    sol = etpg(M, M @ [3.0] + a, 1, nu=0.5 * cond.nu_bound, tol=1e-8)
    assert sol.converged and not sol.stalled
    assert sol.x == pytest.approx([3.0], abs=1e-6)
    assert np.flatnonzero(sol.support).tolist() == [17]


def test_etpg_with_more_attacked_sensors_than_s_stalls():
    # two sensors of three attacked by different amounts: no 1-sparse attack explains y
    _, C = lasso_example_1()
    y = C @ [1.0] + np.array([0.0, 4.0, -3.0])
    sol = etpg(C, y, 1, max_inner=200)
    assert sol.stalled and not sol.converged
    assert sol.residual > 1.0


def test_etpg_is_robust_to_small_noise():
    # the Lasso paper (Sec. 5.1): ETPG degrades only slightly under noise bounded by 1e-4
    rng = np.random.default_rng(4)
    A, C = random_plant(rng, 3, 6)
    O, y, X, supports = stacked_batch(rng, A, C, 1, 3, 1)
    noisy = y[0] + rng.uniform(-1e-4, 1e-4, y.shape[1])
    sol = etpg(O, noisy, 1, sensors_of_row=np.tile(np.arange(6), 3), max_inner=300)
    assert not sol.converged  # the noise leaves no exact fit
    assert tuple(np.flatnonzero(sol.support)) == supports[0]
    assert np.linalg.norm(sol.x - X[0]) <= 1e-2 * np.linalg.norm(X[0])


def test_etpg_refuses_bad_arguments():
    M, y = np.ones((3, 1)), np.ones(3)
    lam = np.linalg.norm(M, 2) ** 2 + 1
    with pytest.raises(ValueError, match="step must be < 1 / lambda_max"):
        etpg(M, y, 1, step=1.0 / lam)
    with pytest.raises(ValueError, match="step"):
        etpg(M, y, 1, step=-0.1)
    with pytest.raises(ValueError, match="nu"):
        etpg(M, y, 1, nu=1.0)
    with pytest.raises(ValueError, match="s must be <= 2"):
        etpg(M, y, 3)
    with pytest.raises(TypeError, match="s must be an integer"):
        etpg(M, y, 1.5)
    with pytest.raises(ValueError, match="y"):
        etpg(M, np.ones(4), 1)
    with pytest.raises(ValueError, match="sensors_of_row"):
        etpg(M, y, 1, sensors_of_row=[0, 1])
    with pytest.raises(ValueError, match="max_inner"):
        etpg(M, y, 1, max_inner=0)
    with pytest.raises(ValueError, match="tol"):
        etpg(M, y, 1, tol=-1.0)
    with pytest.raises(TypeError, match="M"):
        etpg([["a"], ["b"], ["c"]], y, 1)
    with pytest.raises(ValueError, match="max_sets"):
        etpg_condition(np.ones((30, 1)), 3, max_sets=10)


# ---------------------------------------------------------------------------
# ETPL


def test_etpl_finds_the_attack_on_lasso_example_1():
    A, C = lasso_example_1()
    attack = np.array([0.0, 0.0, -4.0])
    y = np.tile(C @ [2.0] + attack, (300, 1, 1))
    for window in (1, 2):
        traj = ETPLObserver(A, C, 1, window=window).run(y)
        assert traj.delay == window - 1
        assert traj.x_hat[-1, 0] == pytest.approx([2.0], abs=1e-7)
        assert traj.a_hat[-1, 0] == pytest.approx(np.tile(attack, window), abs=1e-7)


def test_etpl_without_attack_converges_to_the_delayed_state():
    rng = np.random.default_rng(5)
    A, C = random_plant(rng, 3, 5)
    X, Y, _ = trajectories(rng, A, C, 0, 250, 3)
    obs = ETPLObserver(A, C, 1)  # window n = 3, estimates x(k - 2)
    traj = obs.run(Y)
    d = obs.delay
    assert d == 2
    error = np.linalg.norm(traj.x_hat[-1] - X[-1 - d], axis=1) / np.linalg.norm(X[-1 - d], axis=1)
    assert error.max() <= 1e-8
    # the estimates wait for a full window
    assert not traj.x_hat[: obs.window].any()


def test_etpl_batch_equals_one_run_at_a_time():
    rng = np.random.default_rng(6)
    A, C = random_plant(rng, 3, 6)
    _, Y, _ = trajectories(rng, A, C, 1, 40, 3)
    obs = ETPLObserver(A, C, 1)
    batch = obs.run(Y)
    for r in range(3):
        one = obs.run(Y[:, r : r + 1])
        np.testing.assert_allclose(batch.x_hat[:, r], one.x_hat[:, 0], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(batch.a_hat[:, r], one.a_hat[:, 0], rtol=1e-12, atol=1e-12)


@pytest.mark.slow
def test_etpl_converges_under_attack_on_2s_sparse_observable_plants():
    # the Lasso paper's Fig. 3 setting: n = 10, p = 15, s = 3, tau = n
    rng = np.random.default_rng(7)
    A, C = random_plant(rng, 10, 15)
    assert sparse_observability(System(A, C), 3).verdict.value == "holds"
    X, Y, attack = trajectories(rng, A, C, 3, 150, 3)
    obs = ETPLObserver(A, C, 3)
    traj = obs.run(Y)
    d = obs.delay
    error = np.linalg.norm(traj.x_hat[-1] - X[-1 - d], axis=1) / np.linalg.norm(X[-1 - d], axis=1)
    assert error.max() <= 1e-6
    last = traj.a_hat[-1].reshape(3, obs.window, 15)[:, -1]  # the newest sample's attack
    assert last == pytest.approx(attack, abs=1e-5)


@pytest.mark.slow
def test_etpl_converges_where_theorem_5_2_applies():
    q = 200
    C = np.full((q, 1), 1.0 / np.sqrt(q))
    cond = etpg_condition(C, 1)  # window 1: Q = [C I]
    assert cond.holds
    attack = np.zeros(q)
    attack[5] = 30.0
    y = np.tile(C @ [-2.0] + attack, (400, 1, 1))
    traj = ETPLObserver([[1.0]], C, 1, window=1, nu=0.5 * cond.nu_bound).run(y)
    assert traj.x_hat[-1, 0] == pytest.approx([-2.0], abs=1e-6)
    assert np.argmax(np.abs(traj.a_hat[-1, 0])) == 5


def test_etpl_refuses_bad_arguments():
    A, C = lasso_example_1()
    with pytest.raises(ValueError, match="A must be square"):
        ETPLObserver(np.ones((2, 3)), C, 1)
    with pytest.raises(ValueError, match="C"):
        ETPLObserver(A, np.ones((3, 2)), 1)
    with pytest.raises(ValueError, match="s must be <= 2"):
        ETPLObserver(A, C, 3)
    with pytest.raises(ValueError, match="window"):
        ETPLObserver(A, C, 1, window=0)
    with pytest.raises(ValueError, match="step must be < 1 / lambda_max"):
        ETPLObserver(A, C, 1, step=1.0)
    with pytest.raises(ValueError, match="nu"):
        ETPLObserver(A, C, 1, nu=0.0)
    with pytest.raises(ValueError, match="max_outer"):
        ETPLObserver(A, C, 1, max_outer=0)
    obs = ETPLObserver(A, C, 1)
    with pytest.raises(ValueError, match="y must have shape"):
        obs.step(obs.initial_state(1), np.ones((1, 2)))
