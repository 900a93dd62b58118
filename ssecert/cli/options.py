"""The options of the ``ssecert`` command: their types, the budget and Dask options.

``ssecert.cli`` builds its parser from these: the option types refuse a bad
value with one line naming what was expected, and the shared option groups
(analysis, budget, Dask) are added to each command that takes them; what the
command shows while it works is ``ssecert.cli.progress``.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
from typing import Any

__all__: list[str] = []

_INT64_MAX = 2**63 - 1


def _shown(text: str) -> str:
    return repr(text if len(text) <= 40 else text[:37] + "...")


def _integer(text: str, minimum: int, *, scientific: bool = False) -> int:
    """An integer option in [minimum, 2^63 - 1]; ``5e7`` too when ``scientific``."""
    try:
        if len(text) > 40:
            raise ValueError(text)
        if scientific and "e" in text.lower():  # 5e7
            number = float(text)
            if not number.is_integer():  # also refuses inf and nan
                raise ValueError(text)
            value = int(number)
        else:
            value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {_shown(text)}") from None
    if value < minimum:
        raise argparse.ArgumentTypeError(f"expected an integer >= {minimum}, got {value}")
    if value > _INT64_MAX:
        raise argparse.ArgumentTypeError(
            f"expected an integer <= {_INT64_MAX:,} (64 bits), got {_shown(text)}"
        )
    return value


def _nonnegative_int(text: str) -> int:
    return _integer(text, 0)


def _positive_int(text: str) -> int:
    return _integer(text, 1, scientific=True)


def _horizon(text: str) -> int:
    from ..spec.core import MAX_HORIZON

    value = _integer(text, 1, scientific=True)
    if value > MAX_HORIZON:
        raise argparse.ArgumentTypeError(f"expected an integer <= {MAX_HORIZON:,}, got {value:,}")
    return value


def _local_workers(text: str) -> int:
    from ..parallel import max_local_workers

    value = _integer(text, 1, scientific=True)
    limit = max_local_workers()
    if value > limit:
        raise argparse.ArgumentTypeError(
            f"expected at most {limit} local worker processes (four per core of this "
            f"machine), got {_shown(text)}; a larger cluster is one --scheduler ADDRESS away"
        )
    return value


def _nonnegative(text: str, what: str, finite: str) -> float:
    """A finite, non-negative number (``what`` and ``finite`` name it in the messages)."""
    try:
        if len(text) > 40:
            raise ValueError(text)
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}, got {_shown(text)}") from None
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(
            f"expected a finite {what.removeprefix('a ')} >= 0, got {text}"
        )
    return value


def _seconds(text: str) -> float:
    """A finite, non-negative number of seconds."""
    return _nonnegative(text, "seconds", "number of seconds")


def _noise_bound(text: str) -> float:
    """A finite, non-negative noise bound."""
    return _nonnegative(text, "a noise bound", "noise bound")


def _add_budget_options(parser: argparse.ArgumentParser) -> None:
    from ..budget import parse_bytes, parse_operations

    def checked(parse: Any) -> Any:
        def convert(text: str) -> Any:
            try:
                return parse(text)
            except ValueError as exc:
                raise argparse.ArgumentTypeError(str(exc)) from None

        return convert

    parser.add_argument(
        "--memory-budget",
        type=checked(parse_bytes),
        metavar="SIZE",
        help="memory per analysis step, e.g. 512M or 8G (default 2G)",
    )
    parser.add_argument(
        "--work-budget",
        type=checked(parse_operations),
        metavar="FLOPS",
        help="floating-point operations per analysis step (default 1e12)",
    )


def _budget(args: argparse.Namespace) -> Any:
    from ..budget import Budget

    return Budget(
        **{
            key: value
            for key, value in (("memory", args.memory_budget), ("work", args.work_budget))
            if value
        }
    )


def _add_output_options(parser: argparse.ArgumentParser) -> None:
    """--quiet and --verbose."""
    talk = parser.add_mutually_exclusive_group()
    talk.add_argument(
        "--quiet",
        action="store_true",
        help="print nothing but errors (files and --json - are written as usual)",
    )
    talk.add_argument(
        "--verbose",
        action="store_true",
        help="say each step of the analysis as it ends, with its seconds, on stderr",
    )


def _steps(args: argparse.Namespace) -> Any:
    """A context telling stderr of each step as it ends under --verbose (else nothing)."""
    if not getattr(args, "verbose", False):
        return contextlib.nullcontext()
    from ..budget import reporting

    def report(step: str, seconds: float) -> None:
        sys.stderr.write(f"ssecert: {step.replace('_', ' ')}: {seconds:.2f} s\n")
        sys.stderr.flush()

    return reporting(report)


def _solver(args: argparse.Namespace) -> Any:
    """A context solving the LMIs with the solver ``--solver`` names (checked at once)."""
    name = getattr(args, "solver", None)
    if not name:
        return contextlib.nullcontext()
    from ..solvers import check_solver, using_solver
    from .files import UsageError

    try:
        check_solver(name)
    except ValueError as exc:
        raise UsageError(f"--solver {name}: {exc}") from None
    return using_solver(name)


def _add_dask_options(parser: argparse.ArgumentParser, work: str) -> None:
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help=f"run {work} on an existing Dask scheduler (needs the dist extra)",
    )
    parser.add_argument(
        "--workers",
        type=_local_workers,
        metavar="N",
        help=f"run {work} on a local Dask cluster of N worker processes",
    )


def _dask(args: argparse.Namespace) -> Any:
    """A context giving the Dask client the options ask for, else None."""
    if not (args.scheduler or args.workers):
        return contextlib.nullcontext(None)
    from ..parallel import dask_client

    return dask_client(args.scheduler, workers=args.workers)


def _device(args: argparse.Namespace) -> str | None:
    """The device ``--device`` asks for, checked to be usable here (None: the CPU)."""
    from ..structure.device import resolve_device

    return resolve_device(getattr(args, "device", "cpu"))


def _add_analysis_options(parser: argparse.ArgumentParser) -> None:
    """Options shared by ``certify`` and ``analyze``."""
    from ..budget import DEFAULT_TIME_BUDGET

    parser.add_argument(
        "--max-attacked",
        type=_nonnegative_int,
        metavar="S",
        help="number of attacked sensors s (required for .npz/.mat)",
    )
    parser.add_argument(
        "--horizon",
        type=_horizon,
        metavar="T",
        help="stacked horizon tau (default: the spec's, else n)",
    )
    parser.add_argument(
        "--max-sets",
        type=_positive_int,
        metavar="N",
        default=50_000_000,
        help="enumeration budget in sets (default 5e7)",
    )
    parser.add_argument(
        "--noise",
        type=_noise_bound,
        metavar="ETA",
        default=None,
        help="measurement noise within ETA on every sample of every sensor, replacing the "
        "spec's [noise] measurement bound (its process noise stays): adds the certified "
        "worst-case errors of the l0, l1 and Lasso decoders (decoder_error_bound, "
        "l1_error_bound, lasso_error_bound)",
    )
    parser.add_argument(
        "--method",
        choices=("auto", "enumeration", "eigenspace"),
        default="auto",
        help="sparse-observability method (default auto)",
    )
    parser.add_argument(
        "--solver",
        metavar="NAME",
        default=None,
        help="conic solver of the LMIs, any installed one cvxpy supports for them (default "
        "CLARABEL; every certificate is re-verified in numpy whichever solves it)",
    )
    parser.add_argument(
        "--device",
        choices=("cpu", "cuda"),
        default="cpu",
        help="screen the enumeration's sensor sets on this device (cuda: PyTorch or CuPy, the "
        "gpu extra; the answer is the CPU's)",
    )
    refine = parser.add_mutually_exclusive_group()
    refine.add_argument(
        "--time-budget",
        type=_seconds,
        metavar="SECONDS",
        default=DEFAULT_TIME_BUDGET,
        help=(
            "seconds spent refining max_removable once the verdict is decided; beyond it "
            f"max_removable is a lower bound (default {DEFAULT_TIME_BUDGET:g})"
        ),
    )
    refine.add_argument(
        "--exact",
        action="store_const",
        const=None,
        dest="time_budget",
        help="compute the exact max_removable however long it takes",
    )
    _add_budget_options(parser)
