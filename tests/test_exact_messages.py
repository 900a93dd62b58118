"""Exact observability decisions: decided on codes, worded apart (``numerics.exact_messages``)."""

import numpy as np
import pytest

from ssecert.numerics import exact_messages
from ssecert.numerics.exact import Observability, exact_observability, exact_stacked_rank
from ssecert.numerics.outcomes import ExactCode


@pytest.mark.parametrize(
    ("A", "C", "state", "code"),
    [
        (
            np.eye(2),
            np.array([[1.0, 0.0], [0.0, 1.0]]),
            Observability.OBSERVABLE,
            ExactCode.DECIDED,
        ),
        # two copies of one direction: the second state is never seen, found exactly
        (
            np.eye(2),
            np.array([[1.0, 0.0], [2.0, 0.0]]),
            Observability.UNOBSERVABLE,
            ExactCode.DECIDED,
        ),
        (np.eye(2), np.zeros((1, 2)), Observability.UNOBSERVABLE, ExactCode.NO_OUTPUT),
        (np.eye(2), np.array([[np.nan, 0.0]]), Observability.UNKNOWN, ExactCode.NON_FINITE),
        (np.eye(61), np.eye(61)[:1], Observability.UNKNOWN, ExactCode.TOO_LARGE),
    ],
)
def test_each_exact_code_is_reached_by_a_plant_known_by_construction(A, C, state, code):
    result = exact_observability(A, C)
    assert result.state is state and result.code is code
    if state is Observability.UNOBSERVABLE and code is ExactCode.DECIDED:
        z = np.array(result.z_exact, dtype=float)
        assert np.all(C @ z == 0) and np.any(z)
    record = result.to_dict()
    assert record.get("reason", "") == result.reason


def test_too_large_carries_its_numbers_and_rows_have_their_own_codes():
    big = exact_observability(np.eye(61), np.eye(61)[:1])
    assert big.facts == {"n": 61, "limit": 60}
    assert exact_stacked_rank(np.eye(2), np.eye(2), [], 1).code is ExactCode.NO_ROWS


def test_every_exact_code_has_words_and_only_a_proof_has_none():
    for code in ExactCode:
        words = exact_messages.reason(code, {"n": 70, "limit": 60})
        assert bool(words) is (code is not ExactCode.DECIDED), code
    assert exact_messages.reason(ExactCode.TOO_LARGE, {"n": 70, "limit": 60}) == (
        "n = 70 exceeds the exact limit 60"
    )
