"""Sparse observability by enumeration of sensor sets.

Sensor sets are checked by increasing size, so the first breaking set found
is a smallest one, lexicographically first among equals.  Each sensor's
observable row space comes from an orthogonal Krylov staircase; a set of
kept sensors is observable iff the sum of their orthogonal projectors is
positive definite, screened for many sets per numpy call (colex-ordered
partial sums; a bound shared by the sets with the same largest sensor, a
single-precision Cholesky factorization with the batch last, LAPACK's where
neither proves the answer: ``_level_scan``) and decided exactly by SVD where
screening fails.  Sensors that alone observe the whole state must all be
removed to break the plant, which prunes the search.  Float failures are
confirmed on the exact data (``_resolve_failures``).

``ssecert.structure.sparse`` combines this method with the eigenspace
method; ``ssecert.structure.removals`` scans one level of removals alone
(``scan_removals``).
"""

from __future__ import annotations

import enum
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..base.format import distance as format_distance
from ..numerics.exact import ExactPlant, Observability
from ..numerics.linalg import (
    EigenAnalysis,
    SensorSubspaces,
    sensor_subspaces,
)
from ..parallel import ChunkError, map_ranges, rank_ranges
from ..system import System
from ..tolerances import NONZERO, Tolerances
from . import device as accelerator
from ._combinatorics import (
    colex_rank,
    count_subsets,
    level_split,
)
from ._level_scan import (
    _BATCH_SETS,
    _REFINE_SETS,
    MIN_WORKER_SETS,
    _Level,
    _LevelTask,
    _refine,
    _scan_range,
)
from .cost import cost_of_the_rest, rounded_seconds, verdict_cost
from .observability import pbh_margins
from .outcomes import Problem, ProblemCode
from .sparse_messages import placement_text

__all__: list[str] = []


Progress = Callable[[int, int], None]

REFUTATION_LIMIT = 5_000  # float failures confirmed exactly per enumeration (about 1 ms each)
_REFINE_TIMING = 16  # copies of a set refined to time the refinement on a plant


class SparseMethod(enum.StrEnum):
    """Which method found an ``_Outcome``: the value is the name written in evidence."""

    ENUMERATION = "enumeration"
    EIGENSPACE = "eigenspace"
    EXACT_ARITHMETIC = "exact arithmetic"  # the exact data are unobservable with every sensor


class OutcomeStatus(enum.StrEnum):
    """How far an ``_Outcome`` got: the value is the word written in evidence."""

    EXACT = "exact"  # max_removable found
    LOWER_BOUND = "lower_bound"  # max_removable is at least the one found
    INCONCLUSIVE = "inconclusive"
    BUDGET = "budget"  # the eigenspace method's search ran out of hyperplanes or time


@dataclass
class _Outcome:
    """What one method found (internal)."""

    method: SparseMethod
    status: OutcomeStatus
    max_removable: int | None = None
    breaking_set: tuple[int, ...] | None = None
    z: np.ndarray | None = None
    checked: int = 0
    needed: int | None = None  # sets needed to finish, when over budget
    problems: list[Problem] = field(default_factory=list)
    critical: list[tuple[int, ...]] = field(default_factory=list)  # kept-sensor sets
    details: dict[str, Any] = field(default_factory=dict)
    refinement_seconds: float = 0.0  # spent past the verdict (not in the evidence: it varies)
    # with a Dask client, the levels (by sets' size) split over the workers (into how many
    # ranges) and those run in-process (not in the evidence: the answer is the same)
    on_workers: dict[int, int] = field(default_factory=dict)
    in_process: list[int] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.method, self.status = SparseMethod(self.method), OutcomeStatus(self.status)


def _enumeration(
    system: System,
    s: int,
    max_sets: int,
    tol: Tolerances,
    progress: Progress | None,
    subspaces: SensorSubspaces | None = None,
    eig: EigenAnalysis | None = None,
    exact: ExactPlant | None = None,
    time_budget: float | None = None,
    client: Any | None = None,
    device: str | None = None,
) -> _Outcome:
    """Remove every set of sensors, smallest first, until one breaks observability.

    The verdict needs the sets of up to 2s sensors; larger sets only refine
    max_removable, and with ``time_budget`` (seconds from the start) a level
    whose predicted end is past it is not started, and one still running
    when it ends stops there (the sets checked are the first in
    lexicographic order): the result is then a lower bound, with
    ``details["stopped_by_time_budget"]``.  With a Dask ``client`` each
    level is split over the workers, with the same findings; with a ``device``
    (``device.DEVICES``) the sets are screened there, with the same findings.
    """
    start = time.monotonic()
    n, p = system.n, system.p
    out = _Outcome(method=SparseMethod.ENUMERATION, status=OutcomeStatus.INCONCLUSIVE)
    sub = (
        subspaces if subspaces is not None else sensor_subspaces(system.A, system.C, tolerances=tol)
    )
    if sub.borderline.any():
        bad = np.flatnonzero(sub.borderline).tolist()
        out.problems.append(Problem.of(ProblemCode.BORDERLINE_SUBSPACE, sensors=tuple(bad)))
        return out
    full = np.flatnonzero(sub.ranks == n)  # must all be removed to break the plant
    rest = np.flatnonzero(sub.ranks < n)
    out.details = {
        "sensor_observable_dimensions": sub.ranks.tolist(),
        "sensors_observing_everything": full.tolist(),
    }
    if rest.size == 0:
        return _only_all_sensors(out, n, p, s)
    scan = _Levels(system, s, tol, eig, exact, client, progress, sub, full, rest, out, start)
    scan.device = device
    cost = _verdict_cost(rest.size, n, scan.target, client, time_budget)
    if cost is not None:
        out.details["cost_estimate"] = cost
    refining = 0.0  # seconds spent on the levels past the verdict's
    for k in range(rest.size + 1):
        if scan.past_time_budget(k, time_budget) or scan.past_set_budget(k, max_sets, time_budget):
            break
        began = time.monotonic()
        level = scan.level(k, time_budget)
        if level is not None and cost is not None and k == max(scan.target, 0):
            cost["measured_seconds_for_verdict"] = rounded_seconds(time.monotonic() - start)
        going = level is not None and scan.go_on(k, level)
        if k > max(scan.target, 0):
            refining += time.monotonic() - began
        if not going:
            break
    out.refinement_seconds = refining
    if out.status is OutcomeStatus.LOWER_BOUND and scan.undecided is not None:
        out.max_removable = scan.undecided - 1
    out.critical = [kept for _, _, kept in scan.best_critical]
    return out


def _only_all_sensors(out: _Outcome, n: int, p: int, s: int) -> _Outcome:
    """Every sensor alone observes the state: only removing all of them breaks the plant."""
    out.status = OutcomeStatus.EXACT
    out.max_removable = p - 1
    out.breaking_set = tuple(range(p))
    z = np.zeros(n)
    z[0] = 1.0
    out.z = z
    out.critical = [tuple(range(min(2 * s, p - 1), p))]
    return out


@dataclass
class _Found:
    """What the exact confirmation of a level's float failures found so far."""

    first: tuple[int, ...] | None = None  # the first breaking set, lexicographically
    z: np.ndarray | None = None  # its unobservable direction
    within: list[tuple[int, ...]] = field(default_factory=list)  # within precision of breaking


class _Levels:
    """The enumeration's state: the levels of removals scanned so far and what they found.

    Level k removes the sensors that alone observe the state (``full``) and
    k of the others (``rest``); ``target`` is the level of 2s removals.
    """

    def __init__(
        self,
        system: System,
        s: int,
        tol: Tolerances,
        eig: EigenAnalysis | None,
        exact: ExactPlant | None,
        client: Any | None,
        progress: Progress | None,
        sub: SensorSubspaces,
        full: np.ndarray,
        rest: np.ndarray,
        out: _Outcome,
        start: float,
    ) -> None:
        self.system, self.tol, self.eig, self.exact = system, tol, eig, exact
        self.client, self.progress, self.sub = client, progress, sub
        self.full, self.rest, self.out, self.start = full, rest, out, start
        self.P = sub.bases[rest]  # (q, n, n), zero-padded orthonormal rows
        self.proj = np.einsum("qkn,qkm->qnm", self.P, self.P)
        self.base = self.proj.sum(axis=0)
        self.target = 2 * s - full.size  # level whose sets have 2s removed sensors
        self.undecided: int | None = None  # size of the first removal level with undecided sets
        self.found = _Found()  # the current level's confirmed failures
        self.best_critical: list[tuple[float, int, tuple[int, ...]]] = []
        # failing sets refined by SVD so far, the seconds it took, and (once timed) the
        # seconds per set of a refinement on this plant before any was needed
        self.refined, self.refine_seconds = 0, 0.0
        self._refine_rate: float | None = None
        self._largest: list[np.ndarray] | None = None  # for ``_first_certain``
        self.time_budget: float | None = None  # of the level scanned last
        self.device: str | None = None  # the accelerator that screens the sets
        if self.target < 0:
            # every set of 2s sensors keeps a sensor that alone observes the state
            dropped = set(full[: 2 * s].tolist())
            kept = tuple(i for i in range(system.p) if i not in dropped)
            self.best_critical = [(0.0, 0, kept)]

    def removed(self, k: int) -> int:
        """Sensors removed by each set of level k."""
        return self.full.size + k

    def past_time_budget(self, k: int, time_budget: float | None) -> bool:
        """Whether to stop refining before level k: the verdict is settled (no set of up to 2s
        sensors breaks the plant) and the level is predicted to end past the budget."""
        out = self.out
        if time_budget is None or k <= max(self.target, 0) or not out.checked:
            return False
        q, count = self.rest.size, math.comb(self.rest.size, k)
        elapsed = time.monotonic() - self.start
        predicted = elapsed + self.predicted_seconds(k, elapsed, time_budget - elapsed)
        if predicted <= time_budget:
            return False
        out.needed = count_subsets(q, range(k, q + 1))
        out.status = OutcomeStatus.LOWER_BOUND
        out.max_removable = self.removed(k) - 1
        out.details["stopped_by_time_budget"] = {
            "time_budget_seconds": time_budget,
            "elapsed_seconds": round(elapsed, 3),
            "next_level_sets": count,
            "next_level_predicted_seconds": round(predicted - elapsed, 3),
        }
        out.problems.append(
            Problem.of(
                ProblemCode.TIME_BEFORE_LEVEL,
                budget=time_budget,
                sets=count,
                removed=self.removed(k),
                seconds=predicted - elapsed,
            )
        )
        return True

    def predicted_seconds(self, k: int, elapsed: float, left: float) -> float:
        """Seconds level k is predicted to take: the sets its scan checks, in lexicographic
        order up to the first one certain to break the plant (``_first_certain``) or all of
        them, at the seconds per set of the screening so far, and the failing sets it refines
        by SVD (as many per set as so far, and the group of ``_refine`` that holds the
        certain one) at the seconds per failing set so far, or else timed on that set (only
        when the screening leaves ``left`` seconds for them)."""
        count = math.comb(self.rest.size, k)
        screening = max(elapsed - self.refine_seconds, 0.0) / self.out.checked
        certain = self._first_certain(k)
        checked = count
        if certain is not None:
            # the scan screens whole batches, from the first set in lexicographic order
            position = self._position(certain, k)
            checked = min(count, -(-(position + 1) // _BATCH_SETS) * _BATCH_SETS)
        seconds = checked * screening
        failing = checked * self.refined / self.out.checked
        if certain is not None:
            failing += min(checked, _REFINE_SETS)
        if failing and seconds < left:
            seconds += failing * self._seconds_per_refined(certain)
        return seconds

    def _seconds_per_refined(self, certain: tuple[int, ...] | None) -> float:
        """Seconds per failing set refined by SVD: as measured so far, or else timed on
        ``_REFINE_TIMING`` copies of the set certain to break the plant (once)."""
        if self.refined:
            return self.refine_seconds / self.refined
        if self._refine_rate is None:
            if certain is None:
                return 0.0
            index = {int(sensor): i for i, sensor in enumerate(self.rest)}
            rows = np.array([[index[i] for i in certain if i in index]] * _REFINE_TIMING)
            began = time.monotonic()
            _refine(self.P, self.sub.ranks[self.rest], rows, self.rest.size, self.tol,
                    self.sub.errors[self.rest])  # fmt: skip
            self._refine_rate = (time.monotonic() - began) / _REFINE_TIMING
        return self._refine_rate

    def _first_certain(self, k: int) -> tuple[int, ...] | None:
        """The first removal of level k, in lexicographic order, that certainly breaks the
        plant: the kept sensors' observable dimensions add up to less than n (their sum
        of subspaces cannot be the state space); None when there is none."""
        r = self.sub.ranks[self.rest].astype(np.int64)
        q, n = r.size, self.system.n
        need = int(r.sum()) - n + 1  # the removed sensors' dimensions must add up to this
        if k == 0:
            return tuple(self.full.tolist()) if need <= 0 else None
        if self._largest is None:
            # [j][i]: the sum of the i + 1 largest dimensions among sensors j, j + 1, ...
            self._largest = [np.cumsum(np.sort(r[j:])[::-1]) for j in range(q)]
        best = self._largest
        if k > q or best[0][k - 1] < need:
            return None
        chosen: list[int] = []
        total, j = 0, 0
        for slot in range(k):
            left = k - slot - 1
            while total + r[j] + (best[j + 1][left - 1] if left else 0) < need:
                j += 1
            chosen.append(j)
            total += int(r[j])
            j += 1
        return tuple(sorted(self.full.tolist() + self.rest[chosen].tolist()))

    def past_set_budget(self, k: int, max_sets: int, time_budget: float | None) -> bool:
        """Whether level k would take the enumeration past ``max_sets`` (then a lower bound,
        with what the rest would cost)."""
        out, q = self.out, self.rest.size
        if out.checked + math.comb(q, k) <= max_sets:
            return False
        out.needed = count_subsets(q, range(k, max(self.target, k) + 1))
        out.status = OutcomeStatus.LOWER_BOUND
        out.max_removable = self.removed(k) - 1
        removed = self.removed(k)
        rest = cost_of_the_rest(q, self.system.n, k, self.target, self.client, time_budget)
        seconds, workers = rest if rest is not None else (None, None)
        out.problems.append(
            Problem.of(
                ProblemCode.SET_BUDGET,
                max_sets=max_sets,
                removed=removed,
                seconds=seconds,
                workers=workers,
                time_budget=time_budget,
            )
        )
        return True

    def level(self, k: int, time_budget: float | None = None) -> _Level | None:
        """Scan level k (on the Dask workers when there is a client); None, with the reason,
        when a range of it failed twice there.  A level past the verdict's ends when the
        ``time_budget`` (seconds from the start) does."""
        self.found = _Found()
        self.time_budget, deadline = time_budget, None
        if time_budget is not None and k > max(self.target, 0):
            deadline = self.start + time_budget
        try:
            level = _scan_level(
                self.P,
                self.sub.ranks[self.rest],
                self.proj,
                self.base,
                k,
                self.rest,
                self.full,
                self.tol,
                critical=(k == self.target),
                progress=self.progress,
                errors=self.sub.errors[self.rest],
                client=self.client,
                stop=self._confirms,
                deadline=deadline,
                device=self.device,
            )
        except ChunkError as exc:
            out = self.out
            out.status = OutcomeStatus.LOWER_BOUND
            out.max_removable = self.removed(k) - 1
            # the level's ranges are colex ranks of the sensors in reverse order: as positions
            # in the lexicographic order of the removed sets, they are counted from the end
            total = math.comb(self.rest.size, k)
            first, last = total - exc.chunk[1], total - 1 - exc.chunk[0]
            out.details["failed_chunk"] = {
                "removed_sensors": self.removed(k),
                "lexicographic_positions": [first, last],
            }
            out.problems.append(
                Problem.of(
                    ProblemCode.WORKERS_FAILED,
                    removed=self.removed(k),
                    first=first,
                    last=last,
                    cause=repr(exc.cause),
                )
            )
            return None
        if self.client is not None:
            self._record_placement(k, level)
        self.out.checked += level.checked
        self.refined += level.refined
        self.refine_seconds += level.refine_seconds
        if level.critical:
            self.best_critical = level.critical
        return level

    def _record_placement(self, k: int, level: _Level) -> None:
        """Record whether level k ran on the Dask workers or in-process (``placement_note``)."""
        if level.ranges > 1:
            self.out.on_workers[self.removed(k)] = level.ranges
        else:
            self.out.in_process.append(self.removed(k))

    def _confirms(self, part: _Level) -> bool:
        """Confirm the float failures of the next range of the level (in lexicographic order,
        after those of every earlier range) on the exact data; whether one breaks the plant,
        which ends the level: the first breaking set in lexicographic order is found."""
        first, z, within = _resolve_failures(
            self.system, part.failures, self.eig, self.tol, self.exact, self.out
        )
        self.found.within.extend(within)
        if first is None:
            return False
        self.found.first, self.found.z = first, z
        return True

    def go_on(self, k: int, level: _Level) -> bool:
        """Record what level k decided; whether the next level must be scanned."""
        out = self.out
        first, z_first, within = self.found.first, self.found.z, self.found.within
        if first is not None:
            self._breaking(k, level, first, z_first, within)
            return False
        if level.cut_short:
            self._cut_short(k, level, within)
            return False
        if self.undecided is not None and not (level.borderline or within):
            return k < self.target
        if level.borderline or within:
            out.status = OutcomeStatus.LOWER_BOUND
            out.max_removable = self.removed(k) - 1
            if self.undecided is not None:  # reported at the first undecided level
                if k < self.target:
                    return True
                out.max_removable = self.undecided - 1
                return False
            self.undecided = self.removed(k)
            self._undecided_reasons(k, level, within)
            # a larger set of at most 2s sensors may still break the plant for certain
            return k < self.target
        return True

    def _cut_short(self, k: int, level: _Level, within: list[tuple[int, ...]]) -> None:
        """The time budget ended level k after its first ``level.checked`` sets in
        lexicographic order, none of which breaks the plant: max_removable is at least the
        size of the level before."""
        out, q = self.out, self.rest.size
        count, removed = math.comb(q, k), self.removed(k)
        out.status = OutcomeStatus.LOWER_BOUND
        out.max_removable = removed - 1
        out.needed = count_subsets(q, range(k, q + 1)) - level.checked
        if (level.borderline or within) and self.undecided is None:
            self.undecided = removed
            self._undecided_reasons(k, level, within)
        out.details["stopped_by_time_budget"] = {
            "time_budget_seconds": self.time_budget,
            "elapsed_seconds": round(time.monotonic() - self.start, 3),
            "level_sets": count,
            "level_sets_checked": level.checked,
            "level_removed_sensors": removed,
        }
        out.problems.append(
            Problem.of(
                ProblemCode.TIME_WITHIN_LEVEL,
                budget=self.time_budget,
                checked=level.checked,
                sets=count,
                removed=removed,
            )
        )

    def _breaking(
        self,
        k: int,
        level: _Level,
        first: tuple[int, ...],
        z_first: np.ndarray | None,
        within: list[tuple[int, ...]],
    ) -> None:
        """Level k holds the smallest breaking set ``first`` (or, after undecided levels, a
        breaking set that bounds max_removable from above)."""
        out = self.out
        out.status = OutcomeStatus.EXACT
        out.max_removable = self.removed(k) - 1
        out.breaking_set = first
        out.z = z_first
        # what the level needed: the sets up to the first breaking one, lexicographically (a
        # split into ranges may have checked a few more, which are not counted)
        position = self._position(first, k)
        out.checked -= level.checked - (position + 1)
        borderline = sum(1 for b in level.borderline_at if b < position)
        if borderline or within:
            out.details["borderline_sets_at_breaking_size"] = borderline + len(within)
        if self.undecided is not None:
            # smaller sets were undecided, so this set need not be the smallest: the verdict
            # (a breaking set of at most 2s sensors) is certain, max_removable only bounded
            out.details["max_removable_is_upper_bound"] = True
            out.details["max_removable_at_least"] = self.undecided - 1

    def _position(self, removed: tuple[int, ...], k: int) -> int:
        """Position of the removed set in the lexicographic order of level k's sets."""
        q = self.rest.size
        index = {int(sensor): i for i, sensor in enumerate(self.rest)}
        reverse = sorted(q - 1 - index[i] for i in removed if i in index)
        return math.comb(q, k) - 1 - colex_rank(reverse)

    def _undecided_reasons(self, k: int, level: _Level, within: list[tuple[int, ...]]) -> None:
        """Why the first undecided level could not be decided: borderline rank decisions, or
        sets within floating-point precision of breaking the plant."""
        out = self.out
        if level.borderline:
            out.problems.append(
                Problem.of(
                    ProblemCode.BORDERLINE_SETS, count=level.borderline, removed=self.removed(k)
                )
            )
        if not within:
            return
        out.details["within_precision_of_breaking"] = [list(w) for w in within[:8]]
        distance = out.details.get("distance_to_breaking")
        out.problems.append(
            Problem.of(
                ProblemCode.WITHIN_PRECISION,
                sensors=tuple(within[0]),
                others=len(within) - 1,
                distance=format_distance(distance) if distance is not None else None,
            )
        )


CALIBRATE_ABOVE = 200_000  # sets for the verdict: below, the enumeration takes about a second


def _verdict_cost(
    q: int, n: int, target: int, client: Any | None, time_budget: float | None
) -> dict[str, Any] | None:
    """The estimated cost of the levels that decide the verdict, when they are many sets."""
    if count_subsets(q, range(max(target, 0) + 1)) <= CALIBRATE_ABOVE:
        return None
    return verdict_cost(q, n, target, client, time_budget)


def _clearly_observable(
    system: System, kept: tuple[int, ...], eig: EigenAnalysis | None, tol: Tolerances
) -> bool:
    """Float evidence, independent of the Krylov screening, that (A, C_kept) is observable
    with a margin beyond the borderline band (PBH at every eigenvalue group and the
    conservative staircase)."""
    from ..numerics.linalg import staircase

    if eig is None or eig.problems or not kept:
        return False
    Ck = system.C[list(kept)]
    centers = np.array([c.center for c in eig.clusters], dtype=complex)
    _, codes = pbh_margins(system.A, Ck, centers, tolerances=tol)
    if not np.all(codes == NONZERO):
        return False
    sc = staircase(system.A, Ck, tolerances=tol, error_model="compound")
    return sc.rank == system.n and not sc.problem


def _distance(
    system: System, kept: tuple[int, ...], eig: EigenAnalysis | None, tol: Tolerances
) -> float | None:
    """Smallest relative PBH singular value of (A, C_kept) over the eigenvalue groups and the
    computed eigenvalues: how far the kept sensors are from losing observability."""
    if not kept:
        return 0.0
    Ck = system.C[list(kept)]
    points = [c.center for c in eig.clusters] if eig is not None else []
    lam = np.linalg.eigvals(system.A)
    points.extend(lam[lam.imag >= 0])
    m, _ = pbh_margins(system.A, Ck, np.array(points, dtype=complex), tolerances=tol)
    return float(m.min()) if m.size else None


def _resolve_failures(
    system: System,
    failures: dict[tuple[int, ...], np.ndarray],
    eig: EigenAnalysis | None,
    tol: Tolerances,
    exact: ExactPlant | None,
    out: _Outcome,
) -> tuple[tuple[int, ...] | None, np.ndarray | None, list[tuple[int, ...]]]:
    """Confirm the float failures of a level on the exact data, in lexicographic order.

    Returns the first breaking set that survives (exactly unobservable, or
    undecidable exactly and kept on the float evidence) with its direction,
    and the sets that are exactly observable but within floating-point
    precision of unobservable.  Sets that are exactly observable with a clear
    margin were float mistakes (basis errors amplified by defective
    eigenvalues) and are dropped, counted in ``out.details``.
    """
    p = system.p
    within: list[tuple[int, ...]] = []
    for removed in sorted(failures):
        if exact is None:
            return removed, failures[removed], within
        if out.details.get("float_failures_refuted_exactly", 0) >= REFUTATION_LIMIT:
            # the float screening is wrong too often on this plant to be worth confirming
            # set by set; what is left counts as undecided
            out.details["refutation_limit_reached"] = True
            within.append(removed)
            continue
        gone = set(removed)
        kept = tuple(i for i in range(p) if i not in gone)
        decision = exact.observability(kept)
        if decision.state is Observability.UNOBSERVABLE:
            out.details["breaking_set_exact"] = True
            return removed, decision.z, within
        if decision.state is Observability.UNKNOWN:
            out.details["breaking_set_exact"] = False
            return removed, failures[removed], within
        if _clearly_observable(system, kept, eig, tol):
            out.details["float_failures_refuted_exactly"] = (
                out.details.get("float_failures_refuted_exactly", 0) + 1
            )
        else:
            within.append(removed)
            if "distance_to_breaking" not in out.details:
                # of the lexicographically first such set of the first level that has one: the
                # set the summary names, whatever the split of the level into ranges
                out.details["distance_to_breaking"] = _distance(system, kept, eig, tol)
    return None, None, within


# a level is split over Dask workers in ranges of at least this many sets, and of at least
# this many times the precomputed partial sums every range recomputes
MIN_CHUNK_SETS = 200_000
_CHUNK_OVER_LEVEL = 20
# ... and on Dask workers, of at least ``MIN_WORKER_SETS``


def _chunks(task: _LevelTask, client: Any | None, segments: bool = False) -> list[tuple[int, int]]:
    """Ascending ranges of colex ranks covering the level, none smaller than is worth a task:
    the minimum, and many times the partial sums each range rebuilds.  Without a client, one
    range, or with ``segments`` (a search that may end early) ranges of that smallest size."""
    q, n = task.rest.size, task.proj.shape[-1]
    m = level_split(q, task.k, 8 * n * n)
    smallest = max(MIN_CHUNK_SETS, _CHUNK_OVER_LEVEL * math.comb(q, m))
    total = math.comb(q, task.k)
    if client is None and segments:
        return [(lo, min(lo + smallest, total)) for lo in range(0, total, smallest)]
    return rank_ranges(total, client, max(smallest, MIN_WORKER_SETS))


def _scan_level(
    P: np.ndarray,
    ranks: np.ndarray,
    proj: np.ndarray,
    base: np.ndarray,
    k: int,
    rest: np.ndarray,
    full: np.ndarray,
    tol: Tolerances,
    *,
    critical: bool = False,
    progress: Progress | None = None,
    errors: np.ndarray | None = None,
    client: Any | None = None,
    stop: Callable[[_Level], bool] | None = None,
    deadline: float | None = None,
    device: str | None = None,
) -> _Level:
    """Check the removals of ``full`` plus k sensors of ``rest``, in lexicographic order.

    The sets are visited in lexicographic order of the removed sensors: the
    colex ranks of the sensors taken in reverse order, from the last rank
    down.  The level is split into ranges of ranks (on the Dask workers with
    a ``client``); the sums, screening and refinement of each set do not
    depend on the split, so the findings are the in-process ones.
    ``stop(part)`` is offered the findings in that order (in-process, each
    group of failures that ``_refine`` decides together; on Dask, each
    range's); once it returns True, the later sets are not checked, and the
    level holds the findings so far.  Once ``deadline`` (a
    ``time.monotonic()`` value) has passed, the level ends likewise
    (``cut_short``; in-process between batches of sets and groups of
    failures, on Dask between ranges), ``checked`` counting the sets decided.
    """
    q = rest.size
    n = proj.shape[-1]
    if errors is None:
        errors = np.zeros(q)
    # A set that is rank deficient in exact arithmetic shows a smallest
    # eigenvalue up to about sum(err_i^2) <= (sum err_i)^2 when the sensors'
    # bases carry errors err_i: screen at least that far from zero.
    shift = max(tol.screen_rtol * max(q, 1), 10.0 * float(np.sum(errors)) ** 2)
    # the screening shift is folded into the base once, not per block; the sensors in reverse
    # order, so that descending colex ranks are ascending lexicographic order
    back = slice(None, None, -1)
    task = _LevelTask(
        P[back], ranks[back], proj[back], base - shift * np.eye(n), shift, k, rest[back], full,
        tol, critical, errors[back], device,
    )  # fmt: skip
    chunks = _chunks(task, client, segments=stop is not None)
    segment = None
    if client is None and task.device is not None and len(chunks) > 1:
        # an accelerator screens a few of these ranges at once, each refined in its own blocks
        segment = chunks[0][1] - chunks[0][0]
        chunks = _joined(chunks, max(1, accelerator.DEVICE_BATCH_SETS // segment))
    chunks = chunks[::-1]
    if client is None:
        level = _Level()
        total, done = sum(hi - lo for lo, hi in chunks), 0
        shared: dict[tuple[Any, ...], Any] = {}  # the partial sums, once for every range
        for chunk in chunks:
            part = _scan_range(
                task,
                chunk,
                _from(progress, done, total),
                stop=stop,
                deadline=deadline,
                shared=shared,
                segment=segment,
            )
            level.merge(part)
            done += chunk[1] - chunk[0]
            if part.ended or part.cut_short:
                break
        return level
    if len(chunks) == 1:
        level = _scan_range(task, chunks[0], progress)
        if stop is not None:
            level.ended = stop(level)
        return level
    offered = 0

    def ends(part: _Level) -> bool:
        nonlocal offered
        offered += 1
        if stop is not None and stop(part):
            part.ended = True
        elif deadline is not None and offered < len(chunks) and time.monotonic() > deadline:
            part.cut_short = True
        return part.ended or part.cut_short

    level = _Level(ranges=len(chunks))
    for part in map_ranges(_scan_range, task, chunks, client, progress, stop=ends):
        level.merge(part)
    return level


def _joined(chunks: list[tuple[int, int]], count: int) -> list[tuple[int, int]]:
    """Ascending ranges joined ``count`` at a time."""
    return [
        (chunks[i][0], chunks[min(i + count, len(chunks)) - 1][1])
        for i in range(0, len(chunks), count)
    ]


def placement_note(outcome: _Outcome) -> str | None:
    """What ran where, for an enumeration given a Dask client (None without one): a level is
    split only into ranges of at least ``MIN_WORKER_SETS`` sets and of ``_CHUNK_OVER_LEVEL``
    times the partial sums each range rebuilds; a level too small for two runs in-process
    (words: ``sparse_messages.placement_text``)."""
    if not outcome.on_workers and not outcome.in_process:
        return None
    return placement_text(
        outcome.on_workers, outcome.in_process, MIN_WORKER_SETS, _CHUNK_OVER_LEVEL
    )


def _from(progress: Progress | None, done: int, total: int) -> Progress | None:
    """``progress`` of a range that starts ``done`` sets into a level of ``total``."""
    if progress is None:
        return None
    return lambda checked, _: progress(done + checked, total)
