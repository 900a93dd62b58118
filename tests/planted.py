"""Plants with a planted, exactly known sparse-observability structure.

A plant is built in modal coordinates, M = block diagonal of Jordan blocks
J_m(lambda) (integer lambda) and rotation blocks [[a, -b], [b, a]]
(eigenvalues a +- ib), with an integer output matrix C_modal whose entries on
each eigenvector column are zero outside a chosen sensor set.  A random
similarity T (integer unimodular, or orthogonal) gives A = T M T^-1 and
C = C_modal T^-1.  Since C v = C_modal e for the eigenvector v = T e, the
truth is computed from C_modal in exact rational arithmetic, independently of
the package:

    max_removable = min over eigenvalues of (fewest sensors that see some
                    nonzero vector of the eigenspace) - 1,

and the lexicographically first smallest breaking set is the first among
the minimal supports.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from fractions import Fraction

import numpy as np


def exact_rank(rows: list[list[Fraction]]) -> int:
    """Rank over Q by Gaussian elimination on Fractions."""
    M = [[Fraction(x) for x in r] for r in rows]
    if not M:
        return 0
    rank, cols = 0, len(M[0])
    for c in range(cols):
        pivot = next((r for r in range(rank, len(M)) if M[r][c] != 0), None)
        if pivot is None:
            continue
        M[rank], M[pivot] = M[pivot], M[rank]
        for r in range(len(M)):
            if r != rank and M[r][c] != 0:
                f = M[r][c] / M[rank][c]
                M[r] = [a - f * b for a, b in zip(M[r], M[rank])]
        rank += 1
    return rank


def exact_null_vector(rows: list[list[Fraction]], g: int) -> list[Fraction]:
    """A nonzero vector u with rows @ u = 0 (rows of rank g - 1, g columns)."""
    M = [list(r) for r in rows]
    pivots = []
    rank = 0
    for c in range(g):
        pivot = next((r for r in range(rank, len(M)) if M[r][c] != 0), None)
        if pivot is None:
            continue
        M[rank], M[pivot] = M[pivot], M[rank]
        lead = M[rank][c]
        M[rank] = [a / lead for a in M[rank]]
        for r in range(len(M)):
            if r != rank and M[r][c] != 0:
                f = M[r][c]
                M[r] = [a - f * b for a, b in zip(M[r], M[rank])]
        pivots.append(c)
        rank += 1
    free = next(c for c in range(g) if c not in pivots)
    u = [Fraction(0)] * g
    u[free] = Fraction(1)
    for r, c in enumerate(pivots):
        u[c] = -M[r][free]
    return u


def exact_min_supports(W: list[list[int]]) -> tuple[int, list[tuple[int, ...]]]:
    """Fewest nonzero entries of W u over u != 0 (real integer W, p x g), all minimisers."""
    p, g = len(W), len(W[0])
    F = [[Fraction(x) for x in row] for row in W]
    if exact_rank(F) < g:
        return 0, [()]
    best, supports = None, set()
    for R in itertools.combinations(range(p), g - 1):
        sub = [F[i] for i in R]
        if g > 1 and exact_rank(sub) < g - 1:
            continue
        u = exact_null_vector(sub, g) if g > 1 else [Fraction(1)]
        support = tuple(i for i in range(p) if sum(a * b for a, b in zip(F[i], u)) != 0)
        if best is None or len(support) < best:
            best, supports = len(support), {support}
        elif len(support) == best:
            supports.add(support)
    return best, sorted(supports)


@dataclass(frozen=True)
class Planted:
    A: np.ndarray
    C: np.ndarray
    max_removable: int
    breaking_set: tuple[int, ...]
    description: str


def _unimodular(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Integer T with integer inverse, from a few elementary row operations."""
    T = np.eye(n, dtype=np.int64)
    for _ in range(2 * n if n > 1 else 0):
        i, j = rng.choice(n, 2, replace=False)
        T[i] += int(rng.choice([-1, 1])) * T[j]
    Tinv = np.round(np.linalg.inv(T)).astype(np.int64)
    assert np.array_equal(T @ Tinv, np.eye(n, dtype=np.int64))
    return T, Tinv


def planted(rng: np.random.Generator, kind: str, *, integer: bool = True) -> Planted:
    """A random plant of the given kind with its exact sparse-observability truth.

    kind: "distinct" (simple real eigenvalues and complex pairs), "jordan"
    (Jordan blocks, some eigenvalues repeated in several blocks), "identity"
    (A = I), "mixed" (any of these structures together).
    """
    p = int(rng.integers(2, 9))
    blocks: list[tuple[str, int, int, int]] = []  # (type, size, a, b)
    if kind == "identity":
        n = int(rng.integers(1, 5))
        blocks = [("jordan", 1, 1, 0)] * n
    else:
        n_target = int(rng.integers(2, 7))
        size = 0
        values = list(rng.permutation(np.arange(-4, 5)))
        while size < n_target:
            choice = rng.random()
            if kind == "distinct" and choice < 0.3 and size + 2 <= n_target + 1:
                a, b = int(rng.integers(-2, 3)), int(rng.integers(1, 3))
                if ("rot", 2, a, b) not in blocks:
                    blocks.append(("rot", 2, a, b))
                    size += 2
                continue
            if kind in ("jordan", "mixed") and choice < 0.6:
                m = int(rng.integers(1, 4))
                lam = (
                    int(values[0]) if rng.random() < 0.5 or len(values) < 2 else int(values.pop(0))
                )
                blocks.append(("jordan", m, lam, 0))
                size += m
                continue
            if kind == "mixed" and choice < 0.8:
                a, b = int(rng.integers(-2, 3)), int(rng.integers(1, 3))
                if ("rot", 2, a, b) not in blocks:
                    blocks.append(("rot", 2, a, b))
                    size += 2
                continue
            blocks.append(("jordan", 1, int(values.pop(0)), 0))
            size += 1
        n = size
    M = np.zeros((n, n), dtype=np.int64)
    Cm = rng.integers(-3, 4, size=(p, n))
    eig_cols: dict[tuple[int, int], list[int]] = {}
    start = 0
    for typ, m, a, b in blocks:
        if typ == "jordan":
            M[start : start + m, start : start + m] = a * np.eye(m, dtype=np.int64) + np.diag(
                np.ones(m - 1, dtype=np.int64), 1
            )
            eig_cols.setdefault((a, 0), []).append(start)
        else:
            M[start : start + 2, start : start + 2] = [[a, -b], [b, a]]
            eig_cols.setdefault((a, b), []).append(start)
        start += m
    # plant the sensor patterns on the eigenvector columns
    for (_, b), cols in eig_cols.items():
        for c in cols:
            width = 2 if b else 1
            k = int(rng.integers(1, p + 1)) if rng.random() < 0.9 else 0
            seen = set(rng.choice(p, k, replace=False).tolist()) if k else set()
            for i in range(p):
                if i in seen:
                    while not np.any(Cm[i, c : c + width]):
                        Cm[i, c : c + width] = rng.integers(-3, 4, size=width)
                else:
                    Cm[i, c : c + width] = 0
    if rng.random() < 0.3:  # duplicated sensors make larger zero sets
        i, j = rng.choice(p, 2, replace=False)
        Cm[j] = Cm[i] * int(rng.choice([-2, -1, 1, 2]))
    # exact truth
    best, supports = None, []
    for (_, b), cols in eig_cols.items():
        if b == 0:
            W = [[int(Cm[i, c]) for c in cols] for i in range(p)]
            size, sup = exact_min_supports(W)
        else:
            # complex pair a + ib (simple): eigenvector e_c - i e_(c+1) up to scale;
            # a sensor sees it iff its two entries are not both zero
            c = cols[0]
            sup = [tuple(i for i in range(p) if Cm[i, c] or Cm[i, c + 1])]
            size = len(sup[0])
        if best is None or size < best:
            best, supports = size, list(sup)
        elif size == best:
            supports.extend(sup)
    if integer:
        T, Tinv = _unimodular(rng, n)
        A = (T @ M @ Tinv).astype(float)
        C = (Cm @ Tinv).astype(float)
    else:
        Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
        A = Q @ M @ Q.T
        C = Cm @ Q.T
    return Planted(
        A=A,
        C=C,
        max_removable=best - 1,
        breaking_set=min(supports),
        description=f"{kind}: blocks {blocks}, p = {p}",
    )


def hidden_jordan(rng: np.random.Generator) -> Planted | None:
    """Jordan blocks up to size 4, eigenvalues repeated across blocks, hidden by an
    ill-conditioned integer similarity (the data stay exact integers, so the planted
    truth is the truth).  None when the entries would exceed 2^50."""
    p = int(rng.integers(3, 11))
    n_target = int(rng.integers(3, 10))
    blocks: list[tuple[int, int]] = []
    size = 0
    values = [int(v) for v in rng.permutation(np.arange(-3, 4))]
    while size < n_target:
        m = int(rng.integers(1, 5))
        if rng.random() < 0.5 or len(values) < 2:
            lam = values[0]
        else:
            lam = values.pop(0)
        blocks.append((m, lam))
        size += m
    n = size
    M = np.zeros((n, n), dtype=np.int64)
    Cm = rng.integers(-3, 4, size=(p, n))
    eig_cols: dict[int, list[int]] = {}
    start = 0
    for m, lam in blocks:
        M[start : start + m, start : start + m] = lam * np.eye(m, dtype=np.int64) + np.diag(
            np.ones(m - 1, dtype=np.int64), 1
        )
        eig_cols.setdefault(lam, []).append(start)
        start += m
    for cols in eig_cols.values():
        for c in cols:
            seen = set(rng.choice(p, int(rng.integers(1, p + 1)), replace=False).tolist())
            for i in range(p):
                if i in seen:
                    while Cm[i, c] == 0:
                        Cm[i, c] = rng.integers(-3, 4)
                else:
                    Cm[i, c] = 0
    best, supports = None, []
    for cols in eig_cols.values():
        size_, sup = exact_min_supports([[int(Cm[i, c]) for c in cols] for i in range(p)])
        if best is None or size_ < best:
            best, supports = size_, list(sup)
        elif size_ == best:
            supports.extend(sup)
    T = np.eye(n, dtype=np.int64)
    for _ in range(int(rng.integers(n, 4 * n))):
        i, j = rng.choice(n, 2, replace=False)
        T[i] += int(rng.choice([-2, -1, 1, 2])) * T[j]
    Tinv = np.round(np.linalg.inv(T)).astype(np.int64)
    if not np.array_equal(T @ Tinv, np.eye(n, dtype=np.int64)):
        return None
    A, C = T @ M @ Tinv, Cm @ Tinv
    if np.abs(A).max() > 2**50 or np.abs(C).max() > 2**50:
        return None
    return Planted(
        A=A.astype(float),
        C=C.astype(float),
        max_removable=best - 1,
        breaking_set=min(supports),
        description=f"hidden jordan {blocks}, p = {p}",
    )
