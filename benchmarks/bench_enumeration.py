"""Sparse-observability enumeration against the usual reference, in one run.

The reference is what Imhotep-SMT's enumeration and published Python code
do: loop over sensor sets and call numpy.linalg.matrix_rank on the stacked
observability matrix of the sensors kept.  Both decide the same sets: every
set of 2s removed sensors of a random plant like the thesis's (n = 15,
p = 30, s = 3: all 593,775 sets of 6 sensors).  The reference is timed on a
sample of the sets (it would take about 40 s for all); ssecert decides every
set, without the pruning its sparse_observability applies (which answers
this plant without enumerating anything).  A second plant of the same size,
with many breaking sets and a well-conditioned observability matrix (so that
the reference's ranks can be trusted), checks that both decide alike.

The eigenspace method is timed against the enumeration on a plant where
both must work: distinct integer eigenvalues, each sensor seeing about half
of the modes (so no sensor alone observes the state and nothing is pruned),
exact integer data; both are asked for the verdict only (time budget 0), so
the enumeration checks every set of up to 2s = 6 sensors.  Also timed: the
eigenspace method on a generic n = 50, p = 1000 plant, where the
enumeration (C(1000, 6) sets) is out of reach.

The refinement past the verdict against its time budget: static plants
(A = I, n = 10) with 20 and 26 generic sensors, s = 2, where every set of
p - 9 removed sensors breaks the plant (the kept rows cannot span the
state): the seconds of the check beside the budget it was given, and what
it answered (the exact max_removable, or a lower bound and where the budget
stopped it).

    python benchmarks/bench_enumeration.py [--sample N] [--repeat N]
"""

from __future__ import annotations

import argparse
import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from _common import best_of, cost_model_row, row, yes_no

from ssecert import System, scan_removals, sparse_observability
from ssecert.examples import load_example
from ssecert.structure.sparse import DEFAULT_TIME_BUDGET


def reference(system: System, sets: list[tuple[int, ...]]) -> list[tuple[int, ...]]:
    """matrix_rank of the stacked observability matrix of the kept sensors, per set."""
    n, p = system.n, system.p
    blocks = system.sensor_blocks(n)  # (p, n, n)
    breaking = []
    for removed in sets:
        keep = np.setdiff1d(np.arange(p), removed)
        O = blocks[keep].reshape(-1, n)
        if np.linalg.matrix_rank(O) < n:
            breaking.append(removed)
    return breaking


def _unimodular(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """An integer change of coordinates T and its integer inverse (n random row operations), so
    that T M T^-1 keeps integer data exact."""
    T = np.eye(n)
    for _ in range(n):
        i, j = rng.choice(n, 2, replace=False)
        T[i] += rng.choice([-1.0, 1.0]) * T[j]
    T_inv = np.round(np.linalg.inv(T))
    assert np.array_equal(T @ T_inv, np.eye(n))
    return T, T_inv


def structured_plant(seed: int = 0, n_rot: int = 7, p: int = 30) -> System:
    """n = 15 plant with many breaking sets of 6 sensors, exact in floating point.

    Integer blocks [[a, -b], [b, a]] (distinct complex eigenvalue pairs) plus
    one eigenvalue 1, under an integer similarity with an integer inverse, so
    that A and C are exact integers: the sensor sets that break the plant
    break its exact data, and the reference's matrix_rank and ssecert's exact
    confirmation can agree.  Each sensor sees each mode with probability 0.2.
    """
    from scipy.linalg import block_diag

    rng = np.random.default_rng(seed)
    pairs = [(1, 1), (1, 2), (2, 1), (0, 1), (0, 2), (-1, 1), (-1, 2)][:n_rot]
    blocks = [np.array([[a, -b], [b, a]], dtype=float) for a, b in pairs]
    M = block_diag(*blocks, [[1.0]])
    n = M.shape[0]
    Cm = rng.integers(-3, 4, size=(p, n)).astype(float)
    Cm[Cm == 0] = 1.0
    sees = rng.random((p, n_rot + 1)) < 0.2
    for j in range(n_rot):
        Cm[~sees[:, j], 2 * j : 2 * j + 2] = 0.0
    Cm[~sees[:, n_rot], -1] = 0.0
    T, T_inv = _unimodular(rng, n)
    return System(T @ M @ T_inv, Cm @ T_inv, name="structured-n15-p30")


def modal_plant(seed: int = 0, n: int = 10, p: int = 30, sees: float = 0.5) -> System:
    """Distinct integer eigenvalues, each sensor seeing about half of the modes, exact data.

    A = T diag(-4, ..., 5) T^-1 with an integer T of integer inverse, and
    C = C_modes T^-1 with integer entries: no sensor alone observes the
    state, every mode is seen by many sensors, and the breaking sets of the
    floating-point data are those of the exact data.
    """
    rng = np.random.default_rng(seed)
    M = np.diag(np.arange(1, n + 1) - n // 2).astype(float)
    Cm = rng.integers(-3, 4, size=(p, n)).astype(float)
    Cm[Cm == 0] = 1.0
    Cm[rng.random((p, n)) >= sees] = 0.0
    T, T_inv = _unimodular(rng, n)
    return System(T @ M @ T_inv, Cm @ T_inv, name=f"modal-n{n}-p{p}")


def identity_plant(n: int = 10, p: int = 20, seed: int = 0) -> System:
    """A = I with p generic sensors: removing any p - n + 1 of them breaks the plant, every set
    of that level failing the screening, and no smaller set does."""
    rng = np.random.default_rng(seed)
    return System(np.eye(n), rng.standard_normal((p, n)), name=f"identity-n{n}-p{p}")


@dataclass(frozen=True)
class Budgeted:
    """One sparse_observability call with a time budget: its seconds and what it answered."""

    label: str
    budget: float
    seconds: float  # the whole check (the budget counts from the enumeration's start)
    refinement: float  # past the verdict
    verdict: str
    max_removable: int | None
    lower_bound: bool
    stopped: dict[str, Any] | None


def budgeted(system: System, s: int, budget: float, label: str) -> Budgeted:
    timing: dict[str, float] = {}
    check = sparse_observability(system, s, time_budget=budget, timing=timing)
    return Budgeted(
        label=label,
        budget=budget,
        seconds=timing["seconds"],
        refinement=timing["refinement_seconds"],
        verdict=check.verdict.value,
        max_removable=check.fields["max_removable"],
        lower_bound=bool(check.fields.get("max_removable_is_lower_bound")),
        stopped=check.evidence.get("stopped_by_time_budget"),
    )


def measure_budgets() -> list[Budgeted]:
    """The refinement against its time budget on the static plants."""
    out = []
    for p, budgets in ((20, (5.0, 1.0, 0.0)), (26, (5.0, 1.0))):
        system = identity_plant(p=p)
        label = f"{system.name} (A = I, s = 2; every set of {p - 9} breaks it)"
        out.extend(budgeted(system, 2, budget, label) for budget in budgets)
    return out


def _answer(b: Budgeted) -> str:
    text = f"{b.verdict}, max_removable {'>= ' if b.lower_bound else '= '}{b.max_removable}"
    if b.stopped is not None and "level_sets_checked" in b.stopped:
        text += (
            f", stopped after {b.stopped['level_sets_checked']:,} of the "
            f"{b.stopped['level_sets']:,} sets of {b.stopped['level_removed_sensors']} sensors"
        )
    elif b.stopped is not None:
        text += f", the {b.stopped['next_level_sets']:,} sets of the next level not started"
    return text


@dataclass(frozen=True)
class Comparison:
    """Enumeration against the per-set matrix_rank loop on one plant."""

    label: str
    size: int
    total: int
    sampled: int
    reference_per_set: float
    ssecert_per_set: float
    breaking: int
    reference_breaking: int
    ssecert_breaking: int
    agree: bool


def compare(system: System, size: int, sample_size: int, repeat: int, label: str) -> Comparison:
    """Time both on one plant and check that their decisions agree on the sample."""
    total = math.comb(system.p, size)
    rng = np.random.default_rng(0)
    all_sets = list(itertools.combinations(range(system.p), size))
    sample = [all_sets[i] for i in rng.choice(total, min(sample_size, total), replace=False)]
    ref_seconds, ref_breaking = best_of(lambda: reference(system, sample), repeat)
    ours_seconds, scan = best_of(lambda: scan_removals(system, size, prune=False), repeat)
    assert scan.checked == total
    ours_on_sample = sorted(set(scan.breaking_sets) & set(sample))
    return Comparison(
        label=label,
        size=size,
        total=total,
        sampled=len(sample),
        reference_per_set=ref_seconds / len(sample),
        ssecert_per_set=ours_seconds / scan.checked,
        breaking=len(scan.breaking_sets),
        reference_breaking=len(ref_breaking),
        ssecert_breaking=len(ours_on_sample),
        agree=ours_on_sample == sorted(ref_breaking),
    )


def print_comparison(c: Comparison) -> None:
    ref, ours = c.reference_per_set, c.ssecert_per_set
    print(f"{c.label}: {c.total:,} sets of {c.size} removed sensors")
    print(
        f"  {'reference: matrix_rank per set (sampled)':<46} {ref * 1e6:9.2f} us/set "
        f"{1 / ref:12,.0f} sets/s"
    )
    print(
        f"  {'ssecert enumeration (every set, no pruning)':<46} {ours * 1e6:9.2f} us/set "
        f"{1 / ours:12,.0f} sets/s"
    )
    print(
        f"  speed-up per set: {ref / ours:.1f}x (target >= 30x); breaking sets: "
        f"{c.breaking:,} of {c.total:,} (sample: {c.reference_breaking} by the "
        f"reference, {c.ssecert_breaking} by ssecert); decisions agree: {c.agree}"
    )


@dataclass(frozen=True)
class Decision:
    """One sparse_observability call: its answer and the best of its times."""

    seconds: float
    verdict: str
    max_removable: int | None
    lower_bound: bool
    method: str
    cost: dict[str, Any] | None


def decide(
    system: System, s: int, method: str, repeat: int, time_budget: float | None = 0.0
) -> Decision:
    """Best of ``repeat`` calls; time budget 0 asks for the verdict only."""
    seconds, check = best_of(
        lambda: sparse_observability(system, s, method=method, time_budget=time_budget), repeat
    )
    return Decision(
        seconds=seconds,
        verdict=check.verdict.value,
        max_removable=check.fields["max_removable"],
        lower_bound=bool(check.fields.get("max_removable_is_lower_bound")),
        method=check.method,
        cost=check.evidence.get("cost_estimate"),
    )


@dataclass(frozen=True)
class Results:
    comparisons: list[Comparison]
    auto: Decision
    modal_label: str
    modal_eigenspace: Decision
    modal_enumeration: Decision
    big_label: str
    big_sets: int
    big_eigenspace: Decision
    budgets: list[Budgeted]


def measure(*, sample: int, repeat: int) -> Results:
    spec = load_example("random-n15-p30")
    system, s = spec.system, spec.max_attacked
    size = 2 * s
    comparisons = [
        compare(system, size, sample, repeat, f"{spec.name} (n = 15, p = 30, s = {s})"),
        compare(
            structured_plant(),
            size,
            sample,
            repeat,
            "structured-n15-p30 (rotations, sparse sensor patterns)",
        ),
    ]
    auto = decide(system, s, "auto", 1, time_budget=DEFAULT_TIME_BUDGET)
    modal = modal_plant()
    rng = np.random.default_rng(1)
    big = System(rng.standard_normal((50, 50)), rng.standard_normal((1000, 50)))
    return Results(
        comparisons=comparisons,
        auto=auto,
        modal_label=f"{modal.name} (n = 10, p = 30, s = 3, exact integer data)",
        modal_eigenspace=decide(modal, 3, "eigenspace", repeat),
        modal_enumeration=decide(modal, 3, "enumeration", repeat),
        big_label="generic n = 50, p = 1000, s = 3",
        big_sets=math.comb(1000, 6),
        big_eigenspace=decide(big, 3, "eigenspace", repeat),
        budgets=measure_budgets(),
    )


def _removable(d: Decision) -> str:
    return f"{'>= ' if d.lower_bound else ''}{d.max_removable}"


def print_results(r: Results) -> None:
    for c in r.comparisons:
        print_comparison(c)
    print(
        f"sparse_observability(auto) on this plant: {r.auto.verdict}, max_removable = "
        f"{r.auto.max_removable}, method {r.auto.method}, {r.auto.seconds * 1e3:.1f} ms"
    )
    eig, enum = r.modal_eigenspace, r.modal_enumeration
    print(
        f"{r.modal_label}, verdict only: eigenspace {eig.verdict} (max_removable "
        f"{_removable(eig)}) in {eig.seconds:.3f} s; enumeration {enum.verdict} (max_removable "
        f"{_removable(enum)}) in {enum.seconds:.3f} s; {enum.seconds / eig.seconds:.1f}x"
    )
    big = r.big_eigenspace
    print(
        f"eigenspace method, {r.big_label}: {big.verdict}, max_removable = "
        f"{big.max_removable}, {big.seconds:.3f} s (target < 1 s)"
    )
    for b in r.budgets:
        print(
            f"{b.label}, time budget {b.budget:g} s: {b.seconds:.3f} s (refinement "
            f"{b.refinement:.3f} s); {_answer(b)}"
        )


def to_rows(r: Results) -> list[dict[str, Any]]:
    out = []
    for c in r.comparisons:
        note = (
            f"reference timed on {c.sampled:,} random sets and extrapolated; ssecert decides "
            f"every set; decisions agree on the sample: {yes_no(c.agree)} "
            f"({c.breaking:,} breaking sets in all)"
        )
        out.append(
            row(
                "enumeration vs rank loop",
                f"{c.label}: {c.total:,} sets of {c.size}",
                c.ssecert_per_set * c.total,
                c.reference_per_set * c.total,
                "numpy matrix_rank per set",
                note,
            )
        )
    eig, enum = r.modal_eigenspace, r.modal_enumeration
    same = eig.verdict == enum.verdict
    note = (
        f"verdict only (time budget 0); same verdict: {yes_no(same)} ({eig.verdict}); "
        f"max_removable {_removable(eig)} (eigenspace), {_removable(enum)} (enumeration)"
    )
    out.append(
        row(
            "eigenspace vs enumeration",
            r.modal_label,
            eig.seconds,
            enum.seconds,
            "enumeration (every set of up to 6)",
            note,
        )
    )
    big = r.big_eigenspace
    note = (
        f"{big.verdict}, max_removable = {big.max_removable}; no reference: the enumeration "
        f"would check C(1000, 6) = {r.big_sets:.1e} sets"
    )
    out.append(row("eigenspace vs enumeration", r.big_label, big.seconds, None, "-", note))
    if enum.cost is not None:
        out.append(cost_model_row(r.modal_label, enum.cost))
    for b in r.budgets:
        note = f"{_answer(b)}; refinement {b.refinement:.3g} s"
        if b.budget == 0:
            # the verdict only: no refinement, nothing to compare the seconds with
            out.append(row("refinement vs time budget", f"{b.label}, budget 0", b.seconds,
                           None, "-", note))  # fmt: skip
            continue
        out.append(
            row(
                "refinement vs time budget",
                f"{b.label}, budget {b.budget:g} s",
                b.seconds,
                b.budget,
                "the time budget (seconds allowed)",
                note,
            )
        )
    return out


def rows(quick: bool = False) -> list[dict[str, Any]]:
    """The figures as table rows (quick: a smaller sample and the best of 2)."""
    results = measure(sample=2000, repeat=2) if quick else measure(sample=20000, repeat=3)
    return to_rows(results)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--sample", type=int, default=20000, help="sets timed for the reference (default 20000)"
    )
    parser.add_argument("--repeat", type=int, default=3, help="timing repetitions (best of)")
    args = parser.parse_args()
    print_results(measure(sample=args.sample, repeat=args.repeat))


if __name__ == "__main__":
    main()
