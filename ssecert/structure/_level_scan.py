"""One level of the sensor-set enumeration: the sets of a range of colex ranks, screened.

A range of level k (removals of k of the q screened sensors, colex ranks
``[lo, hi)``) is scanned block by block: each block's Gramians (precomputed
partial sums plus the block's top) are screened for positive definiteness
(``ColexScreen``: a bound shared by the sets with the same largest sensor,
a single-precision Cholesky factorization with a proven margin, LAPACK's
where neither is conclusive; the decisions are LAPACK's); the sets that
fail are decided by an exact rank test of their kept sensors (``_refine``);
on the level that decides the verdict, the sets closest to breaking are kept
for the re-checks.  The batches are screened, and the failures refined, in
lexicographic order of the removed sets, so that a search for the first
breaking set ends there, and a deadline leaves the first sets decided.  The
findings do not depend on how the level is split into ranges, so ranges
run in-process, on Dask workers, or (a small synthetic level) in the cost
model's calibration give the same answers.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..numerics.linalg import single_precision_margin, stacked_rank
from ..tolerances import BORDERLINE, ZERO, Tolerances
from . import device as accelerator
from ._combinatorics import ColexScreen, DeviceScreenedBatch, ScreenedBatch

__all__: list[str] = []

_CRITICAL = 8  # critical sets re-checked per level

Progress = Callable[[int, int], None]


@dataclass
class _Level:
    checked: int = 0
    failures: dict[tuple[int, ...], np.ndarray] = field(default_factory=dict)
    # positions in lexicographic order of the sets with a borderline rank decision, ascending
    borderline_at: list[int] = field(default_factory=list)
    # (proxy, lexicographic position, kept sensors) of the sets closest to breaking: the
    # smallest by (proxy, position), whatever the split of the level into ranges
    critical: list[tuple[float, int, tuple[int, ...]]] = field(default_factory=list)
    # the failing sets decided by ``_refine`` and the seconds it took (the cost model's)
    refined: int = 0
    refine_seconds: float = 0.0
    ended: bool = False  # ``stop`` ended the search: the later sets were not checked
    # the deadline passed first: ``checked`` counts the sets decided, the first ones in
    # lexicographic order, and the later ones were not checked
    cut_short: bool = False
    ranges: int = 1  # the ranges the level was split into (more than one: on Dask workers)

    @property
    def borderline(self) -> int:
        return len(self.borderline_at)

    def merge(self, other: _Level) -> None:
        """Add the findings of another range of the same level (the next one in
        lexicographic order)."""
        self.checked += other.checked
        self.failures.update(other.failures)
        self.borderline_at.extend(other.borderline_at)
        self.critical = sorted(self.critical + other.critical)[:_CRITICAL]
        self.refined += other.refined
        self.refine_seconds += other.refine_seconds
        self.ended |= other.ended
        self.cut_short |= other.cut_short


@dataclass(frozen=True)
class _LevelTask:
    """What every range of one level's sets reads (sent once to Dask workers)."""

    P: np.ndarray
    ranks: np.ndarray
    proj: np.ndarray
    shifted: np.ndarray  # sum of all projectors minus the screening shift
    shift: float
    k: int
    rest: np.ndarray
    full: np.ndarray
    tol: Tolerances
    critical: bool
    errors: np.ndarray
    device: str | None = None  # screen on this accelerator (``device.DEVICES``), else the CPU


def _screen_margin(task: _LevelTask) -> float:
    """The single-precision screening margin of every Gramian of the level
    (``single_precision_margin``, with k single-precision additions behind each sum): each
    is the shifted sum of all projectors minus some, so its positive diagonal and its
    entries are bounded by those of the sum and of the projectors."""
    n = task.proj.shape[-1]
    diagonal = np.abs(np.diagonal(task.shifted)).sum() + n * task.shift
    frobenius = np.linalg.norm(task.shifted) + np.linalg.norm(task.proj, axis=(1, 2)).sum()
    return float(single_precision_margin(n, 1.01 * diagonal, 1.01 * frobenius, terms=task.k))


# sets screened together: tier 1 decides most sets of most levels, and its numpy calls are
# per batch (a refinement level of 593,775 sets at n = 10: 22 ms in batches of 16,384, 34 ms
# in batches of 4,096); tier 2 factors them ``TIER2_SETS`` at a time
_BATCH_SETS = 16384
# on the level that ranks the sets closest to breaking, the first batch (its threshold is not
# known before: tier 2 factors the whole batch)
_FIRST_RANKED_SETS = 4096
# then: tier 2 factors only the sets tier 1 does not prove above the threshold, gathered, and
# more of them at once cost less each (a factorization of 10 x 10 matrices: 60-70 ns a set
# 16,384 at once, 110 ns 4,096 at once)
_RANKED_BATCH_SETS = 16384


# failing sets decided together by ``_refine``'s SVDs: between two groups the scan can end
_REFINE_SETS = 256

# a range of sets sent to a Dask worker holds at least this many: a level of 658,008 sets
# (n = 10) took longer in 3 ranges on 2 workers than in-process (0.23-0.25 s against 0.15-0.23
# s), each range paying for its task, its data and its own partial sums
MIN_WORKER_SETS = 500_000


def _scan_range(
    task: _LevelTask,
    ranks: tuple[int, int],
    progress: Progress | None = None,
    *,
    stop: Callable[[_Level], bool] | None = None,
    deadline: float | None = None,
    shared: dict[tuple[Any, ...], Any] | None = None,
    segment: int | None = None,
) -> _Level:
    """Check the removals whose colex ranks lie in ``ranks`` (one chunk of a level; the
    sensors in ``task`` in reverse order, so a set of colex rank r is at position
    ``C(q, k) - 1 - r`` in the lexicographic order of the removed sets).

    The sets are screened in batches of consecutive ranks, from the last ranks down (in
    lexicographic order); the failures are refined block by block, the blocks of
    ``colex_blocks`` (the rank tolerance of ``_refine`` depends on the sets decided
    together), once the whole block is screened, in ``_refine``'s groups of
    ``_REFINE_SETS``, from the last down.  The findings do not depend on the order.

    ``stop(part)`` is offered the failures of each group, in lexicographic order; once it
    returns True the later sets are not checked (``ended``).  Once ``deadline`` (a
    ``time.monotonic()`` value) has passed, checked between batches and between groups, the
    scan ends (``cut_short``) and ``checked`` counts the sets decided, the first ones in
    lexicographic order.  ``shared``: a dict the caller keeps across the ranges of one level
    run in one process (``ColexScreen``'s levels of partial sums, computed once for them).
    ``segment``: the range is consecutive segments of this many ranks, each refined in the
    blocks it would have as a range of its own (``ColexScreen``)."""
    n = task.proj.shape[-1]
    level = _Level()
    candidates: list[tuple[float, int, tuple[int, ...]]] = []
    lo, hi = ranks
    if lo >= hi:
        return level
    kernel = None
    if task.device is not None and hi - lo >= accelerator.DEVICE_MIN_SETS:
        kernel = accelerator.device_kernel(task.device)
    source = ColexScreen(
        task.proj,
        task.shifted,
        task.k,
        _screen_margin(task),
        start=lo,
        stop=hi,
        factors=task.P,
        device=kernel,
        segment=segment,
        shared=shared,
    )
    if kernel is not None:
        batches = _batches(lo, hi, accelerator.DEVICE_BATCH_SETS)
    elif task.critical:
        batches = _batches(lo, hi, _RANKED_BATCH_SETS, _FIRST_RANKED_SETS)
    else:
        batches = _batches(lo, hi, _BATCH_SETS)
    size = max((last - first for first, last in batches), default=0)
    # the CPU's single-precision tier's buffers
    room = 0 if kernel is not None else min(size, source.tier2_sets)
    work = np.empty((n, n, room), dtype=np.float32)
    diagonal = np.empty((n, room), dtype=np.float32)
    pending = np.zeros(0, dtype=np.int64)  # failures of the blocks not wholly screened yet
    for first, last in batches:
        if deadline is not None and time.monotonic() > deadline:
            level.cut_short = True
            break
        threshold = None
        if task.critical:
            threshold = candidates[-1][0] if len(candidates) >= _CRITICAL else np.inf
        screen = source.screen(first, last, task.shift, threshold, work, diagonal)
        if task.critical:
            _keep_closest(
                candidates, screen, task.shift, task.rest, math.comb(task.rest.size, task.k)
            )
        failed = np.concatenate([first + screen.failed(), pending])
        level.checked += last - first
        pending = _refine_blocks(task, source, failed, first, level, stop, deadline)
        if level.ended or level.cut_short:
            break
        if progress is not None:
            progress(level.checked, hi - lo)
    if level.cut_short:
        # only the sets above the lowest rank not decided count (a lexicographic prefix)
        level.checked = hi - (int(pending[-1]) + 1 if pending.size else hi - level.checked)
        level.cut_short = level.checked < hi - lo
    level.borderline_at.sort()
    level.critical = candidates
    return level


def _batches(lo: int, hi: int, size: int, first: int | None = None) -> list[tuple[int, int]]:
    """The batches of ranks [lo, hi), from the last down: ``size`` ranks each from ``lo`` up
    (the last may be shorter), or, given ``first``, a first batch of ``first`` ranks below
    ``hi``, then ``size`` ranks each (the lowest may be shorter)."""
    if first is None:
        return [(start, min(start + size, hi)) for start in reversed(range(lo, hi, size))]
    if hi <= lo:
        return []
    out = [(max(hi - first, lo), hi)]
    while out[-1][0] > lo:
        out.append((max(out[-1][0] - size, lo), out[-1][0]))
    return out


def _refine_blocks(
    task: _LevelTask,
    source: ColexScreen,
    failed: np.ndarray,
    screened: int,
    level: _Level,
    stop: Callable[[_Level], bool] | None = None,
    deadline: float | None = None,
) -> np.ndarray:
    """Refine the failures (ascending colex ranks) of the blocks of ``colex_blocks`` that are
    wholly screened (that begin at ``screened`` or above), each as that block alone would be,
    from the last group down (``_scan_range``); returns the failures not refined, those of
    the block that is not wholly screened or, once the scan ends, all below."""
    if failed.size == 0:
        return failed
    begins, _ = source.spans(failed)
    cut = int(np.searchsorted(begins, screened, side="left"))
    edges = np.flatnonzero(begins[cut + 1 :] != begins[cut:-1]) + cut + 1
    for a, b in reversed(list(itertools.pairwise([cut, *edges.tolist(), failed.size]))):
        for g in reversed(range(a, b, _REFINE_SETS)):
            _refine_group(task, source, failed[g : min(g + _REFINE_SETS, b)], level, stop)
            if level.ended:
                return failed[:g]
            if deadline is not None and time.monotonic() > deadline:
                level.cut_short = True
                return failed[:g]
    return failed[:cut]


def _refine_group(
    task: _LevelTask,
    source: ColexScreen,
    ranks: np.ndarray,
    level: _Level,
    stop: Callable[[_Level], bool] | None,
) -> None:
    """Decide the failures of one group (ascending colex ranks) by ``_refine``, record them
    in ``level`` and offer them to ``stop``."""
    rest, full, q = task.rest, task.full, task.rest.size
    total = math.comb(q, task.k)
    began = time.monotonic()
    subsets = source.subsets(ranks)
    codes, _, nulls = _refine(task.P, task.ranks, subsets, q, task.tol, task.errors)
    level.refine_seconds += time.monotonic() - began
    level.refined += ranks.size
    part = _Level()
    for rank, row, code, zvec in zip(ranks.tolist(), subsets, codes, nulls):
        removed = tuple(sorted(full.tolist() + rest[row].tolist()))
        if code == ZERO:
            level.failures[removed] = zvec
            part.failures[removed] = zvec
        elif code == BORDERLINE:
            level.borderline_at.append(total - 1 - rank)
    if stop is not None and part.failures and stop(part):
        level.ended = True


def _keep_closest(
    candidates: list[tuple[float, int, tuple[int, ...]]],
    screen: ScreenedBatch | DeviceScreenedBatch,
    shift: float,
    rest: np.ndarray,
    total: int,
) -> None:
    """Merge the screened sets into ``candidates``, the ``_CRITICAL`` smallest (proxy,
    lexicographic position, kept sensors) so far; a set of colex rank r (sensors in reverse
    order) is at position ``total - 1 - r``.

    Only a set whose proxy is at most a threshold can enter: the largest proxy of a full
    list, and the largest of the ``_CRITICAL`` sets with the smallest lower bounds of the
    screening (the closest sets are at most that).  The proxies are computed (by LAPACK)
    only where the lower bound is at most the threshold: most batches add nothing and
    compute none."""
    threshold = candidates[-1][0] if len(candidates) >= _CRITICAL else np.inf
    rows, many = screen.below(threshold, _CRITICAL)
    if many:  # the proxies of the sets of the smallest bounds first: a lower threshold
        threshold = min(threshold, float(screen.proxies(rows, shift).max()))
        rows, _ = screen.below(threshold)
    if rows.size == 0:
        return
    proxy = screen.proxies(rows, shift)
    rows, proxy = rows[proxy <= threshold], proxy[proxy <= threshold]
    position = total - 1 - (screen.offset + rows)
    order = np.sort(np.lexsort((position, proxy))[:_CRITICAL])
    for j, value, removed in zip(rows[order], proxy[order], screen.subsets(rows[order])):
        dropped = set(rest[removed].tolist())
        kept = tuple(sorted(int(i) for i in rest if i not in dropped))
        candidates.append((float(value), total - 1 - screen.offset - int(j), kept))
    candidates.sort()
    del candidates[_CRITICAL:]


def _refine(
    P: np.ndarray,
    ranks: np.ndarray,
    removed: np.ndarray,
    q: int,
    tol: Tolerances,
    errors: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact rank decision for the kept sensors of each removed subset.

    The tolerance adds the basis errors of the kept sensors: a sum of
    subspaces that is rank deficient in exact arithmetic shows a smallest
    singular value up to about their sum.
    """
    n = P.shape[-1]
    codes = np.empty(removed.shape[0], dtype=np.int8)
    rel = np.empty(removed.shape[0])
    nulls = np.zeros((removed.shape[0], n))
    for start in range(0, removed.shape[0], 256):
        chunk = removed[start : start + 256]
        keep = np.ones((chunk.shape[0], q), dtype=bool)
        np.put_along_axis(keep, chunk, False, axis=1)
        kept = [np.flatnonzero(row) for row in keep]
        width = max((len(k) for k in kept), default=0)
        if width == 0:
            codes[start : start + len(chunk)] = ZERO
            nulls[start : start + len(chunk), 0] = 1.0
            continue
        idx = np.array([np.pad(k, (0, width - len(k)), constant_values=-1) for k in kept])
        stacks = P[idx]  # (N, width, n, n)
        stacks[idx < 0] = 0.0
        stacks = stacks.reshape(len(chunk), width * n, n)
        rows = int(max(ranks[k].sum() for k in kept))
        data_error = np.array([errors[k].sum() for k in kept])
        c, r, z = stacked_rank(stacks, tolerances=tol, rows=max(rows, 1), data_error=data_error)
        codes[start : start + len(chunk)] = c
        rel[start : start + len(chunk)] = r
        nulls[start : start + len(chunk)] = z
    return codes, rel, nulls
