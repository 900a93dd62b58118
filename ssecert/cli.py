"""The ``ssecert`` command.

Exit status: 0 every required check holds; 1 a required check fails; 3 none
fails but one is inconclusive; 2 bad input or usage; 4 internal error.
"""

from __future__ import annotations

import argparse
import sys
import time
import traceback
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NoReturn, TextIO

from . import __version__

__all__ = ["main"]

EXIT_BAD_INPUT = 2
EXIT_INTERNAL = 4


class UsageError(Exception):
    """Bad command-line usage (exit status 2)."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:  # one line, no usage dump
        raise UsageError(f"{message} (see '{self.prog} --help')")


class _Progress:
    """Throttled progress on a terminal; silent otherwise."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream
        self.enabled = stream.isatty()
        self.start = time.monotonic()
        self.last = 0.0
        self.shown = False

    def __call__(self, label: str, done: int, total: int) -> None:
        if not self.enabled:
            return
        now = time.monotonic()
        if now - self.start < 1.0 or (now - self.last < 0.25 and done < total):
            return
        self.last = now
        pct = 100.0 * done / max(total, 1)
        self.stream.write(f"\r{label}: {done:,}/{total:,} sets ({pct:5.1f}%)   ")
        self.stream.flush()
        self.shown = True

    def close(self) -> None:
        if self.shown:
            self.stream.write("\r" + " " * 70 + "\r")
            self.stream.flush()


def _nonnegative_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {value}")
    return value


def _positive_int(text: str) -> int:
    try:
        if "e" in text.lower():  # 5e7
            number = float(text)
            if not number.is_integer():  # also refuses inf and nan
                raise ValueError(text)
            value = int(number)
        else:
            value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {value}")
    return value


def _add_budget_options(parser: argparse.ArgumentParser) -> None:
    from .budget import parse_bytes, parse_operations

    def checked(parse: Any) -> Any:
        def convert(text: str) -> Any:
            try:
                return parse(text)
            except ValueError as exc:
                raise argparse.ArgumentTypeError(str(exc)) from None
        return convert

    parser.add_argument("--memory-budget", type=checked(parse_bytes), metavar="SIZE",
                        help="memory per analysis step, e.g. 512M or 8G (default 2G)")
    parser.add_argument("--work-budget", type=checked(parse_operations), metavar="FLOPS",
                        help="floating-point operations per analysis step (default 1e12)")


def _budget(args: argparse.Namespace) -> Any:
    from .budget import Budget

    return Budget(**{key: value for key, value in (("memory", args.memory_budget),
                                                   ("work", args.work_budget)) if value})


def _add_analysis_options(parser: argparse.ArgumentParser) -> None:
    """Options shared by ``certify`` and ``analyze``."""
    parser.add_argument("--max-attacked", type=_nonnegative_int, metavar="S",
                        help="number of attacked sensors s (required for .npz/.mat)")
    parser.add_argument("--horizon", type=_positive_int, metavar="T",
                        help="stacked horizon tau (default: the spec's, else n)")
    parser.add_argument("--max-sets", type=_positive_int, metavar="N", default=50_000_000,
                        help="enumeration budget in sets (default 5e7)")
    parser.add_argument("--method", choices=("auto", "enumeration", "eigenspace"),
                        default="auto", help="sparse-observability method (default auto)")
    _add_budget_options(parser)


def _build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="ssecert",
        description="Certify secure state estimation under sparse sensor attacks.",
    )
    parser.add_argument("--version", action="version", version=f"ssecert {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    certify = sub.add_parser(
        "certify",
        help="the main job: every check, the simulations, an HTML report and a JSON certificate",
        description=(
            "Run every analysis that applies to SPEC (structure, gains, certificates, simulations "
            "of its scenarios and of the stealthy attack when one exists), write DIR/NAME.html "
            "and DIR/NAME.json and print a compact verdict table. Without SPEC, certify the "
            "packaged UGV example (which fails by design: its position sensor is a single point "
            "of failure)."
        ),
    )
    certify.add_argument("spec", metavar="SPEC", nargs="?", default="ugv",
                         help="spec file or packaged example name (default: ugv)")
    certify.add_argument("--out", metavar="DIR", default="reports",
                         help="folder for NAME.html and NAME.json (default ./reports)")
    certify.add_argument("--json", metavar="PATH", dest="json_path",
                         help="also write the JSON certificate to PATH ('-' for stdout)")
    certify.add_argument("--seed", type=_nonnegative_int, metavar="N",
                         help="replace every scenario's seed")
    certify.add_argument("--no-sim", action="store_true", help="skip the simulations")
    certify.add_argument("--runs", type=_positive_int, metavar="N",
                         help="runs per scenario (default: the spec's)")
    _add_analysis_options(certify)

    analyze = sub.add_parser(
        "analyze",
        help="run every structural check of a design (no simulations, no report)",
        description=(
            "Observability, s-sparse observability (breaking sensor set and stealthy attack) "
            "and the irrepresentable constant of a design. SPEC is a .toml, .json, .npz or "
            ".mat file, or the name of a packaged example (see 'ssecert examples')."
        ),
    )
    analyze.add_argument("spec", metavar="SPEC", help="spec file or packaged example name")
    analyze.add_argument("--json", metavar="PATH", dest="json_path",
                         help="write the JSON certificate to PATH ('-' for stdout)")
    _add_analysis_options(analyze)
    analyze.add_argument("--seed", type=_nonnegative_int, default=0, metavar="N",
                         help="seed of the simulated stealthy-attack check (default 0)")

    simulate = sub.add_parser(
        "simulate",
        help="simulate the spec's observer under each of its attack scenarios",
        description=(
            "Monte Carlo simulation of the [observer] of SPEC under each [[scenario]]: final "
            "relative state error, support error and detection delay, with per-step series in "
            "the JSON."
        ),
    )
    simulate.add_argument("spec", metavar="SPEC", help="spec file or packaged example name")
    simulate.add_argument("--json", metavar="PATH", dest="json_path",
                          help="write the results as JSON to PATH ('-' for stdout)")
    simulate.add_argument("--seed", type=_nonnegative_int, metavar="N",
                          help="replace every scenario's seed")
    simulate.add_argument("--runs", type=_positive_int, metavar="N",
                          help="runs per scenario (default: the spec's)")
    simulate.add_argument("--steps", type=_positive_int, metavar="N",
                          help="steps per run (default: the spec's)")
    simulate.add_argument("--max-attacked", type=_nonnegative_int, metavar="S",
                          help="number of attacked sensors s (required for .npz/.mat)")
    simulate.add_argument("--scheduler", metavar="ADDRESS",
                          help="run on an existing Dask scheduler (needs the dist extra)")
    simulate.add_argument("--workers", type=_positive_int, metavar="N",
                          help="run on a local Dask cluster of N worker processes")
    _add_budget_options(simulate)

    examples = sub.add_parser("examples", help="list the packaged examples or print one",
                              description="List packaged example specs, or print one.")
    examples.add_argument("name", nargs="?", help="example to print")
    return parser


def _resolve_spec(text: str) -> Path:
    from .examples import example_path, list_examples

    path = Path(text)
    if path.exists() or path.suffix:
        return path
    if text in list_examples():
        return example_path(text)
    raise UsageError(
        f"{text}: no such file, and no packaged example of that name "
        f"(available: {', '.join(list_examples())})"
    )


def _cmd_analyze(args: argparse.Namespace) -> int:
    from .analyze import analyze
    from .report.json import certificate_json, write_json
    from .report.table import render_table
    from .spec import load_spec

    target = None
    if args.json_path and args.json_path != "-":
        target = Path(args.json_path)
        if target.is_dir():
            raise UsageError(f"--json {args.json_path}: is a folder, expected a file path")
        if not target.parent.exists():
            raise UsageError(f"--json {args.json_path}: folder {target.parent} does not exist")
    spec = load_spec(_resolve_spec(args.spec), max_attacked=args.max_attacked,
                     horizon=args.horizon)
    to_stdout_json = args.json_path == "-"
    human = sys.stderr if to_stdout_json else sys.stdout
    progress = _Progress(sys.stderr)
    try:
        cert = analyze(spec, method=args.method, max_sets=args.max_sets, seed=args.seed,
                       progress=progress, budget=_budget(args))
    finally:
        progress.close()
    human.write(render_table(cert))
    if to_stdout_json:
        sys.stdout.write(certificate_json(cert))
    elif target is not None:
        try:
            write_json(cert, target)
        except OSError as exc:
            raise UsageError(f"--json {args.json_path}: cannot write: "
                             f"{exc.strerror or exc}") from None
        human.write(f"JSON written to {target}\n")
    return cert.exit_code


def _cmd_certify(args: argparse.Namespace, argv: Sequence[str] | None) -> int:
    import json

    from .certify import certify
    from .report.html import render_report
    from .report.table import render_table
    from .spec import load_spec
    from ._io import atomic_write_text

    out_dir = Path(args.out)
    if out_dir.exists() and not out_dir.is_dir():
        raise UsageError(f"--out {args.out}: exists and is not a folder")
    target = None
    if args.json_path and args.json_path != "-":
        target = Path(args.json_path)
        if target.is_dir() or not target.parent.exists():
            raise UsageError(f"--json {args.json_path}: expected a file path in an existing folder")
    spec = load_spec(_resolve_spec(args.spec), max_attacked=args.max_attacked,
                     horizon=args.horizon)
    human = sys.stderr if args.json_path == "-" else sys.stdout
    tty = sys.stderr.isatty()

    def say(message: str) -> None:
        if tty:
            sys.stderr.write(f"ssecert: {message}...\n")
            sys.stderr.flush()

    words = ["ssecert", "certify", *(list(argv) if argv is not None else sys.argv[2:])]
    command = " ".join(words if argv is not None else ["ssecert", *sys.argv[1:]])
    result = certify(spec, seed=args.seed, simulate=not args.no_sim, runs=args.runs,
                     method=args.method, max_sets=args.max_sets, progress=say, command=command,
                     budget=_budget(args))
    say("writing the report")
    html = render_report(result)
    document = json.dumps(result.to_dict(), indent=2, allow_nan=False) + "\n"
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        html_path = atomic_write_text(out_dir / f"{spec.name}.html", html)
        json_path = atomic_write_text(out_dir / f"{spec.name}.json", document)
        if target is not None:
            atomic_write_text(target, document)
    except OSError as exc:
        raise UsageError(f"cannot write the report: {exc.strerror or exc}") from None
    human.write(render_table(result.certificate, compact=True))
    human.write(f"report: {html_path}\ncertificate: {json_path}\n")
    if args.json_path == "-":
        sys.stdout.write(document)
    return result.exit_code


def _cmd_simulate(args: argparse.Namespace) -> int:
    import contextlib
    import json

    from .results import to_jsonable
    from .simulation.engine import simulate_spec
    from .spec import load_spec
    from ._io import atomic_write_text

    target = None
    if args.json_path and args.json_path != "-":
        target = Path(args.json_path)
        if target.is_dir() or not target.parent.exists():
            raise UsageError(f"--json {args.json_path}: expected a file path in an existing folder")
    spec = load_spec(_resolve_spec(args.spec), max_attacked=args.max_attacked)
    if spec.observer is None or not spec.scenarios:
        raise UsageError(f"{spec.source}: simulate needs an [observer] section and at least one "
                         f"[[scenario]]")
    context: Any = contextlib.nullcontext(None)
    if args.scheduler or args.workers:
        from .parallel import dask_client

        context = dask_client(args.scheduler, workers=args.workers)
    with context as client:
        results = simulate_spec(spec, seed=args.seed, runs=args.runs, steps=args.steps,
                                client=client, budget=_budget(args))
    human = sys.stderr if args.json_path == "-" else sys.stdout
    human.write(_simulation_table(spec, results["scenarios"]))
    document = {"ssecert_version": __version__, "system": spec.system.to_dict(),
                "scenarios": {name: (r.to_dict() if hasattr(r, "to_dict") else r)
                              for name, r in results["scenarios"].items()}}
    text = json.dumps(to_jsonable(document), indent=2, allow_nan=False) + "\n"
    if args.json_path == "-":
        sys.stdout.write(text)
    elif target is not None:
        try:
            atomic_write_text(target, text)
        except OSError as exc:
            raise UsageError(f"--json {args.json_path}: cannot write: "
                             f"{exc.strerror or exc}") from None
        human.write(f"JSON written to {target}\n")
    return 0


def _simulation_table(spec: Any, scenarios: dict[str, Any]) -> str:
    rows = [("scenario", "attack", "runs", "steps", "rel. error mean", "q90", "support error",
             "delay (median)")]
    notes = []
    for name, res in scenarios.items():
        if isinstance(res, dict):
            rows.append((name, "-", "-", "-", "skipped", "", "", ""))
            notes.append(f"{name}: {res['skipped']}")
            continue
        f = res.final()
        fmt = lambda v: "-" if v is None else f"{v:.3g}"  # noqa: E731
        rows.append((name, res.attack, str(res.runs), str(res.steps),
                     fmt(f["relative_error_mean"]), fmt(f["relative_error_q90"]),
                     fmt(f["support_error_mean"]), fmt(f.get("detection_delay_median"))))
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = [f"ssecert simulate: {spec.name} ({spec.observer['kind']} observer), final step", ""]
    for j, row in enumerate(rows):
        lines.append("  ".join(c.ljust(w) for c, w in zip(row, widths)).rstrip())
        if j == 0:
            lines.append("  ".join("-" * w for w in widths))
    lines.extend(["", *notes] if notes else [])
    return "\n".join(lines) + "\n"


def _cmd_examples(args: argparse.Namespace) -> int:
    from .examples import example_path, list_examples

    if args.name is None:
        for name in list_examples():
            sys.stdout.write(f"{name}\n")
        return 0
    try:
        path = example_path(args.name)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    sys.stdout.write(path.read_text())
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``ssecert`` command; returns the exit status."""
    from .budget import ResourceLimitError
    from .design.gains import GainError
    from .spec import SpecError

    parser = _build_parser()
    try:
        args = parser.parse_args(argv)
        if args.command is None:
            raise UsageError("no command given; use 'ssecert certify [SPEC]', "
                             "'ssecert analyze SPEC' or 'ssecert examples' "
                             "(see 'ssecert --help')")
        if args.command == "analyze":
            return _cmd_analyze(args)
        if args.command == "certify":
            return _cmd_certify(args, argv[1:] if argv is not None else None)
        if args.command == "examples":
            return _cmd_examples(args)
        if args.command == "simulate":
            return _cmd_simulate(args)
        raise UsageError(f"unknown command {args.command!r}")  # pragma: no cover
    except (UsageError, SpecError, ResourceLimitError) as exc:
        sys.stderr.write(f"ssecert: error: {exc}\n")
        return EXIT_BAD_INPUT
    except GainError as exc:
        sys.stderr.write(f"ssecert: error: the spec's observer gain cannot be computed: {exc}\n")
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        sys.stderr.write("ssecert: interrupted\n")
        return 130
    except BrokenPipeError:  # pragma: no cover - e.g. piping into head
        return 0
    except Exception as exc:  # noqa: BLE001 - report, ask for a bug report
        sys.stderr.write(
            f"ssecert: internal error: {type(exc).__name__}: {exc}\n"
            "This is a bug in ssecert; please report it with the command and spec file that "
            "triggered it. Details:\n"
        )
        traceback.print_exc(limit=6, file=sys.stderr)
        return EXIT_INTERNAL


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
