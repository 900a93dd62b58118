"""The thesis's assumptions, decided on instances."""

import numpy as np
import pytest

from ssecert.examples import load_example
from ssecert.observers import build_observer
from ssecert.stability import thesis_messages
from ssecert.stability.outcomes import (
    AssumptionCode,
    SearchStop,
    SeriesCode,
    SeriesFailure,
    StopCode,
)
from ssecert.stability.thesis import SUBNORMAL_FLOOR, pi_map, thesis_assumptions


def items_of(design):
    verdict, items = thesis_assumptions(design, observability_holds=True)
    return verdict, {i.name: i for i in items}


def test_deadbeat_gain_breaks_lemma_1():
    spec = load_example("ugv")
    verdict, items = items_of(build_observer(spec.system, spec.observer))
    assert verdict == "fails"
    assert items["lemma_1"].code in (AssumptionCode.F_DEADBEAT, AssumptionCode.F_SINGULAR)
    assert items["assumption_2"].verdict == "holds"
    assert items["assumption_3"].verdict == "inconclusive"
    assert items["epsilon_bound"].verdict == "inconclusive"


@pytest.mark.parametrize("poles", [[0.5, 0.6], [0.9, 0.95]])
def test_claimed_lipschitz_constant_has_a_verified_counterexample(poles):
    spec = load_example("ugv")
    design = build_observer(
        spec.system,
        {
            "kind": "elastic_net",
            "gain": "place",
            "poles": poles,
            "step": 0.01,
            "threshold": 0.1,
            "shrink": 0.3,
        },
    )
    _, items = items_of(design)
    lemma = items["lemma_1"]
    assert lemma.verdict == "fails"
    a1, a2 = (np.asarray(lemma.details["counterexample"][k]) for k in ("a1", "a2"))
    L1 = -design.gain.L
    F = spec.system.A + L1 @ spec.system.C
    Finv = np.linalg.inv(F)
    ratio = np.linalg.norm(
        pi_map(a1, Finv, L1, 0.3, 0.1) - pi_map(a2, Finv, L1, 0.3, 0.1)
    ) / np.linalg.norm(a1 - a2)
    claimed = np.linalg.norm(L1, 2) / abs(np.abs(np.linalg.eigvals(F)).max() - 0.3)
    assert ratio > claimed
    # the corrected bound still holds
    assert ratio <= lemma.details["correct_bound"] * (1 + 1e-9)


def test_pi_satisfies_equation_5_9():
    spec = load_example("ugv")
    design = build_observer(
        spec.system,
        {
            "kind": "elastic_net",
            "gain": "place",
            "poles": [0.9, 0.95],
            "step": 0.01,
            "threshold": 0.1,
            "shrink": 0.3,
        },
    )
    L1 = -design.gain.L
    F = spec.system.A + L1 @ spec.system.C
    Finv = np.linalg.inv(F)
    a = np.random.default_rng(0).standard_normal((50, 3))
    psi = 0.3 * np.sign(a) * np.maximum(np.abs(a) - 0.1, 0)
    lhs = F @ pi_map(a, Finv, L1, 0.3, 0.1).T + L1 @ a.T - pi_map(psi, Finv, L1, 0.3, 0.1).T
    assert np.abs(lhs).max() < 1e-10


def test_epsilon_bound_is_sufficient_not_necessary():
    spec = load_example("ugv")
    small = build_observer(
        spec.system,
        {
            "kind": "elastic_net",
            "gain": "place",
            "poles": [0.9, 0.95],
            "step": 0.01,
            "threshold": 0.1,
            "shrink": 0.3,
        },
    )
    large = build_observer(
        spec.system,
        {
            "kind": "elastic_net",
            "gain": "place",
            "poles": [0.9, 0.95],
            "step": 0.5,
            "threshold": 0.1,
            "shrink": 0.3,
        },
    )
    assert items_of(small)[1]["epsilon_bound"].verdict == "holds"
    assert items_of(large)[1]["epsilon_bound"].verdict == "inconclusive"


def test_a_subnormal_plant_leaves_lemma_1_unchecked_instead_of_crashing():
    """F = 1e-320 is invertible in exact arithmetic, but its inverse overflows: Lemma 1 is
    inconclusive (it was an internal error)."""
    from ssecert import analyze, spec_from_dict

    spec = spec_from_dict(
        {
            "name": "subnormal",
            "system": {"A": [[1e-320]], "C": [[1.0], [1.0], [1.0]]},
            "attack": {"max_attacked": 1},
            "observer": {
                "kind": "elastic_net",
                "gain": [[0.0, 0.0, 0.0]],
                "step": 0.5,
                "threshold": 0.1,
                "shrink": 0.5,
            },
        }
    )
    check = analyze(spec)["thesis_assumptions"]
    lemma = check.evidence["lemma_1"]
    assert lemma["verdict"].value == "inconclusive"
    # F's smallest singular value is at the bottom of the floating-point range: Lemma 1 is not
    # checked (the reason of that code with that number)
    smallest = lemma["smallest_singular_value_F"]
    assert 0 < smallest < SUBNORMAL_FLOOR
    words = thesis_messages.reason(AssumptionCode.F_AT_FLOAT_FLOOR, {"smallest": smallest})
    assert lemma["reason"] == words


def test_every_assumption_code_has_words_and_only_failures_a_finding():
    stop = SearchStop(StopCode.DIMENSION, {"dimension": 300, "most": 200})
    facts = {
        "refusal": "REFUSAL", "q": 0.5, "lam": 0.1, "smallest": 1e-300, "claimed": 2.0,
        "ratio": 7.0, "correct": float("inf"),
        "lemma_fails": True, "worst": 1e5, "rho": 0.81, "failure": None, "stopped": stop,
        "step": 0.1,
        "star": 0.05,
    }  # fmt: skip
    for code in AssumptionCode:
        assert thesis_messages.reason(code, facts), code
        finding = thesis_messages.finding(code, facts)
        assert bool(finding) is (code.verdict.value == "fails"), code
    exceeded = thesis_messages.finding(AssumptionCode.LIPSCHITZ_EXCEEDED, facts)
    assert "infinite here" in exceeded and "factor 3.5" in exceeded  # 7 / 2
    assert "dimension 300 (> 200)" in thesis_messages.reason(AssumptionCode.NOT_EVALUATED, facts)
    assert "not finite" in thesis_messages.reason(
        AssumptionCode.NOT_EVALUATED, {"failure": None, "stopped": None}
    )
    # a failure to evaluate comes before a stop, and a Lipschitz search that sampled nothing
    # says why
    overflow = SeriesFailure(SeriesCode.SUM_OVERFLOW)
    both = {**facts, "failure": overflow, "ratio": None}
    assert thesis_messages.reason(AssumptionCode.NOT_EVALUATED, both).endswith(
        "evaluated: the series for Pi overflows"
    )
    assert "no ratio could be sampled: the series for Pi overflows" in thesis_messages.reason(
        AssumptionCode.LIPSCHITZ_NOT_PROVEN, both
    )
    assert "by a factor" in thesis_messages.reason(AssumptionCode.NOT_CONTRACTING, facts)
    assert "0.5 times" in thesis_messages.reason(AssumptionCode.NOT_CONTRACTING, {"worst": 0.5})


def test_every_search_failure_and_stop_has_words():
    facts = {
        "needed": 2e4, "magnitude": 2e4, "threshold": 1.0, "shrink": 1.0, "most": 10_000,
        "memory_mib": None, "terms": 7, "norm_F_inv": 1e300, "dimension": 300,
    }  # fmt: skip
    for code in SeriesCode:
        assert thesis_messages.series_failure(SeriesFailure(code, facts)), code
    for code in StopCode:
        assert thesis_messages.search_stop(SearchStop(code, facts)), code
    limited = thesis_messages.series_failure(
        SeriesFailure(SeriesCode.TOO_MANY_TERMS, {**facts, "memory_mib": 64})
    )
    assert limited.endswith("(the cached powers F^-l L1 are bounded to 64 MiB)")


def test_the_series_says_why_it_cannot_be_summed_as_data():
    """Lemma 1's series reports a point it cannot sum as a code with the numbers, and sums the
    others."""
    from ssecert.stability.pi_series import _PiSeries

    F_inv, L1 = np.array([[2.0]]), np.array([[1.0]])
    values, failure = _PiSeries(F_inv, L1, 1.0, 1.0, max_terms=100)(np.array([[0.5], [500.0]]))
    assert np.isfinite(values[0]).all() and np.isnan(values[1]).all()
    assert failure is not None and failure.code is SeriesCode.TOO_MANY_TERMS
    assert failure.facts["needed"] == 501 and failure.facts["most"] == 100
    values, failure = _PiSeries(np.array([[1e200]]), L1, 1.0, 1.0)(np.array([[5.0]]))
    assert failure is not None and failure.code is SeriesCode.POWERS_OVERFLOW
    assert failure.facts["terms"] == 1 and np.isnan(values).all()
    assert _PiSeries(F_inv, L1, 1.0, 1.0)(np.array([[0.5]]))[1] is None


def test_a_pair_search_writes_its_record():
    """Lemma 1's search record: why nothing was evaluated, or why it stopped and its first
    failure; a later stop (the (5.9) check) only where it had not stopped."""
    from ssecert.stability.counterexample_search import PairSearch

    overflow = SeriesFailure(SeriesCode.SUM_OVERFLOW)
    late = SearchStop(StopCode.BUDGET_EQUATION_5_9)
    none = PairSearch(0, 8, failure=overflow, late_stop=late).evidence()
    assert list(none) == ["pairs_evaluated", "pairs_not_evaluated", "reason", "stopped"]
    assert none["reason"] == "the series for Pi overflows"
    assert none["stopped"] == "the search budget ran out before the (5.9) check"
    some = PairSearch(5, 3, 3, overflow, SearchStop(StopCode.BUDGET_LOCAL), late).evidence()
    assert some == {
        "pairs_evaluated": 5,
        "pairs_not_evaluated": 3,
        "stopped": "the search budget ran out during the local refinement",
        "evaluations_failed": 3,
        "first_failure": "the series for Pi overflows",
    }
    assert PairSearch(0, 8).evidence()["reason"] == "no pair could be evaluated"
