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
import time

import numpy as np

from ssecert import System
from ssecert.parallel import dask_client
from ssecert.structure.cost import calibrate, level_seconds
from ssecert.structure.sparse import sparse_observability


def _plant() -> System:
    return System(np.eye(10), np.random.default_rng(0).standard_normal((30, 10)))


def _answer(check) -> str:
    fields = dict(check.fields)
    return json.dumps([check.verdict.value, fields], sort_keys=True, default=str)


def _timed(system: System, client=None) -> tuple[float, object]:
    start = time.perf_counter()
    check = sparse_observability(system, 3, method="enumeration", time_budget=0.0, client=client)
    return time.perf_counter() - start, check


def main(repeats: int) -> None:
    system = _plant()
    calibrate(system.n)  # measured once per process, as in a real run
    local = min(_timed(system) for _ in range(repeats))
    cost = local[1].evidence["cost_estimate"]
    print(
        f"plant: A = I (n = 10), p = 30, s = 3; {cost['sets_for_verdict']:,} sets for the verdict"
    )
    print(
        f"in-process: {local[0]:.2f} s (enumeration {cost['measured_seconds_for_verdict']:.2f} s; "
        f"cost model estimate {cost['seconds_for_verdict']:.2f} s, ratio measured/estimate "
        f"{cost['measured_seconds_for_verdict'] / cost['seconds_for_verdict']:.2f})"
    )
    for workers in (1, 2):
        with dask_client(workers=workers) as client:
            _timed(system, client)  # the workers import ssecert and calibrate once
            spread = min(_timed(system, client) for _ in range(repeats))
        same = _answer(spread[1]) == _answer(local[1])
        print(
            f"{workers} Dask worker{'s' if workers > 1 else ''}: {spread[0]:.2f} s, "
            f"{local[0] / spread[0]:.2f}x in-process; same answer: {same}"
        )
        if not same:
            raise SystemExit("the Dask answer differs from the in-process one")
    sets = math.comb(60, 10)
    seconds = level_seconds(60, 10, 10)
    print(
        f"projection: the {sets:.2e} sets of 10 of 60 sensors (n = 10) would take "
        f"{seconds / 3600:.0f} h on one core here, {seconds / 64 / 3600:.1f} h on 64 workers"
    )


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=2)
    main(parser.parse_args().repeats)
