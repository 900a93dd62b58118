"""The irrepresentable check's words: every code's summary from its facts, in one module."""

from __future__ import annotations

from ssecert.budget import Refusal, Resource
from ssecert.structure import irrepresentable_messages
from ssecert.structure.outcomes import IrrepresentableCode as Code

FACTS = {
    "tau": 3, "rank": 1, "n": 2, "k": 2, "items": 4, "noun": "sensors", "count": 6,
    "max_sets": 5, "refusal": "REFUSAL", "longer_than_n": True, "first": 0, "last": 9, "cause": "X",
    "problem": "PROBLEM", "doubt": "DOUBT.", "label": "y1, y2", "checked": 6, "total": 6,
    "worst": 1.5, "direct": 1.4, "estimate": 0.1, "kappa": 1e3, "counted": "sensors",
    "stopped": None, "exact": None, "band": 1e-9, "accuracy": None, "imprecise_label": "y3, y4",
    "error": 24.0,
}  # fmt: skip

WHAT = "the irrepresentable enumeration (6 supports of 20 rows of the 30 x 3 matrix O_tau)"


def test_every_irrepresentable_code_has_words_and_a_verdict():
    for code in Code:
        exact = 1 if code is Code.EXACTLY_AT_LEAST_ONE else None
        words = irrepresentable_messages.summary(code, {**FACTS, "exact": exact})
        assert words.endswith(".") and "{" not in words, code
    assert {c for c in Code if c.verdict.value == "holds"} == {Code.NO_ATTACK, Code.BELOW_ONE}
    # the accuracy of the worst support is stated beside its names where it is worth it
    accurate = irrepresentable_messages.summary(
        Code.BELOW_ONE, {**FACTS, "worst": 0.5, "accuracy": (0.2, 1e9)}
    )
    assert "y1, y2; relative error about 0.2" in accurate
    cut = irrepresentable_messages.summary(Code.ABOVE_ONE, {**FACTS, "stopped": 1234})
    assert "after 1,234 supports" in cut and "--exact" in cut
    # supports too ill-conditioned to rank: the worst found is a lower bound, or not the worst
    imprecise = {"count": 2, "imprecise_label": "y3, y4", "error": 24.0}
    above = irrepresentable_messages.summary(Code.ABOVE_ONE, {**FACTS, "imprecise": imprecise})
    assert "2 supports' O_Sbar are too ill-conditioned" in above and "at least that" in above
    exactly = irrepresentable_messages.summary(
        Code.EXACTLY_AT_LEAST_ONE, {**FACTS, "exact": 1, "imprecise": imprecise}
    )
    assert "is exactly 1" in exactly and "at least that" in exactly
    below = irrepresentable_messages.summary(Code.IMPRECISE_SUPPORTS, {**FACTS, "worst": 0.5})
    assert "y3, y4, with a relative error estimate of 24" in below
    assert Code.IMPRECISE_SUPPORTS.verdict.value == "inconclusive"


def test_a_doubted_rank_states_its_singular_value():
    smallest = 6.409875621278545e-17
    words = irrepresentable_messages.doubt(
        {"n": 2, "smallest": smallest, "rtol": 1e-15, "band": 1e-13}
    )
    assert f"{smallest:.2g} times its largest" in words
    assert "within the precision of its data" in words
    overflowing = irrepresentable_messages.doubt({"n": 2, "overflow": True})
    assert "rows overflow" in overflowing and "rank 2 modulo a prime" in overflowing


def test_a_refused_scan_states_its_need_its_budget_and_the_shorter_horizon():
    memory = Refusal(WHAT, Resource.MEMORY, 9.6e9, 2 * 2**30)
    words = irrepresentable_messages.summary(
        Code.OVER_BUDGET, {"refusal": memory, "longer_than_n": True}
    )
    assert words.startswith("Not attempted: " + WHAT)
    assert "needs about" in words and "memory budget of 2 GiB" in words
    assert "--horizon" in words
    small = Refusal(WHAT, Resource.MEMORY, 9.6e9, 8 * 2**20)
    within_n = irrepresentable_messages.summary(
        Code.OVER_BUDGET, {"refusal": small, "longer_than_n": False}
    )
    assert "memory budget of 8 MiB" in within_n and "--horizon" not in within_n


def test_too_many_supports_are_counted_in_scientific_notation():
    words = irrepresentable_messages.summary(
        Code.TOO_MANY_SUPPORTS, {"items": 400, "k": 200, "count": 10**119.3, "max_sets": 1000}
    )
    assert "C(400, 200) = " in words and "e+119" in words
    assert "budget of 1,000" in words and "--max-sets" in words


def test_the_irrepresentable_budget_counts_the_supports_exactly():
    # C(20, 3) = 1,140 read as 10 ** log10, rounded down: "1,139 supports exceed 1,139"
    import numpy as np

    from ssecert import System, irrepresentable

    C = np.random.default_rng(0).standard_normal((20, 4))
    check = irrepresentable(System(np.eye(4), C), 3, max_sets=1139)
    assert "C(20, 3) = 1,140 supports exceed the budget of 1,139" in check.summary
