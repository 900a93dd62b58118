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
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..base.validation import as_choice, as_float_option, as_int_option
from ..budget import DEFAULT_TIME_BUDGET
from ..numerics.exact import ExactPlant, Observability
from ..numerics.linalg import (
    EigenAnalysis,
    SensorSubspaces,
    balanced_units,
    eigen_clusters,
    sensor_subspaces,
)
from ..results import Check, Verdict
from ..system import System
from ..tolerances import Tolerances
from ._breaking_set import _failure
from ._combinatorics import count_subsets
from ._rechecks import _cross_check, _recheck_holds
from .cost import rounded_seconds, verdict_cost
from .device import resolve_device
from .eigenspace import _eigenspace, search_seconds
from .enumeration import (
    OutcomeStatus,
    Progress,
    SparseMethod,
    _enumeration,
    _Outcome,
    placement_note,
)
from .observability import observability
from .outcomes import RecheckProblem, SparseCode
from .removals import RemovalScan, scan_removals
from .sparse_messages import problem_texts, recheck_text, undecided_summary

__all__ = [
    "sparse_observability",
    "scan_removals",
    "RemovalScan",
    "DEFAULT_MAX_SETS",
    "DEFAULT_TIME_BUDGET",
    "METHODS",
]

DEFAULT_MAX_SETS = 50_000_000

METHODS = ("auto", "enumeration", "eigenspace")
# the method each choice forces (None: the cheaper first, ``_run``)
_FORCED: dict[str, SparseMethod | None] = {
    "auto": None,
    "enumeration": SparseMethod.ENUMERATION,
    "eigenspace": SparseMethod.EIGENSPACE,
}


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
    return {SparseMethod.EIGENSPACE: float(eigen_cost), SparseMethod.ENUMERATION: float(enum_cost)}


# above this many flops for the cheaper method, ``auto`` picks by calibrated seconds
SECONDS_MODEL_ABOVE = 1e8


def _seconds(
    system: System, s: int, eig: EigenAnalysis, sub: SensorSubspaces, client: Any | None
) -> dict[str, float]:
    """Estimated seconds of the eigenspace method (its hyperplane searches) and of the
    enumeration's levels up to the verdict (on the client's threads), on this machine."""
    n = system.n
    full = int(np.count_nonzero(sub.ranks == n))
    enumeration = verdict_cost(system.p - full, n, 2 * s - full, client, None)
    return {
        "eigenspace_s": rounded_seconds(search_seconds(system.p, eig)),
        "enumeration_s": enumeration["seconds_for_verdict"],
    }


def _run(
    system: System,
    s: int,
    forced: SparseMethod | None,
    max_sets: int,
    tol: Tolerances,
    progress: Progress | None,
    eig: EigenAnalysis,
    exact: ExactPlant | None = None,
    time_budget: float | None = None,
    client: Any | None = None,
    device: str | None = None,
) -> tuple[_Outcome, list[_Outcome], dict[str, float]]:
    n, p = system.n, system.p
    sub: SensorSubspaces | None = None
    estimates: dict[str, float] = {}
    both = [SparseMethod.EIGENSPACE, SparseMethod.ENUMERATION]
    if forced is not None:
        order = [forced]
    else:
        estimates = _estimates(system, s, eig, None)
        # the enumeration costs at least the p sensor staircases
        if estimates[SparseMethod.EIGENSPACE] <= p * n**3:
            order = both
        else:
            sub = sensor_subspaces(system.A, system.C, tolerances=tol)
            estimates = _estimates(system, s, eig, sub)
            if min(estimates.values()) > SECONDS_MODEL_ABOVE and math.isfinite(
                max(estimates.values())
            ):
                # both cost something: compare the seconds each takes here (rates measured on
                # this machine), not flop counts, whose rates differ by orders of magnitude
                estimates = {**estimates, **_seconds(system, s, eig, sub, client)}
                order = sorted(both, key=lambda m: estimates[f"{m}_s"])
            else:
                order = sorted(both, key=lambda m: estimates[m])
    tried: list[_Outcome] = []
    for name in order:
        if name is SparseMethod.ENUMERATION:
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
                device=device,
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
            # in auto, a hyperplane search far past its predicted time gives way to the
            # enumeration, which decides the verdict first; a forced eigenspace method runs to
            # the end.  The refinement's time budget is no deadline here: this search gives
            # the verdict itself (a budget of 0 means no refinement, not a weaker verdict)
            deadline = (
                time.monotonic() + _search_allowance(system.p, eig, time_budget)
                if time_budget is not None and order == both and not tried
                else None
            )
            outcome = _eigenspace(system, s, max_sets, tol, eig, exact, deadline=deadline)
            if outcome.status is OutcomeStatus.EXACT:
                if sub is None:
                    sub = sensor_subspaces(system.A, system.C, tolerances=tol)
                checked = _cross_check(system, s, outcome, tol, eig, exact, sub)
                if checked is not outcome:
                    tried.append(outcome)
                    outcome = checked
        tried.append(outcome)
        if outcome.status is OutcomeStatus.EXACT:
            return outcome, tried, estimates
    # no exact answer: prefer a lower bound that decides the verdict
    for outcome in tried:
        if outcome.status is OutcomeStatus.LOWER_BOUND and outcome.max_removable is not None:
            if outcome.max_removable >= 2 * s:
                return outcome, tried, estimates
    return tried[0], tried, estimates


# the hyperplane search may take this many times its predicted seconds, plus a second,
# before the enumeration takes over
SEARCH_ALLOWANCE = (4.0, 1.0)


def _search_allowance(p: int, eig: EigenAnalysis, time_budget: float) -> float:
    """Seconds the eigenspace method's search gets before the enumeration takes over: the
    refinement budget, or a multiple of its own predicted time when that is longer."""
    factor, fixed = SEARCH_ALLOWANCE
    return max(time_budget, fixed + factor * search_seconds(p, eig))


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
    timing: dict[str, Any] | None = None,
    device: str | None = None,
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
        (``balanced_units(system).system.A``).
    time_budget : float or None, default 5
        Seconds the enumeration may spend refining max_removable once the
        verdict is decided (every set of up to 2s sensors checked): a level
        of larger sets predicted to end past it is not started, one still
        running when it ends stops there (the sets it checked are the first
        in lexicographic order), and max_removable is then a lower bound
        (``max_removable_is_lower_bound``, with the reason).  None computes
        the exact value however long it takes.  The verdict itself is never
        cut short by it.
    client : dask.distributed.Client, optional
        Split each level of the enumeration over the client's workers (in
        ranges of colex ranks).  The answer is the in-process one: the same
        max_removable, the same smallest breaking set (lexicographically first
        among equals), the same critical sets.  A range that fails on a
        worker is retried once; a second failure ends the enumeration there
        with the reason.
    timing : dict, optional
        Filled with the seconds the check took (``seconds``), those it took
        to decide the verdict (``seconds_to_verdict``: everything but the
        refinement) and those it spent refining max_removable past the
        verdict (``refinement_seconds``), and with a ``client``, what ran
        where (``placement``: sentences naming the levels run on the workers
        and those run in-process).  Kept out of the check, whose JSON is the
        same from one run to the next and with or without Dask.
    device : {"cpu", "cuda", "numpy"}, optional
        Where the enumeration screens its sets (None or ``"cpu"``: numpy
        and LAPACK).  ``"cuda"`` screens each range of 16,384 sets or more
        on a GPU (PyTorch with CUDA, else CuPy, with array-api-compat: the
        ``gpu`` extra); ``"numpy"`` runs that code on the CPU (slower, for
        testing it).  The accelerator only proves sets observable; every
        other decision is LAPACK's on the CPU, so the answer is the one
        without it, bit for bit.  ``DeviceUnavailable`` when the device
        cannot be used here.

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
    start = time.monotonic()
    tol = Tolerances.check(tolerances)
    seed = as_int_option(seed, "seed", min_value=0)
    s = as_int_option(max_attacked, "max_attacked", min_value=0)
    method = as_choice(method, "method", METHODS)
    max_sets = as_int_option(max_sets, "max_sets", min_value=1)
    H = system.n if horizon is None else as_int_option(horizon, "horizon", min_value=1)
    # decisions in power-of-two units (no sensor's units can tip a rank threshold), confirmed
    # on the user's exact data; the witness is built in the user's units
    units = balanced_units(system)
    work, alpha = units.system, units.alpha
    eig = eigen if eigen is not None else eigen_clusters(work.A, tolerances=tol, unit=alpha)
    exact = ExactPlant(system.A, system.C)
    if time_budget is not None:
        time_budget = as_float_option(time_budget, "time_budget", min_value=0.0)
    device = resolve_device(device)
    outcome, tried, estimates = _run(
        work, s, _FORCED[method], max_sets, tol, progress, eig, exact,
        time_budget=time_budget, client=client, device=device,
    )  # fmt: skip
    for o in tried:
        for item in o.details.get("eigenvalues", []):
            item["eigenvalue"] = item["eigenvalue"] / alpha
    evidence = _evidence(s, outcome, tried, estimates, max_sets)
    if units.balanced:
        evidence["state_scaling"] = units.states
    decision = _Decision(
        system, work, s, outcome, tried, H, seed, tol, eig, exact, evidence, units.to_user,
    )  # fmt: skip
    if outcome.status is OutcomeStatus.EXACT:
        check = decision.exact_answer()
    elif (
        outcome.status is OutcomeStatus.LOWER_BOUND
        and outcome.max_removable is not None
        and outcome.max_removable >= 2 * s
    ):
        check = decision.lower_bound_answer()
    else:
        check = decision.undecided()
    if timing is not None:
        seconds = time.monotonic() - start
        refining = sum(o.refinement_seconds for o in tried)
        timing.update(
            seconds=seconds, seconds_to_verdict=seconds - refining, refinement_seconds=refining
        )
        notes = [note for o in tried if (note := placement_note(o)) is not None]
        if notes:
            timing["placement"] = notes
    return check


def _evidence(
    s: int,
    outcome: _Outcome,
    tried: list[_Outcome],
    estimates: dict[str, float],
    max_sets: int,
) -> dict[str, Any]:
    """What every sparse-observability check records: the methods tried and the condition."""
    evidence: dict[str, Any] = {
        "methods_tried": [
            {
                "method": o.method,
                "status": o.status,
                "max_removable": o.max_removable,
                "breaking_set": list(o.breaking_set) if o.breaking_set is not None else None,
                "sets_checked": o.checked,
                "problems": problem_texts(o.problems),
            }
            for o in tried
        ],
        "cost_estimates_flops": {k: v for k, v in estimates.items() if not k.endswith("_s")},
        "max_sets": max_sets,
        **(
            {
                "cost_estimates_seconds": {
                    k[:-2]: v for k, v in estimates.items() if k.endswith("_s")
                }
            }
            if any(k.endswith("_s") for k in estimates)
            else {}
        ),
        "assumption": "the attacked sensor set is fixed over the observation window",
        "condition": f"secure estimation with s = {s} attacked sensors needs 2s = {2 * s} <= max_removable",
    }
    evidence.update(outcome.details)
    return evidence


@dataclass
class _Decision:
    """Turns the chosen method's outcome into the check: exact, lower bound or undecided."""

    system: System  # the user's plant (witnesses)
    work: System  # the plant in power-of-two units (float decisions)
    s: int
    outcome: _Outcome
    tried: list[_Outcome]
    horizon: int
    seed: int
    tol: Tolerances
    eig: EigenAnalysis
    exact: ExactPlant
    evidence: dict[str, Any]
    to_user: Callable[[np.ndarray], np.ndarray]  # a direction of ``work`` in the user's units

    def fields(self, mr: int | None, lower: bool, bset: tuple[int, ...] | None) -> dict[str, Any]:
        """The check's fields for max_removable ``mr`` and breaking set ``bset``."""
        if mr is None:
            correctable = None
        else:
            correctable = -1 if mr < 0 else mr // 2
        return {
            "max_attacked": self.s,
            "method": self.outcome.method,
            "max_removable": mr,
            "max_removable_is_lower_bound": lower,
            "max_correctable": correctable,
            "breaking_set": list(bset) if bset is not None else None,
        }

    def make(
        self,
        code: SparseCode,
        summary: str,
        value: int | None,
        extra: dict[str, Any],
        margin: float | None = None,
        witness: dict | None = None,
    ) -> Check:
        """The check, its verdict the code's, with this decision's evidence and tolerances."""
        return Check(
            id="sparse_observability",
            title=f"{self.s}-sparse observability",
            verdict=code.verdict,
            code=code,
            summary=summary,
            value=value,
            margin=margin,
            method=self.outcome.method,
            fields=extra,
            evidence=self.evidence,
            witness=witness,
            tolerances=self.tol.to_dict(),
        )

    def failure(self, found: _Outcome) -> tuple[SparseCode, str, dict[str, Any] | None]:
        """Code, summary and stealthy attack of a breaking set (``_failure``)."""
        return _failure(
            self.system, self.work, self.s, found, self.horizon, self.seed, self.tol,
            self.evidence, self.exact, self.to_user,
        )  # fmt: skip

    def recheck(self) -> tuple[float | None, RecheckProblem | None]:
        """Margin and problem of the independent re-check of a holds (``_recheck_holds``)."""
        margin, records, problem = _recheck_holds(
            self.work, self.outcome, self.eig, self.tol, self.s, self.exact
        )
        self.evidence["recheck"] = records
        return margin, problem

    def unobservable_plant(self) -> Check | None:
        """max_removable = -1 when the exact data are unobservable with every sensor kept,
        whatever the floating-point trouble of the methods."""
        decision = self.exact.observability(tuple(range(self.system.p)))
        if decision.state is not Observability.UNOBSERVABLE or decision.z is None:
            return None
        found = _Outcome(SparseMethod.EXACT_ARITHMETIC, OutcomeStatus.EXACT, -1, (), decision.z)
        self.evidence["undecided_methods_settled_by"] = (
            "the exact data are unobservable with every sensor kept (an exact kernel vector)"
        )
        code, summary, witness = self.failure(found)
        if code is not SparseCode.BREAKING_SET:
            return None
        return self.make(code, summary, -1, self.fields(-1, False, ()), witness=witness)

    def exact_answer(self) -> Check:
        """A method found the exact max_removable: fails with the stealthy attack, or holds
        once the sets closest to breaking are re-checked."""
        outcome, s, p = self.outcome, self.s, self.system.p
        mr = outcome.max_removable
        assert mr is not None and outcome.breaking_set is not None and outcome.z is not None
        if 2 * s > mr:
            code, summary, witness = self.failure(outcome)
            extra = self.fields(mr, False, outcome.breaking_set)
            if outcome.details.get("max_removable_is_upper_bound"):
                extra["max_removable_is_upper_bound"] = True
                extra["max_removable_at_least"] = outcome.details.get("max_removable_at_least")
            return self.make(code, summary, mr, extra, witness=witness)
        margin, problem = self.recheck()
        self.evidence["margin_definition"] = (
            "smallest relative PBH singular value sigma_min([A - lambda I; C_T]) / ||[A; C]||"
            " over the kept-sensor sets T that come closest to breaking"
        )
        if problem is not None:
            self.evidence["disputed_max_removable"] = mr
            settled = self.unobservable_plant()
            if settled is not None:
                return settled
            return self.make(
                SparseCode.RECHECK_DISPUTED,
                f"The {outcome.method} method finds max_removable = {mr}, but "
                f"{recheck_text(problem)}.",
                None,
                self.fields(None, False, None),
                margin=margin,
            )
        summary = (
            f"Removing any {mr} of the {p} sensors keeps the plant observable, so up to "
            f"{mr // 2} attacked sensor{'' if mr // 2 == 1 else 's'} can be corrected "
            f"(s = {s} needed)."
        )
        return self.make(
            SparseCode.EXACT_MAX_REMOVABLE,
            summary,
            mr,
            self.fields(mr, False, outcome.breaking_set),
            margin=margin,
        )

    def lower_bound_answer(self) -> Check:
        """Every set of up to 2s sensors was checked: the verdict holds, max_removable is a
        lower bound."""
        outcome = self.outcome
        mr = outcome.max_removable
        assert mr is not None
        margin, problem = self.recheck()
        if problem is not None:
            summary = f"Lower bound max_removable >= {mr}, but {recheck_text(problem)}."
        else:
            summary = (
                f"Every set of up to {mr} sensors was checked and none breaks observability, "
                f"so s = {self.s} attacked sensors can be corrected; the exact max_removable was "
                f"not computed ({'; '.join(problem_texts(outcome.problems))})."
            )
        return self.make(
            SparseCode.LOWER_BOUND if problem is None else SparseCode.LOWER_BOUND_DISPUTED,
            summary,
            mr,
            self.fields(mr, True, None),
            margin=margin,
        )

    def undecided(self) -> Check:
        """No method decided: settled exactly when the plant is unobservable, by observability
        when s = 0, else inconclusive with the reasons and the sets still needed."""
        settled = self.unobservable_plant()
        if settled is not None:
            return settled
        reasons = [pr for o in self.tried for pr in problem_texts(o.problems)] or [
            "no method could decide"
        ]
        if self.s == 0:
            held = self.observability_decides(reasons)
            if held is not None:
                return held
        needed = next((o.needed for o in self.tried if o.needed is not None), None)
        outcome = self.outcome
        lower = outcome.max_removable if outcome.status is OutcomeStatus.LOWER_BOUND else None
        return self.make(
            SparseCode.UNDECIDED,
            undecided_summary(reasons, needed),
            lower,
            {**self.fields(lower, lower is not None, None), "sets_needed": needed},
        )

    def observability_decides(self, reasons: list[str]) -> Check | None:
        """With s = 0 the condition 0 <= max_removable is the observability of (A, C)."""
        plain = observability(self.system, tolerances=self.tol, eigen=self.eig)
        self.evidence["observability"] = {
            "verdict": plain.verdict.value,
            "summary": plain.summary,
        }
        if plain.verdict is not Verdict.HOLDS:
            return None
        return self.make(
            SparseCode.OBSERVABILITY_DECIDES,
            f"With s = 0 the condition 0 <= max_removable is the observability of (A, C), "
            f"which holds: {plain.summary} The exact max_removable was not computed "
            f"({'; '.join(reasons)}).",
            0,
            self.fields(0, True, None),
            margin=plain.margin,
        )
