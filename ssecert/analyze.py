"""Spec -> Certificate: every structural check of a design, no simulations."""

from __future__ import annotations

import datetime as _dt
import platform
from collections.abc import Callable
from typing import Any

from .budget import Budget
from .results import Certificate, Check
from .spec import Spec
from .structure._linalg import eigen_clusters
from .structure.irrepresentable import irrepresentable
from .structure.observability import observability
from .structure.sparse import DEFAULT_MAX_SETS, sparse_observability
from .tolerances import Tolerances

__all__ = ["analyze", "environment"]


def environment() -> dict[str, str]:
    """Versions of ssecert, Python and the numerical libraries."""
    import numpy
    import scipy

    from . import __version__

    versions = {
        "ssecert": __version__,
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
    }
    for module in ("control", "cvxpy", "clarabel", "sympy"):
        try:
            versions[module] = __import__(module).__version__
        except Exception:  # pragma: no cover - optional at analysis time
            versions[module] = "not installed"
    return versions


def analyze(
    spec: Spec,
    *,
    method: str = "auto",
    max_sets: int = DEFAULT_MAX_SETS,
    seed: int = 0,
    tolerances: Tolerances | None = None,
    progress: Callable[[str, int, int], None] | None = None,
    budget: Budget | None = None,
) -> Certificate:
    """Run the structural checks of a design.

    Parameters
    ----------
    spec : Spec
        A validated design (``load_spec`` or ``spec_from_dict``).
    method : {"auto", "enumeration", "eigenspace"}, default "auto"
        Sparse-observability method.
    max_sets : int, default 50,000,000
        Enumeration budget (sensor sets, hyperplanes or supports).
    seed : int, default 0
        Seed of the initial state used to simulate the stealthy attack.
    tolerances : Tolerances, optional
    progress : callable, optional
        ``progress(check_id, done, total)`` during long enumerations.
    budget : Budget, optional
        Memory and work allowed for each analysis step (default ``Budget()``:
        2 GiB, 1e12 operations); a step that does not fit is inconclusive
        with its estimate.

    Returns
    -------
    Certificate
        Checks ``observability``, ``sparse_observability`` (required) and
        ``irrepresentable`` (advisory); with an ``[observer]`` section also
        ``observer_gain``, ``observer_stability`` (required), ``iss_gain``
        and ``thesis_assumptions`` (advisory).

    Examples
    --------
    >>> from ssecert.examples import load_example
    >>> cert = analyze(load_example("notes-example-2"))
    >>> cert.verdict.value, cert["sparse_observability"].fields["breaking_set"]
    ('fails', [0, 2])
    """
    tol = tolerances or Tolerances()
    system = spec.system
    eig = eigen_clusters(system.A, tolerances=tol)

    def relay(check_id: str) -> Callable[[int, int], None] | None:
        if progress is None:
            return None
        return lambda done, total: progress(check_id, done, total)

    checks: list[Check] = [
        observability(system, tolerances=tol, eigen=eig),
        sparse_observability(
            system,
            spec.max_attacked,
            method=method,
            max_sets=max_sets,
            horizon=spec.horizon,
            seed=seed,
            tolerances=tol,
            progress=relay("sparse_observability"),
            eigen=eig,
        ),
        irrepresentable(
            system,
            spec.max_attacked,
            horizon=spec.horizon,
            max_sets=max_sets,
            tolerances=tol,
            progress=relay("irrepresentable"),
            budget=budget,
        ),
    ]
    if spec.observer is not None:
        from .stability.checks import observer_checks

        checks.extend(observer_checks(system, spec.observer, observability=checks[0], seed=seed,
                                      budget=budget))
    notes = []

    meta: dict[str, Any] = {
        "spec": {"source": spec.source, "sha256": spec.sha256, "name": spec.name},
        "max_attacked": spec.max_attacked,
        "horizon": spec.horizon,
        "seed": seed,
        "budget": (budget or Budget()).to_dict(),
        "date": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "versions": environment(),
        "notes": notes,
    }
    return Certificate(system=system, checks=tuple(checks), meta=meta)
