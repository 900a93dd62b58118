"""What installing ssecert costs a pytest run that does not use it: the plugin's start-up.

pytest imports every installed plugin when it starts, so ssecert's plugin is
imported by every pytest run in an environment where ssecert is installed.
This script runs pytest on a directory with one trivial test, with the
plugin and without it (``-p no:ssecert``), in turn, and reports the median of
the per-pair ratios of wall-clock times and of CPU times (user + system of
the pytest process; pairing keeps the ratio meaningful when a shared
machine's speed drifts during the run, and CPU time is less moved by other
jobs than wall-clock time); the goal is a ratio within 10% of 1.  It also
lists the heavy modules that importing the plugin pulls in (none is the
goal) and the time ``import ssecert`` takes, which the plugin used to pay at
every start:

    python benchmarks/plugin_startup.py [--runs N]

The ratio is with / without; no test asserts on times.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from _common import row

HEAVY = ("numpy", "scipy", "control", "cvxpy", "sympy", "matplotlib", "hypothesis", "ssecert")
TRIVIAL_TEST = "def test_nothing():\n    assert True\n"


def _environment() -> dict[str, str]:
    # a user's shell: none of this project's pytest or hypothesis settings
    return {k: v for k, v in os.environ.items() if not k.startswith(("PYTEST_", "HYPOTHESIS_"))}


def _seconds(command: list[str], cwd: Path) -> tuple[float, float]:
    """(wall-clock, CPU) seconds of one run of ``command``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(command, cwd=cwd, env=_environment(), capture_output=True, check=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def heavy_imports() -> list[str]:
    """The heavy packages in ``sys.modules`` after importing the plugin's entry-point module."""
    code = (
        "import sys, _ssecert_pytestplugin; "
        f"print(' '.join(m for m in {HEAVY!r} if m in sys.modules))"
    )
    run = subprocess.run(
        [sys.executable, "-c", code], env=_environment(), capture_output=True, text=True, check=True
    )
    return run.stdout.split()


def import_seconds(module: str, runs: int) -> float:
    """Median wall-clock time of ``python -c "import MODULE"`` minus that of ``python -c pass``."""
    with tempfile.TemporaryDirectory() as folder:
        cwd = Path(folder)
        pairs = [
            _seconds([sys.executable, "-c", f"import {module}"], cwd)[0]
            - _seconds([sys.executable, "-c", "pass"], cwd)[0]
            for _ in range(runs)
        ]
    return statistics.median(pairs)


def measure(runs: int = 10) -> dict[str, Any]:
    """Median pytest start-up with and without the plugin, and the median per-pair ratios."""
    with tempfile.TemporaryDirectory() as folder:
        cwd = Path(folder)
        (cwd / "test_trivial.py").write_text(TRIVIAL_TEST, encoding="utf-8")
        base = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "test_trivial.py"]
        _seconds(base, cwd)  # warm the file system caches
        with_plugin, without = [], []
        for _ in range(runs):
            with_plugin.append(_seconds(base, cwd))
            without.append(_seconds([*base, "-p", "no:ssecert"], cwd))
    out: dict[str, Any] = {"runs": runs}
    for index, kind in enumerate(("wall", "cpu")):
        ratios = [a[index] / b[index] for a, b in zip(with_plugin, without)]
        out[kind] = {
            "with_plugin": statistics.median(a[index] for a in with_plugin),
            "without": statistics.median(b[index] for b in without),
            "ratio": statistics.median(ratios),
            "ratio_range": (min(ratios), max(ratios)),
        }
    return out


def rows(quick: bool = False) -> list[dict[str, Any]]:
    """The figures as table rows: ratio = without / with, so 1x means the plugin costs nothing."""
    result = measure(runs=4 if quick else 10)
    heavy = heavy_imports()
    wall, cpu = result["wall"], result["cpu"]
    note = (
        f"median of {result['runs']} runs each, alternated; with / without = "
        f"{wall['ratio']:.3f} wall-clock, {cpu['ratio']:.3f} CPU; heavy modules the plugin "
        f"imports: {', '.join(heavy) or 'none'}"
    )
    return [
        row(
            "pytest plugin start-up",
            "one trivial test",
            wall["with_plugin"],
            wall["without"],
            "pytest -p no:ssecert",
            note,
        )
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10, help="pytest runs of each kind (10)")
    args = parser.parse_args()
    result = measure(runs=args.runs)
    heavy = heavy_imports()
    print(f"pytest on one trivial test, median of {result['runs']} runs each, alternated")
    wall, cpu = result["wall"], result["cpu"]
    lines = (
        ("", "wall s", "CPU s"),
        ("with ssecert's plugin", f"{wall['with_plugin']:.3f}", f"{cpu['with_plugin']:.3f}"),
        ("without (-p no:ssecert)", f"{wall['without']:.3f}", f"{cpu['without']:.3f}"),
        ("with / without", f"{wall['ratio']:.3f}", f"{cpu['ratio']:.3f}"),
    )
    for label, wall_text, cpu_text in lines:
        print(f"  {label:26}{wall_text:>8}{cpu_text:>8}")
    for kind, figures in (("wall", wall), ("CPU", cpu)):
        low, high = figures["ratio_range"]
        print(f"  {kind} ratios of the pairs from {low:.3f} to {high:.3f}")
    print(f"heavy modules imported with the plugin: {', '.join(heavy) or 'none'}")
    print(
        f"import ssecert, which the plugin no longer imports: "
        f"{import_seconds('ssecert', max(3, args.runs // 2)):.3f} s"
    )


if __name__ == "__main__":
    main()
