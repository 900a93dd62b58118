"""``ssecert design``: an observer synthesised against its certificate, written as a spec file."""

from __future__ import annotations

import argparse
import json
from typing import Any

__all__: list[str] = []

KIND_NAMES = {"elastic-net": "elastic_net", "elastic_net": "elastic_net", "dsso": "dsso",
              "luenberger": "luenberger"}  # fmt: skip


def add_design_parser(sub: Any) -> None:
    from ._cli_options import _nonnegative_int, _seconds

    design = sub.add_parser(
        "design",
        help="synthesise a certified observer for a spec and write it as a spec file",
        description=(
            "Search the observer of the chosen kind with the best certified guarantee for the "
            "spec's plant: the gain L comes out of the dissipation LMI that certifies it, "
            "(shrink, step) are searched on a grid within the time budget, and every candidate "
            "is certified exactly as 'ssecert analyze' certifies a spec. Writes DIR/NAME-design"
            ".toml (the spec with the synthesised [observer]) and prints the synthesised design "
            "beside the spec's own. Exit status 0 when a design is written, 1 when none of the "
            "grid is certified."
        ),
    )
    design.add_argument("spec", metavar="SPEC", help="spec file or packaged example name")
    design.add_argument(
        "--observer",
        choices=sorted(KIND_NAMES),
        metavar="KIND",
        help="elastic-net, dsso or luenberger (default: the spec's kind if one of those, "
        "else elastic-net)",
    )
    design.add_argument(
        "--objective",
        choices=("gain", "rate"),
        default="gain",
        help="smallest certified l2 gain from attack to error (default) or fastest certified decay",
    )
    design.add_argument("--out", default="reports", metavar="DIR", help="folder of the spec file")
    design.add_argument(
        "--time-budget",
        type=_seconds,
        default=60.0,
        metavar="SECONDS",
        help="time for the search (default 60)",
    )
    design.add_argument(
        "--json", metavar="PATH", dest="json_path", help="write the result as JSON ('-': stdout)"
    )
    design.add_argument(
        "--max-attacked",
        type=_nonnegative_int,
        metavar="S",
        help="number of attacked sensors s (required for .npz/.mat)",
    )


def cmd_design(
    args: argparse.Namespace, load: Any, output_folder: Any, output_file: Any, write: Any
) -> int:
    """Search, write the spec file, print the comparison; 0 when a design is written."""
    import sys

    from ._spec_write import dumps, spec_document
    from .results import to_jsonable
    from .synthesize import design_observer

    folder = output_folder("--out", args.out)
    target = output_file("--json", args.json_path)
    spec = load(args.spec, max_attacked=args.max_attacked)
    own = spec.observer or {}
    own_kind = str(own.get("kind", ""))
    if args.observer:
        kind = KIND_NAMES[args.observer]
    else:
        kind = own_kind if own_kind in ("elastic_net", "dsso", "luenberger") else "elastic_net"
    threshold = float(own.get("threshold") or 0.1)
    result = design_observer(
        spec.system,
        kind,
        objective=args.objective,
        threshold=threshold,
        time_budget=args.time_budget,
    )
    human = sys.stderr if args.json_path == "-" else sys.stdout
    before = _certified(spec) if spec.observer is not None else None
    document: dict[str, Any] = {
        "spec": spec.source,
        "kind": kind,
        "objective": args.objective,
        "design": result.observer,
        "gamma": result.gamma,
        "decay": result.decay,
        "spec_design": before,
        "candidates": result.candidates,
        "seconds": result.seconds,
        "complete": result.complete,
    }
    path = folder / f"{spec.name}-design.toml"
    files: dict[Any, str] = {}
    if result.observer is not None:
        text = (
            f"# Observer synthesised by ssecert design ({kind}, objective {args.objective}):\n"
            f"# certified l2 gain {result.gamma:.6g}, decay {result.decay:.3g} per step.\n"
            + dumps(spec_document(spec, result.observer))
        )
        files[path] = text
        document["spec_file"] = str(path)
    else:
        document["reason"] = result.reason
    rendered = json.dumps(to_jsonable(document), indent=2) + "\n"
    if target is not None:
        files[target] = rendered
    if files:
        write(files)  # every file or none
    searched = f"{len(result.candidates)} candidates in {result.seconds:.1f} s"
    if not result.complete:
        searched += " (the time budget ended the search)"
    human.write(f"ssecert design: {spec.name}, {kind}, objective {args.objective}: {searched}\n")
    if before is not None:
        human.write(
            f"  the spec's design ({before['kind']}): observer_stability {before['stability']}, "
            f"certified l2 gain {_num(before['gamma'])}\n"
        )
    limit = _sparse_limit(spec)
    if limit:
        document["sparse_observability"] = limit
        human.write(f"  note: {limit}\n")
    if result.observer is None:
        human.write(f"  no design: {result.reason}\n")
        if kind == "dsso":
            human.write(
                "  (a D-SSO has shrink 1: when the plant has an eigenvalue at 1 no quadratic "
                "certificate can exist; try --observer elastic-net)\n"
            )
    else:
        params = ", ".join(
            f"{k} {v:g}" for k, v in result.observer.items() if k in ("step", "shrink")
        )
        human.write(
            f"  synthesised ({params or 'gain only'}): observer_stability holds, certified "
            f"l2 gain {_num(result.gamma)}, decay {_num(result.decay)} per step\n"
            f"spec file: {path}\n"
        )
    if args.json_path == "-":
        sys.stdout.write(rendered)
    return 0 if result.observer is not None else 1


def _sparse_limit(spec: Any) -> str:
    """What no observer can do on this plant ('' when it is 2s-sparse observable): the
    certified gain bounds the error under attack, it does not make it vanish."""
    from .structure.sparse import sparse_observability

    check = sparse_observability(spec.system, spec.max_attacked, time_budget=0)
    if check.verdict.value != "fails":
        return ""
    names = [spec.system.sensors[i] for i in check.fields.get("breaking_set") or []]
    return (
        f"no observer can recover the state exactly with {spec.max_attacked} attacked "
        f"sensor(s): the plant is not {2 * spec.max_attacked}-sparse observable (removing "
        f"{', '.join(names) or 'the breaking set'} leaves it unobservable); the design bounds "
        "the error under attack by its certified gain"
    )


def _certified(spec: Any) -> dict[str, Any]:
    """The spec's own design: its stability verdict and certified gain (as analyze gives)."""
    from .observers import build_observer
    from .synthesize import certified_gain

    stability, iss = certified_gain(build_observer(spec.system, spec.observer))
    return {
        "kind": spec.observer["kind"],
        "stability": stability.verdict.value,
        "gamma": iss.value if iss.verdict.value == "holds" else None,
    }


def _num(v: Any) -> str:
    return "none" if v is None else f"{float(v):.4g}"
