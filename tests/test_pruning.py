"""Tests of ssecert.estimators.pruning (Zheng and Anubi's weighted l1 observer with pruning)."""

import itertools

import cvxpy as cp
import numpy as np
import pytest
import scipy.linalg
import scipy.stats

from ssecert import System
from ssecert.estimators.pruning import (
    DetectorDecision,
    detector,
    l1_decode,
    poisson_binomial_pmf,
    prune_support_prior,
    pruned_weighted_l1_observer,
    pruned_weighted_l1_window_observer,
    reliable_safe_count,
    weighted_l1_observer,
)
from ssecert.estimators.pruning_attacks import successful_attack, verify_successful_attack

SEEDS = range(8)


def relative_error(x_hat, x):
    return np.linalg.norm(np.asarray(x_hat) - x) / np.linalg.norm(x)


def cvxpy_decode(M, y, weights=None):
    """Definition 1 as printed: V Sigma_1^-1 argmin_z ||y - U_1 z||_(1, w), solved by Clarabel."""
    U1, sigma, Vt = np.linalg.svd(M, full_matrices=False)
    w = np.ones(len(y)) if weights is None else np.asarray(weights)
    z = cp.Variable(M.shape[1])
    problem = cp.Problem(cp.Minimize(cp.sum(cp.multiply(w, cp.abs(y - U1 @ z)))))
    problem.solve(solver=cp.CLARABEL)
    return Vt.T @ (z.value / sigma), problem.value


def brute_force_pmf(probs):
    pmf = np.zeros(len(probs) + 1)
    for outcome in itertools.product((0, 1), repeat=len(probs)):
        weight = np.prod([p if bit else 1 - p for p, bit in zip(probs, outcome)])
        pmf[sum(outcome)] += weight
    return pmf


# --------------------------------------------------------------------------
# Poisson-binomial pmf and the pruning (Lemma 3.1, (13)-(14))
# --------------------------------------------------------------------------


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("size", [0, 1, 2, 5, 9])
def test_pmf_matches_enumeration(seed, size):
    probs = np.random.default_rng(seed).uniform(0.0, 1.0, size)
    np.testing.assert_allclose(poisson_binomial_pmf(probs), brute_force_pmf(probs), atol=1e-14)


@pytest.mark.parametrize("size", [1, 7, 40, 300])
@pytest.mark.parametrize("p", [0.0, 0.03, 0.5, 0.81, 1.0])
def test_pmf_matches_binomial_for_equal_probabilities(size, p):
    pmf = poisson_binomial_pmf(np.full(size, p))
    np.testing.assert_allclose(
        pmf, scipy.stats.binom.pmf(np.arange(size + 1), size, p), rtol=1e-9, atol=1e-15
    )


@pytest.mark.parametrize("seed", SEEDS)
def test_pmf_matches_lemma_3_1_root_form(seed):
    # r = prod(p_i) * coefficients of prod_i (t - s_i), s_i = -(1 - p_i) / p_i, lowest power first.
    probs = np.random.default_rng(seed).uniform(0.2, 1.0, 12)
    s = -(1 - probs) / probs
    r = np.prod(probs) * np.polynomial.polynomial.polyfromroots(s)
    np.testing.assert_allclose(poisson_binomial_pmf(probs), r, atol=1e-13)


def test_pmf_is_a_distribution_for_extreme_probabilities():
    probs = np.random.default_rng(3).choice([1e-12, 1e-3, 0.5, 1 - 1e-9], 500)
    pmf = poisson_binomial_pmf(probs)
    assert pmf.min() >= 0.0
    assert abs(pmf.sum() - 1.0) < 1e-12


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("reliability", [0.05, 0.5, 0.9, 0.99])
def test_reliable_count_is_the_largest_k_of_13(seed, reliability):
    probs = np.random.default_rng(seed).uniform(0.3, 1.0, 8)
    pmf = brute_force_pmf(probs)
    tail = [pmf[k:].sum() for k in range(len(probs) + 2)]  # tail[N + 1] = 0
    count = reliable_safe_count(probs, reliability=reliability)
    assert tail[count] >= reliability
    assert tail[count + 1] < reliability


@pytest.mark.parametrize("size,p", [(10, 0.9), (50, 0.6), (200, 0.75)])
def test_reliable_count_matches_binomial_quantile(size, p):
    reliability = 0.9
    # Pr{S >= k} = sf(k - 1); the largest k with sf(k - 1) >= eta.
    expected = max(
        k for k in range(size + 1) if scipy.stats.binom.sf(k - 1, size, p) >= reliability
    )
    assert reliable_safe_count(np.full(size, p), reliability=reliability) == expected


def test_reliable_count_decreases_with_reliability():
    probs = np.random.default_rng(0).uniform(0.2, 1.0, 60)
    counts = [reliable_safe_count(probs, reliability=eta) for eta in (0.1, 0.5, 0.9, 0.999)]
    assert counts == sorted(counts, reverse=True)
    assert counts[0] > counts[-1]


@pytest.mark.parametrize("seed", SEEDS)
def test_pruning_keeps_the_most_confident_rows_of_the_prior(seed):
    rng = np.random.default_rng(seed)
    probs = rng.uniform(0.0, 1.0, 40)
    prior = sorted(rng.choice(40, 25, replace=False).tolist())
    pruned = prune_support_prior(prior, probs, reliability=0.8)
    assert pruned.count == reliable_safe_count(probs[prior], reliability=0.8)
    assert len(pruned.trusted) == pruned.count
    assert set(pruned.trusted) <= set(prior)
    left_out = set(prior) - set(pruned.trusted)
    if pruned.trusted and left_out:
        assert min(probs[list(pruned.trusted)]) >= max(probs[list(left_out)])
    assert pruned.tail_probability >= 0.8
    assert pruned.expected_correct == pytest.approx(probs[prior].sum())


# --------------------------------------------------------------------------
# Decoder and detector
# --------------------------------------------------------------------------


@pytest.mark.parametrize("seed", SEEDS)
def test_l1_decoder_recovers_state_under_sparse_attack(seed):
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((40, 5))
    x = rng.standard_normal(5)
    e = np.zeros(40)
    e[rng.choice(40, 4, replace=False)] = 100.0 * rng.standard_normal(4)
    assert relative_error(l1_decode(M, M @ x + e), x) < 1e-9


@pytest.mark.parametrize("seed", SEEDS)
def test_l1_decoder_agrees_with_cvxpy(seed):
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((25, 4))
    y = rng.standard_normal(25) * 3.0  # no structure: the minimiser is unique, not x
    weights = rng.uniform(0.1, 2.0, 25)
    for w in (None, weights):
        x_hat = l1_decode(M, y, weights=w)
        x_ref, value = cvxpy_decode(M, y, w)
        cost = np.ones(25) if w is None else w
        assert np.sum(cost * np.abs(y - M @ x_hat)) == pytest.approx(value, rel=1e-7)
        np.testing.assert_allclose(x_hat, x_ref, atol=1e-5)


def test_detector_fires_only_above_threshold():
    M = np.random.default_rng(0).standard_normal((6, 2))
    x = np.array([1.0, -1.0])
    y = M @ x
    y[0] += 0.3
    decision = detector(M, y, x, 0.25)
    assert isinstance(decision, DetectorDecision)
    assert decision.alarm and bool(decision)
    assert decision.residual == pytest.approx(0.3)
    assert not detector(M, y, x, 0.35).alarm


# --------------------------------------------------------------------------
# Theorem 2.1: (eps, alpha)-successful attacks
# --------------------------------------------------------------------------


def test_attack_direction_solves_program_7():
    rng = np.random.default_rng(1)
    M = rng.standard_normal((20, 4))
    support = list(range(11))
    attack = successful_attack(M, support, 0.1)
    U1, sigma, Vt = np.linalg.svd(M, full_matrices=False)
    G = U1[11:]
    # (7): max z' Sigma^-2 z s.t. z' G'G z <= budget^2, a generalized symmetric eigenproblem.
    lam = scipy.linalg.eigh(np.diag(sigma**-2.0), G.T @ G, eigvals_only=True)[-1]
    budget = np.linalg.norm(G @ attack.z)
    assert np.linalg.norm(attack.z / sigma) == pytest.approx(budget * np.sqrt(lam), rel=1e-9)
    assert np.linalg.norm(attack.state_shift) == pytest.approx(np.linalg.norm(attack.z / sigma))
    # No feasible random point does better.
    trial = rng.standard_normal((1000, 4))
    trial *= budget / np.linalg.norm(trial @ G.T, axis=1, keepdims=True)
    assert np.max(np.linalg.norm(trial / sigma, axis=1)) <= budget * np.sqrt(lam) * (1 + 1e-12)
    # (8): zero off the support, U_(1,T) z_e on it.
    np.testing.assert_array_equal(attack.attack[11:], 0.0)
    np.testing.assert_allclose(attack.attack[:11], U1[:11] @ attack.z, atol=1e-12)


@pytest.mark.parametrize("seed", SEEDS)
def test_theorem_2_1_attack_is_verified_successful(seed):
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((20, 4))
    support = rng.choice(20, 12, replace=False).tolist()
    eps = 0.1
    attack = successful_attack(M, support, eps)
    assert attack.bounded
    assert attack.alpha > 0.5 * np.linalg.norm(attack.state_shift)
    assert attack.alpha_guaranteed <= attack.alpha + 1e-9
    assert attack.safe_residual <= eps
    x = rng.standard_normal(4)
    check = verify_successful_attack(M, x, attack.attack, eps, attack.alpha)
    assert check.successful
    assert check.deviation >= attack.alpha - 1e-7 and not check.alarm
    # The same verdict from the cvxpy decoder, which knows nothing of the LP.
    y = M @ x + attack.attack
    x_ref, _ = cvxpy_decode(M, y)
    assert np.linalg.norm(x_ref - x) >= attack.alpha - 1e-6
    assert np.sum(np.abs(y - M @ x_ref)) <= eps


def test_paper_budget_makes_the_detector_fire():
    # (7) with budget eps bounds ||U_(1,T^c) z||_2, so the l1 residual can reach sqrt(|T^c|) eps.
    M = np.random.default_rng(0).standard_normal((12, 3))
    eps = 0.1
    attack = successful_attack(M, range(7), eps, scaling="paper")
    assert not attack.detector_silent
    assert not verify_successful_attack(M, np.ones(3), attack.attack, eps, 0.0).successful
    assert attack.decoder_residual <= np.sqrt(5) * eps
    assert successful_attack(M, range(7), eps).detector_silent


def test_unbounded_program_gives_an_undetectable_attack():
    rng = np.random.default_rng(2)
    M = rng.standard_normal((10, 4))
    attack = successful_attack(M, range(7), 0.1, max_shift=50.0)  # 3 safe rows < n = 4
    assert not attack.bounded
    assert attack.alpha == pytest.approx(50.0, rel=1e-9)
    assert attack.safe_residual < 1e-10
    check = verify_successful_attack(M, rng.standard_normal(4), attack.attack, 0.1, 49.0)
    assert check.successful and check.residual < 1e-8


def test_verification_refuses_an_attack_the_decoder_corrects():
    rng = np.random.default_rng(4)
    M = rng.standard_normal((30, 4))
    attack = successful_attack(M, [0, 1], 0.1)
    assert attack.alpha < 1e-9  # two of thirty rows: the l1 decoder corrects it
    check = verify_successful_attack(M, rng.standard_normal(4), attack.attack, 0.1, 1e-3)
    assert not check.successful and not check.alarm


# --------------------------------------------------------------------------
# Weighted l1 observer with pruned prior (Definition 5)
# --------------------------------------------------------------------------


def consistent_attack(rng, M, attacked, size):
    """Attacked rows read M_T (x + delta): the l1 decoder sees the larger set as the truth."""
    delta = rng.standard_normal(M.shape[1])
    e = np.zeros(M.shape[0])
    e[attacked] = M[attacked] @ (size * delta / np.linalg.norm(delta))
    return e


@pytest.mark.parametrize("seed", SEEDS)
def test_pruned_prior_recovers_where_l1_fails(seed):
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((20, 5))
    x = rng.standard_normal(5)
    attacked = rng.choice(20, 12, replace=False)
    safe = np.setdiff1d(np.arange(20), attacked)
    y = M @ x + consistent_attack(rng, M, attacked, 5.0)
    assert relative_error(l1_decode(M, y), x) > 0.1

    # A prior pointing at the attacked sensors, plus three wrong "safe" rows of low confidence.
    wrong = attacked[:3]
    probs = np.full(20, 0.6)
    probs[safe] = 0.97
    estimate = pruned_weighted_l1_observer(M, y, np.concatenate([safe, wrong]), probs)
    assert set(estimate.trusted) <= set(safe.tolist())
    assert len(estimate.trusted) >= 5
    assert relative_error(estimate.x_hat, x) < 1e-9
    np.testing.assert_allclose(estimate.residual[safe], 0.0, atol=1e-8)
    assert set(np.flatnonzero(estimate.weights == 1.0)) == set(estimate.trusted)


@pytest.mark.parametrize("seed", SEEDS)
def test_window_observer_recovers_where_l1_fails(seed):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((3, 3))
    A /= np.max(np.abs(np.linalg.eigvals(A)))
    plant = System(A, rng.standard_normal((6, 3)))
    H = plant.observability_matrix(4)  # 4 steps of 6 sensors
    x = rng.standard_normal(3)
    sensors = rng.choice(6, 4, replace=False)  # 4 of 6 sensors over the whole window
    rows = np.array([step * 6 + i for step in range(4) for i in sensors])
    y = H @ x + consistent_attack(rng, H, rows, 5.0)
    assert relative_error(l1_decode(H, y), x) > 0.1
    safe = np.setdiff1d(np.arange(24), rows)
    probs = np.full(24, 0.99)
    estimate = pruned_weighted_l1_window_observer(H, y, safe, probs, sensors=6, omega=0.01)
    assert set(estimate.trusted) <= set(safe.tolist())
    assert relative_error(estimate.x_hat, x) < 1e-9
    static = pruned_weighted_l1_observer(H, y, safe, probs, omega=0.01)
    assert static.trusted == estimate.trusted
    np.testing.assert_allclose(static.x_hat, estimate.x_hat, atol=1e-12)


@pytest.mark.parametrize("seed", SEEDS)
def test_weighted_observer_agrees_with_cvxpy(seed):
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((15, 3))
    y = rng.standard_normal(15)
    trusted = rng.choice(15, 6, replace=False).tolist()
    estimate = weighted_l1_observer(M, y, trusted, omega=0.3)
    w = np.full(15, 0.3)
    w[trusted] = 1.0
    x_ref, value = cvxpy_decode(M, y, w)
    assert np.sum(w * np.abs(estimate.residual)) == pytest.approx(value, rel=1e-7)
    np.testing.assert_allclose(estimate.x_hat, x_ref, atol=1e-5)


# --------------------------------------------------------------------------
# Input validation
# --------------------------------------------------------------------------

M0 = np.random.default_rng(0).standard_normal((6, 2))
Y0 = M0 @ np.ones(2)
P0 = np.full(6, 0.9)

BAD_INPUTS = [
    (lambda: l1_decode("M", Y0), TypeError, "M"),
    (lambda: l1_decode(M0, Y0[:5]), ValueError, "y has the wrong number"),
    (lambda: l1_decode(M0, Y0, weights=np.ones(6, dtype=bool)), TypeError, "weights"),
    (lambda: l1_decode(M0, Y0, weights=-np.ones(6)), ValueError, "weights"),
    (lambda: l1_decode(M0, Y0, weights=np.zeros(6)), ValueError, "weights"),
    (lambda: l1_decode(M0, np.full(6, np.nan)), ValueError, "y must be finite"),
    (lambda: detector(M0, Y0, np.ones(3), 0.1), ValueError, "x_hat"),
    (lambda: detector(M0, Y0, np.ones(2), 0.0), ValueError, "eps"),
    (lambda: detector(M0, Y0, np.ones(2), "0.1"), TypeError, "eps"),
    (lambda: poisson_binomial_pmf([0.5, 1.2]), ValueError, r"probs\[1\]"),
    (lambda: poisson_binomial_pmf([[0.5]]), ValueError, "probs must be a 1-D"),
    (lambda: poisson_binomial_pmf(["a"]), TypeError, "probs"),
    (lambda: reliable_safe_count(P0, reliability=1.0), ValueError, "reliability"),
    (lambda: reliable_safe_count(P0, reliability=True), TypeError, "reliability"),
    (lambda: prune_support_prior([0, 6], P0), ValueError, r"prior_safe\[1\]"),
    (lambda: prune_support_prior([1, 1], P0), ValueError, "prior_safe has repeated"),
    (lambda: prune_support_prior("01", P0), TypeError, "prior_safe"),
    (lambda: weighted_l1_observer(M0, Y0, [0], omega=1.5), ValueError, "omega"),
    (lambda: weighted_l1_observer(M0, Y0, [], omega=0.0), ValueError, "omega"),
    (lambda: weighted_l1_observer(M0, Y0, [0.5]), TypeError, r"trusted\[0\]"),
    (lambda: pruned_weighted_l1_observer(M0, Y0, [0], P0[:4]), ValueError, "probs"),
    (
        lambda: pruned_weighted_l1_window_observer(M0, Y0, [0], P0, sensors=4),
        ValueError,
        "sensors = 4",
    ),
    (lambda: pruned_weighted_l1_window_observer(M0, Y0, [0], P0, sensors=0), ValueError, "sensors"),
    (
        lambda: pruned_weighted_l1_window_observer(M0, Y0[:3], [0], P0, sensors=3),
        ValueError,
        "y_window",
    ),
    (lambda: successful_attack(M0, [], 0.1), ValueError, "support"),
    (lambda: successful_attack(M0, [7], 0.1), ValueError, r"support\[0\]"),
    (lambda: successful_attack(M0, [0], -1.0), ValueError, "eps"),
    (lambda: successful_attack(M0, [0], 0.1, scaling="papers"), ValueError, "scaling"),
    (lambda: successful_attack(M0, [0], 0.1, margin=1.0), ValueError, "margin"),
    (lambda: successful_attack(M0, [0], 0.1, max_shift=0), ValueError, "max_shift"),
    (lambda: successful_attack(np.ones((6, 2)), [0], 0.1), ValueError, "full column rank"),
    (lambda: verify_successful_attack(M0, np.ones(2), np.ones(5), 0.1, 0.0), ValueError, "attack"),
    (lambda: verify_successful_attack(M0, np.ones(2), np.ones(6), 0.1, -1.0), ValueError, "alpha"),
]


@pytest.mark.parametrize("call,error,message", BAD_INPUTS)
def test_bad_inputs_name_the_argument(call, error, message):
    with pytest.raises(error, match=message):
        call()
