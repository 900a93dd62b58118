"""The refinement of max_removable past the verdict keeps its time budget.

The levels past the verdict's are scanned in lexicographic order of the
removed sets, the failing sets refined lazily (a group of ``_refine`` at a
time) and the scan ends at the first breaking set or once the time budget
has passed: what it reports then is the first sets of the level, none of
which breaks the plant, and max_removable as a lower bound.  No test here
asserts an absolute time: a deadline is simulated with a clock, or a run
with a budget is compared with the many times longer run it cuts short.
"""

import functools
import itertools
import math
import time

import numpy as np
import pytest

from ssecert import System
from ssecert.numerics.linalg import balanced_units, sensor_subspaces
from ssecert.structure import _level_scan
from ssecert.structure.enumeration import _Levels, _Outcome, _scan_level
from ssecert.structure.outcomes import ProblemCode, SparseCode
from ssecert.structure.sparse import sparse_observability
from ssecert.tolerances import Tolerances


def _static(n: int, p: int, seed: int = 0) -> System:
    """A = I with p generic sensors: removing any p - n + 1 of them breaks the plant (the
    kept rows cannot span the state), every set of p - n or fewer keeps it observable."""
    return System(np.eye(n), np.random.default_rng(seed).standard_normal((p, n)))


def test_a_breaking_level_where_every_set_fails_ends_at_its_first_set(monkeypatch):
    # every set of 11 of the 20 sensors breaks the plant: the scan of that level refines the
    # first group of failures in lexicographic order and stops at the first one, instead of
    # refining all 167,960 of them (14 s of the 5 s budget, past the verdict's 0.1 s)
    n, p = 10, 20
    refined = {}
    level = _Levels.level

    def record(self, k, time_budget=None):
        found = level(self, k, time_budget)
        refined[k] = found.refined
        return found

    monkeypatch.setattr(_Levels, "level", record)
    check = sparse_observability(_static(n, p), 2, time_budget=None)
    assert 0 < refined[p - n + 1] <= _level_scan._REFINE_SETS
    assert check.verdict.value == "holds"
    assert check.fields["max_removable"] == p - n
    assert not check.fields["max_removable_is_lower_bound"]
    assert check.fields["breaking_set"] == list(range(p - n + 1))
    # the sets of up to 10 sensors, and the first one of 11
    assert (
        check.evidence["methods_tried"][0]["sets_checked"]
        == sum(math.comb(p, k) for k in range(p - n + 1)) + 1
    )
    budgeted = sparse_observability(_static(n, p), 2)
    assert budgeted.fields == check.fields


@pytest.mark.parametrize("budget", [None, 5.0, 0.0])
@pytest.mark.parametrize("seed", range(4))
def test_the_budget_never_changes_the_verdict_or_the_first_breaking_set(seed, budget):
    # sensors of a few distinct rows, so that small sets break the plant; s = 1 or 2
    rng = np.random.default_rng(seed)
    n, p = 3, 9
    rows = rng.integers(-2, 3, (4, n)).astype(float)
    C = rows[rng.integers(0, 4, p)] + (rng.random((p, n)) < 0.3) * rng.integers(-1, 2, (p, n))
    A = np.diag([1.0, 0.5, 0.25])
    for s in (1, 2):
        exact = sparse_observability(System(A, C), s, method="enumeration", time_budget=None)
        check = sparse_observability(System(A, C), s, method="enumeration", time_budget=budget)
        assert check.verdict == exact.verdict
        if check.verdict.value == "fails" or not check.fields["max_removable_is_lower_bound"]:
            assert check.fields == exact.fields
        else:
            assert 2 * s <= check.fields["max_removable"] <= exact.fields["max_removable"]
        # the breaking set is a smallest one, lexicographically first among equals
        mr = exact.fields["max_removable"]
        first = next(
            removed
            for removed in itertools.combinations(range(p), mr + 1)
            if np.linalg.matrix_rank(
                System(A, C)
                .sensor_blocks(n)[[i for i in range(p) if i not in removed]]
                .reshape(-1, n)
            )
            < n
        )
        assert exact.fields["breaking_set"] == list(first)


def _every_set_fails(n: int = 6, p: int = 14):
    """A level of a static plant where every set fails (k = p - n + 1 removed): its scan's
    arguments."""
    tol = Tolerances()
    system = balanced_units(_static(n, p)).system
    sub = sensor_subspaces(system.A, system.C, tolerances=tol)
    rest = np.arange(p)
    P = sub.bases
    proj = np.einsum("qkn,qkm->qnm", P, P)
    args = (P, sub.ranks, proj, proj.sum(axis=0), p - n + 1, rest, np.zeros(0, dtype=np.int64))
    return args, tol, sub.errors


class _Clock:
    """time.monotonic for the scan: one second per reading."""

    def __init__(self) -> None:
        self.now = 0.0

    def monotonic(self) -> float:
        self.now += 1.0
        return self.now


@pytest.mark.parametrize("readings", [1, 3, 10, 40, 200])
def test_a_deadline_ends_a_level_after_its_first_sets_in_lexicographic_order(readings, monkeypatch):
    # blocks of 64 sets, batches of 48 (a block's failures wait for the next batch) and
    # groups of 16 failures: the deadline can pass between any two of them
    monkeypatch.setattr(
        _level_scan, "ColexScreen", functools.partial(_level_scan.ColexScreen, chunk_bytes=1)
    )
    monkeypatch.setattr(_level_scan, "_BATCH_SETS", 48)
    monkeypatch.setattr(_level_scan, "_REFINE_SETS", 16)
    args, tol, errors = _every_set_fails()
    whole = _scan_level(*args, tol, errors=errors)
    total = math.comb(14, args[4])
    assert whole.checked == total and len(whole.failures) == total and not whole.cut_short
    monkeypatch.setattr(_level_scan, "time", _Clock())
    cut = _scan_level(*args, tol, errors=errors, deadline=float(readings))
    assert cut.cut_short and 0 <= cut.checked < total
    # the sets decided are the first ones in lexicographic order, decided as in the whole
    # scan (every set of this level fails, so they are the failures)
    first = sorted(whole.failures)[: cut.checked]
    assert sorted(cut.failures) == first
    for removed in first:
        assert np.array_equal(cut.failures[removed], whole.failures[removed])
    assert cut.refined == cut.checked
    if readings >= 10:
        assert cut.checked > 0


def test_a_deadline_that_has_passed_decides_nothing_and_one_in_the_future_everything(
    monkeypatch,
):
    args, tol, errors = _every_set_fails()
    passed = _scan_level(*args, tol, errors=errors, deadline=time.monotonic() - 1.0)
    assert passed.cut_short and passed.checked == 0 and not passed.failures
    later = _scan_level(*args, tol, errors=errors, deadline=time.monotonic() + 3600.0)
    assert not later.cut_short and later.checked == math.comb(14, args[4])


def test_the_budget_stops_a_level_that_runs_past_it(monkeypatch, sparse_problems):
    # every level starts, whatever its prediction: the deadline inside a level must end it;
    # the exact refinement of this plant takes minutes (levels of millions of sets)
    monkeypatch.setattr(_Levels, "past_time_budget", lambda self, k, time_budget: False)
    system = _static(10, 26)
    budget = 0.5
    timing: dict[str, float] = {}
    check = sparse_observability(system, 1, method="enumeration", time_budget=budget, timing=timing)
    assert check.verdict.value == "holds"
    assert check.fields["max_removable_is_lower_bound"]
    stopped = check.evidence["stopped_by_time_budget"]
    assert stopped["time_budget_seconds"] == budget
    assert 0 <= stopped["level_sets_checked"] < stopped["level_sets"]
    removed = stopped["level_removed_sensors"]
    assert check.fields["max_removable"] == removed - 1
    # the reason says where in the level it stopped (its words: tests/test_problem_messages.py)
    assert check.code is SparseCode.LOWER_BOUND
    [[problems]] = sparse_problems
    (within,) = [p for p in problems if p.code is ProblemCode.TIME_WITHIN_LEVEL]
    assert within.facts == {
        "budget": budget,
        "checked": stopped["level_sets_checked"],
        "sets": stopped["level_sets"],
        "removed": removed,
    }
    # the whole refinement would take far longer than this generous multiple of the budget
    assert timing["refinement_seconds"] < 20 * budget + 5.0
    verdict_only = sparse_observability(system, 1, method="enumeration", time_budget=0.0)
    assert verdict_only.verdict == check.verdict
    assert verdict_only.fields["max_removable"] == 2  # the verdict's level, no refinement


def test_a_zero_budget_refines_nothing_on_the_plant_whose_every_breaking_set_fails():
    timing: dict[str, float] = {}
    check = sparse_observability(_static(10, 20), 2, time_budget=0.0, timing=timing)
    assert check.verdict.value == "holds"
    assert check.fields["max_removable"] == 4 and check.fields["max_removable_is_lower_bound"]
    assert timing["refinement_seconds"] == 0.0
    assert check.evidence["methods_tried"][0]["sets_checked"] == sum(
        math.comb(20, k) for k in range(5)
    )


def _levels(system: System, s: int) -> _Levels:
    tol = Tolerances()
    sub = sensor_subspaces(system.A, system.C, tolerances=tol)
    full = np.flatnonzero(sub.ranks == system.n)
    rest = np.flatnonzero(sub.ranks < system.n)
    out = _Outcome(method="enumeration", status="inconclusive")
    return _Levels(system, s, tol, None, None, None, None, sub, full, rest, out, 0.0)


@pytest.mark.parametrize("seed", range(6))
def test_the_first_set_certain_to_break_is_the_first_in_lexicographic_order(seed):
    # sensors that observe 1 to 3 of the 4 modes: a set whose kept sensors' observable
    # dimensions add up to less than n cannot observe the state
    rng = np.random.default_rng(seed)
    n, p = 4, 9
    A = np.diag([1.0, 0.5, -0.5, 0.25])
    C = rng.standard_normal((p, n)) * (rng.random((p, n)) < 0.6)
    C[:, 0] += rng.random(p) < 0.2  # a few sensors that see mode 0
    scan = _levels(System(A, C), 1)
    ranks = dict(zip(scan.rest.tolist(), scan.sub.ranks[scan.rest].tolist()))
    for k in range(scan.rest.size + 1):
        certain = [
            removed
            for removed in itertools.combinations(scan.rest.tolist(), k)
            if sum(r for i, r in ranks.items() if i not in removed) < n
        ]
        expected = tuple(sorted(scan.full.tolist() + list(certain[0]))) if certain else None
        assert scan._first_certain(k) == expected


def test_the_prediction_counts_the_refinement_of_failing_sets():
    # after the levels up to 10 with their refinement timed, the level of 11 sensors (every
    # set certain to break, the first one first): its prediction counts one group of
    # failures at the measured seconds per failing set, however slow the refinement
    scan = _levels(_static(10, 20), 2)
    scan.out.checked = sum(math.comb(20, k) for k in range(11))
    elapsed = 10.0
    assert scan._first_certain(10) is None
    assert scan._first_certain(11) == tuple(range(11))
    scan.refined, scan.refine_seconds = 4, 0.0
    free = scan.predicted_seconds(11, elapsed, 1000.0)
    scan.refine_seconds = 4.0  # one second per failing set
    slow = scan.predicted_seconds(11, elapsed, 1000.0)
    # the screening's seconds are those not spent refining: what changes is the group of
    # failures that holds the first set of the level, at one second each
    assert slow - free == pytest.approx(_level_scan._REFINE_SETS)
    # the level of 10 sensors has no set certain to break: all of it is screened
    whole = scan.predicted_seconds(10, elapsed, 1000.0)
    assert whole >= math.comb(20, 10) * (elapsed - 4.0) / scan.out.checked


def test_enumeration_records_the_refinement_rate():
    # the levels' failing sets and seconds add up in the enumeration's state, which the
    # prediction of the next level reads
    scan = _levels(_static(4, 9), 1)
    for k in range(7):
        scan.level(k)
    assert scan.refined > 0 and scan.refine_seconds > 0.0
    assert scan.found.first == tuple(range(6))
