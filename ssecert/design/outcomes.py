"""How the design steps end, as codes and numbers the code decides on (their words:
``synthesis_messages`` and ``search_messages``)."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

__all__ = ["DecayChoice", "DecayCode", "SynthesisCode"]


class SynthesisCode(Enum):
    """How a synthesis ended (the numbers its words need are on ``GainSynthesis``)."""

    SOLVED = "solved"  # a gain; ``solver`` is the solver's status
    NOT_SOLVED = "not solved"  # the solver's status (``solver``) says no solution
    REFUSED = "refused"  # the LMI's interior-point system over the memory budget (``refusal``)
    SOLVER_FAILED = "solver failed"  # the solver raised (``solver``: the exception's type)
    NOT_FINITE = "not finite"  # the solver's gain has a non-finite entry
    TIME_LIMIT = "time limit"  # the bisection's time limit came before a feasible decay
    NO_DECAY = "no decay"  # no decay above ``decay`` is feasible


class DecayCode(Enum):
    """Which rule chose the decay a design imposes (``choose_decay``, ``choose_noise_decay``)."""

    TOO_FEW_POINTS = "too few points"  # fewer than two verified points: the default decay
    TWICE_AS_FAST = "twice as fast"  # the smallest gain contracting by rho(A)^2 or faster
    KNEE = "knee"  # the knee of the front's points faster than the plant
    FEW_FASTER = "few faster"  # the smallest gain of fewer than three points faster
    FASTEST = "fastest"  # none faster than the plant: the fastest point
    NO_NOISE_BOUND = "no noise bound"  # no point with a certified noise bound: the default
    SMALLEST_NOISE_BOUND = "smallest noise bound"  # among the points faster than the plant
    FASTEST_NOISE_BOUND = "fastest noise bound"  # none faster than the plant: the fastest
    NO_NOISE = "no noise"  # every noise bound 0: the gain objective's rule (``then``)


@dataclass(frozen=True)
class DecayChoice:
    """The decay a design imposes, read off the trade-off front, and the rule and numbers
    that chose it (why, in words: ``search_messages.decay_text``).

    ``contraction`` is the chosen point's certified error contraction per step (None for the
    default decay); ``verified`` and ``faster`` count the front's verified points and those
    faster than the plant; ``fastest`` is the smallest contraction of the verified points;
    ``noise_bound`` the chosen point's certified bound under noise; ``then`` the gain
    objective's choice a noise-free front fell back on.
    """

    alpha: float
    code: DecayCode
    plant_radius: float
    plant_stable: bool
    contraction: float | None = None
    verified: int = 0
    faster: int = 0
    fastest: float | None = None
    noise_bound: float | None = None
    then: DecayChoice | None = None
