"""The enumeration's screening on an accelerator (``device="cuda"``) against the CPU.

The plant: A = I, n = 10, 40 generic sensors, s = 3; its verdict is decided by the
3,838,380 sets of 6 removed sensors (the sets closest to breaking ranked), and the level of 7
(18,643,560 sets) refines it.  Each level is timed around the enumeration's function for one
level (``_scan_level``), on the device and on the CPU, in the same run; the answer must be
the same JSON.  The figure is sets per second of the whole level: the device's screening
plus the CPU's share (the LAPACK decisions of the sets it does not prove, the proxies of the
closest sets, the transfers).  Without a usable device the script says why and gives no row.

    python benchmarks/bench_device.py [--device cuda|numpy] [--repeats N] [--kernel]
                                      [--profile FILE]

``--kernel`` also times the device's screening alone (``DeviceKernel.screen`` on batches of
2^20 matrices with their tops, as the enumeration sends them, the results back on the host);
``--profile FILE`` writes where the time of one level of 6 on the device goes (cProfile).

``--device numpy`` runs the accelerator's code on the CPU (to check the script without a GPU;
it is slower than the CPU path).
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from _common import row, yes_no

from ssecert import System
from ssecert.structure import enumeration
from ssecert.structure.device import DeviceUnavailable, resolve_device
from ssecert.structure.sparse import sparse_observability

CASE = "A = I, n = 10, p = 40, s = 3"
GOAL = 5e7  # sets per second on one H100, level 6


def _plant() -> System:
    return System(np.eye(10), np.random.default_rng(0).standard_normal((40, 10)))


def _run(device: str | None, levels: int) -> tuple[dict[int, float], str]:
    """(seconds of each level of removed sensors, the answer as JSON): the enumeration up to
    ``levels`` removed sensors (exact refinement, no time budget)."""
    scan, seconds = enumeration._scan_level, {}

    def timed(*args: Any, **kwargs: Any) -> Any:
        began = time.perf_counter()
        out = scan(*args, **kwargs)
        seconds[args[4]] = time.perf_counter() - began
        return out

    enumeration._scan_level = timed
    try:
        check = sparse_observability(
            _plant(),
            3,
            method="enumeration",
            time_budget=None,
            max_sets=_sets(levels),
            device=device,
        )
    finally:
        enumeration._scan_level = scan
    evidence = dict(check.evidence)
    evidence.pop("cost_estimate", None)
    answer = json.dumps([check.verdict.value, check.fields, evidence], sort_keys=True, default=str)
    return seconds, answer


def _sets(levels: int) -> int:
    return sum(math.comb(40, k) for k in range(levels + 1))


def _machine(device: str) -> str:
    if device == "cuda":
        try:
            import torch

            if torch.cuda.is_available():
                return f"{torch.cuda.get_device_name(0)} (PyTorch {torch.__version__})"
        except ImportError:
            pass
        import cupy

        props = cupy.cuda.runtime.getDeviceProperties(0)
        return f"{props['name'].decode()} (CuPy {cupy.__version__})"
    return f"the CPU through the accelerator's code ({platform.processor() or 'cpu'})"


@dataclass(frozen=True)
class Results:
    device: str
    machine: str
    cpu: dict[int, float]
    accelerated: dict[int, float]
    same: bool


def measure(device: str, repeats: int, levels: int = 7) -> Results:
    _run(device, 5)  # the library's start (CUDA's context, its kernels) is not timed
    cpu_runs, device_runs, same = [], [], True
    for _ in range(max(1, repeats)):
        seconds, cpu_answer = _run(None, levels)
        cpu_runs.append(seconds)
        seconds, device_answer = _run(device, levels)
        device_runs.append(seconds)
        same &= device_answer == cpu_answer
    best = {k: min(run[k] for run in cpu_runs) for k in cpu_runs[0]}
    faster = {k: min(run[k] for run in device_runs) for k in device_runs[0]}
    return Results(device, _machine(device), best, faster, same)


def kernel_rate(device: str, n: int = 10, repeats: int = 20) -> tuple[float, float]:
    """(sets per second, seconds) of the device's screening alone: batches of 2^20 random
    positive definite single-precision matrices (a level of 2^16 partial sums and 16 tops, as
    ``ColexScreen`` sends them), the failures sent back, the median of ``repeats`` screens
    after one not timed."""
    from ssecert.structure.device import DEVICE_BATCH_SETS, device_kernel

    kernel = device_kernel(device)
    rng = np.random.default_rng(1)
    M, N = 1 << 16, DEVICE_BATCH_SETS
    G = rng.standard_normal((M, n, n + 2)).astype(np.float32)
    level = kernel.load(np.ascontiguousarray((G @ G.transpose(0, 2, 1)).transpose(1, 2, 0)))
    steps = np.arange(1, N // M + 1, dtype=np.float32)
    tops = np.float32(0.1) * np.eye(n, dtype=np.float32)[:, :, None] * steps  # float32
    rows = np.arange(0, N, M)
    offsets = -rows  # each piece the whole level, plus its top
    failed = kernel.screen(level, rows, offsets, tops, N).failed()
    assert failed.size == 0, "positive definite matrices refused"
    seconds = []
    for _ in range(repeats):
        began = time.perf_counter()
        kernel.screen(level, rows, offsets, tops, N).failed()
        seconds.append(time.perf_counter() - began)
    median = float(np.median(seconds))
    return N / median, median


def library_rate(n: int = 10, repeats: int = 20) -> float | None:
    """Sets per second of PyTorch's own batched Cholesky (``torch.linalg.cholesky_ex``) on
    2^20 single-precision matrices already on the GPU (a reference for the screening alone:
    the matrices not assembled, nothing sent back), None without PyTorch and CUDA."""
    try:
        import torch
    except ImportError:
        return None
    if not torch.cuda.is_available():
        return None
    from ssecert.structure.device import DEVICE_BATCH_SETS

    g = torch.Generator(device="cuda").manual_seed(2)
    G = torch.randn((DEVICE_BATCH_SETS, n, n + 2), device="cuda", generator=g)
    A = G @ G.transpose(1, 2)
    torch.linalg.cholesky_ex(A)
    torch.cuda.synchronize()
    seconds = []
    for _ in range(repeats):
        began = time.perf_counter()
        torch.linalg.cholesky_ex(A)
        torch.cuda.synchronize()
        seconds.append(time.perf_counter() - began)
    return DEVICE_BATCH_SETS / float(np.median(seconds))


def profile(device: str, path: str) -> None:
    """cProfile of the enumeration up to level 6 on ``device``, the 40 largest cumulative
    times written to ``path``."""
    import cProfile
    import io
    import pstats

    _run(device, 5)
    profiler = cProfile.Profile()
    profiler.enable()
    _run(device, 6)
    profiler.disable()
    out = io.StringIO()
    pstats.Stats(profiler, stream=out).sort_stats("cumulative").print_stats(40)
    pstats.Stats(profiler, stream=out).sort_stats("tottime").print_stats(25)
    with open(path, "w") as f:
        f.write(out.getvalue())


def _level_note(r: Results, k: int) -> str:
    sets = math.comb(40, k)
    rate, cpu_rate = sets / r.accelerated[k], sets / r.cpu[k]
    role = "the verdict's level, the closest sets ranked" if k == 6 else "a refinement level"
    goal = ""
    if k == 6 and r.device == "cuda":
        goal = f"; goal {GOAL:.0e} sets/s: {'met' if rate >= GOAL else 'NOT met'}"
    return (
        f"{rate:,.0f} sets/s on {r.machine} against {cpu_rate:,.0f} on the CPU "
        f"({role}){goal}; same answer: {yes_no(r.same)}"
    )


def to_rows(r: Results) -> list[dict[str, Any]]:
    return [
        row(
            "accelerator screening vs CPU",
            f"{CASE}, level of {math.comb(40, k):,} sets of {k} removed, device {r.device}",
            r.accelerated[k],
            r.cpu[k],
            "CPU enumeration (numpy and LAPACK)",
            _level_note(r, k),
        )
        for k in sorted(r.accelerated)
        if k >= 6
    ]


def rows(quick: bool = False) -> list[dict[str, Any]]:
    """The rows on ``cuda`` where this machine has one, else none (the reason printed)."""
    try:
        resolve_device("cuda")
    except DeviceUnavailable as exc:
        print(f"bench_device: not run: {exc}")
        return []
    return to_rows(measure("cuda", 1 if quick else 3, levels=6 if quick else 7))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--device", default="cuda", choices=("cuda", "numpy"))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--levels", type=int, default=7, choices=(6, 7))
    parser.add_argument("--kernel", action="store_true", help="time the screening alone")
    parser.add_argument("--profile", metavar="FILE", help="where a level's time goes")
    args = parser.parse_args()
    try:
        resolve_device(args.device)
    except DeviceUnavailable as exc:
        raise SystemExit(f"bench_device: {exc}") from None
    print(f"device: {_machine(args.device)}")
    if args.kernel:
        rate, seconds = kernel_rate(args.device)
        print(f"screening alone: {rate:,.0f} sets/s (2^20 sets of n = 10 in {seconds:.4f} s)")
        library = library_rate() if args.device == "cuda" else None
        if library is not None:
            print(f"torch.linalg.cholesky_ex on 2^20 matrices on the GPU: {library:,.0f} sets/s")
    if args.profile:
        profile(args.device, args.profile)
    r = measure(args.device, args.repeats, args.levels)
    for k in sorted(r.accelerated):
        if k >= 6:
            print(
                f"{CASE}, {k} removed: {r.accelerated[k]:.3f} s against {r.cpu[k]:.3f} s on "
                f"the CPU; {_level_note(r, k)}"
            )
    if not r.same:
        raise SystemExit("the device's answer differs from the CPU's")


if __name__ == "__main__":
    main()
