"""The l1 decoder's certified worst-case error under bounded noise (``l1_error_bound``): the
null-space constant against its primal programs, decoders that never exceed the bound, and
the ways a bound is not certified."""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
import pytest

from ssecert import System
from ssecert.analyze import analyze
from ssecert.examples import load_example
from ssecert.noise import MeasurementNoise
from ssecert.results import Verdict
from ssecert.structure.l1_bound import L1BoundCode, l1_bound_rechecks, l1_error_bound
from ssecert.structure.noise_messages import l1_reason

THREE = System(np.eye(1), np.ones((3, 1)))


def test_three_sensors_of_one_state():
    # the attacked sensor against the two others: theta = 1/2, ||w_K||_1 <= 2 eta, and
    # O_K^+ = (1/2, 1/2): the bound 2 (2 eta) (1/2) / (1/2), where 1 / sigma_min(O_K) would
    # give sqrt(2) times that
    eta = 0.1
    found = l1_error_bound(THREE, 1, MeasurementNoise.uniform(eta, 3), horizon=1)
    assert found.code is L1BoundCode.CERTIFIED and l1_bound_rechecks(found)
    assert found.theta >= 0.5 and found.theta == pytest.approx(0.5, rel=1e-9)
    assert found.bound == pytest.approx(4 * eta, rel=1e-9) and found.bound >= 4 * eta
    assert found.reach == pytest.approx(0.5, rel=1e-9) and found.reach * found.sigma <= 1
    assert found.programs == 3  # three sets, one sign pattern each
    none = l1_error_bound(THREE, 1, MeasurementNoise.uniform(0.0, 3), horizon=1)
    assert none.code is L1BoundCode.CERTIFIED and none.bound == 0.0  # exact recovery


def _primal_theta(O_K, O_S):
    """max over sign patterns of max sigma' O_S e subject to ||O_K e||_1 <= 1 (HiGHS)."""
    from scipy.optimize import linprog

    k, n = O_K.shape
    best = 0.0
    for signs in itertools.product((1.0, -1.0), repeat=O_S.shape[0]):
        # variables (e, u): max sigma' O_S e, -u <= O_K e <= u, sum u <= 1
        cost = np.concatenate([-(np.array(signs) @ O_S), np.zeros(k)])
        A_ub = np.block(
            [[O_K, -np.eye(k)], [-O_K, -np.eye(k)], [np.zeros((1, n)), np.ones((1, k))]]
        )
        b_ub = np.concatenate([np.zeros(2 * k), [1.0]])
        result = linprog(cost, A_ub=A_ub, b_ub=b_ub, bounds=[(None, None)] * (n + k))
        best = max(best, -result.fun)
    return best


def test_the_null_space_constant_bounds_its_primal_programs():
    rng = np.random.default_rng(4)
    compared = 0
    for _ in range(15):
        n, p, tau = int(rng.integers(1, 4)), int(rng.integers(3, 7)), int(rng.integers(1, 3))
        s = int(rng.integers(1, (p - 1) // 2 + 1))
        plant = System(rng.standard_normal((n, n)) * 0.6, rng.standard_normal((p, n)))
        found = l1_error_bound(plant, s, MeasurementNoise.uniform(1e-3, p), horizon=tau)
        if found.code not in (L1BoundCode.CERTIFIED, L1BoundCode.NOT_NULL_SPACE):
            continue
        O = plant.observability_matrix(tau)

        def primal(S, O=O, p=p, tau=tau):
            return _primal_theta(
                O[[t * p + i for t in range(tau) for i in range(p) if i not in S]],
                O[[t * p + i for t in range(tau) for i in S]],
            )

        if found.code is L1BoundCode.CERTIFIED:  # the largest over every set
            theta = max(primal(S) for S in itertools.combinations(range(p), s))
        else:  # the first set refused: the others are not examined
            theta = primal(found.theta_support)
            assert found.theta >= 1
        assert found.theta >= theta * (1 - 1e-9) and found.theta == pytest.approx(theta, rel=1e-6)
        compared += 1
    assert compared >= 5


def _never_exceeded(seed, plants, runs):
    from ssecert.estimators.support_decoders import l1_decoder

    rng = np.random.default_rng(seed)
    certified = 0
    for _ in range(plants):
        n, p, tau = int(rng.integers(1, 4)), int(rng.integers(3, 9)), int(rng.integers(1, 3))
        s = int(rng.integers(0, (p - 1) // 2 + 1))
        plant = System(rng.standard_normal((n, n)) * 0.6, rng.standard_normal((p, n)))
        noise = MeasurementNoise(rng.uniform(0, 0.1, p), "inf" if rng.random() < 0.6 else "2")
        found = l1_error_bound(plant, s, noise, horizon=tau)
        if found.code is not L1BoundCode.CERTIFIED:
            continue
        certified += 1
        O = plant.observability_matrix(tau)
        for _ in range(runs):
            x = rng.standard_normal(n)
            attack = np.zeros((tau, p))
            support = rng.choice(p, size=s, replace=False)
            attack[:, support] = rng.standard_normal((tau, s)) * rng.choice([0.01, 1.0, 100.0])
            if noise.per_sample:
                w = rng.choice([-1.0, 1.0], (tau, p)) * noise.eta
            else:
                w = rng.standard_normal((tau, p))
                w *= noise.eta / np.linalg.norm(w, axis=0)
            x_hat = l1_decoder(O, O @ x + attack.reshape(-1) + w.reshape(-1), tol=1e-10)
            assert np.linalg.norm(x_hat - x) <= found.bound * (1 + 1e-7) + 1e-9
    return certified


def test_the_l1_decoder_never_exceeds_the_bound():
    assert _never_exceeded(seed=0, plants=12, runs=4) >= 4


@pytest.mark.slow
def test_the_l1_decoder_never_exceeds_the_bound_on_many_plants():
    assert _never_exceeded(seed=1, plants=80, runs=15) >= 30


def test_the_codes_of_the_ways_a_bound_is_not_certified():
    eta = MeasurementNoise.uniform(0.01, 3)
    # an attack on the sensor that reads ten times louder outweighs the two others
    loud = System(np.eye(1), np.array([[1.0], [1.0], [10.0]]))
    found = l1_error_bound(loud, 1, eta, horizon=1)
    assert found.code is L1BoundCode.NOT_NULL_SPACE and found.theta_support == (2,)
    assert found.theta == pytest.approx(5.0, rel=1e-9)
    assert l1_error_bound(THREE, 3, eta, horizon=1).code is L1BoundCode.TOO_FEW_SENSORS
    many = l1_error_bound(THREE, 1, eta, horizon=1, max_programs=2)
    assert many.code is L1BoundCode.TOO_MANY_PROGRAMS and many.programs == 3
    blind = System(np.eye(2), np.array([[1.0, 0.0], [2.0, 0.0], [0.0, 1.0]]))
    found = l1_error_bound(blind, 1, eta, horizon=1)
    assert found.code is L1BoundCode.WINDOW_TOO_SHORT and found.worst_support == (2,)
    close = System(np.eye(2), np.array([[1.0, 0.0], [1.0, 2.0**-60], [0.0, 1.0]]))
    found = l1_error_bound(close, 1, eta, horizon=1)
    assert found.code is L1BoundCode.NO_MARGIN and found.worst_support == (2,)


def test_the_recheck_and_the_words():
    found = l1_error_bound(THREE, 1, MeasurementNoise.uniform(0.01, 3), horizon=1)
    assert l1_bound_rechecks(found) and l1_reason(found, THREE) == ""
    assert not l1_bound_rechecks(replace(found, bound=found.bound * 0.99))
    assert not l1_bound_rechecks(replace(found, reach=found.reach * 2))
    loud = System(np.eye(1), np.array([[1.0], [1.0], [10.0]]))
    refused = l1_error_bound(loud, 1, MeasurementNoise.uniform(0.01, 3), horizon=1)
    assert l1_reason(refused, loud).startswith(
        "the null-space constant reaches 5 >= 1 on sensors y3: an attack there may move the l1 "
        "decoder's estimate even without noise"
    )
    many = l1_error_bound(THREE, 1, MeasurementNoise.uniform(0.01, 3), horizon=1, max_programs=2)
    assert l1_reason(many, THREE) == (
        "3 linear programs (sets of s sensors times the sign patterns of their rows over the "
        "window), more than the limit of 2"
    )
    huge = l1_error_bound(THREE, 1, MeasurementNoise.uniform(0.01, 3), horizon=40)
    assert l1_reason(huge, THREE).startswith("about 1.6e+12 linear programs")


def test_analyze_reports_the_l1_bound():
    cert = analyze(load_example("lasso-example-1"), noise=0.01)
    l1 = cert["l1_error_bound"]
    assert l1.verdict is Verdict.HOLDS and not l1.required and l1.fields["decoder"] == "l1"
    assert l1.value >= cert["decoder_error_bound"].fields["lower_bound"]
    broken = analyze(load_example("notes-example-2"), noise=0.01)
    assert broken["l1_error_bound"].verdict is Verdict.FAILS
    assert "breaking_set" in broken["l1_error_bound"].witness


@pytest.mark.parametrize("seed", range(3))
def test_the_lower_bound_is_the_decoders_error_on_the_window_built_for_it(seed):
    """The data of x = 0 with the noise (within its bounds on p - s sensors) and the attack (on
    the others) of ``l1_worst_case`` are explained exactly by x + c v: the l1 decoder returns
    it, its error is the lower bound, and the bound is above it."""
    from ssecert.estimators.support_decoders import l1_decoder
    from ssecert.structure.l1_bound import l1_worst_case, with_lower_bound

    rng = np.random.default_rng(seed)
    checked = 0
    while checked < 4:
        n, p, tau = int(rng.integers(1, 4)), int(rng.integers(3, 7)), int(rng.integers(1, 3))
        s = int(rng.integers(1, (p - 1) // 2 + 1))
        plant = System(rng.standard_normal((n, n)) * 0.6, rng.standard_normal((p, n)))
        noise = MeasurementNoise(rng.uniform(1e-3, 0.1, p), "inf" if rng.random() < 0.6 else "2")
        found = with_lower_bound(plant, l1_error_bound(plant, s, noise, horizon=tau))
        if found.code is not L1BoundCode.CERTIFIED:
            continue
        case = l1_worst_case(plant, found)
        assert case is not None and 0 < found.lower <= found.bound
        assert len(case["attacked"]) == s and set(case["attacked"]).isdisjoint(found.lower_kept)
        size = np.abs(case["noise"])
        size = size.max(axis=1) if noise.per_sample else np.linalg.norm(size, axis=1)
        assert np.all(size <= noise.eta)
        O = plant.sensor_blocks(tau).reshape(-1, n)  # sensor-major, as the data
        data = (case["noise"] + case["attack"]).reshape(-1)  # x = 0
        x_hat = l1_decoder(O, data, tol=1e-10)
        assert np.linalg.norm(x_hat) == pytest.approx(found.lower, rel=1e-6)
        checked += 1


def test_analyze_reports_the_l1_lower_bound_within_the_measurement_noise():
    data = {"name": "l1", "system": {"A": [[0.9, 0.1], [0.0, 0.8]],
            "C": [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, -1.0], [2.0, 1.0]]},
            "attack": {"max_attacked": 1}, "noise": {"measurement": 0.01}}  # fmt: skip
    from ssecert import spec_from_dict

    quiet = analyze(spec_from_dict(data))["l1_error_bound"]
    assert quiet.verdict is Verdict.HOLDS
    assert 0 < quiet.fields["lower_bound"] < quiet.value
    assert len(quiet.evidence["lower_bound_kept_sensors"]) == 4  # p - s kept
    # process noise: the bound grows, the construction stays within the measurement noise
    data["noise"] = {"measurement": 0.01, "process": 0.02, "input": [[1.0], [0.5]]}
    noisy = analyze(spec_from_dict(data))["l1_error_bound"]
    assert noisy.value > quiet.value and noisy.fields["lower_bound"] == quiet.fields["lower_bound"]


def test_a_subnormal_lower_bound_is_not_claimed():
    """Noise of 5e-324: the window's scale is rounded in the subnormal range, where the
    relative margins do not hold; the lower bound is 0 rather than a number that may be high."""
    from ssecert.structure.l1_bound import with_lower_bound

    plant = System(np.eye(1), np.ones((3, 1)))
    for eta, positive in ((5e-324, False), (1e-300, True)):
        found = with_lower_bound(
            plant, l1_error_bound(plant, 1, MeasurementNoise.uniform(eta, 3), horizon=1)
        )
        assert found.code is L1BoundCode.CERTIFIED and (found.lower > 0) is positive
