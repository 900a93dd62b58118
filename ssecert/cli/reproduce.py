"""``ssecert reproduce``: the documents' experiments beside their numbers
(``ssecert.experiments``)."""

from __future__ import annotations

import argparse
import sys
import textwrap
from typing import Any

from .options import _nonnegative_int, _positive_int

__all__: list[str] = []


def add_reproduce_parser(sub: Any) -> None:
    reproduce = sub.add_parser(
        "reproduce",
        help="run the documents' experiments beside the numbers they report",
        description=(
            "Run the experiments of the documents ssecert is built from (every table, figure "
            "and worked example has an ID: DOCUMENT.figN, DOCUMENT.tableN, DOCUMENT.exampleN) "
            "and write DIR/reproduce.html and DIR/reproduce.json: the document's numbers and "
            "ours under the same keys, the settings the document leaves unstated and the "
            "values chosen, and an agreement line computed from the numbers (reproduced, "
            "close, differs, not comparable, or not run with the reason)."
        ),
    )
    reproduce.add_argument("ids", nargs="*", metavar="ID", help="experiments to run (default all)")
    reproduce.add_argument(
        "--list", action="store_true", help="list every experiment ID with where it is and stop"
    )
    reproduce.add_argument(
        "--quick",
        action="store_true",
        help="a few runs of each experiment (the default unless --runs is given)",
    )
    reproduce.add_argument(
        "--runs",
        type=_positive_int,
        default=None,
        metavar="N",
        help="runs of each randomised experiment (default: a few; the documents' counts are "
        "listed in each entry)",
    )
    reproduce.add_argument(
        "--seed", type=_nonnegative_int, default=0, metavar="S", help="seed of every draw"
    )
    reproduce.add_argument(
        "--out",
        default="reports",
        metavar="DIR",
        help="folder of reproduce.html and reproduce.json (default ./reports)",
    )


def cmd_reproduce(args: argparse.Namespace) -> int:
    """List or run the experiments; 0 once listed or once both files are written."""
    from ..experiments import (
        Settings,
        all_experiments,
        render_reproduce,
        reproduce_json,
        run_experiments,
    )
    from .files import UsageError, output_folder, write_outputs

    registry = all_experiments()
    unknown = [i for i in args.ids if i not in registry]
    if unknown:
        raise UsageError(
            f"{unknown[0]}: no such experiment (see 'ssecert reproduce --list'; the IDs: "
            f"{', '.join(registry)})"
        )
    if args.list:
        width = max(len(i) for i in registry)
        for entry in registry.values():
            state = "" if entry.run is not None else "  [not run]"
            print(f"{entry.id:<{width}}  {entry.where}{state}")
            print(textwrap.fill(entry.measures, 96, initial_indent=" " * (width + 2) + "measures: ",
                                subsequent_indent=" " * (width + 4)))  # fmt: skip
            if entry.run is None:
                print(textwrap.fill(entry.why_not, 96, initial_indent=" " * (width + 2) + "why: ",
                                    subsequent_indent=" " * (width + 4)))  # fmt: skip
        return 0
    folder = output_folder("--out", args.out)
    settings = Settings(quick=args.runs is None, runs=args.runs, seed=args.seed)
    tty = sys.stderr.isatty()

    def progress(experiment_id: str) -> None:
        if tty:
            sys.stderr.write(f"\rrunning {experiment_id} ...{' ' * 30}")
            sys.stderr.flush()

    outcomes = run_experiments(args.ids or None, settings, progress=progress)
    if tty:
        sys.stderr.write("\r" + " " * 70 + "\r")
    html, js = folder / "reproduce.html", folder / "reproduce.json"
    write_outputs({html: render_reproduce(outcomes), js: reproduce_json(outcomes)})
    width = max(len(o.experiment.id) for o in outcomes)
    for o in outcomes:
        print(f"{o.experiment.id:<{width}}  {o.agreement.words}")
    print(f"reproduce written to {html} and {js}")
    return 0
