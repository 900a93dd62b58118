"""What the analysis context saves in one ``certify`` run, on the packaged examples.

One ``certify`` run builds the observer once (the checks and the simulations
share it) and decides sparse observability once (the stealthy scenarios
replay the certificate's witness).  Without the context each consumer did
that work again.  This script counts the calls in one run and times one call
of each, so the saving is "calls avoided x time per call", measured in the
same run:

    python benchmarks/bench_computed_once.py

Without the context, the observer checks and the simulations each built the
observer (one build avoided when there is an observer), and each stealthy
scenario decided sparse observability again (one decision avoided per
stealthy scenario).  The saving is small on these plants because their gains
and enumerations are cheap; it grows with the plant (a deadbeat gain's exact construction, an
enumeration over many sensor sets), and it removes the chance that the
simulated stealthy attack differs from the one the certificate reports.
"""

from __future__ import annotations

import importlib
import time
from dataclasses import dataclass
from typing import Any

from _common import row

MODULES = (
    "ssecert.certify",
    "ssecert.analyze",
    "ssecert.simulation.engine",
    "ssecert.stability.checks",
    "ssecert.structure.sparse",
    "ssecert.observers",
)


@dataclass(frozen=True)
class ExampleResult:
    example: str
    builds: int
    sparse: int
    per_build: float
    per_sparse: float
    certify: float
    avoided_builds: int
    avoided_sparse: int

    @property
    def saved(self) -> float:
        return self.avoided_builds * self.per_build + self.avoided_sparse * self.per_sparse


def measure(examples: tuple[str, ...] = ("ugv", "random-n15-p30")) -> list[ExampleResult]:
    """One certify run per example, counting and timing the calls the context shares."""
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
    results = []
    try:
        for example in examples:
            spec = load_example(example)
            calls.clear()
            seconds.clear()
            start = time.perf_counter()
            certify(spec, seed=0)
            total = time.perf_counter() - start
            builds, sparse = calls.get("build_observer", 0), calls.get("sparse_observability", 0)
            stealthy = sum(sc["attack"] == "stealthy" for sc in spec.scenarios)
            results.append(
                ExampleResult(
                    example=example,
                    builds=builds,
                    sparse=sparse,
                    per_build=seconds.get("build_observer", 0.0) / max(builds, 1),
                    per_sparse=seconds.get("sparse_observability", 0.0) / max(sparse, 1),
                    certify=total,
                    avoided_builds=1 if builds else 0,
                    avoided_sparse=stealthy if builds else 0,
                )
            )
    finally:
        for module in modules.values():
            for name, original in originals.items():
                if hasattr(module, name):
                    setattr(module, name, original)
    return results


def print_results(results: list[ExampleResult]) -> None:
    print(
        f"{'example':16} {'builds':>6} {'sparse':>6} {'per build (s)':>13} "
        f"{'per sparse (s)':>14} {'certify (s)':>11} {'saved (s)':>9}"
    )
    for r in results:
        print(
            f"{r.example:16} {r.builds:>6} {r.sparse:>6} {r.per_build:>13.4f} "
            f"{r.per_sparse:>14.4f} {r.certify:>11.2f} {r.saved:>9.4f}"
        )
    print(
        "without the context, each run made the avoided calls again: one more observer build "
        "when there is an observer, one more sparse decision per stealthy scenario; "
        "saved = avoided calls x time per call"
    )


def to_rows(results: list[ExampleResult]) -> list[dict[str, Any]]:
    out = []
    for r in results:
        note = (
            f"reference = this run + the calls it avoided, timed in it ({r.avoided_builds} "
            f"observer build, {r.avoided_sparse} sparse decision): saved {r.saved:.2g} s"
        )
        out.append(
            row(
                "shared analysis context",
                f"certify {r.example}",
                r.certify,
                r.certify + r.saved,
                "certify without the context",
                note,
            )
        )
    return out


def rows(quick: bool = False) -> list[dict[str, Any]]:
    """The figures as table rows (the same run, quick or not: it takes a few seconds)."""
    return to_rows(measure())


def main() -> None:
    print_results(measure())


if __name__ == "__main__":
    main()
