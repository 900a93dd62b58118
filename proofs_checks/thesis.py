"""Claims of 001, Cilia's MSc thesis: Lyapunov and ISS background (Ch. 2), observers and the
Lasso algorithms (Ch. 4), the elastic-net observer and its theorems (Ch. 5), the simulations and
the localization algorithm (Ch. 6).

The thesis writes x+ = A x, y = C x + a with n states; Chapters 3, 4 and 6 count the sensors with
q, Chapter 5 with p.  The D-SSO (4.4.3, Algorithm 1) writes x_hat+ = A x_hat - L (y_hat - y), the
elastic-net observer (5.2, Algorithm 2) x_hat+ = A x_hat + L1 (y_hat - y): L1 = -L.  Exact checks
use integers and Python fractions (the helpers below), so that no verdict rests on rounding.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from fractions import Fraction
from typing import Any

import numpy as np
import sympy as sp

from ._core import Finding, claim

__all__: list[str] = []

Mat = list[list[Any]]  # exact entries: integers, or fractions after a division


# --------------------------------------------------------------------------- exact helpers
def _mul(A: Mat, B: Mat) -> Mat:
    return [[sum(a * b for a, b in zip(row, col)) for col in zip(*B)] for row in A]


def _eye(n: int) -> Mat:
    return [[int(i == j) for j in range(n)] for i in range(n)]


def _sub(A: Mat, B: Mat) -> Mat:
    return [[a - b for a, b in zip(ra, rb)] for ra, rb in zip(A, B)]


def _pow(A: Mat, k: int) -> Mat:
    out = _eye(len(A))
    for _ in range(k):
        out = _mul(out, A)
    return out


def _rank(M: Mat) -> int:
    """Exact rank by fraction-free elimination."""
    rows, rank = [list(r) for r in M], 0
    for c in range(len(rows[0])):
        piv = next((i for i in range(rank, len(rows)) if rows[i][c] != 0), None)
        if piv is None:
            continue
        rows[rank], rows[piv] = rows[piv], rows[rank]
        p = rows[rank]
        for i in range(rank + 1, len(rows)):
            if rows[i][c] != 0:
                rows[i] = [p[c] * v - rows[i][c] * w for v, w in zip(rows[i], p)]
        rank += 1
    return rank


def _solve(M: Mat, B: Mat) -> Mat:
    """M^(-1) B exactly, by Gauss-Jordan (StopIteration if M is singular)."""
    n = len(M)
    W = [[Fraction(v) for v in r + b] for r, b in zip(M, B)]
    for c in range(n):
        piv = next(i for i in range(c, n) if W[i][c] != 0)
        W[c], W[piv] = W[piv], W[c]
        W[c] = [v / W[c][c] for v in W[c]]
        for i in range(n):
            if i != c and W[i][c] != 0:
                W[i] = [v - W[i][c] * w for v, w in zip(W[i], W[c])]
    return [r[n:] for r in W]


def _pivots(M: Mat) -> list[Fraction]:
    """Pivots of elimination without row exchanges: a symmetric M is > 0 iff all are > 0."""
    W, out = [[Fraction(v) for v in r] for r in M], []
    for c in range(len(W)):
        out.append(W[c][c])
        if W[c][c] == 0:
            break
        for i in range(c + 1, len(W)):
            W[i] = [v - W[i][c] / W[c][c] * w for v, w in zip(W[i], W[c])]
    return out


def _obs(A: Mat, C: Mat, T: int) -> Mat:
    """The observability matrix [C; C A; ...; C A^(T-1)]."""
    rows, CA = list(C), C
    for _ in range(T - 1):
        CA = _mul(CA, A)
        rows += CA
    return rows


def _soft(v: Fraction, t: Fraction) -> Fraction:
    return v - t if v > t else v + t if v < -t else Fraction(0)


def _soft_np(v: np.ndarray, t: np.ndarray | float) -> np.ndarray:
    return np.sign(v) * np.maximum(np.abs(v) - t, 0.0)


def _escape(s: Sequence[Fraction], rho: Fraction, beta: Fraction) -> int:
    """First k with |s_k| > beta/(rho - 1), past which |s+| >= rho |s| - beta grows."""
    return next(k for k, v in enumerate(s) if abs(v) > beta / (rho - 1))


# --------------------------------------------------------------------------- Chapter 2
@claim(
    "thesis.young",
    where="001 Prop. 2 (2.2)",
    statement="For a, b in R^n and gamma > 0: 2 a^T b <= gamma a^T a + (1/gamma) b^T b.",
    recorded="holds",
)
def young() -> Finding:
    # gamma a^T a + b^T b / gamma - 2 a^T b = || sqrt(gamma) a - b / sqrt(gamma) ||^2, a sum
    # of squares: an identity sympy verifies for symbolic vectors of any fixed length
    g = sp.symbols("gamma", positive=True)
    checked = []
    for n in (1, 2, 3, 5):
        a = sp.Matrix(sp.symbols(f"a1:{n + 1}", real=True))
        b = sp.Matrix(sp.symbols(f"b1:{n + 1}", real=True))
        gap = g * (a.T * a)[0] + (b.T * b)[0] / g - 2 * (a.T * b)[0]
        square = sum((sp.sqrt(g) * a[i] - b[i] / sp.sqrt(g)) ** 2 for i in range(n))
        if sp.simplify(sp.expand(gap - square)) != 0:
            raise AssertionError(f"the sum-of-squares identity failed for n = {n}")
        checked.append(n)
    return Finding(
        "holds",
        "The gap gamma a^T a + b^T b / gamma - 2 a^T b equals ||sqrt(gamma) a - b / "
        "sqrt(gamma)||^2, a sum of squares, so it is never negative; equality holds exactly "
        "when b = gamma a. The thesis's proof (Cauchy-Schwarz, then the arithmetic-geometric "
        "mean inequality) is correct.",
        {
            "method": "symbolic",
            "identity": "gamma a'a + b'b/gamma - 2 a'b = ||sqrt(gamma) a - b/sqrt(gamma)||^2",
            "verified_by": "sympy expansion, symbolic vectors of length n",
            "n": checked,
        },
    )


def _stable_2x2(A: Mat) -> bool:
    """Lyapunov stability of x+ = A x, A 2 x 2, from its exact eigenvalue structure."""
    (a, b), (c, d) = A
    t, det = a + d, a * d - b * c
    if t * t < 4 * det:  # a complex pair of modulus sqrt(det)
        return det <= 1
    if t * t > 4 * det:  # distinct real roots of z^2 - t z + det, both in [-1, 1]
        return 1 - t + det >= 0 and 1 + t + det >= 0 and abs(t) <= 2
    # a double root t/2: on the unit circle stable only if A = (t/2) I (semisimple)
    return abs(t) < 2 or (abs(t) == 2 and b == c == 0 and a == d)


def _lyapunov_exact(rng: np.random.Generator, count: int) -> float:
    """Solve A'PA - P = -Q exactly for random Schur A = U T U^(-1) (T triangular, eigenvalues
    in {-9/10, -3/10, 1/2, 9/10}, often repeated: Jordan blocks) and Q = B B' + I; check P > 0.
    Returns the smallest pivot of P."""
    smallest = None
    for _ in range(count):
        n = int(rng.integers(2, 5))
        T: Mat = np.triu(rng.integers(-5, 6, (n, n)), 1).tolist()
        for i in range(n):
            T[i][i] = Fraction(int(rng.choice([-9, -3, 5, 9])), 10)
        U = [[int(i == j) + int(rng.integers(-2, 3)) * (j > i) for j in range(n)] for i in range(n)]
        A = _mul(_mul(U, T), _solve(U, _eye(n)))
        B = rng.integers(-2, 3, (n, n))
        Q = (B @ B.T + np.eye(n, dtype=int)).tolist()
        # row-major vec(A' P A) = (A' kron A') vec(P)
        K = [
            [int(r == c) - A[c // n][r // n] * A[c % n][r % n] for c in range(n * n)]
            for r in range(n * n)
        ]
        p = _solve(K, [[v] for row in Q for v in row])
        P = [[p[i * n + j][0] for j in range(n)] for i in range(n)]
        At = [list(r) for r in zip(*A)]
        piv = _pivots(P)
        if any(_sub(_mul(_mul(At, P), A), P)[i][j] != -Q[i][j] for i in range(n) for j in range(n)):
            raise AssertionError("the Kronecker solution does not solve (2.7)")
        if [list(r) for r in zip(*P)] != P or min(piv) <= 0:
            raise AssertionError(f"no symmetric P > 0 for the Schur matrix {A}")
        smallest = min(piv) if smallest is None else min(smallest, *piv)
    return float(smallest or 0)


@claim(
    "thesis.thm3",
    where="001 Thm 3 and the Remark after (2.7)",
    statement="For x+ = A x: x = 0 is stable iff all eigenvalues of A satisfy |lambda_i| < 1 and "
    "the algebraic and geometric multiplicities of the eigenvalues with absolute value 1 "
    "coincide; it is globally asymptotically stable iff all |lambda_i| < 1 (A Schur). Remark: "
    "for every Schur A the discrete Lyapunov equation A'PA - P = -Q (2.7) has a unique solution "
    "P > 0 for each Q > 0.",
    recorded="fails",
)
def thm3() -> Finding:
    # exhaustive: A = N/2 for every integer N in {-2..2}^(2x2); ||A^K||_inf = ||N^K||_inf / 2^K
    counts, largest_j = {"matrices": 0, "schur": 0, "stable": 0, "stable_not_schur": 0}, 0
    for e in itertools.product(range(-2, 3), repeat=4):
        A = [[Fraction(e[0], 2), Fraction(e[1], 2)], [Fraction(e[2], 2), Fraction(e[3], 2)]]
        t, det = A[0][0] + A[1][1], A[0][0] * A[1][1] - A[0][1] * A[1][0]
        schur, stable = abs(det) < 1 and abs(t) < 1 + det, _stable_2x2(A)  # Jury; exact
        N, norms = [list(e[:2]), list(e[2:])], []
        for j in range(10):  # N^(2^j), j = 0..9
            norms.append(Fraction(max(abs(r[0]) + abs(r[1]) for r in N), 2 ** (2**j)))
            N = _mul(N, N)
        gas = next((j for j, v in enumerate(norms) if v < 1), None)  # A^k -> 0 certified
        if (
            schur != (gas is not None)
            or (max(norms) <= 10) != stable
            or (norms[-1] > 100) == stable
        ):
            raise AssertionError(f"eigenvalue tests and exact powers disagree on A = {A}")
        largest_j = max(largest_j, gas or 0)
        for key, flag in zip(counts, (True, schur, stable, stable and not schur)):
            counts[key] += flag
    # the Remark, symbolically for 2 x 2: det(I - A' kron A') = (1 - det)^2 ((1 + det)^2 - tr^2)
    As = sp.Matrix(2, 2, sp.symbols("a0:4", real=True))
    kron_det = (sp.eye(4) - sp.kronecker_product(As.T, As.T)).det(method="berkowitz")
    if sp.expand(kron_det - (1 - As.det()) ** 2 * ((1 + As.det()) ** 2 - As.trace() ** 2)) != 0:
        raise AssertionError("the Kronecker determinant identity failed")
    smallest_pivot = _lyapunov_exact(np.random.default_rng(2), 30)
    return Finding(
        "fails",
        "As printed, Theorem 3's first sentence asks |lambda_i| < 1 of all eigenvalues, then "
        "speaks of those with |lambda| = 1, which that excludes: it reads 'stable iff Schur', a "
        "well-formed statement that is false (A = 1 is stable without being Schur), so it fails. "
        "It is evidently a misprint of < for <=, and the corrected theorem holds: with |lambda_i| "
        f"<= 1 the stability test agrees with exact powers on all {counts['matrices']} matrices "
        f"A = N/2, N in {{-2..2}}^(2x2), {counts['stable_not_schur']} of them stable but not "
        "Schur. The rest holds: GAS iff Schur (Jury's test against an exact certificate "
        "||A^(2^j)||_inf < 1, same set); the Remark, as det(I - A' kron A') = prod(1 - lambda_i "
        "lambda_j) != 0 for Schur A (symbolic for 2 x 2) and P = sum_k A'^k Q A^k >= Q > 0 (30 "
        "random rational, non-normal Schur A with repeated eigenvalues, solved exactly).",
        {
            "method": "exhaustive+symbolic+randomised",
            "exhaustive": {
                **counts,
                "set": "A = N/2, N integer 2 x 2, entries in -2..2",
                "schur_test": "Jury: |det A| < 1 and |tr A| < 1 + det A (exact)",
                "stability_test": "|lambda| <= 1, a double root on the unit circle only if "
                "A = lambda I (exact); against ||A^(2^j)||_inf <= 10 for j <= 9 (stable) or "
                "||A^512||_inf > 100 (unstable)",
                "gas_certificate_largest_j": largest_j,
            },
            "symbolic": "det(I4 - kron(A', A')) = (1 - det A)^2 ((1 + det A)^2 - (tr A)^2)",
            "lyapunov_exact": "30 instances (seed 2), see _lyapunov_exact: P symmetric, "
            f"positive pivots (smallest {smallest_pivot:.3g})",
            "not_schur": "A = 1: (2.7) reads 0 = -Q, no solution; A = 2: P = -Q/3 < 0",
        },
        counterexample={
            "A": [[1]],
            "shows": "x(k) = A^k x0 = x0, so ||x(k)|| < epsilon whenever ||x0|| < delta = "
            "epsilon: x = 0 is stable (Definition 3), yet the eigenvalue 1 does not satisfy "
            "|lambda| < 1, which Theorem 3's first sentence requires of all eigenvalues.",
        },
    )


# --------------------------------------------------------------------------- Chapter 4
def _deadbeat_indices(rng: np.random.Generator, n: int, q: int, count: int) -> list[int]:
    """Nilpotency indices of A - L C, L = A^nu O_nu^(-1) E (E: last q columns of I, nu = n/q),
    on random integer plants with O_nu invertible; checks that O_(nu-1) is rank deficient."""
    nu, found = n // q, list[int]()
    E = [[int(i - q * (nu - 1) == j) for j in range(q)] for i in range(q * nu)]
    while len(found) < count:
        A, C = rng.integers(-3, 4, (n, n)).tolist(), rng.integers(-3, 4, (q, n)).tolist()
        if _rank(_obs(A, C, nu)) < n or (nu > 1 and _rank(_obs(A, C, nu - 1)) == n):
            continue
        F = _sub(A, _mul(_mul(_mul(_pow(A, nu), _solve(_obs(A, C, nu), _eye(n))), E), C))
        found.append(next(k for k in range(n + 1) if not any(map(any, _pow(F, k)))))
    return found


@claim(
    "thesis.deadbeat_n_steps",
    where="001 Sec. 4.2, 'Dead-beat observer'",
    statement="Choosing L so that all eigenvalues of A - L C are zero gives the deadbeat "
    "observer, 'which converges in exactly n steps'.",
    recorded="conditional",
)
def deadbeat_n_steps() -> Finding:
    rng = np.random.default_rng(5)
    siso = {n: _deadbeat_indices(rng, n, 1, 8) for n in (2, 3, 4)}
    mimo = {(n, q): _deadbeat_indices(rng, n, q, 6) for n, q in ((4, 2), (6, 3), (6, 2))}
    if any(i != n for n, idx in siso.items() for i in idx) or any(
        i != n // q for (n, q), idx in mimo.items() for i in idx
    ):
        raise AssertionError(f"unexpected nilpotency indices: {siso}, {mimo}")
    F_fast, F_slow = _sub([[1, 1], [0, 1]], [[1, 1], [0, 1]]), _sub([[1, 1], [0, 1]], _eye(2))
    if any(map(any, F_fast)) or any(map(any, _mul(F_slow, F_slow))) or not any(map(any, F_slow)):
        raise AssertionError("the counterexample's gains are not what they should be")
    return Finding(
        "conditional",
        "e(k) = (A - L C)^k e(0) and A - L C is nilpotent, so e(n) = 0 for every e(0) "
        "(Cayley-Hamilton): 'at most n steps' always holds. The worst case takes the nilpotency "
        "index of A - L C, between the observability index (F^k = 0 forces rank O_k = n) and n. "
        "With one sensor it is n, as (A - L C, C) is observable, so C (A - L C)^(n-1) != 0 (24 "
        "random plants, exact). With several sensors it depends on L and can be smaller: on 18 "
        "random plants with q = 2, 3, L = A^nu O_nu^(-1) [0; I] needs only nu = n/q steps; in "
        "Sec. 6.1's setting (q = 30 sensors, n = 15, rank C = n) L = A C^+ needs one.",
        {
            "method": "symbolic+randomised",
            "argument": "F nilpotent => F^n = 0; F^k = 0 => rank O_k = n; one sensor and "
            "(F, C) observable => C F^(n-1) != 0",
            "indices_one_sensor_by_n": siso,
            "indices_several_sensors": {f"n={n}, q={q}": idx for (n, q), idx in mimo.items()},
            "construction": "L = A^nu O_nu^(-1) E, E the last q columns of I_(q nu); random "
            "integer A, C in -3..3 with O_nu invertible and O_(nu-1) rank deficient (seed 5); "
            "exact fractions",
        },
        counterexample={
            "A": [[1, 1], [0, 1]],
            "C": [[1, 0], [0, 1]],
            "L": [[1, 1], [0, 1]],
            "shows": "A - L C = 0 (both eigenvalues zero, a deadbeat gain, n = 2), so "
            "e(1) = (A - L C) e(0) = 0 for every e(0): convergence in 1 step, not n = 2. The "
            "deadbeat gain L = I instead gives A - L C = [[0, 1], [0, 0]], which needs 2 steps.",
        },
        condition="one sensor (q = 1), or more generally a gain making A - L C a single "
        "nilpotent Jordan block; in general the error vanishes in at most n steps, exactly "
        "in the nilpotency index of A - L C (between the observability index and n).",
    )


def _prop3_case(A: Mat, C: Mat, tally: dict[str, int]) -> None:
    """Tally (A, C) by observability and eigenvalue 1; raise if O'_(n+q) disagrees."""
    n, q = len(A), len(C)
    observable, eig1 = _rank(_obs(A, C, n)) == n, _rank(_sub(A, _eye(n))) < n
    O = _obs(A, C, n + q)
    augmented = _rank([row + [int(i % q == j) for j in range(q)] for i, row in enumerate(O)])
    key = ("observable" if observable else "unobservable") + (", eig 1" if eig1 else ", no eig 1")
    tally[key] = tally.get(key, 0) + 1
    if (augmented == n + q) != (observable and not eig1):
        raise AssertionError(f"Prop. 3 or its converse fails on A = {A}, C = {C}")


@claim(
    "thesis.prop3",
    where="001 Prop. 3 (4.15)-(4.25)",
    statement="Let the attack-free system (A, C) be observable. If A has an eigenvalue equal to "
    "1, then the CPS under constant attacks (4.15), with state (x, a) and observability "
    "matrix O'_T (4.20), is not observable.",
    recorded="holds",
)
def prop3() -> Finding:
    exhaustive: dict[str, int] = {}
    for n, q in ((1, 1), (1, 2), (2, 1), (2, 2)):
        for a in itertools.product((-1, 0, 1), repeat=n * n):
            for c in itertools.product((-1, 0, 1), repeat=q * n):
                A = [list(a[i * n : (i + 1) * n]) for i in range(n)]
                _prop3_case(A, [list(c[i * n : (i + 1) * n]) for i in range(q)], exhaustive)
    rng, random3 = np.random.default_rng(7), dict[str, int]()
    for i in range(240):  # n = 3, q = 1..3, half with A - I made singular
        B = rng.integers(-2, 3, (3, 3))
        if i % 2:
            B[2] = B[0] - B[1]
        _prop3_case(
            (B + np.eye(3, dtype=int)).tolist(),
            rng.integers(-2, 3, (1 + i % 3, 3)).tolist(),
            random3,
        )
    # symbolic, n = 2, q = 1: the row differences (4.23) give det O'_3 = det(A - I) det O_2
    A2, c2 = sp.Matrix(2, 2, sp.symbols("a0:4")), sp.Matrix(1, 2, sp.symbols("c0:2"))
    O3 = sp.Matrix([[*(c2 * A2**k), 1] for k in range(3)]).det(method="berkowitz")
    if sp.expand(O3 - (A2 - sp.eye(2)).det() * sp.Matrix.vstack(c2, c2 * A2).det()) != 0:
        raise AssertionError("det O'_3 = det(A - I) det O_2 failed")
    return Finding(
        "holds",
        "If A v = v, v != 0, then O'_T (v; -C v) = 0 for every T: the constant attack a = -C v "
        "hides the mode, as stated. The converse holds too: for observable (A, C) without the "
        "eigenvalue 1, the row differences (4.23) turn O'_(n+q) into [[C, I], [O_(n+q-1) (A - "
        "I), 0]], of rank q + n. So the augmented system is observable iff (A, C) is and 1 is "
        "not an eigenvalue of A; exact ranks agree on every case tried. The proof is right, "
        "except its aside that T = n + q is 'minimal in the nominal case' (n suffices there).",
        {
            "method": "exhaustive+symbolic+randomised",
            "exhaustive": "(n, q) in (1,1), (1,2), (2,1), (2,2), every A, C with entries in "
            "{-1, 0, 1}: exact ranks of O_n, A - I and O'_(n+q)",
            "exhaustive_counts": exhaustive,
            "random_n3": "240 integer plants, q = 1..3, entries -2..2, half with A - I singular "
            "(seed 7)",
            "random_n3_counts": random3,
            "symbolic": "det O'_3 = det(A - I) det O_2, symbolic A (2 x 2) and C (1 x 2)",
            "disagreements": 0,
        },
    )


def _dsso_minus_ijam(
    rng: np.random.Generator, n: int, q: int, steps: int
) -> tuple[bool, float, float]:
    """A = I, L = C^+, both from (0, 0): (rank C = n, rho(I - C^+ C), largest relative difference
    of the D-SSO and IJAM iterates)."""
    C = rng.standard_normal((q, n))
    if n > q or rng.random() < 0.3:
        C[:, -1] = C[:, 0]  # rank deficient
    Cp, a0 = np.linalg.pinv(C), np.zeros(q)
    a0[rng.choice(q, max(1, q // 4), replace=False)] = rng.uniform(2, 5)
    y = C @ rng.standard_normal(n) + a0
    nu, lam = rng.uniform(0.1, 1.0), rng.uniform(0.05, 0.5)
    xd, ad, xi, ai, worst = np.zeros(n), np.zeros(q), np.zeros(n), np.zeros(q), 0.0
    for _ in range(steps):
        rd, ri = C @ xd + ad - y, C @ xi + ai - y
        xd, ad = xd - Cp @ rd, _soft_np(ad - nu * rd, nu * lam)  # D-SSO with A = I, L = C^+
        xi, ai = Cp @ (y - ai), _soft_np(ai - nu * ri, nu * lam)  # IJAM
        worst = max(worst, float(np.abs(np.r_[xd - xi, ad - ai]).max() / np.abs(y).max()))
    full = bool(np.linalg.matrix_rank(C) == n)
    return full, float(np.abs(np.linalg.eigvals(np.eye(n) - Cp @ C)).max()), worst


@claim(
    "thesis.dsso_is_ijam",
    where="001 Sec. 4.4.3 (with 4.4.2 and 4.4.4)",
    statement="If the number of sensors q is at least n and the gain L of the D-SSO is C^+ "
    "(Moore-Penrose), the D-SSO coincides with IJAM (Sec. 4.3.2).",
    recorded="conditional",
)
def dsso_is_ijam() -> Finding:
    # symbolic: the x-updates differ by (A - C^+ C) x_hat (P stands for C^+); the a-updates are
    # the same formula S_(nu lambda)(a_hat - nu (C x_hat + a_hat - y))
    A, C, P = (
        sp.Matrix(r, c, sp.symbols(f"{s}0:{r * c}"))
        for s, r, c in (("A", 2, 2), ("C", 3, 2), ("P", 2, 3))
    )
    x, h, y = (sp.Matrix(sp.symbols(f"{s}0:{k}")) for s, k in (("x", 2), ("h", 3), ("y", 3)))
    if sp.expand(A * x - P * (C * x + h - y) - P * (y - h) - (A - P * C) * x) != sp.zeros(2, 1):
        raise AssertionError("the update difference is not (A - C^+ C) x_hat")
    rng, shapes = np.random.default_rng(11), [(2, 4), (3, 3), (3, 8), (4, 2), (5, 3)]
    runs = [_dsso_minus_ijam(rng, *shapes[i % 5], 200) for i in range(30)]
    full = [r for r in runs if r[0]]
    deficient = [r for r in runs if not r[0]]
    deficient_q_ge_n = sum(
        not r[0] and shapes[i % 5][1] >= shapes[i % 5][0] for i, r in enumerate(runs)
    )
    worst_full = max(r[2] for r in full)
    if not (worst_full < 1e-9 and all(abs(r[1] - 1) < 1e-9 for r in deficient)):
        raise AssertionError("the D-SSO with L = C^+ and IJAM did not compare as expected")
    # the counterexample (A = I, q = n = 2, rank C = 1), exactly: C^+ = [[1/2, 1/2], [0, 0]]
    Cx: Mat = [[1, 0], [1, 0]]
    Cp: Mat = [[Fraction(1, 2), Fraction(1, 2)], [0, 0]]
    x0: Mat = [[0], [1]]
    y0: Mat = [[1], [1]]
    dsso = _sub(x0, _mul(Cp, _sub(_mul(Cx, x0), y0)))  # a_hat = 0
    ijam = _mul(Cp, y0)
    if _sub(_eye(2), _mul(Cp, Cx)) != [[0, 0], [0, 1]] or [dsso, ijam] != [[[1], [1]], [[1], [0]]]:
        raise AssertionError("the counterexample's steps are not (1, 1) and (1, 0)")
    # remark, outside the comparison's setting: A != I with L = C^+ deadbeat; L = A C^+ matches
    xh0, yr = [[0], [1]], [[1], [1]]
    if [r[0] for r in _sub(_mul([[1, 1], [0, 1]], xh0), _sub(xh0, yr))] != [2, 1]:
        raise AssertionError("the remark's D-SSO step is not (2, 1)")
    worst_repair = 0.0  # L = A C^+ (rank C = n): A - L C = 0 and x_hat+ = A C^+ (y - a_hat)
    for _ in range(20):
        Ad, Cd = rng.standard_normal((3, 3)), rng.standard_normal((6, 3))
        xh, ah, yy = rng.standard_normal(3), rng.standard_normal(6), rng.standard_normal(6)
        L = Ad @ np.linalg.pinv(Cd)
        step = Ad @ xh - L @ (Cd @ xh + ah - yy) - L @ (yy - ah)
        worst_repair = max(worst_repair, float(np.abs(step).max() + np.abs(Ad - L @ Cd).max()))
    return Finding(
        "conditional",
        "Sec. 4.4.3 defines the D-SSO for any A (eig(A - L C) = 0), but its comparison with "
        "IJAM, which solves the static problem, is made, like 4.4.2's with ISTA ('when A is the "
        "identity') and 4.4.4's 'same considerations', for A = I: the statement is read there. "
        "With L = C^+ the D-SSO's state update differs from IJAM's C^+ (y - a_hat) by exactly "
        "(A - C^+ C) x_hat (symbolic); the attack updates are the same formula. With A = I, "
        "A - L C = I - C^+ C is the projection onto ker C, with eigenvalue 1 unless rank C = n: "
        "q >= n does not make C^+ a deadbeat gain, rank C = n does (and implies q >= n). Then "
        "C^+ C = I and, from the same start, the two coincide (the runs with rank C = n agree "
        f"to {worst_full:.1e}). Without it the observer with L = C^+ is no D-SSO (every "
        "rank-deficient run had I - C^+ C with eigenvalue 1), and from an x_hat(0) off the row "
        "space of C its iterates are not IJAM's (counterexample, q = n = 2). So the statement "
        "holds in its setting only with rank C = n in place of q >= n: conditional. Remark, "
        "outside that setting: for A != I, L = C^+ can be deadbeat (A = [[1, 1], [0, 1]], "
        "C = I, A - L C nilpotent) and the D-SSO's step from x_hat = (0, 1), y = (1, 1) is "
        "(2, 1), not IJAM's (1, 1); the gain that makes the D-SSO an IJAM step is then "
        "L = A C^+ (A - L C = 0, x_hat+ = A C^+ (y - a_hat); 20 random plants).",
        {
            "method": "symbolic+randomised",
            "symbolic": "(A x - P (C x + h - y)) - P (y - h) = (A - P C) x, P = C^+ symbolic",
            "randomised": f"A = I, 30 runs of 200 steps from (0, 0), (n, q) in {shapes}, C "
            "rank deficient in 30% of the runs and whenever q < n, nu in (0.1, 1), seed 11",
            "runs_with_rank_C_n": len(full),
            "worst_relative_difference_rank_C_n": worst_full,
            "runs_rank_deficient": len(deficient),
            "runs_rank_deficient_with_q_ge_n": deficient_q_ge_n,
            "rank_deficient_rho_of_I_minus_CplusC": sorted({round(r[1], 12) for r in deficient}),
            "rank_deficient_note": "from x_hat(0) = 0 the iterates stay in the row space of C "
            "and agree with IJAM's (worst relative difference "
            f"{max((r[2] for r in deficient), default=0.0):.1e}), but L = C^+ is then not "
            "a deadbeat gain",
            "remark_A_not_I": {
                "A": [[1, 1], [0, 1]],
                "C": [[1, 0], [0, 1]],
                "L": [[1, 0], [0, 1]],
                "x_hat": [0, 1],
                "y": [1, 1],
                "shows": "A - L C = [[0, 1], [0, 0]] (deadbeat); D-SSO step (2, 1), IJAM's (1, 1)",
            },
            "L_equals_A_Cplus_worst_residual": worst_repair,
        },
        counterexample={
            "A": [[1, 0], [0, 1]],
            "C": [[1, 0], [1, 0]],
            "L": [[0.5, 0.5], [0, 0]],
            "x_hat": [0, 1],
            "a_hat": [0, 0],
            "y": [1, 1],
            "shows": "q = n = 2 and L = C^+, but rank C = 1: A - L C = I - C^+ C = [[0, 0], [0, 1]] "
            "has eigenvalue 1, so L is not a D-SSO (deadbeat) gain. From x_hat = (0, 1) (the "
            "D-SSO starts anywhere) its step x_hat+ = x_hat - L (C x_hat + a_hat - y) = (1, 1), "
            "IJAM's x+ = C^+ (y - a_hat) = (1, 0), and the difference (0, 1) never decays.",
        },
        condition="A = I (the static problem IJAM solves, the setting of the comparison) and "
        "rank C = n (hence q >= n), which makes L = C^+ deadbeat, with the same start (IJAM's "
        "x_hat(0) = 0, a_hat(0) = 0), nu and lambda; q >= n alone does not suffice. For A != I "
        "the matching gain is L = A C^+.",
    )


def _kkt(C: np.ndarray, y: np.ndarray, x: np.ndarray, a: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """P-Lasso optimality residual per run: ||C' r||_inf and the subgradient condition on a."""
    r = np.einsum("bij,bj->bi", C, x) + a - y
    l = lam[:, None]
    sub = np.where(a != 0, np.abs(r + l * np.sign(a)), np.maximum(np.abs(r) - l, 0.0))
    return np.maximum(np.abs(np.einsum("bij,bi->bj", C, r)).max(1), sub.max(1))


def _ista_ijam(
    C: np.ndarray, y: np.ndarray, lam: np.ndarray, nu_i: np.ndarray, nu_j: np.ndarray, steps: int
) -> np.ndarray:
    """KKT residuals, shape (4, runs): ISTA after steps/2 and steps, then IJAM likewise."""
    B, q, n = C.shape
    Cp, out = np.linalg.pinv(C), []
    x, a, xj, aj = np.zeros((B, n)), np.zeros((B, q)), np.zeros((B, n)), np.zeros((B, q))
    for k in range(1, steps + 1):
        r, rj = np.einsum("bij,bj->bi", C, x) + a - y, np.einsum("bij,bj->bi", C, xj) + aj - y
        x = x - nu_i[:, None] * np.einsum("bij,bi->bj", C, r)  # ISTA
        a = _soft_np(a - nu_i[:, None] * r, (nu_i * lam)[:, None])
        xj = np.einsum("bji,bi->bj", Cp, y - aj)  # IJAM: both lines use the old iterates
        aj = _soft_np(aj - nu_j[:, None] * rj, (nu_j * lam)[:, None])
        if k in (steps // 2, steps):
            out += [_kkt(C, y, x, a, lam), _kkt(C, y, xj, aj, lam)]
    return np.array(out)[[0, 2, 1, 3]]


@claim(
    "thesis.ista_ijam_converge",
    where="001 Sec. 4.3.2 (IJAM, ISTA and the Summary)",
    statement="IJAM (x(0) = 0, a(0) = 0, inertial parameter nu in (0, 1]) and ISTA (step size "
    "nu > 0) solve the P-Lasso min 1/2 ||C x + a - y||^2 + lambda ||a||_1; 'both IJAM and "
    "ISTA are provably convergent under standard assumptions'.",
    recorded="conditional",
)
def ista_ijam_converge() -> Finding:
    rng, kkt = np.random.default_rng(13), []
    for n, q in ((2, 8), (3, 10), (4, 14), (1, 2)):  # C = (1, 1)': minimisers often not unique
        C = rng.standard_normal((16, q, n)) if n > 1 else np.ones((16, q, n))
        a0 = np.zeros((16, q))
        for b in range(16):
            a0[b, rng.choice(q, 2, replace=False)] = rng.uniform(2, 5, 2) * rng.choice([-1, 1], 2)
        y = np.einsum("bij,bj->bi", C, rng.standard_normal((16, n))) + a0
        nu_i = rng.uniform(0.5, 0.95, 16) * 2 / (np.linalg.norm(C, 2, axis=(1, 2)) ** 2 + 1)
        nu_j = rng.uniform(0.2, 0.99, 16)
        nu_j[:4] = 1.0 if n > 1 else nu_j[:4]  # nu = 1 only where the minimiser is unique
        lam = rng.uniform(0.05, 0.3, 16)
        kkt.append(_ista_ijam(C, y, lam, nu_i, nu_j, 4000))
    non_unique = int((np.abs(y[:, 0] - y[:, 1]) > 2 * lam).sum())  # C = (1, 1)': a segment
    K = np.concatenate(kkt, axis=1)  # rows: ISTA at 2000, 4000; IJAM at 2000, 4000
    slow = [K[1] > 1e-8, K[3] > 1e-8]
    ratio = [
        float((K[2 * m + 1][sl] / K[2 * m][sl]).max()) if sl.any() else 0.0
        for m, sl in enumerate(slow)
    ]
    # the counterexample, exactly: C = (1, 1)', y = (2, -1), lambda = 1/2, nu = 1
    y_, half, cyc, s = [Fraction(2), Fraction(-1)], Fraction(1, 2), [], []
    x, a = Fraction(0), [Fraction(0)] * 2
    for _ in range(5):  # IJAM
        r = [x + a[i] - y_[i] for i in (0, 1)]
        x, a = (y_[0] - a[0] + y_[1] - a[1]) / 2, [_soft(a[i] - r[i], half) for i in (0, 1)]
        cyc.append((x, *a))
    if not (cyc[0] == cyc[2] == cyc[4] and cyc[1] == cyc[3] and cyc[0] != cyc[1]):
        raise AssertionError(f"IJAM's iterates are not a 2-cycle: {cyc}")
    x, a = Fraction(0), [Fraction(0)] * 2
    for _ in range(12):  # ISTA; u = (2, 1, 1) = G'(1, 1), s = u'z: s+ = -2 s + 3 - u'(0, clip)
        r = [x + a[i] - y_[i] for i in (0, 1)]
        x, a = x - r[0] - r[1], [_soft(a[i] - r[i], half) for i in (0, 1)]
        s.append(2 * x + a[0] + a[1])
    k = _escape(s, Fraction(2), Fraction(4))  # |u'(0, clip)| <= 2 nu lambda = 1
    return Finding(
        "conditional",
        "The text allows nu = 1 for IJAM explicitly ('nu in (0, 1]'), and there IJAM need not "
        "converge: at nu = 1 its even and odd iterates decouple (a(k+2) = S_lambda((I - C C^+) y "
        "+ C C^+ a(k))) and, when the minimiser is not unique, settle on different minimisers, so "
        "(x(k), a(k)) cycles between two points that are not minimisers (counterexample: C = "
        "(1, 1)', y = (2, -1), lambda = 1/2). For nu in (0, 1), and for nu = 1 where the "
        "minimiser is unique (each of the two decoupled chains is then an exact alternating "
        "minimisation), IJAM converged on every instance. ISTA's part rests on a hedged "
        "sentence ('provably convergent under standard assumptions'): under the standard step "
        "0 < nu < 2/||G||^2 = 2/(||C||^2 + 1), G = (C I), it is the proximal gradient method on "
        "z = (x, a) and converges; the text's 'nu > 0' is not that assumption, and beyond it "
        "ISTA can diverge (the same data with nu = 1 > 2/3). Randomised (64 instances, 4000 "
        f"iterations): the KKT residual is below 1e-8 on {64 - int(slow[1].sum())} for IJAM (nu "
        f"= 1 included where the minimiser is unique) and {64 - int(slow[0].sum())} for ISTA, "
        f"and still decreasing on the others (worst {K[[1, 3]].max():.1e}, at most "
        f"{max(ratio):.2g} times its value at 2000 iterations): slow, not divergent. IJAM's "
        "convergence for nu < 1 rests on these instances (16 of them with C = (1, 1)', "
        f"{non_unique} of which have a segment of minimisers).",
        {
            "method": "randomised+certificate",
            "randomised": "16 instances per (n, q) in (2, 8), (3, 10), (4, 14) (C Gaussian) and "
            "(1, 2) (C = (1, 1)'), 2 attacked sensors with |a_i| in [2, 5], lambda in "
            "[0.05, 0.3], ISTA nu in (0.5, 0.95) 2/||G||^2, IJAM nu in (0.2, 0.99) or 1; seed "
            "13. KKT residual: max of ||C'r||_inf and the subgradient condition (r_i = -lambda "
            "sign(a_i) on the support, |r_i| <= lambda off it)",
            "worst_kkt_ista_ijam": [float(K[1].max()), float(K[3].max())],
            "runs_above_1e-8_ista_ijam": [int(slow[0].sum()), int(slow[1].sum())],
            "instances_with_non_unique_minimiser": non_unique,
            "worst_ratio_kkt_4000_over_2000_ista_ijam": ratio,
            "ijam_cycle": [[float(v) for v in c] for c in cyc[:2]],
            "ista_escape": {"step": k + 1, "s": float(s[k]), "bound": 4},
        },
        counterexample={
            "C": [[1], [1]],
            "y": [2, -1],
            "lambda": 0.5,
            "nu": 1,
            "shows": "IJAM with nu = 1 (allowed: nu in (0, 1]) from x(0) = 0, a(0) = 0 "
            "alternates forever between (x, a) = (1/2, (3/2, -1/2)) and (0, (1, -1)); the "
            "minimisers are x in [-1/2, 3/2], a = (3/2 - x, -1/2 - x), and neither point is one "
            "(C'r = 1 and -1). Remark on the hedged ISTA sentence: with the same nu = 1 > "
            "2/(||C||^2 + 1) = 2/3, outside the standard step, s = 2x + a_1 + a_2 satisfies "
            f"|s(k+1)| >= 2|s(k)| - 4, and |s({k + 1})| = {float(abs(s[k])):g} > 4, so ISTA "
            "diverges.",
        },
        condition="IJAM: 0 < nu < 1, or nu = 1 when the P-Lasso minimiser is unique; ISTA: the "
        "standard step 0 < nu < 2/(||C||_2^2 + 1).",
    )


# --------------------------------------------------------------------------- Chapter 6
def _alg3(
    G: np.ndarray, y: np.ndarray, t: float, thr: np.ndarray, shrink: np.ndarray, N: int
) -> np.ndarray:
    """Algorithm 3: z <- shrink * S_thr(z - t G'(G z - y)), t = epsilon L2, N times from 0."""
    z = np.zeros(G.shape[1])
    for _ in range(N):
        z = shrink * _soft_np(z - t * G.T @ (G @ z - y), thr)
        if np.abs(z).max() > 1e12:  # diverged: stop before overflow
            break
    return z


@claim(
    "thesis.algorithm3",
    where="001 Sec. 6.3, Algorithm 3 and the extended elastic net before it",
    statement="Algorithm 3 (G = [D I_q], z(0) = 0, gamma = z - epsilon L2 G'(G z - y), "
    "x = q_x S_lambda_x(gamma_x), a = q_a S_lambda_a(gamma_a), N iterations; inputs "
    "lambda_x, lambda_a > 0, q_x, q_a in (0, 1), L2, epsilon > 0) solves min ||D x + a - y||^2 "
    "+ lambda_x ||x||_1 + lambda_a ||a||_1 + mu_x/2 ||x||^2 + mu_a/2 ||a||^2.",
    recorded="conditional",
)
def algorithm3() -> Finding:
    rng = np.random.default_rng(17)
    worst_kkt, worst_naive, diverged, largest_kappa = 0.0, np.inf, 0, 0.0
    for i in range(40):
        qs, ns = int(rng.integers(3, 7)), int(rng.integers(3, 9))
        G, y = np.hstack([rng.standard_normal((qs, ns)), np.eye(qs)]), 3 * rng.standard_normal(qs)
        Lg = np.linalg.norm(G, 2) ** 2
        shrink = np.repeat(rng.uniform(0.5, 0.95, 2), [ns, qs])
        thr = np.repeat(rng.uniform(0.01, 0.2, 2), [ns, qs])
        if i % 4 == 3:  # beyond the bound, q_x = q_a: the linear part's radius q (t L - 1) > 1
            shrink[:] = shrink[0]
            t = rng.uniform(1.1, 2.0) * (1 + 1 / shrink[0]) / Lg
            diverged += bool(np.abs(_alg3(G, y, t, thr, shrink, 3000)).max() > 1e12)
            continue
        t = rng.uniform(0.2, 0.95) * (1 + 1 / shrink.max()) / Lg
        kappa = shrink.max() * max(1.0, t * Lg - 1)  # a Lipschitz constant of the iteration
        largest_kappa = max(largest_kappa, kappa)
        z = _alg3(G, y, t, thr, shrink, int(np.log(1e-16) / np.log(kappa)) + 50)
        g = 2 * G.T @ (G @ z - y)  # gradient of the printed data term ||G z - y||^2
        l1, mu = 2 * thr / t, 2 * (1 / shrink - 1) / t  # the weights of the fixed point
        on, scale = z != 0, np.abs(g).max()
        res = np.where(on, np.abs(g + l1 * np.sign(z) + mu * z), np.maximum(np.abs(g) - l1, 0))
        worst_kkt = max(worst_kkt, float(res.max() / scale))
        naive = np.where(on, np.abs(g + thr * np.sign(z) + mu * z), 0.0)  # lambda read as is
        worst_naive = min(worst_naive, float(naive.max() / scale))
    # exact counterexample: D = 1, y = 1, lambda = 1/10, q = 1/2, L2 = 1, epsilon = 2
    zc, s = [Fraction(0)] * 2, []
    for _ in range(12):
        r = zc[0] + zc[1] - 1
        zc = [Fraction(1, 2) * _soft(v - 2 * r, Fraction(1, 10)) for v in zc]
        s.append(zc[0] + zc[1])
    k = _escape(s, Fraction(3, 2), Fraction(21, 10))  # s+ = -3/2 s + 2 - d, |d| <= 1/10
    return Finding(
        "conditional",
        "Algorithm 3 is the proximal gradient method with step t = epsilon L2 on 1/2 ||G z - "
        "y||^2 plus an elastic-net penalty: its fixed points minimise the printed objective "
        "with lambda^obj = 2 lambda/t and mu^obj = 2 (1/q - 1)/t (KKT on 30 random instances, "
        f"worst relative residual {worst_kkt:.1e}). As the printed data term has no 1/2, the "
        "algorithm's lambda_x, lambda_a are not the objective's (read as equal they leave a "
        f"KKT residual of at least {worst_naive:.2f}), and mu is never given. The iteration is "
        "a contraction when t ||G||^2 < 1 + 1/max(q_x, q_a), so it converges as N grows (the "
        "N = 1000 of Sec. 6.3 is not judged here); with 'epsilon > 0' as printed it diverges: "
        f"{diverged} of 10 random instances beyond the bound did, and the counterexample "
        "provably does.",
        {
            "method": "randomised+certificate",
            "randomised": "40 instances, seed 17: q in 3..6 sensors, n in 3..8 cells, D "
            "Gaussian, y ~ N(0, 9), q_x, q_a in (0.5, 0.95), thresholds in (0.01, 0.2); 30 with "
            "t ||G||^2 in (0.2, 0.95) (1 + 1/max q), run until the contraction bound is 1e-16; "
            "10 with q_x = q_a and t ||G||^2 in (1.1, 2) (1 + 1/q), 3000 iterations",
            "worst_kkt_residual": worst_kkt,
            "largest_contraction_factor": largest_kappa,
            "smallest_residual_reading_lambda_as_is": worst_naive,
            "diverged_beyond_bound": diverged,
            "escape": {"step": k + 1, "s": float(s[k]), "bound": 4.2},
        },
        counterexample={
            "D": [[1]],
            "y": [1],
            "lambda_x": 0.1,
            "lambda_a": 0.1,
            "q_x": 0.5,
            "q_a": 0.5,
            "L2": 1,
            "epsilon": 2,
            "shows": "G = [1 1], ||G||^2 = 2, epsilon L2 ||G||^2 = 4 > 1 + 1/q = 3. With "
            "s = x + a, s(k+1) = -3/2 s(k) + 2 - d(k) with |d(k)| <= 1/10, so once |s| > 4.2 it "
            f"grows geometrically; from z(0) = 0, |s({k + 1})| = {float(abs(s[k])):g}: "
            "Algorithm 3 diverges.",
        },
        condition="epsilon L2 ||G||_2^2 < 1 + 1/max(q_x, q_a) (the iterates then converge as N "
        "grows; with q_x = q_a they diverge beyond it), and the objective's weights read as "
        "lambda^obj = 2 lambda/(epsilon L2), mu^obj = 2 (1/q - 1)/(epsilon L2).",
    )


def _fixed_point(
    alpha: int, q: Fraction, step: Fraction, lam: Fraction, signs: Sequence[int]
) -> list[Any]:
    """Exact fixed point (e, a_hat) of x_hat+ = x_hat - mean(y~), a_hat+ = q S_lam(a_hat -
    step y~), y~ = e + a_hat - a (A = 1, C = (1, 1, 1, 1)', a = (alpha, 0, 0, 0)) with the
    given signs of a_hat; verified by one exact step."""
    a = [alpha, 0, 0, 0]
    M: Mat = [[4, 1, 1, 1, 1]]
    b: list[Any] = [alpha]  # sum y~ = 0; a_i = q (a_i - step y~_i - lam s_i) or 0
    for i, sg in enumerate(signs):
        M.append(
            [q * step * (sg != 0)] + [(1 - q + q * step if sg else 1) * (j == i) for j in range(4)]
        )
        b.append((q * step * a[i] - q * lam * sg) * (sg != 0))
    sol = [v[0] for v in _solve(M, [[v] for v in b])]
    yt = [sol[0] + sol[i + 1] - a[i] for i in range(4)]
    if sum(yt) != 0 or [q * _soft(sol[i + 1] - step * yt[i], lam) for i in range(4)] != sol[1:]:
        raise AssertionError(f"the signs {signs} give no fixed point")
    return sol


def _simulate(alpha: float, q: float, step: float, lam: float, steps: int) -> np.ndarray:
    """The same observer from x_hat(0) = 0, a_hat(0) = 0 on x = 1: final (e, a_hat)."""
    a, e, ah = np.array([alpha, 0.0, 0.0, 0.0]), -1.0, np.zeros(4)
    for _ in range(steps):
        yt = e + ah - a
        e, ah = e - yt.mean(), q * _soft_np(ah - step * yt, lam)
    return np.r_[e, ah]


def _elastic_grid(alpha: int, q: float, steps: int) -> dict[str, Any]:
    """Algorithm 2 on the counterexample for lambda = 0.1, 0.2, ..., 20 and eps L2 = c I,
    c = 0.25, 0.5, ..., 4.  The fixed point (e, a_hat_1, a_hat_2 = a_hat_3 = a_hat_4) is the
    unique minimiser of a strongly convex elastic net, solved in closed form on each sign
    pattern; the observer, simulated from x_hat(0) = 0, a_hat(0) = 0, converges or not."""
    lam, c = (v.ravel() for v in np.meshgrid(np.arange(1, 201) / 10, np.arange(1, 17) / 4))
    mu, lp, G = (1 / q - 1) / c, lam / c, lam.size
    fixed = np.full((G, 3), np.nan)
    for s1, s2 in itertools.product((1, 0, -1), repeat=2):
        # sum y~ = 0; e + (1 + mu) a_i = a_i^true - lambda' s_i on the support, a_i = 0 off it
        M = np.zeros((G, 3, 3))
        M[:, 0] = [4, 1, 3]
        M[:, 1] = np.stack([np.full(G, s1 != 0), np.where(s1, 1 + mu, 1), np.zeros(G)], 1)
        M[:, 2] = np.stack([np.full(G, s2 != 0), np.zeros(G), np.where(s2, 1 + mu, 1)], 1)
        rhs = np.stack([np.full(G, alpha), (alpha - lp * s1) * (s1 != 0), -lp * s2], 1)
        e, a1, b = np.linalg.solve(M, rhs[..., None])[..., 0].T
        ok = (a1 * s1 > 1e-9) if s1 else (np.abs(e - alpha) <= lp + 1e-9)
        ok &= (b * s2 > 1e-9) if s2 else (np.abs(e) <= lp + 1e-9)
        fixed[ok] = np.stack([e, a1, b], 1)[ok]
    if np.isnan(fixed).any():
        raise AssertionError("a grid point has no fixed point on any sign pattern")
    e, ah = np.full(G, -1.0), np.zeros((G, 4))  # x = 1, x_hat(0) = 0
    attack = np.array([alpha, 0.0, 0.0, 0.0])
    with np.errstate(over="ignore", invalid="ignore"):
        for _ in range(steps):
            yt = e[:, None] + ah - attack
            e, ah = e - yt.mean(axis=1), q * _soft_np(ah - c[:, None] * yt, lam[:, None])
        gap = np.abs(np.c_[e, ah] - fixed[:, [0, 1, 2, 2, 2]]).max(axis=1)
    reached, diverged = gap < 1e-9, ~(np.abs(e) < 1e6)
    best = int(np.argmin(np.where(reached, np.abs(fixed[:, 0]), np.inf)))
    least = int(np.argmin(np.abs(fixed[:, 0])))
    return {
        "grid_points": G,
        "reached": int(reached.sum()),
        "diverged": int(diverged.sum()),
        "largest_eps_L2_reached": float(c[reached].max()),
        "best_reached": (float(lam[best]), float(c[best]), float(fixed[best, 0])),
        "best_fixed_point_anywhere": (float(lam[least]), float(c[least]), float(fixed[least, 0])),
        "best_signs": tuple(int(np.sign(round(v, 9))) for v in fixed[best, [1, 2, 2, 2]]),
    }


@claim(
    "thesis.elastic_vs_dsso",
    where="001 Sec. 6.2 (6.2.4, 6.2.7), Algorithms 1 and 2",
    statement="Under constant sparse attacks the elastic-net observer (Algorithm 2, q in (0, 1)) "
    "accurately reconstructs the state, its estimation error converging to values close to "
    "zero, and consistently identifies the attack support, comparing well with the D-SSO.",
    recorded="fails",
)
def elastic_vs_dsso() -> Finding:
    lam, q, eps, nu = Fraction(1, 10), Fraction(9, 10), Fraction(1, 2), Fraction(7, 10)
    rows, z100 = [], _fixed_point(100, q, eps, lam, (1, -1, -1, -1))
    for alpha in (10, 100, 1000):
        z = _fixed_point(alpha, q, eps, lam, (1, -1, -1, -1))
        gap = float(np.abs(_simulate(alpha, 0.9, 0.5, 0.1, 3000) - np.array(z, dtype=float)).max())
        if z[0] != (alpha - 2 * lam * q / (1 - q)) / 4 or gap > 1e-9:
            raise AssertionError(f"the elastic-net fixed point is not as computed: {z}, {gap}")
        rows.append(
            {"alpha": alpha, "e": float(z[0]), "a_hat": [float(v) for v in z[1:]], "sim_gap": gap}
        )
    d = _fixed_point(100, Fraction(1), nu, lam, (1, 0, 0, 0))
    gap_d = float(np.abs(_simulate(100.0, 1.0, 0.7, 0.1, 3000) - np.array(d, dtype=float)).max())
    if d != [lam / (3 * nu), 100 - 4 * lam / (3 * nu), 0, 0, 0] or gap_d > 1e-9:
        raise AssertionError(f"the D-SSO fixed point is not as computed: {d}, {gap_d}")
    # tuned as in Sec. 6.2 (a grid over lambda and L2): the best steady state still has e > 4
    grid = _elastic_grid(100, 0.9, 1500)
    (lam_b, c_b, e_b), e_l = grid["best_reached"], grid["best_fixed_point_anywhere"][2]
    lam_f, c_f = Fraction(round(10 * lam_b), 10), Fraction(round(4 * c_b), 4)
    exact_b = _fixed_point(100, q, c_f, lam_f, grid["best_signs"])
    mu_b = (1 / q - 1) / c_f  # the right-support fixed point, e = (mu a + l)/(3 + 4 mu)
    if exact_b[0] != (100 * mu_b + lam_f / c_f) / (3 + 4 * mu_b):
        raise AssertionError("the tuned fixed point is not the closed form")
    done = grid["reached"] + grid["diverged"] == grid["grid_points"]
    if not (abs(float(exact_b[0]) - e_b) < 1e-9 and e_b > 4 and e_l > 1 and done):
        raise AssertionError(f"tuning removed the elastic-net bias: {grid}")
    return Finding(
        "fails",
        "For q < 1, q S_lambda shrinks every nonzero entry, so a_hat cannot converge to a "
        "constant attack a != 0, and the bias passes into the state. On the counterexample (A = "
        "1, marginally stable as in Sec. 6.2; one of 4 sensors attacked by alpha; one deadbeat "
        "gain for both observers) Algorithm 2 converges to e = (alpha - 2 lambda q/(1 - q))/4, "
        "the least-squares error alpha/4 less a constant, flagging all four sensors, for alpha "
        "= 10, 100, 1000 (exact fixed points, reached by simulation); the D-SSO (Algorithm 1) "
        "converges to e = lambda/(3 nu) = 1/21 with the right support. Algorithm 2's fixed "
        "points satisfy the optimality conditions of the elastic net 1/2 ||C x + a - y||^2 + "
        "(lambda/epsilon) ||a||_1 + (1/q - 1)/(2 epsilon) ||a||^2, whose ridge term spreads a "
        "large attack over all sensors as least squares does: q < 1, which Chapter 5's proof "
        "needs, costs accuracy under persistent attacks. The statement reports the thesis's own "
        "simulations, whose plants are not given, and Sec. 6.2 tuned lambda and L2 by a grid "
        "search; tuning does not save it here: over lambda = 0.1..20 and eps L2 = 0.25..4 "
        f"({grid['grid_points']} points), the observer from 0 reaches its fixed point only for "
        f"eps L2 <= {grid['largest_eps_L2_reached']:g} (at the other points it diverges), and "
        f"the best steady-state error there is e = {exact_b[0]} = {e_b:.4f} (lambda = "
        f"{lam_b:g}, eps L2 = {c_b:g}, support right), still 4.5 times the state x = 1; no "
        f"fixed point on the grid, reached or not, has e below {e_l:.3f}. With the right "
        "support the fixed point is e = (mu' alpha + lambda')/(3 + 4 mu') >= mu' alpha / (2 + 4 "
        "mu'), lambda' = lambda/(eps L2), mu' = (1 - q)/(q eps L2): the bias goes like (1 - q)/q "
        "and needs a large eps L2, which destabilises the observer.",
        {
            "method": "certificate+randomised",
            "fixed_points": "solved exactly for the signs of a_hat and checked by one exact "
            "step of each observer; 3000-step simulations from x_hat(0) = 0, a_hat(0) = 0, "
            "x = 1 reach them (sim_gap)",
            "elastic_net": rows,
            "dsso_alpha_100": {
                "e": float(d[0]),
                "a_hat": [float(v) for v in d[1:]],
                "sim_gap": gap_d,
            },
            "tuned_grid": {
                "lambda": "0.1, 0.2, ..., 20",
                "eps_L2": "0.25, 0.5, ..., 4 (L2 = I, or eps L2 = c I)",
                "alpha": 100,
                "q": 0.9,
                "fixed_points": "closed form on each sign pattern of (a_hat_1, a_hat_2 = a_hat_3 "
                "= a_hat_4): the unique minimiser of the strongly convex elastic net of the explanation",
                "simulation": "1500 steps from x_hat(0) = 0, a_hat(0) = 0, x = 1; reached = "
                "within 1e-9 of the fixed point, diverged = |x_hat - x| > 1e6",
                **{k: v for k, v in grid.items() if k != "best_signs"},
                "best_reached_exact_e": str(exact_b[0]),
            },
        },
        counterexample={
            "A": [[1]],
            "C": [[1], [1], [1], [1]],
            "L1": [[-0.25, -0.25, -0.25, -0.25]],
            "L2": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]],
            "epsilon": 0.5,
            "lambda": 0.1,
            "q": 0.9,
            "nu": 0.7,
            "x0": [1],
            "a": [100, 0, 0, 0],
            "shows": "A + L1 C = 0 (deadbeat). Algorithm 2 (x_hat+ = A x_hat + L1 (y_hat - y), "
            "a_hat+ = q S_lambda(a_hat - epsilon L2 (y_hat - y))) from 0 converges to x_hat - x "
            f"= {z100[0]} = {float(z100[0]):g} (least squares: 25) with a_hat = ({z100[1]}, "
            f"{z100[2]}, {z100[2]}, {z100[2]}), nonzero on all four sensors. Algorithm 1 "
            "(D-SSO: x_hat+ = A x_hat - L (y_hat - y), L = -L1, a_hat+ = S_lambda(a_hat - nu "
            "(y_hat - y))) converges to x_hat - x = 1/21, a_hat = (100 - 4/21, 0, 0, 0). Tuned "
            f"over lambda in [0.1, 20] and eps L2 in [0.25, 4] ({grid['grid_points']} grid "
            f"points), Algorithm 2's best steady-state error is {e_b:.4f} (lambda = {lam_b:g}, "
            f"eps L2 = {c_b:g}); it converges only for eps L2 <= "
            f"{grid['largest_eps_L2_reached']:g}, and no fixed point on the grid has an error "
            f"below {e_l:.3f}.",
        },
    )


# Chapter 5's claims live in their own module; importing it registers them after these
from . import _thesis_ch5  # noqa: E402, F401
