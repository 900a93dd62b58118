"""Batched enumeration of subsets with additive per-item matrices.

Many structural questions need, for every k-subset S of q items, the
matrix ``base + sign * sum(items[i] for i in S)`` (a Gramian of the sensors
left after removing S, or of the rows of an attack support).  Enumerating
in colexicographic order makes this cheap: the k-subsets whose largest
elements are a fixed "top" tuple are exactly the first C(t, m) m-subsets
(in colex order) of the smaller indices, so one precomputed level of
partial sums serves every top with a single broadcast addition and no
per-subset gathering.

Screening the sums for positive definiteness (``ColexScreen``) factors
them in single precision with the batch as the last, contiguous axis,
shifted by a margin that proves LAPACK's float64 factorization succeeds
wherever the single-precision one does; only the other sets are factored
by LAPACK (``numpy.linalg.cholesky``), so every decision and every
smallest pivot used is LAPACK's, bit for bit.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..numerics.linalg import (
    cholesky_batch_last,
    cholesky_or_nan,
    single_passed,
    single_screen,
)
from .device import DeviceBatch, DeviceKernel

__all__ = [
    "ColexScreen",
    "ScreenedBatch",
    "SubsetBlock",
    "cholesky_screen",
    "colex_blocks",
    "colex_rank",
    "colex_unrank",
    "count_subsets",
    "level_split",
]

# partial sums kept for a level: small enough to stay in cache (measured as fast as or faster
# than 128 MiB on 10 x 10 to 15 x 15 Gramians) and cheap to rebuild for each range of ranks
DEFAULT_MEMORY = 8 * 2**20
DEFAULT_CHUNK_BYTES = 4 * 2**20  # measured best for 15 x 15 Gramians


def count_subsets(q: int, sizes: range | list[int]) -> int:
    """Number of subsets of q items with sizes in ``sizes``."""
    if isinstance(sizes, range) and sizes.step == 1:  # a huge range (s >> p) costs O(q)
        sizes = range(max(sizes.start, 0), min(sizes.stop, q + 1))
    return sum(math.comb(q, k) for k in sizes if 0 <= k <= q)


def colex_rank(subset: tuple[int, ...] | list[int]) -> int:
    """Colexicographic rank of a sorted subset: sum of C(c_i, i), i = 1..k."""
    return sum(math.comb(c, i + 1) for i, c in enumerate(sorted(subset)))


def colex_unrank(rank: int, k: int) -> tuple[int, ...]:
    """Inverse of ``colex_rank`` for subsets of size k."""
    out = []
    for i in range(k, 0, -1):
        c = i - 1
        while math.comb(c + 1, i) <= rank:
            c += 1
        out.append(c)
        rank -= math.comb(c, i)
    return tuple(sorted(out))


@dataclass(frozen=True)
class SubsetBlock:
    """A run of consecutive k-subsets (colex order) and their matrices.

    Attributes
    ----------
    offset : int
        Colex rank of the first subset.
    bottoms : ndarray of int, shape (N, m)
        Lower part of each subset.
    top : tuple of int
        Upper part, shared by the whole block.
    partial : ndarray, shape (N, n, n)
        The precomputed sums of the bottoms (a view of the level).
    shift : ndarray, shape (n, n), or None
        ``sign * sum(items[top])``, added to every partial sum (None: no top).
    """

    offset: int
    bottoms: np.ndarray
    top: tuple[int, ...]
    partial: np.ndarray
    shift: np.ndarray | None = None

    def __len__(self) -> int:
        return self.bottoms.shape[0]

    @property
    def matrices(self) -> np.ndarray:
        """``base + sign * sum(items[S])`` for each subset S of the block, shape (N, n, n)."""
        return self.partial if self.shift is None else self.partial + self.shift

    def matrices_of(self, rows: np.ndarray) -> np.ndarray:
        """The matrices of the selected rows, bit for bit those of ``matrices``."""
        part = self.partial[rows]
        return part if self.shift is None else part + self.shift

    def subsets(self, rows: np.ndarray | slice | None = None) -> np.ndarray:
        """Sorted subsets of the block (or of the selected rows), shape (N, k)."""
        bottoms = self.bottoms if rows is None else self.bottoms[rows]
        top = np.broadcast_to(np.array(self.top, dtype=np.int64), (bottoms.shape[0], len(self.top)))
        return np.concatenate([bottoms, top], axis=1)


def _level(
    items: np.ndarray, base: np.ndarray, sign: float, m: int
) -> tuple[np.ndarray, np.ndarray]:
    """All m-subsets in colex order with their summed matrices."""
    sums = base[None].copy()
    subsets = np.zeros((1, 0), dtype=np.int64)
    q = items.shape[0]
    for j in range(1, m + 1):
        parts, sparts = [], []
        for last in range(j - 1, q):
            c = math.comb(last, j - 1)
            parts.append(sums[:c] + sign * items[last])
            sparts.append(
                np.concatenate([subsets[:c], np.full((c, 1), last, dtype=np.int64)], axis=1)
            )
        sums = np.concatenate(parts)
        subsets = np.concatenate(sparts)
    return sums, subsets


def level_split(q: int, k: int, per: int, memory: int = DEFAULT_MEMORY) -> int:
    """Size m of the precomputed level of partial sums for k-subsets of q items.

    The largest m <= k whose C(q, m) matrices of ``per`` bytes fit in
    ``memory``.  Every k-subset is its m smallest items (a precomputed sum)
    plus its k - m largest (the "top", added per block), so the arithmetic
    of each subset's sum depends on m alone: any split of the ranks into
    ranges gives bitwise the same matrices.
    """
    for cand in range(k, -1, -1):
        if math.comb(q, cand) * per <= memory:
            return cand
    return 0


def _next_top(top: list[int], low: int, q: int) -> bool:
    """Advance ``top`` to the next subset of {low, ..., q-1} in colex order; False after the last."""
    for i in range(len(top)):
        limit = top[i + 1] if i + 1 < len(top) else q
        if top[i] + 1 < limit:
            top[i] += 1
            top[:i] = range(low, low + i)
            return True
    return False


def _tops(
    q: int, k: int, m: int, start: int, stop: int, first: tuple[int, ...] | None = None
) -> Iterator[tuple[int, int, list[int]]]:
    """(colex rank of its first subset, number of subsets, top) of each top, the k - m
    largest items, whose subsets meet the ranks [start, stop); the list is reused.
    ``first``: the subset of rank ``start``, when known."""
    if m == k:
        yield 0, math.comb(q, k), []
        return
    # tops: (k - m)-subsets t_1 < ... of {m, ..., q-1}, in colex order, from the one that
    # holds rank ``start`` (its m smallest items are the bottom, the rest the top)
    top = list((colex_unrank(start, k) if first is None else first)[m:])
    while True:
        offset = sum(math.comb(t, m + j + 1) for j, t in enumerate(top))
        if offset >= stop:
            return
        yield offset, math.comb(top[0], m), top
        if not _next_top(top, m, q):
            return


Span = tuple[int, int, int, tuple[int, ...]]


def _spans(q: int, k: int, m: int, chunk: int, start: int, stop: int) -> Iterator[Span]:
    """(colex rank, first and last row of the level, top) of each block of ``colex_blocks``."""
    for offset, count, top in _tops(q, k, m, start, stop):
        here = tuple(top)
        for first in range(max(start - offset, 0), min(count, stop - offset), chunk):
            yield offset + first, first, min(first + chunk, count, stop - offset), here


def colex_blocks(
    items: np.ndarray,
    base: np.ndarray,
    k: int,
    *,
    sign: float = -1.0,
    memory: int = DEFAULT_MEMORY,
    chunk_bytes: int = DEFAULT_CHUNK_BYTES,
    start: int = 0,
    stop: int | None = None,
) -> Iterator[SubsetBlock]:
    """Yield every k-subset of the q items with its summed matrix, colex order.

    Parameters
    ----------
    items : ndarray, shape (q, n, n)
        Per-item matrices.
    base : ndarray, shape (n, n)
        Matrix every sum starts from.
    k : int
        Subset size, 0 <= k <= q.
    sign : float, default -1
        ``-1`` removes the items from ``base``; ``+1`` adds them.
    memory : int
        Bytes allowed for the precomputed level of partial sums.
    chunk_bytes : int
        Approximate size of each yielded block.
    start, stop : int, optional
        Only the subsets with colex ranks in [start, stop) (default: all
        C(q, k)).  The matrices do not depend on the range: splitting the
        ranks into ranges and concatenating the blocks gives the same
        matrices, bit for bit, as one pass.

    Yields
    ------
    SubsetBlock
        Blocks covering the subsets of the range exactly once, in colex order.
    """
    q = items.shape[0]
    if not 0 <= k <= q:
        return
    total = math.comb(q, k)
    stop = total if stop is None else min(stop, total)
    if start >= stop:
        return
    per = items[0].nbytes if q else base.nbytes
    m = level_split(q, k, per, memory)
    sums, subsets = _level(items, base, sign, m)
    chunk = max(64, chunk_bytes // max(per, 1))
    shift: tuple[tuple[int, ...], np.ndarray | None] = ((), None)
    for rank, first, last, top in _spans(q, k, m, chunk, start, stop):
        if top and top != shift[0]:
            shift = (top, sign * items[list(top)].sum(axis=0))
        yield SubsetBlock(
            rank, subsets[first:last], top, sums[first:last], shift[1] if top else None
        )


def _proxies(L: np.ndarray, shift: float) -> tuple[np.ndarray, np.ndarray]:
    """Success of LAPACK's factorizations ``L`` and their proxies (see ``cholesky_screen``)."""
    ok = np.isfinite(L[:, -1, -1]) & np.isfinite(L[:, 0, 0])
    smallest = np.min(np.diagonal(L, axis1=1, axis2=2), axis=1) if L.shape[0] else np.zeros(0)
    return ok, np.where(ok, smallest**2 + shift, -np.inf)


def cholesky_screen(
    shifted: np.ndarray, shift: float, want_proxy: bool, out: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Cholesky screening of Gramians already shifted by ``-shift I``.

    Returns whether each factorization exists and, when asked, a proxy for
    the smallest eigenvalue of the unshifted Gramian (squared smallest
    Cholesky pivot plus the shift, an upper bound) that ranks the sets that
    come closest to breaking.  Both are those of LAPACK's factorization
    (``numpy.linalg.cholesky``): single precision proves the success of
    most (``screen_positive_definite``), LAPACK factors the rest and, for
    the proxies, every matrix.  ``out`` is not used (kept for callers that
    pass a buffer).
    """
    if want_proxy:
        return _proxies(cholesky_or_nan(shifted), shift)
    ok = single_screen(shifted)[0] if shifted.shape[0] else np.zeros(0, dtype=bool)
    unsure = np.flatnonzero(~ok)
    if unsure.size:
        ok[unsure] = _proxies(cholesky_or_nan(shifted[unsure]), shift)[0]
    return ok, np.empty(0)


# bytes allowed for the single-precision level of partial sums of ``ColexScreen``: deeper than
# the float64 level, so that most screened batches are a few broadcast additions
DEFAULT_SINGLE_MEMORY = 16 * 2**20

# tier 2 factors the whole batch when more than this share of it is left open by tier 1 (a
# few contiguous calls), else only the sets left open (gathered)
_GATHER_FRACTION = 0.5

# tier 1 is skipped for this many sets after a batch where it left most of them open
_SKIP_SETS = 8 * 4096

# matrices tier 2 factors together (the chunks of a batch of ``_level_scan._RANKED_BATCH_SETS``;
# measured no faster in larger chunks at n = 12 and 20)
TIER2_SETS = 4096


def _single_level(signed: np.ndarray, base: np.ndarray, m: int) -> np.ndarray:
    """All m-subsets' sums of ``_level`` with the batch last, shape (n, n, C(q, m)), from the
    items already multiplied by the sign."""
    sums = base[:, :, None]
    for j in range(1, m + 1):
        sums = np.concatenate(
            [
                sums[:, :, : math.comb(last, j - 1)] + signed[last][:, :, None]
                for last in range(j - 1, signed.shape[0])
            ],
            axis=2,
        )
    return np.ascontiguousarray(sums)


class ColexScreen:
    """Every k-subset of a range of colex ranks, screened for positive definiteness in batches.

    The subsets and their float64 matrices are those of ``colex_blocks``
    (``matrices``, ``subsets``; ``spans`` tells the block of each subset),
    and ``screen`` decides a batch of consecutive ranks as
    ``cholesky_screen`` decides those matrices, bit for bit, in up to three
    tiers, each only for the subsets the one before leaves open:

    1. With the factors of the items (``items[i] = factors[i].T @
       factors[i]``, sign -1): the subsets whose largest item is t share
       ``H = base - items[t]``, and with ``c_b = ||H^(-1/2) factors[b].T||^2``
       (from one eigendecomposition of H) the smallest eigenvalue of the
       sum is at least ``lambda_min(H) (1 - sum of c_b over the other
       items)``.  A positive bound (less every rounding of the sums and
       LAPACK's backward error) proves LAPACK's factorization succeeds and
       bounds its smallest pivot, at the cost of a few additions per subset.
       Where the sets closest to breaking are ranked, H is taken at a shift mu
       just under the ranking's threshold (``H = base - items[t] - mu I``, the
       bound ``mu + lambda_min(H) (1 - sum of c)`` where the sum is below 1):
       most sets are proved above the threshold, where at mu = 0 most would
       be proved only positive definite, and tier 2 factors only the others
       (gathered).
    2. The matrices minus ``margin`` I factored in single precision with the
       batch last (``cholesky_batch_last``): where that succeeds LAPACK's
       float64 factorization provably succeeds too, and its smallest pivot
       is at least the single-precision one
       (``ssecert.numerics.linalg.single_precision_margin``).  Their own level of
       partial sums, deeper than the float64 one (their rounding is part of
       the margin), makes a batch a few broadcast additions.
    3. LAPACK (``numpy.linalg.cholesky``) on the float64 matrices.

    The float64 level and the single-precision one are computed when
    first needed.

    Parameters
    ----------
    items : ndarray, shape (q, n, n)
    base : ndarray, shape (n, n)
    k : int
    margin : float
        ``single_precision_margin`` of every sum, its rounding counting k
        single-precision additions.
    sign, memory, chunk_bytes, start, stop
        As for ``colex_blocks``.
    factors : ndarray, shape (q, r, n), optional
        With ``sign = -1``: ``items[i]`` is ``factors[i].T @ factors[i]``
        rounded (tier 1).
    single_memory : int
        Bytes allowed for the single-precision level of partial sums.
    device : DeviceKernel, optional
        Tier 2 on an accelerator (``ssecert.structure.device``), for every
        batch and without tier 1; the decisions stay LAPACK's.
    segment : int, optional
        The range is made of consecutive segments of this many ranks from
        ``start`` (the last may be shorter), and ``spans`` gives the blocks
        each segment alone would have as a range of its own (an accelerator
        screens a few of the CPU's ranges at once, with their blocks).
    shared : dict, optional
        Kept by the caller across the screens of ranges of one level (the
        same items, base, k, sign and margin): the levels of partial sums
        (and their copies on the device) are computed once for all of them
        rather than once per range.  They do not depend on the range, so
        the screens are the same, bit for bit.
    """

    def __init__(
        self,
        items: np.ndarray,
        base: np.ndarray,
        k: int,
        margin: float,
        *,
        sign: float = -1.0,
        memory: int = DEFAULT_MEMORY,
        chunk_bytes: int = DEFAULT_CHUNK_BYTES,
        start: int = 0,
        stop: int | None = None,
        factors: np.ndarray | None = None,
        single_memory: int = DEFAULT_SINGLE_MEMORY,
        device: DeviceKernel | None = None,
        segment: int | None = None,
        shared: dict[tuple[Any, ...], Any] | None = None,
    ) -> None:
        q, n = items.shape[0], base.shape[-1]
        if not 0 <= k <= q:
            raise ValueError(f"subsets of {k} of {q} items")
        total = math.comb(q, k)
        if total >= 2**62:
            raise ValueError(f"C({q}, {k}) subsets: too many to number in 64 bits")
        self.items, self.base, self.k, self.sign, self.margin = items, base, k, sign, margin
        self.start, self.stop = start, total if stop is None else min(stop, total)
        per = items[0].nbytes if q else base.nbytes
        self.m = level_split(q, k, per, memory)
        self.chunk = max(64, chunk_bytes // max(per, 1))
        self._sums: tuple[np.ndarray, np.ndarray] | None = None
        # C(c, i) for c = 0..q, i = 0..k, for the unranking of many ranks at once (capped:
        # ranks are below C(q, k) < 2^62, so a capped entry is above every rank, as it was)
        self._comb = [
            np.array([min(math.comb(c, i), 2**62) for c in range(q + 1)], dtype=np.int64)
            for i in range(k + 1)
        ]
        # single precision: no more partial sums than the sets of the range (a small range
        # does not pay for a level it would not use)
        sets = max(self.stop - self.start, 1)
        m32 = level_split(q, k, 4 * n * n, single_memory)
        while m32 > 0 and math.comb(q, m32) > sets:
            m32 -= 1
        if factors is not None and sign == -1.0 and k > 0:
            m32 = min(m32, k - 1)  # tier 1 needs a top, the largest item at least
        self.m32 = m32
        self._sums32: np.ndarray | None = None
        # matrices formed one by one while no level is built (``_direct``): how many so far
        self._formed = {"float64": 0, "float32": 0}
        self._signed32 = sign * items.astype(np.float32)
        # the walk through the tops of the single-precision level: (where the last range
        # asked stopped, the tops after the current one, the current one); the sum of the
        # current top's largest items
        self._cursor: list[Any] | None = None
        self._upper: tuple[tuple[int, ...], np.ndarray | None] = ((), None)
        self.factors = factors if sign == -1.0 and (m32 > 0 or k == 1) and m32 < k else None
        # the bounds of the last few largest items asked (ranges ascending or descending)
        self._bounds: dict[
            int, tuple[float, tuple[float, np.ndarray, np.ndarray, float] | None]
        ] = {}
        # tier 1 is skipped for this many sets after a batch where it left most of them open
        self._skip = 0
        self._slack = 0.0 if self.factors is None else _bound_slack(items, base, self.factors, k)
        self.tier2_sets = TIER2_SETS
        self.device = device
        self._single_device: Any = None  # the single-precision level on the device
        self._shared = {} if shared is None else shared
        self.segment = segment

    def batches(self, size: int) -> Iterator[tuple[int, int]]:
        """Consecutive ranges of ``size`` ranks covering the range."""
        for first in range(self.start, self.stop, size):
            yield first, min(first + size, self.stop)

    def subsets(self, ranks: np.ndarray) -> np.ndarray:
        """Sorted subsets of the given colex ranks, shape (len(ranks), k) (``colex_unrank``)."""
        return self._unrank(ranks, self.k)

    def _unrank(self, ranks: np.ndarray, k: int) -> np.ndarray:
        """Sorted k-subsets of the given colex ranks (k <= ``self.k``), shape (len(ranks), k)."""
        rest = np.array(ranks, dtype=np.int64)
        out = np.empty((rest.size, k), dtype=np.int64)
        for i in range(k, 0, -1):
            c = np.searchsorted(self._comb[i], rest, side="right") - 1
            out[:, i - 1] = c
            rest = rest - self._comb[i][c]
        return out

    def _tops(self, subsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Colex rank of the first subset of each subset's top, and the top's subsets."""
        if self.m == self.k:
            return np.zeros(subsets.shape[0], dtype=np.int64), np.full(
                subsets.shape[0], math.comb(self.items.shape[0], self.k)
            )
        first = sum(
            self._comb[self.m + j + 1][subsets[:, self.m + j]] for j in range(self.k - self.m)
        )
        return first, self._comb[self.m][subsets[:, self.m]]

    def spans(self, ranks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """First and last (excluded) rank of the block of ``colex_blocks`` over the range that
        holds each rank."""
        ranks = np.asarray(ranks, dtype=np.int64)
        offset, count = self._tops(self.subsets(ranks))
        start: int | np.ndarray = self.start
        stop: int | np.ndarray = self.stop
        if self.segment is not None:  # the segment of each rank, as a range of its own
            start = self.start + (ranks - self.start) // self.segment * self.segment
            stop = np.minimum(start + self.segment, self.stop)
        first = np.maximum(start - offset, 0)
        lo = first + (ranks - offset - first) // self.chunk * self.chunk
        hi = np.minimum(np.minimum(lo + self.chunk, count), stop - offset)
        return offset + lo, offset + hi

    def _direct(self, precision: str, level: int, count: int) -> bool:
        """Whether ``count`` more matrices are formed one by one (their ``level`` smallest
        items added in turn, as the level of partial sums adds them) rather than from the
        level, built for them: while the level is not built and the matrices formed one by
        one, these included, cost no more additions than building it would (a level that
        only a few sets ask for, as on most refinement levels, is never built)."""
        built = self._sums if precision == "float64" else self._sums32
        if built is not None or (precision, level) in self._shared:
            return False
        formed = self._formed[precision] + count
        if formed * level > math.comb(self.items.shape[0], level):
            return False
        self._formed[precision] = formed
        return True

    @staticmethod
    def _bottoms(start: np.ndarray, signed: np.ndarray, subsets: np.ndarray) -> np.ndarray:
        """``start`` plus the ``signed`` items of each subset's columns in turn, shape
        (len(subsets), n, n): bit for bit the sums of ``_level`` and ``_single_level`` (each
        the sum of the smaller items plus one signed item)."""
        out = np.repeat(start[None], subsets.shape[0], axis=0)
        for j in range(subsets.shape[1]):
            out += np.take(signed, subsets[:, j], axis=0)
        return out

    def matrices(self, ranks: np.ndarray) -> np.ndarray:
        """The float64 matrices of the given ranks (ascending), bit for bit those of the
        blocks of ``colex_blocks``."""
        ranks = np.asarray(ranks, dtype=np.int64)
        subsets = self.subsets(ranks)
        if self._direct("float64", self.m, ranks.size):
            signed = self.sign * self.items
            part = self._bottoms(self.base, signed, subsets[:, : self.m])
        else:
            if self._sums is None:
                key = ("float64", self.m)
                if key not in self._shared:
                    self._shared[key] = _level(self.items, self.base, self.sign, self.m)
                self._sums = self._shared[key]
            offset, _ = self._tops(subsets)
            part = self._sums[0][ranks - offset]
        if self.m == self.k:
            return part
        tops = subsets[:, self.m :]
        edges = np.flatnonzero(np.any(tops[1:] != tops[:-1], axis=1)) + 1
        for a, b in itertools.pairwise([0, *edges.tolist(), ranks.size]):
            part[a:b] += self.sign * self.items[tops[a].tolist()].sum(axis=0)
        return part

    def _pieces(self, start: int, stop: int) -> list[tuple[int, int, int, tuple[int, ...]]]:
        """(first row in the range, first and last row of the single-precision level, top) of
        the runs of the ranks [start, stop) that share a top of that level (ranges asked in
        ascending order continue the walk through the tops where the last one stopped)."""
        cursor = self._cursor
        if cursor is None or cursor[0] > start:
            # (ranges asked in descending order start a walk each, from the vectorized unrank)
            subset = tuple(self.subsets(np.array([start]))[0].tolist())
            tops = _tops(self.items.shape[0], self.k, self.m32, start, self.stop, subset)
            cursor = self._cursor = [start, tops, next(tops, None)]
        cursor[0] = stop
        pieces = []
        while cursor[2] is not None:
            offset, count, top = cursor[2]
            first, last = max(start - offset, 0), min(count, stop - offset)
            if first < last:
                pieces.append((offset + first - start, first, last, tuple(top)))
            if offset + count > stop:
                break
            cursor[2] = next(cursor[1], None)
        return pieces

    def piece_arrays(
        self, start: int, stop: int
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """The pieces of ``_pieces`` as arrays, found without walking the tops one by one:
        (first row of each piece in the range, the piece's first row of the single-precision
        level minus its first row in the range, the single-precision sums of the pieces' tops
        as ``_top_total`` makes them, batch last, or None when the level is the whole sum).

        The tops of the level are the (k - m32)-subsets of the items from m32 up, in colex
        order: those of the range are the consecutive ranks between the tops of its first
        and last subsets, unranked together."""
        k, m = self.k, self.m32
        if m == k:
            return np.zeros(1, dtype=np.int64), np.array([start], dtype=np.int64), None
        r = k - m
        ends = self.subsets(np.array([start, stop - 1]))[:, m:] - m
        first_top, last_top = (sum(self._comb[j + 1][ends[e, j]] for j in range(r)) for e in (0, 1))
        tops = self._unrank(np.arange(first_top, last_top + 1), r) + m
        offset = sum(self._comb[m + j + 1][tops[:, j]] for j in range(r))
        first = np.maximum(start - offset, 0)
        last = np.minimum(self._comb[m][tops[:, 0]], stop - offset)
        keep = first < last  # (a top holding no subset of the range: none, as ranks go)
        tops, offset, first = tops[keep], offset[keep], first[keep]
        rows = offset + first - start
        signed = self._signed32
        total = signed[tops[:, 0]]
        if r > 1:
            upper = signed[tops[:, 1]]
            for j in range(2, r):
                upper = upper + signed[tops[:, j]]
            total = total + upper
        return rows, first - rows, np.ascontiguousarray(total.transpose(1, 2, 0))

    def _shifted32(self) -> np.ndarray:
        """The base minus the margin, in single precision (the level's first sum)."""
        n = self.base.shape[-1]
        return np.asarray(self.base - self.margin * np.eye(n), dtype=np.float32)

    def _single(self) -> np.ndarray:
        """The single-precision level of partial sums minus the margin, batch last."""
        if self._sums32 is None:
            key = ("float32", self.m32)
            if key not in self._shared:
                self._shared[key] = _single_level(self._signed32, self._shifted32(), self.m32)
            self._sums32 = self._shared[key]
        return self._sums32

    def _top_total(self, top: tuple[int, ...]) -> np.ndarray | None:
        """The single-precision sum of a top's items (None for no top), added to the level's
        partial sums: its largest item plus the sum of the others (kept for the next top)."""
        if not top:
            return None
        rest = top[1:]
        if rest != self._upper[0]:
            upper = None
            for item in rest:  # one addition at a time, as ``piece_arrays`` adds them
                upper = self._signed32[item] if upper is None else upper + self._signed32[item]
            self._upper = (rest, upper)
        upper = self._upper[1]
        return self._signed32[top[0]] if upper is None else self._signed32[top[0]] + upper

    def fill(self, pieces: list[tuple[int, int, int, tuple[int, ...]]], out: np.ndarray) -> None:
        """The single-precision matrices minus the margin of the pieces (``_pieces``), batch
        last, into ``out``."""
        sums = self._single()
        for row, first, last, top in pieces:
            where = out[:, :, row : row + last - first]
            total = self._top_total(top)
            if total is None:
                np.copyto(where, sums[:, :, first:last])
            else:
                np.add(sums[:, :, first:last], total[:, :, None], out=where)

    def fill_rows(
        self, pieces: list[tuple[int, int, int, tuple[int, ...]]], rows: np.ndarray, start: int
    ) -> np.ndarray:
        """The matrices of ``fill`` for the selected rows of the batch of ranks from ``start``
        only (ascending), bit for bit the same, batch last, shape (n, n, len(rows))."""
        starts = np.array([piece[0] for piece in pieces], dtype=np.int64)
        firsts = np.array([piece[1] for piece in pieces], dtype=np.int64)
        which = np.searchsorted(starts, rows, side="right") - 1
        if self._direct("float32", self.m32, rows.size):
            bottoms = self.subsets(start + rows)[:, : self.m32]
            out = self._bottoms(self._shifted32(), self._signed32, bottoms).transpose(1, 2, 0)
            out = np.ascontiguousarray(out)
        else:
            # (``take``: the result batch last and contiguous, as the factorization wants it)
            level = self._single()
            out = np.take(level, firsts[which] + rows - starts[which], axis=2, mode="clip")
        edges = np.flatnonzero(np.diff(which)) + 1
        for a, b in itertools.pairwise([0, *edges.tolist(), rows.size]):
            total = self._top_total(pieces[which[a]][3])
            if total is not None:
                out[:, :, a:b] += total[:, :, None]
        return out

    def _single_tier(
        self,
        pieces: list[tuple[int, int, int, tuple[int, ...]]],
        start: int,
        N: int,
        work: np.ndarray,
        diagonal: np.ndarray,
        rows: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Tier 2 on the whole batch of ranks from ``start`` (or on the selected rows,
        gathered), at most ``tier2_sets`` matrices (and the buffers' room) at a time:
        (passed, smallest pivot) of each single-precision factorization."""
        size = N if rows is None else rows.size
        step = max(min(self.tier2_sets, work.shape[2]), 1)
        passed, smallest = np.empty(size, dtype=bool), np.empty(size, dtype=np.float32)
        for a in range(0, size, step):
            b = min(a + step, size)
            if rows is None:
                mats = work[:, :, : b - a]
                self.fill(_clip(pieces, a, b), mats)
            else:
                mats = self.fill_rows(pieces, rows[a:b], start)
            diag = diagonal[:, : b - a]
            cholesky_batch_last(mats, diag)
            passed[a:b], smallest[a:b] = single_passed(diag)
        return passed, smallest

    def _device_batch(self, start: int, N: int) -> DeviceBatch:
        """Tier 2 on the device for the batch of ranks [start, start + N) (its pieces sent as
        arrays, the level of partial sums on the device once for every range of the level)."""
        assert self.device is not None
        if self._single_device is None:
            key = ("device", self.device.name, self.m32)
            if key not in self._shared:
                self._shared[key] = self.device.load(self._single())
            self._single_device = self._shared[key]
        rows, offsets, totals = self.piece_arrays(start, start + N)
        return self.device.screen(self._single_device, rows, offsets, totals, N)

    def _bound(
        self, t: int, mu: float
    ) -> tuple[float, float, np.ndarray, np.ndarray, float] | None:
        """(mu', lambda, c, sums, rounding) of tier 1 for the subsets whose largest item is t,
        at a shift mu' near ``mu``: a lower bound lambda of the smallest eigenvalue of the
        rounded ``K = base - items[t] - mu' I``, upper bounds c[b] of ``||K^(-1/2)
        factors[b].T||^2`` for b < t, the sums of c over the rows of the single-precision
        level below t, and a bound of ``||K - (base - items[t] - mu' I)||`` (None when K is
        not positive definite or too ill-conditioned).  The last three
        items' are kept (consecutive ranks share their largest item, and batches asked in
        descending order each ask theirs in ascending order), and reused while their shift
        is at least ``mu`` and at most 5% above it (the threshold of the ranking only falls
        within a range)."""
        kept = self._bounds.pop(t, None)
        if kept is None or not (mu <= kept[0] <= mu * 1.05):
            assert self.factors is not None
            H = self.base - self.items[t]
            shared = _shared_bound(H, self.factors, t, mu)
            bound = None
            if shared is not None:
                bound = (*shared, _level_sums(shared[1], self.m32), _shift_rounding(H, mu))
            kept = (mu, bound)
            if len(self._bounds) >= 3:
                del self._bounds[next(iter(self._bounds))]
        self._bounds[t] = kept  # the most recent last
        return None if kept[1] is None else (kept[0], *kept[1])

    def lower_bounds(
        self, pieces: list[tuple[int, int, int, tuple[int, ...]]], size: int, mu: float = 0.0
    ) -> np.ndarray:
        """Tier 1: a lower bound of the smallest eigenvalue of each matrix minus LAPACK's
        backward error (-inf where there is none).

        For the subsets whose largest item is t, with ``H = base - items[t] - mu I``
        positive definite and ``E`` the sum of the other items, ``G - mu I = H - E =
        H^(1/2) (I - H^(-1/2) E H^(-1/2)) H^(1/2)``, so where the sum s of the c of the
        other items is below 1, ``lambda_min(G) >= mu + lambda_min(H) (1 - s)``.  A shift
        ``mu`` near the threshold of the ranking (``screen``) proves most sets above it
        where ``mu = 0`` proves them only positive definite.  Taken off: ``_bound_slack``
        (the float64 sums, the items against their factors, LAPACK's backward error),
        ``_shift_rounding`` (K against ``H - mu I``) and the rounding of the bound's own
        operations."""
        low = np.full(size, -np.inf)
        if self.factors is None:
            return low
        for row, first, last, top in pieces:
            bound = self._bound(top[-1], mu)
            if bound is None:
                continue
            shift, lam, c, sums, rounding = bound
            s = sums[first:last] + c[list(top[:-1])].sum()
            # less the slack, the rounding of K, and that of the bound's own three operations
            # (at most 4 u (shift + lambda): 1 - s and its product are within lambda)
            off = self._slack + rounding + 4 * _U64 * (shift + lam)
            low[row : row + last - first] = np.where(
                s < 1.0, shift + lam * (1.0 - s) - off, -np.inf
            )
        return low

    def screen(
        self,
        start: int,
        stop: int,
        shift: float,
        threshold: float | None,
        work: np.ndarray,
        diagonal: np.ndarray,
    ) -> ScreenedBatch | DeviceScreenedBatch:
        """Screen the subsets of the ranks [start, stop) (a range of ``batches``).

        Parameters
        ----------
        start, stop : int
        shift : float
            The screening shift already in the matrices (for the proxies).
        threshold : float or None
            With the proxies asked: the largest proxy that can still matter
            (the subsets whose lower bound is above it need no more).
        work : ndarray of float32, shape (n, n, M), M >= stop - start
        diagonal : ndarray of float32, shape (n, M)
            Buffers.

        Returns
        -------
        ScreenedBatch or DeviceScreenedBatch
        """
        N = stop - start
        if self.device is not None:
            return self._device_screen(start, N, shift)
        pieces = self._pieces(start, stop)
        tried = self._skip <= 0
        self._skip -= N
        # the ranking asks for sets proved above its threshold: tier 1 at a shift just under it
        mu = 0.0 if threshold is None or not np.isfinite(threshold) else threshold - shift
        mu = max(mu * (1.0 - 2.0**-20), 0.0)
        bound = self.lower_bounds(pieces, N, mu) if tried else np.full(N, -np.inf)
        ok = bound > 0
        screen = ScreenedBatch(self, start, ok)
        if threshold is not None:
            screen.low = np.where(ok, _proxy_floor(bound, shift), -np.inf)
            screen.exact = np.zeros(N, dtype=bool)
            rows = np.flatnonzero(~ok | (screen.low <= threshold))
        else:
            rows = np.flatnonzero(~ok)
        if rows.size > max(64, N // 50):
            if tried and self.factors is not None and rows.size > N // 2:
                self._skip = _SKIP_SETS
            # many subsets left open: tier 2 for them (for the whole batch, a few calls, when
            # they are most of it), then LAPACK for those it leaves open
            every = rows.size > N * _GATHER_FRACTION
            passed, smallest = self._single_tier(
                pieces, start, N, work, diagonal, None if every else rows
            )
            ok_rows = slice(None) if every else rows
            ok[ok_rows] |= passed
            if screen.low is not None:
                low = smallest.astype(np.float64) ** 2 + shift
                screen.low[ok_rows] = np.where(
                    passed, np.maximum(screen.low[ok_rows], low), screen.low[ok_rows]
                )
            # LAPACK decides the rest; the proxies under the threshold are asked for later
            rows = np.flatnonzero(~ok)
        self._lapack(screen, rows, shift)
        return screen

    def _device_screen(self, start: int, N: int, shift: float) -> DeviceScreenedBatch:
        """``screen`` on the device: tier 2 for the whole batch (tier 1 would keep the CPU busy
        meanwhile), LAPACK for the subsets it leaves open."""
        return DeviceScreenedBatch(self, start, self._device_batch(start, N), shift)

    def lapack(self, ranks: np.ndarray, shift: float) -> tuple[np.ndarray, np.ndarray]:
        """LAPACK's decisions and proxies (``cholesky_screen``) of the given ranks' float64
        matrices (ascending ranks)."""
        return _proxies(cholesky_or_nan(self.matrices(ranks)), shift)

    def _lapack(self, screen: ScreenedBatch, rows: np.ndarray, shift: float) -> None:
        """LAPACK decides the selected rows of a screened batch (their proxies known)."""
        if rows.size:
            decided, proxies = self.lapack(screen.offset + rows, shift)
            screen.ok[rows] = decided
            if screen.low is not None and screen.exact is not None:
                screen.low[rows] = proxies
                screen.exact[rows] = True


def _clip(
    pieces: list[tuple[int, int, int, tuple[int, ...]]], a: int, b: int
) -> list[tuple[int, int, int, tuple[int, ...]]]:
    """The pieces (``ColexScreen._pieces``) of the rows [a, b) of their batch, as pieces of
    a batch of their own."""
    out = []
    for row, first, last, top in pieces:
        lo, hi = max(row, a), min(row + last - first, b)
        if lo < hi:
            out.append((lo - a, first + lo - row, first + hi - row, top))
    return out


def _level_sums(values: np.ndarray, m: int) -> np.ndarray:
    """Sums of ``values`` over every m-subset of its indices, in colex order."""
    sums = np.zeros(1)
    for j in range(1, m + 1):
        parts = [
            sums[: math.comb(last, j - 1)] + values[last] for last in range(j - 1, values.size)
        ]
        sums = np.concatenate(parts) if parts else np.zeros(0)
    return sums


_U64 = 2.0**-53


def _gamma(m: int) -> float:
    return m * _U64 / (1 - m * _U64)


def _bound_slack(items: np.ndarray, base: np.ndarray, factors: np.ndarray, k: int) -> float:
    """What tier 1's bound takes off, whatever the subset: the roundings of the float64 sums
    (``gamma(k + 3)`` times the absolute values of the terms), of the items against their
    factors (``gamma(r) ||factors[i]||_F^2``), and LAPACK's backward error on the sum
    (``gamma(4 n + 4)`` times its trace, taken 100 times over), each doubled."""
    n = base.shape[-1]
    frobenius = np.linalg.norm(base) + np.linalg.norm(items, axis=(1, 2)).sum()
    trace = np.abs(np.diagonal(base)).sum() + np.abs(np.trace(items, axis1=1, axis2=2)).sum()
    rounding = _gamma(k + 3) * frobenius + _gamma(factors.shape[1]) * np.sum(factors**2)
    return float(2.0 * (rounding + 100 * _gamma(4 * n + 4) * trace)) + 1e-300


def _shared_bound(
    H: np.ndarray, factors: np.ndarray, t: int, mu: float = 0.0
) -> tuple[float, np.ndarray] | None:
    """(lambda, c) of ``ColexScreen._bound`` for the rounded ``K = H - mu I``, ``H = base -
    items[t]`` (K differs from ``H - mu I`` by ``_shift_rounding``).

    The eigendecomposition of K is backward stable: its eigenvalues are within ``64 n u
    ||K||`` of K's (a generous multiple of LAPACK's bound).  The computed c are then within
    a relative ``kappa 64 n u`` of the exact ones (kappa the condition number of K), which
    the condition cap keeps below 1e-6 (kappa at most 1e6, less for n above about 140); they
    are taken 1e-5 relatively (and 1e-12 absolutely) above, which also covers the rounding
    of their sums.
    """
    n = H.shape[-1]
    lam, V = np.linalg.eigh(H - mu * np.eye(n) if mu else H)
    lowest = lam[0] - 64 * n * _U64 * max(abs(lam[0]), abs(lam[-1]))
    cap = min(1e6, 1e-6 / (64 * n * _U64))
    if not np.all(np.isfinite(lam)) or lowest <= 0 or lam[-1] > cap * lowest:
        return None
    Z = np.einsum("brn,nj->brj", factors[:t], V / np.sqrt(lam))
    c = np.linalg.eigvalsh(Z @ Z.transpose(0, 2, 1))[:, -1] if t else np.zeros(0)
    return float(lowest), np.maximum(c, 0.0) * (1 + 1e-5) + 1e-12


def _shift_rounding(H: np.ndarray, mu: float) -> float:
    """At most twice the largest rounding of ``H - mu I``'s diagonal (``u (|H_ii| + mu)``)."""
    return 2 * _U64 * (float(np.abs(np.diagonal(H)).max()) + mu) if mu else 0.0


def _proxy_floor(bound: np.ndarray, shift: float) -> np.ndarray:
    """A lower bound of the proxy ``fl(fl(l^2) + shift)`` of a factorization whose smallest
    diagonal entry l has ``l^2 >= bound`` (each rounding of the proxy and of this bound
    taken off)."""
    low = 1.0 - 2.0**-50
    return (np.maximum(bound, 0.0) * low + shift) * low


@dataclass
class ScreenedBatch:
    """Consecutive subsets screened together (``ColexScreen.screen``); row r is the subset
    of colex rank ``offset + r``.

    Attributes
    ----------
    source : ColexScreen
    offset : int
        Colex rank of the first row.
    ok : ndarray of bool, shape (N,)
        Whether LAPACK's Cholesky factorization of each matrix succeeds.
    low : ndarray, shape (N,), or None
        With the proxies asked: a lower bound of each proxy of
        ``cholesky_screen`` (squared smallest pivot plus the shift, -inf
        where the factorization fails), the proxy itself where ``exact``.
    exact : ndarray of bool, shape (N,), or None
        Where ``low`` is the proxy.
    """

    source: ColexScreen
    offset: int
    ok: np.ndarray
    low: np.ndarray | None = None
    exact: np.ndarray | None = None

    def subsets(self, rows: np.ndarray) -> np.ndarray:
        """Sorted subsets of the selected rows, shape (len(rows), k)."""
        return self.source.subsets(self.offset + rows)

    def failed(self) -> np.ndarray:
        """The rows whose factorization fails (LAPACK's decision), ascending."""
        return np.flatnonzero(~self.ok)

    def below(self, threshold: float, most: int | None = None) -> tuple[np.ndarray, bool]:
        """The rows whose lower bound (``low``) is at most ``threshold``, ascending, and
        False; when there are more than ``most``, those of the ``most`` smallest bounds
        (ascending) and True."""
        assert self.low is not None
        rows = np.flatnonzero(self.low <= threshold)
        if most is not None and rows.size > most:
            return np.sort(rows[np.argpartition(self.low[rows], most - 1)[:most]]), True
        return rows, False

    def proxies(self, rows: np.ndarray, shift: float) -> np.ndarray:
        """The proxies of the selected rows (ascending), bit for bit those of
        ``cholesky_screen`` (LAPACK factors the rows whose proxy is not known yet, and they
        are kept)."""
        assert self.low is not None and self.exact is not None
        todo = rows[~self.exact[rows]]
        if todo.size:
            self.low[todo] = self.source.lapack(self.offset + todo, shift)[1]
            self.exact[todo] = True
        return self.low[rows]


@dataclass
class DeviceScreenedBatch:
    """Consecutive subsets screened on a device (``ColexScreen.screen``), answering the
    questions of ``ScreenedBatch`` (``failed``, ``below``, ``proxies``) with the same
    answers: the bounds stay on the device, which sends the host the few rows it asks for;
    the rows the device leaves open are decided by LAPACK, as on the CPU.

    Attributes
    ----------
    source : ColexScreen
    offset : int
        Colex rank of the first row.
    batch : DeviceBatch
        The device's factorizations (``ssecert.structure.device``).
    shift : float
        The screening shift already in the matrices.
    decided, decided_ok : ndarray
        The rows the device leaves open (ascending) and LAPACK's decision on each.
    rows, values : ndarray
        The rows LAPACK factored (ascending) and their proxies (-inf where the factorization
        fails).
    """

    source: ColexScreen
    offset: int
    batch: DeviceBatch
    shift: float
    decided: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    decided_ok: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    rows: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    values: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __post_init__(self) -> None:
        self.decided = self.batch.failed()
        self.decided_ok = self._lapack(self.decided)

    def _lapack(self, rows: np.ndarray) -> np.ndarray:
        """LAPACK's decisions on rows not factored yet (ascending), their proxies kept."""
        if rows.size == 0:
            return np.zeros(0, dtype=bool)
        ok, proxies = self.source.lapack(self.offset + rows, self.shift)
        merged = np.concatenate([self.rows, rows])
        order = np.argsort(merged, kind="stable")
        self.rows, self.values = merged[order], np.concatenate([self.values, proxies])[order]
        return ok

    def _known(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where each row is among those LAPACK factored, and whether it is."""
        where = np.minimum(np.searchsorted(self.rows, rows), max(self.rows.size - 1, 0))
        return where, (self.rows[where] == rows) if self.rows.size else np.zeros(rows.size, bool)

    def subsets(self, rows: np.ndarray) -> np.ndarray:
        """Sorted subsets of the selected rows, shape (len(rows), k)."""
        return self.source.subsets(self.offset + rows)

    def failed(self) -> np.ndarray:
        """The rows whose factorization fails (LAPACK's decision), ascending."""
        return self.decided[~self.decided_ok]

    def below(self, threshold: float, most: int | None = None) -> tuple[np.ndarray, bool]:
        """As ``ScreenedBatch.below``: the device's bounds of the rows it proves, LAPACK's
        proxies where it factored."""
        rows, lows, truncated = self.batch.below(threshold, self.shift, most)
        lows = np.array(lows, dtype=np.float64)
        where, known = self._known(rows)
        lows[known] = self.values[where[known]]  # the proxy itself where it is known
        # the rows the device did not prove are LAPACK's alone (the others are among the
        # device's rows whenever their proxy is at most the threshold)
        extra = (self.values <= threshold) & ~np.isin(self.rows, rows)
        rows = np.concatenate([rows[lows <= threshold], self.rows[extra]])
        lows = np.concatenate([lows[lows <= threshold], self.values[extra]])
        order = np.argsort(rows, kind="stable")
        rows, lows = rows[order], lows[order]
        if most is None or (not truncated and rows.size <= most):
            return rows, False
        if rows.size < most:  # (LAPACK's proxies took some above: every row, then)
            return self.below(threshold)
        return np.sort(rows[np.argpartition(lows, most - 1)[:most]]), True

    def proxies(self, rows: np.ndarray, shift: float) -> np.ndarray:
        """The proxies of the selected rows, bit for bit those of ``cholesky_screen``."""
        _, known = self._known(rows)
        self._lapack(np.unique(rows[~known]))
        where, _ = self._known(rows)
        return self.values[where]
