"""The ``ssecert`` command.

Exit status: 0 every required check holds; 1 a required check fails; 3 none
fails but one is inconclusive; 2 bad input or usage (one line on stderr, no
traceback); 4 internal error.

Output paths are checked before the checks run, so a typo costs seconds, not
the whole run; reports are written all or nothing (``ssecert.base.atomic``).  Python
warnings raised by the numerical code while a command runs do not reach the
terminal as such: each distinct one becomes a one-line note in the output and
in the report (where it was raised and how often), because a floating-point
overflow may explain an inconclusive verdict; deprecation warnings of the
libraries, which say nothing about the design, are dropped.

This module builds the parser and runs ``certify``, ``analyze``, ``simulate``
and ``examples``; the package's other modules hold the options shared by the
commands (``options``), the spec argument and the output files (``files``),
and the ``audit`` and ``design`` commands.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import traceback
import warnings
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, NoReturn

from .._version import __version__
from .audit import add_audit_parser, cmd_audit
from .design import add_design_parser, cmd_design
from .files import (
    UsageError,
    load_argument,
    output_file,
    output_folder,
    separate_outputs,
    write_outputs,
)
from .options import (
    _add_analysis_options,
    _add_budget_options,
    _add_dask_options,
    _add_output_options,
    _budget,
    _dask,
    _device,
    _nonnegative_int,
    _positive_int,
    _solver,
    _steps,
)
from .progress import stage_display
from .reproduce import add_reproduce_parser, cmd_reproduce

__all__ = ["main"]

EXIT_BAD_INPUT = 2
EXIT_INTERNAL = 4
EXIT_BROKEN_PIPE = 141  # 128 + SIGPIPE, what a shell reports for a closed pipe


class _Parser(argparse.ArgumentParser):
    """The command's parsers: one-line errors, and arguments completed when first used."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        # what completes this parser's arguments (choices and help that cost imports), run
        # before it parses or formats its help: a command pays only for its own parser's
        self.completions: list[Callable[[], None]] = []

    def _complete(self) -> None:
        while self.completions:
            self.completions.pop(0)()

    def parse_known_args(self, args: Any = None, namespace: Any = None) -> Any:
        self._complete()
        return super().parse_known_args(args, namespace)

    def format_usage(self) -> str:
        self._complete()
        return super().format_usage()

    def format_help(self) -> str:
        self._complete()
        return super().format_help()

    def error(self, message: str) -> NoReturn:  # one line, no usage dump
        raise UsageError(f"{message} (see '{self.prog} --help')")


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
    certify.add_argument(
        "spec",
        metavar="SPEC",
        nargs="?",
        default="ugv",
        help="spec file or packaged example name (default: ugv)",
    )
    certify.add_argument(
        "--out",
        metavar="DIR",
        default="reports",
        help="folder for NAME.html and NAME.json (default ./reports)",
    )
    certify.add_argument(
        "--json",
        metavar="PATH",
        dest="json_path",
        help="also write the JSON certificate to PATH ('-' for stdout)",
    )
    certify.add_argument(
        "--seed", type=_nonnegative_int, metavar="N", help="replace every scenario's seed"
    )
    certify.add_argument("--no-sim", action="store_true", help="skip the simulations")
    certify.add_argument(
        "--runs", type=_positive_int, metavar="N", help="runs per scenario (default: the spec's)"
    )
    _add_analysis_options(certify)
    _add_dask_options(certify, "the enumeration and the runs")
    _add_output_options(certify)

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
    analyze.add_argument(
        "--json",
        metavar="PATH",
        dest="json_path",
        help="write the JSON certificate to PATH ('-' for stdout)",
    )
    analyze.add_argument(
        "--mat",
        metavar="PATH",
        dest="mat_path",
        help="write the certificate's vectors and matrices to a MATLAB .mat file",
    )
    _add_analysis_options(analyze)
    _add_dask_options(analyze, "the enumeration")
    _add_output_options(analyze)
    analyze.add_argument(
        "--seed",
        type=_nonnegative_int,
        default=0,
        metavar="N",
        help="seed of the simulated stealthy-attack check (default 0)",
    )

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
    simulate.add_argument(
        "--json",
        metavar="PATH",
        dest="json_path",
        help="write the results as JSON to PATH ('-' for stdout)",
    )
    simulate.add_argument(
        "--seed", type=_nonnegative_int, metavar="N", help="replace every scenario's seed"
    )
    simulate.add_argument(
        "--runs", type=_positive_int, metavar="N", help="runs per scenario (default: the spec's)"
    )
    simulate.add_argument(
        "--steps", type=_positive_int, metavar="N", help="steps per run (default: the spec's)"
    )
    simulate.add_argument(
        "--max-attacked",
        type=_nonnegative_int,
        metavar="S",
        help="number of attacked sensors s (required for .npz/.mat)",
    )
    _add_dask_options(simulate, "the runs")
    _add_budget_options(simulate)
    _add_output_options(simulate)

    examples = sub.add_parser(
        "examples",
        help="list the packaged examples or print one",
        description="List packaged example specs, or print one.",
    )
    examples.add_argument("name", nargs="?", help="example to print")

    schema = sub.add_parser(
        "schema",
        help="print the JSON Schema of a spec file or of the certificate",
        description=(
            "Print the JSON Schema (draft 2020-12) of a spec file or of the JSON certificate "
            "of 'ssecert analyze' and 'ssecert certify', built from the code that reads and "
            "writes them: editors and scripts validate against it."
        ),
    )
    schema.add_argument("name", choices=("spec", "certificate"), help="which schema")
    add_audit_parser(sub)
    add_design_parser(sub)
    add_reproduce_parser(sub)
    return parser


class _WarningLog:
    """Python warnings raised during a command, as one-line notes (see the module doc)."""

    DROPPED = (DeprecationWarning, PendingDeprecationWarning, FutureWarning)

    def __init__(self) -> None:
        self.seen: dict[tuple[str, str], list[Any]] = {}

    def show(
        self,
        message: Any,
        category: type[Warning],
        filename: str,
        lineno: int,
        file: Any = None,
        line: Any = None,
    ) -> None:
        text = str(message).strip().splitlines()[0] if str(message).strip() else ""
        key = (category.__name__, text[:200])
        if key in self.seen:
            self.seen[key][0] += 1
        else:
            self.seen[key] = [1, self._origin()]

    @staticmethod
    def _origin() -> str | None:
        """The innermost ssecert module (not the CLI) on the stack."""
        root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # the package
        for frame in reversed(traceback.extract_stack()):
            name = os.path.abspath(frame.filename)
            if name.startswith(root + os.sep) and name != os.path.abspath(__file__):
                module = os.path.relpath(name, os.path.dirname(root))
                return module[: -len(".py")].replace(os.sep, ".")
        return None

    def notes(self, *, besides: _WarningLog | None = None) -> list[str]:
        """One line per distinct warning (those of ``besides`` left out)."""
        from ..spec import one_line

        notes = []
        for (category, text), (count, origin) in self.seen.items():
            if besides is not None and (category, text) in besides.seen:
                continue
            where = [f"in {origin}"] if origin else []
            where += [f"{count} times"] if count > 1 else []
            kind = "" if category in ("RuntimeWarning", "UserWarning") else f"{category}: "
            place = f" ({', '.join(where)})" if where else ""
            notes.append(one_line(f"{kind}{text}{place}"))
        return notes


@contextmanager
def _warnings_as_notes() -> Iterator[_WarningLog]:
    log = _WarningLog()
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        for category in _WarningLog.DROPPED:
            warnings.simplefilter("ignore", category)
        warnings.showwarning = log.show
        yield log


class _Silent:
    """Where --quiet sends what a command would print for people."""

    def write(self, text: str) -> int:
        return len(text)

    def flush(self) -> None:
        pass


def _load(text: str, **overrides: Any) -> tuple[Any, list[str]]:
    """The spec argument (``load_argument``) and the notes its reading raised (the variables of
    a MATLAB save that are not used, say)."""
    with _warnings_as_notes() as log:
        spec = load_argument(text, **overrides)
    return spec, log.notes()


def _cmd_analyze(args: argparse.Namespace) -> int:
    from ..analyze import analyze
    from ..report.json import certificate_json
    from ..report.table import render_table

    target = output_file("--json", args.json_path)
    if args.mat_path == "-":
        raise UsageError("--mat -: a .mat file is binary; give a file path")
    mat_target = output_file("--mat", args.mat_path)
    separate_outputs(args.spec, [("--json", target), ("--mat", mat_target)])
    spec, load_notes = _load(
        args.spec, max_attacked=args.max_attacked, horizon=args.horizon, noise=args.noise
    )
    to_stdout_json = args.json_path == "-"
    human = _Silent() if args.quiet else sys.stderr if to_stdout_json else sys.stdout
    device = _device(args)  # before any work: an unusable device is refused at once
    solver = _solver(args)  # likewise an unusable solver
    display = stage_display(quiet=args.quiet, verbose=args.verbose, json_to_stdout=to_stdout_json)
    with (
        display.showing(),
        _warnings_as_notes() as log,
        _dask(args) as client,
        _steps(args),
        solver,
    ):
        cert = analyze(
            spec,
            method=args.method,
            max_sets=args.max_sets,
            seed=args.seed,
            progress=display,
            budget=_budget(args),
            time_budget=args.time_budget,
            client=client,
            device=device,
        )
    if load_notes or log.notes():
        meta = dict(cert.meta or {})
        meta["notes"] = [*meta.get("notes", []), *load_notes, *log.notes()]
        cert = dataclasses.replace(cert, meta=meta)
    with _warnings_as_notes() as render_log:
        document = certificate_json(cert)
        table = render_table(cert)
    outputs: dict[Path, str | bytes] = {}
    if target is not None:
        outputs[target] = document
    if mat_target is not None:
        from ..report.mat import certificate_mat

        outputs[mat_target] = certificate_mat(cert)
    if outputs:
        write_outputs(outputs)  # both or neither
    human.write(table)
    for note in render_log.notes(besides=log):
        human.write(f"note: {note}\n")
    if to_stdout_json:
        sys.stdout.write(document)
    elif target is not None:
        human.write(f"JSON written to {args.json_path}\n")
    if mat_target is not None:
        human.write(f"matrices written to {args.mat_path}\n")
    return cert.exit_code


def _cmd_certify(args: argparse.Namespace, argv: Sequence[str] | None) -> int:
    from ..certify import certify
    from ..report.html import render_report
    from ..report.json import certify_json
    from ..report.table import render_table

    out_dir = output_folder("--out", args.out)
    target = output_file("--json", args.json_path)
    spec, load_notes = _load(
        args.spec, max_attacked=args.max_attacked, horizon=args.horizon, noise=args.noise
    )
    html_path, json_path = out_dir / f"{spec.name}.html", out_dir / f"{spec.name}.json"
    for path in (html_path, json_path):
        if path.is_dir():
            raise UsageError(f"--out {args.out}: {path} is a folder; the report needs that name")
    # (--json may name the folder's certificate: the same document)
    separate_outputs(
        args.spec, [(f"--out {args.out}", html_path), (f"--out {args.out}", json_path)]
    )
    separate_outputs(args.spec, [("--json", target)])
    human = _Silent() if args.quiet else sys.stderr if args.json_path == "-" else sys.stdout
    display = stage_display(
        quiet=args.quiet, verbose=args.verbose, json_to_stdout=args.json_path == "-"
    )
    device = _device(args)  # before any work: an unusable device is refused at once
    solver = _solver(args)  # likewise an unusable solver
    words = ["ssecert", "certify", *(list(argv) if argv is not None else sys.argv[2:])]
    command = " ".join(words if argv is not None else ["ssecert", *sys.argv[1:]])
    with display.showing():
        with _warnings_as_notes() as log, _dask(args) as client, _steps(args), solver:
            result = certify(
                spec,
                seed=args.seed,
                simulate=not args.no_sim,
                runs=args.runs,
                method=args.method,
                max_sets=args.max_sets,
                progress=display.say,
                command=command,
                budget=_budget(args),
                time_budget=args.time_budget,
                client=client,
                set_progress=display,
                device=device,
            )
            result.to_dict()  # simulation metrics are computed here: their warnings are notes too
        notes = [*load_notes, *log.notes()]
        if notes:
            result = dataclasses.replace(result, notes=(*result.notes, *notes))
        display.say("writing the report")
        with _warnings_as_notes() as render_log:
            html = render_report(result)
            document = certify_json(result)
        files = {html_path: html, json_path: document}
        if target is not None:
            files[target] = document
        write_outputs(files)
    human.write(render_table(result.certificate, compact=True))
    for note in [*notes, *render_log.notes(besides=log)]:
        human.write(f"note: {note}\n")
    human.write(f"report: {html_path}\ncertificate: {json_path}\n")
    if args.json_path == "-":
        sys.stdout.write(document)
    return result.exit_code


def _cmd_simulate(args: argparse.Namespace) -> int:
    import json

    from ..design.gains import GainError
    from ..results import to_jsonable
    from ..simulation.engine import simulate_spec

    target = output_file("--json", args.json_path)
    separate_outputs(args.spec, [("--json", target)])
    spec, load_notes = _load(args.spec, max_attacked=args.max_attacked)
    if spec.observer is None or not spec.scenarios:
        raise UsageError(
            f"{spec.source}: simulate needs an [observer] section and at least one [[scenario]]"
        )
    display = stage_display(
        quiet=args.quiet, verbose=args.verbose, json_to_stdout=args.json_path == "-"
    )
    with _warnings_as_notes() as log:
        with display.showing(), _dask(args) as client:
            try:
                results = simulate_spec(
                    spec,
                    seed=args.seed,
                    runs=args.runs,
                    steps=args.steps,
                    client=client,
                    budget=_budget(args),
                )
            except GainError as exc:
                gain = spec.observer.get("gain")
                shown = repr(gain) if isinstance(gain, str) else "the given matrix"
                raise UsageError(
                    f"{spec.source}: observer.gain = {shown} cannot be used, so nothing can be "
                    f"simulated: {exc}"
                ) from exc
        document = {
            "ssecert_version": __version__,
            "system": spec.system.to_dict(),
            "scenarios": {
                name: (r.to_dict() if hasattr(r, "to_dict") else r)
                for name, r in results["scenarios"].items()
            },
        }
        table = _simulation_table(spec, results["scenarios"])
    human = _Silent() if args.quiet else sys.stderr if args.json_path == "-" else sys.stdout
    notes = [*load_notes, *log.notes()]
    if notes:
        document["notes"] = notes
    text = json.dumps(to_jsonable(document), indent=2, allow_nan=False) + "\n"
    if target is not None:
        write_outputs({target: text})
    human.write(table)
    for note in notes:
        human.write(f"note: {note}\n")
    if args.json_path == "-":
        sys.stdout.write(text)
    elif target is not None:
        human.write(f"JSON written to {args.json_path}\n")
    return 0


def _simulation_table(spec: Any, scenarios: dict[str, Any]) -> str:
    rows = [
        (
            "scenario",
            "attack",
            "runs",
            "steps",
            "error mean",
            "q90",
            "of initial",
            "rel. error",
            "support error",
            "delay (median)",
        )
    ]
    notes = []
    for name, res in scenarios.items():
        if isinstance(res, dict):
            rows.append((name, "-", "-", "-", "skipped", "", "", "", "", ""))
            notes.append(f"{name}: {res['skipped']}")
            continue
        notes.extend(f"{name}: {note}" for note in getattr(res, "notes", ()))
        f = res.final()
        fmt = lambda v: "-" if v is None else f"{v:.3g}"  # noqa: E731
        rows.append(
            (
                name,
                res.attack,
                str(res.runs),
                str(res.steps),
                fmt(f.get("absolute_error_mean")),
                fmt(f.get("absolute_error_q90")),
                fmt(f.get("initial_relative_error_mean")),
                fmt(f["relative_error_mean"]),
                fmt(f["support_error_mean"]),
                fmt(f.get("detection_delay_median")),
            )
        )
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = [f"ssecert simulate: {spec.name} ({spec.observer['kind']} observer), final step", ""]
    for j, row in enumerate(rows):
        lines.append("  ".join(c.ljust(w) for c, w in zip(row, widths)).rstrip())
        if j == 0:
            lines.append("  ".join("-" * w for w in widths))
    lines.append("")
    lines.append(
        "error: ||x_hat - x|| (mean and 90th percentile over runs); of initial: the mean of "
        "||x_hat - x|| / ||x_hat(0) - x(0)||; rel. error: the mean of ||x_hat - x|| / ||x||, "
        "which grows without bound when the state decays and the error does not."
    )
    lines.extend(["", *notes] if notes else [])
    return "\n".join(lines) + "\n"


def _cmd_schema(args: argparse.Namespace) -> int:
    import json

    from ..schemas import SCHEMAS

    sys.stdout.write(json.dumps(SCHEMAS[args.name](), indent=2) + "\n")
    return 0


def _cmd_examples(args: argparse.Namespace) -> int:
    from ..examples import example_path, list_examples

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
    # The error classes are imported by _failure when something fails, so that
    # nothing numerical is imported before a command needs it.
    given = sys.argv[1:] if argv is None else list(argv)
    if given[:1] == ["--version"]:  # argparse's answer, without building every command's
        sys.stdout.write(f"ssecert {__version__}\n")  # parser (the design kinds import numpy)
        return 0
    parser = _build_parser()
    args = None
    try:
        args = parser.parse_args(argv)
        if args.command is None:
            raise UsageError(
                "no command given; use 'ssecert certify [SPEC]', "
                "'ssecert analyze SPEC' or 'ssecert examples' "
                "(see 'ssecert --help')"
            )
        if args.command == "analyze":
            return _cmd_analyze(args)
        if args.command == "certify":
            return _cmd_certify(args, argv[1:] if argv is not None else None)
        if args.command == "examples":
            return _cmd_examples(args)
        if args.command == "schema":
            return _cmd_schema(args)
        if args.command == "simulate":
            return _cmd_simulate(args)
        if args.command == "audit":
            return cmd_audit(args)
        if args.command == "design":
            return cmd_design(args, argv[1:] if argv is not None else None)
        if args.command == "reproduce":
            return cmd_reproduce(args)
        raise UsageError(f"unknown command {args.command!r}")  # pragma: no cover
    except KeyboardInterrupt:
        sys.stderr.write("ssecert: interrupted\n")
        return 130
    except Exception as exc:
        return _failure(exc, args)


def _failure(exc: Exception, args: argparse.Namespace | None) -> int:
    """Write what failed to stderr and return the exit status for it."""
    from ..budget import ResourceLimitError
    from ..design.gains import GainError
    from ..parallel import ChunkError, DaskUnavailable
    from ..spec import SpecError, one_line
    from ..structure.device import DeviceUnavailable

    if isinstance(exc, (UsageError, SpecError, ResourceLimitError)):
        sys.stderr.write(f"ssecert: error: {one_line(str(exc))}\n")
        return EXIT_BAD_INPUT
    if isinstance(exc, GainError):
        sys.stderr.write(
            f"ssecert: error: the spec's observer gain cannot be computed: {one_line(str(exc))}\n"
        )
        return EXIT_BAD_INPUT
    if isinstance(exc, DaskUnavailable):
        option = "--scheduler" if getattr(args, "scheduler", None) else "--workers"
        sys.stderr.write(f"ssecert: error: {option}: {one_line(str(exc))}\n")
        return EXIT_BAD_INPUT
    if isinstance(exc, DeviceUnavailable):
        device = getattr(args, "device", "cuda")
        sys.stderr.write(f"ssecert: error: --device {device}: {one_line(str(exc))}\n")
        return EXIT_BAD_INPUT
    if isinstance(exc, ChunkError):  # a simulation chunk failed twice on the workers
        sys.stderr.write(f"ssecert: error: {one_line(str(exc))}\n")
        return EXIT_BAD_INPUT
    if isinstance(exc, BrokenPipeError):  # e.g. piping into head: stop quietly
        try:  # and keep the interpreter from complaining when it flushes stdout at exit
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
        except (OSError, ValueError):
            pass
        return EXIT_BROKEN_PIPE
    if isinstance(exc, MemoryError):
        detail = f" ({one_line(str(exc))})" if str(exc) else ""
        sys.stderr.write(
            f"ssecert: error: out of memory{detail}; the problem is too large for "
            f"this machine (if the spec is small, please report this as a bug)\n"
        )
        return EXIT_BAD_INPUT
    sys.stderr.write(
        f"ssecert: internal error: {type(exc).__name__}: {exc}\n"
        "This is a bug in ssecert; please report it with the command and spec file that "
        "triggered it. Details:\n"
    )
    traceback.print_exc(limit=6, file=sys.stderr)
    return EXIT_INTERNAL
