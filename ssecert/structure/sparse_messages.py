"""The words of the sparse-observability methods' problems (``ssecert.structure.outcomes``)."""

from __future__ import annotations

from collections.abc import Iterable

from .outcomes import Problem, ProblemCode, RecheckCode, RecheckProblem

__all__ = ["problem_text", "problem_texts", "recheck_text"]


def problem_text(problem: Problem) -> str:
    """The sentence of one problem."""
    f = problem.facts
    code = problem.code
    if code is ProblemCode.EIGENVALUES:
        return str(f["text"])
    if code is ProblemCode.EIGENSPACE:
        return f"eigenvalue {f['eigenvalue']}: {f['text']}"
    if code is ProblemCode.NOT_EXACT:
        return (
            f"its smallest support, sensors {list(f['support'])}, does not break the exact data "
            f"(relative distance {f['distance']} to a plant it breaks: within the precision of "
            f"the floating-point rank decision, or its eigenvectors are too ill-conditioned to "
            f"trust)"
        )
    if code is ProblemCode.BORDERLINE_SUBSPACE:
        return f"the observable subspace of sensor(s) {list(f['sensors'])} has a borderline rank decision"
    if code is ProblemCode.TIME_BEFORE_LEVEL:
        return (
            f"the refinement stopped at the time budget of {f['budget']:g} s before the "
            f"{f['sets']:,} sets of {f['removed']} sensors (about {f['seconds']:.3g} s more); "
            f"--exact computes the exact value"
        )
    if code is ProblemCode.SET_BUDGET:
        removed = f["removed"]
        return (
            f"enumeration budget of {f['max_sets']:,} sets reached before sets of "
            f"{removed} sensor{'s' if removed != 1 else ''}" + str(f["rest"])
        )
    if code is ProblemCode.WORKERS_FAILED:
        return (
            f"the Dask workers failed twice on the sets of {f['removed']} sensors at "
            f"positions {f['first']:,} to {f['last']:,} in lexicographic order ({f['cause']})"
        )
    if code is ProblemCode.TIME_WITHIN_LEVEL:
        return (
            f"the refinement stopped at the time budget of {f['budget']:g} s after "
            f"{f['checked']:,} of the {f['sets']:,} sets of {f['removed']} sensors (the first in "
            f"lexicographic order; none breaks the plant); --exact computes the exact value"
        )
    if code is ProblemCode.BORDERLINE_SETS:
        return f"{f['count']} set(s) of {f['removed']} sensors have a borderline rank decision"
    if code is ProblemCode.WITHIN_PRECISION:
        others = f["others"]
        also = f" (and {others} other set(s) of that size)" if others else ""
        far = f" (relative distance {f['distance']})" if f["distance"] is not None else ""
        return (
            f"removing sensors {list(f['sensors'])}{also} leaves a plant that is observable in "
            f"exact arithmetic but, within the precision of the floating-point rank decision (the "
            f"error bound of its computed eigenvalues and singular values), of an unobservable "
            f"one{far}, so the answer depends on digits the data do not have"
        )
    if code is ProblemCode.SMALLER_BY_ENUMERATION:
        found = (
            "a breaking set"
            if f["exact"]
            else "a set within the rank decision's precision of breaking"
        )
        return (
            f"the enumeration finds {found} of {f['size']} sensors, smaller than the eigenspace "
            f"method's {f['eigenspace_size']} (its eigenvalue groups missed it)"
        )
    if code is ProblemCode.MISSED_BY_ENUMERATION:
        return (
            f"the enumeration finds no breaking set of {f['size']} sensors, although sensors "
            f"{list(f['sensors'])} break the exact data: the enumeration's decisions are "
            f"unreliable on this plant"
        )
    raise ValueError(f"no words for {code}")  # pragma: no cover - every code has words


def problem_texts(problems: Iterable[Problem]) -> list[str]:
    """The sentences of several problems, in order."""
    return [problem_text(p) for p in problems]


def recheck_text(problem: RecheckProblem) -> str:
    """The clause that says what disputes a holds verdict in its re-check."""
    f, code = problem.facts, problem.code
    if code is RecheckCode.EXACT_UNOBSERVABLE:
        return (
            f"without sensors outside {list(f['kept'])} the exact data are unobservable "
            f"(an exact kernel vector), which floating point missed"
        )
    if code is RecheckCode.NOT_CONFIRMED:
        return (
            f"re-check of kept sensors {list(f['kept'])} does not confirm observability "
            f"(PBH full rank: {f['pbh']}, staircase full rank: {f['staircase']})"
        )
    if code is RecheckCode.RAW_EIGENVALUE:
        return (
            f"the PBH test at the computed eigenvalue {f['eigenvalue']}, after removing the "
            f"{f['removed']} sensors that see its eigenvector best, is "
            f"{'rank deficient' if f['deficient'] else 'borderline'}"
        )
    raise ValueError(f"no words for {code}")  # pragma: no cover - every code has words
