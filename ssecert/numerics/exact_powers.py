"""Exact powers of float matrices: dyadic rationals and certified spectral-radius bounds.

Every float is a dyadic rational m 2^e, so a float matrix is exactly an
integer matrix times a power of two (``Dyadic``, ``dyadic``).  F = A - L C
is formed exactly from the floats of A, L and C (``exact_error_matrix``),
its powers are computed in integers, and rho(F) <= ||F^m||_inf^(1/m) for any
m (``spectral_radius_bound``): a certified bound on the spectral radius of
the very matrix a report prints, which no eigenvalue solver gives for a
nearly nilpotent F.  ``ssecert.numerics.exact`` re-exports these names.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from functools import cached_property

import numpy as np

__all__ = [
    "Dyadic",
    "dyadic",
    "exact_error_matrix",
    "exact_observability_matrix",
    "ExactMatrix",
    "as_dyadic",
    "shift_by",
    "PowerBound",
    "spectral_radius_bound",
]


@dataclass(frozen=True)
class Dyadic:
    """An exact matrix ``ints * 2**exponent`` (``ints`` of Python integers)."""

    ints: np.ndarray  # object array of int
    exponent: int

    @property
    def shape(self) -> tuple[int, ...]:
        return self.ints.shape

    def bits(self) -> int:
        """Largest bit length of an entry."""
        return max((abs(int(x)).bit_length() for x in self.ints.flat), default=0)

    def __matmul__(self, other: Dyadic) -> Dyadic:
        if self.ints.size == 0 or other.ints.size == 0:
            return Dyadic.zeros((self.shape[0], other.shape[1]))
        return Dyadic(self.ints.dot(other.ints), self.exponent + other.exponent)

    def __add__(self, other: Dyadic) -> Dyadic:
        ia, ib, e = _align(self, other)
        return Dyadic(ia + ib, e)

    def __sub__(self, other: Dyadic) -> Dyadic:
        ia, ib, e = _align(self, other)
        return Dyadic(ia - ib, e)

    def __neg__(self) -> Dyadic:
        return Dyadic(-self.ints, self.exponent)

    @property
    def T(self) -> Dyadic:
        return Dyadic(self.ints.T, self.exponent)

    def __getitem__(self, index: tuple[slice, slice]) -> Dyadic:
        return Dyadic(self.ints[index], self.exponent)

    def times(self, x: float) -> Dyadic:
        """The exact product with the float ``x``."""
        d = dyadic(np.array([[float(x)]]))
        return Dyadic(self.ints * d.ints[0, 0], self.exponent + d.exponent)

    def scaled(self, left: np.ndarray, right: np.ndarray) -> Dyadic:
        """diag(2^left) self diag(2^right), exactly, for integer exponents."""
        left = np.asarray(left, dtype=np.int64)
        right = np.asarray(right, dtype=np.int64)
        shifts = left[:, None] + right[None, :]
        low = int(shifts.min(initial=0))
        out = np.empty(self.shape, dtype=object)
        for index in np.ndindex(*self.shape):
            out[index] = int(self.ints[index]) << int(shifts[index] - low)
        return Dyadic(out, self.exponent + low)

    def to_fractions(self) -> list[list[Fraction]]:
        """The entries as Fractions (rows of a 2-D matrix)."""
        unit = Fraction(2) ** self.exponent
        return [[int(v) * unit for v in row] for row in self.ints]

    def distance_bound(self, M: np.ndarray) -> float:
        """An upper bound on ||self - M||_2 for the float matrix ``M`` (the Frobenius norm of
        the exact difference, rounded up; infinite when M has a non-finite entry)."""
        if not np.all(np.isfinite(np.asarray(M, dtype=float))):
            return math.inf
        diff = self - dyadic(M)
        top = max((abs(int(v)) for v in diff.ints.flat), default=0)
        if top == 0:
            return 0.0
        shift = max(top.bit_length() - 60, 0)  # entries to about 60 bits, rounded up
        squares = sum(((abs(int(v)) >> shift) + 1) ** 2 for v in diff.ints.flat if v)
        try:
            value = math.ldexp(math.sqrt(squares) * (1 + 1e-12), diff.exponent + shift)
        except OverflowError:
            return math.inf
        return max(value, 5e-324)  # never 0 for a nonzero difference

    @staticmethod
    def zeros(shape: tuple[int, ...]) -> Dyadic:
        out = np.empty(shape, dtype=object)
        out.fill(0)
        return Dyadic(out, 0)

    @staticmethod
    def eye(n: int) -> Dyadic:
        out = Dyadic.zeros((n, n))
        for i in range(n):
            out.ints[i, i] = 1
        return out

    @staticmethod
    def block(rows: Sequence[Sequence[Dyadic]]) -> Dyadic:
        """The block matrix of ``rows`` (each a sequence of Dyadic blocks of matching sizes)."""
        low = min(b.exponent for row in rows for b in row)
        lifted = [
            [b.ints * (1 << (b.exponent - low)) if b.exponent > low else b.ints for b in row]
            for row in rows
        ]
        return Dyadic(np.vstack([np.hstack(row) for row in lifted]).astype(object), low)

    def inf_norm_log2(self) -> float:
        """log2 of the exact infinity norm (max absolute row sum); -inf for zero.

        Rounded up by a relative 1e-12, so that 2 ** value bounds the norm
        from above.
        """
        if self.ints.size == 0:
            return -math.inf
        sums = [sum(abs(int(x)) for x in row) for row in self.ints]
        top = max(sums)
        if top == 0:
            return -math.inf
        value = math.log2(top)
        return value + 1e-12 * max(1.0, abs(value)) + self.exponent

    def two_norm_log2_bounds(self) -> tuple[float, float]:
        """log2 of exact bounds on the spectral norm: ||X||_inf / sqrt(n) <= ||X||_2 <=
        sqrt(||X||_1 ||X||_inf) (-inf for zero)."""
        inf = self.inf_norm_log2()
        if inf == -math.inf:
            return -math.inf, -math.inf
        one = Dyadic(self.ints.T, self.exponent).inf_norm_log2()
        n = self.ints.shape[1]
        lower = inf - 1e-12 * max(1.0, abs(inf)) * 2 - 0.5 * math.log2(n)
        return lower, 0.5 * (inf + one)

    def to_float(self) -> np.ndarray:
        """Nearest floats (entries beyond the float range become inf)."""
        out = np.empty(self.ints.shape)
        for index, x in np.ndenumerate(self.ints):
            try:
                out[index] = math.ldexp(float(int(x)), self.exponent)
            except OverflowError:
                out[index] = math.copysign(math.inf, int(x))
        return out


def dyadic(M: np.ndarray) -> Dyadic:
    """The exact value of a finite float matrix as integers times a power of two.

    Examples
    --------
    >>> d = dyadic(np.array([[0.5, 3.0]]))
    >>> d.ints.tolist(), d.exponent
    ([[1, 6]], -1)
    """
    M = np.asarray(M, dtype=np.float64)
    if not np.all(np.isfinite(M)):
        raise ValueError("dyadic: the matrix has non-finite entries")
    mant, expo = np.frexp(M)
    ints = (mant * 2.0**53).astype(np.int64)  # exact: |mant| < 1
    expo = expo.astype(np.int64) - 53
    nonzero = ints != 0
    if not nonzero.any():
        return Dyadic(np.zeros(M.shape, dtype=object), 0)
    # strip common trailing zero bits to keep the integers small
    tz = np.zeros(M.shape, dtype=np.int64)
    vals = np.abs(ints[nonzero])
    tz_nz = np.zeros(vals.shape, dtype=np.int64)
    work = vals.copy()
    while True:
        even = (work & 1) == 0
        if not even.any():
            break
        tz_nz[even] += 1
        work[even] >>= 1
    tz[nonzero] = tz_nz
    ints = np.where(nonzero, ints >> np.where(nonzero, tz, 0), 0)
    expo = expo + tz
    low = int(expo[nonzero].min())
    out = np.empty(M.shape, dtype=object)
    for index in np.ndindex(M.shape):
        v = int(ints[index])
        out[index] = v << int(expo[index] - low) if v else 0
    return Dyadic(out, low)


def _align(a: Dyadic, b: Dyadic) -> tuple[np.ndarray, np.ndarray, int]:
    e = min(a.exponent, b.exponent)
    sa, sb = a.exponent - e, b.exponent - e
    ia = a.ints * (1 << sa) if sa else a.ints
    ib = b.ints * (1 << sb) if sb else b.ints
    return ia, ib, e


def as_dyadic(M: np.ndarray | Dyadic) -> Dyadic:
    """``M`` itself when it is a Dyadic, else the exact value of its floats."""
    return M if isinstance(M, Dyadic) else dyadic(M)


def exact_error_matrix(
    A: np.ndarray | Dyadic, L: np.ndarray | Dyadic, C: np.ndarray | Dyadic
) -> Dyadic:
    """F = A - L C computed exactly from the floats (or exact values) of A, L and C."""
    return as_dyadic(A) - as_dyadic(L) @ as_dyadic(C)


def exact_observability_matrix(
    A: np.ndarray,
    C: np.ndarray,
    tau: int,
    *,
    max_bits: int = 1_000_000,
    max_total_bits: float = 5e7,
) -> Dyadic | None:
    """O_tau = [C; C A; ...; C A^(tau-1)] formed exactly from the floats of A and C, or None
    when an entry would exceed ``max_bits`` bits or all of them ``max_total_bits`` (the
    entries of C A^k grow by A's bits at each power, so O_tau holds about tau^2 / 2 times
    them: a window of 3,000 spent minutes in the products of its exact gain)."""
    Ad, row = dyadic(A), dyadic(C)
    blocks = [row]
    total = float(row.bits() * row.ints.size)
    for _ in range(1, tau):
        if row.bits() + Ad.bits() > max_bits:
            return None
        row = row @ Ad
        total += float(row.bits() * row.ints.size)
        if total > max_total_bits:
            return None
        blocks.append(row)
    return Dyadic.block([[b] for b in blocks])


@dataclass(frozen=True)
class ExactMatrix:
    """The exact value of a matrix that was computed in floating point, formed on demand.

    Attributes
    ----------
    build : callable
        Returns the exact value (a ``Dyadic``), or None when it is beyond its budget.
    bound : float or None
        An a-priori upper bound on the 2-norm of the computed floats minus the exact value;
        None to measure it on the exact value when it is needed.
    source : str
        How the exact value is formed, for messages.
    """

    build: Callable[[], Dyadic | None]
    bound: float | None
    source: str

    @cached_property
    def value(self) -> Dyadic | None:
        """The exact matrix (formed once), or None beyond its budget."""
        return self.build()

    def rounding(self, computed: np.ndarray) -> float:
        """An upper bound on ||computed - exact||_2 (inf when neither is known)."""
        if self.bound is not None:
            return self.bound
        exact = self.value
        return math.inf if exact is None else exact.distance_bound(computed)

    def similar(self, k: np.ndarray, source: str) -> ExactMatrix:
        """The exact S^-1 X S, S = diag(2^k) (a change of state units by powers of two), of
        this matrix X, formed on demand; its rounding is measured on it."""
        parent = self

        def build() -> Dyadic | None:
            value = parent.value
            return None if value is None else value.scaled(-k, k)

        return ExactMatrix(build, None, source)

    @classmethod
    def error_matrix(
        cls,
        A: np.ndarray,
        L: np.ndarray | Dyadic,
        C: np.ndarray | Dyadic,
        *,
        bound: float | None = None,
        source: str = "F = A - L C formed exactly from the floats of A, L and C",
    ) -> ExactMatrix:
        """F = A - L C from the floats of A and the floats (or exact values) of L and C; the
        a-priori bound on fl(A - L C) is Higham's when L and C are given as floats."""
        if bound is None and not isinstance(C, Dyadic) and not isinstance(L, Dyadic):
            from ..tolerances import product_rounding

            bound = product_rounding(L, C, A)
        return cls(lambda: exact_error_matrix(A, L, C), bound, source)


def shift_by(F: Dyadic, value: float) -> Dyadic:
    """F - value I, exactly, for any finite float ``value`` (a dyadic rational)."""
    n = F.shape[0]
    ia, ib, e = _align(F, dyadic(np.diag(np.full(n, float(value)))))
    return Dyadic(ia - ib, e)


@dataclass(frozen=True)
class PowerBound:
    """Certified facts about the powers of an exact matrix F.

    Attributes
    ----------
    log2_norms : tuple of float
        log2 ||F^k||_inf for k = 1, ..., len (upper bounds, exact data).
    log2_two_norms : tuple of (float, float)
        log2 of a lower and an upper bound on ||F^k||_2, k = 1, ..., len.
    nilpotent_index : int or None
        Smallest k with F^k exactly zero, if found.
    radius_bound : float
        Certified upper bound on the spectral radius: min over the powers m
        computed of ||F^m||_inf^(1/m).
    radius_power : int
        The power m that gave the bound.
    powers : tuple of int
        Every power whose exact norm was computed.
    complete : bool
        False when the bit budget stopped the computation early.
    radius_lower : float
        Certified lower bound on the spectral radius: max over the powers m
        of (|trace F^m| / n)^(1/m), since |trace F^m| <= n rho^m.
    lower_power : int
        The power that gave the lower bound (0 if none).
    trace_reaches_n : int
        A power m with |trace F^m| >= n exactly (then rho >= 1), or 0.
    radius_gap : float
        Certified lower bound on 1 - rho(F), from an exact power m with ||F^m||_inf < 1
        decided in integers: 1 - ||F^m||^(1/m) >= (1 - ||F^m||) / m.  Positive exactly
        when such a power was found, even when ``radius_bound`` rounds to 1 (F = 1 - 1e-17).
    gap_power : int
        The power that gave the gap (0 if none).
    radius_excess : float
        Certified lower bound on rho(F) - 1, from an exact power m with |trace F^m| = T > n
        decided in integers: rho >= (T / n)^(1/m) >= 1 + (T - n) / (m T).  Positive exactly
        when such a power was found, even when ``radius_lower`` rounds to 1 (F = 1 + 1e-17).
    trace_excess : float
        T - n at that power, from the exact trace (rounded down; 0 if none).
    excess_power : int
        The power that gave the excess (0 if none).
    """

    log2_norms: tuple[float, ...]
    log2_two_norms: tuple[tuple[float, float], ...]
    nilpotent_index: int | None
    radius_bound: float
    radius_power: int
    powers: tuple[int, ...]
    complete: bool
    radius_lower: float = 0.0
    lower_power: int = 0
    trace_reaches_n: int = 0
    radius_gap: float = 0.0
    gap_power: int = 0
    radius_excess: float = 0.0
    trace_excess: float = 0.0
    excess_power: int = 0


def spectral_radius_bound(
    F: Dyadic,
    *,
    consecutive: int | None = None,
    squarings: int = 6,
    target: float | None = 1.0,
    max_work: float = 3e8,
) -> PowerBound:
    """Exact norms of F, F^2, ..., F^consecutive, then of repeated squares.

    rho(F) <= ||F^m||^(1/m) for every m and every induced norm, so each
    exact power gives a certified bound; squaring F^m tightens it (the bound
    tends to rho(F)).  Squaring stops once the bound is below ``target``.

    Parameters
    ----------
    F : Dyadic, shape (n, n)
    consecutive : int, optional
        Powers 1..consecutive computed one by one (default n).
    squarings : int, default 6
        Further squarings of the last power.
    target : float or None, default 1
        Stop squaring when the bound is below this value.
    max_work : float, default 3e8
        Budget in word operations (n^3 times the words of the entries to the
        power 1.6, Karatsuba); beyond it the result is marked incomplete.

    Returns
    -------
    PowerBound
    """
    n = F.shape[0]
    k_max = n if consecutive is None else max(1, int(consecutive))
    trail = _PowerTrail(n, max_work)
    P, nil = _consecutive_powers(F, k_max, trail)
    if nil is None and trail.complete:
        _square_powers(P, squarings, target, trail)
    return PowerBound(
        tuple(trail.log2_norms),
        tuple(trail.log2_two),
        nil,
        trail.best,
        trail.best_m,
        tuple(trail.powers),
        trail.complete,
        trail.lower,
        trail.lower_m,
        trail.reaches,
        trail.gap,
        trail.gap_m,
        trail.excess,
        trail.trace_excess,
        trail.excess_m,
    )


class _PowerTrail:
    """What the exact powers of F computed so far prove, and the work they cost."""

    def __init__(self, n: int, max_work: float) -> None:
        self.n = n
        self.max_work = max_work
        self.work = 0.0
        self.complete = True
        self.powers: list[int] = []
        self.log2_norms: list[float] = []  # of the consecutive powers only
        self.log2_two: list[tuple[float, float]] = []
        self.best, self.best_m = math.inf, 0
        self.lower, self.lower_m = 0.0, 0
        self.reaches = 0
        self.gap, self.gap_m = 0.0, 0
        self.excess, self.trace_excess, self.excess_m = 0.0, 0.0, 0

    def affordable(self, a: Dyadic, b: Dyadic) -> bool:
        """Whether a @ b fits in the work budget (then it is charged); else incomplete."""
        words = (a.bits() + b.bits()) / 64.0 + 1.0
        cost = float(self.n) ** 3 * words**1.6
        if self.work + cost > self.max_work:
            self.complete = False
            return False
        self.work += cost
        return True

    def record(self, m: int, P: Dyadic) -> float:
        """Take P = F^m into the bounds; returns log2 ||F^m||_inf (-inf when zero)."""
        value = P.inf_norm_log2()
        self.powers.append(m)
        bound = 0.0 if value == -math.inf else _pow2(value / m)
        if bound < self.best:
            self.best, self.best_m = bound, m
        gap = _exact_gap(P, m)
        if gap > self.gap:
            self.gap, self.gap_m = gap, m
        trace = abs(sum(int(P.ints[i, i]) for i in range(self.n)))
        if trace and not self.reaches and _trace_reaches_n(trace, P.exponent, self.n):
            self.reaches = m
        if trace:
            low = _trace_radius_lower(trace, P.exponent, self.n, m)
            if low > self.lower:
                self.lower, self.lower_m = low, m
            excess = _trace_excess(trace, P.exponent, self.n, m)
            if excess is not None and excess[0] > self.excess:
                self.excess, self.trace_excess, self.excess_m = *excess, m
        return value


def _exact_gap(P: Dyadic, m: int) -> float:
    """(1 - ||P||_inf) / m rounded down when ||P||_inf < 1 exactly (integers), else 0: with
    P = F^m a lower bound on 1 - rho(F), since 1 - x^(1/m) >= (1 - x) / m for 0 <= x <= 1."""
    top = max((sum(abs(int(x)) for x in row) for row in P.ints), default=0)
    e = P.exponent
    if e >= 0:
        return 1.0 if top == 0 else 0.0
    one = 1 << -e
    if top >= one:
        return 0.0
    # (a quotient of integers is rounded correctly, as the Fraction's float was, without its
    # gcd: quadratic in the bits of powers whose entries lie 2^600 apart)
    return (one - top) / (one * m) * (1 - 1e-15)


def _pow2(x: float) -> float:
    """2^x, inf beyond the float range (2.0 ** 1024 raises OverflowError)."""
    return math.inf if x >= 1024 else 2.0 ** max(x, -1e4)


def _trace_reaches_n(trace: int, exponent: int, n: int) -> bool:
    """|trace F^m| >= n, decided in integers: trace * 2^exponent >= n."""
    e = exponent
    return (trace << e if e >= 0 else trace) >= (n if e >= 0 else n << -e)


def _trace_excess(trace: int, exponent: int, n: int, m: int) -> tuple[float, float] | None:
    """With T = |trace F^m| = trace 2^exponent > n (decided in integers): the lower bound
    (T - n) / (m T) on rho(F) - 1 and T - n, both rounded down; None when T <= n.

    rho^m >= T / n = x^m with x >= 1, and x^m - 1 <= m x^(m-1) (x - 1) <= m (T / n) (x - 1)."""
    # T - n = excess / unit and (T - n) / (m T) = excess / (m trace), in integers (quotients of
    # integers are rounded correctly, as a Fraction's float is, without its gcd)
    unit = 1 << -exponent if exponent < 0 else 1
    whole = trace << exponent if exponent > 0 else trace
    excess = whole - n * unit
    if excess <= 0:
        return None
    down = 1 - 1e-15
    try:
        beyond = excess / unit * down
    except OverflowError:
        beyond = math.inf
    return excess / (m * whole) * down, beyond


def _trace_radius_lower(trace: int, exponent: int, n: int, m: int) -> float:
    """(|trace F^m| / n)^(1/m), rounded down: a lower bound on the spectral radius."""
    # log2 of an int is within a few ulps
    log_t = math.log2(trace) - 1e-12 * max(1.0, abs(math.log2(trace))) + exponent
    return _pow2((log_t - math.log2(n)) / m)


def _consecutive_powers(F: Dyadic, k_max: int, trail: _PowerTrail) -> tuple[Dyadic, int | None]:
    """F, F^2, ..., F^k_max into ``trail``: the last power computed and the nilpotency index."""
    P = F
    for k in range(1, k_max + 1):
        if k > 1:
            if not trail.affordable(P, F):
                break
            P = P @ F
        value = trail.record(k, P)
        trail.log2_norms.append(value)
        trail.log2_two.append(P.two_norm_log2_bounds())
        if value == -math.inf:
            return P, k
    return P, None


def _square_powers(P: Dyadic, squarings: int, target: float | None, trail: _PowerTrail) -> None:
    """Square the last power P into ``trail`` until the bounds decide ``target`` or stop."""
    m = trail.powers[-1] if trail.powers else 1
    for _ in range(squarings):
        if target is not None and (
            trail.best < target
            or trail.lower > target
            or (target == 1.0 and (trail.gap > 0 or trail.excess > 0))
        ):
            break
        if not trail.affordable(P, P):
            break
        P = P @ P
        m *= 2
        if trail.record(m, P) == -math.inf:
            break
