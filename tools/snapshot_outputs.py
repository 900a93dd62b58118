"""Write what a user sees for every packaged example, with run times and dates removed.

    python tools/snapshot_outputs.py DIR
    diff -r BEFORE AFTER

For each example: the certificate JSON, the HTML report, and the terminal
output of ``ssecert analyze`` and ``ssecert simulate``.  Two snapshots of the
same version, spec and seed are identical; a refactoring that changes nothing
a user sees leaves ``diff -r`` empty.
"""

import json
import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # this tree's ssecert, whatever is installed

from ssecert.certify import certify  # noqa: E402
from ssecert.examples import list_examples, load_example  # noqa: E402
from ssecert.report.html import render_report  # noqa: E402
from ssecert.report.json import certify_json  # noqa: E402

_DATE = re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d[+\-Z0-9:]*")
_SECONDS = re.compile(r"\b\d+(\.\d+)? ?(s|ms|seconds)\b")
# what a time budget cut short: how far the scan got depends on the machine's speed
_BUDGETED = re.compile(
    r"(budget after )[\d,]+(?= supports)"
    r"|(\"supports_checked\": )\d+"
    r"|(<th>supports_checked</th><td>)\d+"
)


def _without_times(text: str) -> str:
    text = _BUDGETED.sub(lambda m: next(g for g in m.groups() if g) + "<count>", text)
    return _SECONDS.sub("<time>", _DATE.sub("<date>", text))


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    for name in list_examples():
        result = certify(load_example(name), seed=0, command=f"ssecert certify {name} --seed 0")
        doc = json.loads(certify_json(result))
        doc["meta"].pop("timings", None)
        doc["meta"].pop("date", None)
        # in the order written, so that a moved field shows
        (out / f"{name}.json").write_text(_without_times(json.dumps(doc, indent=1)))
        (out / f"{name}.html").write_text(_without_times(render_report(result)))
        for command in ("analyze", "simulate"):
            run = subprocess.run(
                [sys.executable, "-m", "ssecert", command, name, "--seed", "0"],
                capture_output=True,
                text=True,
                check=False,
                # this tree's ssecert in the child too, not the installed one
                env={
                    **os.environ,
                    "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
                },
            )
            (out / f"{name}.{command}.txt").write_text(
                f"exit {run.returncode}\n{_without_times(run.stdout)}{_without_times(run.stderr)}"
            )
        print(name, result.certificate.verdict.value)


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, metavar="DIR", help="folder to write the snapshot into")
    main(parser.parse_args().out)
