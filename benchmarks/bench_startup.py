"""Fixed costs: what a user pays before and around the analysis, against the goals set for them.

Each figure is the median over ``--runs`` fresh processes (the first run, which fills the
operating system's file cache, is left out):

* ``import ssecert`` (wall-clock), goal 0.5 s;
* ``ssecert --version`` (wall-clock), goal 0.5 s;
* ``ssecert analyze ugv`` (the 2-state packaged example), CPU time of the process
  (user + system), goal 1 s; the note names its slowest steps (``meta.timings``);
* ``ssecert analyze notes-example-0`` (a 3-state packaged example without an observer: the
  command's own fixed costs around a small analysis), CPU time, against the same goal;
* ``ssecert certify`` on the packaged example (the README's first command), wall-clock,
  no goal: the note names its slowest steps.

The reference column is the goal, so a ratio of 1x or more meets it; ``python -c pass``
(the interpreter alone) is measured in the same run and named in the notes.

The processes keep their compiled bytecode, as an installed package has it (pip compiles
it at install; an editable install writes it on the first import): they run with
``PYTHONPYCACHEPREFIX`` set to a temporary folder, which the warm-up run fills, and
without ``PYTHONDONTWRITEBYTECODE`` (where it is set, as on some development machines,
every run would compile each of ssecert's modules again, about a second).

    python benchmarks/bench_startup.py [--runs N]
"""

from __future__ import annotations

import argparse
import json
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

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
NAME = "fixed costs vs goal"


def _child_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


# the children's environment: bytecode kept in a folder of their own (``measure`` sets it)
_ENV: dict[str, str] = {}


def run(command: list[str]) -> tuple[float, float]:
    """(wall-clock seconds, CPU seconds of the child) of one run of ``command`` from the source
    tree (``-c`` and ``-m`` put it first on the path, so its ssecert is the one run); exit
    statuses 0, 1 (fails) and 3 (inconclusive) are answers."""
    cpu, start = _child_cpu(), time.perf_counter()
    done = subprocess.run(
        command, cwd=ROOT, capture_output=True, text=True, check=False, env=_ENV or None
    )
    wall = time.perf_counter() - start
    if done.returncode not in (0, 1, 3):
        raise RuntimeError(f"{' '.join(command)} exited {done.returncode}: {done.stderr}")
    return wall, _child_cpu() - cpu


def median_of(command: list[str], runs: int) -> tuple[float, float]:
    """Medians of wall-clock and CPU seconds over ``runs`` runs after one warm-up run."""
    run(command)
    samples = [run(command) for _ in range(max(1, runs))]
    return (statistics.median(s[0] for s in samples), statistics.median(s[1] for s in samples))


def slowest(path: Path, count: int = 3) -> str:
    """The certificate's ``count`` slowest steps, as 'name 1.2 s': its ``meta.timings``
    without the whole analysis, the steps that have nested steps and the seconds recorded
    inside a check's evidence (a part of that check's time)."""
    timings = json.loads(path.read_text(encoding="utf-8")).get("meta", {}).get("timings", {})
    steps = {}
    for key, value in timings.items():
        nested = any(other.startswith(key + ".") for other in timings)
        if key == "analyze" or nested or ".evidence." in key:
            continue
        name = key.removesuffix(".seconds").split(".")[-1]
        steps[name] = float(value)
    top = sorted(steps.items(), key=lambda kv: -kv[1])[:count]
    return ", ".join(f"{k} {v:.2g} s" for k, v in top)


def measure(runs: int) -> dict[str, Any]:
    python = [sys.executable]
    out: dict[str, Any] = {"runs": runs}
    with tempfile.TemporaryDirectory() as scratch:
        _ENV.clear()
        _ENV.update(os.environ, PYTHONPYCACHEPREFIX=str(Path(scratch) / "bytecode"))
        _ENV.pop("PYTHONDONTWRITEBYTECODE", None)
        out["python"] = median_of([*python, "-c", "pass"], runs)
        out["import"] = median_of([*python, "-c", "import ssecert"], runs)
        out["version"] = median_of([*python, "-m", "ssecert", "--version"], runs)
        certificate = Path(scratch) / "ugv.json"
        analyze = [*python, "-m", "ssecert", "analyze", "ugv", "--json", str(certificate)]
        out["analyze"] = median_of(analyze, runs)
        out["analyze_steps"] = slowest(certificate)
        small = Path(scratch) / "small.json"
        out["small"] = median_of(
            [*python, "-m", "ssecert", "analyze", "notes-example-0", "--json", str(small)], runs
        )
        out["small_steps"] = slowest(small)
        folder = Path(scratch) / "certify"
        out["certify"] = median_of([*python, "-m", "ssecert", "certify", "--out", str(folder)],
                                   max(1, runs // 2))  # fmt: skip
        out["certify_steps"] = slowest(next(folder.glob("*.json")))
        _ENV.clear()
    return out


def to_rows(m: dict[str, Any]) -> list[dict[str, Any]]:
    runs, bare = m["runs"], m["python"][0]
    median = (
        f"median of {runs} fresh processes after a warm-up, bytecode kept as an installed "
        f"package keeps it; `python -c pass` {bare:.2f} s"
    )
    goal = "the goal (seconds allowed)"
    return [
        row(NAME, "`import ssecert`, wall-clock", m["import"][0], 0.5, goal, median),
        row(NAME, "`ssecert --version`, wall-clock", m["version"][0], 0.5, goal, median),
        row(
            NAME,
            "`ssecert analyze ugv` (n = 2, p = 3), CPU time",
            m["analyze"][1],
            1.0,
            goal,
            f"{median}; wall-clock {m['analyze'][0]:.2f} s; slowest steps: {m['analyze_steps']}",
        ),
        row(
            NAME,
            "`ssecert analyze notes-example-0` (n = 3, p = 3, no observer), CPU time",
            m["small"][1],
            1.0,
            goal,
            f"{median}; wall-clock {m['small'][0]:.2f} s; slowest steps: {m['small_steps']}",
        ),
        row(
            NAME,
            "`ssecert certify` (the packaged example, ugv), wall-clock",
            m["certify"][0],
            None,
            "-",
            f"median of {max(1, runs // 2)} runs after a warm-up; CPU time {m['certify'][1]:.2f}"
            f" s; slowest steps: {m['certify_steps']}",
        ),
    ]


def rows(quick: bool = False) -> list[dict[str, Any]]:
    return to_rows(measure(3 if quick else 7))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=7)
    for r in to_rows(measure(parser.parse_args().runs)):
        goal = f" (goal {r['reference']:g} s)" if r["reference"] is not None else ""
        print(f"{r['case']}: {r['ssecert']:.3f} s{goal}; {r['note']}")


if __name__ == "__main__":
    main()
