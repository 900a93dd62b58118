"""Fixed costs: ``import ssecert`` imports neither SciPy nor the analyses, and the lazily
imported names behave as the eagerly imported ones did."""

import subprocess
import sys

import numpy as np
import pytest

import ssecert


def _fresh(code: str) -> str:
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.strip()


def test_import_ssecert_does_not_import_scipy_control_or_the_analyses():
    out = _fresh(
        "import sys, ssecert; "
        "print(sorted(m for m in ('scipy', 'control', 'cvxpy', 'ssecert.analyze', "
        "'ssecert.structure') if m in sys.modules))"
    )
    assert out == "[]"


def test_the_command_line_parser_imports_no_analysis_until_a_command_needs_it():
    # the design command's kinds import every observer (and SciPy): built only when the
    # design command parses its arguments or prints its help
    out = _fresh(
        "import sys; from ssecert.cli import _build_parser; parser = _build_parser(); "
        "parser.parse_args(['examples']); "
        "print(sorted(m for m in ('scipy', 'ssecert.observers', 'ssecert.design.search') "
        "if m in sys.modules))"
    )
    assert out == "[]"
    out = _fresh(
        "import sys; from ssecert.cli import _build_parser; "
        "args = _build_parser().parse_args(['design', 'ugv', '--observer', 'dsso']); "
        "print(args.observer, 'ssecert.design.search' in sys.modules)"
    )
    assert out == "dsso True"


def test_a_function_named_like_its_module_stays_the_function():
    # importing the module ssecert.analyze first used to leave nothing to rebind the name
    out = _fresh(
        "import ssecert.analyze, ssecert.certify, ssecert; "
        "print(callable(ssecert.analyze), type(ssecert.analyze).__name__)"
    )
    assert out == "True function"


@pytest.mark.parametrize("name", ssecert.__all__)
def test_every_public_name_resolves(name):
    assert getattr(ssecert, name) is not None
    assert name in dir(ssecert)


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        ssecert.nope  # noqa: B018


def test_notebook_display_renders_with_the_report():
    check = ssecert.observability(ssecert.System([[0.5]], [[1.0]]))
    assert "observability" in check._repr_html_().lower()


@pytest.mark.parametrize("seed", range(6))
def test_pbh_margins_of_many_sensors_agree_with_the_stacked_svd(seed):
    """Beyond 4 sensors per state the PBH matrices are compressed by a QR factor of C."""
    from ssecert.structure.observability import pbh_margins

    rng = np.random.default_rng(seed)
    n, p = int(rng.integers(2, 8)), int(rng.integers(40, 80))
    A, C = rng.standard_normal((n, n)), rng.standard_normal((p, n))
    lam = np.linalg.eigvals(A)
    margins, _ = pbh_margins(A, C, lam)
    norm = np.linalg.norm(np.vstack([A, C]), 2)
    for value, margin in zip(lam, margins):
        shift = value.real if value.imag == 0 else value
        stacked = np.vstack([A - shift * np.eye(n), C])
        assert margin == pytest.approx(
            np.linalg.svd(stacked, compute_uv=False)[-1] / norm, rel=1e-12
        )
