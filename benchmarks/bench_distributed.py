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

A second plant has a verdict level of more than 10^6 sets (A = I, n = 10,
40 generic sensors, s = 3: the 3,838,380 sets of 6 removed sensors decide
it): its enumeration (``measured_seconds_for_verdict``) on 2 workers against
in-process, with the machine's own ceiling measured in the same run: the
same in-process check run by two processes at once, each timed (on two
cores that share caches and memory, two copies do not run at full speed).

    python benchmarks/bench_distributed.py [--repeats N]
"""

from __future__ import annotations

import argparse
import json
import math
import time
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
BIG_CASE = "A = I, n = 10, p = 40, s = 3"
BIG_LEVEL = math.comb(40, 6)
GOAL = 1.6  # 2 workers against in-process on a level of more than 10^6 sets


def _big_plant() -> System:
    return System(np.eye(10), np.random.default_rng(0).standard_normal((40, 10)))


def _enumeration_seconds(client=None) -> tuple[float, float, Any]:
    """(the big plant's enumeration seconds to its verdict, those of its level of 6 removed
    sensors, the check).  The level is timed around the enumeration's own function for one
    level (``_scan_level``, wrapped for the call)."""
    from ssecert.structure import enumeration

    scan, seconds = enumeration._scan_level, {}

    def timed(*args: Any, **kwargs: Any) -> Any:
        began = time.perf_counter()
        out = scan(*args, **kwargs)
        seconds[args[4]] = time.perf_counter() - began  # args[4]: the sets' size
        return out

    enumeration._scan_level = timed
    try:
        check = sparse_observability(
            _big_plant(), 3, method="enumeration", time_budget=0.0, client=client
        )
    finally:
        enumeration._scan_level = scan
    whole = check.evidence["cost_estimate"]["measured_seconds_for_verdict"]
    return whole, seconds[6], check


def _concurrent(_: int) -> float:
    calibrate(10)
    return _enumeration_seconds()[0]


def _two_at_once() -> float:
    """The longer of the enumeration seconds of two in-process checks run at the same time by
    two forked processes."""
    import multiprocessing

    with multiprocessing.get_context("fork").Pool(2) as pool:
        return max(pool.map(_concurrent, range(2)))


@dataclass(frozen=True)
class Big:
    local: float  # the level in-process
    dask: float  # the level on 2 workers
    local_whole: float  # the enumeration to the verdict
    dask_whole: float
    same: bool
    two_at_once: float  # the enumeration of each of two in-process copies run at once


def measure_big(repeats: int) -> Big:
    """The best of ``repeats`` rounds, each round in-process, on 2 workers and two copies at
    once, one after the other (a busy spell slows all three)."""
    calibrate(10)
    local: list[tuple[float, float]] = []
    dask: list[tuple[float, float]] = []
    both = []
    with dask_client(workers=2) as client:
        _enumeration_seconds(client)  # the workers import ssecert and calibrate once
        for _ in range(max(1, repeats)):
            *seconds, alone = _enumeration_seconds()
            local.append((seconds[1], seconds[0]))
            *seconds, spread = _enumeration_seconds(client)
            dask.append((seconds[1], seconds[0]))
            both.append(_two_at_once())
    return Big(
        local=min(level for level, _ in local),
        dask=min(level for level, _ in dask),
        local_whole=min(whole for _, whole in local),
        dask_whole=min(whole for _, whole in dask),
        same=_answer(alone) == _answer(spread),
        two_at_once=min(both),
    )


@dataclass(frozen=True)
class Results:
    local: float
    cost: dict[str, Any]
    spread: dict[int, tuple[float, bool]]  # workers: (seconds, same answer)
    projected_sets: int
    projected_seconds: float  # on one core
    big: Big | None = None


def measure(repeats: int, workers: tuple[int, ...] = (1, 2), big: bool = True) -> Results:
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
        big=measure_big(max(repeats, 3)) if big else None,
    )


def _big_note(b: Big) -> str:
    ceiling = 2 * b.local_whole / b.two_at_once
    verdict = "met" if b.local / b.dask >= GOAL else "NOT met"
    return (
        f"same answer: {yes_no(b.same)}; the level of 6 removed sensors alone, best of a few "
        f"rounds; goal {GOAL}x: {verdict}; the whole enumeration to the verdict (the smaller "
        f"levels run in-process either way): {b.dask_whole:.2f} s against "
        f"{b.local_whole:.2f} s ({b.local_whole / b.dask_whole:.2f}x); the machine's ceiling "
        f"in the same run: two in-process copies at once took {b.two_at_once:.2f} s each, "
        f"{ceiling:.2f}x the work of one in the time of one"
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
    if r.big is not None:
        b = r.big
        print(
            f"{BIG_CASE}: in-process {b.local:.2f} s, 2 Dask workers {b.dask:.2f} s "
            f"({b.local / b.dask:.2f}x); {_big_note(b)}"
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
    if r.big is not None:
        out.append(
            row(
                "Dask workers vs in-process",
                f"{BIG_CASE}, a level of {BIG_LEVEL:,} sets, 2 workers",
                r.big.dask,
                r.big.local,
                "in-process enumeration",
                _big_note(r.big),
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
    if not all(same for _, same in r.spread.values()) or (r.big and not r.big.same):
        raise SystemExit("the Dask answer differs from the in-process one")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=2)
    main(parser.parse_args().repeats)
