"""Typed outcomes of the structural analyses: why an answer is not exact, as codes and numbers.

The sparse-observability methods record their problems as ``Problem``
values (a ``ProblemCode`` and the facts its words need); the sentences a
user reads are written from them in ``ssecert.structure.sparse_messages``.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

__all__ = ["Problem", "ProblemCode"]


class ProblemCode(enum.Enum):
    """Why a sparse-observability method did not give an exact answer."""

    #: the eigenvalues could not be grouped reliably (``text``: the eigen analysis's words)
    EIGENVALUES = "eigenvalues"
    #: one eigenspace's search did not finish (``eigenvalue``, ``text``)
    EIGENSPACE = "eigenspace"
    #: the eigenspace method's smallest support does not break the exact data (``support``,
    #: ``distance``: its words)
    NOT_EXACT = "not exact"
    #: a sensor's observable subspace has a borderline rank decision (``sensors``)
    BORDERLINE_SUBSPACE = "borderline subspace"
    #: the time budget stopped the refinement before a level (``budget``, ``sets``,
    #: ``removed``, ``seconds`` more predicted)
    TIME_BEFORE_LEVEL = "time budget before a level"
    #: the enumeration budget stopped it before a level (``max_sets``, ``removed``, ``rest``:
    #: what the rest would cost, in words)
    SET_BUDGET = "set budget"
    #: the Dask workers failed twice on a range (``removed``, ``first``, ``last``, ``cause``)
    WORKERS_FAILED = "workers failed"
    #: the time budget stopped the refinement within a level (``budget``, ``checked``,
    #: ``sets``, ``removed``)
    TIME_WITHIN_LEVEL = "time budget within a level"
    #: sets with a borderline rank decision (``count``, ``removed``)
    BORDERLINE_SETS = "borderline sets"
    #: a removal within floating-point precision of breaking the plant (``sensors``,
    #: ``others``, ``distance``: its words or None)
    WITHIN_PRECISION = "within precision"
    #: the enumeration found a smaller breaking set than the eigenspace method (``exact``,
    #: ``size``, ``eigenspace_size``)
    SMALLER_BY_ENUMERATION = "smaller by enumeration"
    #: the enumeration missed a breaking set the exact data confirm (``size``, ``sensors``)
    MISSED_BY_ENUMERATION = "missed by enumeration"


@dataclass(frozen=True)
class Problem:
    """One reason an answer is not exact: a code and the facts its words need."""

    code: ProblemCode
    facts: Mapping[str, Any] = field(default_factory=dict)

    @classmethod
    def of(cls, code: ProblemCode, **facts: Any) -> Problem:
        return cls(code, facts)
