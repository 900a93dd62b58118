"""The whole ``ssecert analyze`` command on generic plants with many sensors, against the naive
loop and against an earlier revision of ssecert measured in the same run.

Each plant is generic (A and C standard Gaussian, A scaled to spectral radius about 1), with
n = 50 states and p = 1,000 sensors, or n = 100 and p = 200, and s = 2 attacked sensors.  Its
spec (JSON) is written to a temporary folder and the real command

    python -m ssecert analyze SPEC --json OUT

is timed in a subprocess, start-up included (best of a few runs).  Two references:

* the naive loop of ``bench_analyze.py`` (every set of up to 2s removed sensors, smallest
  first, ``numpy.linalg.matrix_rank`` of the kept sensors' stacked observability matrix),
  timed on the first sets of each level and extrapolated, plus Python's start-up with numpy;
* the same command run from a git worktree of an earlier revision (``--reference REV``,
  default ``REFERENCE``, the revision whose 50 x 1,000 plant took several seconds where the
  week before it took half a second: a regression this row would have shown).  Both must give
  the same verdict.

    python benchmarks/bench_large.py [--runs N] [--sample N] [--reference REV]
"""

from __future__ import annotations

import argparse
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from _common import best_of, row, yes_no
from bench_analyze import interpreter_start, naive, run_analyze, write_spec

from ssecert import System

ROOT = Path(__file__).resolve().parents[1]
PLANTS = ((50, 1000, 2), (100, 200, 2))
REFERENCE = "2abc180"


def generic_plant(n: int, p: int, seed: int = 0) -> System:
    """A and C standard Gaussian, A scaled by 1 / sqrt(n) (spectral radius about 1)."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n)) / np.sqrt(n)
    return System(A, rng.standard_normal((p, n)), name=f"generic-n{n}-p{p}")


@dataclass(frozen=True)
class Large:
    n: int
    p: int
    s: int
    seconds: float
    verdict: str
    reference_seconds: float | None
    reference_verdict: str | None
    naive_seconds: float
    naive_holds: bool
    start: float

    @property
    def case(self) -> str:
        return f"generic n = {self.n}, p = {self.p}, s = {self.s}"


def _timed(spec: Path, out: Path, cwd: Path, runs: int) -> tuple[float, str]:
    """Best-of-``runs`` seconds of the command from ``cwd`` and its sparse-observability verdict."""
    certs: list[dict[str, Any]] = []
    seconds, _ = best_of(lambda: certs.append(run_analyze(spec, out, cwd=cwd)), runs)
    return seconds, str(certs[-1]["checks"]["sparse_observability"]["verdict"])


def _worktree(revision: str, folder: Path) -> Path | None:
    """A detached worktree of ``revision`` in ``folder``, or None when git cannot make one."""
    done = subprocess.run(
        ["git", "worktree", "add", "--detach", str(folder), revision],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
    )
    return folder if done.returncode == 0 else None


def measure(*, runs: int = 3, sample: int = 200, reference: str = REFERENCE) -> list[Large]:
    results = []
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        out = folder / "certificate.json"
        start = interpreter_start(runs)
        tree = _worktree(reference, folder / "reference")
        try:
            for n, p, s in PLANTS:
                system = generic_plant(n, p)
                spec = write_spec(folder, system, s)
                seconds, verdict = _timed(spec, out, ROOT, runs)
                ref_seconds = ref_verdict = None
                if tree is not None:
                    ref_seconds, ref_verdict = _timed(spec, out, tree, runs)
                loop = naive(system, s, sample=sample, repeat=1)
                results.append(
                    Large(
                        n,
                        p,
                        s,
                        seconds,
                        verdict,
                        ref_seconds,
                        ref_verdict,
                        loop.seconds,
                        loop.holds,
                        start,
                    )
                )
        finally:
            if tree is not None:
                subprocess.run(
                    ["git", "worktree", "remove", "--force", str(tree)],
                    cwd=ROOT,
                    capture_output=True,
                    check=False,
                )
    return results


def to_rows(results: list[Large], sample: int, reference: str) -> list[dict[str, Any]]:
    out = []
    for r in results:
        naive_verdict = "holds" if r.naive_holds else "fails"
        out.append(
            row(
                "large plants",
                f"{r.case}, vs the naive loop",
                r.seconds,
                r.naive_seconds + r.start,
                "the loop as a script",
                f"same verdict: {yes_no(r.verdict == naive_verdict)} ({r.verdict}); the whole "
                f"command, start-up and every check included; the loop timed on the first "
                f"{sample:,} sets of each level and extrapolated, plus {r.start:.2g} s to start "
                "Python with numpy",
            )
        )
        if r.reference_seconds is not None:
            out.append(
                row(
                    "large plants",
                    f"{r.case}, vs revision {reference}",
                    r.seconds,
                    r.reference_seconds,
                    f"ssecert at {reference}",
                    f"same verdict: {yes_no(r.verdict == r.reference_verdict)} ({r.verdict}); "
                    f"the same command run from a worktree of {reference} in the same run",
                )
            )
    return out


def rows(quick: bool = False) -> list[dict[str, Any]]:
    """The figures as table rows (quick: one run of each command, a smaller sample)."""
    runs, sample = (1, 50) if quick else (3, 200)
    return to_rows(measure(runs=runs, sample=sample), sample, REFERENCE)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="runs of each command (best of)")
    parser.add_argument("--sample", type=int, default=200, help="sets timed per naive level")
    parser.add_argument("--reference", default=REFERENCE, help="git revision to compare with")
    args = parser.parse_args()
    results = measure(runs=args.runs, sample=args.sample, reference=args.reference)
    for line in to_rows(results, args.sample, args.reference):
        ratio = line["ratio"]
        print(
            f"{line['case']:<58} ssecert {line['ssecert']:8.2f} s  {line['reference_name']} "
            f"{line['reference']:.3g} s  ratio {ratio:.3g}x\n    {line['note']}"
        )


if __name__ == "__main__":
    main()
