"""The code passes its linter, its formatter and its type checker (configured in pyproject.toml)."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _installed(module: str) -> bool:
    """Whether ``module`` (ruff, mypy: the ``dev`` extra) is installed for this Python."""
    import importlib.util

    return importlib.util.find_spec(module) is not None


def _run(*command: str) -> subprocess.CompletedProcess:
    return subprocess.run(command, cwd=ROOT, capture_output=True, text=True, check=False)


@pytest.mark.skipif(not (ROOT / "pyproject.toml").is_file(), reason="needs the source tree")
def test_ruff_lint_and_format():
    if not _installed("ruff"):
        pytest.skip('ruff is not installed: python -m pip install -e ".[dev]"')
    ruff = (sys.executable, "-m", "ruff")  # the one installed with this Python, PATH or not
    lint = _run(*ruff, "check", "--no-cache", ".")
    assert lint.returncode == 0, lint.stdout + lint.stderr
    fmt = _run(*ruff, "format", "--check", "--no-cache", ".")
    assert fmt.returncode == 0, fmt.stdout + fmt.stderr


@pytest.mark.slow
@pytest.mark.skipif(not (ROOT / "pyproject.toml").is_file(), reason="needs the source tree")
def test_mypy():
    if not _installed("mypy"):
        pytest.skip('mypy is not installed: python -m pip install -e ".[dev]"')
    run = _run(sys.executable, "-m", "mypy", "--cache-dir", "/dev/null")
    assert run.returncode == 0, run.stdout + run.stderr


def test_every_test_module_keeps_a_quick_test():
    # the default run deselects tests marked slow (pyproject's addopts); each module keeps one
    # test it runs, so the quick suite touches every module
    for path in [
        *sorted((ROOT / "tests").glob("test_*.py")),
        ROOT / "proofs_checks/test_claims.py",
    ]:
        text = path.read_text()
        tests = text.count("\ndef test_") + text.count("\n    def test_")
        whole = re.search(r"^pytestmark = pytest\.mark\.slow", text, re.MULTILINE)
        assert whole is None, f"{path.name}: mark its slow tests one by one"
        assert text.count("@pytest.mark.slow\n") < tests, path.name
