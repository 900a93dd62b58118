"""Typed outcomes of the structural analyses: why an answer is not exact, as codes and numbers.

The sparse-observability methods record their problems as ``Problem``
values (a ``ProblemCode`` and the facts its words need); the sentences a
user reads are written from them in ``ssecert.structure.sparse_messages``.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from ..results import Verdict

__all__ = [
    "IrrepresentableCode",
    "ObservabilityCode",
    "Problem",
    "ProblemCode",
    "RecheckCode",
    "RecheckProblem",
    "SparseCode",
]


class ProblemCode(enum.Enum):
    """Why a sparse-observability method did not give an exact answer."""

    #: the eigenvalues could not be grouped reliably (``text``: the eigen analysis's words)
    EIGENVALUES = "eigenvalues"
    #: one eigenspace's search did not finish (``eigenvalue``, ``text``)
    EIGENSPACE = "eigenspace"
    #: the eigenspace method's smallest support does not break the exact data (``support``,
    #: ``distance``: its words)
    NOT_EXACT = "not exact"
    #: a sensor's observable subspace has a borderline rank decision (``sensors``)
    BORDERLINE_SUBSPACE = "borderline subspace"
    #: the time budget stopped the refinement before a level (``budget``, ``sets``,
    #: ``removed``, ``seconds`` more predicted)
    TIME_BEFORE_LEVEL = "time budget before a level"
    #: the enumeration budget stopped it before a level (``max_sets``, ``removed``;
    #: ``seconds``: what the rest of the verdict's sets would take here, None past the
    #: verdict's level; ``workers``: the Dask workers that would take them under
    #: ``time_budget``, or None)
    SET_BUDGET = "set budget"
    #: the Dask workers failed twice on a range (``removed``, ``first``, ``last``, ``cause``)
    WORKERS_FAILED = "workers failed"
    #: the time budget stopped the refinement within a level (``budget``, ``checked``,
    #: ``sets``, ``removed``)
    TIME_WITHIN_LEVEL = "time budget within a level"
    #: sets with a borderline rank decision (``count``, ``removed``)
    BORDERLINE_SETS = "borderline sets"
    #: a removal within floating-point precision of breaking the plant (``sensors``,
    #: ``others``, ``distance``: its words or None)
    WITHIN_PRECISION = "within precision"
    #: the enumeration found a smaller breaking set than the eigenspace method (``exact``,
    #: ``size``, ``eigenspace_size``)
    SMALLER_BY_ENUMERATION = "smaller by enumeration"
    #: the enumeration missed a breaking set the exact data confirm (``size``, ``sensors``)
    MISSED_BY_ENUMERATION = "missed by enumeration"


@dataclass(frozen=True)
class Problem:
    """One reason an answer is not exact: a code and the facts its words need."""

    code: ProblemCode
    facts: Mapping[str, Any] = field(default_factory=dict)

    @classmethod
    def of(cls, code: ProblemCode, **facts: Any) -> Problem:
        return cls(code, facts)


class IrrepresentableCode(enum.Enum):
    """Why the irrepresentable check (``ssecert.structure.irrepresentable``) has its verdict; the
    numbers are in the facts its words need (``ssecert.structure.irrepresentable_messages``)."""

    #: holds: no attacked entry, nothing to misidentify
    NO_ATTACK = "no attack"
    #: fails: O_tau is rank deficient even without attack (``tau``, ``rank``, ``n``)
    NO_ATTACK_RANK_DEFICIENT = "no attack, rank deficient"
    #: fails: more attacked items than items (``k``, ``items``, ``noun``)
    SUPPORT_TOO_LARGE = "support too large"
    #: fails: every item attacked (``items``, ``noun``)
    ALL_ATTACKED = "all attacked"
    #: inconclusive: more supports than the budget (``items``, ``k``, ``count``, ``max_sets``)
    TOO_MANY_SUPPORTS = "too many supports"
    #: inconclusive: the memory or work budget refused the scan (``refusal``, ``hint``)
    OVER_BUDGET = "over budget"
    #: inconclusive: the stacked observability matrix overflows (``tau``)
    OVERFLOW = "overflow"
    #: inconclusive: the Dask workers failed twice on a range (``first``, ``last``, ``cause``)
    WORKERS_FAILED = "workers failed"
    #: inconclusive: O_tau's rank cannot be decided (``problem``: the staircase's words)
    RANK_UNDECIDED = "rank undecided"
    #: inconclusive: O_tau looks rank deficient but the exact data say otherwise (``tau``,
    #: ``doubt``)
    O_TAU_DOUBT = "O_tau in doubt"
    #: fails: O_tau is rank deficient, so every O_Sbar is (``tau``, ``rank``, ``n``, ``label``)
    O_TAU_RANK_DEFICIENT = "O_tau rank deficient"
    #: inconclusive: supports with a borderline rank decision (``count``)
    BORDERLINE = "borderline"
    #: inconclusive: a support's O_Sbar looks rank deficient, the exact data doubt it
    #: (``label``, ``doubt``)
    SUPPORT_DOUBT = "support in doubt"
    #: fails: a support's O_Sbar lacks full column rank (``count``, ``checked``, ``total``,
    #: ``label``)
    SUPPORT_RANK_DEFICIENT = "support rank deficient"
    #: inconclusive: the worst value does not match its recomputation (``worst``, ``label``,
    #: ``direct``)
    RECOMPUTE_MISMATCH = "recompute mismatch"
    #: inconclusive: the worst value cannot be told from 1 (``worst``, ``label``,
    #: ``estimate``, ``kappa``)
    NOT_TOLD_FROM_ONE = "not told from 1"
    #: holds: the worst value is below 1 (``worst``, ``label``, ``k``, ``counted``)
    BELOW_ONE = "below 1"
    #: inconclusive: the worst value is below 1, but some support's rho was computed too
    #: imprecisely (an ill-conditioned O_Sbar) to be known below it (``worst``, ``label``,
    #: ``count``, ``imprecise_label``, ``error``)
    IMPRECISE_SUPPORTS = "imprecise supports"
    #: fails: the worst value is above 1 (``worst``, ``label``, ``stopped``: supports checked
    #: when the time budget cut the scan short, else None; ``imprecise``: the facts of
    #: IMPRECISE_SUPPORTS where another support may be larger, else None)
    ABOVE_ONE = "above 1"
    #: fails: the exact value on the worst support is at least 1 (``label``, ``exact``,
    #: ``imprecise`` as for ABOVE_ONE)
    EXACTLY_AT_LEAST_ONE = "exactly at least 1"
    #: inconclusive: the worst value is within the band of 1 (``worst``, ``band``, ``label``,
    #: ``exact``: its exact value below 1, or None)
    WITHIN_BAND = "within the band of 1"

    @property
    def verdict(self) -> Verdict:
        """The verdict this code gives."""
        holds = self in (IrrepresentableCode.NO_ATTACK, IrrepresentableCode.BELOW_ONE)
        return Verdict.of(holds=holds, fails=self in _IRREPRESENTABLE_FAILS)


_IRREPRESENTABLE_FAILS = frozenset(
    {
        IrrepresentableCode.NO_ATTACK_RANK_DEFICIENT,
        IrrepresentableCode.SUPPORT_TOO_LARGE,
        IrrepresentableCode.ALL_ATTACKED,
        IrrepresentableCode.O_TAU_RANK_DEFICIENT,
        IrrepresentableCode.SUPPORT_RANK_DEFICIENT,
        IrrepresentableCode.ABOVE_ONE,
        IrrepresentableCode.EXACTLY_AT_LEAST_ONE,
    }
)


class ObservabilityCode(enum.Enum):
    """Why the observability check (``ssecert.structure.observability``) has its verdict
    (``Check.code``; its words are written where the check is built)."""

    #: holds: PBH and the staircase agree on full rank
    OBSERVABLE = "observable"
    #: fails: an unobservable subspace, its direction verified (by simulation, the staircase
    #: or exact arithmetic)
    UNOBSERVABLE = "unobservable"
    #: fails: exact arithmetic finds an unobservable direction floating point could not resolve
    EXACTLY_UNOBSERVABLE = "exactly unobservable"
    #: inconclusive: unobservable in floating point, observable with the data taken exactly
    #: (within the precision of the rank decision)
    WITHIN_PRECISION = "within precision"
    #: inconclusive: neither method's answer could be trusted
    UNDECIDED = "undecided"

    @property
    def verdict(self) -> Verdict:
        """The verdict this code gives."""
        fails = self in (ObservabilityCode.UNOBSERVABLE, ObservabilityCode.EXACTLY_UNOBSERVABLE)
        return Verdict.of(holds=self is ObservabilityCode.OBSERVABLE, fails=fails)


class SparseCode(enum.Enum):
    """Why the sparse-observability check has its verdict (``Check.code``; its words are
    written where the check is built, ``ssecert.structure.sparse``)."""

    #: fails: a breaking set confirmed (without its sensors the exact data are unobservable, or
    #: the floats' stealthy attack verifies)
    BREAKING_SET = "breaking set"
    #: inconclusive: a breaking set of the floats, but without it the exact data are observable
    EXACT_DATA_OBSERVABLE = "exact data observable"
    #: inconclusive: a breaking set whose stealthy attack does not verify
    ATTACK_NOT_VERIFIED = "attack not verified"
    #: holds: the exact max_removable, its closest sets re-checked
    EXACT_MAX_REMOVABLE = "exact max_removable"
    #: inconclusive: the re-check of a holds disputes it (a ``RecheckProblem``)
    RECHECK_DISPUTED = "re-check disputed"
    #: holds: every set of up to 2s sensors checked, max_removable a lower bound
    LOWER_BOUND = "lower bound"
    #: inconclusive: a lower bound whose re-check disputes it
    LOWER_BOUND_DISPUTED = "lower bound disputed"
    #: holds: s = 0, and the plant is observable
    OBSERVABILITY_DECIDES = "observability decides"
    #: inconclusive: no method decided
    UNDECIDED = "undecided"

    @property
    def verdict(self) -> Verdict:
        """The verdict this code gives."""
        holds = self in (
            SparseCode.EXACT_MAX_REMOVABLE,
            SparseCode.LOWER_BOUND,
            SparseCode.OBSERVABILITY_DECIDES,
        )
        return Verdict.of(holds=holds, fails=self is SparseCode.BREAKING_SET)


class RecheckCode(enum.Enum):
    """What disputes a holds verdict of sparse observability in its re-check
    (``ssecert.structure._rechecks``)."""

    #: the exact data are unobservable without the sensors outside a kept set (facts: kept)
    EXACT_UNOBSERVABLE = "exact data unobservable"
    #: the other numerics do not confirm a kept set observable (facts: kept, pbh, staircase)
    NOT_CONFIRMED = "not confirmed"
    #: the PBH test at a computed eigenvalue, without the 2s sensors that see its
    #: eigenvector best, is rank deficient or borderline (facts: eigenvalue, removed,
    #: deficient)
    RAW_EIGENVALUE = "raw eigenvalue"


@dataclass(frozen=True)
class RecheckProblem:
    """What disputes a holds verdict: a code and the facts its words need
    (``sparse_messages.recheck_text``)."""

    code: RecheckCode
    facts: Mapping[str, Any] = field(default_factory=dict)
