"""``ssecert design``: an observer synthesised against its certificate, written as a spec file."""

from __future__ import annotations

import argparse
import dataclasses
import json
from typing import Any

__all__: list[str] = []

KIND_NAMES = {"elastic-net": "elastic_net", "elastic_net": "elastic_net", "dsso": "dsso",
              "luenberger": "luenberger"}  # fmt: skip


def add_design_parser(sub: Any) -> None:
    from ._cli_options import _nonnegative_int, _positive_int, _seconds

    design = sub.add_parser(
        "design",
        help="synthesise a certified observer for a spec and write it as a spec file",
        description=(
            "Search the observer of the chosen kind with the best certified guarantee for the "
            "spec's plant: the gain L comes out of the dissipation LMI that certifies it, "
            "(shrink, step) are searched on a grid within the time budget, and every candidate "
            "is certified exactly as 'ssecert analyze' certifies a spec. The best design is "
            "certified and simulated under the spec's scenarios as 'ssecert certify' does, "
            "beside the spec's own design with the same seeds. Writes DIR/NAME-design.toml (the "
            "spec with the synthesised [observer]), DIR/NAME-design.html (the report, with the "
            "comparison) and DIR/NAME-design.json (the certificate). Exit status 0 when a "
            "design is written, 1 when none is certified."
        ),
    )
    design.add_argument("spec", metavar="SPEC", help="spec file or packaged example name")
    design.add_argument(
        "--observer",
        choices=sorted(KIND_NAMES),
        metavar="KIND",
        help="elastic-net (default; dsso with --objective roa), dsso or luenberger",
    )
    design.add_argument(
        "--objective",
        choices=("gain", "rate", "roa"),
        default="gain",
        help="smallest certified l2 gain from attack to error (default), fastest certified "
        "decay, or (D-SSO) largest certified region of attraction",
    )
    design.add_argument(
        "--out",
        default="reports",
        metavar="DIR",
        help="folder of NAME-design.toml, .html and .json (default reports)",
    )
    design.add_argument(
        "--seed", type=int, help="replaces every scenario's seed (both designs get the same)"
    )
    design.add_argument(
        "--runs", type=_positive_int, metavar="N", help="Monte Carlo runs per scenario"
    )
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
    args: argparse.Namespace,
    load: Any,
    output_folder: Any,
    output_file: Any,
    write: Any,
    usage_error: type[Exception],
) -> int:
    """Search, certify and simulate the best design, write its spec file, report and
    certificate, print the comparison; 0 when a design is written."""
    import hashlib
    import sys
    import tomllib

    from .report.html import render_report
    from .report.json import certify_json
    from .results import to_jsonable
    from .spec import spec_from_dict
    from .synthesize import design_observer, design_report, design_spec_text

    folder = output_folder("--out", args.out)
    target = output_file("--json", args.json_path)
    spec = load(args.spec, max_attacked=args.max_attacked)
    own = spec.observer or {}
    kind = KIND_NAMES[args.observer] if args.observer else "elastic_net"
    if args.objective == "roa" and not args.observer:
        kind = "dsso"
    if args.objective == "roa" and kind != "dsso":
        raise usage_error(
            f"--objective roa is for --observer dsso (shrink 1), got --observer {args.observer}: "
            "the other kinds are certified globally or not at all"
        )
    threshold = float(own.get("threshold") or 0.1)
    human = sys.stderr if args.json_path == "-" else sys.stdout
    tty = sys.stderr.isatty() and args.json_path != "-"

    def say(message: str) -> None:
        if tty:
            sys.stderr.write(f"ssecert: {message}...\n")
            sys.stderr.flush()

    say(f"searching {kind} designs ({args.objective})")
    result = design_observer(
        spec.system,
        kind,
        objective=args.objective,
        threshold=threshold,
        time_budget=args.time_budget,
    )
    stem = f"{spec.name}-design"
    paths = {ext: folder / f"{stem}.{ext}" for ext in ("toml", "html", "json")}
    document: dict[str, Any] = {
        "spec": spec.source,
        "kind": kind,
        "objective": args.objective,
        "design": result.observer,
        "gamma": result.gamma,
        "decay": result.decay,
        "radius": result.radius,
        "candidates": result.candidates,
        "seconds": result.seconds,
        "complete": result.complete,
        "time_budget": args.time_budget,
    }
    limit = _sparse_limit(spec)
    if limit:
        document["sparse_observability"] = limit
    files: dict[Any, str] = {}
    report = None
    if result.observer is not None:
        text = design_spec_text(spec, result, kind)
        designed = spec_from_dict(
            tomllib.loads(text),
            source=str(paths["toml"]),
            sha256=hashlib.sha256(text.encode()).hexdigest(),
        )
        command = f"ssecert certify {paths['toml']} --out {folder}" + (
            f" --seed {args.seed}" if args.seed is not None else ""
        )
        report = design_report(
            spec, designed, seed=args.seed, runs=args.runs, command=command, progress=say
        )
        if limit:
            report = dataclasses.replace(report, notes=(*report.notes, limit))
        document["comparison"] = report.comparison
        document["files"] = {ext: str(path) for ext, path in paths.items()}
        files = {
            paths["toml"]: text,
            paths["html"]: render_report(report),
            paths["json"]: certify_json(report),
        }
    else:
        document["reason"] = result.reason
    rendered = json.dumps(to_jsonable(document), indent=2, allow_nan=False) + "\n"
    if target is not None:
        files[target] = rendered
    if files:
        write(files)  # every file or none
    _print_design(human, spec, kind, args, result, report, limit, paths)
    if args.json_path == "-":
        sys.stdout.write(rendered)
    return 0 if result.observer is not None else 1


def _print_design(
    out: Any,
    spec: Any,
    kind: str,
    args: argparse.Namespace,
    result: Any,
    report: Any,
    limit: str,
    paths: dict[str, Any],
) -> None:
    """The terminal summary: the search, both designs' certified numbers, each scenario."""
    searched = f"{len(result.candidates)} candidates in {result.seconds:.1f} s"
    if not result.complete:
        searched += f" (the time budget of {args.time_budget:g} s ended the search)"
    out.write(f"ssecert design: {spec.name}, {kind}, objective {args.objective}: {searched}\n")
    if limit:
        out.write(f"  note: {limit}\n")
    if result.observer is None:
        out.write(f"  no design: {result.reason}\n")
        if kind == "dsso" and args.objective != "roa":
            out.write(
                "  (a D-SSO has shrink 1: when the plant has an eigenvalue at 1 no quadratic "
                "certificate can exist; try --observer elastic-net, or --objective roa for "
                "the largest certified region of attraction)\n"
            )
        return
    comparison = report.comparison
    for d in comparison["designs"]:
        label = "the spec's design" if d["design"] == "spec" else "synthesised"
        params = ", ".join(
            f"{k} {d[k]:g}" for k in ("step", "threshold", "shrink") if isinstance(d.get(k), float)
        )
        words = [f"observer_stability {d.get('observer_stability', '-')}"]
        words.append(f"certified l2 gain {_num(d.get('iss_gain_value'))}")
        if "region_of_attraction_value" in d:
            words.append(f"region of attraction {_num(d['region_of_attraction_value'])}")
        out.write(f"  {label} ({d['kind']}, {params or 'gain only'}): {', '.join(words)}\n")
    if result.decay is not None:
        out.write(f"  synthesised: certified decay {result.decay:.3g} per step (V(k+1) <= "
                  f"{1 - result.decay:.3g} V(k))\n")  # fmt: skip
    for row in comparison["scenarios"]:
        cells = []
        for label in ("spec", "synthesised"):
            sim = row.get(label)
            if sim is None:
                continue
            if "skipped" in sim:
                cells.append(f"{label}: skipped")
            else:
                settle = sim["settling_step"]
                cells.append(
                    f"{label} {_num(sim['final_mean'])}"
                    + ("" if settle is None else f" (settles by step {settle})")
                )
        verdict = f" -> {row['comparison']}" if "comparison" in row else ""
        out.write(f"  scenario {row['scenario']}: final mean error {'; '.join(cells)}{verdict}\n")
    out.write(f"  {comparison['summary']}\n")
    out.write(
        f"spec file: {paths['toml']}\nreport: {paths['html']}\ncertificate: {paths['json']}\n"
    )


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


def _num(v: Any) -> str:
    return "none" if v is None else f"{float(v):.4g}"
