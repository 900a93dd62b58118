"""Independent re-checks of a sparse-observability answer.

An eigenspace answer is confirmed by enumerating the sets up to its
breaking-set size (``_cross_check``); a holds verdict is re-checked on the
kept-sensor sets that come closest to breaking, by the other numerics and
on the exact data (``_recheck_holds``), and at every computed eigenvalue
independently of any grouping (``_recheck_raw_eigenvalues``).
``ssecert.structure.sparse`` decides which apply.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..numerics.exact import ExactPlant, Observability
from ..numerics.linalg import EigenAnalysis, SensorSubspaces
from ..system import System
from ..tolerances import NONZERO, ZERO, Tolerances
from ._combinatorics import count_subsets
from .enumeration import OutcomeStatus, SparseMethod, _enumeration, _Outcome
from .observability import pbh_margins
from .outcomes import Problem, ProblemCode, RecheckCode, RecheckProblem

__all__: list[str] = []


CROSS_CHECK_SETS = 200_000  # enumeration that confirms an eigenspace answer when this cheap


def _cross_check(
    system: System,
    s: int,
    outcome: _Outcome,
    tol: Tolerances,
    eig: EigenAnalysis,
    exact: ExactPlant | None,
    sub: SensorSubspaces,
) -> _Outcome:
    """Confirm an eigenspace answer by enumerating every set up to its breaking-set size.

    The eigenspace method's minimality rests on the computed eigenvalue
    groups, which ill-conditioned or hidden defective eigenvalues can merge
    or split; the enumeration does not use them.  Agreement keeps the
    answer (with the enumeration's lexicographically first breaking set); a
    smaller breaking set or a smaller set within precision of breaking
    replaces it; an enumeration that misses the eigenspace method's exactly
    confirmed set makes the answer disputed.
    """
    assert outcome.breaking_set is not None and outcome.max_removable is not None
    n = system.n
    full = int(np.count_nonzero(sub.ranks == n))
    q = system.p - full
    size = len(outcome.breaking_set)
    needed = count_subsets(q, range(max(size - full, 0) + 1))
    if needed > CROSS_CHECK_SETS:
        outcome.details["cross_check"] = {
            "status": "not run",
            "sets_needed": needed,
            "limit": CROSS_CHECK_SETS,
        }
        return outcome
    enum = _enumeration(system, s, CROSS_CHECK_SETS, tol, None, sub, eig, exact)
    record = {
        "status": enum.status,
        "max_removable": enum.max_removable,
        "breaking_set": list(enum.breaking_set) if enum.breaking_set is not None else None,
        "sets_checked": enum.checked,
    }
    mr = outcome.max_removable
    if enum.max_removable is not None and enum.max_removable < mr:
        outcome.problems.append(
            Problem.of(
                ProblemCode.SMALLER_BY_ENUMERATION,
                exact=enum.status is OutcomeStatus.EXACT,
                size=enum.max_removable + 1,
                eigenspace_size=size,
            )
        )
        outcome.status = OutcomeStatus.INCONCLUSIVE
        enum.details["cross_check_of_eigenspace"] = {
            "max_removable": mr,
            "breaking_set": list(outcome.breaking_set),
        }
        return enum
    if enum.status is OutcomeStatus.EXACT and enum.max_removable == mr:
        record["agrees"] = True
        outcome.breaking_set = enum.breaking_set
        outcome.z = enum.z
        outcome.details["breaking_set_exact"] = enum.details.get(
            "breaking_set_exact", outcome.details.get("breaking_set_exact")
        )
    elif (
        outcome.details.get("breaking_set_exact")
        and enum.max_removable is not None
        and (enum.max_removable >= size)
    ):
        record["agrees"] = False
        outcome.problems.append(
            Problem.of(
                ProblemCode.MISSED_BY_ENUMERATION, size=size, sensors=tuple(outcome.breaking_set)
            )
        )
        outcome.status = OutcomeStatus.INCONCLUSIVE
    outcome.details["cross_check"] = record
    return outcome


def _recheck_holds(
    system: System,
    outcome: _Outcome,
    eig: EigenAnalysis,
    tol: Tolerances,
    s: int,
    exact: ExactPlant | None = None,
) -> tuple[float | None, list[dict[str, Any]], RecheckProblem | None]:
    """Independent re-check of the sets closest to breaking.

    Each is also decided on the exact data when affordable: a set the exact
    data prove unobservable withdraws the holds.

    Enumeration results are re-checked by the PBH test at the eigenvalues;
    eigenspace results by the Krylov staircase of the kept sensors.  Returns
    the margin (smallest relative PBH singular value found), the records and
    the first problem (None when every re-check agrees).
    """
    from ..numerics.linalg import staircase

    records = []
    margin = None
    problem: RecheckProblem | None = None
    centers = np.array([c.center for c in eig.clusters], dtype=complex)
    for kept in outcome.critical:
        if not kept:
            continue
        Ck = system.C[list(kept)]
        m, codes = pbh_margins(system.A, Ck, centers, tolerances=tol)
        sc = staircase(system.A, Ck, tolerances=tol, error_model="compound")
        pbh_ok = bool(np.all(codes == NONZERO)) and not eig.problems
        stair_ok = sc.rank == system.n and not sc.problem
        value = float(m.min()) if m.size else None
        if value is not None:
            margin = value if margin is None else min(margin, value)
        exact_state = (
            exact.observability(kept, proof=False).state
            if exact is not None
            else Observability.UNKNOWN
        )
        records.append(
            {
                "kept_sensors": list(kept),
                "pbh_margin": value,
                "pbh_full_rank": pbh_ok,
                "staircase_full_rank": stair_ok,
                "exact": exact_state,
            }
        )
        if exact_state is Observability.UNOBSERVABLE and problem is None:
            problem = RecheckProblem(RecheckCode.EXACT_UNOBSERVABLE, {"kept": kept})
        checker_ok = pbh_ok if outcome.method is SparseMethod.ENUMERATION else stair_ok
        if eig.problems and outcome.method is SparseMethod.ENUMERATION:
            checker_ok = stair_ok
        # full Krylov rank of the exact data modulo a prime proves the kept set observable,
        # whatever the floating-point re-check of an ill-conditioned plant says
        if not checker_ok and exact_state is not Observability.OBSERVABLE and problem is None:
            problem = RecheckProblem(
                RecheckCode.NOT_CONFIRMED, {"kept": kept, "pbh": pbh_ok, "staircase": stair_ok}
            )
    # Independently of any grouping: at every computed eigenvalue, remove the
    # 2s sensors that see its (numerical) eigenvector best and test PBH there.
    if problem is None:
        raw_margin, raw_problem = _recheck_raw_eigenvalues(system, s, tol, eig)
        if raw_margin is not None:
            margin = raw_margin if margin is None else min(margin, raw_margin)
        problem = raw_problem
    return margin, records, problem


def _recheck_raw_eigenvalues(
    system: System, s: int, tol: Tolerances, eig: EigenAnalysis
) -> tuple[float | None, RecheckProblem | None]:
    """PBH at each computed eigenvalue after removing the 2s sensors that see it best."""
    A, C = system.A, system.C
    n, p = system.n, system.p
    if 2 * s >= p:
        return None, None
    norms = np.linalg.norm(C, axis=1)
    safe = np.where(norms > 0, norms, 1.0)
    worst = None
    lam = eig.eigenvalues
    for value in lam[lam.imag >= 0]:
        shift = value.real if value.imag == 0 else value
        _, _, vh = np.linalg.svd(A - shift * np.eye(n))
        v = vh[-1].conj()
        seen = np.abs(C @ v) / safe
        kept = np.sort(np.argsort(-seen, kind="stable")[2 * s :])
        m, codes = pbh_margins(A, C[kept], np.array([value]), tolerances=tol)
        worst = float(m[0]) if worst is None else min(worst, float(m[0]))
        if codes[0] != NONZERO:
            return worst, RecheckProblem(
                RecheckCode.RAW_EIGENVALUE,
                {"eigenvalue": eig.label(value), "removed": 2 * s, "deficient": codes[0] == ZERO},
            )
    return worst, None
