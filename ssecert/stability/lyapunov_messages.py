"""The words of the Lyapunov certificate: every sentence written from a ``LyapunovCertificate``.

``ssecert.stability.lyapunov.lyapunov_certificate`` returns a
``LyapunovCode`` for its Lyapunov solution and, when no P verified, the exact
``SchurDecision`` on F; this module alone writes the reason (read through
``LyapunovCertificate.reason``, which calls it), the decision's own words
coming from ``ssecert.stability.spectral_messages``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from .outcomes import LyapunovCode, SchurState

__all__ = ["reason", "unverified"]


def unverified(code: LyapunovCode, facts: Mapping[str, Any]) -> str:
    """Why no Lyapunov matrix P is the certificate (empty for a verified one)."""
    if code is LyapunovCode.NO_UNIQUE_SOLUTION:
        return f"the Lyapunov equation has no unique solution ({facts['error']})"
    if code is LyapunovCode.NOT_FINITE:
        return "the Lyapunov solution is not finite"
    if code is LyapunovCode.NOT_VERIFIED:
        return (
            f"the Lyapunov solution cannot be verified with a margin (smallest decrease "
            f"{facts['decrease']:.2e}, smallest eigenvalue of P {facts['p_min']:.2e}, error "
            f"bound {facts['bound']:.2e})"
        )
    return ""


def reason(
    code: LyapunovCode, facts: Mapping[str, Any], state: SchurState | None, decided: str
) -> str:
    """Why a certificate's verdict is what it is: empty when a verified P is the proof (no
    exact ``state``), an exact instability alone (``decided``: the decision's reason),
    otherwise why no P verified (``code``, ``facts``) and what the exact F says."""
    if state is None:
        return ""
    if state is SchurState.UNSTABLE:
        return decided
    if state is SchurState.STABLE:
        return f"{unverified(code, facts)}; instead, {decided}"
    return f"{unverified(code, facts)}; {decided}"
