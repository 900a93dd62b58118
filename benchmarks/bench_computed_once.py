"""What the analysis context saves in one ``certify`` run, on the packaged examples.

One ``certify`` run builds the observer once (the checks and the simulations
share it) and decides sparse observability once (the stealthy scenarios
replay the certificate's witness).  Without the context each consumer did
that work again.  This script counts the calls in one run and times one call
of each, so the saving is "calls avoided x time per call", measured in the
same run:

    python benchmarks/bench_computed_once.py

Measured on the development machine (2 cores, Python 3.11, another job running):

    example          observer builds  sparse decisions  saved (s)  certify (s)
    ugv              1 (was 2)        1 (was 2)         0.011      3.1
    random-n15-p30   0 (was 0)        1 (was 1)         0            0.7

The saving is small on these plants because their gains and enumerations are
cheap; it grows with the plant (a deadbeat gain's exact construction, an
enumeration over many sensor sets), and it removes the chance that the
simulated stealthy attack differs from the one the certificate reports.
"""

from __future__ import annotations

import importlib
import time

MODULES = (
    "ssecert.certify",
    "ssecert.analyze",
    "ssecert.simulation.engine",
    "ssecert.stability.checks",
    "ssecert.structure.sparse",
    "ssecert.observers",
)


def main() -> None:
    from ssecert.examples import load_example

    modules = {name: importlib.import_module(name) for name in MODULES}
    originals = {
        "sparse_observability": modules["ssecert.structure.sparse"].sparse_observability,
        "build_observer": modules["ssecert.observers"].build_observer,
    }
    calls: dict[str, int] = {}
    seconds: dict[str, float] = {}

    def counting(name):
        def wrapped(*args, **kwargs):
            start = time.perf_counter()
            try:
                return originals[name](*args, **kwargs)
            finally:
                calls[name] = calls.get(name, 0) + 1
                seconds[name] = seconds.get(name, 0.0) + time.perf_counter() - start

        return wrapped

    for module in modules.values():
        for name in originals:
            if hasattr(module, name):
                setattr(module, name, counting(name))
    certify = modules["ssecert.certify"].certify
    print(
        f"{'example':16} {'builds':>6} {'sparse':>6} {'per build (s)':>13} "
        f"{'per sparse (s)':>14} {'certify (s)':>11}"
    )
    for example in ("ugv", "random-n15-p30"):
        spec = load_example(example)
        calls.clear()
        seconds.clear()
        start = time.perf_counter()
        certify(spec, seed=0)
        total = time.perf_counter() - start
        builds, sparse = calls.get("build_observer", 0), calls.get("sparse_observability", 0)
        per_build = seconds.get("build_observer", 0.0) / max(builds, 1)
        per_sparse = seconds.get("sparse_observability", 0.0) / max(sparse, 1)
        print(
            f"{example:16} {builds:>6} {sparse:>6} {per_build:>13.4f} {per_sparse:>14.4f} "
            f"{total:>11.2f}"
        )
    print(
        "without the context, ugv's run made one more observer build and one more sparse "
        "decision (its stealthy scenario re-decided it): saved = per build + per sparse"
    )


if __name__ == "__main__":
    main()
