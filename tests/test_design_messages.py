"""The words of ``ssecert design``: why no design was certified, and how the designs compare."""

from __future__ import annotations

from ssecert.design.search_messages import comparison_summary, comparison_words, no_design_text


def test_no_design_names_the_kind_the_rejections_and_the_modes():
    words = no_design_text("dsso", 3, ["iss_gain fails", "not certified"], [])
    assert words == "no dsso design of the 3 tried was certified: iss_gain fails; not certified"
    unstable = no_design_text("sso", 1, ["not certified"], [1.5, complex(0, 1.25)])
    assert unstable.endswith(
        "; the plant has an unobservable mode that is not stable (eigenvalue 1.5, 0+1.25j): "
        "no observer's error can converge"
    )


def test_the_comparison_counts_the_scenarios_and_names_those_not_compared():
    worse = comparison_summary(True, 3, 1, ["a"], ["b", "skipped"], None)
    assert "||x_hat - x||" in worse and "horizon is worse than" in worse
    assert "1 of 1 scenarios compared (a)" in worse
    assert "Not compared (b, skipped)" in worse
    no_worse = comparison_summary(True, 2, 2, [], [], None)
    assert "||x_hat - x||" in no_worse and "is no worse" in no_worse
    assert "in every one of the 2 scenarios compared" in no_worse
    assert "is worse than" not in no_worse and "Not compared" not in no_worse
    # the tie rule the words rest on is said where they are (a 2.4% larger error is a tie)
    assert "no worse (within 5%, or smaller)" in no_worse and "(more than 5% larger)" in worse
    assert comparison_words("no worse") == "no worse (within 5%)"
    assert comparison_words("worse") == "worse (more than 5% larger)"


def test_the_comparison_without_a_design_scenarios_or_finite_errors():
    alone = comparison_summary(False, 2, 0, [], ["a"], None)
    assert alone == "The spec has no observer of its own: the synthesised design alone is shown."
    assert comparison_summary(True, 0, 0, [], [], None).startswith("The spec has no scenarios")
    assert comparison_summary(True, 1, 0, [], [], None).startswith("No scenario was simulated")


def test_the_comparison_says_when_the_spec_design_has_the_smaller_noise_bound():
    words = comparison_summary(True, 1, 1, [], [], (0.5, 2.25))
    assert words.endswith(
        " The spec's own design has the smaller certified ultimate error under the noise "
        "(0.5 against 2.25)."
    )


def test_the_comparison_says_when_the_spec_design_has_the_larger_region():
    words = comparison_summary(True, 1, 1, [], [], None, (14.142, 7.071))
    assert words.endswith(
        " The spec's own design has the larger certified region of attraction (radius 14.14 "
        "against 7.071)."
    )
    none = comparison_summary(True, 1, 1, [], [], None, (0.5, 0.0))
    assert none.endswith("(radius 0.5 against 0 (none certified)).")
