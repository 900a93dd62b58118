"""rho(S) for every attack support of a given size, block by block in colex order.

The engine behind ``ssecert.structure.irrepresentable``: with Q the
orthonormal factor of O_tau, the Gramian Q_Sbar^T Q_Sbar = I - Q_S^T Q_S of
each support is formed by the colex enumeration, screened for positive
definiteness, and rho follows from one dense product per batch of supports;
the supports that fail screening are decided by an SVD of Q_Sbar.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from .._linalg import screen_positive_definite, stacked_rank
from ..budget import Budget
from ..parallel import map_ranges, rank_ranges
from ..tolerances import BORDERLINE, NONZERO, ZERO, Tolerances
from ._combinatorics import DEFAULT_CHUNK_BYTES, DEFAULT_MEMORY, colex_blocks

__all__ = ["ScanPlan", "SupportScan", "plan_scan", "scan_supports"]

_SUB = 128  # largest number of supports per dense product


class ScanPlan(NamedTuple):
    """Sizes of the enumeration and its cost estimate."""

    rows: int  # h, the rows of O_tau in one support
    colex_memory: int
    batch: int  # supports per dense product
    nbytes: float
    flops: float
    per_support: float


def plan_scan(
    n: int, p: int, tau: int, items: int, k: int, total: int, mode: str, budget: Budget
) -> ScanPlan:
    """Rows per support, the colex engine's memory, the batch size and the cost estimate."""
    h = k * tau if mode == "block" else k
    colex_memory = int(min(DEFAULT_MEMORY, budget.memory // 8))
    nbytes, flops, per_support = _cost(n, p, tau, items, h, total, mode, colex_memory)
    batch = int(max(1, min(_SUB, (budget.memory // 4) // per_support)))
    return ScanPlan(h, colex_memory, batch, nbytes, flops, per_support)


def _cost(
    n: int, p: int, tau: int, items: int, h: int, supports: int, mode: str, colex_memory: int
) -> tuple[float, float, float]:
    """Peak bytes, operations and bytes per support of the enumeration, from the shapes.

    Peak: O_tau and its QR factor (4 copies of p tau x n), the per-item
    Gramians, the colex engine's partial sums, one support's dense products
    (2 copies of p tau x h, the rows of O_tau outside and inside it), and the
    direct pinv recomputation of the worst support.  Work: the QR, the Gramians
    and, per support, the p tau x n x h product, its absolute row sums and an
    n x n factorisation; calibrated so that 1e12 is one to three minutes on
    one core.
    """
    M = p * tau
    per_support = 8.0 * (2 * M * h + 3 * h * n + M)
    colex = min(colex_memory + DEFAULT_CHUNK_BYTES, 2 * 8.0 * supports * n * n)
    nbytes = 8.0 * (4 * M * n + M + items * n * n) + colex + per_support + 8.0 * (2 * M * n + M * h)
    # the elementwise passes over the p tau x h product (absolute value, sums, the
    # memory traffic) cost far more than their count: 60 per entry, measured
    flops = (
        4.0 * M * n * n
        + 2.0 * M * n * n
        + supports * (2.0 * M * n * h + 60.0 * M * h + n**3 + 2.0 * n * n * h)
    )
    return nbytes, flops, per_support


@dataclass
class SupportScan:
    """What the enumeration found: the worst finite rho, its support and the infinite ones."""

    worst: float = -1.0
    worst_support: tuple[int, ...] | None = None
    infinite: tuple[int, ...] | None = None  # the first support whose O_Sbar is rank deficient
    n_inf: int = 0
    borderline: int = 0
    stopped_after: int | None = None  # supports checked when the time budget stopped the scan

    def add_refined(self, codes: np.ndarray, subsets: np.ndarray) -> None:
        """Count the SVD rank decisions of refined supports; keep the first deficient one."""
        self.borderline += int(np.count_nonzero(codes == BORDERLINE))
        deficient = subsets[codes == ZERO]
        self.n_inf += deficient.shape[0]
        for row in deficient:
            cand = tuple(int(x) for x in row)
            if self.infinite is None or cand < self.infinite:
                self.infinite = cand

    def add_finite(self, rho: np.ndarray, subsets: np.ndarray) -> None:
        """Keep the largest finite rho, with the first support among its near-ties."""
        finite = np.flatnonzero(np.isfinite(rho))
        if not finite.size:
            return
        top = float(rho[finite].max())
        ties = finite[rho[finite] >= top - 1e-12 * max(1.0, top)]
        self._keep(top, min(tuple(int(x) for x in subsets[j]) for j in ties))

    def merge(self, other: SupportScan) -> None:
        """Add what another range of supports found (ranges merged in colex order)."""
        self.borderline += other.borderline
        self.n_inf += other.n_inf
        if other.infinite is not None and (self.infinite is None or other.infinite < self.infinite):
            self.infinite = other.infinite
        if other.worst_support is not None:
            self._keep(other.worst, other.worst_support)

    def _keep(self, top: float, cand: tuple[int, ...]) -> None:
        """The larger of the kept worst and ``top``, the first support among near-ties."""
        if self.worst_support is None or top > self.worst + 1e-12 * max(1.0, self.worst):
            self.worst, self.worst_support = top, cand
        elif top >= self.worst - 1e-12 * max(1.0, self.worst):
            self.worst, self.worst_support = max(self.worst, top), min(self.worst_support, cand)


# supports per task on Dask workers, at least (fewer cost more to send than to decide)
MIN_CHUNK_SUPPORTS = 20_000


@dataclass(frozen=True)
class _ScanTask:
    """What every range of supports reads (sent once to Dask workers)."""

    Q: np.ndarray
    rows_of: np.ndarray
    G: np.ndarray  # per-item Gramians U_i^T U_i
    k: int
    plan: ScanPlan
    tol: Tolerances


def scan_supports(
    Q: np.ndarray,
    rows_of: np.ndarray,
    k: int,
    plan: ScanPlan,
    tol: Tolerances,
    total: int,
    progress: Callable[[int, int], None] | None,
    client: Any | None = None,
    deadline: float | None = None,
    stop_above: float = math.inf,
) -> SupportScan:
    """rho over every support of k items, block by block in colex order.

    With a Dask ``client`` the colex ranks are split into ranges decided on
    the workers and merged in order: the same worst support, value and
    counts as in-process.  A range that fails twice raises ``ChunkError``.
    In-process, once ``deadline`` (a ``time.monotonic()`` value) has passed
    and a support with rho above ``stop_above`` is known, the scan stops
    (``stopped_after``): the verdict is decided, the worst value is a lower
    bound.
    """
    U = Q[rows_of]  # (items, r, n)
    task = _ScanTask(Q, rows_of, np.einsum("irn,irm->inm", U, U), k, plan, tol)
    ranges = rank_ranges(total, client, MIN_CHUNK_SUPPORTS)
    if len(ranges) == 1:
        return _scan_range(task, ranges[0], progress, deadline, stop_above)
    scan = SupportScan()
    for part in map_ranges(_scan_range, task, ranges, client, progress):
        scan.merge(part)
    return scan


def _scan_range(
    task: _ScanTask,
    ranks: tuple[int, int],
    progress: Callable[[int, int], None] | None = None,
    deadline: float | None = None,
    stop_above: float = math.inf,
) -> SupportScan:
    """rho over the supports whose colex ranks lie in ``ranks`` (see ``scan_supports`` for
    the deadline)."""
    scan = SupportScan()
    Q, rows_of = task.Q, task.rows_of
    lo, hi = ranks
    done = 0
    base = np.eye(Q.shape[1])
    blocks = colex_blocks(task.G, base, task.k, memory=task.plan.colex_memory, start=lo, stop=hi)
    for block in blocks:
        subsets = block.subsets()
        rho = _block_rho(Q, rows_of, block.matrices, subsets, task.plan.batch, task.tol, scan)
        scan.add_finite(rho, subsets)
        done += len(block)
        if progress is not None:
            progress(done, hi - lo)
        if deadline is not None and scan.worst > stop_above and time.monotonic() > deadline:
            scan.stopped_after = done
            break
    return scan


def _block_rho(
    Q: np.ndarray,
    rows_of: np.ndarray,
    matrices: np.ndarray,
    subsets: np.ndarray,
    batch: int,
    tol: Tolerances,
    scan: SupportScan,
) -> np.ndarray:
    """rho of one block: screened supports in dense batches, the rest by SVD (tallied in scan)."""
    ok = screen_positive_definite(matrices, tol.screen_rtol)
    rho = np.full(matrices.shape[0], np.nan)
    good = np.flatnonzero(ok)
    for start in range(0, good.size, batch):
        sel = good[start : start + batch]
        rho[sel] = _rho_batch(Q, rows_of, matrices[sel], subsets[sel])
    bad = np.flatnonzero(~ok)
    if bad.size:
        r_bad, codes = _rho_refine(Q, rows_of, subsets[bad], tol)
        rho[bad] = r_bad
        scan.add_refined(codes, subsets[bad])
    return rho


def _rho_batch(
    Q: np.ndarray, rows_of: np.ndarray, M: np.ndarray, subsets: np.ndarray
) -> np.ndarray:
    """rho for supports whose Gramian M = Q_Sbar^T Q_Sbar passed screening."""
    N = subsets.shape[0]
    rows = rows_of[subsets].reshape(N, -1)  # (N, h)
    QS = Q[rows]  # (N, h, n)
    X = np.linalg.solve(M, QS.transpose(0, 2, 1))  # (N, n, h)
    h = X.shape[2]
    # one product for the whole batch: (p tau, n) x (n, N h)
    full = Q @ X.transpose(1, 0, 2).reshape(Q.shape[1], N * h)
    np.abs(full, out=full)
    sums = full.reshape(Q.shape[0], N, h).sum(axis=2).T  # (N, p tau)
    np.put_along_axis(sums, rows, 0.0, axis=1)  # keep only rows outside S
    return sums.max(axis=1)


def _rho_refine(
    Q: np.ndarray, rows_of: np.ndarray, subsets: np.ndarray, tol: Tolerances
) -> tuple[np.ndarray, np.ndarray]:
    """Exact rank decision by SVD for supports that failed screening, and rho."""
    N = subsets.shape[0]
    m = Q.shape[0]
    rho = np.empty(N)
    codes = np.empty(N, dtype=np.int8)
    for j in range(N):
        mask = np.ones(m, dtype=bool)
        rows = rows_of[subsets[j]].ravel()
        mask[rows] = False
        Qbar = Q[mask]
        c, _, _ = stacked_rank(Qbar[None], tolerances=tol)
        codes[j] = c[0]
        if c[0] == NONZERO:
            M = np.linalg.pinv(Qbar).T @ Q[rows].T
            rho[j] = np.abs(M).sum(axis=1).max()
        else:
            rho[j] = math.inf if c[0] == ZERO else math.nan
    return rho, codes
