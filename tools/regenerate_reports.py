"""Regenerate reports/: NAME.html and NAME.json for every packaged example, the UGV's designed
observer (ugv-design.toml, .html and .json, as ``ssecert design ugv --seed 0`` writes them) and
the audit of the documents' claims (audit.html and audit.json, as ``ssecert audit`` writes them)
and the documents' experiments (reproduce.html and reproduce.json, as ``ssecert reproduce`` writes
them, quick runs), whose agreement per document it writes into the README's block between
``<!-- reproduce:start -->`` and ``<!-- reproduce:end -->``.

python tools/regenerate_reports.py [--reproduce-only]
"""

from pathlib import Path

from proofs_checks import audit_json, render_audit, run_audit
from ssecert.base.atomic import atomic_write_text
from ssecert.certify import certify
from ssecert.examples import list_examples, load_example
from ssecert.report.html import render_report
from ssecert.report.json import certify_json

ROOT = Path(__file__).resolve().parents[1]
START, END = "<!-- reproduce:start -->", "<!-- reproduce:end -->"


def reproduce(out: Path) -> None:
    """reports/reproduce.html and .json (quick runs, seed 0) and the README's table from them."""
    import json

    from ssecert.experiments import (
        agreement_table,
        render_reproduce,
        reproduce_json,
        run_experiments,
    )

    outcomes = run_experiments()
    text = reproduce_json(outcomes)
    atomic_write_text(out / "reproduce.html", render_reproduce(outcomes))
    atomic_write_text(out / "reproduce.json", text)
    readme = (ROOT / "README.md").read_text()
    head, rest = readme.split(START, 1)
    _, tail = rest.split(END, 1)
    table = agreement_table(json.loads(text))
    atomic_write_text(ROOT / "README.md", f"{head}{START}\n{table}{END}{tail}")
    print(f"reproduce: {len(outcomes)} experiments")


def main() -> None:
    import sys

    out = ROOT / "reports"
    out.mkdir(exist_ok=True)
    if sys.argv[1:] == ["--reproduce-only"]:
        reproduce(out)
        return
    for name in list_examples():
        result = certify(load_example(name), seed=0, command=f"ssecert certify {name} --seed 0")
        atomic_write_text(out / f"{name}.html", render_report(result))
        # the same layout as `ssecert certify` (run times kept apart in meta.timings)
        atomic_write_text(out / f"{name}.json", certify_json(result))
        print(f"{name}: {result.certificate.verdict.value}")
    import os

    from ssecert.cli import main as command

    os.chdir(out.parent)  # the report's reproduce command names reports/, not this machine's path
    status = command(["design", "ugv", "--out", "reports", "--seed", "0"])
    print(f"ugv design: exit status {status}")
    outcomes = run_audit()
    atomic_write_text(out / "audit.html", render_audit(outcomes))
    atomic_write_text(out / "audit.json", audit_json(outcomes))
    counts = {v: sum(o.finding.verdict == v for o in outcomes) for v in ("holds", "conditional")}
    print(f"audit: {len(outcomes)} claims, {counts}")
    reproduce(out)


if __name__ == "__main__":
    main()
