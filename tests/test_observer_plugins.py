"""An observer kind is one module: a kind defined here alone is read, certified, simulated,
reported, designed (``ssecert design``) and drawn by ``ssecert.testing``."""

import json
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import ssecert
from ssecert import System
from ssecert.budget import Budget
from ssecert.certify import certify
from ssecert.cli import main
from ssecert.design.gains import Gain, pinv_gain
from ssecert.design.search import design_kinds, objective_refusal
from ssecert.observers import (
    BUILTIN_KINDS,
    LinearObserver,
    ObserverDesign,
    ObserverKind,
    build_observer,
    get_kind,
    observer_kinds,
    register,
    unregister,
)
from ssecert.report.html import render_report
from ssecert.spec import SpecError, spec_from_dict
from ssecert.testing import assert_schur
from ssecert.testing.strategies import observer_designs
from ssecert.tolerances import Tolerances


@dataclass(frozen=True)
class Damping:
    """The kind's own parameters, beyond the general form of ``ObserverDesign``."""

    factor: float


class DampedPinv(ObserverKind):
    """x_hat+ = A x_hat + L (y - C x_hat) with L = factor * A C^+ (defined in this test only)."""

    name = "damped_pinv"
    keys = ("kind", "factor")
    design_objectives = ("gain",)

    def parse(self, table, n, p):
        return {"factor": table.real("factor", table.require("factor"), min_value=0.0)}

    def build(
        self, system: System, params: Mapping[str, Any], budget: Budget, tolerances: Tolerances
    ) -> ObserverDesign:
        base = pinv_gain(system)
        L = params["factor"] * base.L
        gain = Gain(
            L=L,
            method="damped pinv",
            error_matrix=system.A - L @ system.C,
            verified=True,
            details={"factor": params["factor"]},
        )
        return ObserverDesign(
            kind=self.name,
            system=system,
            gain=gain,
            sensing=system.C,
            parameters=Damping(params["factor"]),
        )

    def simulator(self, design):
        return LinearObserver(design.system.A, design.system.C, design.gain.L)

    # ssecert design searches the factor; its gain is the kind's own, not synthesised
    def design_axes(self, objective):
        return (None,), (0.25, 0.5, 0.75)

    def design_section(self, system, row, col, *, threshold):
        return {"kind": self.name, "factor": col}

    def parameter_strategy(self, system):
        return st.fixed_dictionaries({"factor": st.floats(0.05, 0.95)})


@pytest.fixture
def damped():
    register(DampedPinv)
    yield
    unregister(DampedPinv.name)


A = [[0.9, 0.2], [0.0, 0.8]]
C = [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]


def _spec(factor: float = 0.5, max_attacked: int = 1) -> dict:
    return {
        "name": "plugin",
        "system": {"A": A, "C": C},
        "attack": {"max_attacked": max_attacked},
        "observer": {"kind": "damped_pinv", "factor": factor},
        "scenario": [{"name": "quiet", "attack": "none", "runs": 4, "steps": 40}],
    }


def test_builtin_kinds_are_registered():
    assert observer_kinds()[: len(BUILTIN_KINDS)] == BUILTIN_KINDS
    for name in BUILTIN_KINDS:
        assert get_kind(name).name == name


@pytest.mark.slow
def test_a_kind_defined_in_a_test_is_certified_simulated_and_reported(damped):
    spec = spec_from_dict(_spec())
    assert spec.observer == {"kind": "damped_pinv", "factor": 0.5}
    result = certify(spec, seed=0)
    cert = result.certificate
    assert cert["observer_gain"].fields["kind"] == "damped_pinv"
    assert cert["observer_gain"].fields["gain_method"] == "damped pinv"
    # A - 0.5 A C^+ C = 0.5 A: stable, and the certificate says so
    assert cert["observer_gain"].verdict.value == "holds"
    assert cert["observer_stability"].verdict.value == "holds"
    assert cert["iss_gain"].verdict.value == "holds"
    assert "thesis_assumptions" not in cert  # not an attack-estimating observer
    sim = result.simulations["quiet"]
    assert sim.observer == "damped_pinv" and sim.final()["relative_error_mean"] < 1e-6
    design = build_observer(spec.system, spec.observer)
    assert design.parameters == Damping(0.5) and design.to_dict()["factor"] == 0.5
    html = render_report(result)
    assert "damped_pinv" in html and "damped pinv" in html


def test_a_kind_defined_in_a_test_fails_when_it_should(damped):
    # factor 2 / 0.45: F = (1 - factor) A has spectral radius 0.9 * 3.44 > 1
    result = certify(spec_from_dict(_spec(factor=1 / 0.225)), seed=0, simulate=False)
    assert result.certificate["observer_gain"].verdict.value == "fails"
    assert result.certificate["observer_stability"].verdict.value == "fails"


@pytest.mark.slow
def test_a_kind_defined_in_a_test_through_the_cli(damped, tmp_path, capsys):
    spec_file = tmp_path / "plugin.json"
    spec_file.write_text(json.dumps(_spec()))
    code = main(["certify", str(spec_file), "--out", str(tmp_path / "out"), "--seed", "0"])
    # exit 1: sensor 1 alone does not observe x1, so one attacked sensor cannot be corrected
    assert code == 1, capsys.readouterr()
    doc = json.loads((tmp_path / "out" / "plugin.json").read_text())
    assert doc["checks"]["sparse_observability"]["verdict"] == "fails"
    assert doc["checks"]["observer_gain"]["kind"] == "damped_pinv"
    assert doc["checks"]["observer_stability"]["verdict"] == "holds"
    assert (tmp_path / "out" / "plugin.html").is_file()


def test_the_kind_reads_its_own_keys(damped):
    with pytest.raises(SpecError, match=r"key 'observer.factor': missing \(required\)"):
        spec_from_dict({**_spec(), "observer": {"kind": "damped_pinv"}})
    with pytest.raises(SpecError, match=r"key 'observer.step': unknown key"):
        spec_from_dict({**_spec(), "observer": {"kind": "damped_pinv", "factor": 1, "step": 1}})


def test_an_unregistered_kind_is_refused_with_the_registered_ones():
    with pytest.raises(SpecError, match="damped_pinv") as info:
        spec_from_dict(_spec())
    assert "dsso" in str(info.value)
    with pytest.raises(ValueError, match="unknown observer kind 'damped_pinv'"):
        build_observer(System(np.eye(1), np.eye(1)), {"kind": "damped_pinv"})


@pytest.mark.parametrize("bad", [{"name": "not an identifier"}, {"keys": ("factor",)}])
def test_register_checks_the_class(bad):
    cls = type("Bad", (DampedPinv,), bad)
    with pytest.raises(ValueError, match="observer kind"):
        register(cls)


def test_a_kind_defined_in_a_test_is_offered_by_design(damped):
    assert "damped_pinv" in design_kinds()
    assert design_kinds()[0] == "elastic_net"  # the default stays the built-in one
    # it is designed for the gain objective alone, and says who takes the others
    assert objective_refusal("gain", "damped_pinv") is None
    refusal = objective_refusal("roa", "damped_pinv")
    assert refusal is not None and refusal.takers == ("the D-SSO (shrink 1)",)
    assert str(refusal).startswith(
        "objective 'roa' is for the D-SSO (shrink 1), got kind 'damped_pinv'"
    )
    with pytest.raises(ValueError, match="objective 'rate' is for the elastic-net observer"):
        ssecert.design(System(A, C), "damped_pinv", objective="rate")


def test_design_without_the_kind_registered_refuses_it():
    assert "damped_pinv" not in design_kinds()
    with pytest.raises(ValueError, match="kind: expected one of elastic_net, dsso, luenberger"):
        ssecert.design(System(A, C), "damped_pinv")


@pytest.mark.slow
def test_a_kind_defined_in_a_test_is_designed(damped):
    result = ssecert.design(System(A, C), "damped_pinv", time_budget=30)
    # its grid (the factors) was searched with its own gain, and the best certified kept
    assert [c["factor"] for c in result.candidates] == [0.25, 0.5, 0.75]
    assert all(c["gain"] == "damped pinv" and c["certified"] for c in result.candidates)
    best = min(result.candidates, key=lambda c: c["gamma"])
    assert result.observer == {"kind": "damped_pinv", "factor": best["factor"]}
    assert result.gamma == best["gamma"] and np.isfinite(result.gamma)
    # the design's linear loop: F = (1 - factor) A
    assert result.linear_radius == pytest.approx(0.9 * (1 - best["factor"]))


@pytest.mark.slow
def test_a_kind_defined_in_a_test_is_designed_through_the_cli(damped, tmp_path, capsys):
    spec_file = tmp_path / "plugin.json"
    bias = {"name": "bias", "attack": "constant", "sensors": [2], "runs": 4, "steps": 40}
    spec_file.write_text(json.dumps({**_spec(max_attacked=0), "scenario": [bias]}))
    out = tmp_path / "out"
    argv = ["design", str(spec_file), "--observer", "damped_pinv", "--time-budget", "30"]
    code = main([*argv, "--out", str(out), "--seed", "0", "--runs", "4"])
    assert code == 0, capsys.readouterr()
    written = spec_from_dict(json.loads((out / "plugin-design.json").read_text())["spec"])
    assert written.observer["kind"] == "damped_pinv"
    assert written.observer["factor"] in (0.25, 0.5, 0.75)
    doc = json.loads((out / "plugin-design.json").read_text())
    assert doc["checks"]["observer_stability"]["verdict"] == "holds"
    designs = {d["design"]: d for d in doc["design_comparison"]["designs"]}
    assert designs["synthesised"]["kind"] == designs["spec"]["kind"] == "damped_pinv"
    assert designs["synthesised"]["gain"] == "damped pinv"
    assert "damped_pinv" in (out / "plugin-design.html").read_text()
    assert 'kind = "damped_pinv"' in (out / "plugin-design.toml").read_text()


@given(data=st.data())
def test_a_kind_defined_in_a_test_is_drawn_by_its_strategy(data):
    register(DampedPinv)  # a fixture would be shared by every example
    try:
        spec = data.draw(observer_designs(System(A, C), kinds=["damped_pinv"]))
        design = build_observer(spec.system, spec.observer)
        factor = spec.observer["factor"]
        assert 0.05 <= factor <= 0.95 and design.parameters == Damping(factor)
        np.testing.assert_allclose(design.error_matrix, (1 - factor) * np.array(A), atol=1e-12)
        assert_schur(design.error_matrix)
    finally:
        unregister(DampedPinv.name)
