"""Run the benchmarks and write their table: benchmarks/README.md and the project README's block.

Each ``bench_*.py`` script returns its figures as rows (``rows(quick)``);
every ratio is a reference against ssecert measured in the same run.  This
script runs each one in its own Python process (so that one script's BLAS
threads, Dask clusters and caches do not reach the next), keeps the rows in
benchmarks/results.json, and writes benchmarks/README.md (what each
benchmark measures, how to run it, the machine and the full table) and the
compact table between ``<!-- benchmarks:start -->`` and
``<!-- benchmarks:end -->`` in the project README.

    python benchmarks/table.py [--quick] [--only NAME ...] [--no-run]

``--only`` reruns the named benchmarks and keeps the others' rows from
results.json; ``--no-run`` only rewrites the files from results.json.

The experiment scripts (``exp_*.py``) are not run here: each one run with
``--record`` keeps its numbers in benchmarks/experiments.json, and
benchmarks/README.md gets a section written from them by the scripts' own
``report`` and ``conclusion`` functions.
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from ssecert.base.atomic import atomic_write_text

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RESULTS = HERE / "results.json"
# one BLAS thread unless the environment says otherwise: on a shared machine, OpenBLAS
# threads waiting for a busy core slowed numpy's SVD tenfold or more from run to run
BLAS_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
START = "<!-- benchmarks:start -->"
END = "<!-- benchmarks:end -->"

# name: (script, what it measures)
BENCHMARKS: dict[str, tuple[str, str]] = {
    "enumeration": (
        "bench_enumeration.py",
        "The sparse-observability enumeration (every set of 2s = 6 removed sensors of two "
        "15-state, 30-sensor plants, no pruning) against a Python loop calling "
        "`numpy.linalg.matrix_rank` on the stacked observability matrix of the kept sensors, "
        "one set at a time (timed on a random sample of the sets and extrapolated). The "
        "eigenspace method against the enumeration on a plant both must work on (distinct "
        "eigenvalues, no sensor observing the whole state, verdict only), and the eigenspace "
        "method alone on n = 50, p = 1000. The refinement past the verdict against its time "
        "budget (the reference column is the budget) on static plants whose breaking level's "
        "sets all fail (A = I, n = 10, p = 20 and 26, s = 2).",
    ),
    "kernel": (
        "bench_kernel.py",
        "The enumeration's screening of one level of sensor sets (n = 10, 12, 20; p = 30; "
        "every set of 6, 6, 5 removed sensors: 593,775, 593,775, 142,506 sets), as the "
        "verdict's level (the sets closest to breaking ranked) and as a refinement level, "
        "against a 28-line numpy baseline (colex order, Gram partial sums, a float64 Cholesky "
        "written batch-innermost) screening the same sets, with the GFLOP/s achieved (n^3/3 + "
        "n^2 flops per set) against the flop limit measured in the same run (a float64 "
        "matrix product on one thread); the breaking sets each finds are shown.",
    ),
    "observers": (
        "bench_observers.py",
        "The sparse soft observer simulated for 100 Monte Carlo runs at once against a Python "
        "loop over the runs (the Lasso paper's Sec. 5.2 set-up); the estimates must be equal. "
        "One run's cost per step (n = 10, p = 15) against the paper's MATLAB figure (4e-6 s, "
        "its machine) and against the previous one-run loops timed in the same run.",
    ),
    "lmi": (
        "bench_lmi.py",
        "The circle-criterion certificate of an elastic-net observer with ssecert's structured "
        "Lyapunov matrix against the plain formulation (full P, full LMI), both in cvxpy with "
        "Clarabel; the certified (shrink, step) region map (full run only).",
    ),
    "fista": (
        "bench_fista.py",
        "FISTA on the partial Lasso (in orthonormal coordinates with adaptive restart, and "
        "plain, the default) run until it is within 1e-6 of the cvxpy solution, against "
        "cvxpy with Clarabel; medians over random instances.",
    ),
    "analyze": (
        "bench_analyze.py",
        "A naive Python loop over every set of up to 2s removed sensors calling "
        "`numpy.linalg.matrix_rank`, smallest first, stopping at the first breaking set, "
        "against `python -m ssecert analyze SPEC --json OUT` on static plants A = I with many "
        "generic sensors (one with a planted breaking set, which fails): the time the "
        "sparse-observability check took to its verdict inside the command (its "
        "`meta.timings`), against the loop in-process; and the whole command, start-up and "
        "every check included (best of a few runs), against the loop as a script (plus the "
        "start-up of Python with numpy). Both must give the same verdict.",
    ),
    "large": (
        "bench_large.py",
        "The whole `ssecert analyze` command on generic plants with many sensors (n = 50, "
        "p = 1,000 and n = 100, p = 200, s = 2) against the naive rank loop (sampled and "
        "extrapolated, plus Python's start-up) and against the same command run from a git "
        "worktree of an earlier revision in the same run (same verdict required).",
    ),
    "distributed": (
        "bench_distributed.py",
        "The enumeration on local Dask clusters of 1 and 2 single-thread worker processes "
        "against in-process (same answer required); the cost model's estimate against the "
        "measured enumeration; C(60, 10) sensor sets projected onto 64 workers.",
    ),
    "device": (
        "bench_device.py",
        "The enumeration's screening on a GPU (`--device cuda`: PyTorch or CuPy) against the "
        "CPU on A = I, n = 10, p = 40, s = 3: the verdict's level of 3,838,380 sets of 6 "
        "removed sensors and the refinement level of 18,643,560 sets of 7, each timed whole "
        "(the device's screening and the CPU's share) in the same run, same answer required; "
        "sets per second on each, and the machine. No row where no GPU is usable.",
    ),
    "exact": (
        "bench_exact.py",
        "ssecert's exact observability (a Krylov rank modulo a prime, an exact kernel vector "
        "when it is short) against python-flint (the observability matrix of the integer-scaled "
        "data, its fmpz rank and nullspace) on random plants, observable and with one state "
        "unseen, n = 5 to 30; same answer required. No row without python-flint.",
    ),
    "design": (
        "bench_design.py",
        "Observer synthesis on the 15-state, 30-sensor random-n15-p30 plant: ssecert's "
        "synthesis LMI (Schur complement of the error block only) against the Schur "
        "complement of the whole Lyapunov matrix, both cvxpy with Clarabel, same proposed "
        "gain required; and the whole `design_observer` search (elastic net, l2 gain) within "
        "its 60 s budget: candidates tried, the first certified, the certified gamma.",
    ),
    "startup": (
        "bench_startup.py",
        "Fixed costs against the goals set for them (the reference column is the goal): "
        "`import ssecert` and `ssecert --version` (wall-clock, goal 0.5 s), `ssecert analyze "
        "ugv` on the 2-state packaged example (CPU time, goal 1 s), `ssecert analyze` on a "
        "3-state example without an observer (the command's own fixed costs, CPU time, against "
        "the same goal) and `ssecert certify` on "
        "the packaged example (the README's first command, no goal), each the median over "
        "fresh processes after a warm-up, with the slowest steps named.",
    ),
    "computed_once": (
        "bench_computed_once.py",
        "What the shared analysis context saves in one `certify` run of the packaged examples "
        "(the calls it avoids, timed in the same run).",
    ),
}

# rows are grouped by their benchmark name, in this order
ORDER = (
    "enumeration vs rank loop",
    "eigenspace vs enumeration",
    "refinement vs time budget",
    "enumeration kernel vs baseline",
    "batched simulation vs loop",
    "single SSO run vs paper",
    "single SSO run vs previous loop",
    "structured LMI vs plain",
    "LMI region map",
    "FISTA vs cvxpy",
    "verdict vs naive loop",
    "analyze vs naive loop",
    "large plants",
    "Dask workers vs in-process",
    "accelerator screening vs CPU",
    "exact observability vs python-flint",
    "cost model",
    "cost model projection",
    "fixed costs vs goal",
    "shared analysis context",
    "design synthesis LMI",
    "design search",
)

# experiments of the documents (``exp_*.py``): name: what it reruns
EXPERIMENTS_FILE = "experiments.json"
EXPERIMENTS = HERE / EXPERIMENTS_FILE
EXPERIMENT_SCRIPTS: dict[str, str] = {
    "exp_lasso_sec51": "Lasso paper Sec. 5.1: Lasso (FISTA) vs l1 vs l0 decoders, n = 20, p varied, "
    "with and without noise",
    "exp_sso_sec52": "Lasso paper Sec. 5.2: the sparse soft observer with tau = 1 and tau = n",
    "exp_thesis_observers": "thesis Sec. 6.1-6.2: the D-SSO (grid-searched, as the thesis did) "
    "vs the elastic-net observer in four attack scenarios",
    "exp_pruning": "weighted l1 paper Sec. IV: success rate against attack percentage, m = 20, "
    "n = 10",
    "exp_sise": "SISE paper: relative errors against the oracle, p = 40, m = 20, n = 50 and 70",
    "exp_localization": "thesis Sec. 6.3: RSS localization of a target under sensor attacks",
}

CHILD = """
import json, sys
module = __import__(sys.argv[1])
rows = module.rows(quick=sys.argv[2] == "quick")
with open(sys.argv[3], "w", encoding="utf-8") as handle:
    json.dump(rows, handle)
"""


def significant(value: float, digits: int = 3) -> str:
    """``value`` rounded to ``digits`` significant digits, without an exponent."""
    if value == 0 or not math.isfinite(value):
        return f"{value:g}"
    rounded = float(f"{value:.{digits}g}")
    decimals = max(0, digits - 1 - math.floor(math.log10(abs(rounded))))
    return f"{rounded:.{decimals}f}"


def format_seconds(seconds: float | None) -> str:
    """A duration with three significant digits and a unit (us, ms, s, min, h)."""
    if seconds is None:
        return "-"
    if not math.isfinite(seconds):
        return "n/a"
    for limit, scale, unit in ((1e-3, 1e6, "us"), (1.0, 1e3, "ms"), (120.0, 1.0, "s")):
        if seconds < limit:
            return f"{significant(seconds * scale)} {unit}"
    if seconds < 7200.0:
        return f"{significant(seconds / 60)} min"
    return f"{significant(seconds / 3600)} h"


def format_ratio(ratio: float | None) -> str:
    """The ratio as "12x", "3.74x" or "0.423x"; "-" without a reference.

    Three significant digits below 10, so that a cost-model ratio of 2.03
    does not read as 2.0 (within a factor of 2).
    """
    if ratio is None:
        return "-"
    if not math.isfinite(ratio):
        return "n/a"
    if ratio >= 10:
        return f"{ratio:.0f}x"
    return f"{significant(ratio)}x"


def ordered(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Rows grouped by benchmark (in ORDER, unknown names last), each group in its order."""
    rank = {name: i for i, name in enumerate(ORDER)}
    return sorted(rows, key=lambda r: rank.get(r["benchmark"], len(ORDER)))


def _cell(text: Any) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def markdown_table(header: list[str], lines: list[list[str]]) -> str:
    out = ["| " + " | ".join(header) + " |", "|" + " --- |" * len(header)]
    out += ["| " + " | ".join(_cell(c) for c in line) + " |" for line in lines]
    return "\n".join(out) + "\n"


def full_table(rows: list[dict[str, Any]]) -> str:
    header = ["benchmark", "case", "ssecert", "reference", "ratio", "reference is", "note"]
    lines = [
        [
            r["benchmark"],
            r["case"],
            format_seconds(r["ssecert"]),
            format_seconds(r["reference"]),
            format_ratio(r["ratio"]),
            r["reference_name"],
            r["note"],
        ]
        for r in ordered(rows)
    ]
    return markdown_table(header, lines)


def compact_table(rows: list[dict[str, Any]]) -> str:
    header = ["benchmark", "case", "ssecert", "reference", "ratio"]
    lines = [
        [
            r["benchmark"],
            r["case"],
            format_seconds(r["ssecert"]),
            format_seconds(r["reference"]),
            format_ratio(r["ratio"]),
        ]
        for r in ordered(rows)
    ]
    return markdown_table(header, lines)


def replace_block(text: str, block: str) -> str:
    """``text`` with ``block`` between the markers.

    Without the markers, the block is added at the end of the
    "## Performance" section, or in a new such section before
    "## References" (or at the end).
    """
    marked = f"{START}\n{block.rstrip()}\n{END}"
    start, end = text.find(START), text.find(END)
    if start >= 0 and end > start:
        return text[:start] + marked + text[end + len(END) :]
    if start >= 0 or end >= 0:
        raise ValueError(f"the README has only one of {START} and {END}")
    heading = text.find("\n## Performance\n")
    if heading >= 0:
        following = text.find("\n## ", heading + 1)
        at = following + 1 if following >= 0 else len(text)
        before = text[:at].rstrip("\n")
        return before + "\n\n" + marked + "\n" + ("\n" + text[at:] if following >= 0 else "")
    section = "## Performance\n\n" + marked + "\n"
    references = text.find("\n## References\n")
    if references >= 0:
        return text[: references + 1] + section + "\n" + text[references + 1 :]
    return text.rstrip("\n") + "\n\n" + section


def machine() -> dict[str, Any]:
    import numpy
    import scipy

    model = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text(encoding="utf-8").splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {
        "cpus": os.cpu_count(),
        "cpu_model": model,
        "blas_threads": os.environ.get("OPENBLAS_NUM_THREADS", "1"),
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
    }


def _where(m: dict[str, Any]) -> str:
    """A machine in a few words (its CPUs and numerical libraries)."""
    return (
        f"{m['cpus']} CPUs ({m['cpu_model']}), Python {m['python']}, numpy {m['numpy']}, "
        f"scipy {m['scipy']}"
    )


def _all_rows(results: dict[str, Any]) -> list[dict[str, Any]]:
    return [r for name in BENCHMARKS for r in results["benchmarks"].get(name, {}).get("rows", [])]


def _runs_line(results: dict[str, Any]) -> str:
    entries = [results["benchmarks"][n] for n in BENCHMARKS if n in results["benchmarks"]]
    dates = sorted({e["date"][:10] for e in entries})
    modes = {bool(e["quick"]) for e in entries}
    when = dates[0] if len(dates) == 1 else f"{dates[0]} to {dates[-1]}"
    if modes == {True}:
        return f"quick run (--quick), {when}"
    if modes == {False}:
        return f"full run, {when}"
    return f"full and quick (--quick) runs, {when}"


def compact_block(results: dict[str, Any]) -> str:
    m = results["machine"]
    where = (
        f"{_runs_line(results)}; {m['cpus']} CPUs, {m['cpu_model']}, numpy {m['numpy']}, "
        f"BLAS threads: {m.get('blas_threads', '?')}"
    )
    intro = (
        f"Generated by `python benchmarks/table.py` ({where}). Ratio = reference / ssecert, "
        "both timed in the same run: above 1x ssecert is faster. For the cost model, the "
        "ssecert column is the estimate and the reference the measured time (the target: "
        "within a factor of 2). What each row "
        "compares, its notes and how to rerun it: [benchmarks/README.md](benchmarks/README.md)."
    )
    return intro + "\n\n" + compact_table(_all_rows(results))


def load_experiments() -> dict[str, Any]:
    """The recorded experiment runs (benchmarks/experiments.json), {} when there are none."""
    if not EXPERIMENTS.is_file():
        return {}
    return dict(json.loads(EXPERIMENTS.read_text(encoding="utf-8")))


def experiment_module(name: str) -> Any:
    """Import ``benchmarks/NAME.py`` (an experiment script) without running it."""
    import importlib.util

    if str(HERE) not in sys.path:
        sys.path.insert(0, str(HERE))  # the scripts import _common beside them
    spec = importlib.util.spec_from_file_location(name, HERE / f"{name}.py")
    if spec is None or spec.loader is None:
        raise ImportError(f"cannot import benchmarks/{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def experiments_section(experiments: dict[str, Any]) -> str:
    """The README's section on the experiments, its words written from the recorded numbers.

    Each script's ``report`` (its table) and ``conclusion`` (its comparison
    with the document) are called on the numbers kept by ``--record``; no
    sentence is stored, so none can disagree with the numbers beside it.
    """
    parts = [
        "## Experiments of the documents\n",
        "Each `exp_*.py` script reruns one experiment of the reference documents, prints its "
        "table and ends with a comparison with the document. Every comparing word (faster or "
        "slower and by how much, the same order of magnitude or not, which is better, as in "
        "the document or unlike it) is computed from the numbers by the script's "
        "`conclusion` function, with its rule stated; `tests/test_benchmarks_conclusions.py` "
        "feeds those functions other numbers and checks that the words change. The text "
        "below is written from the numbers of the last run recorded with `--record` (kept "
        f"in `benchmarks/{EXPERIMENTS_FILE}`); `--quick` runs are smaller (fewer runs, a "
        "coarser grid) than the default ones, whose sizes each script's docstring gives.\n",
        "```\n"
        "python benchmarks/exp_sso_sec52.py --quick --record   # run, print, keep for this file\n"
        "python benchmarks/exp_sso_sec52.py                    # the full experiment, printed\n"
        "```\n",
    ]
    for name, what in EXPERIMENT_SCRIPTS.items():
        entry = experiments.get(name)
        what = what[:1].upper() + what[1:]
        parts.append(f"### `{name}.py`\n")
        if entry is None:
            parts.append(f"{what}. Not recorded yet (`python benchmarks/{name}.py --record`).\n")
            continue
        module = experiment_module(name)
        m = entry["machine"]
        mode = "Quick run (--quick)" if entry["quick"] else "Full run"
        parts += [
            f"{what}. {mode} on {entry['date'][:10]}, {format_seconds(entry['seconds'])} "
            f"({m['cpus']} CPUs: {m['cpu_model']}; Python {m['python']}, numpy {m['numpy']}): "
            f"`{entry['command']}`\n",
            "```\n" + module.report(entry["numbers"]).rstrip("\n") + "\n```\n",
            module.conclusion(entry["numbers"]) + "\n",
        ]
    return "\n".join(part.rstrip("\n") + "\n" for part in parts)


def benchmarks_readme(results: dict[str, Any], experiments: dict[str, Any] | None = None) -> str:
    m = results["machine"]
    parts = [
        "# Benchmarks\n",
        "This file is written by `python benchmarks/table.py` (and its last section by the "
        "`exp_*.py` scripts run with `--record`); do not edit it by hand. Every "
        "figure in the table is a ratio against a reference measured in the same run, on the same "
        "machine: ratio = reference / ssecert, so above 1x ssecert is faster. For the cost "
        "model rows the ssecert column is the cost model's estimate and the reference the "
        "measured enumeration, so the ratio is measured / estimate (within a factor of 2 is "
        "the target). Times are the best of a few runs unless the note says otherwise.\n",
        "## How to run\n",
        "```\n"
        "python benchmarks/table.py            # every benchmark, full sizes; rewrites this file\n"
        "python benchmarks/table.py --quick    # smaller sizes and repeats, a few minutes\n"
        "python benchmarks/table.py --only analyze distributed   # rerun some, keep the rest\n"
        "python benchmarks/table.py --no-run   # rewrite the tables from results.json\n"
        "```\n",
        "Each script also runs alone and prints its own text "
        "(`python benchmarks/bench_enumeration.py --help`). From a source checkout, put it "
        "first on the path (`PYTHONPATH=. python benchmarks/table.py`). The rows of the last "
        "run are kept in `benchmarks/results.json`.\n",
        "## What each benchmark measures\n",
    ]
    items = []
    for name, (script, what) in BENCHMARKS.items():
        entry = results["benchmarks"].get(name)
        if entry is None:
            ran = "not run yet"
        else:
            mode = "quick" if entry["quick"] else "full"
            ran = f"{mode} run on {entry['date'][:10]}, {format_seconds(entry['seconds'])}"
            other = entry.get("machine")
            if other is not None and _where(other) != _where(m):
                ran += f", on another machine: {_where(other)}"
            if not entry["rows"]:
                ran += ", no row: it found nothing to measure on this machine"
        items.append(f"- **{name}** (`{script}`; {ran}): {what}\n")
    total = sum(e["seconds"] for e in results["benchmarks"].values())
    parts += [
        "".join(items),
        "## Machine\n",
        f"- {m['cpus']} CPUs: {m['cpu_model']} (from /proc/cpuinfo)\n"
        f"- Python {m['python']}, numpy {m['numpy']}, scipy {m['scipy']}\n"
        f"- BLAS threads: {m.get('blas_threads', '?')} (`table.py` sets OPENBLAS_NUM_THREADS, "
        "OMP_NUM_THREADS and MKL_NUM_THREADS to 1 unless they are set: on this shared machine "
        "OpenBLAS's threads waiting for a busy core made numpy's SVD, and so the eigenspace "
        "method, many times slower from one run to the next)\n"
        f"- {_runs_line(results)}; the benchmarks took {format_seconds(total)} in all\n"
        "- The machine is shared and may be busy with other jobs: absolute times move from "
        "run to run. The two times of a ratio are measured in the same run, one after the "
        "other, so a busy machine slows both, though not always equally.\n",
        "## Table\n",
        full_table(_all_rows(results)),
    ]
    if experiments is not None:
        parts.append(experiments_section(experiments))
    return "\n".join(part.rstrip("\n") + "\n" for part in parts)


def write_benchmarks_readme() -> None:
    """Rewrite benchmarks/README.md from results.json and experiments.json (nothing else)."""
    results = json.loads(RESULTS.read_text(encoding="utf-8"))
    atomic_write_text(HERE / "README.md", benchmarks_readme(results, load_experiments()))


def run_benchmark(name: str, *, quick: bool) -> dict[str, Any]:
    """Run one script's rows() in a new Python process; its rows, date and duration."""
    module = BENCHMARKS[name][0].removesuffix(".py")
    env = dict(os.environ)
    for variable in BLAS_VARIABLES:
        env.setdefault(variable, "1")
    env["PYTHONPATH"] = os.pathsep.join(
        [str(ROOT), str(HERE)] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else [])
    )
    date = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "rows.json"
        start = time.perf_counter()
        command = [sys.executable, "-c", CHILD, module, "quick" if quick else "full", str(out)]
        subprocess.run(command, cwd=ROOT, env=env, check=True)
        seconds = time.perf_counter() - start
        rows = json.loads(out.read_text(encoding="utf-8"))
    return {"rows": rows, "seconds": seconds, "date": date, "quick": quick, "machine": machine()}


def kept_entry(previous: dict[str, Any] | None, entry: dict[str, Any]) -> dict[str, Any]:
    """The entry a benchmark's run leaves in results.json: the new one, unless it found
    nothing to measure (no rows: no GPU, or an optional reference not installed) where the
    previous one has rows, which stay with their date and machine (a run without a GPU or
    without python-flint does not erase what one with them measured)."""
    if entry["rows"] or not previous or not previous.get("rows"):
        return entry
    return previous


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller sizes and repeats")
    parser.add_argument(
        "--only", nargs="+", choices=list(BENCHMARKS), metavar="NAME", help="run only these"
    )
    parser.add_argument(
        "--no-run",
        action="store_true",
        help="run nothing: rewrite the files from benchmarks/results.json",
    )
    args = parser.parse_args(argv)
    results: dict[str, Any] = {"machine": machine(), "benchmarks": {}}
    previous = json.loads(RESULTS.read_text(encoding="utf-8")) if RESULTS.is_file() else None
    if (args.only or args.no_run) and previous is not None:
        # the table's machine stays: a benchmark rerun elsewhere (a GPU machine) says where
        results = previous
    failed = []
    for name in [] if args.no_run else args.only or list(BENCHMARKS):
        print(f"{name}: running {BENCHMARKS[name][0]}", file=sys.stderr, flush=True)
        try:
            entry = run_benchmark(name, quick=args.quick)
        except subprocess.CalledProcessError as exc:
            print(f"{name}: failed with exit status {exc.returncode}", file=sys.stderr)
            failed.append(name)
            continue
        before = (previous or {}).get("benchmarks", {}).get(name)
        results["benchmarks"][name] = kept_entry(before, entry)
        print(f"{name}: {format_seconds(entry['seconds'])}", file=sys.stderr, flush=True)
        if results["benchmarks"][name] is before and before is not entry:
            print(f"{name}: nothing to measure here; its rows of {before.get('date', '?')} kept",
                  file=sys.stderr, flush=True)  # fmt: skip
    if not results["benchmarks"]:
        return 1
    atomic_write_text(RESULTS, json.dumps(results, indent=1) + "\n")
    atomic_write_text(HERE / "README.md", benchmarks_readme(results, load_experiments()))
    readme = ROOT / "README.md"
    text = readme.read_text(encoding="utf-8")
    atomic_write_text(readme, replace_block(text, compact_block(results)))
    print(compact_table(_all_rows(results)))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
