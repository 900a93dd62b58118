"""Every removal of a given number of sensors, decided: ``scan_removals``.

One level of the enumeration of ``ssecert.structure.enumeration`` on its
own: every set of ``size`` removed sensors is screened and decided, and the
sets that break observability are confirmed on the exact data.
``ssecert.structure.sparse`` re-exports it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..base.validation import as_int_option
from ..numerics.exact import ExactPlant, Observability
from ..numerics.linalg import balanced_units, eigen_clusters, sensor_subspaces
from ..system import System
from ..tolerances import Tolerances
from .enumeration import Progress, _clearly_observable, _scan_level

__all__ = ["scan_removals", "RemovalScan"]


@dataclass(frozen=True)
class RemovalScan:
    """Result of ``scan_removals``.

    Attributes
    ----------
    size : int
        Number of removed sensors per set.
    checked : int
        Number of sets decided.
    breaking_sets : tuple of tuple of int
        Removed-sensor sets that leave the plant unobservable, sorted; each is
        confirmed on the exact data when the plant is small enough (n <= 60):
        its kept sensors have Krylov rank below n modulo two primes.
    borderline : int
        Sets whose rank decision was borderline, or that floating point
        finds breaking while the exact data are observable within precision.
    """

    size: int
    checked: int
    breaking_sets: tuple[tuple[int, ...], ...]
    borderline: int


def scan_removals(
    system: System,
    size: int,
    *,
    prune: bool = True,
    tolerances: Tolerances | None = None,
    progress: Progress | None = None,
) -> RemovalScan:
    """Check every set of ``size`` removed sensors for observability of the rest.

    Parameters
    ----------
    system : System
    size : int
        Number of sensors removed in each set, 0 <= size <= p.
    prune : bool, default True
        Skip sets that keep a sensor which alone observes the whole state
        (they cannot break observability).  With ``prune=False`` all C(p,
        size) sets are decided, which is what the enumeration benchmark
        measures.
    tolerances : Tolerances, optional
    progress : callable, optional

    Returns
    -------
    RemovalScan

    Examples
    --------
    >>> import numpy as np
    >>> from ssecert import System
    >>> ex2 = System(np.eye(3), [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1], [1, -1, 1]])
    >>> scan_removals(ex2, 2).breaking_sets
    ((0, 2),)
    """
    tol = Tolerances.check(tolerances)
    size = as_int_option(size, "size", min_value=0, max_value=system.p)
    original = system
    system = balanced_units(system).system
    sub = sensor_subspaces(system.A, system.C, tolerances=tol)
    n = system.n
    if prune:
        full = np.flatnonzero(sub.ranks == n)
        rest = np.flatnonzero(sub.ranks < n)
    else:
        full = np.zeros(0, dtype=np.int64)
        rest = np.arange(system.p)
    k = size - full.size
    if k < 0:
        return RemovalScan(size, 0, (), 0)
    P = sub.bases[rest]
    proj = np.einsum("qkn,qkm->qnm", P, P)
    level = _scan_level(
        P,
        sub.ranks[rest],
        proj,
        proj.sum(axis=0),
        k,
        rest,
        full,
        tol,
        progress=progress,
        errors=sub.errors[rest],
    )
    # every reported breaking set is confirmed on the exact data; refuted ones are dropped
    # when independent float evidence shows a clear margin, else counted as borderline
    exact = ExactPlant(original.A, original.C)
    eig = eigen_clusters(system.A, tolerances=tol)
    confirmed, borderline = [], level.borderline
    for removed in sorted(level.failures):
        gone = set(removed)
        kept = tuple(i for i in range(system.p) if i not in gone)
        state = exact.observability(kept, proof=False).state
        if state is not Observability.OBSERVABLE:
            confirmed.append(removed)
        elif not _clearly_observable(system, kept, eig, tol):
            borderline += 1
    return RemovalScan(size, level.checked, tuple(confirmed), borderline)
