"""Is e(k+1) = F e(k) asymptotically stable?  Decided on the exact matrix.

Eigenvalue solvers cannot decide this for the matrices observers produce: a
deadbeat F is nearly nilpotent, its computed eigenvalues are off by
eps^(1/n) and can land outside the unit circle (or inside it, for a printed
gain that rounding made unstable), and a simulated trajectory that grows for
a while proves nothing about a non-normal F.  ``schur_decision`` works on the
exact value of F (from the floats of A, L and C when given, so it is the
matrix of the printed gain):

* **stable** when rho(F) <= ||F^m||_inf^(1/m) < 1 for an exact power m;
* **unstable** when rho(F) >= (|trace F^m| / n)^(1/m) > 1 for an exact power
  m, or when F - I or F + I has an exact kernel vector (an eigenvalue on the
  unit circle: not asymptotically stable);
* where neither decides (rho within a hair of 1, n <= ``SCHUR_COHN_LIMIT``):
  **stable** when the exact characteristic polynomial passes the Schur-Cohn
  test on the circle of a radius 1 - 2^-j, **unstable** when it fails it on
  the unit circle (``ssecert.numerics.schur_cohn``);
* otherwise a dominant eigenvalue that exceeds 1 by more than its
  first-order error bound n eps ||F|| kappa is reported as unstable, with
  the method saying so; anything else is undecided.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..numerics.exact import (
    Dyadic,
    PowerBound,
    dyadic,
    exact_kernel_vector,
    shift_by,
    spectral_radius_bound,
)
from ..numerics.exact_powers import ExactMatrix
from ..numerics.schur_cohn import (
    SCHUR_COHN_LIMIT,
    characteristic_polynomial,
    radius_below,
    schur_stable,
)
from ..tolerances import EPS
from . import spectral_messages
from .outcomes import SchurCode, SchurState

__all__ = ["SchurCode", "SchurState", "SchurDecision", "schur_decision", "EXACT_SCHUR_LIMIT"]

EXACT_SCHUR_LIMIT = 80  # largest n whose powers are computed exactly


@dataclass(frozen=True)
class SchurDecision:
    """Outcome of ``schur_decision``.

    Attributes
    ----------
    code : SchurCode
        What decided it; ``state``, ``rigorous``, ``method`` and ``reason``
        follow from it and from ``facts``.
    radius_upper, radius_lower : float or None
        Certified bounds on the spectral radius of the exact F.
    eigenvalue : complex
        Dominant computed eigenvalue (floating point, reported only).
    facts : mapping
        The numbers the words need (the power m, the gap below 1, the exact
        trace's excess, the eigenvalue found, the first-order bound, n, what F
        stands for); not written to JSON.
    details : dict
    """

    code: SchurCode
    radius_upper: float | None
    radius_lower: float | None
    eigenvalue: complex
    facts: Mapping[str, Any] = field(default_factory=dict)
    details: dict[str, Any] = field(default_factory=dict)

    @property
    def state(self) -> SchurState:
        """``STABLE``, ``UNSTABLE`` or ``UNKNOWN``."""
        return self.code.state

    @property
    def rigorous(self) -> bool:
        """True when the decision rests on exact arithmetic only."""
        return self.code.rigorous

    @property
    def method(self) -> str:
        """How the state was decided, in words (``spectral_messages``)."""
        return spectral_messages.method(self.code, self.facts)

    @property
    def reason(self) -> str:
        """Why, in words (``spectral_messages``)."""
        return spectral_messages.reason(
            self.code, self.facts, self.eigenvalue, self.radius_upper, self.radius_lower
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "state": self.state,
            "spectral_radius_upper_bound": self.radius_upper,
            "spectral_radius_lower_bound": self.radius_lower,
            "method": self.method,
            "rigorous": self.rigorous,
            "computed_dominant_eigenvalue": self.eigenvalue,
            "reason": self.reason,
            **self.details,
        }


def _first_order(F: np.ndarray, rounding: float = 0.0) -> tuple[complex, float]:
    """Dominant computed eigenvalue and its first-order error bound (``rounding`` bounds how
    far F's floats are from the matrix it stands for)."""
    import scipy.linalg

    n = F.shape[0]
    lam, vl, vr = scipy.linalg.eig(F, left=True, right=True)
    j = int(np.argmax(np.abs(lam)))
    y = vl[:, j] / np.linalg.norm(vl[:, j])
    x = vr[:, j] / np.linalg.norm(vr[:, j])
    dot = abs(np.vdot(y, x))
    with np.errstate(over="ignore", invalid="ignore"):
        kappa = 1.0 / dot if dot > 0 else np.inf  # a subnormal dot: infinite
        bound = (n * EPS * np.linalg.norm(F, 2) + rounding) * kappa
    return complex(lam[j]), float(bound) if np.isfinite(bound) else np.inf


def schur_decision(
    F: np.ndarray,
    *,
    parts: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    exact: ExactMatrix | None = None,
    max_work: float = 3e8,
) -> SchurDecision:
    """Decide whether every eigenvalue of the exact F lies inside the unit circle.

    Parameters
    ----------
    F : ndarray, shape (n, n)
        The matrix, or its floating-point rounding when ``parts`` or ``exact`` is given.
    parts : (A, L, C), optional
        Decide F = A - L C formed exactly from these floats instead: the
        matrix of the gain as printed, not its rounded product.
    exact : ExactMatrix, optional
        The exact value F stands for, formed on demand (instead of ``parts``).  When it is
        beyond its budget nothing is decided in exact arithmetic.
    max_work : float, default 3e8
        Budget of the exact powers (word operations).

    Returns
    -------
    SchurDecision

    Examples
    --------
    >>> import numpy as np
    >>> schur_decision(np.array([[0.5, 100.0], [0.0, 0.5]])).state
    <SchurState.STABLE: 'stable'>
    >>> d = schur_decision(np.array([[0.0, 1.0], [-1.0, 0.0]]))  # rho = 1: not Schur
    >>> d.state.value, d.method
    ('unstable', 'exact traces: |tr F^2| >= n')
    >>> schur_decision(np.eye(2)).state
    <SchurState.UNSTABLE: 'unstable'>
    """
    F = np.asarray(F, dtype=float)
    n = F.shape[0]
    if not np.all(np.isfinite(F)):
        return SchurDecision(SchurCode.NON_FINITE, None, None, complex(np.nan))
    if exact is None and parts is not None:
        exact = ExactMatrix.error_matrix(*parts)
    rounding = 0.0 if exact is None else exact.rounding(F)
    try:
        lam, bound = _first_order(F, rounding)
    except (np.linalg.LinAlgError, ValueError):
        lam, bound = complex(np.nan), np.inf
    upper = lower = None
    details: dict[str, Any] = {"first_order_error_bound": bound}
    if exact is not None:
        details["exact_data"] = exact.source
        details["rounding_of_F"] = rounding
    value: Dyadic | None = None
    if n <= EXACT_SCHUR_LIMIT:
        value = dyadic(F) if exact is None else exact.value
        if value is None:
            details["exact_data"] = f"{exact.source if exact else 'F'}: beyond its budget"
    if value is not None and np.isfinite(abs(lam)) and abs(abs(lam) - 1.0) <= 1e-9:
        # an eigenvalue that looks like +-1: an exact kernel vector decides at once, where the
        # powers of a matrix with rho = 1 never do
        norm = value.inf_norm_log2()  # rho <= ||F||_inf: the upper bound this decision has
        upper_now = 0.0 if norm == -np.inf else (np.inf if norm >= 1024 else 2.0**norm)
        decided = _exact_eigenvalue_on_circle(value, n, upper_now, 0.0, lam, details)
        if decided is not None:
            return decided
    if value is not None:
        powers = spectral_radius_bound(value, squarings=8, target=1.0, max_work=max_work)
        upper, lower = powers.radius_bound, powers.radius_lower
        details.update(
            upper_bound_power=powers.radius_power,
            lower_bound_power=powers.lower_power,
            exactly_nilpotent_index=powers.nilpotent_index,
            exact_powers_complete=powers.complete,
        )
        source = f"of {exact.source}" if exact is not None else "of F"
        decided = _decided_by_powers(powers, source, n, lam, details)
        if decided is None:
            decided = _exact_eigenvalue_on_circle(
                value, n, powers.radius_bound, powers.radius_lower, lam, details
            )
        if decided is None:
            decided = _decided_by_schur_cohn(value, source, upper, lower, lam, details)
        if decided is not None:
            return decided
    return _decided_to_first_order(lam, bound, upper, lower, details)


# bisection steps that tighten the radius 1 - 2^-j of a stable polynomial's bound
_SCHUR_COHN_BISECTIONS = 4


def _decided_by_schur_cohn(
    exact: Dyadic,
    source: str,
    upper: float,
    lower: float,
    lam: complex,
    details: dict[str, Any],
) -> SchurDecision | None:
    """Stable or unstable by the Schur-Cohn test of the exact characteristic polynomial
    (n <= ``SCHUR_COHN_LIMIT``), or None.

    Stable needs a radius bound: the test runs on the circles of radius r = 1 - 2^-j, first
    with j from the computed eigenvalue's distance to 1 (where that circle holds every root,
    one test decides), else, once the unit circle holds them, with j doubled until one does,
    which proves rho < r, and a few bisections tighten j; none up to 2^-1074 (or the budget)
    decides nothing."""
    n = exact.shape[0]
    if not 0 < n <= SCHUR_COHN_LIMIT:
        return None
    try:
        coefficients = characteristic_polynomial(exact)
    except ArithmeticError:  # (sympy's polynomial not confirmed: nothing decided)
        details["schur_cohn"] = "the characteristic polynomial did not check"
        return None
    gap = 1.0 - abs(lam) if np.isfinite(abs(lam)) else 0.0
    j = min(max(1, math.ceil(-math.log2(gap)) + 1), 1074) if 0.0 < gap < 1.0 else 1
    # the computed eigenvalue's radius first (one test where it is right), else the unit circle
    below = radius_below(coefficients, j) if j > 1 else False
    stable = True if below else (None if below is None else schur_stable(coefficients))
    if stable is None:
        details["schur_cohn"] = "beyond its budget"
        return None
    if not stable:
        return SchurDecision(
            SchurCode.SCHUR_COHN_FAILS, upper, max(lower, 1.0), lam, {"source": source}, details
        )
    # rho >= 1 - 2^-failed; rho < 1 - 2^-proved
    proved, failed = (j, 0) if below else (None, j if j > 1 else 0)
    j = max(2 * failed, 1)
    while proved is None:  # j doubled until a radius 1 - 2^-j holds every root
        j = min(j, 1074)
        below = radius_below(coefficients, j)
        if below is None:
            break
        if below:
            proved = j
        elif j == 1074:
            break
        else:
            failed, j = j, 2 * j
    for _ in range(_SCHUR_COHN_BISECTIONS if failed else 0):  # then a tighter j between
        if proved is None or proved - failed <= 1:
            break
        j = (failed + proved) // 2
        below = radius_below(coefficients, j)
        if below is None:
            break
        failed, proved = (failed, j) if below else (j, proved)
    if proved is not None:
        gap = math.ldexp(1.0, -proved)
        upper = min(upper, 1.0 - gap)  # (rounds to 1 for j > 53: still a bound)
        details["spectral_radius_gap"] = gap
        facts: dict[str, Any] = {"source": source, "upper": upper, "gap": gap, "j": proved}
        return SchurDecision(SchurCode.SCHUR_COHN_STABLE, upper, lower, lam, facts, details)
    details["schur_cohn"] = "stable, with no radius 1 - 2^-j (j <= 1074) proved"
    return None


def _decided_by_powers(
    powers: PowerBound, source: str, n: int, lam: complex, details: dict[str, Any]
) -> SchurDecision | None:
    """Stable by the norm of an exact power, unstable by exact traces, or None."""
    upper, lower = powers.radius_bound, powers.radius_lower
    if upper < 1.0 or powers.radius_gap > 0:
        m = powers.radius_power
        if not upper < 1.0 or 1.0 - upper < powers.radius_gap:
            m, upper = powers.gap_power, min(upper, 1.0 - powers.radius_gap)
        gap = max(1.0 - upper, powers.radius_gap)
        details["spectral_radius_gap"] = gap
        facts = {"power": m, "source": source, "upper": upper, "gap": gap}
        return SchurDecision(SchurCode.POWERS_STABLE, upper, lower, lam, facts, details)
    if powers.radius_excess > 0 and not lower > 1.0:
        # |trace F^m| > n exactly, by less than the float lower bound resolves (1 + 2^-60)
        m = powers.excess_power
        details["spectral_radius_excess"] = powers.radius_excess
        facts = {
            "power": m,
            "source": source,
            "n": n,
            "trace_excess": powers.trace_excess,
            "radius_excess": powers.radius_excess,
        }
        return SchurDecision(SchurCode.TRACE_EXCESS, upper, max(lower, 1.0), lam, facts, details)
    if powers.trace_reaches_n and not lower > 1.0:
        facts = {"power": powers.trace_reaches_n, "source": source, "n": n}
        return SchurDecision(SchurCode.TRACE_REACHES_N, upper, max(lower, 1.0), lam, facts, details)
    if lower > 1.0:
        facts = {"power": powers.lower_power, "source": source, "lower": lower}
        return SchurDecision(SchurCode.TRACES_BELOW, upper, lower, lam, facts, details)
    return None


def _exact_eigenvalue_on_circle(
    exact: Dyadic,
    n: int,
    upper: float | None,
    lower: float,
    lam: complex,
    details: dict[str, Any],
) -> SchurDecision | None:
    """Unstable by an exact eigenvalue of modulus >= 1 that is a float, or None.

    The candidates are 1, -1 and the computed dominant eigenvalue when it is
    real (a perturbation of 2^-40 is below what the first-order bound
    resolves, but an exact kernel vector proves it); tried for n <= 40.
    """
    candidates: list[float] = [1.0, -1.0]
    if np.isfinite(abs(lam)) and lam.imag == 0 and abs(lam.real) >= 1.0:
        candidates.append(float(lam.real))
    for value in candidates:
        if n <= 40 and exact_kernel_vector(shift_by(exact, value)) is not None:
            return SchurDecision(
                SchurCode.EIGENVALUE_ON_CIRCLE,
                upper,
                max(lower, abs(value)),
                lam,
                {"eigenvalue": value},
                details,
            )
    return None


def _decided_to_first_order(
    lam: complex,
    bound: float,
    upper: float | None,
    lower: float | None,
    details: dict[str, Any],
) -> SchurDecision:
    """Unstable when the dominant eigenvalue clears 1 by its first-order bound, else unknown."""
    if np.isfinite(abs(lam)) and abs(lam) - bound > 1 + 1e-9:
        return SchurDecision(SchurCode.FIRST_ORDER, upper, lower, lam, {"bound": bound}, details)
    return SchurDecision(SchurCode.UNDECIDED, upper, lower, lam, {}, details)
