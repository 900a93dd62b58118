"""The whole ``ssecert analyze`` command against a naive loop, on static plants with many sensors.

Each plant is A = I with generic sensors (standard Gaussian C): its output
at one step is all there is, so only the sensor sets decide it, and nothing
can be pruned.  The spec files (JSON: name, [system] A C, [attack]
max_attacked) are written to a temporary folder, and the real command

    python -m ssecert analyze SPEC --json OUT

is timed in a subprocess, start-up included (the best of a few runs), with
its default options and with ``--time-budget 0`` (the verdict only, no
refinement of max_removable); the same command on the packaged 2-state
``ugv`` example shows its fixed cost (start-up, imports, the other checks).  The reference answers the same question (is
the plant 2s-sparse observable?) the way one writes it first: a Python loop
over every set of up to 2s removed sensors, smallest first, calling
numpy.linalg.matrix_rank on the stacked observability matrix of the kept
sensors (per-sensor blocks precomputed once), stopping at the first set
that breaks observability.  A level with more sets than ``--sample`` is
timed on its first that many sets in the loop's order (where the loop
stops if one of them breaks the plant) and extrapolated to all of them.
Both must give the same verdict.

Two comparisons are made.  The time to the verdict: the seconds the
sparse-observability check took to decide it inside the command (its JSON's
``meta.timings["sparse_observability.to_verdict"]``: everything but the
refinement of max_removable past the verdict), against the loop timed
in-process.  And the whole command, against the loop as a user would run it
as a script: the loop's time plus the start-up of a Python interpreter that
imports numpy (measured in the same run, best of a few).

The command's JSON also holds the cost model's estimate of its enumeration
beside the measured time (``cost_estimate``, for enumerations of more than
200,000 sets); both are reported for the plants that hold (one that fails
ends its enumeration at the breaking set, which the estimate of the
verdict's levels bounds from above).

    python benchmarks/bench_analyze.py [--runs N] [--sample N] [--specs DIR]
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from _common import best_of, cost_model_row, row, yes_no

from ssecert import System

ROOT = Path(__file__).resolve().parents[1]
# (n, p, s, planted): the verdict needs every set of up to 2s of the p sensors; with planted = m,
# the plant fails: only its first m sensors see outside a hyperplane, so removing them (the
# lexicographically first set of its size) breaks it, and no smaller set does
PLANTS = ((10, 30, 3, 0), (12, 28, 3, 0), (8, 30, 1, 0), (6, 24, 2, 0), (10, 30, 3, 6))
VARIANTS = {"default options": (), "--time-budget 0": ("--time-budget", "0")}


def static_plant(n: int, p: int, seed: int = 0, planted: int = 0) -> System:
    """A = I with p generic sensors; with ``planted`` = m, sensors m, m + 1, ... do not see the
    first state (generic in the hyperplane x_1 = 0), so removing sensors 0..m-1 breaks it."""
    C = np.random.default_rng(seed).standard_normal((p, n))
    if planted:
        C[planted:, 0] = 0.0
    suffix = f"-planted{planted}" if planted else ""
    return System(np.eye(n), C, name=f"static-n{n}-p{p}{suffix}")


def write_spec(folder: Path, system: System, s: int) -> Path:
    name = f"{system.name}-s{s}"
    spec = {
        "name": name,
        "system": {"A": np.asarray(system.A).tolist(), "C": np.asarray(system.C).tolist()},
        "attack": {"max_attacked": s},
    }
    path = folder / f"{name}.json"
    path.write_text(json.dumps(spec), encoding="utf-8")
    return path


def interpreter_start(runs: int) -> float:
    """Seconds to start Python and import numpy (what a script of the loop pays first)."""
    command = [sys.executable, "-c", "import numpy"]
    seconds, _ = best_of(lambda: subprocess.run(command, check=True, cwd=ROOT), runs)
    return seconds


def run_analyze(
    spec: str | Path, out: Path, options: tuple[str, ...] = (), *, cwd: Path = ROOT
) -> dict[str, Any]:
    """One run of the command from ``cwd`` (the source tree, so that this ssecert is the one
    run, or a worktree of another revision); its JSON certificate."""
    command = [sys.executable, "-m", "ssecert", "analyze", str(spec), "--json", str(out)]
    done = subprocess.run(
        [*command, *options], cwd=cwd, capture_output=True, text=True, check=False
    )
    if done.returncode not in (0, 1, 3):  # holds, fails, inconclusive
        raise RuntimeError(f"{' '.join(command)} in {cwd} exited {done.returncode}: {done.stderr}")
    return json.loads(out.read_text(encoding="utf-8"))


@dataclass(frozen=True)
class Naive:
    """The reference loop: its (extrapolated) time, its verdict and the levels it sampled."""

    seconds: float
    holds: bool
    checked: int
    sets: int
    sampled_levels: tuple[int, ...]


def naive(system: System, s: int, *, sample: int, repeat: int) -> Naive:
    """Every set of up to 2s removed sensors, smallest first, until one breaks observability."""
    n, p = system.n, system.p
    blocks = system.sensor_blocks(n)  # (p, n, n): C[i] A^k
    everyone = np.arange(p)

    def first_breaking(sets) -> tuple[int, tuple[int, ...] | None]:
        count = 0
        for removed in sets:
            count += 1
            keep = np.setdiff1d(everyone, removed)
            if np.linalg.matrix_rank(blocks[keep].reshape(-1, n)) < n:
                return count, tuple(removed)
        return count, None

    seconds, checked, sets, sampled = 0.0, 0, 0, []
    for size in range(2 * s + 1):
        total = math.comb(p, size)
        # the loop's own order (lexicographic), over the whole level or its first ``sample`` sets
        elapsed, (count, breaking) = best_of(
            lambda size=size: first_breaking(
                itertools.islice(itertools.combinations(range(p), size), sample)
            ),
            repeat,
        )
        checked += count
        if breaking is not None or total <= sample:
            seconds += elapsed
            sets += count
        else:
            # extrapolated to the whole level (a breaking set later in it would stop the loop
            # sooner: for a plant that holds there is none)
            seconds += elapsed / count * total
            sets += total
            sampled.append(size)
        if breaking is not None:
            return Naive(seconds, False, checked, sets, tuple(sampled))
    return Naive(seconds, True, checked, sets, tuple(sampled))


@dataclass(frozen=True)
class CommandRun:
    seconds: float
    verdict: str
    max_removable: int | None
    lower_bound: bool
    cost: dict[str, Any] | None
    to_verdict: float  # inside the command: the check's seconds to its verdict (best run)


@dataclass(frozen=True)
class PlantResult:
    n: int
    p: int
    s: int
    naive: Naive
    commands: dict[str, CommandRun]
    fixed_cost: float  # the command on the 2-state ugv example: start-up, imports, checks
    start: float  # Python and numpy start-up, added to the loop for the command's comparison
    planted: int = 0

    @property
    def case(self) -> str:
        case = f"static A = I, n = {self.n}, p = {self.p}, s = {self.s}"
        if self.planted:
            case += f", sensors 0-{self.planted - 1} a planted breaking set (fails)"
        return case


def measure(
    *, runs: int = 3, sample: int = 20000, repeat: int = 1, specs: Path | None = None
) -> list[PlantResult]:
    """Time the command (best of ``runs``) and the naive loop (best of ``repeat``) on each plant."""
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(specs) if specs is not None else Path(scratch)
        folder.mkdir(parents=True, exist_ok=True)
        out = Path(scratch) / "certificate.json"
        fixed_cost, _ = best_of(lambda: run_analyze("ugv", out), runs)
        start = interpreter_start(runs)
        results = []
        for n, p, s, planted in PLANTS:
            system = static_plant(n, p, planted=planted)
            spec = write_spec(folder, system, s)
            commands = {}
            for variant, options in VARIANTS.items():
                certs: list[dict[str, Any]] = []
                seconds, _ = best_of(
                    lambda spec=spec, options=options, certs=certs: certs.append(
                        run_analyze(spec, out, options)
                    ),
                    runs,
                )
                check = certs[-1]["checks"]["sparse_observability"]
                commands[variant] = CommandRun(
                    seconds=seconds,
                    verdict=check["verdict"],
                    max_removable=check.get("max_removable"),
                    lower_bound=bool(check.get("max_removable_is_lower_bound")),
                    cost=check["evidence"].get("cost_estimate"),
                    to_verdict=min(
                        c["meta"]["timings"]["sparse_observability.to_verdict"] for c in certs
                    ),
                )
            reference = naive(system, s, sample=sample, repeat=repeat)
            results.append(PlantResult(n, p, s, reference, commands, fixed_cost, start, planted))
    return results


def _verdict(holds: bool) -> str:
    return "holds" if holds else "fails"


def _removable(c: CommandRun) -> str:
    return f"{'>= ' if c.lower_bound else ''}{c.max_removable}"


def print_results(results: list[PlantResult], sample: int) -> None:
    print(f"{'plant':<36} {'to the verdict (s)':>18} {'naive loop (s)':>14} {'ratio':>7}")
    for r in results:
        c = r.commands["default options"]
        print(
            f"{r.case:<36} {c.to_verdict:18.3f} {r.naive.seconds:14.3f} "
            f"{r.naive.seconds / c.to_verdict:6.1f}x"
        )
    print(f"\n{'plant':<36} {'command':<16} {'analyze (s)':>11} {'script (s)':>10} {'ratio':>7}")
    for r in results:
        for variant, c in r.commands.items():
            same = c.verdict == _verdict(r.naive.holds)
            script = r.naive.seconds + r.start
            print(
                f"{r.case:<36} {variant:<16} {c.seconds:11.2f} {script:10.2f} "
                f"{script / c.seconds:6.2f}x  verdict {c.verdict} (max_removable "
                f"{_removable(c)}), naive {_verdict(r.naive.holds)}: same {same}"
            )
        if r.naive.sampled_levels:
            print(
                f"{'':<36} naive loop: {r.naive.sets:,} sets, levels "
                f"{', '.join(map(str, r.naive.sampled_levels))} timed on their first {sample:,} "
                "sets and extrapolated"
            )
    if results:
        print(
            f"the command on the 2-state ugv example: {results[0].fixed_cost:.2f} s; Python "
            f"with numpy starts in {results[0].start:.2f} s (added to the loop as a script)"
        )
    for r in results:
        cost = r.commands["default options"].cost
        if cost is not None and r.commands["default options"].verdict == "holds":
            ratio = cost["measured_seconds_for_verdict"] / cost["seconds_for_verdict"]
            print(
                f"cost model, {r.case}: estimate {cost['seconds_for_verdict']:.2f} s, measured "
                f"{cost['measured_seconds_for_verdict']:.2f} s (measured/estimate {ratio:.2f})"
            )


def _sampled(r: PlantResult, sample: int) -> str:
    if not r.naive.sampled_levels:
        return ""
    levels = ", ".join(map(str, r.naive.sampled_levels))
    return (
        f"; reference: {r.naive.sets:,} sets, levels {levels} timed on their first {sample:,} "
        "sets in the loop's order and extrapolated"
    )


def to_rows(results: list[PlantResult], sample: int) -> list[dict[str, Any]]:
    out = []
    for r in results:
        c = r.commands["default options"]
        same = c.verdict == _verdict(r.naive.holds)
        out.append(
            row(
                "verdict vs naive loop",
                r.case,
                c.to_verdict,
                r.naive.seconds,
                "matrix_rank per set, up to 2s removed",
                f"same verdict: {yes_no(same)} ({c.verdict}); ssecert: the sparse-observability "
                "check's seconds to its verdict inside `ssecert analyze` (meta.timings), "
                "re-checks included, refinement of max_removable excluded; both in-process"
                + _sampled(r, sample),
            )
        )
    for r in results:
        for variant, c in r.commands.items():
            same = c.verdict == _verdict(r.naive.holds)
            note = (
                f"same verdict: {yes_no(same)} ({c.verdict}; max_removable {_removable(c)}); "
                f"the command includes start-up and every check ({r.fixed_cost:.2g} s for the "
                f"2-state ugv example); the reference is the loop plus {r.start:.2g} s to start "
                "Python with numpy, as a script of it would"
            )
            if variant == "default options":
                note += ", and the command refines max_removable up to its 5 s time budget"
            out.append(
                row(
                    "analyze vs naive loop",
                    f"{r.case}, {variant}",
                    c.seconds,
                    r.naive.seconds + r.start,
                    "the loop as a script",
                    note + _sampled(r, sample),
                )
            )
    for r in results:
        c = r.commands["default options"]
        # a plant that fails ends its enumeration at the breaking set: the estimate of the
        # verdict's levels bounds that time from above, it does not predict it
        if c.cost is not None and c.verdict == "holds":
            out.append(cost_model_row(f"{r.case} (analyze)", c.cost))
    return out


def rows(quick: bool = False) -> list[dict[str, Any]]:
    """The figures as table rows (quick: one run of the command, a smaller sample)."""
    runs, sample = (1, 2000) if quick else (3, 20000)
    return to_rows(measure(runs=runs, sample=sample), sample)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="runs of the command (best of)")
    parser.add_argument(
        "--sample", type=int, default=20000, help="sets timed per sampled level (default 20000)"
    )
    parser.add_argument(
        "--repeat", type=int, default=1, help="repetitions of the naive loop (best of)"
    )
    parser.add_argument("--specs", type=Path, help="keep the spec files in this folder")
    args = parser.parse_args()
    results = measure(runs=args.runs, sample=args.sample, repeat=args.repeat, specs=args.specs)
    print_results(results, args.sample)


if __name__ == "__main__":
    main()
