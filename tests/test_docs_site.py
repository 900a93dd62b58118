"""The documentation site: its tutorials run as doctests, its reference pages are written from
the code, and (with the docs extra) it builds without a warning."""

import doctest
import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

SITE = Path(__file__).resolve().parents[1] / "docs" / "site"
TUTORIALS = sorted((SITE / "tutorials").glob("*.rst"))


def _generate():
    spec = importlib.util.spec_from_file_location("_generate", SITE / "_generate.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
@pytest.mark.parametrize("path", TUTORIALS, ids=lambda p: p.name)
def test_the_tutorials_run_as_written(path):
    flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    result = doctest.testfile(str(path), module_relative=False, optionflags=flags)
    assert result.failed == 0


def test_every_tutorial_is_in_the_site_and_runs_something():
    index = (SITE / "tutorials" / "index.rst").read_text(encoding="utf-8")
    for path in TUTORIALS:
        if path.name != "index.rst":
            assert path.stem in index, path.name
            assert ">>> " in path.read_text(encoding="utf-8"), path.name


def test_the_reference_pages_are_written_from_the_code(tmp_path):
    from ssecert.cli import _build_parser
    from ssecert.observers import observer_kinds

    _generate().write_all(tmp_path)
    spec = (tmp_path / "spec.rst").read_text(encoding="utf-8")
    for kind in observer_kinds():
        assert f'kind = "{kind}"' in spec
    for key in ("max_attacked", "horizon", "threshold", "inner_steps", "magnitude", "period"):
        assert f"``{key}``" in spec
    cli = (tmp_path / "cli.rst").read_text(encoding="utf-8")
    commands = next(a for a in _build_parser()._actions if hasattr(a, "choices") and a.choices)
    for name in commands.choices:
        assert f"ssecert {name}\n" in cli
    assert "--device {cpu,cuda}" in cli
    certificate = (tmp_path / "certificate.rst").read_text(encoding="utf-8")
    assert "``max_removable``" in certificate and "``breaking_set``" in certificate


@pytest.mark.slow
def test_the_site_builds_without_a_warning(tmp_path):
    pytest.importorskip("sphinx")
    pytest.importorskip("pydata_sphinx_theme")
    pytest.importorskip("myst_parser")
    build = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
         str(SITE), str(tmp_path / "html")],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert build.returncode == 0, build.stderr[-3000:]
    assert (tmp_path / "html" / "generated" / "spec.html").exists()
