"""The sparse-observability methods' problems: codes and numbers, words from one module."""

from __future__ import annotations

import pytest

from ssecert.structure.outcomes import Problem, ProblemCode
from ssecert.structure.sparse_messages import (
    placement_text,
    problem_text,
    problem_texts,
    undecided_summary,
)

FACTS = {
    ProblemCode.EIGENVALUES: {"text": "eigenvalues 1 and 1.0000001 are too close to group"},
    ProblemCode.EIGENSPACE: {"eigenvalue": "0.5", "text": "the time budget ended"},
    ProblemCode.NOT_EXACT: {"support": (1, 2), "distance": "2^-52"},
    ProblemCode.BORDERLINE_SUBSPACE: {"sensors": (3,)},
    ProblemCode.TIME_BEFORE_LEVEL: {"budget": 5.0, "sets": 167960, "removed": 11, "seconds": 40.0},
    ProblemCode.SET_BUDGET: {
        "max_sets": 1000,
        "removed": 1,
        "seconds": 2.0,
        "workers": 3,
        "time_budget": 5.0,
    },
    ProblemCode.WORKERS_FAILED: {"removed": 4, "first": 0, "last": 99, "cause": "KilledWorker()"},
    ProblemCode.TIME_WITHIN_LEVEL: {"budget": 1.0, "checked": 10, "sets": 100, "removed": 3},
    ProblemCode.BORDERLINE_SETS: {"count": 2, "removed": 3},
    ProblemCode.WITHIN_PRECISION: {"sensors": (0, 1), "others": 0, "distance": None},
    ProblemCode.SMALLER_BY_ENUMERATION: {"exact": True, "size": 2, "eigenspace_size": 3},
    ProblemCode.MISSED_BY_ENUMERATION: {"size": 2, "sensors": (0, 4)},
}


@pytest.mark.parametrize("code", list(ProblemCode))
def test_every_problem_has_words_with_its_numbers(code):
    words = problem_text(Problem(code, FACTS[code]))
    assert words and words == words.strip()
    for value in FACTS[code].values():
        if isinstance(value, int) and not isinstance(value, bool) and value > 1:
            assert f"{value:,}" in words or str(value) in words, (code, value)


def test_the_words_follow_the_numbers():
    past = {"seconds": None, "workers": None, "time_budget": None}
    one = problem_text(Problem.of(ProblemCode.SET_BUDGET, max_sets=10, removed=1, **past))
    two = problem_text(Problem.of(ProblemCode.SET_BUDGET, max_sets=10, removed=2, **past))
    assert one.endswith("1 sensor") and two.endswith("2 sensors")
    assert problem_texts([]) == []


def test_a_refusal_over_the_set_budget_quotes_the_time_the_rest_would_take():
    alone = {"max_sets": 1000, "removed": 3, "seconds": 12.5, "workers": None, "time_budget": 5.0}
    words = problem_text(Problem(ProblemCode.SET_BUDGET, alone))
    assert words.startswith("enumeration budget of 1,000 sets reached before sets of 3 sensors")
    assert "would take about 12.5 s here" in words and "Dask" not in words
    assert words.endswith("; --max-sets raises the budget)")
    spread = problem_text(Problem(ProblemCode.SET_BUDGET, {**alone, "workers": 1200}))
    assert "about 1,200 Dask workers would take them under 5 s" in spread


def test_the_time_budget_points_to_the_exact_value():
    before = {"budget": 0.0, "sets": 220, "removed": 3, "seconds": 0.5}
    within = {"budget": 0.5, "checked": 1234, "sets": 65780, "removed": 4}
    for code, facts in [
        (ProblemCode.TIME_BEFORE_LEVEL, before),
        (ProblemCode.TIME_WITHIN_LEVEL, within),
    ]:
        words = problem_text(Problem(code, facts))
        assert "time budget" in words and words.endswith("--exact computes the exact value")
    cut = problem_text(Problem(ProblemCode.TIME_WITHIN_LEVEL, within))
    assert "after 1,234 of the 65,780 sets of 4 sensors" in cut


def test_the_workers_failure_names_the_range():
    facts = {"removed": 2, "first": 0, "last": 1_499, "cause": "RuntimeError('worker lost')"}
    words = problem_text(Problem(ProblemCode.WORKERS_FAILED, facts))
    assert "failed twice on the sets of 2 sensors at positions 0 to 1,499" in words


def test_an_undecided_check_names_the_sets_still_needed_and_the_option():
    words = undecided_summary(["first reason", "second reason"], 12_345)
    assert words.startswith("Sparse observability could not be decided: first reason; second")
    assert "About 12,345 more sensor sets are needed" in words and "--max-sets" in words
    assert "--max-sets" not in undecided_summary(["first reason"], None)


def test_placement_names_the_levels_in_process_and_on_the_workers():
    words = placement_text({6: 6}, [0, 1, 2, 3, 4, 5], 500_000, 20)
    assert words.startswith(
        "Dask workers: the sets of 6 sensors in 6 ranges; in-process: the sets of 0 to 5 sensors;"
    )
    assert "ranges of at least 500,000 sets and 20 times the partial sums" in words
    # levels split alike are named together; a run with no level on the workers says so
    many = placement_text({2: 8, 3: 8, 4: 8, 5: 6}, [0, 1], 500_000, 20)
    assert many.startswith(
        "Dask workers: the sets of 2 to 4 sensors in 8 ranges each; the sets of 5 sensors in "
        "6 ranges; in-process: the sets of 0 and 1 sensors;"
    )
    small = placement_text({}, [0, 1, 2], 500_000, 20)
    assert small.startswith("every level ran in-process (the sets of 0 to 2 sensors), none on")
    assert placement_text({1: 2, 2: 2}, [], 500_000, 20) == (
        "Dask workers: the sets of 1 and 2 sensors in 2 ranges each"
    )
