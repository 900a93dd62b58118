"""ssecert: certificates for secure state estimation under sparse sensor attacks.

A plant x(k+1) = A x(k), y(k) = C x(k) + a(k) has p sensors, up to s of
which an adversary controls.  ssecert decides, with evidence anyone can
re-check, whether secure estimation is possible at all (observability,
s-sparse observability, the breaking sensor set and a stealthy attack) and
whether Lasso will find the attack (the irrepresentable constant).
"""

__version__ = "0.1.0"

from .analyze import analyze
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
