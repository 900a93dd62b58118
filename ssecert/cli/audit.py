"""``ssecert audit``: the audit of the reference documents' claims (package ``proofs_checks``)."""

from __future__ import annotations

import argparse
import sys
import textwrap
from typing import Any

__all__: list[str] = []


def add_audit_parser(sub: Any) -> None:
    audit = sub.add_parser(
        "audit",
        help="audit every numbered claim of the reference documents",
        description=(
            "Run the check of every numbered claim of the documents ssecert is built from "
            "(theorems, lemmas, propositions, worked examples) and write DIR/audit.html and "
            "DIR/audit.json: each claim holds, fails (with a counterexample in the document's "
            "own symbols) or holds under an extra condition (conditional). With --claim, run "
            "those claims only and print their evidence."
        ),
    )
    audit.add_argument(
        "--out",
        default=None,
        metavar="DIR",
        help="folder of audit.html and audit.json (default ./reports; with --claim, nothing is "
        "written unless --out is given)",
    )
    audit.add_argument(
        "--claim",
        action="append",
        metavar="ID",
        help="run this claim only (repeatable); its evidence and counterexample are printed",
    )


def cmd_audit(args: argparse.Namespace) -> int:
    """Run the audit; 0 once audit.html and audit.json are written (with --claim alone, once
    the claims are printed)."""
    import json

    from proofs_checks import all_claims, audit_json, render_audit, run_audit

    from .files import UsageError, output_folder, write_outputs

    # a run of a few claims prints them and leaves the whole audit's report as it is
    write = args.out is not None or not args.claim
    folder = output_folder("--out", args.out or "reports") if write else None
    claims = all_claims()
    wanted = args.claim
    if wanted:
        unknown = [c for c in wanted if c not in claims]
        if unknown:
            raise UsageError(
                f"--claim {unknown[0]}: no such claim (the claims: {', '.join(claims)})"
            )
    tty = sys.stderr.isatty()

    def progress(claim_id: str) -> None:
        if tty:
            sys.stderr.write(f"\rchecking {claim_id} ...{' ' * 30}")
            sys.stderr.flush()

    outcomes = run_audit(wanted, progress=progress)
    if tty:
        sys.stderr.write("\r" + " " * 70 + "\r")
    if folder is not None:
        html, js = folder / "audit.html", folder / "audit.json"
        write_outputs({html: render_audit(outcomes), js: audit_json(outcomes)})  # both or none
    width = max(len(o.claim.id) for o in outcomes)
    for o in outcomes:
        print(f"{o.claim.id:<{width}}  {o.finding.verdict:<11}  {o.claim.where}")
    if wanted:
        for o in outcomes:
            print(f"\n{o.claim.id}: {o.finding.verdict}")
            print(textwrap.fill(o.claim.statement, 96, initial_indent="  claim: ",
                                subsequent_indent="    "))  # fmt: skip
            print(textwrap.fill(o.finding.explanation, 96, initial_indent="  finding: ",
                                subsequent_indent="    "))  # fmt: skip
            if o.finding.condition:
                print(textwrap.fill(o.finding.condition, 96, initial_indent="  holds when: ",
                                    subsequent_indent="    "))  # fmt: skip
            entry = o.to_dict()["evidence"]
            if "counterexample" in entry:
                print("  counterexample: " + json.dumps(entry["counterexample"]))
    counts = {v: sum(o.finding.verdict == v for o in outcomes) for v in ("holds", "conditional")}
    fails = len(outcomes) - counts["holds"] - counts["conditional"]
    print(
        f"\n{len(outcomes)} claims: {counts['holds']} hold, {counts['conditional']} conditional, "
        f"{fails} fail"
    )
    if folder is not None:
        print(f"audit written to {html} and {js}")
    return 0
