"""Exact arithmetic on the floating-point data a user gives.

Every float is a dyadic rational m 2^e, so a float matrix is exactly an
integer matrix times a power of two.  Two kinds of exact decision are built
on that:

* **powers of a float matrix** (``spectral_radius_bound``, in
  ``ssecert.numerics.exact_powers`` and re-exported here): F = A - L C formed
  exactly from the floats of A, L and C, its powers computed in integers,
  and rho(F) <= ||F^m||_inf^(1/m) for any m: a certified bound on the
  spectral radius of the very matrix a report prints, which no eigenvalue
  solver gives for a nearly nilpotent F;
* **observability of the exact data** (``exact_observability``): the
  Krylov rank of (A, C) modulo a prime bounds the rank over the rationals
  from below, so full rank modulo a prime proves observability; an exact
  rational kernel vector z with C A^k z = 0 for k < n, re-checked in
  integers, proves the opposite.  A decision that floating point makes but
  the exact data contradicts hinged on digits below the data's precision.

Both are affordable for the plant sizes of this field (tens of states);
callers pass budgets and get ``None`` or ``Observability.UNKNOWN`` beyond them.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import exact_messages
from .exact_powers import (
    Dyadic,
    PowerBound,
    dyadic,
    exact_error_matrix,
    shift_by,
    spectral_radius_bound,
)
from .outcomes import ExactCode

__all__ = [
    "Dyadic",
    "dyadic",
    "exact_error_matrix",
    "shift_by",
    "PowerBound",
    "spectral_radius_bound",
    "Observability",
    "ExactObservability",
    "exact_observability",
    "pow2_row_scaling",
    "pow2_scale",
    "ExactPlant",
    "exact_stacked_rank",
]

# primes just below 2^26: products of two residues stay below 2^52, so a dot
# product of up to 2^11 terms fits in int64 without overflow
_PRIMES = (67108859, 67108837, 67108819)
_MAX_MOD_N = 2048


# ---------------------------------------------------------------------------
# exact observability


def pow2_scale(x: float) -> float:
    """The power of two nearest to 1 / x (exact rescaling), 1 for x = 0 or non-finite.

    For a subnormal x that power (up to 2^1075) is not a double; the largest
    one, 2^1023, is returned: still exact, and x times it is normal.
    """
    if not np.isfinite(x) or x <= 0:
        return 1.0
    return math.ldexp(1.0, min(-math.frexp(x)[1] + 1, 1023))


# quantities whose largest magnitude is within this factor of 1 keep their units
UNITS_SPREAD = 2.0**4


def pow2_units(top: float, spread: float = UNITS_SPREAD) -> float:
    """The unit (a power of two) for quantities whose largest magnitude is ``top``: 1 where
    ``top`` is within ``spread`` of 1 (or zero, or not finite), else ``pow2_scale(top)``,
    which brings it into [1, 2).  One rule for every "units far from 1" decision."""
    if not np.isfinite(top) or top == 0.0 or 1.0 / spread <= top < spread:
        return 1.0
    return pow2_scale(top)


def pow2_row_scaling(M: np.ndarray) -> np.ndarray:
    """Powers of two d_i with d_i ||M_i|| in [1, 2) (1 for zero rows): exact row units.

    Scaling a sensor's row by a power of two changes no rounding, so
    decisions made on the scaled rows are exactly those of any other
    power-of-two choice of units, and within a factor 2 of any unit at all.
    """
    M = np.asarray(M, dtype=float)
    with np.errstate(over="ignore"):
        norms = np.max(np.abs(M), axis=1) if M.size else np.zeros(M.shape[0])
    usable = np.isfinite(norms) & (norms > 0)
    _, exponents = np.frexp(np.where(usable, norms, 1.0))
    return np.where(usable, np.ldexp(1.0, np.minimum(1 - exponents, 1023)), 1.0)


class Observability(enum.StrEnum):
    """An observability decision: its value is the word written in evidence and JSON."""

    OBSERVABLE = "observable"
    UNOBSERVABLE = "unobservable"
    UNKNOWN = "unknown"


@dataclass(frozen=True)
class ExactObservability:
    """The observability of the exact data (A, C).

    Attributes
    ----------
    state : Observability
        ``OBSERVABLE`` (Krylov rank n modulo a prime: a proof),
        ``UNOBSERVABLE`` (an exact kernel vector, re-checked in integers)
        or ``UNKNOWN`` (beyond the budget, or rank deficient modulo the
        primes without an exact kernel vector).
    rank_mod_p : int or None
        Krylov rank modulo the prime (a lower bound on the exact rank).
    z : ndarray or None
        A unit-norm float rounding of the exact unobservable direction.
    z_exact : list of int or None
        The exact integer direction.
    prime : int or None
    code : ExactCode
        Why the decision is what it is (``DECIDED`` for a plain proof).
    facts : mapping
        The numbers the words of ``code`` need; not written to JSON.
    """

    state: Observability
    rank_mod_p: int | None = None
    z: np.ndarray | None = None
    z_exact: list[int] | None = None
    prime: int | None = None
    code: ExactCode = ExactCode.DECIDED
    facts: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "state", Observability(self.state))  # a name is accepted too

    @property
    def reason(self) -> str:
        """Why, in words (``exact_messages``; empty for a plain proof)."""
        return exact_messages.reason(self.code, self.facts)

    def to_dict(self) -> dict:
        out: dict = {"state": self.state, "rank_mod_p": self.rank_mod_p, "prime": self.prime}
        if self.z_exact is not None:
            out["z_exact_integers"] = [str(v) for v in self.z_exact]
        if self.reason:
            out["reason"] = self.reason
        return out


def _integer_data(A: np.ndarray, C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Integer matrices with the same Krylov structure as (A, C).

    Scaling A or C by a nonzero constant changes no observable subspace, so
    the dyadic mantissas can be used directly.
    """
    return dyadic(A).ints, dyadic(C).ints


def _mod(M: np.ndarray, prime: int) -> np.ndarray:
    return np.array([[int(x) % prime for x in row] for row in M], dtype=np.int64).reshape(M.shape)


def _rank_mod_p(Aint: np.ndarray, Cint: np.ndarray, prime: int) -> int:
    """Krylov rank of (A, C) modulo ``prime``: the dimension of span{C A^k} over GF(prime).

    The basis is kept in reduced echelon form with unit pivots, so a row is
    reduced against all of it by one vector operation; residues are below
    2^26, so every dot product of up to 2^11 terms fits in int64.
    """
    return _rank_mod_p_residues(_mod(Aint, prime), _mod(Cint, prime), prime)


def _rank_mod_p_residues(Am: np.ndarray, Cm: Any, prime: int) -> int:
    """``_rank_mod_p`` on residues already reduced modulo ``prime``.

    ``Cm`` may be any iterable of residue rows; it is consumed only until the
    rank reaches n.
    """
    n = Am.shape[0]
    basis = np.zeros((0, n), dtype=np.int64)
    pivots: list[int] = []
    frontier: Any = iter(Cm)
    while len(pivots) < n:
        added = []
        for r in frontier:
            if len(pivots) == n:
                break
            if pivots:
                r = (r - (r[pivots] @ basis) % prime) % prime
            nz = np.flatnonzero(r)
            if nz.size == 0:
                continue
            pc = int(nz[0])
            r = (r * pow(int(r[pc]), -1, prime)) % prime
            if basis.shape[0]:
                basis = (basis - (basis[:, [pc]] * r[None, :]) % prime) % prime
            basis = np.vstack([basis, r[None, :]])
            pivots.append(pc)
            added.append(r)
        if not added:
            break
        frontier = [(r @ Am) % prime for r in added]
    return len(pivots)


def _exact_kernel_vector(Aint: np.ndarray, Cint: np.ndarray, max_bits: int) -> list[int] | None:
    """An integer z != 0 orthogonal to every row C A^k, or None (full rank or budget)."""
    n = Aint.shape[0]
    A_rows = [[int(x) for x in row] for row in Aint]
    basis: list[list[int]] = []  # fraction-free reduced rows
    pivots: list[int] = []

    def primitive(r: list[int]) -> list[int]:
        g = 0
        for x in r:
            g = math.gcd(g, x)
        if g > 1:
            r = [x // g for x in r]
        lead = next(x for x in r if x)
        return [-x for x in r] if lead < 0 else r

    def reduce(r: list[int]) -> list[int]:
        for b, pc in zip(basis, pivots):
            if r[pc]:
                f, g = b[pc], r[pc]
                d = math.gcd(f, g)
                f, g = f // d, g // d
                r = [f * x - g * y for x, y in zip(r, b)]
        return r

    def times_A(r: list[int]) -> list[int]:
        return [sum(r[i] * A_rows[i][j] for i in range(n) if r[i]) for j in range(n)]

    frontier = [[int(x) for x in row] for row in Cint]
    for _ in range(n + 1):
        added = []
        for r in frontier:
            r = reduce(r)
            if not any(r):
                continue
            r = primitive(r)
            if max(abs(x).bit_length() for x in r) > max_bits:
                return None
            pc = next(j for j, x in enumerate(r) if x)
            # clear the new pivot from earlier rows
            for i, b in enumerate(basis):
                if b[pc]:
                    f, g = r[pc], b[pc]
                    d = math.gcd(f, g)
                    basis[i] = primitive([(f // d) * x - (g // d) * y for x, y in zip(b, r)])
            basis.append(r)
            pivots.append(pc)
            added.append(r)
        if not added or len(pivots) == n:
            break
        frontier = [times_A(r) for r in added]
    if len(pivots) == n:
        return None
    free = next(j for j in range(n) if j not in set(pivots))
    # z_free = D, z_pivot(i) = -b_i[free] * D / b_i[pc_i], D = lcm of pivots
    D = 1
    for b, pc in zip(basis, pivots):
        D = D * abs(b[pc]) // math.gcd(D, abs(b[pc]))
    z = [0] * n
    z[free] = D
    for b, pc in zip(basis, pivots):
        z[pc] = -b[free] * D // b[pc]
    g = 0
    for x in z:
        g = math.gcd(g, x)
    return [x // g for x in z] if g > 1 else z


def _verify_kernel(Aint: np.ndarray, Cint: np.ndarray, z: list[int]) -> bool:
    """C A^k z == 0 exactly for k < n (integers)."""
    n = Aint.shape[0]
    A_rows = [[int(x) for x in row] for row in Aint]
    C_rows = [[int(x) for x in row] for row in Cint]
    w = list(z)
    for _ in range(n):
        if not any(w):
            break
        for row in C_rows:
            if sum(a * b for a, b in zip(row, w)):
                return False
        w = [sum(A_rows[i][j] * w[j] for j in range(n) if w[j]) for i in range(n)]
    return any(z)


def exact_observability(
    A: np.ndarray,
    C: np.ndarray,
    *,
    max_n: int = 60,
    max_bits: int = 200_000,
) -> ExactObservability:
    """Decide observability of the exact data (A, C) (floats taken as rationals).

    Parameters
    ----------
    A : ndarray, shape (n, n)
    C : ndarray, shape (q, n)
        May have no rows (then every state is unobservable).
    max_n : int, default 60
        Largest n decided exactly.
    max_bits : int, default 200000
        Bit budget of the exact kernel computation.

    Returns
    -------
    ExactObservability

    Examples
    --------
    >>> exact_observability(np.eye(2), np.array([[1.0, 0.0]])).state
    <Observability.UNOBSERVABLE: 'unobservable'>
    >>> exact_observability(np.array([[1.0, 1.0], [0.0, 1.0]]), np.array([[1.0, 0.0]])).state
    <Observability.OBSERVABLE: 'observable'>
    """
    A = np.asarray(A, dtype=float)
    C = np.asarray(C, dtype=float).reshape(-1, A.shape[0])
    n = A.shape[0]
    if n > max_n or n > _MAX_MOD_N:
        return ExactObservability(
            Observability.UNKNOWN, code=ExactCode.TOO_LARGE, facts={"n": n, "limit": max_n}
        )
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(C))):
        return ExactObservability(Observability.UNKNOWN, code=ExactCode.NON_FINITE)
    if C.shape[0] == 0 or not np.any(C):
        unit = np.zeros(n)
        unit[0] = 1.0
        zi = [0] * n
        zi[0] = 1
        return ExactObservability(
            Observability.UNOBSERVABLE,
            0,
            unit,
            zi,
            None,
            ExactCode.NO_OUTPUT,
        )
    Aint, Cint = _integer_data(A, C)
    rank = 0
    prime = _PRIMES[0]
    for prime in _PRIMES[:2]:
        rank = _rank_mod_p(Aint, Cint, prime)
        if rank == n:
            return ExactObservability(Observability.OBSERVABLE, rank, prime=prime)
    z = _exact_kernel_vector(Aint, Cint, max_bits)
    if z is None:
        return ExactObservability(
            Observability.UNKNOWN,
            rank,
            prime=prime,
            code=ExactCode.KERNEL_NOT_FOUND,
        )
    if not _verify_kernel(Aint, Cint, z):  # pragma: no cover - would be a bug above
        return ExactObservability(
            Observability.UNKNOWN,
            rank,
            prime=prime,
            code=ExactCode.KERNEL_NOT_VERIFIED,
        )
    zf = _scaled_floats(z)
    return ExactObservability(Observability.UNOBSERVABLE, rank, zf / np.linalg.norm(zf), z, prime)


def _scaled_floats(z: list[int]) -> np.ndarray:
    """The integers z divided by a common power of two, as floats without overflow."""
    top = max(abs(x) for x in z)
    shift = max(top.bit_length() - 60, 0)
    return np.array([float(v >> shift) if v >= 0 else -float((-v) >> shift) for v in z])


def exact_kernel_vector(M: Dyadic, *, max_bits: int = 200_000) -> list[int] | None:
    """An integer vector z != 0 with M z = 0 exactly (re-checked), or None."""
    n = M.shape[1]
    zero = np.zeros((n, n), dtype=object)
    z = _exact_kernel_vector(zero, M.ints, max_bits)
    if z is None or not _verify_kernel(zero, M.ints, z):
        return None
    return z


class ExactPlant:
    """Exact observability decisions for many sensor subsets of one plant.

    The integer data and their residues are computed once; each subset then
    costs one Krylov rank modulo a prime (a proof when it is full) and, only
    when that is deficient, an exact kernel vector re-checked in integers.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    C : ndarray, shape (p, n)
    max_n : int, default 60
        Larger plants are not decided exactly (every answer is ``UNKNOWN``).
    """

    def __init__(self, A: np.ndarray, C: np.ndarray, *, max_n: int = 60) -> None:
        A = np.asarray(A, dtype=float)
        C = np.asarray(C, dtype=float)
        self.n = A.shape[0]
        self.enabled = (
            self.n <= max_n and bool(np.all(np.isfinite(A))) and bool(np.all(np.isfinite(C)))
        )
        self._cache: dict[tuple[int, ...], ExactObservability] = {}
        if self.enabled:
            self.Aint = dyadic(A).ints
            self.C = C
            self.prime = _PRIMES[0]
            self.A_residues = [(q, _mod(self.Aint, q)) for q in _PRIMES[:2]]
            self._rows: dict[int, tuple[np.ndarray, list[np.ndarray]]] = {}

    def _row(self, i: int) -> tuple[np.ndarray, list[np.ndarray]]:
        """Sensor i's row as integers (scaled on its own: row scaling changes no subspace)
        and its residues, converted when first needed."""
        if i not in self._rows:
            ints = dyadic(self.C[i : i + 1]).ints[0]
            self._rows[i] = (ints, [_mod(ints[None, :], q)[0] for q, _ in self.A_residues])
        return self._rows[i]

    def observability(
        self, kept: tuple[int, ...] | list[int], *, proof: bool = True
    ) -> ExactObservability:
        """Exact observability of (A, C[kept]).

        With ``proof=False`` a Krylov rank below n modulo two primes is
        reported as unobservable without computing the exact kernel vector
        (``z`` is then None); full rank modulo a prime is always a proof.
        """
        key = tuple(int(i) for i in kept)
        cached = self._cache.get(key)
        if cached is not None and (
            cached.z_exact is not None
            or not proof
            or cached.state is not Observability.UNOBSERVABLE
        ):
            return cached
        if not self.enabled:
            result = ExactObservability(Observability.UNKNOWN, code=ExactCode.BEYOND_LIMITS)
        elif not key:
            unit = np.zeros(self.n)
            unit[0] = 1.0
            result = ExactObservability(
                Observability.UNOBSERVABLE,
                0,
                unit,
                [1] + [0] * (self.n - 1),
                None,
                ExactCode.NO_SENSOR_KEPT,
            )
        else:
            rank = self.n
            for j, (q, Am) in enumerate(self.A_residues):
                rank = _rank_mod_p_residues(Am, (self._row(i)[1][j] for i in key), q)
                if rank == self.n:
                    break
            if rank == self.n:
                result = ExactObservability(Observability.OBSERVABLE, rank, prime=q)
            elif not proof:
                result = ExactObservability(
                    Observability.UNOBSERVABLE,
                    rank,
                    prime=q,
                    code=ExactCode.RANK_MODULO_PRIMES,
                )
            else:
                Csub = np.array([self._row(i)[0] for i in key], dtype=object)
                z = _exact_kernel_vector(self.Aint, Csub, 200_000)
                if z is not None and _verify_kernel(self.Aint, Csub, z):
                    zf = _scaled_floats(z)
                    result = ExactObservability(
                        Observability.UNOBSERVABLE, rank, zf / np.linalg.norm(zf), z, q
                    )
                else:
                    result = ExactObservability(
                        Observability.UNKNOWN,
                        rank,
                        prime=q,
                        code=ExactCode.KERNEL_BUDGET,
                    )
        self._cache[key] = result
        return result


def exact_stacked_rank(
    A: np.ndarray,
    C: np.ndarray,
    rows: Any,
    steps: int,
    *,
    max_n: int = 60,
    max_bits: int = 200_000,
) -> ExactObservability:
    """Whether chosen rows of the stacked observability matrix have full column rank, exactly.

    Row ``t * p + i`` of O_steps is C_i A^t (sensor i at step t), taken with
    the floats of A and C as rationals.  Each row may be scaled by its own
    power of two (a row scale changes no rank), so the rows are the integer
    vectors C_i^int (A^int)^t.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    C : ndarray, shape (p, n)
    rows : iterable of int
        Row indices into O_steps.
    steps : int
        The horizon of O_steps.
    max_n, max_bits : int
        Budgets: larger plants, or rows longer than ``max_bits`` bits, are
        ``UNKNOWN``.

    Returns
    -------
    ExactObservability
        ``OBSERVABLE`` when the rows have rank n modulo a prime (a proof of
        full column rank); ``UNOBSERVABLE`` with an integer z, O_rows z = 0
        re-checked exactly; ``UNKNOWN`` beyond the budgets.

    Examples
    --------
    >>> A = np.diag([1.0, 1.0 + 2.0**-52])
    >>> exact_stacked_rank(A, np.ones((3, 2)), range(6), 2).state
    <Observability.OBSERVABLE: 'observable'>
    >>> exact_stacked_rank(np.eye(2), np.ones((3, 2)), range(6), 2).state
    <Observability.UNOBSERVABLE: 'unobservable'>
    """
    A = np.asarray(A, dtype=float)
    C = np.asarray(C, dtype=float)
    n, p = A.shape[0], C.shape[0]
    wanted = sorted({int(r) for r in rows})
    if n > max_n:
        return ExactObservability(
            Observability.UNKNOWN, code=ExactCode.TOO_LARGE, facts={"n": n, "limit": max_n}
        )
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(C))):
        return ExactObservability(Observability.UNKNOWN, code=ExactCode.NON_FINITE)
    if any(r < 0 or r >= p * steps for r in wanted):
        raise ValueError(f"rows must index the {p * steps} rows of O_{steps}")
    last = max((r // p for r in wanted), default=-1)
    exact_A = dyadic(A)
    if last * max(exact_A.bits(), 1) > max_bits:
        return ExactObservability(Observability.UNKNOWN, code=ExactCode.POWERS_BIT_BUDGET)
    picked: list[np.ndarray] = []
    by_sensor: dict[int, set[int]] = {}
    for r in wanted:
        by_sensor.setdefault(r % p, set()).add(r // p)
    for i, ts in by_sensor.items():
        row = dyadic(C[i : i + 1]).ints[0]  # C_i A^t, each row on its own power of two
        for t in range(max(ts) + 1):
            if t in ts:
                picked.append(row)
            if t < max(ts):
                row = row @ exact_A.ints
    if not picked:
        unit = np.zeros(n)
        unit[0] = 1.0
        return ExactObservability(
            Observability.UNOBSERVABLE, 0, unit, [1] + [0] * (n - 1), None, ExactCode.NO_ROWS
        )
    M = np.array(picked, dtype=object).reshape(len(picked), n)
    zero = np.zeros((n, n), dtype=np.int64)
    rank = 0
    prime = _PRIMES[0]
    for prime in _PRIMES[:2]:
        rank = _rank_mod_p_residues(zero, _mod(M, prime), prime)
        if rank == n:
            return ExactObservability(Observability.OBSERVABLE, rank, prime=prime)
    z = exact_kernel_vector(Dyadic(M, 0), max_bits=max_bits)  # re-checked in integers
    if z is None:
        return ExactObservability(
            Observability.UNKNOWN,
            rank,
            prime=prime,
            code=ExactCode.NO_KERNEL_VECTOR,
        )
    zf = _scaled_floats(z)
    return ExactObservability(Observability.UNOBSERVABLE, rank, zf / np.linalg.norm(zf), z, prime)
