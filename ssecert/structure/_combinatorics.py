"""Batched enumeration of subsets with additive per-item matrices.

Many structural questions need, for every k-subset S of q items, the
matrix ``base + sign * sum(items[i] for i in S)`` (a Gramian of the sensors
left after removing S, or of the rows of an attack support).  Enumerating
in colexicographic order makes this cheap: the k-subsets whose largest
elements are a fixed "top" tuple are exactly the first C(t, m) m-subsets
(in colex order) of the smaller indices, so one precomputed level of
partial sums serves every top with a single broadcast addition and no
per-subset gathering.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from .._linalg import cholesky_or_nan, single_screen

__all__ = [
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
    matrices : ndarray, shape (N, n, n)
        ``base + sign * sum(items[S])`` for each subset S of the block.
    bottoms : ndarray of int, shape (N, m)
        Lower part of each subset.
    top : tuple of int
        Upper part, shared by the whole block.
    """

    offset: int
    matrices: np.ndarray
    bottoms: np.ndarray
    top: tuple[int, ...]

    def __len__(self) -> int:
        return self.matrices.shape[0]

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
    if m == k:
        for first in range(start, stop, chunk):
            last = min(first + chunk, stop)
            yield SubsetBlock(first, sums[first:last], subsets[first:last], ())
        return
    # tops: (k - m)-subsets t_1 < ... of {m, ..., q-1}, in colex order, from the one that
    # holds rank ``start`` (its m smallest items are the bottom, the rest the top)
    top = list(colex_unrank(start, k)[m:])
    while True:
        count = math.comb(top[0], m)
        offset = sum(math.comb(t, m + j + 1) for j, t in enumerate(top))
        if offset >= stop:
            return
        shift = sign * items[top].sum(axis=0)
        for first in range(max(start - offset, 0), min(count, stop - offset), chunk):
            last = min(first + chunk, count, stop - offset)
            yield SubsetBlock(
                offset + first, sums[first:last] + shift, subsets[first:last], tuple(top)
            )
        if not _next_top(top, m, q):
            return


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
