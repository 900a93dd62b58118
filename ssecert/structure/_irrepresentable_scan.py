"""rho(S) for every attack support of a given size, block by block in colex order.

The engine behind ``ssecert.structure.irrepresentable``: with Q the
orthonormal factor of O_tau, the Gramian Q_Sbar^T Q_Sbar = I - Q_S^T Q_S of
each support is formed by the colex enumeration, screened for positive
definiteness with a margin, and rho follows from one dense product per batch
of supports.  The Gramian's rounding (about eps) reaches rho amplified by
1 / lambda_min(I - Q_S^T Q_S), so the supports below the margin
(``VALUE_SCREEN``, and among them every rank deficient one) are decided on the
rows of O_tau themselves (``StackedRows``): the rank by an SVD of O_Sbar with
its rows and columns scaled by powers of two to unit size, rho by a
Householder QR of O_Sbar with its rows in decreasing size.  Neither depends on
the units of a state or of a sensor: whitening by all of O_tau does, where one
sensor's rows are 2^30 times the others'.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from ..budget import Budget
from ..numerics.exact import pow2_row_scaling, pow2_scale
from ..numerics.linalg import screen_positive_definite, stacked_rank
from ..parallel import map_ranges, rank_ranges
from ..tolerances import BORDERLINE, EPS, NONZERO, ZERO, Tolerances
from ._combinatorics import DEFAULT_CHUNK_BYTES, DEFAULT_MEMORY, colex_blocks

__all__ = [
    "ScanPlan",
    "StackedRows",
    "SupportScan",
    "VALUE_SCREEN",
    "plan_scan",
    "rho_error",
    "scan_supports",
    "sensor_units_condition",
    "support_rho",
]

_SUB = 128  # largest number of supports per dense product

#: Margin of the Gramian screening: a support whose whitened Gramian I - Q_S^T Q_S has an
#: eigenvalue below it (or below ``Tolerances.screen_rtol``) is decided on the rows of O_tau
#: (``support_rho``).  Above it the Gramian's rounding reaches rho amplified by at most
#: 2^10; below it rho >= sqrt((1 - 2^-10) / (2^-10 r)) > 1 for r < 1023 rows outside the
#: support (||O_Sbar^dagger^T O_S^T||_2^2 = (1 - lambda_min) / lambda_min, and ||X||_2 <=
#: sqrt(r) ||X||_inf for r rows), so with fewer the supports sent there all fail Theorem 1's
#: condition; with more rows one may not, and its rho, computed by the QR with an error
#: estimate (``rho_error``), is imprecise where that estimate is large.
VALUE_SCREEN = 2.0**-10


class ScanPlan(NamedTuple):
    """Sizes of the enumeration and its cost estimate."""

    rows: int  # h, the rows of O_tau in one support
    colex_memory: int
    batch: int  # supports per dense product
    nbytes: float
    flops: float
    per_support: float
    refine_batch: int = 1  # supports per stacked SVD and QR of their O_Sbar


def plan_scan(
    n: int, p: int, tau: int, items: int, k: int, total: int, mode: str, budget: Budget
) -> ScanPlan:
    """Rows per support, the colex engine's memory, the batch size and the cost estimate."""
    h = k * tau if mode == "block" else k
    colex_memory = int(min(DEFAULT_MEMORY, budget.memory // 8))
    nbytes, flops, per_support = _cost(n, p, tau, items, h, total, mode, colex_memory)
    batch = int(max(1, min(_SUB, (budget.memory // 4) // per_support)))
    M = p * tau
    # O_Sbar, its scaled copy, its Q factor and SVD, O_S and the product: (4 n + 2 h + 1) M
    per_refined = 8.0 * (M * (4 * n + 2 * h + 1) + n * n)
    refine_batch = int(max(1, min(_SUB, (budget.memory // 4) // per_refined)))
    return ScanPlan(h, colex_memory, batch, nbytes, flops, per_support, refine_batch)


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
    infinite_smallest: float = math.nan  # its sigma_min / sigma_max, rows and columns scaled
    n_inf: int = 0
    borderline: int = 0
    stopped_after: int | None = None  # supports checked when the time budget stopped the scan
    # refined supports whose rho may be off by more than IMPRECISE (relative): their number,
    # and the two whose values could be largest, as (upper, support, error) with upper =
    # rho (1 + 2 error), inf past an error of 1/2 (two: one of them may be the worst itself)
    imprecise: int = 0
    imprecise_top: list[tuple[float, tuple[int, ...], float]] = field(default_factory=list)

    def add_refined(self, codes: np.ndarray, subsets: np.ndarray, smallest: np.ndarray) -> None:
        """Count the SVD rank decisions of refined supports; keep the first deficient one (with
        its relative smallest singular value)."""
        self.borderline += int(np.count_nonzero(codes == BORDERLINE))
        zero = np.flatnonzero(codes == ZERO)
        self.n_inf += zero.size
        for j in zero:
            cand = tuple(int(x) for x in subsets[j])
            if self.infinite is None or cand < self.infinite:
                self.infinite, self.infinite_smallest = cand, float(smallest[j])

    def add_imprecise(self, rho: np.ndarray, error: np.ndarray, subsets: np.ndarray) -> None:
        """Count the refined supports whose finite rho may be off by more than IMPRECISE, and
        keep the one whose true value could be largest."""
        doubt = np.flatnonzero(np.isfinite(rho) & ~(error <= IMPRECISE))
        if not doubt.size:
            return
        self.imprecise += doubt.size
        upper = np.where(error[doubt] < 0.5, rho[doubt] * (1 + 2 * error[doubt]), math.inf)
        for j in np.argsort(-upper, kind="stable")[:2]:
            support = tuple(int(x) for x in subsets[doubt[j]])
            self._keep_imprecise((float(upper[j]), support, float(error[doubt[j]])))

    def _keep_imprecise(self, entry: tuple[float, tuple[int, ...], float]) -> None:
        """Keep the two largest upper bounds (the first support among ties)."""
        self.imprecise_top = sorted([*self.imprecise_top, entry], key=lambda e: (-e[0], e[1]))[:2]

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
        self.imprecise += other.imprecise
        for entry in other.imprecise_top:
            self._keep_imprecise(entry)
        if other.infinite is not None and (self.infinite is None or other.infinite < self.infinite):
            self.infinite, self.infinite_smallest = other.infinite, other.infinite_smallest
        if other.worst_support is not None:
            self._keep(other.worst, other.worst_support)

    def _keep(self, top: float, cand: tuple[int, ...]) -> None:
        """The larger of the kept worst and ``top``, the first support among near-ties."""
        if self.worst_support is None or top > self.worst + 1e-12 * max(1.0, self.worst):
            self.worst, self.worst_support = top, cand
        elif top >= self.worst - 1e-12 * max(1.0, self.worst):
            self.worst, self.worst_support = max(self.worst, top), min(self.worst_support, cand)


@dataclass(frozen=True)
class StackedRows:
    """O_tau as the scan reads it.

    ``O`` is O_tau in the plant's own sensor units (any state coordinates: rho does not
    depend on them) times one power of two; ``Q`` its orthonormal QR factor, which whitens
    the Gramians; ``equilibrated`` each row of ``O`` scaled by a power of two to a largest
    entry in [1, 2) (the rank of any set of rows is that of ``O``'s, exactly); ``size_rank``
    each row's place in decreasing size (the order of a row-sorted Householder QR).
    """

    O: np.ndarray
    Q: np.ndarray
    equilibrated: np.ndarray
    size_rank: np.ndarray

    @classmethod
    def of(cls, O: np.ndarray) -> StackedRows:
        """The scan's view of a finite O_tau."""
        O = np.asarray(O, dtype=float)
        if O.size:
            O = O * pow2_scale(float(np.abs(O).max()))  # exact: no overflow in the products
        rows = pow2_row_scaling(O)
        order = np.argsort(-np.max(np.abs(O), axis=1, initial=0.0), kind="stable")
        size_rank = np.empty(O.shape[0], dtype=np.int64)
        size_rank[order] = np.arange(O.shape[0])
        Q, _ = np.linalg.qr(O)
        return cls(O, Q, rows[:, None] * O, size_rank)


def support_rho(
    rows: StackedRows, inside: np.ndarray, tol: Tolerances
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Rank decision and rho of supports from the rows of O_tau, whatever their units.

    The rank of O_Sbar is decided by an SVD with its rows and columns scaled
    by powers of two to unit size, so no sensor's or state's units tip it.
    rho follows from a Householder QR of O_Sbar (columns scaled the same way,
    a change of state coordinates) with its rows sorted by decreasing size:
    O_Sbar = Q_b R, so O_Sbar^dagger^T O_S^T = Q_b R^-T O_S^T, without the
    normal equations and without whitening by rows outside O_Sbar: the
    rounding reaches rho amplified by at most about the condition number of
    O_Sbar in the sensors' units (``sensor_units_condition``), and by about
    that of the scaled O_Sbar where the rows' sizes do not cancel.

    Parameters
    ----------
    rows : StackedRows
    inside : ndarray of int, shape (N, h)
        Rows of O_tau in each support S.
    tol : Tolerances

    Returns
    -------
    rho : ndarray, shape (N,)
        inf where O_Sbar is rank deficient, NaN where the decision is borderline.
    codes : ndarray of int8, shape (N,)
        ZERO, BORDERLINE or NONZERO for the smallest singular value.
    smallest : ndarray, shape (N,)
        sigma_min / sigma_max of the scaled O_Sbar.
    error : ndarray, shape (N,)
        An estimate of rho's relative error (``rho_error``: the QR's rounding amplified by
        the condition number of the O_Sbar it factored); NaN where rho is not finite.
    """
    N, h = inside.shape
    m, n = rows.O.shape
    mask = np.ones((N, m), dtype=bool)
    np.put_along_axis(mask, inside, False, axis=1)
    outside = np.nonzero(mask)[1].reshape(N, m - h)
    by_size = np.argsort(rows.size_rank[outside], axis=1, kind="stable")
    outside = np.take_along_axis(outside, by_size, axis=1)
    scaled = rows.equilibrated[outside]  # (N, m - h, n)
    with np.errstate(over="ignore"):
        columns = pow2_row_scaling(np.abs(scaled).max(axis=1, initial=0.0).reshape(-1, 1))
    columns = columns.reshape(N, 1, n)
    codes, smallest, _ = stacked_rank(scaled * columns, tolerances=tol)
    rho = np.where(codes == ZERO, math.inf, math.nan)
    error = np.full(N, math.nan)
    full = np.flatnonzero(codes == NONZERO)
    if full.size:
        B = rows.O[outside[full]] * columns[full]
        Y = rows.O[inside[full]] * columns[full]
        Qb, R = np.linalg.qr(B)
        with np.errstate(all="ignore"):
            Z = _forward_substitution(R.transpose(0, 2, 1), Y.transpose(0, 2, 1))
            rho[full] = np.abs(Qb @ Z).sum(axis=2).max(axis=1) if m > h else 0.0
            # B's condition with its columns scaled by powers of two to unit size (a change
            # of state units, which rho ignores): B D = Q (R D), so that of R D
            unit = pow2_row_scaling(np.abs(B).max(axis=1, initial=0.0).reshape(-1, 1))
            s = np.linalg.svd(R * unit.reshape(full.size, 1, n), compute_uv=False)
            kappa = np.where(s[:, -1] > 0, s[:, 0] / s[:, -1], math.inf)
        error[full] = rho_error(m - h, n, kappa)
    return rho, codes, smallest, error


def rho_error(rows: int, n: int, kappa: Any) -> Any:
    """An estimate of the relative error of rho from a Householder QR of an O_Sbar of
    ``rows`` x ``n`` whose condition number (columns scaled to unit size) is ``kappa``: the
    QR's normwise backward error, amplified by kappa."""
    return (rows + n) * EPS * np.asarray(kappa, dtype=float)


#: a rho whose relative error may exceed this is imprecise: another support may be the worst,
#: or the comparison with 1 may be wrong
IMPRECISE = 1e-6


def _forward_substitution(L: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """X with L X = Y for a batch of lower triangular L (N, n, n) and Y (N, n, h), row by row
    over the whole batch (a zero pivot gives inf or NaN in that matrix only)."""
    X = np.empty(Y.shape)
    for i in range(L.shape[-1]):
        known = np.einsum("nj,njh->nh", L[:, i, :i], X[:, :i]) if i else 0.0
        X[:, i] = (Y[:, i] - known) / L[:, i, i, None]
    return X


def sensor_units_condition(rows: StackedRows, inside: np.ndarray) -> float:
    """sigma_max / sigma_min of O_Sbar for one support (``inside``, its rows of O_tau) in the
    sensors' own units, its columns scaled by powers of two to unit size (state units are
    free): the amplification of the rounding that bounds ``support_rho``'s error."""
    mask = np.ones(rows.O.shape[0], dtype=bool)
    mask[np.asarray(inside, dtype=np.int64).ravel()] = False
    B = rows.O[mask]
    if B.shape[0] < B.shape[1]:
        return math.inf
    with np.errstate(over="ignore"):
        B = B * pow2_row_scaling(np.abs(B).max(axis=0, initial=0.0).reshape(-1, 1))[None, :]
    s = np.linalg.svd(B, compute_uv=False)
    return float(s[0] / s[-1]) if s.size and s[-1] > 0 else math.inf


# supports per task on Dask workers, at least (fewer cost more to send than to decide)
MIN_CHUNK_SUPPORTS = 20_000


@dataclass(frozen=True)
class _ScanTask:
    """What every range of supports reads (sent once to Dask workers)."""

    rows: StackedRows
    rows_of: np.ndarray
    G: np.ndarray  # per-item Gramians U_i^T U_i
    k: int
    plan: ScanPlan
    tol: Tolerances


def scan_supports(
    rows: StackedRows,
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
    U = rows.Q[rows_of]  # (items, r, n)
    task = _ScanTask(rows, rows_of, np.einsum("irn,irm->inm", U, U), k, plan, tol)
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
    lo, hi = ranks
    done = 0
    base = np.eye(task.rows.Q.shape[1])
    blocks = colex_blocks(task.G, base, task.k, memory=task.plan.colex_memory, start=lo, stop=hi)
    for block in blocks:
        subsets = block.subsets()
        rho = _block_rho(task, block.matrices, subsets, scan)
        scan.add_finite(rho, subsets)
        done += len(block)
        if progress is not None:
            progress(done, hi - lo)
        if deadline is not None and scan.worst > stop_above and time.monotonic() > deadline:
            scan.stopped_after = done
            break
    return scan


def _block_rho(
    task: _ScanTask, matrices: np.ndarray, subsets: np.ndarray, scan: SupportScan
) -> np.ndarray:
    """rho of one block: screened supports in dense batches, the rest from the rows of O_tau
    (tallied in scan)."""
    Q, rows_of, plan = task.rows.Q, task.rows_of, task.plan
    ok = screen_positive_definite(matrices, max(task.tol.screen_rtol, VALUE_SCREEN))
    rho = np.full(matrices.shape[0], np.nan)
    good = np.flatnonzero(ok)
    for start in range(0, good.size, plan.batch):
        sel = good[start : start + plan.batch]
        rho[sel] = _rho_batch(Q, rows_of, matrices[sel], subsets[sel])
    bad = np.flatnonzero(~ok)
    for start in range(0, bad.size, plan.refine_batch):
        sel = bad[start : start + plan.refine_batch]
        inside = rows_of[subsets[sel]].reshape(sel.size, -1)
        rho[sel], codes, smallest, error = support_rho(task.rows, inside, task.tol)
        scan.add_refined(codes, subsets[sel], smallest)
        scan.add_imprecise(rho[sel], error, subsets[sel])
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
