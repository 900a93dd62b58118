"""Regenerate reports/ for every packaged example: NAME.html and NAME.json.

python tools/regenerate_reports.py
"""

from pathlib import Path

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


if __name__ == "__main__":
    main()
