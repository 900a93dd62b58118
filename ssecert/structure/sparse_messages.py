"""The words of the sparse-observability methods' problems (``ssecert.structure.outcomes``)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

from .outcomes import Problem, ProblemCode, RecheckCode, RecheckProblem

__all__ = [
    "placement_text",
    "problem_text",
    "problem_texts",
    "recheck_text",
    "undecided_summary",
]


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
            f"{removed} sensor{'s' if removed != 1 else ''}"
            + _rest_text(f["seconds"], f["workers"], f["time_budget"])
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


def _rest_text(seconds: float | None, workers: int | None, time_budget: float | None) -> str:
    """What the rest of the verdict's sets would cost, as the end of a refusal over the set
    budget (empty past the verdict's level)."""
    if seconds is None:
        return ""
    text = f" (the rest of the verdict's sets would take about {seconds:g} s here"
    if workers is not None:
        text += f"; about {workers:,} Dask workers would take them under {time_budget:g} s"
    return text + "; --max-sets raises the budget)"


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


def undecided_summary(reasons: Sequence[str], needed: int | None) -> str:
    """The summary of a sparse-observability check no method decided: the methods' problems
    (``reasons``) and, where a budget stopped the enumeration, the sensor sets still
    ``needed``."""
    hint = ""
    if needed is not None:
        hint = (
            f" About {needed:,} more sensor sets are needed; raise the budget with "
            f"--max-sets (max_sets=...)."
        )
    return f"Sparse observability could not be decided: {'; '.join(reasons)}.{hint}"


def placement_text(
    on_workers: Mapping[int, int], in_process: Sequence[int], min_sets: int, chunk_over_level: int
) -> str:
    """What ran where in an enumeration given a Dask client: the levels (by the number of
    sensors removed) split into ``on_workers[size]`` ranges, those run ``in_process``, and
    why a level is not split (ranges of at least ``min_sets`` sets and ``chunk_over_level``
    times the partial sums each range rebuilds)."""
    groups: list[tuple[list[int], int]] = []  # consecutive sizes split alike
    for size, ranges in on_workers.items():
        if groups and groups[-1][1] == ranges and groups[-1][0][-1] == size - 1:
            groups[-1][0].append(size)
        else:
            groups.append(([size], ranges))
    parts = [
        f"the sets of {_sizes(sizes)} {_sensors(sizes)} in {ranges} ranges"
        + (" each" if len(sizes) > 1 else "")
        for sizes, ranges in groups
    ]
    local = list(in_process)
    if parts:
        text = "Dask workers: " + "; ".join(parts)
        if local:
            text += f"; in-process: the sets of {_sizes(local)} "
            text += _sensors(local)
    else:
        text = f"every level ran in-process (the sets of {_sizes(local)} "
        text += f"{_sensors(local)}), none on the Dask workers"
    if local:
        text += (
            f"; a level is split only into ranges of at least {min_sets:,} sets and "
            f"{chunk_over_level} times the partial sums each range rebuilds: a smaller one "
            "would take longer on the workers"
        )
    return text


def _sensors(sizes: list[int]) -> str:
    return "sensor" if sizes == [1] else "sensors"


def _sizes(sizes: list[int]) -> str:
    """'0 to 5' for consecutive sizes, else '1, 3 and 4'."""
    if len(sizes) > 2 and sizes == list(range(sizes[0], sizes[-1] + 1)):
        return f"{sizes[0]} to {sizes[-1]}"
    if len(sizes) == 1:
        return str(sizes[0])
    return ", ".join(map(str, sizes[:-1])) + f" and {sizes[-1]}"
