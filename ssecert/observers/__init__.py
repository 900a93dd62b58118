"""Observer kinds as plug-ins: one module per kind, one registry.

========================  =====================================  ===============
kind (module)             L                                      attack estimate
========================  =====================================  ===============
luenberger (luenberger)   deadbeat, place, pinv or a matrix      none
ogd (ogd)                 step * A C^T (lecture notes Sec. 4.2)  none
sso (sso)                 step * A S^T (Algorithm 1, Lasso       shrink 1, L2 = I
                          paper; S = O_tau)
dsso (dsso)               deadbeat (default), pinv, place,       shrink 1, L2 = I
                          matrix
elastic_net (elastic_net) any                                    shrink in (0, 1), L2
========================  =====================================  ===============

A kind is a subclass of ``ObserverKind`` decorated with ``register``; the
spec loader, the certificates, the simulations, the report, ``ssecert
design`` and ``ssecert.testing`` reach every kind through ``get_kind`` and
the design's ``observer_kind``.  See
CONTRIBUTING.md for adding one.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ..budget import Budget
from ..system import System
from ..tolerances import Tolerances
from . import dsso, elastic_net, luenberger, ogd, sso  # noqa: F401  (register the built-in kinds)
from .base import GAIN_CHOICES, ObserverDesign, ObserverKind
from .dynamic import DynamicObserver, Trajectory
from .lure import LureModel
from .registry import BUILTIN_KINDS, get_kind, observer_kinds, register, unregister
from .simulators import LinearObserver, SparseSoftObserver, WindowSSO

__all__ = [
    "ObserverDesign",
    "ObserverKind",
    "build_observer",
    "observer_from_design",
    "register",
    "unregister",
    "get_kind",
    "observer_kinds",
    "BUILTIN_KINDS",
    "GAIN_CHOICES",
    "LureModel",
    "DynamicObserver",
    "Trajectory",
    "LinearObserver",
    "SparseSoftObserver",
    "WindowSSO",
]


def build_observer(
    system: System,
    spec: Mapping[str, Any],
    *,
    budget: Budget | None = None,
    tolerances: Tolerances | None = None,
) -> ObserverDesign:
    """Build an observer from a validated ``[observer]`` section.

    Parameters
    ----------
    system : System
    spec : mapping
        As validated by ``ssecert.spec`` (``Spec.observer``).
    budget : Budget, optional
        Memory allowed for the observer's matrices (default ``Budget()``,
        2 GiB): an SSO with window tau stacks O_tau (p tau x n) and an
        identity L2 of size p tau.
    tolerances : Tolerances, optional
        The run's tolerances (default ``Tolerances()``); the deadbeat gain's
        power test uses ``deadbeat_rtol`` and ``certificate_clear``.

    Returns
    -------
    ObserverDesign

    Raises
    ------
    GainError
        If the requested gain cannot be computed (not observable for a
        deadbeat gain, C not of full column rank for pinv, placement missed,
        O_tau or the gain overflows).
    ResourceLimitError
        If the matrices of an SSO window would exceed the memory budget (the
        message gives the estimate).

    Examples
    --------
    >>> from ssecert.examples import load_example
    >>> spec = load_example("ugv")
    >>> design = build_observer(spec.system, spec.observer)
    >>> design.kind, design.gain.method.value, design.gain.details["nilpotency_index"]
    ('dsso', 'deadbeat', 1)
    """
    kind = _checked_kind(system, spec)
    return kind.build(system, spec, budget or Budget(), Tolerances.check(tolerances))


def _checked_kind(system: System, spec: Any) -> ObserverKind:
    """The kind of an observer section given in Python, its keys checked as a spec file's are
    (unknown, required, the shape of a gain matrix, the poles of a placed gain): the values
    themselves are the kind's to judge when it builds."""
    import difflib

    if not isinstance(spec, Mapping):
        raise TypeError(f"observer must be a mapping of its keys, got {type(spec).__name__}")
    if "kind" not in spec:
        raise ValueError(f"observer: key 'kind' is required, one of {', '.join(observer_kinds())}")
    kind = get_kind(spec["kind"])
    for key in spec:
        if key not in kind.keys:
            near = difflib.get_close_matches(str(key), kind.keys, n=1)
            hint = f" (did you mean {near[0]!r}?)" if near else ""
            raise ValueError(
                f"observer: unknown key {key!r} for kind {kind.name!r}{hint}; its keys: "
                f"{', '.join(kind.keys)}"
            )
    for key in kind.required_keys:
        if key not in spec:
            raise ValueError(f"observer: key {key!r} is required for kind {kind.name!r}")
    if "gain" in spec and spec["gain"] is None:
        raise ValueError(
            "observer: key 'gain' is None: give a gain's name or an n x p matrix, or leave the "
            "key out for the kind's default"
        )
    gain = spec.get("gain")
    if gain is not None and not isinstance(gain, str):
        shape = _nested_shape(gain)
        if shape != (system.n, system.p):
            raise ValueError(
                f"observer: key 'gain' must be an n x p = {system.n} x {system.p} matrix "
                f"(states by sensors), got shape {tuple(shape)}"
            )
    placed = isinstance(gain, str) and gain == "place"
    if placed and "poles" not in spec:
        raise ValueError(f"observer: gain 'place' needs key 'poles' ({system.n} poles)")
    if not placed and spec.get("poles") is not None:
        raise ValueError("observer: key 'poles' is only used with gain 'place'")
    return kind


def _nested_shape(value: Any) -> tuple[int, ...]:
    """The shape of an array or of nested lists (a ragged one's outer length only)."""
    import numpy as np

    try:
        return tuple(np.shape(value))
    except ValueError:  # ragged
        return (len(value),) if hasattr(value, "__len__") else ()


def observer_from_design(design: ObserverDesign) -> DynamicObserver:
    """The batched simulator of an ``ObserverDesign``, as its kind gives it.

    Examples
    --------
    >>> from ssecert.examples import load_example
    >>> spec = load_example("ugv")
    >>> type(observer_from_design(build_observer(spec.system, spec.observer))).__name__
    'SparseSoftObserver'
    """
    return design.observer_kind.simulator(design)
