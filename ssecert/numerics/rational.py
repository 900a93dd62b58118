"""Small dense linear algebra in exact rationals, on the values floats hold.

Every float is a rational number; these helpers decide on those exact
values (no rounding), for the few small matrices a certificate's last check
needs: products, a solve, and positive definiteness.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

__all__ = ["Matrix", "fractions", "product", "solve", "is_positive_definite"]

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
