"""The Imhotep-SMT-style decoder on cases whose answer is known, and against the l0 decoder."""

import sys

import numpy as np
import pytest

from ssecert import System, sparse_observability
from ssecert.estimators import l0_decoder, smt_decoder
from ssecert.examples import load_example

z3 = pytest.importorskip("z3")


def signed_uniform(rng, low, high, size):
    return rng.uniform(low, high, size) * rng.choice([-1.0, 1.0], size)


def random_plant(rng, n, p):
    A = rng.standard_normal((n, n))
    A /= np.abs(np.linalg.eigvals(A)).max()
    return System(A, rng.standard_normal((p, n)))


def stacked_instance(rng, system, attacked, tau):
    """y = O_tau x + a with the sensors ``attacked`` under attack at every step."""
    O = system.observability_matrix(tau)
    x = signed_uniform(rng, 2.0, 3.0, system.n)
    a = np.zeros((tau, system.p))
    a[:, list(attacked)] = signed_uniform(rng, 4.0, 5.0, (tau, len(attacked)))
    return O, O @ x + a.ravel(), x, a.ravel()


def lasso_example_1_C():
    return np.asarray(load_example("lasso-example-1").system.C)


def test_no_attack_gives_the_state():
    C = lasso_example_1_C()
    sol = smt_decoder(C, C @ [1.5], 1)
    assert sol.status == "sat" and sol.unique
    assert sol.x == pytest.approx([1.5], abs=1e-12)
    assert len(sol.support) <= 1 and sol.residual <= sol.threshold
    smallest = smt_decoder(C, C @ [1.5], 1, smallest=True)
    assert smallest.support == () and smallest.theory_calls == 1 and smallest.conflicts == ()


@pytest.mark.parametrize("attacked", [0, 1, 2])
def test_one_attacked_sensor_of_lasso_example_1_is_found(attacked):
    C = lasso_example_1_C()
    a = np.zeros(3)
    a[attacked] = 4.2
    sol = smt_decoder(C, C @ [-2.0] + a, 1)
    assert sol.status == "sat" and sol.support == (attacked,)
    assert sol.x == pytest.approx([-2.0], abs=1e-12)
    assert sol.a == pytest.approx(a, abs=1e-12)
    # every learnt clause names the attacked sensor: none excludes the truth
    assert all(attacked in clause for clause in sol.conflicts)


def test_more_attacked_sensors_than_s_is_unsat():
    C = lasso_example_1_C()
    sol = smt_decoder(C, C @ [1.0] + np.array([0.0, 4.0, -3.0]), 1)
    assert sol.status == "unsat" and sol.support is None
    assert np.isnan(sol.x).all() and np.isnan(sol.a).all()
    # two sensors attacked alike outvote the clean one: a consistent, wrong explanation
    wrong = smt_decoder(C, C @ [1.0] + np.array([0.0, 4.0, 4.0]), 1)
    assert wrong.status == "sat" and wrong.support == (0,)
    assert wrong.x == pytest.approx([3.0], abs=1e-12)
    assert l0_decoder(C, C @ [1.0] + np.array([0.0, 4.0, 4.0]), 1).support == (0,)


@pytest.mark.parametrize("seed", range(4))
def test_agrees_with_the_l0_decoder_on_stacked_plants(seed):
    rng = np.random.default_rng(seed)
    n, p, s, tau = 3, 7, 2, 3
    system = random_plant(rng, n, p)
    assert sparse_observability(system, s).verdict.value == "holds"
    attacked = tuple(sorted(int(i) for i in rng.choice(p, s, replace=False)))
    O, y, x, a = stacked_instance(rng, system, attacked, tau)
    rows = np.tile(np.arange(p), tau)
    sol = smt_decoder(O, y, s, sensors_of_row=rows)
    exact = l0_decoder(O, y, s, sensors_of_row=rows)
    assert sol.status == "sat" and exact.consistent
    assert sol.support == exact.support == attacked
    assert sol.x == pytest.approx(exact.x, abs=1e-9)
    assert sol.x == pytest.approx(x, abs=1e-9)
    assert sol.a == pytest.approx(a, abs=1e-9)
    assert all(set(clause) & set(attacked) for clause in sol.conflicts)


@pytest.mark.parametrize("seed", range(4))
def test_smallest_support_is_the_l0_decoders_on_static_data(seed):
    # fewer attacked rows than s: any superset also explains y; smallest=True finds the l0 answer
    rng = np.random.default_rng(10 + seed)
    m, n, s = 12, 3, 3
    M = rng.standard_normal((m, n))
    attacked = tuple(sorted(int(i) for i in rng.choice(m, 2, replace=False)))
    x = signed_uniform(rng, 2.0, 3.0, n)
    a = np.zeros(m)
    a[list(attacked)] = signed_uniform(rng, 4.0, 5.0, 2)
    sol = smt_decoder(M, M @ x + a, s, smallest=True)
    exact = l0_decoder(M, M @ x + a, s)
    assert sol.support == exact.support == attacked
    assert sol.x == pytest.approx(exact.x, abs=1e-9)
    anyone = smt_decoder(M, M @ x + a, s)
    assert anyone.status == "sat" and set(attacked) <= set(anyone.support)
    assert anyone.x == pytest.approx(x, abs=1e-9)


def test_noise_beyond_the_tolerance_makes_it_fail_and_a_bound_restores_it():
    # the Lasso paper's Figs. 1-2: Imhotep-SMT is fragile under noise bounded by 1e-4
    rng = np.random.default_rng(20)
    n, p, s, tau = 3, 7, 2, 3
    system = random_plant(rng, n, p)
    O, y, x, _ = stacked_instance(rng, system, (1, 4), tau)
    noisy = y + rng.uniform(-1e-4, 1e-4, y.size)
    rows = np.tile(np.arange(p), tau)
    fragile = smt_decoder(O, noisy, s, sensors_of_row=rows)
    assert fragile.status == "unsat" and fragile.support is None
    # a per-sensor bound on the noise norm over the window (1e-4 sqrt(tau)) lets the truth pass
    bounded = smt_decoder(O, noisy, s, sensors_of_row=rows, noise_bound=1e-4 * np.sqrt(tau))
    assert bounded.status == "sat" and bounded.support == (1, 4)
    assert np.linalg.norm(bounded.x - x) <= 1e-3 * np.linalg.norm(x)
    # a larger tolerance does the same
    loose = smt_decoder(O, noisy, s, sensors_of_row=rows, atol=1e-2)
    assert loose.support == (1, 4)


def test_the_budget_stops_the_search():
    rng = np.random.default_rng(30)
    M = rng.standard_normal((10, 2))
    a = np.zeros(10)
    a[[2, 7]] = 5.0
    full = smt_decoder(M, M @ [1.0, -1.0] + a, 2)
    assert full.status == "sat" and full.support == (2, 7) and full.theory_calls > 1
    # each call has a z3 context of its own: the same proposals every time
    assert smt_decoder(M, M @ [1.0, -1.0] + a, 2).conflicts == full.conflicts
    sol = smt_decoder(M, M @ [1.0, -1.0] + a, 2, max_theory_calls=full.theory_calls - 1)
    assert sol.status == "budget" and sol.support is None
    assert sol.theory_calls == full.theory_calls - 1
    assert sol.conflicts == full.conflicts[: sol.theory_calls]


def test_a_missing_z3_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "z3", None)
    with pytest.raises(ImportError, match=r"ssecert\[smt\]"):
        smt_decoder(np.ones((3, 1)), np.ones(3), 1)


def test_refuses_bad_arguments():
    M, y = np.ones((3, 1)), np.ones(3)
    with pytest.raises(ValueError, match="s must be <= 2"):
        smt_decoder(M, y, 3)
    with pytest.raises(TypeError, match="s must be an integer"):
        smt_decoder(M, y, "1")
    with pytest.raises(ValueError, match="y"):
        smt_decoder(M, np.ones(2), 1)
    with pytest.raises(ValueError, match="noise_bound must be >= 0"):
        smt_decoder(M, y, 1, noise_bound=-1.0)
    with pytest.raises(ValueError, match="noise_bound"):
        smt_decoder(M, y, 1, noise_bound=[0.1, 0.1])
    with pytest.raises(ValueError, match="noise_bound must be >= 0"):
        smt_decoder(M, y, 1, noise_bound=[0.1, -0.1, 0.1])
    with pytest.raises(TypeError, match="noise_bound"):
        smt_decoder(M, y, 1, noise_bound="small")
    with pytest.raises(ValueError, match="atol"):
        smt_decoder(M, y, 1, atol=-1e-5)
    with pytest.raises(ValueError, match="max_theory_calls"):
        smt_decoder(M, y, 1, max_theory_calls=0)
    with pytest.raises(TypeError, match="smallest"):
        smt_decoder(M, y, 1, smallest=1)
    with pytest.raises(ValueError, match="sensors_of_row"):
        smt_decoder(M, y, 1, sensors_of_row=[0, 0, 2])
