"""One run of the sparse soft observers: the loop without per-step allocation.

``SparseSoftObserver.run`` on one run and ``WindowSSO.run`` on any number of
runs must give the numbers of the loops they replace bit for bit (the batched
loop on one run; repeated ``step`` calls), and a run on its own must agree with
the same run inside a batch (there BLAS multiplies matrices, not one row, so
to rounding).  Times are compared only as ratios measured side by side.
"""

import time

import numpy as np
import pytest

from ssecert.observers import SparseSoftObserver, WindowSSO
from ssecert.observers.dynamic import DynamicObserver


def _bits(a, b):
    """Whether two arrays hold the same float64 numbers bit for bit (signed zeros included)."""
    return a.shape == b.shape and a.tobytes() == b.tobytes()


def _plant(seed, n, p):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A /= np.abs(np.linalg.eigvals(A)).max()
    C = rng.standard_normal((p, n))
    step = 0.9 / np.linalg.norm(np.hstack([C, np.eye(p)]), 2) ** 2
    return rng, A, C, step


def _measurements(rng, C, A, steps, runs):
    """y = C x + a with a constant sparse attack and a little noise, shape (steps, runs, p)."""
    p, n = C.shape
    x = rng.uniform(2, 3, (runs, n)) * rng.choice([-1, 1], (runs, n))
    attack = np.zeros((runs, p))
    attack[:, : max(1, p // 5)] = rng.uniform(4, 5, (runs, max(1, p // 5)))
    y = np.empty((steps, runs, p))
    for k in range(steps):
        y[k] = x @ C.T + attack + 0.01 * rng.standard_normal((runs, p))
        x = x @ A.T
    return y


def _sso(seed, n=10, p=15, shrink=1.0, weighted=False):
    rng, A, C, step = _plant(seed, n, p)
    L2 = np.diag(rng.uniform(0.5, 1.5, p)) if weighted else None
    obs = SparseSoftObserver(
        A, C, step * A @ C.T, step=step, threshold=0.05 * step, shrink=shrink, L2=L2
    )
    return rng, obs


@pytest.mark.parametrize(
    ("seed", "shrink", "weighted"), [(0, 1.0, False), (1, 0.9, False), (2, 1.0, True)]
)
def test_one_sso_run_equals_the_batched_loop_bit_for_bit(seed, shrink, weighted):
    rng, obs = _sso(seed, shrink=shrink, weighted=weighted)
    y = _measurements(rng, obs.C, obs.A, 300, 1)
    state = {"x_hat": rng.standard_normal((1, obs.n)), "a_hat": rng.standard_normal((1, obs.m))}
    for st in (None, state):
        fast = obs.run(y, st)
        z0 = np.zeros((1, obs.n + obs.m)) if st is None else np.hstack([st["x_hat"], st["a_hat"]])
        slow = obs._run_batched(z0, y)
        assert _bits(fast.x_hat, slow.x_hat) and _bits(fast.a_hat, slow.a_hat)
        assert fast.delay == slow.delay == 0


@pytest.mark.parametrize("seed", range(3))
def test_one_sso_run_equals_its_run_in_a_batch(seed):
    rng, obs = _sso(seed, shrink=0.95)
    y = _measurements(rng, obs.C, obs.A, 200, 6)
    batched = obs.run(y)
    assert batched.x_hat.shape == (201, 6, obs.n) and batched.a_hat.shape == (201, 6, obs.m)
    for r in range(6):
        single = obs.run(y[:, r : r + 1])
        np.testing.assert_allclose(
            single.x_hat, batched.x_hat[:, r : r + 1], rtol=1e-12, atol=1e-12
        )
        np.testing.assert_allclose(
            single.a_hat, batched.a_hat[:, r : r + 1], rtol=1e-12, atol=1e-12
        )
        # the same support, step by step
        np.testing.assert_array_equal(single.a_hat != 0, batched.a_hat[:, r : r + 1] != 0)


def test_one_sso_run_of_no_steps_is_its_initial_state():
    _, obs = _sso(0)
    traj = obs.run(np.empty((0, 1, obs.m)))
    assert traj.x_hat.shape == (1, 1, obs.n) and not traj.x_hat.any() and not traj.a_hat.any()


@pytest.mark.parametrize(
    ("window", "inner", "runs"),
    [(1, 1, 1), (1, 5, 1), (1, 2, 7), (3, 1, 1), (3, 2, 1), (3, 3, 5), (4, 2, 1)],
)
def test_window_sso_run_equals_repeated_steps_bit_for_bit(window, inner, runs):
    rng, A, C, _ = _plant(window * 10 + inner, 5, 6)
    O = np.vstack([C @ np.linalg.matrix_power(A, i) for i in range(window)])
    step = 0.9 / np.linalg.norm(np.hstack([O, np.eye(O.shape[0])]), 2) ** 2
    obs = WindowSSO(A, C, step=step, threshold=0.05 * step, window=window, inner_steps=inner)
    y = _measurements(rng, C, A, 40, runs)
    partly_filled = {
        "x_hat": rng.standard_normal((runs, 5)),
        "a_hat": rng.standard_normal((runs, O.shape[0])),
        "buffer": rng.standard_normal((runs, window, 6)),
        "filled": np.asarray(window // 2),
    }
    for state in (None, partly_filled):
        fast = obs.run(y, state)
        slow = DynamicObserver.run(obs, y, state)  # the loop over ``step``
        assert _bits(fast.x_hat, slow.x_hat) and _bits(fast.a_hat, slow.a_hat)
        assert fast.delay == slow.delay == window - 1
    # fewer samples than the window: the estimates wait
    short = obs.run(y[: window - 1])
    assert short.x_hat.shape == (window, runs, 5) and not short.x_hat.any()


def test_window_sso_one_run_equals_its_run_in_a_batch():
    rng, A, C, step = _plant(4, 10, 15)
    obs = WindowSSO(A, C, step=step, threshold=0.1 * step, inner_steps=2)
    y = _measurements(rng, C, A, 150, 4)
    batched = obs.run(y)
    for r in range(4):
        single = obs.run(y[:, r : r + 1])
        np.testing.assert_allclose(
            single.x_hat, batched.x_hat[:, r : r + 1], rtol=1e-12, atol=1e-12
        )
        np.testing.assert_allclose(
            single.a_hat, batched.a_hat[:, r : r + 1], rtol=1e-12, atol=1e-12
        )


def test_window_sso_run_refuses_a_negative_threshold_as_step_does():
    _, A, C, _ = _plant(0, 3, 4)
    obs = WindowSSO(A, C, step=0.1, threshold=-0.1)
    y = np.ones((3, 1, 4))
    with pytest.raises(ValueError, match="threshold"):
        obs.step(obs.initial_state(1), y[0])
    with pytest.raises(ValueError, match="threshold"):
        obs.run(y)


def _best_ratio(slow, fast, repeat=7):
    """(best time of slow) / (best time of fast), the two taking turns."""
    best = [float("inf"), float("inf")]
    for _ in range(repeat):
        for i, call in enumerate((slow, fast)):
            start = time.perf_counter()
            call()
            best[i] = min(best[i], time.perf_counter() - start)
    return best[0] / best[1]


def test_one_run_loops_are_faster_than_the_loops_they_replace():
    """Ratios only, measured side by side (about 1.6-2.4x and 5x on a 2-core machine)."""
    rng, obs = _sso(5)
    y = _measurements(rng, obs.C, obs.A, 2000, 1)
    z0 = np.zeros((1, obs.n + obs.m))
    # best of 15 each, taking turns: a busy machine slows both alike
    assert _best_ratio(lambda: obs._run_batched(z0, y), lambda: obs.run(y), repeat=15) > 1.1
    window = WindowSSO(obs.A, obs.C, step=obs.step_size, threshold=obs.threshold)
    assert _best_ratio(lambda: DynamicObserver.run(window, y), lambda: window.run(y)) > 2.0
