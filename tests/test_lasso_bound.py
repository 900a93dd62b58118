"""The Lasso decoder's certified worst-case error under bounded noise (``lasso_error_bound``):
closed forms, agreement with the irrepresentable check, and Lasso solutions that never exceed
the bound."""

from __future__ import annotations

import itertools
import math
from dataclasses import replace

import numpy as np
import pytest

from ssecert import System
from ssecert.analyze import analyze
from ssecert.examples import load_example
from ssecert.noise import MeasurementNoise
from ssecert.results import Verdict
from ssecert.structure.irrepresentable import irrepresentable_constant
from ssecert.structure.lasso_bound import (
    LassoBoundCode,
    lasso_bound_rechecks,
    lasso_error_bound,
    lasso_worst_case,
)
from ssecert.structure.noise_messages import lasso_reason

EXAMPLE_1 = System(np.eye(1), 2.0 * np.ones((3, 1)))  # the Lasso paper's Example 1, alpha = 2


def test_example_1_in_closed_form():
    # rho = 1/2; on the two safe sensors R = I - 11'/2 (row sums of |R| are 1), so
    # lam_min = eta / (1 - 1/2); the noise's reach is eta / alpha, the bias lam / (2 alpha)
    eta = 0.01
    found = lasso_error_bound(EXAMPLE_1, 1, MeasurementNoise.uniform(eta, 3), horizon=1)
    assert found.code is LassoBoundCode.CERTIFIED and lasso_bound_rechecks(found)
    assert found.rho == pytest.approx(0.5, rel=1e-12) and found.rho >= 0.5
    assert found.lam_min == pytest.approx(2 * eta, rel=1e-12) and found.lam_min >= 2 * eta
    assert found.noise_term == pytest.approx(eta / 2, rel=1e-12)
    assert found.kappa == pytest.approx(0.25, rel=1e-12)
    assert found.bound == pytest.approx(eta / 2 + 0.25 * 2 * eta, rel=1e-12)
    assert found.at(1.0) == pytest.approx(eta / 2 + 0.25, rel=1e-12)
    assert found.at(found.lam_min) == math.inf  # lam must be above lam_min


def test_example_1_bound_is_reached():
    # both safe sensors read eta high, the third is attacked: the estimate is off by the
    # noise's eta / alpha plus the bias lam / (2 alpha), exactly the bound
    from ssecert.estimators.decoders import partial_lasso_cvxpy

    eta, lam, x = 0.01, 1.0, 0.7
    found = lasso_error_bound(EXAMPLE_1, 1, MeasurementNoise.uniform(eta, 3), horizon=1)
    y = 2.0 * x + np.array([eta, eta, 50.0])
    x_hat, a_hat = partial_lasso_cvxpy(EXAMPLE_1.C, y, lam, tol=1e-10)
    assert abs(x_hat[0] - x) == pytest.approx(found.at(lam), rel=1e-6)
    assert abs(x_hat[0] - x) <= found.at(lam)
    assert a_hat[:2] == pytest.approx([0.0, 0.0], abs=1e-8)  # the attack estimate stays on y3
    # the construction finds that worst case by itself
    assert lasso_worst_case(EXAMPLE_1, found, lam)["lower"] == pytest.approx(found.at(lam))


def _plant(rng, n, p):
    return System(rng.standard_normal((n, n)) * 0.6, rng.standard_normal((p, n)))


def test_the_constructed_worst_case_is_what_the_lasso_does_and_below_the_bound():
    from ssecert.estimators.decoders import partial_lasso_cvxpy

    rng = np.random.default_rng(5)
    ratios = []
    for _ in range(25):
        n, p, tau = int(rng.integers(1, 4)), int(rng.integers(3, 8)), int(rng.integers(1, 4))
        s = int(rng.integers(0, (p - 1) // 2 + 1))
        plant = _plant(rng, n, p)
        noise = MeasurementNoise(rng.uniform(0, 0.1, p), "inf" if rng.random() < 0.6 else "2")
        found = lasso_error_bound(plant, s, noise, horizon=tau)
        if found.code is not LassoBoundCode.CERTIFIED:
            continue
        lam = found.lam_min * 1.2 + 1e-6
        reached = lasso_worst_case(plant, found, lam)
        # the attack is on the support's rows, the noise within its bounds
        rows = np.arange(p * tau)
        assert not np.any(reached["attack"][~np.isin(rows % p, reached["support"])])
        per_sensor = reached["noise"].reshape(tau, p)
        if noise.per_sample:
            assert np.all(np.abs(per_sensor) <= noise.eta * (1 + 1e-12))
        else:
            assert np.all(np.linalg.norm(per_sensor, axis=0) <= noise.eta * (1 + 1e-12))
        # from x = 0 the decoder's estimate is the predicted error
        O = plant.observability_matrix(tau)
        x_hat, _ = partial_lasso_cvxpy(O, reached["attack"] + reached["noise"], lam, tol=1e-11)
        assert np.linalg.norm(x_hat) == pytest.approx(reached["lower"], rel=1e-6, abs=1e-9)
        assert reached["lower"] <= found.at(lam)
        ratios.append(reached["lower"] / found.at(lam))
    assert len(ratios) >= 5 and np.median(ratios) > 0.5  # the bound is close to the worst case


def test_the_irrepresentable_constant_is_the_definitions_largest():
    rng = np.random.default_rng(3)
    for _ in range(12):
        n, p, tau = int(rng.integers(1, 4)), int(rng.integers(3, 8)), int(rng.integers(1, 4))
        s = int(rng.integers(1, (p - 1) // 2 + 1))
        plant = _plant(rng, n, p)
        found = lasso_error_bound(plant, s, MeasurementNoise.uniform(1e-3, p), horizon=tau)
        if found.code not in (LassoBoundCode.CERTIFIED, LassoBoundCode.NOT_IRREPRESENTABLE):
            continue
        O = plant.observability_matrix(tau)
        rho = max(
            irrepresentable_constant(O, [t * p + i for t in range(tau) for i in S])
            for S in itertools.combinations(range(p), s)
        )
        assert found.rho >= rho and found.rho == pytest.approx(rho, rel=1e-9)


def _lasso_errors(plant, s, noise, tau, lam, rng, runs):
    """The partial Lasso's errors on attacks of every size and noise at its bounds."""
    from ssecert.estimators.decoders import partial_lasso_cvxpy

    O, p, n = plant.observability_matrix(tau), plant.p, plant.n
    out = []
    for _ in range(runs):
        x = rng.standard_normal(n)
        attack = np.zeros((tau, p))
        support = rng.choice(p, size=s, replace=False)
        attack[:, support] = rng.choice([-1.0, 1.0], (tau, s)) * rng.choice([1e-3, 1.0, 100.0])
        if noise.per_sample:
            w = rng.choice([-1.0, 1.0], (tau, p)) * noise.eta
        else:
            w = rng.standard_normal((tau, p))
            w *= noise.eta / np.linalg.norm(w, axis=0)
        y = O @ x + attack.reshape(-1) + w.reshape(-1)
        x_hat, _ = partial_lasso_cvxpy(O, y, lam, tol=1e-10)
        out.append(float(np.linalg.norm(x_hat - x)))
    return out


def _no_solution_exceeds(seed, plants, runs):
    rng = np.random.default_rng(seed)
    certified = 0
    for _ in range(plants):
        n, p, tau = int(rng.integers(1, 4)), int(rng.integers(3, 8)), int(rng.integers(1, 4))
        s = int(rng.integers(0, (p - 1) // 2 + 1))
        plant = _plant(rng, n, p)
        noise = MeasurementNoise(rng.uniform(0, 0.1, p), "inf" if rng.random() < 0.6 else "2")
        found = lasso_error_bound(plant, s, noise, horizon=tau)
        if found.code is not LassoBoundCode.CERTIFIED:
            continue
        certified += 1
        for lam in (found.lam_min * 1.01 + 1e-9, found.lam_min * 3 + 1e-3):
            bound = found.at(lam)
            # the solver's own accuracy (1e-10) is the only slack
            assert max(_lasso_errors(plant, s, noise, tau, lam, rng, runs)) <= bound + 1e-8
    return certified


def test_no_lasso_solution_exceeds_the_bound():
    assert _no_solution_exceeds(seed=1, plants=10, runs=4) >= 3


@pytest.mark.slow
def test_no_lasso_solution_exceeds_the_bound_on_many_plants():
    assert _no_solution_exceeds(seed=2, plants=60, runs=12) >= 20


def test_the_codes_of_the_ways_a_bound_is_not_certified():
    eta = MeasurementNoise.uniform(0.01, 3)
    small = lasso_error_bound(EXAMPLE_1, 1, eta, horizon=1, lam=0.019)
    assert small.code is LassoBoundCode.LAMBDA_TOO_SMALL and small.bound == math.inf
    assert small.lam_min == pytest.approx(0.02)
    assert lasso_error_bound(EXAMPLE_1, 3, eta, horizon=1).code is LassoBoundCode.TOO_FEW_SENSORS
    many = lasso_error_bound(EXAMPLE_1, 1, eta, horizon=1, max_sets=2)
    assert many.code is LassoBoundCode.TOO_MANY_SETS and many.sets == 3
    # the second state is seen by y3 alone: without it the others do not determine the state,
    # exactly, over any window; an attack on y3 then hides it
    plant = System(np.eye(2), np.array([[1.0, 0.0], [2.0, 0.0], [0.0, 1.0]]))
    blind = lasso_error_bound(plant, 1, eta, horizon=1)
    assert blind.code is LassoBoundCode.WINDOW_TOO_SHORT and blind.worst_support == (2,)
    assert blind.facts == {"longer_horizon_helps": False}
    # y1 and y2 nearly alike: full rank exactly, but not with a margin above rounding
    plant = System(np.eye(2), np.array([[1.0, 0.0], [1.0, 2.0**-60], [0.0, 1.0]]))
    close = lasso_error_bound(plant, 1, eta, horizon=1)
    assert close.code is LassoBoundCode.NO_MARGIN and close.worst_support == (2,)
    # one sensor of a rotation over one step: two steps determine the state
    rotation = System(np.array([[0.0, 1.0], [-1.0, 0.0]]), np.array([[1.0, 0.0], [1.0, 0.0]]))
    short = lasso_error_bound(rotation, 0, MeasurementNoise.uniform(0.1, 2), horizon=1)
    assert short.code is LassoBoundCode.WINDOW_TOO_SHORT
    assert short.facts == {"longer_horizon_helps": True}
    assert lasso_reason(short, rotation).endswith("a window of n steps would determine it")
    # y4 repeats y1 and y2 together: an attack on it is represented by the others
    plant = System(np.eye(2), np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 0.0], [3.0, 3.0]]))
    coherent = lasso_error_bound(plant, 1, MeasurementNoise.uniform(0.01, 4), horizon=1)
    assert coherent.code is LassoBoundCode.NOT_IRREPRESENTABLE and coherent.rho >= 1
    O = plant.observability_matrix(1)
    assert coherent.rho == pytest.approx(irrepresentable_constant(O, list(coherent.rho_support)))


def test_no_noise_and_noise_at_the_edges_of_the_range():
    none = lasso_error_bound(EXAMPLE_1, 1, MeasurementNoise.uniform(0.0, 3), horizon=1)
    assert none.code is LassoBoundCode.CERTIFIED and none.lam_min == 0.0 and none.bound == 0.0
    assert none.at(0.1) == pytest.approx(0.025)  # the l1 bias alone
    for eta in (1e-300, 1e-150, 1e150):
        found = lasso_error_bound(EXAMPLE_1, 1, MeasurementNoise.uniform(eta, 3), horizon=1)
        assert found.code is LassoBoundCode.CERTIFIED and lasso_bound_rechecks(found)
        assert found.lam_min == pytest.approx(2 * eta, rel=1e-9)
        assert found.bound == pytest.approx(eta, rel=1e-9) and found.bound >= eta
    calm = lasso_error_bound(EXAMPLE_1, 0, MeasurementNoise.uniform(0.01, 3), horizon=1)
    assert calm.code is LassoBoundCode.CERTIFIED and calm.kappa == 0.0
    # no attack: least squares on the three sensors, |(1 1 1) w| / (2 * 3) <= 0.005
    assert calm.bound == pytest.approx(0.005, rel=1e-9)


def test_the_recheck_refuses_numbers_that_do_not_add_up():
    found = lasso_error_bound(EXAMPLE_1, 1, MeasurementNoise.uniform(0.01, 3), horizon=1)
    assert lasso_bound_rechecks(found)
    assert not lasso_bound_rechecks(replace(found, lam_min=found.lam_min * 0.99))
    assert not lasso_bound_rechecks(replace(found, bound=found.bound * 0.99))
    assert not lasso_bound_rechecks(replace(found, kappa=found.kappa * 0.99))


def test_the_words_of_each_code():
    eta = MeasurementNoise.uniform(0.01, 3)
    small = lasso_error_bound(EXAMPLE_1, 1, eta, horizon=1, lam=0.01)
    assert lasso_reason(small, EXAMPLE_1) == (
        "lambda = 0.01 is not above lambda_min = 0.02, below which the noise alone may move the "
        "attack estimate off its support"
    )
    plant = System(np.eye(2), np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 0.0], [3.0, 3.0]]))
    coherent = lasso_error_bound(plant, 1, MeasurementNoise.uniform(0.01, 4), horizon=1)
    assert lasso_reason(coherent, plant).startswith(
        f"the irrepresentable constant reaches {coherent.rho:.4g} >= 1 on the attack support y"
    )
    many = lasso_error_bound(EXAMPLE_1, 1, eta, horizon=1, max_sets=2)
    assert lasso_reason(many, EXAMPLE_1).startswith("3 supports of s sensors (the limit: 2)")
    certified = lasso_error_bound(EXAMPLE_1, 1, eta, horizon=1)
    assert lasso_reason(certified, EXAMPLE_1) == ""


def test_analyze_reports_the_lasso_bound_beside_the_l0_bound():
    cert = analyze(load_example("lasso-example-1"), noise=0.01)
    lasso, l0 = cert["lasso_error_bound"], cert["decoder_error_bound"]
    assert lasso.verdict is Verdict.HOLDS and not lasso.required
    assert lasso.fields["decoder"] == "lasso" and lasso.value == lasso.fields["bound"]
    assert lasso.fields["lambda_min"] == pytest.approx(0.02)
    assert lasso.fields["lower_bound"] == pytest.approx(lasso.value, rel=1e-9)  # tight here
    # no decoder guarantees less than the l0 bound's lower end: neither does the Lasso
    assert lasso.value >= l0.fields["lower_bound"]
    # a breaking set: no decoder has a finite error, the Lasso's check fails with it
    broken = analyze(load_example("notes-example-2"), noise=0.01)
    assert broken["lasso_error_bound"].verdict is Verdict.FAILS
    assert (
        broken["lasso_error_bound"].witness["breaking_set"]
        == broken["sparse_observability"].fields["breaking_set"]
    )


def test_the_report_shows_the_lasso_bound():
    from ssecert.certify import certify
    from ssecert.report.html import render_report
    from ssecert.spec import spec_from_dict

    spec = spec_from_dict(
        {
            "name": "example-1-noisy",
            "system": {"A": [[1.0]], "C": [[2.0], [2.0], [2.0]]},
            "attack": {"max_attacked": 1, "horizon": 1},
            "noise": {"measurement": 0.01},
        }
    )
    html = render_report(certify(spec, simulate=False))
    assert "Lasso decoder: certified bound of ||x_hat - x|| for every lambda &gt; 0.02" in html
    assert "Lasso decoder: reached by an explicit attack and noise" in html


@pytest.mark.slow
def test_the_lasso_papers_noisy_setting_is_not_certified_and_says_why():
    """Sec. 5.1's plants (n = tau = 20, p = 20, s = 4, noise 1e-4): the irrepresentable constant
    over sensor supports exceeds 1, as the irrepresentable check finds, so the witness gives no
    bound (the l0 decoder's is certified: test_noise_bounds)."""
    from ssecert.structure.irrepresentable import irrepresentable

    p, s, n = 20, 4, 20
    rng = np.random.default_rng(7)
    A = rng.standard_normal((n, n))
    A /= 1.01 * np.abs(np.linalg.eigvals(A)).max()
    plant = System(A, rng.standard_normal((p, n)))
    found = lasso_error_bound(plant, s, MeasurementNoise.uniform(1e-4, p), horizon=n)
    check = irrepresentable(plant, s, horizon=n)
    assert found.code is LassoBoundCode.NOT_IRREPRESENTABLE
    # an upper bound for the exact plant: the float value plus its certified error terms
    assert found.rho >= check.value and found.rho == pytest.approx(check.value, rel=1e-6)


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_plants_at_the_edges_of_the_float_range():
    from ssecert.structure.l1_bound import L1BoundCode, l1_error_bound
    from ssecert.structure.noise import BoundCode, decoder_error_bound

    # a positive bound that underflows is rounded up, never to 0 (the exact error is positive)
    calm = lasso_error_bound(EXAMPLE_1, 1, MeasurementNoise.uniform(0.0, 3), horizon=1)
    assert calm.at(5e-324) > 0
    loud = System(np.eye(1), np.array([[1e150], [1e150], [1.9e150]]))
    faint = MeasurementNoise.uniform(1e-300, 3)
    found = lasso_error_bound(loud, 0, faint, horizon=1)
    assert found.code is LassoBoundCode.CERTIFIED and found.bound > 0 and found.at(1e-200) > 0
    assert lasso_bound_rechecks(found)
    l0 = decoder_error_bound(System(np.eye(1), np.full((3, 1), 1e100)), 1, faint, horizon=1)
    assert l0.code is BoundCode.CERTIFIED and l0.bound > 0
    # entries near the bottom of the range: the constants do not change with the units
    for alpha in (2e-155, 1e-162, 1e153):
        plant = System(np.eye(1), np.full((3, 1), alpha))
        eta = MeasurementNoise.uniform(0.01, 3)
        lasso = lasso_error_bound(plant, 1, eta, horizon=1)
        assert lasso.code is LassoBoundCode.CERTIFIED and lasso.rho == pytest.approx(0.5)
        assert lasso.bound == pytest.approx(0.01 / alpha + 0.02 / (2 * alpha), rel=1e-9)
        l1 = l1_error_bound(plant, 1, eta, horizon=1)
        assert l1.code is L1BoundCode.CERTIFIED and l1.theta == pytest.approx(0.5)
    # a sensor that reads nothing, and a window shorter than the observability index
    blank = System(np.eye(1), np.array([[0.0], [1.0]]))
    assert lasso_error_bound(blank, 1, MeasurementNoise.uniform(0.01, 2), horizon=1).code is (
        LassoBoundCode.WINDOW_TOO_SHORT
    )


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_huge_noise_and_huge_plants_stay_in_range():
    from ssecert.structure.l1_bound import L1BoundCode, l1_error_bound

    # the worst case is built in units where the noise is about 1: never above the bound
    loud = lasso_error_bound(EXAMPLE_1, 1, MeasurementNoise.uniform(1e160, 3), horizon=1)
    reached = lasso_worst_case(EXAMPLE_1, loud)
    assert loud.code is LassoBoundCode.CERTIFIED
    assert 0 < reached["lower"] <= loud.bound and reached["lower"] == pytest.approx(loud.bound)
    # a noise bound at the top of the range: out of range, or certified, never an exception
    wide = System(np.eye(1), np.array([[1e-9], [1e9], [1e9], [1e9]]))
    found = l1_error_bound(wide, 1, MeasurementNoise.uniform(1.7e308, 4), horizon=1)
    assert found.code in (L1BoundCode.NOT_SOLVED, L1BoundCode.CERTIFIED)
    assert found.code is L1BoundCode.NOT_SOLVED or math.isfinite(found.bound)
    # entries of 1e155 (their squares overflow): decided in power-of-two units
    big = System(np.eye(1), np.full((3, 1), 1e155))
    eta = MeasurementNoise.uniform(0.01, 3)
    assert lasso_error_bound(big, 1, eta, horizon=1).code is LassoBoundCode.CERTIFIED
    assert l1_error_bound(big, 1, eta, horizon=1).code is L1BoundCode.CERTIFIED
    # subnormal noise bounds: the printed numbers re-check
    tiny = MeasurementNoise.uniform(1e-310, 3)
    for found in (
        lasso_error_bound(EXAMPLE_1, 1, tiny, horizon=1),
        l1_error_bound(EXAMPLE_1, 1, tiny, horizon=1),
    ):
        assert found.code.value == "certified" and found.bound > 0


def test_a_window_too_short_fails_every_decoder_bound_with_the_kept_sensors():
    from ssecert.spec import spec_from_dict

    spec = spec_from_dict(
        {
            "name": "rotation",
            "system": {"A": [[0.0, 1.0], [-1.0, 0.0]], "C": [[1.0, 0.0], [1.0, 0.0]]},
            "attack": {"max_attacked": 0, "horizon": 1},
            "noise": {"measurement": 0.1},
        }
    )
    cert = analyze(spec)
    for check_id in ("decoder_error_bound", "l1_error_bound", "lasso_error_bound"):
        check = cert[check_id]
        assert check.verdict is Verdict.FAILS and check.value == math.inf, check_id
    for check_id in ("l1_error_bound", "lasso_error_bound"):
        assert cert[check_id].witness == {"kept_sensors": [0, 1], "horizon": 1}
        assert cert[check_id].code.name == "WINDOW_TOO_SHORT"
    # and a window of n steps would determine the state: the reason says so
    from ssecert.structure import noise_messages
    from ssecert.structure.l1_bound import l1_error_bound

    lasso = lasso_error_bound(spec.system, 0, spec.noise, horizon=1)
    l1 = l1_error_bound(spec.system, 0, spec.noise, horizon=1)
    for found in (lasso, l1):
        assert found.facts["longer_horizon_helps"] is True
    assert noise_messages.lasso_reason(lasso, spec.system).endswith(
        "a window of n steps would determine it"
    )
    assert noise_messages.l1_reason(l1, spec.system).endswith(
        "a window of n steps would determine it"
    )


def test_the_constructed_worst_case_is_a_lower_bound_on_an_ill_conditioned_plant():
    # four sensors of nearly one direction: cond(O_K) near 1e3, the computed N and Z off by
    # far more than the construction's own rounding; the exact error from the constructed
    # attack and noise (x = 0: the witness's closed form in fractions) is at least `lower`
    from fractions import Fraction

    C = np.array(
        [
            [1.0033000478203544, 1.0048966258302836],
            [-0.6178579900937755, -0.6159046521239556],
            [1.8221998825208356, 1.821378169238131],
            [-1.3208085335185262, -1.3215221161309127],
        ]
    )
    plant = System(np.eye(2), C)
    found = lasso_error_bound(plant, 1, MeasurementNoise.uniform(0.1, 4), horizon=1)
    lam = found.lam_min * 1.5
    reached = lasso_worst_case(plant, found, lam)
    S = list(reached["support"])
    K = [i for i in range(4) if i not in S]
    q = [[Fraction(float(x)) for x in row] for row in C]
    OK, OS = [q[i] for i in K], [q[i] for i in S]
    # G = OK' OK (2 x 2), e = G^-1 (OK' w_K + lam OS' sign(attack_S))
    G = [[sum(r[a] * r[b] for r in OK) for b in range(2)] for a in range(2)]
    det = G[0][0] * G[1][1] - G[0][1] * G[1][0]
    inv = [[G[1][1] / det, -G[0][1] / det], [-G[1][0] / det, G[0][0] / det]]
    w = [Fraction(float(reached["noise"][i])) for i in K]
    sign = [Fraction(int(np.sign(reached["attack"][i]))) for i in S]
    rhs = [
        sum(r[a] * wi for r, wi in zip(OK, w))
        + Fraction(lam) * sum(r[a] * si for r, si in zip(OS, sign))
        for a in range(2)
    ]
    e = [inv[a][0] * rhs[0] + inv[a][1] * rhs[1] for a in range(2)]
    assert e[0] ** 2 + e[1] ** 2 >= Fraction(reached["lower"]) ** 2
    assert reached["lower"] <= found.at(lam) and reached["lower"] > 0.99 * found.at(lam)
