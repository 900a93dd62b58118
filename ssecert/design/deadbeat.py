"""Deadbeat observer gains and the tests that verify them.

Observers are written x_hat(k+1) = A x_hat(k) + L (y(k) - y_hat(k)), so the
linear error matrix is F = A - L C; a deadbeat gain makes F nilpotent.

* ``deadbeat_gain``: A - L C nilpotent with the smallest possible index
  (the observability index), for any number of sensors.  ``control.place``
  refuses poles repeated more than rank(C) times, so it cannot do this when
  p < n.  The construction is orthogonal and needs no canonical form;
  nilpotency is verified by matrix powers, never by eigenvalues (a 15 x 15
  nilpotent matrix has computed eigenvalues near 0.09);
* ``exact_deadbeat_gain``: the same construction in rational arithmetic
  (Fractions) for plants with rational data, verified exactly;
* ``nilpotency`` (the floating-point power test) and ``verify_deadbeat``
  (the test of a printed gain on the exact powers of its A - L C).

``ssecert.design.gains`` re-exports every public name here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from ..base.validation import as_real_matrix
from ..system import System
from ..tolerances import Tolerances
from . import deadbeat_messages
from ._gain import Gain, GainError, GainMethod

__all__ = [
    "deadbeat_gain",
    "exact_deadbeat_gain",
    "nilpotency",
    "Nilpotency",
    "verify_deadbeat",
    "DeadbeatCheck",
    "DEADBEAT_RTOL",
]

DEADBEAT_RTOL = Tolerances().deadbeat_rtol  # the default, for the functions' signatures


@dataclass(frozen=True)
class Nilpotency:
    """Floating-point nilpotency test by matrix powers.

    With s the scale of the data (||A|| for an observer of A),
    ``index`` is the smallest k with ``||(F / s)^k|| <= rtol``, i.e.
    ``||F^k|| <= rtol s^k``; the test is conclusive when ``||(F / s)^(k-1)||``
    is clearly above rtol (``clear`` times it).  ``norms`` are the scaled
    norms ``||(F / s)^k||``.
    """

    index: int | None
    norms: tuple[float, ...]
    rtol: float
    scale: float
    conclusive: bool

    @property
    def reason(self) -> str:
        """Why no index, or no clear one, was found (empty when one was: ``deadbeat_messages``)."""
        return deadbeat_messages.nilpotency_reason(
            self.index, self.norms, self.rtol, self.scale, self.conclusive
        )


def nilpotency(
    F: np.ndarray, *, scale: float | None = None, rtol: float = DEADBEAT_RTOL, clear: float = 100.0
) -> Nilpotency:
    """Decide whether F is nilpotent, and its index, from the norms of its powers.

    The rule is ``||F^k|| <= rtol * s^k`` with ``||F^(k-1)||`` clearly above
    ``rtol * s^(k-1)``.  Taking s = max(1, ||A||) would not be
    invariant under rescaling the plant (for ||A|| < 1 it becomes an
    absolute threshold and declares fast-decaying, non-nilpotent powers
    zero), so s is the data's own scale.  Powers of F / s are computed,
    which cannot overflow.

    Parameters
    ----------
    F : ndarray, shape (n, n)
    scale : float, optional
        s; ||A|| for an observer of A (default ||F||).
    rtol : float, default 1e-8
    clear : float, default 100

    Returns
    -------
    Nilpotency

    Examples
    --------
    >>> import numpy as np
    >>> nilpotency(np.diag([1.0, 1.0], 1)).index
    3
    >>> nilpotency(0.002 * np.diag([1.0, 1.0], 1)).index   # the same, rescaled
    3
    """
    F = np.asarray(F, dtype=float)
    n = F.shape[0]
    s = float(np.linalg.norm(F, 2)) if scale is None else float(scale)
    if not np.isfinite(s) or s <= 0:
        s = 1.0
    G = F / s
    norms: list[float] = []
    power = np.eye(n)
    for k in range(1, n + 1):
        power = power @ G
        norms.append(float(np.linalg.norm(power, 2)))
        if norms[-1] <= rtol:
            previous = norms[-2] if k > 1 else 1.0
            return Nilpotency(k, tuple(norms), rtol, s, previous > clear * rtol)
    return Nilpotency(None, tuple(norms), rtol, s, True)


@dataclass(frozen=True)
class DeadbeatCheck:
    """Deadbeat test of the exact matrix F = A - L C of a printed gain.

    F is formed exactly from the floats of A, L and C and its powers are
    computed in integers, so every number here is about the gain as printed
    (and as a user would implement it), not about an exact gain it rounds.

    Attributes
    ----------
    index : int or None
        Smallest k with ``||F^k||_2 <= rtol ||A||_2^k``, the spectral norm of
        the exact power bounded above by ``sqrt(||F^k||_1 ||F^k||_inf)``.
    relative_norms : tuple of float
        Those upper bounds on ``||F^k||_2 / ||A||_2^k``, k = 1, 2, ...
    relative_lower : tuple of float
        Exact lower bounds on the same ratios.
    conclusive : bool
        ``||F^(k-1)||_2`` is clearly (``clear`` times) above the threshold,
        by its exact lower bound ``||F^(k-1)||_inf / sqrt(n)``.
    exactly_nilpotent : bool
        Some power of the printed F is exactly zero.
    exact_index : int or None
        The smallest such power (it may exceed ``index``: a printed F of size
        2^-52 ||A|| that squares to zero has index 1 to rounding, 2 exactly).
    radius_upper, radius_lower : float
        Certified bounds on the spectral radius of the printed F.
    verified : bool
        ``index`` found, conclusive, and ``radius_upper < 1``: the printed
        gain is stable and its error shrinks by ``rtol`` (relative to the
        plant's scale) in ``index`` steps.
    complete : bool
        The exact powers ran to the end (not stopped at their budget).
    radius_excess : float
        How far exact traces put the spectral radius above 1 (0 when they do not).
    """

    index: int | None
    relative_norms: tuple[float, ...]
    conclusive: bool
    exactly_nilpotent: bool
    radius_upper: float
    radius_lower: float
    rtol: float
    verified: bool
    radius_power: int = 0
    relative_lower: tuple[float, ...] = ()
    exact_index: int | None = None
    complete: bool = True
    radius_excess: float = 0.0

    @property
    def reason(self) -> str:
        """Why it is not verified (empty when it is: ``deadbeat_messages``)."""
        return deadbeat_messages.deadbeat_reason(
            index=self.index,
            conclusive=self.conclusive,
            relative=self.relative_norms,
            rtol=self.rtol,
            complete=self.complete,
            radius_upper=self.radius_upper,
            radius_lower=self.radius_lower,
            radius_excess=self.radius_excess,
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "index": self.index,
            "relative_power_norms": list(self.relative_norms),
            "relative_power_norms_lower": list(self.relative_lower),
            "conclusive": self.conclusive,
            "exactly_nilpotent": self.exactly_nilpotent,
            "exact_nilpotency_index": self.exact_index,
            "spectral_radius_upper_bound": self.radius_upper,
            "spectral_radius_lower_bound": self.radius_lower,
            "upper_bound_power": self.radius_power,
            "rtol": self.rtol,
            "verified": self.verified,
            "reason": self.reason,
            "test": (
                "F = A - L C formed exactly from the printed floats, in balanced power-of-two "
                "state coordinates (S^-1 F S, S^-1 A S); ||F^k||_2 <= rtol "
                "||A||_2^k with ||F^(k-1)||_2 clearly above (exact bounds "
                "||X||_inf / sqrt(n) <= ||X||_2 <= sqrt(||X||_1 ||X||_inf)), and "
                "rho(F) <= ||F^m||_inf^(1/m) < 1 for an exact power m"
            ),
        }


def verify_deadbeat(
    A: Any, L: Any, C: Any, *, rtol: float = DEADBEAT_RTOL, clear: float = 100.0
) -> DeadbeatCheck:
    """Is the printed gain L deadbeat for (A, C)?  Decided on exact powers.

    Parameters
    ----------
    A : array_like, shape (n, n)
    L : array_like, shape (n, p)
    C : array_like, shape (p, n)
    rtol : float, default 1e-8
        ``||F^k|| <= rtol ||A||^k`` counts as zero (relative to the plant's
        scale, so the test does not change when the plant is rescaled).
    clear : float, default 100
        ``||F^(k-1)||`` must exceed ``clear * rtol ||A||^(k-1)``.

    Returns
    -------
    DeadbeatCheck

    Examples
    --------
    >>> import numpy as np
    >>> check = verify_deadbeat([[1.0, 1.0], [0.0, 1.0]], [[2.0], [1.0]], [[1.0, 0.0]])
    >>> check.verified, check.index, check.exactly_nilpotent
    (True, 2, True)
    >>> A = 1e6 * np.roll(np.eye(3), 1, axis=0)   # a gain that rounding made unstable
    >>> L = [[388888.88888888893], [-277777.77777777775], [55555.555555555555]]
    >>> check = verify_deadbeat(A, L, [[1.0, 2.0, 3.0]])
    >>> check.verified, check.radius_lower > 4
    (False, True)
    """
    from ..numerics.exact import exact_error_matrix, spectral_radius_bound

    A = np.asarray(as_real_matrix(A, "A"), dtype=float)
    n = A.shape[0]
    C = np.asarray(
        as_real_matrix(C, "C", shape=(None, n), shape_hint="the number of states"), dtype=float
    )
    L = np.asarray(
        as_real_matrix(L, "L", shape=(n, C.shape[0]), shape_hint="n x p: states by sensors"),
        dtype=float,
    )
    F = exact_error_matrix(A, L, C)
    # the norms are measured in balanced state coordinates (F_b = S^-1 F S, exactly), so that
    # a state written in other units does not make a large F look small against ||A||
    from ..numerics.linalg import state_balancing

    s = state_balancing(A, C)
    if s is not None:
        k = np.round(np.log2(s)).astype(np.int64)
        F = F.scaled(-k, k)
        A = A * (s[None, :] / s[:, None])
    powers = spectral_radius_bound(F, consecutive=n, squarings=8, target=1.0)
    scale = float(np.linalg.norm(A, 2))
    if not np.isfinite(scale) or scale <= 0:
        scale = 1.0
    log_s = math.log2(scale)
    upper = [hi - (k + 1) * log_s for k, (_, hi) in enumerate(powers.log2_two_norms)]
    lower = [lo - (k + 1) * log_s for k, (lo, _) in enumerate(powers.log2_two_norms)]
    relative = tuple(0.0 if r == -math.inf else 2.0 ** min(r, 1e4) for r in upper)
    threshold = math.log2(rtol)
    index = next((k + 1 for k, r in enumerate(upper) if r <= threshold), None)
    conclusive = index is not None and (
        index == 1 or lower[index - 2] > threshold + math.log2(clear)
    )
    return DeadbeatCheck(
        index=index,
        relative_norms=relative,
        conclusive=bool(conclusive),
        exactly_nilpotent=powers.nilpotent_index is not None,
        radius_upper=float(powers.radius_bound),
        radius_lower=float(powers.radius_lower),
        rtol=rtol,
        verified=bool(index is not None and conclusive and powers.radius_bound < 1),
        radius_power=powers.radius_power,
        relative_lower=tuple(0.0 if r == -math.inf else 2.0 ** min(r, 1e4) for r in lower),
        exact_index=powers.nilpotent_index,
        complete=bool(powers.complete),
        radius_excess=float(powers.radius_excess),
    )


def _orth(M: np.ndarray, threshold: float) -> np.ndarray:
    """Orthonormal basis of range(M); singular values <= threshold (absolute) count as zero."""
    if M.size == 0:
        return np.zeros((M.shape[0], 0))
    u, s, _ = np.linalg.svd(M, full_matrices=False)
    return u[:, : int(np.count_nonzero(s > threshold))]


def _null(M: np.ndarray, threshold: float) -> np.ndarray:
    """Orthonormal basis of ker(M), with an absolute rank threshold."""
    n = M.shape[1]
    if M.shape[0] == 0:
        return np.eye(n)
    _, s, vh = np.linalg.svd(M)
    return vh[int(np.count_nonzero(s > threshold)) :].T


def deadbeat_gain(
    system: System | None = None,
    *,
    A: np.ndarray | None = None,
    C: np.ndarray | None = None,
    tolerances: Tolerances | None = None,
) -> Gain:
    """Minimal-index deadbeat observer gain: A - L C nilpotent of index nu.

    nu is the observability index, the fewest steps any observer needs.
    Works on the dual pair (A^T, C^T): the rows of A^T - C^T L^T orthogonal
    to range(C^T) cannot be changed by the gain (call them R); the kernels
    of the powers of a minimal-index nilpotent closed loop must be
    V_1 = ker R and V_i = {x : R x in R V_(i-1)}, which reach R^n in nu
    steps.  On an orthonormal basis adapted to this flag the closed loop
    maps each new direction x of V_i to the w in V_(i-1) with R w = R x,
    and the remaining rows determine the (minimum-norm) gain.  No canonical
    form or ill-conditioned similarity is involved.

    Parameters
    ----------
    system : System, optional
        The plant; alternatively pass ``A`` and ``C``.
    A, C : ndarray, optional
    tolerances : Tolerances, optional

    Returns
    -------
    Gain
        ``details`` has the nilpotency test (index, norms of powers), the
        observability index and whether the index is minimal.

    Raises
    ------
    GainError
        If (A, C) is not observable (a deadbeat observer does not exist
        unless the unobservable modes are at 0) or the flag does not reach
        R^n.

    Examples
    --------
    >>> import numpy as np
    >>> from ssecert import System
    >>> g = deadbeat_gain(System(np.diag([0.5, 0.9, 1.0]) + np.diag([1.0, 1.0], 1), [[1, 0, 0]]))
    >>> g.verified, g.details["nilpotency_index"]
    (True, 3)
    """
    from ..numerics.exact import pow2_row_scaling, pow2_scale

    if system is not None:
        A, C = system.A, system.C
    A = np.asarray(as_real_matrix(A, "A"), dtype=float)
    C = np.asarray(as_real_matrix(C, "C", shape=(None, A.shape[0])), dtype=float)
    tol = tolerances or Tolerances()
    # Units: the construction runs on alpha S^-1 A S and D C S with powers of two alpha, D
    # and S (the states balanced, exact), so that no sensor's or state's units or the plant's
    # scale decide a rank; L = S L_n D / alpha maps the gain back exactly.
    from ..numerics.linalg import state_balancing

    D = pow2_row_scaling(C)
    s = state_balancing(A, D[:, None] * C)
    s = np.ones(A.shape[0]) if s is None else s
    A_s, C_s = A * (s[None, :] / s[:, None]), (D[:, None] * C) * s[None, :]
    alpha = pow2_scale(float(np.max(np.abs(A_s)))) if np.any(A_s) else 1.0
    D_s = pow2_row_scaling(C_s)
    L_n, dims = _deadbeat_construction(alpha * A_s, D_s[:, None] * C_s, tol)
    with np.errstate(over="ignore"):
        L = ((s[:, None] * L_n * D_s[None, :]) / alpha) * D[None, :]  # D last: it may be 2^1023
    if not np.all(np.isfinite(L)):
        raise GainError(
            "the deadbeat gain overflows the float range (its entries scale as 1 / C, and C's "
            f"smallest nonzero entry is {np.min(np.abs(C[C != 0])):.3g})"
        )
    F = A - L @ C
    from ..numerics.linalg import staircase

    index = staircase(alpha * A_s, D_s[:, None] * C_s, tolerances=tol).index
    test = verify_deadbeat(A, L, C, rtol=tol.deadbeat_rtol, clear=tol.certificate_clear)
    if not np.any(C) and not test.verified:
        # A - L C = A exactly for every L, and its exact powers do not vanish
        raise GainError(
            "C is zero, so no gain changes A - L C = A, and A is not nilpotent: a deadbeat "
            f"observer does not exist ({test.reason})"
        )
    problem = test.reason
    if test.index is not None and test.index < index:  # impossible: rounding fooled the test
        problem = (
            f"the power test gives index {test.index}, below the observability index "
            f"{index}, which no gain can reach"
        )
    verified = test.verified and test.index is not None and test.index >= index
    return Gain(
        L=L,
        method=GainMethod.DEADBEAT,
        error_matrix=F,
        verified=verified,
        details={
            "nilpotency_index": test.index,
            "observability_index": index,
            "minimal": test.index == index,
            "relative_power_norms": list(test.relative_norms),
            "exactly_nilpotent": test.exactly_nilpotent,
            "exact_nilpotency_index": test.exact_index,
            "spectral_radius_upper_bound": test.radius_upper,
            "spectral_radius_lower_bound": test.radius_lower,
            "upper_bound_power": test.radius_power,
            "kernel_dimensions": dims,
            "test": test.to_dict()["test"],
            "deadbeat_rtol": tol.deadbeat_rtol,
            "clear_factor": tol.certificate_clear,
            "problem": problem,
        },
    )


def _deadbeat_construction(
    A: np.ndarray, C: np.ndarray, tol: Tolerances
) -> tuple[np.ndarray, list[int]]:
    """The flag construction of ``deadbeat_gain`` on (A, C); returns L and the flag dimensions."""
    n, p = A.shape[0], C.shape[0]
    # absolute rank threshold scaled by the data (a subspace that already
    # spans everything leaves a projection that is zero up to rounding)
    scale = max(float(np.linalg.norm(A, 2)), float(np.linalg.norm(C, 2)), np.finfo(float).tiny)
    rtol = 1e3 * tol.rtol(n, p) * scale
    Ad, Bd = A.T, C.T  # dual (control) pair
    UB = _orth(Bd, rtol)  # range(B)
    NB = _null(Bd.T, rtol)  # range(B) orthogonal complement
    if UB.shape[1] == 0:
        # no gain changes anything: L = 0 is deadbeat exactly when A is nilpotent, which the
        # exact power test of the printed gain decides
        return np.zeros((n, p)), []
    R = NB.T @ Ad  # rows the feedback cannot change
    V = _null(R, rtol)  # V_1
    blocks = [V]
    dims = [V.shape[1]]
    while V.shape[1] < n and len(blocks) <= n:
        target = _orth(NB.T @ V, rtol)  # fixed part of V_(i-1)
        proj = R - target @ (target.T @ R)  # component of R x outside it
        V_next = _null(proj, rtol)
        if V_next.shape[1] <= V.shape[1]:
            break
        blocks.append(V_next)
        dims.append(V_next.shape[1])
        V = V_next
    if V.shape[1] < n:
        raise GainError(
            f"(A, C) is not observable (the deadbeat flag stops at dimension {V.shape[1]} < n = "
            f"{n}); a deadbeat observer does not exist unless the unobservable modes are at 0"
        )
    # orthonormal basis adapted to the flag, and the image of each direction
    X = np.zeros((n, 0))
    W = np.zeros((n, 0))
    previous = np.zeros((n, 0))
    for i, Vi in enumerate(blocks):
        new = Vi - X @ (X.T @ Vi)
        new = _orth(new, rtol)[:, : Vi.shape[1] - X.shape[1]]
        if i == 0:
            images = np.zeros((n, new.shape[1]))
        else:
            # w = previous c whose fixed part equals R x (minimum-norm c)
            coeffs, *_ = np.linalg.lstsq(NB.T @ previous, R @ new, rcond=None)
            images = previous @ coeffs
        X = np.hstack([X, new])
        W = np.hstack([W, images])
        previous = Vi
    # top rows: UB^T (A + B F) X = UB^T W  ->  minimum-norm F
    rhs = UB.T @ (W - Ad @ X) @ X.T
    Fd = np.linalg.pinv(UB.T @ Bd) @ rhs
    return -Fd.T, dims


def exact_deadbeat_gain(A: Sequence[Sequence[Any]], C: Sequence[Sequence[Any]]) -> Gain:
    """The deadbeat construction in exact rational arithmetic.

    The same steps as ``deadbeat_gain`` on the exact values, with Fractions
    (``ssecert.numerics.rational``): the bases are read off reduced row
    echelon forms, which are unique, and the gain is the minimum-norm
    solution, so the result does not depend on how the eliminations pivot.

    Parameters
    ----------
    A, C : nested sequences of int, Fraction or exactly representable floats
        Rational plant data.

    Returns
    -------
    Gain
        ``L`` as floats (each the rational entry correctly rounded);
        ``details["L_exact"]`` holds the rational entries as strings and
        ``details["exact_index"]`` the exact nilpotency index (F^k == 0
        exactly and F^(k-1) != 0).

    Raises
    ------
    GainError
        If the pair is not observable.

    Examples
    --------
    >>> g = exact_deadbeat_gain([[1, 1], [0, 1]], [[1, 0]])
    >>> g.details["exact_index"], g.details["L_exact"]
    (2, [['2'], ['1']])
    """
    from ..numerics.rational import (
        inverse,
        minimum_norm_solution,
        nullspace,
        product,
        transpose,
    )

    Ae = _rational_matrix(A, "A")
    Ce = _rational_matrix(C, "C")
    n = len(Ae)
    if n == 0 or any(len(row) != n for row in Ae):
        raise ValueError(f"A must be square with at least one row; got {_shape(Ae)}")
    if not Ce or any(len(row) != n for row in Ce):
        raise ValueError(f"C must have rows of {n} entries (A is {n} x {n}); got {_shape(Ce)}")
    if not any(x != 0 for row in Ce for x in row):
        raise GainError("C is zero: no observer gain can do anything")
    Ad, Bd = transpose(Ae), transpose(Ce)
    NBt = nullspace(Ce, columns=n)  # the rows of NB': a basis of ker C
    R = product(NBt, Ad)  # NB' A', d x n
    flag = _exact_flag(NBt, R, n)
    X, W = _exact_adapted_basis(flag, NBt, R, n)
    Xinv = inverse(X)
    if Xinv is None:
        raise GainError("(A, C) is not observable: the exact deadbeat basis is singular")
    AX = product(Ad, X)
    rhs = product([[w - ax for w, ax in zip(wr, axr)] for wr, axr in zip(W, AX)], Xinv)
    # rhs lies in range(B): the minimum-norm solution of B Fd = rhs
    Fd = minimum_norm_solution(Bd, rhs, columns=len(Ce))
    Le = [[-x for x in row] for row in transpose(Fd)]
    LC = product(Le, Ce)
    exact_index = _exact_nilpotency_index(
        [[a - lc for a, lc in zip(ra, rlc)] for ra, rlc in zip(Ae, LC)], n
    )
    L = np.array([[_float(x) for x in row] for row in Le], dtype=float).reshape(n, len(Ce))
    Af = np.array([[float(x) for x in row] for row in Ae], dtype=float)
    Cf = np.array([[float(x) for x in row] for row in Ce], dtype=float).reshape(len(Ce), n)
    from ..numerics.linalg import staircase

    obs_index = staircase(Af, Cf).index
    with np.errstate(invalid="ignore"):  # an L beyond the floats' range: inf, its products nan
        error_matrix = Af - L @ Cf
    return Gain(
        L=L,
        method=GainMethod.DEADBEAT,
        error_matrix=error_matrix,
        verified=exact_index is not None and exact_index == obs_index,
        details={
            "exact_index": exact_index,
            "nilpotency_index": exact_index,
            "observability_index": obs_index,
            "minimal": exact_index == obs_index,
            "L_exact": [[str(x) for x in row] for row in Le],
            "test": "F^k == 0 exactly in rational arithmetic, F^(k-1) != 0",
        },
    )


def _rational_matrix(rows: Sequence[Sequence[Any]], name: str) -> list[list[Fraction]]:
    """``rows`` as Fractions, each entry the rational it represents exactly."""

    def rational(x: Any) -> Fraction:
        if isinstance(x, (float, np.floating)):
            if not math.isfinite(x):
                raise ValueError(f"{name} must be finite; got {x}")
            return Fraction(float(x))
        if isinstance(x, Fraction):
            return x
        try:
            return Fraction(x)
        except (TypeError, ValueError):
            raise ValueError(f"{name} must hold rational numbers; got {x!r}") from None

    return [[rational(x) for x in row] for row in rows]


def _shape(rows: list[list[Fraction]]) -> str:
    lengths = sorted({len(row) for row in rows})
    return f"{len(rows)} rows of {' or '.join(map(str, lengths)) or 0} entries"


def _float(x: Fraction) -> float:
    """x correctly rounded, +-inf beyond the floats' range."""
    try:
        return float(x)
    except OverflowError:
        return math.inf if x > 0 else -math.inf


def _identity(n: int) -> list[list[Fraction]]:
    return [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]


def _exact_flag(
    NBt: list[list[Fraction]], R: list[list[Fraction]], n: int
) -> list[list[list[Fraction]]]:
    """The kernels V_1 = ker R, V_i = {x : R x in R V_(i-1)} up to R^n, as lists of vectors
    (``NBt``: the rows of NB', a basis of ker C; R = NB' A')."""
    from ..numerics.rational import nullspace, product, transpose

    d = len(NBt)
    V = nullspace(R, columns=n) if d else _identity(n)
    flag = [V]
    while len(V) < n:
        fixed = product(NBt, transpose(V, n)) if V else [[] for _ in range(d)]
        # V_next = {x : R x in range(NB^T V)}: kernel of the projection onto its complement
        comp = nullspace(transpose(fixed, d), columns=d)  # orthogonal to range(NB^T V)
        V_next = nullspace(product(comp, R), columns=n) if comp else _identity(n)
        if len(V_next) <= len(V):
            raise GainError("(A, C) is not observable: the exact deadbeat flag stops early")
        flag.append(V_next)
        V = V_next
    return flag


def _exact_adapted_basis(
    flag: list[list[list[Fraction]]], NBt: list[list[Fraction]], R: list[list[Fraction]], n: int
) -> tuple[list[list[Fraction]], list[list[Fraction]]]:
    """A basis X adapted to the flag and W, the image of each direction under the closed loop
    (as n x n matrices, one direction a column)."""
    from ..numerics.rational import particular_solution, product, rank, transpose

    X_cols: list[list[Fraction]] = []
    W_cols: list[list[Fraction]] = []
    prev: list[list[Fraction]] = []
    for i, Vi in enumerate(flag):
        for v in Vi:
            if rank([*X_cols, v]) > len(X_cols):
                X_cols.append(v)
                if i == 0:
                    W_cols.append([Fraction(0)] * n)
                else:
                    Rv = [sum((r * x for r, x in zip(row, v)), Fraction(0)) for row in R]
                    sol = particular_solution(product(NBt, transpose(prev, n)), Rv)
                    if sol is None:
                        raise GainError("the exact deadbeat construction found no image")
                    W_cols.append(
                        [sum((c * p[j] for c, p in zip(sol, prev)), Fraction(0)) for j in range(n)]
                    )
        prev = Vi
    return transpose(X_cols, n), transpose(W_cols, n)


def _exact_nilpotency_index(Fe: list[list[Fraction]], n: int) -> int | None:
    """The smallest k with Fe^k == 0 exactly (None when Fe^n is not zero)."""
    from ..numerics.rational import product

    def zero(M: list[list[Fraction]]) -> bool:
        return not any(x != 0 for row in M for x in row)

    power = _identity(n)
    exact_index = None
    for k in range(1, n + 1):
        previous = power
        power = product(power, Fe)
        if zero(power):
            exact_index = k if not zero(previous) else k - 1
            break
    return exact_index
