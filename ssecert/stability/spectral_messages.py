"""The words of the exact Schur decision: every sentence written from a ``SchurDecision``.

``ssecert.stability.spectral.schur_decision`` returns a ``SchurCode`` and the
numbers behind it; this module alone writes its method and reason (read
through ``SchurDecision.method`` and ``SchurDecision.reason``, which call
it), so that rewording a sentence here changes no decision.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..base.format import one_minus, one_plus, sig
from .outcomes import SchurCode

__all__ = ["below_one", "method", "reason"]


def _radius(x: float) -> str:
    """A radius with enough digits to show on which side of 1 it lies."""
    return sig(x, 6)


def below_one(upper: float, gap: float) -> str:
    """``upper < 1`` in words that show it: ``1 - 1.65e-07`` when six digits would print 1."""
    if 0 < gap < 1e-3 or upper >= 1.0:
        return f"{one_minus(gap)} < 1"
    return f"{_radius(upper)} < 1"


def _eigenvalue(value: float) -> str:
    return sig(value, 6, versus=float(np.sign(value)))  # 1 + 2^-40 is not "1"


def method(code: SchurCode, facts: Mapping[str, Any]) -> str:
    """How a decision of ``code`` was reached, as the JSON's ``method`` says it."""
    if code is SchurCode.POWERS_STABLE:
        m = facts["power"]
        return f"exact powers: rho <= ||F^{m}||^(1/{m})"
    if code is SchurCode.TRACE_EXCESS:
        return f"exact traces: |tr F^{facts['power']}| > n"
    if code is SchurCode.TRACE_REACHES_N:
        return f"exact traces: |tr F^{facts['power']}| >= n"
    if code is SchurCode.TRACES_BELOW:
        m = facts["power"]
        return f"exact traces: rho >= (|tr F^{m}| / n)^(1/{m})"
    if code is SchurCode.EIGENVALUE_ON_CIRCLE:
        return f"exact eigenvalue {_eigenvalue(facts['eigenvalue'])}"
    if code is SchurCode.SCHUR_COHN_STABLE:
        return f"exact Schur-Cohn test: rho < 1 - 2^-{facts['j']}"
    if code is SchurCode.SCHUR_COHN_FAILS:
        return "exact Schur-Cohn test: rho >= 1"
    if code is SchurCode.FIRST_ORDER:
        return "first-order eigenvalue bound"
    return "none"


def reason(
    code: SchurCode,
    facts: Mapping[str, Any],
    eigenvalue: complex,
    upper: float | None,
    lower: float | None,
) -> str:
    """Why F is (or is not, or may not be) Schur stable, in a sentence: a decision of ``code``
    with its facts, the dominant computed eigenvalue and the certified radius bounds."""
    if code is SchurCode.NON_FINITE:
        return "F has non-finite entries"
    if code is SchurCode.POWERS_STABLE:
        return (
            f"the exact powers {facts['source']} bound its spectral radius by "
            f"{below_one(facts['upper'], facts['gap'])}"
        )
    if code is SchurCode.TRACE_EXCESS:
        n, m = facts["n"], facts["power"]
        return (
            f"the exact powers {facts['source']} give |trace F^{m}| = "
            f"{one_plus(facts['trace_excess'], n)} > n = {n}, so its spectral radius is at "
            f"least {one_plus(facts['radius_excess'])} > 1: the error does not converge to 0 "
            f"from every state"
        )
    if code is SchurCode.TRACE_REACHES_N:
        n, m = facts["n"], facts["power"]
        return (
            f"the exact powers {facts['source']} give |trace F^{m}| = n = {n} exactly, so its "
            f"spectral radius is at least 1: the error does not converge to 0 from every state"
        )
    if code is SchurCode.TRACES_BELOW:
        return (
            f"the exact traces of the powers {facts['source']} bound its spectral radius below "
            f"by {one_plus(facts['lower'] - 1.0)} > 1"
        )
    if code is SchurCode.EIGENVALUE_ON_CIRCLE:
        return (
            f"F has the eigenvalue {_eigenvalue(facts['eigenvalue'])} exactly (F - lambda I has "
            f"an exact kernel vector), of modulus >= 1: the error along it never decays"
        )
    if code is SchurCode.SCHUR_COHN_STABLE:
        return (
            f"the exact characteristic polynomial {facts['source']} passes the Schur-Cohn test "
            f"on the circle of radius 1 - 2^-{facts['j']}, so its spectral radius is below "
            f"{below_one(facts['upper'], facts['gap'])}"
        )
    if code is SchurCode.SCHUR_COHN_FAILS:
        return (
            f"the exact characteristic polynomial {facts['source']} fails the Schur-Cohn test, "
            f"so it has an eigenvalue of modulus at least 1: the error does not converge to 0 "
            f"from every state"
        )
    if code is SchurCode.FIRST_ORDER:
        return (
            f"the dominant eigenvalue {eigenvalue:.6g} exceeds 1 in modulus by more "
            f"than its first-order error bound {facts['bound']:.1e}"
        )
    bounds = (
        f" (certified {_radius(lower)} <= rho <= {_radius(upper)})"
        if upper is not None and lower is not None
        else ""
    )
    return (
        f"neither exact powers nor traces nor the Schur-Cohn test nor a clear eigenvalue "
        f"decide it{bounds}"
    )
