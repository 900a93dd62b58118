"""The examples of the README and of the guide's Python and property-test pages run as written,
with nothing else configured."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
GUIDE = ROOT / "docs" / "site" / "guide"
FILE = "test_ssecert_properties.py"


def _blocks(path: Path, section: str | None = None) -> list[tuple[str, str]]:
    """(language, body) of the fenced code blocks of a page, or of one of its sections."""
    text = path.read_text(encoding="utf-8")
    if section is not None:
        start = text.index(f"\n{section}\n")
        end = text.find("\n## ", start + 1)
        text = text[start : end if end >= 0 else None]
    return re.findall(r"```(\w*)\n(.*?)```", text, re.S)


def test_the_readme_links_the_pages_that_hold_its_former_sections():
    text = README.read_text(encoding="utf-8")
    for page in sorted(GUIDE.glob("*.md")):
        assert f"](docs/site/guide/{page.name})" in text, page.name


@pytest.mark.slow
def test_readme_example_runs_as_shown(tmp_path):
    blocks = _blocks(GUIDE / "property-tests.md")
    code = next(body for lang, body in blocks if lang == "python")
    shown = next(body for lang, body in blocks if lang == "text")
    (tmp_path / FILE).write_text(code, encoding="utf-8")
    # a user's shell: no pytest or hypothesis settings of this project
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTEST_", "HYPOTHESIS_"))}
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "pytest",
            "-q",
            "-rA",
            "-p",
            "no:cacheprovider",
            "--rootdir",
            str(tmp_path),
            FILE,
        ],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    out = run.stdout
    assert run.returncode == 1, out + run.stderr
    assert "1 failed, 3 passed" in out, out
    assert f"FAILED {FILE}::test_ugv_tolerates_one_attacked_sensor" in out
    for name in (
        "test_ugv_observer_converges_without_attack",
        "test_two_removable_sensors_correct_one_attack",
        "test_deadbeat_observer_of_an_integrator",
    ):
        assert f"PASSED {FILE}::{name}" in out, out
    # the failing test's report names the breaking sensor set by name and index
    assert "Breaking sensor set: position (index 0)" in out
    assert "an attacker on position (index 0)" in out
    # and the page shows that report as it is
    shown_errors = [line for line in shown.splitlines() if line.startswith("E ")]
    assert len(shown_errors) >= 4
    for line in shown_errors:
        assert line in out.splitlines(), line


@pytest.mark.slow
@pytest.mark.parametrize(
    ("path", "section"), [(README, "## A short example"), (GUIDE / "python.md", None)]
)
def test_the_python_examples_run_and_print_what_their_comments_say(path, section):
    # each line `expression  # literal` of the examples evaluates to the literal
    import ast
    import warnings

    blocks = [body for lang, body in _blocks(path, section) if lang == "python"]
    assert len(blocks) >= 2
    checked = 0
    for body in blocks:
        namespace: dict = {}
        pending: list[str] = []  # the lines since the last one checked, run before it
        for line in body.splitlines():
            code, _, comment = line.partition("  # ")
            try:
                expected = ast.literal_eval(comment.strip()) if comment else None
            except (ValueError, SyntaxError):
                expected = None
            if expected is None:
                pending.append(line)
                continue
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                exec(compile("\n".join(pending), str(path.name), "exec"), namespace)
                assert eval(code, namespace) == expected, line
            pending = []
            checked += 1
    assert checked >= 4
