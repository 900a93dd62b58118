"""The sparse-observability methods' problems: codes and numbers, words from one module."""

from __future__ import annotations

import pytest

from ssecert.structure.outcomes import Problem, ProblemCode
from ssecert.structure.sparse_messages import problem_text, problem_texts

FACTS = {
    ProblemCode.EIGENVALUES: {"text": "eigenvalues 1 and 1.0000001 are too close to group"},
    ProblemCode.EIGENSPACE: {"eigenvalue": "0.5", "text": "the time budget ended"},
    ProblemCode.NOT_EXACT: {"support": (1, 2), "distance": "2^-52"},
    ProblemCode.BORDERLINE_SUBSPACE: {"sensors": (3,)},
    ProblemCode.TIME_BEFORE_LEVEL: {"budget": 5.0, "sets": 167960, "removed": 11, "seconds": 40.0},
    ProblemCode.SET_BUDGET: {"max_sets": 1000, "removed": 1, "rest": "; the rest: 2 s"},
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
    one = problem_text(Problem.of(ProblemCode.SET_BUDGET, max_sets=10, removed=1, rest=""))
    two = problem_text(Problem.of(ProblemCode.SET_BUDGET, max_sets=10, removed=2, rest=""))
    assert one.endswith("1 sensor") and two.endswith("2 sensors")
    assert problem_texts([]) == []
