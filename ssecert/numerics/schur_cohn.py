"""The Schur-Cohn test on the exact characteristic polynomial of a float matrix.

Every eigenvalue of F lies strictly inside the unit circle exactly when its
characteristic polynomial p passes the Schur-Cohn recursion: with a_0 and a_n
the constant and leading coefficients, p is Schur stable if and only if
|a_0| < |a_n| and ``(a_n p(z) - a_0 z^n p(1/z)) / z`` (degree n - 1, leading
coefficient a_n^2 - a_0^2) is Schur stable; a failed inequality proves a root
of modulus at least 1 (the roots' product has modulus |a_0 / a_n| >= 1, or the
next polynomial's) (Henrici, Applied and Computational Complex Analysis, vol. 1,
Sec. 6.8).  On the integer coefficients of p (``characteristic_polynomial``,
from sympy's exact characteristic polynomial of the integer matrix behind F)
every step is integer arithmetic, so the answer is that of the exact F however
close to 1 its spectral radius lies, where powers of F would need an
astronomical exponent.  The same test on p(r z) bounds rho(F) < r
(``radius_below``).  The integers grow with each step (each step's common
factor is divided out); callers pass a budget of bits and get None beyond it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from .exact_powers import Dyadic

__all__ = ["characteristic_polynomial", "schur_stable", "radius_below", "SCHUR_COHN_LIMIT"]

SCHUR_COHN_LIMIT = 20  # largest n tried (n = 20: about 0.2 s, n = 30: about 2 s)
DEFAULT_MAX_BITS = 2_000_000  # largest integer a step may reach before the test gives up


def characteristic_polynomial(F: Dyadic) -> list[int]:
    """Integer coefficients a_0, ..., a_n of a positive multiple of det(z I - F) (a_k the
    coefficient of z^k), exactly.

    With F = M 2^e (M an integer matrix), det(z I - F) = sum c_(n-k) 2^(e (n - k)) z^k for
    the integer coefficients c of det(w I - M) (sympy's ``DomainMatrix.charpoly`` over the
    integers), times 2^(-e n) when e < 0.

    >>> from ssecert.numerics.exact_powers import dyadic
    >>> import numpy as np
    >>> characteristic_polynomial(dyadic(np.array([[0.5, 1.0], [0.0, 0.25]])))  # 16 (z - 1/2) (z - 1/4)
    [2, -12, 16]
    """
    from sympy import ZZ
    from sympy.polys.matrices import DomainMatrix

    n = F.shape[0]
    if n == 0:
        return [1]
    rows = [[ZZ(int(x)) for x in row] for row in F.ints]
    c = [int(x) for x in DomainMatrix(rows, (n, n), ZZ).charpoly()]  # c[0] = 1 leads
    if not _cayley_hamilton(F, c):  # sympy's polynomial checked independently
        raise ArithmeticError("the characteristic polynomial fails Cayley-Hamilton")
    e = F.exponent
    if e <= 0:
        return [c[n - k] << (-e * k) for k in range(n + 1)]
    return [c[n - k] << (e * (n - k)) for k in range(n + 1)]


def schur_stable(coefficients: Sequence[int], max_bits: int = DEFAULT_MAX_BITS) -> bool | None:
    """Whether every root of the integer polynomial (coefficients a_0 .. a_n, a_n != 0) lies
    strictly inside the unit circle, exactly; None when an integer of the recursion would
    exceed ``max_bits`` bits.

    >>> schur_stable([1, -6, 8])  # roots 1/2 and 1/4
    True
    >>> schur_stable([1, 0, 1])  # roots +-i, on the circle
    False
    """
    a = [int(x) for x in coefficients]
    if not a or a[-1] == 0:
        raise ValueError("a polynomial with a nonzero leading coefficient")
    previous = None  # the leading coefficient one step back: most steps divide by it exactly
    while len(a) > 1:
        low, lead = a[0], a[-1]
        if abs(low) >= abs(lead):
            return False
        m = len(a) - 1
        b = [lead * a[k + 1] - low * a[m - 1 - k] for k in range(m)]
        if max(abs(x).bit_length() for x in b) > max_bits:
            return None
        divided = False
        if previous is not None and abs(previous) > 1:
            parts = [divmod(x, previous) for x in b]
            if all(r == 0 for _, r in parts):
                b, divided = [q for q, _ in parts], True
        if not divided:
            g = 0
            for x in b:
                g = math.gcd(g, x)
            if g > 1:
                b = [x // g for x in b]
        previous, a = lead, b
    return True


def radius_below(
    coefficients: Sequence[int], j: int, max_bits: int = DEFAULT_MAX_BITS
) -> bool | None:
    """Whether every root of the integer polynomial has modulus below r = 1 - 2^-j, exactly
    (``schur_stable`` of p(r z) 2^(j n), integer coefficients a_k (2^j - 1)^k 2^(j (n - k)));
    None beyond the budget.

    >>> radius_below([1, -6, 8], 1), radius_below([1, -6, 8], 2)  # rho = 1/2
    (False, True)
    """
    if j < 1:
        raise ValueError(f"j = {j}: r = 1 - 2^-j needs j >= 1")
    n = len(coefficients) - 1
    r = (1 << j) - 1
    return schur_stable(
        [int(a) * r**k << (j * (n - k)) for k, a in enumerate(coefficients)], max_bits
    )


_PRIMES = (67108859, 67108837)  # below 2^26: n <= 2^11 products of residues fit in int64


def _cayley_hamilton(F: Dyadic, c: list[int]) -> bool:
    """Whether c (c[0] = 1 leading) annihilates the integer matrix M behind F modulo two
    primes (Horner: M^n + c[1] M^(n-1) + ... + c[n] I = 0): an independent check of the
    characteristic polynomial, in int64 arithmetic."""
    import numpy as np

    n = F.shape[0]
    for prime in _PRIMES:
        M = np.array([[int(x) % prime for x in row] for row in F.ints], dtype=np.int64)
        acc = np.zeros((n, n), dtype=np.int64)
        for coefficient in c:
            acc = (acc @ M) % prime
            acc[np.diag_indices(n)] = (acc[np.diag_indices(n)] + coefficient % prime) % prime
        if np.any(acc):
            return False
    return True
