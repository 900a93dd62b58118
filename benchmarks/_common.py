"""What the benchmark scripts share: the best-of timer and the rows of the table.

Every ``bench_*.py`` script measures once and both prints its own text and
returns its figures as rows (``rows(quick=False)``) for ``table.py``.  A row
is a plain dict, so that it crosses a process boundary as JSON:

* ``benchmark``: short name of the comparison;
* ``case``: the plant or the size;
* ``ssecert``: seconds taken by ssecert (for the cost model: its estimate);
* ``reference``: seconds taken by the reference in the same run, or None;
* ``reference_name``: what the reference is;
* ``ratio``: reference / ssecert, or None without a reference;
* ``note``: whether the answers agree, how the reference was sampled, ...
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any, TypeVar

T = TypeVar("T")

ROW_KEYS = ("benchmark", "case", "ssecert", "reference", "reference_name", "ratio", "note")


def best_of(call: Callable[[], T], repeat: int) -> tuple[float, T]:
    """(the shortest of ``repeat`` wall-clock times of ``call()``, its last result)."""
    best = float("inf")
    result: Any = None
    for _ in range(max(1, repeat)):
        start = time.perf_counter()
        result = call()
        best = min(best, time.perf_counter() - start)
    return best, result


def row(
    benchmark: str,
    case: str,
    ssecert: float,
    reference: float | None,
    reference_name: str,
    note: str = "",
) -> dict[str, Any]:
    """One row of the table; the ratio is reference / ssecert."""
    ratio = None
    if reference is not None and ssecert > 0:
        ratio = reference / ssecert
    return {
        "benchmark": benchmark,
        "case": case,
        "ssecert": float(ssecert),
        "reference": None if reference is None else float(reference),
        "reference_name": reference_name,
        "ratio": ratio,
        "note": note,
    }


def yes_no(flag: bool) -> str:
    return "yes" if flag else "NO"


def within_factor(measured: float, estimate: float, factor: float = 2.0) -> bool:
    """Whether measured / estimate lies in [1 / factor, factor]."""
    return estimate > 0 and 1.0 / factor <= measured / estimate <= factor


def cost_model_row(case: str, cost: dict[str, Any]) -> dict[str, Any]:
    """The cost model's estimate against the measured enumeration (``cost_estimate`` evidence).

    The ssecert column holds the estimate and the reference column the
    measured time, so that the ratio is measured / estimate.
    """
    estimate = float(cost["seconds_for_verdict"])
    measured = float(cost["measured_seconds_for_verdict"])
    within = within_factor(measured, estimate)
    sets = f"{cost['sets_for_verdict']:,} sets for the verdict"
    note = (
        f"{sets}; measured / estimate = {measured / estimate:.2f}; within a factor of 2: "
        f"{yes_no(within)}"
    )
    return row("cost model", case, estimate, measured, "measured enumeration", note)
