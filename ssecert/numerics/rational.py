"""Small dense linear algebra in exact rationals, on the values floats hold.

Every float is a rational number; these helpers decide on those exact
values (no rounding), for the few small matrices a certificate's last check
needs: products, a solve, positive definiteness, and the reduced row echelon
form with what follows from it (rank, null space, a particular solution, the
inverse, the minimum-norm solution), as the exact deadbeat construction asks.
The reduced row echelon form is unique, so the null-space basis (one vector
per free column, 1 there) and the particular solution (the free variables 0)
are those of any exact implementation that reads them off it, sympy's
included.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

__all__ = [
    "Matrix",
    "fractions",
    "product",
    "solve",
    "is_positive_definite",
    "rref",
    "rank",
    "nullspace",
    "particular_solution",
    "inverse",
    "minimum_norm_solution",
    "transpose",
]

Matrix = list[list[Fraction]]


def fractions(M: np.ndarray) -> Matrix:
    """The exact values of a float matrix (2-D) as Fractions."""
    return [[Fraction(float(v)) for v in row] for row in np.atleast_2d(np.asarray(M, float))]


def product(X: Matrix, Y: Matrix) -> Matrix:
    """X Y, exactly."""
    columns = list(zip(*Y))
    return [[sum((a * b for a, b in zip(row, col)), Fraction(0)) for col in columns] for row in X]


def solve(M: Matrix, b: list[Fraction]) -> list[Fraction] | None:
    """The solution of M x = b by Gaussian elimination; None when M is singular."""
    n = len(M)
    a = [list(row) + [b[i]] for i, row in enumerate(M)]
    for col in range(n):
        pivot = next((r for r in range(col, n) if a[r][col] != 0), None)
        if pivot is None:
            return None
        a[col], a[pivot] = a[pivot], a[col]
        for r in range(n):
            if r != col and a[r][col] != 0:
                f = a[r][col] / a[col][col]
                a[r] = [x - f * y for x, y in zip(a[r], a[col])]
    return [a[i][n] / a[i][i] for i in range(n)]


def is_positive_definite(M: Matrix) -> bool:
    """Whether the symmetric M is positive definite: every pivot of its symmetric elimination
    (the LDL' factorisation without pivoting) is positive."""
    a = [list(row) for row in M]
    n = len(a)
    for k in range(n):
        if a[k][k] <= 0:
            return False
        for i in range(k + 1, n):
            if a[i][k] != 0:
                f = a[i][k] / a[k][k]
                a[i] = [x - f * y for x, y in zip(a[i], a[k])]
    return True


def transpose(M: Matrix, columns: int | None = None) -> Matrix:
    """M', with ``columns`` the number of columns of M where it has no rows."""
    if not M:
        return [[] for _ in range(columns or 0)]
    return [list(col) for col in zip(*M)]


def rref(M: Matrix) -> tuple[Matrix, list[int]]:
    """The reduced row echelon form of M (unique) and its pivot columns."""
    a = [list(row) for row in M]
    rows = len(a)
    cols = len(a[0]) if rows else 0
    pivots: list[int] = []
    r = 0
    for c in range(cols):
        pivot = next((i for i in range(r, rows) if a[i][c] != 0), None)
        if pivot is None:
            continue
        a[r], a[pivot] = a[pivot], a[r]
        lead = a[r][c]
        a[r] = [x / lead for x in a[r]]
        for i in range(rows):
            if i != r and a[i][c] != 0:
                f = a[i][c]
                a[i] = [x - f * y for x, y in zip(a[i], a[r])]
        pivots.append(c)
        r += 1
        if r == rows:
            break
    return a, pivots


def rank(M: Matrix) -> int:
    """The rank of M."""
    return len(rref(M)[1])


def nullspace(M: Matrix, columns: int | None = None) -> list[list[Fraction]]:
    """A basis of the null space of M read off its reduced row echelon form: one vector per
    free column, 1 there, 0 at the other free columns (``columns``: M's number of columns
    where it has no rows)."""
    cols = len(M[0]) if M else (columns or 0)
    R, pivots = rref(M) if M else ([], [])
    basis = []
    for free in (c for c in range(cols) if c not in pivots):
        v = [Fraction(0)] * cols
        v[free] = Fraction(1)
        for i, c in enumerate(pivots):
            v[c] = -R[i][free]
        basis.append(v)
    return basis


def particular_solution(
    M: Matrix, b: list[Fraction], columns: int | None = None
) -> list[Fraction] | None:
    """The solution of M x = b whose free variables (those of M's reduced row echelon form)
    are 0; None when there is none (``columns``: M's number of columns where it has no
    rows)."""
    cols = len(M[0]) if M else (columns or 0)
    if not M:
        return [Fraction(0)] * cols
    R, pivots = rref([list(row) + [b[i]] for i, row in enumerate(M)])
    if cols in pivots:
        return None
    x = [Fraction(0)] * cols
    for i, c in enumerate(pivots):
        x[c] = R[i][cols]
    return x


def inverse(M: Matrix) -> Matrix | None:
    """M^(-1); None when M is singular."""
    n = len(M)
    R, pivots = rref(
        [list(row) + [Fraction(int(i == j)) for j in range(n)] for i, row in enumerate(M)]
    )
    if pivots[:n] != list(range(n)):
        return None
    return [row[n:] for row in R]


def minimum_norm_solution(B: Matrix, Y: Matrix, columns: int) -> Matrix:
    """B^+ Y, the least-squares solution of B X = Y of least norm (B with ``columns``
    columns and at least one row, Y with as many rows), from the full-rank factorisation
    B = F G: F the pivot columns of B, G the nonzero rows of its reduced row echelon form,
    B^+ = G' (G G')^(-1) (F'F)^(-1) F'."""
    if not B or len(Y) != len(B):
        raise ValueError(f"B X = Y needs B with rows and Y with as many: {len(B)} and {len(Y)}")
    R, pivots = rref(B)
    if not pivots:
        return [[Fraction(0)] * len(Y[0]) for _ in range(columns)]
    F = [[row[c] for c in pivots] for row in B]
    G = R[: len(pivots)]
    Gt, Ft = transpose(G), transpose(F)
    inner = inverse(product(G, Gt))
    outer = inverse(product(Ft, F))
    assert inner is not None and outer is not None  # full rank by construction
    return product(Gt, product(inner, product(outer, product(Ft, Y))))
