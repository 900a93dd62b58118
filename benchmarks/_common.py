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

The ``exp_*.py`` scripts (experiments of the documents) write their
comparisons with the papers through the small pure functions below
(``compare_time``, ``same_order``, ``which_is_better``, ``compare_values``):
every word that compares is computed from the numbers, with the rule it
used, and tests feed them other numbers to see the words change.
``record_experiment`` keeps a run's numbers for benchmarks/README.md.
"""

from __future__ import annotations

import math
import textwrap
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


# Words of the experiment scripts' conclusions, written from the numbers.  Each function
# is pure, so that tests can feed it other numbers and see the words change.

#: Two positive values are "of the same order of magnitude" when within this factor.
SAME_ORDER_FACTOR = 10.0
#: Two values within this relative difference are a tie in ``which_is_better``.
TIE_RTOL = 0.05


def times(ratio: float) -> str:
    """A ratio >= 1 as "65x" (no decimals from 10 up), "1.5x" or "4.7e+09x"."""
    if not math.isfinite(ratio):
        return "infinitely many times"
    if ratio >= 1e4:
        return f"{ratio:.1e}x"
    return f"{ratio:.0f}x" if ratio >= 10 else f"{ratio:.2g}x"


def number_text(value: float) -> str:
    """Two significant digits: "0.26", "65", "4.7e-06" (an exponent outside [1e-3, 1e4))."""
    if value == 0 or not math.isfinite(value) or 1e-3 <= abs(value) < 1e4:
        return f"{value:.2g}"
    return f"{value:.1e}"


def same_order(a: float, b: float, *, factor: float = SAME_ORDER_FACTOR) -> bool:
    """Whether positive ``a`` and ``b`` lie within ``factor`` of each other (default 10)."""
    if not (a > 0 and b > 0 and math.isfinite(a) and math.isfinite(b)):
        return False
    return max(a, b) / min(a, b) <= factor


def order_words(a: float, b: float, *, factor: float = SAME_ORDER_FACTOR) -> str:
    """Whether ``a`` and ``b`` are of the same order, with the rule used."""
    if same_order(a, b, factor=factor):
        return f"the same order of magnitude (within a factor of {factor:g})"
    return f"not the same order of magnitude (more than a factor of {factor:g} apart)"


def seconds_text(seconds: float) -> str:
    """Seconds with two significant digits: "0.26 s", "2.6e-04 s"."""
    return f"{number_text(seconds)} s"


def compare_time(
    ours: float,
    paper: float,
    *,
    reference: str = "the paper's",
    per: str = "",
    rtol: float = TIE_RTOL,
) -> str:
    """Our time beside a reference time, the ratio and whether they are of the same order.

    ``compare_time(2.6e-4, 4e-6, per=" per step")`` is "2.6e-04 s per step, 65x slower
    than the paper's 4.0e-06 s: not the same order of magnitude (more than a factor of 10
    apart)".  Within ``rtol`` of each other the two are "as fast as" each other.
    """
    ratio = ours / paper
    if abs(ratio - 1.0) <= rtol:
        speed = f"as fast as (within {rtol:.0%} of)"
    elif ratio > 1.0:
        speed = f"{times(ratio)} slower than"
    else:
        speed = f"{times(1.0 / ratio)} faster than"
    return (
        f"{seconds_text(ours)}{per}, {speed} {reference} {seconds_text(paper)}: "
        f"{order_words(ours, paper)}"
    )


def which_is_better(
    name_a: str,
    a: float,
    name_b: str,
    b: float,
    *,
    lower_is_better: bool = True,
    rtol: float = TIE_RTOL,
    atol: float = 0.0,
) -> str | None:
    """The name of the better of two measured values; None for a tie or an undecidable pair.

    A tie: |a - b| <= max(rtol * max(|a|, |b|), atol).  An infinite value is the worse
    one (a diverged run); a NaN decides nothing.
    """
    if math.isnan(a) or math.isnan(b):
        return None
    if math.isfinite(a) and math.isfinite(b):
        if abs(a - b) <= max(rtol * max(abs(a), abs(b)), atol):
            return None
    elif a == b:
        return None
    a_better = a < b if lower_is_better else a > b
    return name_a if a_better else name_b


def compare_values(
    name_a: str,
    a: float,
    name_b: str,
    b: float,
    *,
    quantity: str,
    lower_is_better: bool = True,
    rtol: float = TIE_RTOL,
    atol: float = 0.0,
    unit: str = "",
    tie_rule: str | None = None,
) -> str:
    """A sentence naming the better of two values, both values beside it and the factor.

    ``compare_values("D-SSO", 1.8e-4, "elastic net", 1.1e-3, quantity="final MSE")`` is
    "D-SSO has the lower final MSE (1.8e-04 against elastic net's 0.0011, 6.1x lower)";
    a tie (see ``which_is_better``) says so, with the rule (``tie_rule`` words it).
    """
    winner = which_is_better(
        name_a, a, name_b, b, lower_is_better=lower_is_better, rtol=rtol, atol=atol
    )
    va, vb = f"{number_text(a)}{unit}", f"{number_text(b)}{unit}"
    if winner is None:
        if math.isnan(a) or math.isnan(b):
            return f"{name_a} and {name_b} cannot be compared on {quantity} ({va} and {vb})"
        rule = tie_rule or " or ".join(
            [f"within {rtol:.0%} of each other"] * (rtol > 0)
            + [f"within {atol:g}{unit}"] * (atol > 0)
        )
        return f"{name_a} and {name_b} tie on {quantity} ({va} and {vb}, {rule})"
    if winner == name_a:
        won, lost, loser, vw, vl = a, b, name_b, va, vb
    else:
        won, lost, loser, vw, vl = b, a, name_a, vb, va
    side = "lower" if lower_is_better else "higher"
    factor = ""
    if won * lost > 0 and math.isfinite(won) and math.isfinite(lost):
        factor = f", {times(max(abs(won), abs(lost)) / min(abs(won), abs(lost)))} {side}"
    return f"{winner} has the {side} {quantity} ({vw} against {loser}'s {vl}{factor})"


def as_in(reproduced: bool, document: str = "the paper") -> str:
    """ "as in the paper" or "unlike the paper"."""
    return f"as in {document}" if reproduced else f"unlike {document}"


def decade(value: float) -> int:
    """The order of magnitude of a positive value: floor(log10(value))."""
    return math.floor(math.log10(value))


def fill(text: str, width: int = 100) -> str:
    """``text`` wrapped to ``width`` columns."""
    return textwrap.fill(text, width=width)


def record_experiment(script: str, numbers: dict[str, Any], *, quick: bool, seconds: float) -> None:
    """Keep an experiment's numbers in benchmarks/experiments.json; rewrite benchmarks/README.md.

    The README's words are written from these numbers by the script's own
    ``report`` and ``conclusion`` (``table.experiments_section``), so what it
    says always follows from a recorded run.
    """
    import datetime
    import json
    import sys

    import table

    experiments = table.load_experiments()
    experiments[script] = {
        "command": " ".join(["python", f"benchmarks/{script}.py", *sys.argv[1:]]),
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "quick": quick,
        "seconds": seconds,
        "machine": table.machine(),
        "numbers": numbers,
    }
    table.atomic_write_text(table.EXPERIMENTS, json.dumps(experiments, indent=1) + "\n")
    table.write_benchmarks_readme()
