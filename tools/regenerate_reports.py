"""Regenerate reports/: NAME.html and NAME.json for every packaged example, the UGV's designed
observer (ugv-design.toml, .html and .json, as ``ssecert design ugv --seed 0`` writes them) and
the audit of the documents' claims (audit.html and audit.json, as ``ssecert audit`` writes them).

python tools/regenerate_reports.py
"""

from pathlib import Path

from proofs_checks import audit_json, render_audit, run_audit
from ssecert._io import atomic_write_text
from ssecert.certify import certify
from ssecert.examples import list_examples, load_example
from ssecert.report.html import render_report
from ssecert.report.json import certify_json


def main() -> None:
    out = Path(__file__).resolve().parents[1] / "reports"
    out.mkdir(exist_ok=True)
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


if __name__ == "__main__":
    main()
