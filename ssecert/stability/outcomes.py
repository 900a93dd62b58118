"""Typed outcomes of the stability analyses: data and a reason code, no words.

An analysis returns one of these; the words a user reads are written from
it where its ``Check`` is built (``ssecert.stability.region_messages`` for
the region of attraction), so that a decision is always taken on a code
and a sentence can be reworded without changing any verdict.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from ..results import Verdict

__all__ = ["LMICode", "Region", "RegionCode", "WitnessKind"]


class LMICode(enum.Enum):
    """How an LMI certificate (``ssecert.stability.lmi.LMICertificate``) came out."""

    #: holds: solved here and verified in numpy
    VERIFIED = "verified"
    #: holds: a neighbouring design's certificate, verified for this one without a solve
    REUSED = "reused"
    #: a budget or a size refused the solve before it began
    NOT_ATTEMPTED = "not attempted"
    #: structural facts decided before any LMI (an unstable or undecidable linear part, a
    #: sector vertex within rounding of 1, no nonlinearity): no LMI was solved
    DECIDED_BEFORE = "decided before the LMIs"
    #: LMIs solved (their attempts recorded), none verified: this does not show instability
    NOT_VERIFIED = "not verified"
    #: no certificate to build on (an ISS gain without a verified circle certificate)
    NO_BASE = "no certificate to build on"
    #: a certificate that floating point cannot write in the coordinates asked
    NOT_REPRESENTABLE = "not representable"


class WitnessKind(enum.StrEnum):
    """What proves an observer unstable (the ``kind`` of a failing observer_stability's witness,
    and of a failing cell of the region map); its value is what the JSON shows."""

    #: the dead zone's own linear dynamics are unstable (a region map's cell)
    LOCAL_INSTABILITY = "local instability"
    #: the large-signal loop diverges along an eigenvector, replayed
    DIVERGENT_TRAJECTORY = "divergent trajectory"
    #: a nonzero equilibrium without attack, confirmed exactly
    NONZERO_EQUILIBRIUM = "nonzero equilibrium"
    #: a periodic orbit without attack, confirmed exactly
    PERIODIC_ORBIT = "periodic orbit"


class RegionCode(enum.Enum):
    """Why a region of attraction has the radius it has.

    ``CERTIFIED`` and ``PIECEWISE_CERTIFIED`` come with a positive radius;
    every other code with radius 0.  Only ``DEAD_ZONE_UNSTABLE`` proves that
    no region exists (the dead zone's own linear dynamics are unstable).
    """

    #: the largest invariant sublevel set of the dead zone's Lyapunov function
    CERTIFIED = "certified"
    #: a verified piecewise-quadratic Lyapunov function over the soft threshold's regions
    PIECEWISE_CERTIFIED = "piecewise certified"
    #: a budget (or a size the search refuses) stopped it before it began
    NOT_ATTEMPTED = "not attempted"
    #: the observer has no dead zone (no soft threshold, or a threshold of 0)
    NO_DEAD_ZONE = "no dead zone"
    #: the dead zone's linear dynamics are proved unstable: no region exists
    DEAD_ZONE_UNSTABLE = "dead zone unstable"
    #: the dead zone's linear dynamics have no verified Lyapunov matrix
    NO_VERIFIED_LYAPUNOV = "no verified Lyapunov matrix"
    #: the dead zone's level set is beyond the floating-point range
    LEVEL_OUT_OF_RANGE = "level set out of range"
    #: no sublevel set of positive size fits in the dead zone
    NO_INVARIANT_SET = "no invariant sublevel set"
    #: the exact re-check of P, the level and the radius refuted one of its facts
    EXACT_RECHECK_FAILED = "exact re-check failed"
    #: a simulated initial error on the certified sphere left the invariant set
    REPLAY_LEFT_SET = "replay left the set"
    #: the piecewise search: the ball it would search is beyond the floating-point range
    BALL_OUT_OF_RANGE = "ball out of range"
    #: the piecewise search: every radius it would try is within the one already certified
    WITHIN_FLOOR = "within the floor"
    #: the piecewise search: the regions' maps are beyond the floating-point range
    MAPS_OUT_OF_RANGE = "maps out of range"
    #: the piecewise search: no radius's LMIs were solved and verified
    NO_PIECEWISE_FUNCTION = "no piecewise function"
    #: the piecewise search: a simulated initial error inside its radius did not converge
    PIECEWISE_REPLAY_FAILED = "piecewise replay failed"
    #: a simulated initial error run through the observer's own simulator left the dead zone
    SIMULATOR_REPLAY_FAILED = "simulator replay failed"


@dataclass(frozen=True)
class Region:
    """A certified region of attraction, or why there is none.

    Attributes
    ----------
    radius : float
        The certified radius of initial estimation errors (a_hat(0) = 0);
        0 when none is certified.
    code : RegionCode
    facts : mapping
        The numbers and names the words of ``code`` need (a refusal, the
        threshold, the floor, the Lyapunov analysis's reason, the facts an
        exact re-check refuted); not written to JSON.
    evidence : mapping
        What the certificate's JSON shows beside the reason, in order (P,
        the level, the replay, the attempts...).  A value that is itself a
        ``Region`` (``"piecewise"``: the search that did not widen the
        region) is written as its own record.
    """

    radius: float
    code: RegionCode
    facts: Mapping[str, Any] = field(default_factory=dict)
    evidence: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        certified = self.code in (RegionCode.CERTIFIED, RegionCode.PIECEWISE_CERTIFIED)
        if certified != (self.radius > 0):
            raise ValueError(f"a region with code {self.code.value!r} and radius {self.radius!r}")

    @property
    def verdict(self) -> Verdict:
        """Holds with a positive radius, fails when the dead zone is proved unstable,
        inconclusive otherwise."""
        if self.radius > 0:
            return Verdict.HOLDS
        if self.code is RegionCode.DEAD_ZONE_UNSTABLE:
            return Verdict.FAILS
        return Verdict.INCONCLUSIVE

    @property
    def unstable(self) -> bool | None:
        """Whether the dead zone's linear dynamics are proved unstable: True or False where
        its Lyapunov analysis decided nothing else, None where it was not the reason."""
        if self.code is RegionCode.DEAD_ZONE_UNSTABLE:
            return True
        if self.code is RegionCode.NO_VERIFIED_LYAPUNOV:
            return False
        return None

    @classmethod
    def none(
        cls, code: RegionCode, evidence: Mapping[str, Any] | None = None, **facts: Any
    ) -> Region:
        """Radius 0 for the reason ``code``, with the facts its words need."""
        return cls(0.0, code, facts, dict(evidence or {}))
