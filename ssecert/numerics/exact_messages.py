"""The words of the exact observability decisions: every sentence written from an ``ExactCode``.

``ssecert.numerics.exact`` returns ``ExactObservability`` outcomes with a
code and the numbers behind it; this module alone writes their reason (read
through ``ExactObservability.reason``, which calls it, and written to JSON),
so that rewording a sentence here changes no decision.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from .outcomes import ExactCode

__all__ = ["reason"]

_WORDS = {
    ExactCode.DECIDED: "",
    ExactCode.NON_FINITE: "non-finite data",
    ExactCode.NO_OUTPUT: "no sensor output: every state is unobservable",
    ExactCode.NO_SENSOR_KEPT: "no sensor kept",
    ExactCode.NO_ROWS: "no rows",
    ExactCode.BEYOND_LIMITS: "beyond the exact limits",
    ExactCode.KERNEL_NOT_FOUND: "rank deficient modulo two primes, but the exact kernel "
    "computation exceeded its budget or found full rank",
    ExactCode.KERNEL_BUDGET: "rank deficient modulo two primes, but no exact kernel vector "
    "within the budget",
    ExactCode.NO_KERNEL_VECTOR: "no exact kernel vector within the budget",
    ExactCode.KERNEL_NOT_VERIFIED: "the exact kernel vector did not verify",
    ExactCode.RANK_MODULO_PRIMES: "Krylov rank below n modulo two primes",
    ExactCode.POWERS_BIT_BUDGET: "the exact powers of A exceed the bit budget",
}


def reason(code: ExactCode, facts: Mapping[str, Any]) -> str:
    """Why an exact decision of ``code`` is what it is (empty for a plain proof)."""
    if code is ExactCode.TOO_LARGE:
        return f"n = {facts['n']} exceeds the exact limit {facts['limit']}"
    return _WORDS[code]
