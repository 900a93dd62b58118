"""ssecert: certificates for secure state estimation under sparse sensor attacks.

A plant x(k+1) = A x(k), y(k) = C x(k) + a(k) has p sensors, up to s of
which an adversary controls.  ssecert decides, with evidence anyone can
re-check, whether secure estimation is possible at all (observability,
s-sparse observability, the breaking sensor set and a stealthy attack) and
whether Lasso will find the attack (the irrepresentable constant).

The names below are imported when first used (PEP 562), so ``import ssecert``
and ``ssecert --version`` do not pay for SciPy and the analyses.
"""

from __future__ import annotations

import importlib
import sys
import types
from typing import TYPE_CHECKING, Any

from ._version import __version__
from .base import display as _display

if TYPE_CHECKING:  # the lazily imported names, for type checkers and editors
    from .analyze import analyze
    from .certify import certify
    from .design.search import design
    from .results import Certificate, Check, Verdict
    from .spec import Spec, SpecError, load_spec, spec_from_dict
    from .structure.attacks import StealthyAttack, stealthy_attack
    from .structure.irrepresentable import irrepresentable, irrepresentable_constant
    from .structure.observability import observability, observability_index
    from .structure.sparse import RemovalScan, scan_removals, sparse_observability
    from .system import System
    from .tolerances import Tolerances

# name: the module that defines it
_LAZY = {
    "System": ".system",
    "Spec": ".spec",
    "SpecError": ".spec",
    "load_spec": ".spec",
    "spec_from_dict": ".spec",
    "Check": ".results",
    "Certificate": ".results",
    "Verdict": ".results",
    "Tolerances": ".tolerances",
    "analyze": ".analyze",
    "certify": ".certify",
    "design": ".design.search",
    "observability": ".structure.observability",
    "observability_index": ".structure.observability",
    "sparse_observability": ".structure.sparse",
    "scan_removals": ".structure.sparse",
    "RemovalScan": ".structure.sparse",
    "stealthy_attack": ".structure.attacks",
    "StealthyAttack": ".structure.attacks",
    "irrepresentable": ".structure.irrepresentable",
    "irrepresentable_constant": ".structure.irrepresentable",
}

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
    "certify",
    "design",
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


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'ssecert' has no attribute {name!r}")
    value = getattr(importlib.import_module(module, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})


# functions named like a submodule or subpackage: ``ssecert.analyze(spec)`` and the module
# ``ssecert.analyze``, ``ssecert.certify(spec)`` and ``ssecert.certify``,
# ``ssecert.design(plant)`` and the package of gains ``ssecert.design``
_FUNCTIONS = ("analyze", "certify", "design")


class _Package(types.ModuleType):
    """The package's module type: a function named like its submodule stays the attribute.

    Importing ``ssecert.analyze`` (the module) binds it as the package's attribute
    ``analyze``, which is the function ``ssecert.analyze(spec)``; that binding is refused,
    so the function is found (lazily) whoever imported the module first.  The modules stay
    importable by name (``from ssecert.design.gains import place_gain``, ``import
    ssecert.certify``): Python finds them in ``sys.modules``.
    """

    def __setattr__(self, name: str, value: Any) -> None:
        if isinstance(value, types.ModuleType) and name in _FUNCTIONS:
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


def _render_html(fragment: str, result: Any) -> str:
    """Notebook display of results (``ssecert.base.display.html_display``), rendered by the report."""
    from .report import html

    return str(getattr(html, fragment)(result))


_display.html_renderer = _render_html
