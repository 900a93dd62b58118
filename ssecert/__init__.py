"""ssecert: certificates for secure state estimation under sparse sensor attacks.

A plant x(k+1) = A x(k), y(k) = C x(k) + a(k) has p sensors, up to s of
which an adversary controls.  ssecert decides, with evidence anyone can
re-check, whether secure estimation is possible at all (observability,
s-sparse observability, the breaking sensor set and a stealthy attack) and
whether Lasso will find the attack (the irrepresentable constant).
"""

from collections.abc import Callable
from typing import Any

from ._version import __version__
from .analyze import analyze
from .certify import CertifyResult
from .results import Certificate, Check, Verdict
from .spec import Spec, SpecError, load_spec, spec_from_dict
from .structure.attacks import StealthyAttack, stealthy_attack
from .structure.irrepresentable import irrepresentable, irrepresentable_constant
from .structure.observability import observability, observability_index
from .structure.sparse import RemovalScan, scan_removals, sparse_observability
from .system import System
from .tolerances import Tolerances

__all__ = [
    "__version__",
    "System",
    "Spec",
    "SpecError",
    "load_spec",
    "spec_from_dict",
    "Check",
    "Certificate",
    "Verdict",
    "Tolerances",
    "analyze",
    "observability",
    "observability_index",
    "sparse_observability",
    "scan_removals",
    "RemovalScan",
    "stealthy_attack",
    "StealthyAttack",
    "irrepresentable",
    "irrepresentable_constant",
]


def _html_display(fragment: str) -> Callable[[Any], str]:
    """A ``_repr_html_`` that renders with ``ssecert.report.html`` (imported when first shown)."""

    def _repr_html_(self: Any) -> str:
        from .report import html

        return str(getattr(html, fragment)(self))

    return _repr_html_


# Notebooks show checks and certificates as the report does; the renderer sits above the
# results it renders, so the package wires it here rather than results importing it.
for _cls, _fragment in (
    (Check, "check_fragment"),
    (Certificate, "certificate_fragment"),
    (CertifyResult, "render_fragment"),
):
    setattr(_cls, "_repr_html_", _html_display(_fragment))  # noqa: B010  (not a declared attribute)
del _cls, _fragment
