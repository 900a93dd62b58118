"""Gain synthesis against the dissipation certificate (ssecert.design.synthesis)."""

from __future__ import annotations

import numpy as np
import pytest

from ssecert.design.synthesis import synthesize_gain, with_gain
from ssecert.examples import load_example
from ssecert.observers import build_observer
from ssecert.observers.lure import LureModel
from ssecert.stability.lmi import circle_certificate, iss_certificate
from ssecert.system import System


def _certified_gamma(design) -> float | None:
    """gamma from the ordinary certificates, solved and verified from scratch."""
    model = LureModel.from_design(design)
    circle = circle_certificate(model) if model.m else None
    if circle is not None and circle.verdict != "holds":
        return None
    alpha = 0.5 * float(circle.decay or 0.0) if circle is not None else 0.0
    iss = iss_certificate(model, alpha=alpha)
    return iss.gamma if iss.verdict == "holds" else None


def test_the_synthesised_elastic_net_gain_beats_the_deadbeat_gain_on_the_ugv():
    spec = load_example("ugv")
    observer = {"kind": "elastic_net", "gain": "deadbeat", "step": 0.7, "threshold": 0.1}
    design = build_observer(spec.system, {**observer, "shrink": 0.5})
    found = synthesize_gain(design)
    assert found.L is not None and found.L.shape == (2, 3)
    mine = _certified_gamma(with_gain(design, found.L))
    theirs = _certified_gamma(design)
    assert mine is not None and theirs is not None
    assert mine < theirs  # 1.09 against 1.88 when written
    # the verified gamma is never below what the solver proposed by more than rounding
    assert mine >= found.gamma_proposed * (1 - 1e-3)


@pytest.mark.parametrize("seed", range(3))
def test_synthesised_gains_on_random_plants_are_certified_and_converge(seed):
    rng = np.random.default_rng(seed)
    n, p = 3, 5
    A = rng.standard_normal((n, n))
    A /= np.abs(np.linalg.eigvals(A)).max()  # spectral radius 1, as in the thesis
    C = rng.standard_normal((p, n))
    observer = {"kind": "elastic_net", "gain": "pinv", "step": 0.3, "threshold": 0.1}
    design = build_observer(System(A, C), {**observer, "shrink": 0.6})
    found = synthesize_gain(design)
    assert found.L is not None
    synthesised = with_gain(design, found.L)
    assert _certified_gamma(synthesised) is not None
    model = LureModel.from_design(synthesised)
    start = rng.standard_normal((20, model.N)) * 10.0
    end = model.simulate(start, 20_000)[-1]
    assert np.linalg.norm(end, axis=1).max() <= 1e-6 * 10.0


def test_a_dsso_with_shrink_one_on_an_integrator_has_no_certified_gain():
    spec = load_example("ugv")
    found = synthesize_gain(build_observer(spec.system, spec.observer))
    assert found.L is None and "infeasible" in found.status.lower()


def test_a_luenberger_gain_is_synthesised_and_certified():
    spec = load_example("ugv")
    design = build_observer(spec.system, {"kind": "luenberger", "gain": "deadbeat"})
    found = synthesize_gain(design)
    synthesised = with_gain(design, found.L)
    assert np.abs(np.linalg.eigvals(synthesised.error_matrix)).max() < 1
    assert _certified_gamma(synthesised) is not None


def test_a_spec_written_back_reads_as_the_same_spec():
    import tomllib

    from ssecert import spec_from_dict
    from ssecert._spec_write import dumps, spec_document

    spec = load_example("ugv")
    again = spec_from_dict(tomllib.loads(dumps(spec_document(spec))))
    assert again.name == spec.name and again.observer == spec.observer
    np.testing.assert_array_equal(again.system.A, spec.system.A)
    assert again.system.sensors == spec.system.sensors and again.scenarios == spec.scenarios
    assert (again.max_attacked, again.horizon) == (spec.max_attacked, spec.horizon)


def test_the_designed_observer_written_to_toml_certifies_with_the_same_gain():
    import tomllib

    from ssecert import analyze, spec_from_dict
    from ssecert._spec_write import dumps, spec_document
    from ssecert.synthesize import design_observer

    spec = load_example("ugv")
    result = design_observer(spec.system, "elastic_net")
    assert result.observer is not None and result.complete
    assert len(result.candidates) == 20
    text = dumps(spec_document(spec, result.observer))
    cert = analyze(spec_from_dict(tomllib.loads(text)))
    assert cert["observer_stability"].verdict.value == "holds"
    assert cert["iss_gain"].value == pytest.approx(result.gamma, rel=1e-9)
    # better than the thesis's elastic-net choice with the deadbeat gain (1.88)
    assert result.gamma < 1.2


def test_design_refuses_what_it_cannot_design():
    from ssecert.synthesize import design_observer

    spec = load_example("ugv")
    with pytest.raises(ValueError, match="kind"):
        design_observer(spec.system, "sso")
    with pytest.raises(ValueError, match="objective"):
        design_observer(spec.system, objective="roa")
    none = design_observer(spec.system, "dsso")  # shrink 1 on an integrator: no certificate
    assert none.observer is None and "no dsso design" in none.reason
