"""How the design steps end, as codes the code decides on (their words: ``synthesis_messages``)."""

from __future__ import annotations

from enum import Enum

__all__ = ["SynthesisCode"]


class SynthesisCode(Enum):
    """How a synthesis ended (the numbers its words need are on ``GainSynthesis``)."""

    SOLVED = "solved"  # a gain; ``solver`` is the solver's status
    NOT_SOLVED = "not solved"  # the solver's status (``solver``) says no solution
    REFUSED = "refused"  # the LMI's interior-point system over the memory budget (``refusal``)
    SOLVER_FAILED = "solver failed"  # the solver raised (``solver``: the exception's type)
    NOT_FINITE = "not finite"  # the solver's gain has a non-finite entry
    TIME_LIMIT = "time limit"  # the bisection's time limit came before a feasible decay
    NO_DECAY = "no decay"  # no decay above ``decay`` is feasible
