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
the reference's ranks can be trusted), checks that both decide alike.  Also
timed: the eigenspace method on a generic n = 50, p = 1000 plant.

    python benchmarks/bench_enumeration.py [--sample N]
"""

from __future__ import annotations

import argparse
import itertools
import math
import time

import numpy as np

from ssecert import System, scan_removals, sparse_observability
from ssecert.examples import load_example


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
    T = np.eye(n)
    for _ in range(n):
        i, j = rng.choice(n, 2, replace=False)
        T[i] += rng.choice([-1.0, 1.0]) * T[j]
    T_inv = np.round(np.linalg.inv(T))
    assert np.array_equal(T @ T_inv, np.eye(n))
    return System(T @ M @ T_inv, Cm @ T_inv, name="structured-n15-p30")


def compare(system: System, size: int, sample_size: int, repeat: int, label: str) -> float:
    """Time both on one plant; print a row and check that decisions agree."""
    total = math.comb(system.p, size)
    rng = np.random.default_rng(0)
    all_sets = list(itertools.combinations(range(system.p), size))
    sample = [all_sets[i] for i in rng.choice(total, min(sample_size, total), replace=False)]
    ref_times, ours_times = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        ref_breaking = reference(system, sample)
        ref_times.append((time.perf_counter() - t0) / len(sample))
        t0 = time.perf_counter()
        scan = scan_removals(system, size, prune=False)
        ours_times.append((time.perf_counter() - t0) / scan.checked)
    assert scan.checked == total
    ref, ours = min(ref_times), min(ours_times)
    ours_on_sample = sorted(set(scan.breaking_sets) & set(sample))
    agree = ours_on_sample == sorted(ref_breaking)
    print(f"{label}: {total:,} sets of {size} removed sensors")
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
        f"{len(scan.breaking_sets):,} of {total:,} (sample: {len(ref_breaking)} by the "
        f"reference, {len(ours_on_sample)} by ssecert); decisions agree: {agree}"
    )
    return ref / ours


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--sample", type=int, default=20000, help="sets timed for the reference (default 20000)"
    )
    parser.add_argument("--repeat", type=int, default=3, help="timing repetitions (best of)")
    args = parser.parse_args()

    spec = load_example("random-n15-p30")
    system, s = spec.system, spec.max_attacked
    size = 2 * s
    compare(system, size, args.sample, args.repeat, f"{spec.name} (n = 15, p = 30, s = {s})")
    compare(
        structured_plant(),
        size,
        args.sample,
        args.repeat,
        "structured-n15-p30 (rotations, sparse sensor patterns)",
    )

    t0 = time.perf_counter()
    check = sparse_observability(system, s)
    t_auto = time.perf_counter() - t0
    print(
        f"sparse_observability(auto) on this plant: {check.verdict.value}, max_removable = "
        f"{check.fields['max_removable']}, method {check.method}, {t_auto * 1e3:.1f} ms"
    )

    rng = np.random.default_rng(1)
    big = System(rng.standard_normal((50, 50)), rng.standard_normal((1000, 50)))
    times = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        check = sparse_observability(big, 3, method="eigenspace")
        times.append(time.perf_counter() - t0)
    print(
        f"eigenspace method, generic n = 50, p = 1000, s = 3: {check.verdict.value}, "
        f"max_removable = {check.fields['max_removable']}, {min(times):.3f} s (target < 1 s)"
    )


if __name__ == "__main__":
    main()
