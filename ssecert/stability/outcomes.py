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

__all__ = [
    "known",
    "AssumptionCode",
    "LMICause",
    "LMICode",
    "LyapunovCode",
    "Region",
    "RegionCode",
    "SchurCode",
    "SchurState",
    "SearchCode",
    "SearchStop",
    "Searched",
    "SeriesCode",
    "SeriesFailure",
    "StopCode",
    "VerifyCode",
    "VerifyProblem",
    "WitnessKind",
]


class SchurState(enum.StrEnum):
    """Whether every eigenvalue of F lies inside the unit circle: its value is the word written
    in evidence and JSON."""

    STABLE = "stable"
    UNSTABLE = "unstable"
    UNKNOWN = "unknown"


class SchurCode(enum.Enum):
    """What decided a ``SchurDecision`` (``ssecert.stability.spectral``; its words:
    ``ssecert.stability.spectral_messages``)."""

    #: F has a non-finite entry: nothing is decided
    NON_FINITE = "non-finite"
    #: stable: rho <= ||F^m||^(1/m) < 1 for an exact power m
    POWERS_STABLE = "exact powers"
    #: unstable: |trace F^m| > n exactly, by less than a float resolves
    TRACE_EXCESS = "exact trace excess"
    #: unstable: |trace F^m| = n exactly, so rho >= 1
    TRACE_REACHES_N = "exact trace reaches n"
    #: unstable: (|trace F^m| / n)^(1/m) > 1, a float lower bound of rho
    TRACES_BELOW = "exact traces"
    #: unstable: F - lambda I has an exact kernel vector for a float lambda of modulus >= 1
    EIGENVALUE_ON_CIRCLE = "exact eigenvalue"
    #: stable: the exact characteristic polynomial passes the Schur-Cohn test, also scaled to
    #: a radius 1 - 2^-j (rho < 1 - 2^-j), where no exact power decides it
    SCHUR_COHN_STABLE = "exact Schur-Cohn test"
    #: unstable: the exact characteristic polynomial fails the Schur-Cohn test (an eigenvalue
    #: of modulus >= 1)
    SCHUR_COHN_FAILS = "exact Schur-Cohn test fails"
    #: unstable (not rigorous): the dominant eigenvalue clears 1 by its first-order bound
    FIRST_ORDER = "first-order eigenvalue bound"
    #: nothing decides it
    UNDECIDED = "undecided"

    @property
    def state(self) -> SchurState:
        """The state this code decides."""
        if self in (SchurCode.POWERS_STABLE, SchurCode.SCHUR_COHN_STABLE):
            return SchurState.STABLE
        if self in (SchurCode.NON_FINITE, SchurCode.UNDECIDED):
            return SchurState.UNKNOWN
        return SchurState.UNSTABLE

    @property
    def rigorous(self) -> bool:
        """Whether the decision rests on exact arithmetic only."""
        return self not in (SchurCode.NON_FINITE, SchurCode.FIRST_ORDER, SchurCode.UNDECIDED)


class LyapunovCode(enum.Enum):
    """What came of the Lyapunov solution of a ``LyapunovCertificate``
    (``ssecert.stability.lyapunov``; its words: ``ssecert.stability.lyapunov_messages``).
    Every code but ``VERIFIED`` leaves the verdict to the exact decision on F."""

    #: P solves the equation and verifies with a margin: holds
    VERIFIED = "verified"
    #: the Lyapunov operator is singular (lambda_i lambda_j = 1): no unique solution
    NO_UNIQUE_SOLUTION = "no unique solution"
    #: the solver returned a non-finite P
    NOT_FINITE = "not finite"
    #: P was found but P or its decrease is not positive definite by a margin
    NOT_VERIFIED = "not verified"


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


class LMICause(enum.Enum):
    """Why an LMI certificate came out as it did, with the numbers in its ``facts`` (its words:
    ``ssecert.stability.lmi_messages``).  The checks decide on ``LMICode``; the cause is for
    the words and for tests."""

    #: holds: nothing to explain
    CERTIFIED = "certified"
    #: a budget refused the solve (``facts["refusal"]``)
    REFUSED = "refused"
    #: the error dynamics' matrices leave the float range
    NOT_FINITE = "not finite"
    #: F = A - L C is proved unstable (``decision``: the exact decision's words, ``channels``)
    ERROR_MATRIX_UNSTABLE = "error matrix unstable"
    #: F's spectral radius is within rounding of 1 and undecided (``radius``, ``decision``)
    ERROR_MATRIX_UNDECIDED = "error matrix undecided"
    #: the sector's vertex loop has spectral radius within rounding of 1 (``q``, ``radius``,
    #: ``decision``)
    VERTEX_WITHIN_ROUNDING = "vertex within rounding of 1"
    #: shrink = 1: the sector contains the identity (``radius``)
    IDENTITY_IN_SECTOR = "identity in the sector"
    #: the sector's vertex loop is unstable (``q``, ``decision``)
    VERTEX_UNSTABLE = "vertex unstable"
    #: a corner of the channels' sectors has an unstable loop (``corner``)
    CORNER_UNSTABLE = "corner unstable"
    #: the model has no nonlinearity for a multiplier to act on
    NO_NONLINEARITY = "no nonlinearity"
    #: the circle criterion's LMIs were solved, none verified (``attempts``)
    CIRCLE_NOT_VERIFIED = "circle not verified"
    #: the dissipation (ISS) LMIs were solved, none verified (``attempts``)
    DISSIPATION_NOT_VERIFIED = "dissipation not verified"
    #: the Zames-Falb LMIs were solved, none verified (``attempts``)
    ZAMES_FALB_NOT_VERIFIED = "Zames-Falb not verified"
    #: the Zames-Falb gain's LMI has no solution (``order``, ``status``)
    ZAMES_FALB_NO_DISSIPATION = "Zames-Falb no dissipation"
    #: the Zames-Falb gain was solved and not verified (``problem``)
    ZAMES_FALB_GAIN_NOT_VERIFIED = "Zames-Falb gain not verified"
    #: a balanced certificate's P leaves the float range
    P_OUT_OF_RANGE = "P out of range"
    #: a balanced certificate does not scale back to the spec's coordinates exactly
    NOT_SCALED_BACK = "not scaled back"
    #: an ISS gain without a verified circle certificate to build on
    NO_BASE = "no base"
    #: the circle certificate's dissipation matrix leaves the float range
    DISSIPATION_OUT_OF_RANGE = "dissipation out of range"
    #: no scaling of the circle certificate gives a finite gain
    NO_FINITE_GAIN = "no finite gain"
    #: the gain from the circle certificate was not verified (``problem``)
    GAIN_NOT_VERIFIED = "gain not verified"


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
        return Verdict.of(holds=self.radius > 0, fails=self.code is RegionCode.DEAD_ZONE_UNSTABLE)

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


class AssumptionCode(enum.Enum):
    """Why an item of the thesis's chain of assumptions (``ssecert.stability.thesis``) has its
    verdict, with the numbers in the item's facts (its words:
    ``ssecert.stability.thesis_messages``)."""

    #: a budget refused the p x p work (``refusal``)
    NOT_ATTEMPTED = "not attempted"
    #: Assumption 1: the observability check did not run
    NOT_CHECKED = "not checked"
    #: Assumption 1 holds: (A, C) is observable
    OBSERVABLE = "observable"
    #: Assumption 1 fails: (A, C) is not observable
    NOT_OBSERVABLE = "not observable"
    #: Assumption 2 holds for the shrinkage with Q = I (``q``, ``lam``)
    SHRINKAGE = "shrinkage"
    #: Lemma 1: F's smallest singular value at the bottom of the float range (``smallest``)
    F_AT_FLOAT_FLOOR = "F at the float floor"
    #: Lemma 1 fails: a deadbeat gain makes F nilpotent, hence singular (``smallest``)
    F_DEADBEAT = "F nilpotent"
    #: Lemma 1: F singular to rounding, not shown singular exactly (``smallest``)
    F_SINGULAR_TO_ROUNDING = "F singular to rounding"
    #: Lemma 1 fails: F singular exactly (``smallest``)
    F_SINGULAR = "F singular"
    #: Lemma 1 fails: the claimed Lipschitz constant is exceeded (``claimed``, ``factor``,
    #: ``ratio``, ``correct``)
    LIPSCHITZ_EXCEEDED = "Lipschitz constant exceeded"
    #: Lemma 1 holds: the series' bound is at most the claimed constant (``correct``,
    #: ``claimed``)
    LIPSCHITZ_PROVEN = "Lipschitz constant proven"
    #: Lemma 1: Pi exists, the claimed constant is not proven (``claimed``, ``correct``,
    #: ``ratio`` or ``search``: why none was sampled)
    LIPSCHITZ_NOT_PROVEN = "Lipschitz constant not proven"
    #: Assumption 3: Pi is not available (``lemma_fails``: Lemma 1 failed)
    NO_PI = "no Pi"
    #: Assumption 3 fails: a sampled a_hat with ratio >= 1 (``worst``)
    NOT_CONTRACTING = "not contracting"
    #: Assumption 3 holds with rho'' < 1 (``rho``)
    CONTRACTING = "contracting"
    #: Assumption 3: no proof and no sample evaluated (``why``)
    NOT_EVALUATED = "not evaluated"
    #: Assumption 3: no counterexample and no proof (``worst``)
    NO_PROOF = "no proof"
    #: the epsilon bound needs Lemma 1 and Assumption 3
    NEEDS_LEMMA = "needs Lemma 1"
    #: the epsilon bound: F is not certified stable
    F_NOT_CERTIFIED = "F not certified"
    #: the epsilon bound holds: step <= epsilon* (``step``, ``star``)
    STEP_WITHIN = "step within epsilon*"
    #: the epsilon bound is not met (sufficient, not necessary) (``step``, ``star``)
    STEP_ABOVE = "step above epsilon*"

    @property
    def verdict(self) -> Verdict:
        """The verdict this code gives."""
        return Verdict.of(holds=self in _ASSUMPTION_HOLDS, fails=self in _ASSUMPTION_FAILS)


_ASSUMPTION_HOLDS = frozenset(
    {
        AssumptionCode.OBSERVABLE,
        AssumptionCode.SHRINKAGE,
        AssumptionCode.LIPSCHITZ_PROVEN,
        AssumptionCode.CONTRACTING,
        AssumptionCode.STEP_WITHIN,
    }
)
_ASSUMPTION_FAILS = frozenset(
    {
        AssumptionCode.NOT_OBSERVABLE,
        AssumptionCode.F_DEADBEAT,
        AssumptionCode.F_SINGULAR,
        AssumptionCode.LIPSCHITZ_EXCEEDED,
        AssumptionCode.NOT_CONTRACTING,
    }
)


class SeriesCode(enum.Enum):
    """Why a point of the thesis's counterexample searches could not be evaluated (the series
    for Lemma 1's map Pi, ``ssecert.stability.pi_series``; words:
    ``thesis_messages.series_failure``)."""

    #: a point needs more terms of the series than are summed (facts: needed, magnitude,
    #: threshold, shrink, most, memory_mib or None when the limit is the term count's)
    TOO_MANY_TERMS = "too many terms"
    #: the cached powers of F^-1 overflow before the terms a point needs (facts: terms,
    #: norm_F_inv, magnitude, needed)
    POWERS_OVERFLOW = "powers overflow"
    #: the summed series is not finite
    SUM_OVERFLOW = "sum overflows"
    #: the searched ratio is not finite, the series being fine
    RATIO_NOT_FINITE = "ratio not finite"


@dataclass(frozen=True)
class SeriesFailure:
    """The first reason a batch of points of a search could not be evaluated: a code and the
    numbers its words need."""

    code: SeriesCode
    facts: Mapping[str, Any] = field(default_factory=dict)


class StopCode(enum.Enum):
    """Why a counterexample search stopped before it finished (words:
    ``thesis_messages.search_stop``)."""

    #: the search's budget of operations and evaluations ran out while sampling
    BUDGET_SAMPLING = "budget, sampling"
    #: ... during the local (Nelder-Mead) refinement
    BUDGET_LOCAL = "budget, local refinement"
    #: ... before the check of equation (5.9)
    BUDGET_EQUATION_5_9 = "budget, equation (5.9)"
    #: no local refinement in this dimension (facts: dimension, most)
    DIMENSION = "dimension"


@dataclass(frozen=True)
class SearchStop:
    """Why a search stopped early: a code and its numbers."""

    code: StopCode
    facts: Mapping[str, Any] = field(default_factory=dict)


class SearchCode(enum.Enum):
    """What a search for a witness of instability (a nonzero equilibrium, an equilibrium under
    a constant attack, a periodic orbit) looked at and found (words:
    ``ssecert.stability.search_messages``)."""

    #: the map has no soft threshold (or a zero shrink): nothing nonlinear to search
    NO_NONLINEARITY = "no nonlinearity"
    #: not searched: the budget refused it (facts: refusal)
    REFUSED = "refused"
    #: not searched: too many active/sign patterns (facts: m, count, most)
    TOO_MANY_PATTERNS = "too many patterns"
    #: the first confirmed equilibrium, after this many patterns (facts: tried, count)
    FIRST_FOUND = "first found"
    #: every pattern tried (facts: found, count, nonzero, singular)
    PATTERNS_TRIED = "patterns tried"
    #: the mixed-integer search found no pattern (facts: status, message, m, box, seconds,
    #: refused)
    MILP_NONE = "mixed-integer search, none"
    #: the mixed-integer search found one, confirmed exactly (facts: m)
    MILP_FOUND = "mixed-integer search, found"
    #: every candidate of the mixed-integer search refused exactly (facts: m, refused, seconds,
    #: timed_out)
    MILP_REFUSED = "mixed-integer search, refused"
    #: a linear error map with an eigenvalue 1: no unique equilibrium
    LINEAR_SINGULAR = "linear, singular"
    #: a linear error map's unique equilibrium
    LINEAR_UNIQUE = "linear, unique"
    #: a periodic orbit found and confirmed exactly (facts: samples, steps, period)
    ORBIT_FOUND = "orbit found"
    #: no periodic orbit (facts: samples, steps, alive, tried)
    NO_ORBIT = "no orbit"


@dataclass(frozen=True)
class Searched:
    """What a witness search looked at and found: a code, its numbers, and whether it ran in
    balanced state coordinates."""

    code: SearchCode
    facts: Mapping[str, Any] = field(default_factory=dict)
    balanced: bool = False


class VerifyCode(enum.Enum):
    """Why a certificate recomputed in numpy (``ssecert.stability.lmi_verification``,
    ``zames_falb.verify_zames_falb``) is not verified (words: ``lmi_messages.verify_text``)."""

    #: the certificate has non-finite entries
    NON_FINITE = "non-finite"
    #: a multiplier is negative (facts: value)
    NEGATIVE_MULTIPLIER = "negative multiplier"
    #: a Zames-Falb channel's m0 is not above its delayed coefficients (facts: channel, m0,
    #: total)
    CHANNEL_SHORT = "channel short"
    #: P's smallest eigenvalue does not clear its rounding (facts: smallest)
    NOT_CLEARLY_DEFINITE = "P not clearly definite"
    #: P minus half its smallest eigenvalue fails a Cholesky factorization
    CHOLESKY_FAILED = "P fails Cholesky"
    #: the LMI's margin does not clear its error bound (facts: margin, clear, bound)
    MARGIN_NOT_CLEAR = "margin not clear"


@dataclass(frozen=True)
class VerifyProblem:
    """Why a recomputed certificate is not verified: a code and its numbers."""

    code: VerifyCode
    facts: Mapping[str, Any] = field(default_factory=dict)


def known(value: float | None) -> float:
    """A number a holding certificate always carries (its radius, contraction, gain)."""
    if value is None:  # pragma: no cover - certificates that hold set it
        raise RuntimeError("a holding certificate is missing the number it certifies")
    return value
