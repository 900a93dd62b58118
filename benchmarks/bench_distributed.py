"""Enumeration on Dask workers against in-process, and the cost model against the clock.

One plant like the one that stopped users (A = I, n = 10, 30 generic sensors,
s = 3: the verdict needs every set of up to 6 sensors, 768,212 of them) is
decided in-process, then on LocalClusters of 1 and 2 single-thread worker
processes; each figure is a ratio against the in-process time measured in
the same run, and every run must give the same JSON answer.  The cost
model's estimate (``cost_estimate`` in the evidence, calibrated on this
machine) is printed beside the measured enumeration time, and the model
projects the sets of 10 of 60 sensors (C(60, 10), about 7.5e10) onto a
64-worker cluster.

    python benchmarks/bench_distributed.py [--repeats N]
"""

from __future__ import annotations

import argparse
import json
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from _common import best_of, cost_model_row, row, yes_no

from ssecert import System
from ssecert.parallel import dask_client
from ssecert.structure.cost import calibrate, level_seconds
from ssecert.structure.sparse import sparse_observability


def _plant() -> System:
    return System(np.eye(10), np.random.default_rng(0).standard_normal((30, 10)))


def _answer(check) -> str:
    fields = dict(check.fields)
    return json.dumps([check.verdict.value, fields], sort_keys=True, default=str)


def _timed(system: System, repeats: int, client=None) -> tuple[float, Any]:
    return best_of(
        lambda: sparse_observability(
            system, 3, method="enumeration", time_budget=0.0, client=client
        ),
        repeats,
    )


CASE = "A = I, n = 10, p = 30, s = 3"
PROJECTED_WORKERS = 64


@dataclass(frozen=True)
class Results:
    local: float
    cost: dict[str, Any]
    spread: dict[int, tuple[float, bool]]  # workers: (seconds, same answer)
    projected_sets: int
    projected_seconds: float  # on one core


def measure(repeats: int, workers: tuple[int, ...] = (1, 2)) -> Results:
    system = _plant()
    calibrate(system.n)  # measured once per process, as in a real run
    local = _timed(system, repeats)
    spread = {}
    for count in workers:
        with dask_client(workers=count) as client:
            _timed(system, 1, client)  # the workers import ssecert and calibrate once
            seconds, check = _timed(system, repeats, client)
        spread[count] = (seconds, _answer(check) == _answer(local[1]))
    return Results(
        local=local[0],
        cost=local[1].evidence["cost_estimate"],
        spread=spread,
        projected_sets=math.comb(60, 10),
        projected_seconds=level_seconds(60, 10, 10),
    )


def print_results(r: Results) -> None:
    cost = r.cost
    print(f"plant: {CASE}; {cost['sets_for_verdict']:,} sets for the verdict")
    print(
        f"in-process: {r.local:.2f} s (enumeration {cost['measured_seconds_for_verdict']:.2f} s; "
        f"cost model estimate {cost['seconds_for_verdict']:.2f} s, ratio measured/estimate "
        f"{cost['measured_seconds_for_verdict'] / cost['seconds_for_verdict']:.2f})"
    )
    for workers, (seconds, same) in r.spread.items():
        print(
            f"{workers} Dask worker{'s' if workers > 1 else ''}: {seconds:.2f} s, "
            f"{r.local / seconds:.2f}x in-process; same answer: {same}"
        )
    hours = r.projected_seconds / 3600
    print(
        f"projection: the {r.projected_sets:.2e} sets of 10 of 60 sensors (n = 10) would take "
        f"{hours:.0f} h on one core here, {hours / PROJECTED_WORKERS:.1f} h on "
        f"{PROJECTED_WORKERS} workers"
    )


def to_rows(r: Results) -> list[dict[str, Any]]:
    out = []
    for workers, (seconds, same) in r.spread.items():
        plural = "s" if workers > 1 else ""
        note = f"same answer: {yes_no(same)}; ratio > 1 means faster than in-process"
        out.append(
            row(
                "Dask workers vs in-process",
                f"{CASE}, {workers} worker{plural}",
                seconds,
                r.local,
                "in-process enumeration",
                note,
            )
        )
    out.append(cost_model_row(CASE + " (in-process)", r.cost))
    note = (
        f"not run: the cost model's rates measured in this run; {r.projected_seconds / 3600:.0f} h "
        f"on one core here"
    )
    out.append(
        row(
            "cost model projection",
            f"C(60, 10) = {r.projected_sets:.1e} sets, n = 10, {PROJECTED_WORKERS} workers",
            r.projected_seconds / PROJECTED_WORKERS,
            None,
            "-",
            note,
        )
    )
    return out


def rows(quick: bool = False) -> list[dict[str, Any]]:
    """The figures as table rows (quick: one timed run each instead of the best of 2)."""
    return to_rows(measure(1 if quick else 2))


def main(repeats: int) -> None:
    r = measure(repeats)
    print_results(r)
    if not all(same for _, same in r.spread.values()):
        raise SystemExit("the Dask answer differs from the in-process one")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=2)
    main(parser.parse_args().repeats)
