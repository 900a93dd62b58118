"""Cases that once gave wrong answers or crashes (from a review of the code)."""

from pathlib import Path

import numpy as np
import pytest

from ssecert import System, irrepresentable, load_spec, sparse_observability
from ssecert.cli import main
from ssecert.design.gains import deadbeat_gain

DATA = Path(__file__).parent / "data"


@pytest.mark.parametrize("name", ["chain3", "close9"])
@pytest.mark.parametrize("method", ["auto", "enumeration", "eigenspace"])
def test_close_well_conditioned_eigenvalues_are_not_merged(name, method):
    """Distinct eigenvalues 1e-4 apart with condition number 1 are separate modes; one of
    them is seen by a single sensor, so one attacked sensor cannot be corrected."""
    spec = load_spec(DATA / f"{name}.toml")
    check = sparse_observability(spec.system, spec.max_attacked, method=method)
    assert check.verdict.value == "fails"
    assert check.fields["max_removable"] == 0


def test_enumeration_screening_accounts_for_basis_errors():
    """The 12 sensors that break this plant in floating point leave its exact data
    observable, 1.5e-15 away from unobservable: max_removable >= 11 is all the data
    support, and the verdict for s = 1 holds."""
    spec = load_spec(DATA / "t3_71.npz", max_attacked=1)
    enum = sparse_observability(spec.system, 1, method="enumeration")
    eig = sparse_observability(spec.system, 1, method="eigenspace")
    auto = sparse_observability(spec.system, 1)
    assert eig.fields["max_removable"] in (11, None)
    assert enum.fields["max_removable"] in (11, None)
    assert auto.verdict.value == "holds"
    assert auto.fields["max_removable"] == 11 and auto.fields["max_removable_is_lower_bound"]
    assert "precision" in auto.summary


def test_nilpotency_index_is_invariant_under_scaling():
    spec = load_spec(DATA / "small.toml")
    gain = deadbeat_gain(spec.system)
    assert gain.verified and gain.details["nilpotency_index"] == 6
    rng = np.random.default_rng(0)
    A, C = rng.standard_normal((6, 6)), rng.standard_normal((1, 6))
    for alpha in (1e-3, 1.0, 1e3):
        assert deadbeat_gain(System(alpha * A, C)).details["nilpotency_index"] == 6


def test_rounding_does_not_make_a_stable_gain_fail(capsys):
    code = main(["analyze", str(DATA / "jordan12.toml")])
    out = capsys.readouterr().out
    assert "observer_gain         FAILS" not in out
    assert code != 1


def test_irrepresentable_without_attack_on_a_rank_deficient_horizon():
    check = irrepresentable(System(np.eye(2), [[1.0, 0.0]]), 0, horizon=1)
    assert check.verdict.value == "fails" and np.isinf(check.value)


def test_gain_that_cannot_be_computed_is_bad_input_for_simulate(tmp_path, capsys):
    spec = tmp_path / "s.toml"
    spec.write_text(
        'name = "s"\n[system]\nA = [[0.5, 0.0], [0.0, 0.9]]\nC = [[1.0, 0.0]]\n'
        '[attack]\nmax_attacked = 0\n[observer]\nkind = "dsso"\ngain = "deadbeat"\n'
        'step = 0.5\nthreshold = 0.1\n[[scenario]]\nname = "c"\nattack = "none"\n'
    )
    assert main(["simulate", str(spec), "--runs", "2", "--steps", "5"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ssecert: error:") and "Traceback" not in err


def test_elastic_net_with_ogd_gain_runs(tmp_path):
    spec = tmp_path / "s.toml"
    spec.write_text(
        'name = "s"\n[system]\nA = [[0.5, 0.1], [0.0, 0.9]]\nC = [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]\n'
        '[attack]\nmax_attacked = 0\n[observer]\nkind = "elastic_net"\ngain = "ogd"\n'
        'step = 0.1\nthreshold = 0.1\nshrink = 0.5\n[[scenario]]\nname = "c"\nattack = "none"\n'
    )
    assert main(["simulate", str(spec), "--runs", "2", "--steps", "5"]) == 0


def test_unwritable_report_folder_is_bad_input(capsys):
    assert main(["certify", "notes-example-0", "--no-sim", "--out", "/proc/sys/ssecert"]) == 2
    assert "cannot write" in capsys.readouterr().err
