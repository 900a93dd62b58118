"""Irrepresentable constant: batched values against the definition with pinv."""

import itertools
import math

import numpy as np
import pytest

from ssecert import System, irrepresentable, irrepresentable_constant
from ssecert.examples import load_example


@pytest.mark.parametrize("alpha", [1e-3, -0.7, 1.0, 2.0, 350.0])
def test_lasso_example_1_gives_one_half_for_any_alpha(alpha):
    check = irrepresentable(System([[1.0]], alpha * np.ones((3, 1))), 1, horizon=1)
    assert check.verdict.value == "holds"
    assert check.value == pytest.approx(0.5, rel=1e-12)
    assert check.margin == pytest.approx(0.5, rel=1e-12)
    assert check.fields["worst_support"] == [0]


def test_packaged_lasso_example():
    spec = load_example("lasso-example-1")
    check = irrepresentable(spec.system, spec.max_attacked, horizon=spec.horizon)
    assert check.value == pytest.approx(0.5)
    assert not check.required


@pytest.mark.parametrize("seed", range(8))
def test_block_mode_matches_brute_force(seed):
    rng = np.random.default_rng(seed)
    n, p, tau, s = 3, 6, 2, 2
    system = System(rng.standard_normal((n, n)) / 2, rng.standard_normal((p, n)))
    O = system.observability_matrix(tau)
    values = {
        S: irrepresentable_constant(O, [t * p + i for i in S for t in range(tau)])
        for S in itertools.combinations(range(p), s)
    }
    worst = max(values.values())
    first = min(S for S, v in values.items() if v >= worst * (1 - 1e-12))
    check = irrepresentable(system, s, horizon=tau)
    assert check.value == pytest.approx(worst, rel=1e-9)
    assert tuple(check.fields["worst_support"]) == first
    assert check.verdict.value == ("holds" if worst < 1 else "fails")


def test_entrywise_mode_matches_brute_force():
    rng = np.random.default_rng(3)
    system = System(rng.standard_normal((2, 2)), rng.standard_normal((4, 2)))
    O = system.observability_matrix(2)
    worst = max(irrepresentable_constant(O, list(S)) for S in itertools.combinations(range(8), 2))
    check = irrepresentable(system, 2, horizon=2, mode="entrywise")
    assert check.value == pytest.approx(worst, rel=1e-9)
    assert check.fields["mode"] == "entrywise"
    assert all("@" in name for name in check.fields["worst_support_names"])


def test_rank_deficient_complement_gives_infinity_and_witness():
    # sensor 0 alone sees state 0: removing it leaves O_Sbar without full column rank
    system = System(np.eye(2), [[1.0, 0.0], [0.0, 1.0], [0.0, 2.0]])
    check = irrepresentable(system, 1, horizon=1)
    assert check.verdict.value == "fails"
    assert math.isinf(check.value)
    assert check.witness["support"] == [0]


def test_short_horizon_is_infinite():
    # n = 2 with one usable sensor needs two steps
    system = System([[1.0, 1.0], [0.0, 1.0]], [[1.0, 0.0], [1.0, 0.0]])
    check = irrepresentable(system, 1, horizon=1)
    assert math.isinf(check.value) and check.verdict.value == "fails"


def test_no_attack_is_trivially_fine():
    check = irrepresentable(System([[1.0]], [[1.0], [1.0]]), 0)
    assert check.value == 0.0 and check.verdict.value == "holds"


def test_budget():
    check = irrepresentable(System(np.eye(2), np.eye(6, 2) + 1), 3, horizon=1, max_sets=5)
    assert check.verdict.value == "inconclusive"
    assert "--max-sets" in check.summary


def test_bad_mode():
    with pytest.raises(ValueError, match="mode"):
        irrepresentable(System([[1.0]], [[1.0]]), 1, mode="rows")
