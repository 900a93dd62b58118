"""The code passes its linter, its formatter and its type checker (configured in pyproject.toml)."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _run(*command: str) -> subprocess.CompletedProcess:
    return subprocess.run(command, cwd=ROOT, capture_output=True, text=True, check=False)


@pytest.mark.skipif(not (ROOT / "pyproject.toml").is_file(), reason="needs the source tree")
def test_ruff_lint_and_format():
    ruff = (sys.executable, "-m", "ruff")  # the one installed with this Python, PATH or not
    lint = _run(*ruff, "check", "--no-cache", ".")
    assert lint.returncode == 0, lint.stdout + lint.stderr
    fmt = _run(*ruff, "format", "--check", "--no-cache", ".")
    assert fmt.returncode == 0, fmt.stdout + fmt.stderr


@pytest.mark.skipif(not (ROOT / "pyproject.toml").is_file(), reason="needs the source tree")
def test_mypy():
    run = _run(sys.executable, "-m", "mypy", "--cache-dir", "/dev/null")
    assert run.returncode == 0, run.stdout + run.stderr
