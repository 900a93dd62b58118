"""One level of the sensor-set enumeration: the sets of a range of colex ranks, screened.

A range of level k (removals of k of the q screened sensors, colex ranks
``[lo, hi)``) is scanned block by block: each block's Gramians (precomputed
partial sums plus the block's top) are screened by Cholesky; the sets that
fail are decided by an exact rank test of their kept sensors (``_refine``);
on the level that decides the verdict, the sets closest to breaking are kept
for the re-checks.  The findings do not depend on how the level is split
into ranges, so ranges run in-process, on Dask workers, or (a small
synthetic level) in the cost model's calibration give the same answers.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .._linalg import stacked_rank
from ..tolerances import BORDERLINE, ZERO, Tolerances
from ._combinatorics import SubsetBlock, cholesky_screen, colex_blocks

__all__: list[str] = []

_CRITICAL = 8  # critical sets re-checked per level

Progress = Callable[[int, int], None]


@dataclass
class _Level:
    checked: int = 0
    failures: dict[tuple[int, ...], np.ndarray] = field(default_factory=dict)
    # positions in lexicographic order of the sets with a borderline rank decision
    borderline_at: list[int] = field(default_factory=list)
    # (proxy, lexicographic position, kept sensors) of the sets closest to breaking: the
    # smallest by (proxy, position), whatever the split of the level into ranges
    critical: list[tuple[float, int, tuple[int, ...]]] = field(default_factory=list)

    @property
    def borderline(self) -> int:
        return len(self.borderline_at)

    def merge(self, other: _Level) -> None:
        """Add the findings of another range of the same level."""
        self.checked += other.checked
        self.failures.update(other.failures)
        self.borderline_at.extend(other.borderline_at)
        self.critical = sorted(self.critical + other.critical)[:_CRITICAL]


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


def _scan_range(
    task: _LevelTask, ranks: tuple[int, int], progress: Progress | None = None
) -> _Level:
    """Check the removals whose colex ranks lie in ``ranks`` (one chunk of a level; the
    sensors in ``task`` in reverse order, so a set of colex rank r is at position
    ``C(q, k) - 1 - r`` in the lexicographic order of the removed sets)."""
    P, proj, rest, full, tol = task.P, task.proj, task.rest, task.full, task.tol
    n = proj.shape[-1]
    q = rest.size
    level = _Level()
    candidates: list[tuple[float, int, tuple[int, ...]]] = []
    buffer = np.empty((0, n, n))
    lo, hi = ranks
    total = math.comb(q, task.k)
    for block in colex_blocks(proj, task.shifted, task.k, start=lo, stop=hi):
        if buffer.shape[0] < len(block):
            buffer = np.empty((len(block), n, n))
        ok, proxy = cholesky_screen(block.matrices, task.shift, task.critical, buffer[: len(block)])
        if task.critical:
            _keep_closest(candidates, block, proxy, rest, total)
        bad = np.flatnonzero(~ok)
        if bad.size:
            subsets = block.subsets(bad)
            codes, _, nulls = _refine(P, task.ranks, subsets, q, tol, task.errors)
            for j, row, code, zvec in zip(bad, subsets, codes, nulls):
                removed = tuple(sorted(full.tolist() + rest[row].tolist()))
                if code == ZERO:
                    level.failures[removed] = zvec
                elif code == BORDERLINE:
                    level.borderline_at.append(total - 1 - block.offset - int(j))
        level.checked += len(block)
        if progress is not None:
            progress(level.checked, hi - lo)
    level.critical = candidates
    return level


def _keep_closest(
    candidates: list[tuple[float, int, tuple[int, ...]]],
    block: SubsetBlock,
    proxy: np.ndarray,
    rest: np.ndarray,
    total: int,
) -> None:
    """Merge the block's sets into ``candidates``, the ``_CRITICAL`` smallest (proxy,
    lexicographic position, kept sensors) so far; a set of colex rank r (sensors in reverse
    order) is at position ``total - 1 - r``.  Once the list is full only a proxy up to its
    largest can enter it: most blocks add nothing."""
    if len(candidates) >= _CRITICAL:
        rows = np.flatnonzero(proxy <= candidates[-1][0])
    else:
        rows = np.arange(proxy.size)
    if rows.size == 0:
        return
    position = total - 1 - (block.offset + rows)
    rows = rows[np.lexsort((position, proxy[rows]))[:_CRITICAL]]
    for j, removed in zip(rows, block.subsets(rows)):
        dropped = set(rest[removed].tolist())
        kept = tuple(sorted(int(i) for i in rest if i not in dropped))
        candidates.append((float(proxy[j]), total - 1 - block.offset - int(j), kept))
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
