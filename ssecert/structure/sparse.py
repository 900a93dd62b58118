"""s-sparse observability: can any estimator survive s attacked sensors?

``max_removable`` is the largest k such that removing any k sensors leaves
(A, C_rest) observable (-1 when (A, C) itself is unobservable).  With s
attacked sensors, secure estimation is possible iff 2s <= max_removable
(Proposition 1 of the lecture notes; 2s-sparse observability in the Lasso
paper).  The verdict assumes the attacked set is fixed over the window.

Two exact methods answer it, in different numerics (``enumeration`` and
``eigenspace``, one module each; this module runs, confirms and combines them):

* **enumeration**: sensor sets by increasing size, so the first breaking
  set found is a smallest one, lexicographically first among equals.  Each
  sensor's observable row space comes from an orthogonal Krylov staircase;
  a set of kept sensors is observable iff the sum of their orthogonal
  projectors is positive definite, screened for many sets per numpy call by
  a batched Cholesky factorization of colex-ordered partial sums and decided
  exactly by SVD where screening fails.  Sensors that alone observe the whole
  state must all be removed to break the plant, which prunes the search.
* **eigenspace** (PBH): (A, C_T) is unobservable iff some eigenvector v of A
  has C_T v = 0, so the smallest breaking sets are the supports of C v over
  nonzero v in an eigenspace.  One support per eigenvalue of geometric
  multiplicity 1; for an eigenspace of dimension g, the C(p, g-1)
  hyperplanes through g-1 of the sensor rows.

Every holds verdict is re-checked on its critical sensor sets (the sets
that come closest to breaking) by the other numerics, and the margin is
reported; every fails verdict carries a stealthy attack verified by
simulation.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from .._exact import ExactPlant
from .._linalg import (
    EigenAnalysis,
    SensorSubspaces,
    eigen_clusters,
    sensor_subspaces,
    unit_normalized,
)
from .._validation import as_choice, as_float_option, as_int_option
from ..results import Check, Verdict
from ..system import System
from ..tolerances import NONZERO, ZERO, Tolerances
from ._combinatorics import count_subsets
from .attacks import stealthy_attack
from .eigenspace import _eigenspace
from .enumeration import (
    Progress,
    RemovalScan,
    _enumeration,
    _Outcome,
    scan_removals,
)
from .observability import observability, pbh_margins

__all__ = [
    "sparse_observability",
    "scan_removals",
    "RemovalScan",
    "DEFAULT_MAX_SETS",
    "DEFAULT_TIME_BUDGET",
    "METHODS",
]

DEFAULT_MAX_SETS = 50_000_000
# seconds spent refining max_removable once the verdict is settled (None: exact, however long)
DEFAULT_TIME_BUDGET = 5.0

METHODS = ("auto", "enumeration", "eigenspace")


def _estimates(
    system: System, s: int, eig: EigenAnalysis, sub: SensorSubspaces | None
) -> dict[str, float]:
    """Rough flop counts of the two methods."""
    n, p = system.n, system.p
    if eig.problems:
        eigen_cost = math.inf
    else:
        eigen_cost = sum(
            math.comb(p, c.geometric - 1) * p * c.geometric + n**3 for c in eig.clusters
        )
    if sub is None:
        enum_cost = math.inf
    else:
        full = int(np.count_nonzero(sub.ranks == n))
        q = p - full
        upto = max(0, 2 * s - full + 1)
        enum_cost = count_subsets(q, range(upto + 1)) * (n**3 / 3 + n * n) + p * n**3
    return {"eigenspace": float(eigen_cost), "enumeration": float(enum_cost)}


def _run(
    system: System,
    s: int,
    method: str,
    max_sets: int,
    tol: Tolerances,
    progress: Progress | None,
    eig: EigenAnalysis,
    exact: ExactPlant | None = None,
    time_budget: float | None = None,
    client: Any | None = None,
) -> tuple[_Outcome, list[_Outcome], dict[str, float]]:
    n, p = system.n, system.p
    sub: SensorSubspaces | None = None
    estimates: dict[str, float] = {}
    if method == "enumeration":
        order = ["enumeration"]
    elif method == "eigenspace":
        order = ["eigenspace"]
    else:
        estimates = _estimates(system, s, eig, None)
        # the enumeration costs at least the p sensor staircases
        if estimates["eigenspace"] <= p * n**3:
            order = ["eigenspace", "enumeration"]
        else:
            sub = sensor_subspaces(system.A, system.C, tolerances=tol)
            estimates = _estimates(system, s, eig, sub)
            order = sorted(["eigenspace", "enumeration"], key=lambda m: estimates[m])
    tried: list[_Outcome] = []
    for name in order:
        if name == "enumeration":
            if sub is None:
                sub = sensor_subspaces(system.A, system.C, tolerances=tol)
            outcome = _enumeration(
                system,
                s,
                max_sets,
                tol,
                progress,
                sub,
                eig,
                exact,
                time_budget=time_budget,
                client=client,
            )
            if (
                outcome.details.get("stopped_by_time_budget")
                and outcome.max_removable is not None
                and outcome.max_removable >= 2 * s
            ):
                # the verdict is decided; another method would only refine it, past the budget
                tried.append(outcome)
                return outcome, tried, estimates
        else:
            # in auto, a hyperplane search past the time budget gives way to the enumeration,
            # which decides the verdict first; a forced eigenspace method runs to the end
            deadline = (
                time.monotonic() + time_budget
                if time_budget is not None and order == ["eigenspace", "enumeration"] and not tried
                else None
            )
            outcome = _eigenspace(system, s, max_sets, tol, eig, exact, deadline=deadline)
            if outcome.status == "exact":
                if sub is None:
                    sub = sensor_subspaces(system.A, system.C, tolerances=tol)
                checked = _cross_check(system, s, outcome, tol, eig, exact, sub)
                if checked is not outcome:
                    tried.append(outcome)
                    outcome = checked
        tried.append(outcome)
        if outcome.status == "exact":
            return outcome, tried, estimates
    # no exact answer: prefer a lower bound that decides the verdict
    for outcome in tried:
        if outcome.status == "lower_bound" and outcome.max_removable is not None:
            if outcome.max_removable >= 2 * s:
                return outcome, tried, estimates
    return tried[0], tried, estimates


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
        found = "a breaking set" if enum.status == "exact" else "a set within precision of breaking"
        outcome.problems.append(
            f"the enumeration finds {found} of "
            f"{enum.max_removable + 1} sensors, smaller than the eigenspace method's {size} (its "
            f"eigenvalue groups missed it)"
        )
        outcome.status = "inconclusive"
        enum.details["cross_check_of_eigenspace"] = {
            "max_removable": mr,
            "breaking_set": list(outcome.breaking_set),
        }
        return enum
    if enum.status == "exact" and enum.max_removable == mr:
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
            f"the enumeration finds no breaking set of {size} sensors, although sensors "
            f"{list(outcome.breaking_set)} break the exact data: the enumeration's decisions "
            f"are unreliable on this plant"
        )
        outcome.status = "inconclusive"
    outcome.details["cross_check"] = record
    return outcome


def _recheck_holds(
    system: System,
    outcome: _Outcome,
    eig: EigenAnalysis,
    tol: Tolerances,
    s: int,
    exact: ExactPlant | None = None,
) -> tuple[float | None, list[dict[str, Any]], str]:
    """Independent re-check of the sets closest to breaking.

    Each is also decided on the exact data when affordable: a set the exact
    data prove unobservable withdraws the holds.

    Enumeration results are re-checked by the PBH test at the eigenvalues;
    eigenspace results by the Krylov staircase of the kept sensors.  Returns
    the margin (smallest relative PBH singular value found), the records and
    a problem string (empty when every re-check agrees).
    """
    from .._linalg import staircase

    records = []
    margin = None
    problem = ""
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
            exact.observability(kept, proof=False).state if exact is not None else "unknown"
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
        if exact_state == "unobservable" and not problem:
            problem = (
                f"without sensors outside {list(kept)} the exact data are unobservable "
                f"(an exact kernel vector), which floating point missed"
            )
        checker_ok = pbh_ok if outcome.method == "enumeration" else stair_ok
        if eig.problems and outcome.method == "enumeration":
            checker_ok = stair_ok
        # full Krylov rank of the exact data modulo a prime proves the kept set observable,
        # whatever the floating-point re-check of an ill-conditioned plant says
        if not checker_ok and exact_state != "observable" and not problem:
            problem = (
                f"re-check of kept sensors {list(kept)} does not confirm observability "
                f"(PBH full rank: {pbh_ok}, staircase full rank: {stair_ok})"
            )
    # Independently of any grouping: at every computed eigenvalue, remove the
    # 2s sensors that see its (numerical) eigenvector best and test PBH there.
    if not problem:
        raw_margin, raw_problem = _recheck_raw_eigenvalues(system, s, tol, eig)
        if raw_margin is not None:
            margin = raw_margin if margin is None else min(margin, raw_margin)
        problem = raw_problem
    return margin, records, problem


def _recheck_raw_eigenvalues(
    system: System, s: int, tol: Tolerances, eig: EigenAnalysis
) -> tuple[float | None, str]:
    """PBH at each computed eigenvalue after removing the 2s sensors that see it best."""
    A, C = system.A, system.C
    n, p = system.n, system.p
    if 2 * s >= p:
        return None, ""
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
            return worst, (
                f"the PBH test at the computed eigenvalue {eig.label(value)}, after removing the "
                f"{2 * s} sensors that see its eigenvector best, is "
                f"{'rank deficient' if codes[0] == ZERO else 'borderline'}"
            )
    return worst, ""


def sparse_observability(
    system: System,
    max_attacked: int,
    *,
    method: str = "auto",
    max_sets: int = DEFAULT_MAX_SETS,
    horizon: int | None = None,
    seed: int = 0,
    tolerances: Tolerances | None = None,
    progress: Progress | None = None,
    eigen: EigenAnalysis | None = None,
    time_budget: float | None = DEFAULT_TIME_BUDGET,
    client: Any | None = None,
) -> Check:
    """Decide s-sparse observability and find the weakest sensor set.

    Parameters
    ----------
    system : System
    max_attacked : int
        s, the largest number of attacked sensors (s >= 0).
    method : {"auto", "enumeration", "eigenspace"}, default "auto"
        ``auto`` picks the cheaper method from a cost estimate and falls back
        to the other when the first cannot decide.
    max_sets : int, default 50,000,000
        Budget of sensor sets (enumeration) or hyperplanes (eigenspace).
        Beyond it, the verdict still holds when every set of up to 2s sensors
        was checked (``max_removable_is_lower_bound`` is then true), and is
        inconclusive otherwise.
    horizon : int, optional
        Length of the stealthy-attack witness (default n).
    seed : int, default 0
        Seed of the initial state used to simulate the witness.
    tolerances : Tolerances, optional
    progress : callable, optional
        ``progress(done, total)`` called during enumeration.
    eigen : EigenAnalysis, optional
        Precomputed eigenvalue groups of the plant in power-of-two units
        (``unit_normalized(system)[0].A``).
    time_budget : float or None, default 5
        Seconds the enumeration may spend refining max_removable once the
        verdict is decided (every set of up to 2s sensors checked): a level
        of larger sets predicted to end past it is not started, and
        max_removable is then a lower bound (``max_removable_is_lower_bound``,
        with the reason).  None computes the exact value however long it
        takes.  The verdict itself is never cut short by it.
    client : dask.distributed.Client, optional
        Split each level of the enumeration over the client's workers (in
        ranges of colex ranks).  The answer is the in-process one: the same
        max_removable, the same smallest breaking set (lexicographically first
        among equals), the same critical sets.  A range that fails on a
        worker is retried once; a second failure ends the enumeration there
        with the reason.

    Returns
    -------
    Check
        ``id = "sparse_observability"`` with fields ``max_removable``,
        ``max_removable_is_lower_bound``, ``max_correctable``,
        ``breaking_set`` and ``method``; a failing check carries the
        stealthy attack as ``witness``.

    Examples
    --------
    >>> from ssecert import System
    >>> ugv = System([[1.0, 0.0099], [0.0, 0.9876]], [[1, 0], [0, 1], [0, 1]])
    >>> check = sparse_observability(ugv, 1)
    >>> check.verdict.value, check.fields["max_removable"], check.fields["breaking_set"]
    ('fails', 0, [0])
    """
    if not isinstance(system, System):
        raise TypeError(f"system must be a System, got {type(system).__name__}")
    tol = Tolerances.check(tolerances)
    seed = as_int_option(seed, "seed", min_value=0)
    s = as_int_option(max_attacked, "max_attacked", min_value=0)
    method = as_choice(method, "method", METHODS)
    max_sets = as_int_option(max_sets, "max_sets", min_value=1)
    H = system.n if horizon is None else as_int_option(horizon, "horizon", min_value=1)
    # decisions in power-of-two units (no sensor's units can tip a rank threshold), confirmed
    # on the user's exact data; the witness is built in the user's units
    work, alpha = unit_normalized(system)
    eig = eigen if eigen is not None else eigen_clusters(work.A, tolerances=tol, unit=alpha)
    exact = ExactPlant(system.A, system.C)
    if time_budget is not None:
        time_budget = as_float_option(time_budget, "time_budget", min_value=0.0)
    outcome, tried, estimates = _run(
        work, s, method, max_sets, tol, progress, eig, exact, time_budget=time_budget, client=client
    )
    for o in tried:
        for item in o.details.get("eigenvalues", []):
            item["eigenvalue"] = item["eigenvalue"] / alpha

    p = system.p
    evidence: dict[str, Any] = {
        "methods_tried": [
            {
                "method": o.method,
                "status": o.status,
                "max_removable": o.max_removable,
                "breaking_set": list(o.breaking_set) if o.breaking_set is not None else None,
                "sets_checked": o.checked,
                "problems": o.problems,
            }
            for o in tried
        ],
        "cost_estimates_flops": estimates,
        "max_sets": max_sets,
        "assumption": "the attacked sensor set is fixed over the observation window",
        "condition": f"secure estimation with s = {s} attacked sensors needs 2s = {2 * s} <= max_removable",
    }
    evidence.update(outcome.details)
    tolerances_out = tol.to_dict()
    title = f"{s}-sparse observability"
    base_fields: dict[str, Any] = {
        "max_attacked": s,
        "method": outcome.method,
    }

    def fields(mr: int | None, lower: bool, bset: tuple[int, ...] | None) -> dict[str, Any]:
        if mr is None:
            correctable = None
        else:
            correctable = -1 if mr < 0 else mr // 2
        return {
            **base_fields,
            "max_removable": mr,
            "max_removable_is_lower_bound": lower,
            "max_correctable": correctable,
            "breaking_set": list(bset) if bset is not None else None,
        }

    def make(
        verdict: Verdict,
        summary: str,
        value: int | None,
        extra: dict[str, Any],
        margin: float | None = None,
        witness: dict | None = None,
    ) -> Check:
        return Check(
            id="sparse_observability",
            title=title,
            verdict=verdict,
            summary=summary,
            value=value,
            margin=margin,
            method=outcome.method,
            fields=extra,
            evidence=evidence,
            witness=witness,
            tolerances=tolerances_out,
        )

    def unobservable_plant() -> Check | None:
        # the methods could not decide, but when the exact data are unobservable with every
        # sensor kept, max_removable = -1 whatever the floating-point trouble
        decision = exact.observability(tuple(range(p)))
        if decision.state != "unobservable" or decision.z is None:
            return None
        found = _Outcome("exact arithmetic", "exact", -1, (), decision.z)
        evidence["undecided_methods_settled_by"] = (
            "the exact data are unobservable with every sensor kept (an exact kernel vector)"
        )
        verdict, summary, witness = _failure(system, work, s, found, H, seed, tol, evidence, exact)
        if verdict is not Verdict.FAILS:
            return None
        return make(verdict, summary, -1, fields(-1, False, ()), witness=witness)

    if outcome.status == "exact":
        mr = outcome.max_removable
        assert mr is not None and outcome.breaking_set is not None and outcome.z is not None
        if 2 * s > mr:
            verdict, summary, witness = _failure(
                system, work, s, outcome, H, seed, tol, evidence, exact
            )
            extra = fields(mr, False, outcome.breaking_set)
            if outcome.details.get("max_removable_is_upper_bound"):
                extra["max_removable_is_upper_bound"] = True
                extra["max_removable_at_least"] = outcome.details.get("max_removable_at_least")
            return make(verdict, summary, mr, extra, witness=witness)
        margin, records, problem = _recheck_holds(work, outcome, eig, tol, s, exact)
        evidence["recheck"] = records
        evidence["margin_definition"] = (
            "smallest relative PBH singular value sigma_min([A - lambda I; C_T]) / ||[A; C]||"
            " over the kept-sensor sets T that come closest to breaking"
        )
        if problem:
            evidence["disputed_max_removable"] = mr
            settled = unobservable_plant()
            if settled is not None:
                return settled
            return make(
                Verdict.INCONCLUSIVE,
                f"The {outcome.method} method finds max_removable = {mr}, but {problem}.",
                None,
                fields(None, False, None),
                margin=margin,
            )
        else:
            summary = (
                f"Removing any {mr} of the {p} sensors keeps the plant observable, so up to "
                f"{mr // 2} attacked sensors can be corrected (s = {s} needed)."
            )
        return make(
            Verdict.INCONCLUSIVE if problem else Verdict.HOLDS,
            summary,
            mr,
            fields(mr, False, outcome.breaking_set),
            margin=margin,
        )

    if outcome.status == "lower_bound" and outcome.max_removable is not None:
        mr = outcome.max_removable
        if mr >= 2 * s:
            margin, records, problem = _recheck_holds(work, outcome, eig, tol, s, exact)
            evidence["recheck"] = records
            if problem:
                summary = f"Lower bound max_removable >= {mr}, but {problem}."
            else:
                summary = (
                    f"Every set of up to {mr} sensors was checked and none breaks observability, "
                    f"so s = {s} attacked sensors can be corrected; the exact max_removable was "
                    f"not computed ({'; '.join(outcome.problems)})."
                )
            return make(
                Verdict.INCONCLUSIVE if problem else Verdict.HOLDS,
                summary,
                mr,
                fields(mr, True, None),
                margin=margin,
            )
    settled = unobservable_plant()
    if settled is not None:
        return settled
    reasons = [pr for o in tried for pr in o.problems] or ["no method could decide"]
    if s == 0:
        # 2s = 0 <= max_removable is observability of (A, C) itself
        plain = observability(system, tolerances=tol, eigen=eig)
        evidence["observability"] = {"verdict": plain.verdict.value, "summary": plain.summary}
        if plain.verdict is Verdict.HOLDS:
            return make(
                Verdict.HOLDS,
                f"With s = 0 the condition 0 <= max_removable is the observability of (A, C), "
                f"which holds: {plain.summary} The exact max_removable was not computed "
                f"({'; '.join(reasons)}).",
                0,
                fields(0, True, None),
                margin=plain.margin,
            )
    needed = next((o.needed for o in tried if o.needed is not None), None)
    hint = ""
    if needed is not None:
        hint = (
            f" About {needed:,} more sensor sets are needed; raise the budget with "
            f"--max-sets (max_sets=...)."
        )
    lower = outcome.max_removable if outcome.status == "lower_bound" else None
    return make(
        Verdict.INCONCLUSIVE,
        f"Sparse observability could not be decided: {'; '.join(reasons)}.{hint}",
        lower,
        {**fields(lower, lower is not None, None), "sets_needed": needed},
    )


def _failure(
    system: System,
    work: System,
    s: int,
    outcome: _Outcome,
    H: int,
    seed: int,
    tol: Tolerances,
    evidence: dict[str, Any],
    exact: ExactPlant,
) -> tuple[Verdict, str, dict[str, Any] | None]:
    """Verdict, summary and stealthy-attack witness of a failing check.

    ``work`` is the plant in power-of-two units used for float decisions;
    the witness is built on the user's ``system``.
    """
    from .._linalg import staircase

    mr = outcome.max_removable
    B = outcome.breaking_set
    z = outcome.z
    assert mr is not None and B is not None and z is not None
    names = [system.sensors[i] for i in B]
    # independent confirmation that the kept sensors do not observe the plant
    kept = [i for i in range(system.p) if i not in set(B)]
    sc_rank = (
        staircase(work.A, work.C[kept], tolerances=tol, error_model="compound").rank if kept else 0
    )
    decision = exact.observability(tuple(kept))
    evidence["breaking_set_check"] = {
        "kept_sensors": kept,
        "kept_observable_dimension": sc_rank,
        "unobservable": sc_rank < system.n,
        "exact": decision.to_dict(),
    }
    if decision.state == "observable":
        return (
            Verdict.INCONCLUSIVE,
            (
                f"The {outcome.method} method finds breaking set {list(B)}, but without those sensors "
                f"the exact data are observable (Krylov rank {system.n} modulo a prime): the plant is "
                f"within floating-point precision of one they break, and the answer depends on digits "
                f"the data do not have."
            ),
            None,
        )
    witness = stealthy_attack(system, B, z, s, horizon=H, seed=seed, tolerances=tol)
    witness_out = witness.to_dict()
    if decision.state == "unobservable":
        witness_out["exact_check"] = (
            "removing the breaking set leaves the exact data "
            "unobservable: z_exact_integers (up to scale) satisfies "
            "C_i A^k z = 0 exactly for every kept sensor i"
        )
        witness_out["z_exact_integers"] = [str(v) for v in decision.z_exact or []]
    if decision.state != "unobservable" and (
        not witness.verified or (kept and sc_rank >= system.n)
    ):
        return (
            Verdict.INCONCLUSIVE,
            (
                f"The {outcome.method} method finds breaking set {list(B)}, but the stealthy attack "
                f"built from it does not verify (output mismatch {witness.residual:.2e}, kept sensors "
                f"observable dimension {sc_rank})."
            ),
            witness_out,
        )
    if mr == -1:
        what = "(A, C) itself is not observable: some states produce no output at all."
    elif len(B) <= s:
        what = (
            f"Removing sensor{'s' if len(B) > 1 else ''} {', '.join(names)} leaves the plant "
            f"unobservable, and {len(B)} <= s = {s}: an attacker on "
            f"{'them' if len(B) > 1 else 'it'} can mimic a different initial state without "
            f"being detected."
        )
    else:
        what = (
            f"Removing sensors {', '.join(names)} leaves the plant unobservable; split into two "
            f"groups of at most s = {s}, they give two attacks under which different initial "
            f"states produce the same outputs."
        )
    if outcome.details.get("max_removable_is_upper_bound"):
        low = int(outcome.details.get("max_removable_at_least", -1))
        summary = (
            f"max_removable <= {mr} < 2s = {2 * s}: {s} attacked sensor"
            f"{'s' if s != 1 else ''} cannot be corrected, whatever digits the data lack. "
            f"{what} (Smaller sets, from {low + 1} sensors on, are within floating-point "
            f"precision of breaking the plant, so the exact max_removable, between {low} and "
            f"{mr}, is not decided; the verdict does not depend on it.)"
        )
        return Verdict.FAILS, summary, witness_out
    summary = (
        f"max_removable = {mr} < 2s = {2 * s}: {s} attacked sensor{'s' if s != 1 else ''} "
        f"cannot be corrected. {what}"
    )
    return Verdict.FAILS, summary, witness_out
