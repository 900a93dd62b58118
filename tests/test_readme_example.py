"""The README's property-test example runs as written, with nothing else configured."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
SECTION = "## Property tests in your own pytest suite"
FILE = "test_ssecert_properties.py"


def _section_blocks() -> list[tuple[str, str]]:
    """(language, body) of the fenced code blocks of the README section."""
    text = README.read_text(encoding="utf-8")
    start = text.index(SECTION)
    end = text.find("\n## ", start + len(SECTION))
    return re.findall(r"```(\w*)\n(.*?)```", text[start : end if end >= 0 else None], re.S)


def test_readme_example_runs_as_shown(tmp_path):
    blocks = _section_blocks()
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
    # and the README shows that report as it is
    shown_errors = [line for line in shown.splitlines() if line.startswith("E ")]
    assert len(shown_errors) >= 4
    for line in shown_errors:
        assert line in out.splitlines(), line


@pytest.mark.slow
def test_the_python_section_runs_and_prints_what_its_comments_say():
    # each line `expression  # literal` of the README's Python section evaluates to the literal
    import ast
    import warnings

    text = README.read_text(encoding="utf-8")
    start = text.index("\n## Python\n")
    end = text.find("\n## ", start + 1)
    blocks = re.findall(r"```python\n(.*?)```", text[start:end], re.S)
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
                exec(compile("\n".join(pending), "README", "exec"), namespace)
                assert eval(code, namespace) == expected, line
            pending = []
            checked += 1
    assert checked >= 4
