"""Typed outcomes of the exact-arithmetic decisions: codes and numbers, no words.

``ssecert.numerics.exact`` returns ``ExactObservability`` outcomes whose
``ExactCode`` says why a decision is what it is; their words are written in
``ssecert.numerics.exact_messages``.
"""

from __future__ import annotations

import enum

__all__ = ["ExactCode"]


class ExactCode(enum.Enum):
    """Why an exact observability decision came out as it did (``ExactObservability.code``)."""

    #: decided by a proof with nothing more to say (a Krylov rank n modulo a prime, or an
    #: exact kernel vector re-checked in integers)
    DECIDED = "decided"
    #: the state dimension is above the exact limit (``n``, ``limit``)
    TOO_LARGE = "too large"
    #: the data have a non-finite entry
    NON_FINITE = "non-finite data"
    #: no sensor output at all: every state is unobservable
    NO_OUTPUT = "no output"
    #: no sensor kept (a removal of every sensor)
    NO_SENSOR_KEPT = "no sensor kept"
    #: no row of the observability matrix asked
    NO_ROWS = "no rows"
    #: the sizes are beyond what the exact plant decides
    BEYOND_LIMITS = "beyond the limits"
    #: rank deficient modulo two primes; the kernel computation exceeded its budget or found
    #: full rank
    KERNEL_NOT_FOUND = "kernel not found"
    #: rank deficient modulo two primes; no exact kernel vector within the budget
    KERNEL_BUDGET = "kernel budget"
    #: no exact kernel vector of the rows asked within the budget
    NO_KERNEL_VECTOR = "no kernel vector"
    #: an exact kernel vector that did not verify (a bug if it ever happens)
    KERNEL_NOT_VERIFIED = "kernel not verified"
    #: unobservable from the Krylov ranks modulo two primes, without an exact kernel vector
    RANK_MODULO_PRIMES = "rank modulo primes"
    #: the exact powers of A exceed the bit budget
    POWERS_BIT_BUDGET = "powers bit budget"
