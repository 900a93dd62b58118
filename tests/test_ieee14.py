"""The packaged IEEE 14-bus example and the script that builds it (tools/make_ieee14.py)."""

import importlib.util
import tomllib
from pathlib import Path

import numpy as np
import pytest

import ssecert
from ssecert.examples import example_path, load_example

TOOL = Path(__file__).resolve().parents[1] / "tools" / "make_ieee14.py"


@pytest.fixture(scope="module")
def tool():
    pytest.importorskip("pypower")
    spec = importlib.util.spec_from_file_location("make_ieee14", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def example():
    return load_example("ieee14")


def test_the_packaged_matrices_are_what_pypower_regenerates(tool, example):
    model = tool.published_model()
    system = example.system
    np.testing.assert_allclose(system.A, model["A"], rtol=0, atol=1e-13)
    np.testing.assert_allclose(system.C, model["C"], rtol=0, atol=1e-12 * np.abs(model["C"]).max())
    assert list(system.sensors) == model["sensors"]
    document = tomllib.loads(tool.render(model))
    assert document["attack"] == tomllib.loads(example_path("ieee14").read_text())["attack"]


def test_the_consistent_model_cannot_observe_the_common_rotor_angle(tool):
    # The reason the packaged model keeps the set-up's Kron-reduction sign: with the right one,
    # K is a Laplacian and shifting every rotor angle by the same amount changes no meter.
    model = tool.consistent_model()
    K, A, C = model["K"], model["A"], model["C"]
    ones = np.ones(5)
    assert np.linalg.norm(K @ ones) <= 1e-12 * np.linalg.norm(K)
    z = np.concatenate([ones, np.zeros(5)])
    np.testing.assert_allclose(A @ z, z, atol=1e-12)
    assert np.linalg.norm(C @ z) <= 1e-12 * np.linalg.norm(C)
    assert ssecert.observability(ssecert.System(A, C)).verdict.value in ("fails", "inconclusive")
    # its injection map is PYPOWER's DC model P = Bbus theta, with theta = S delta
    np.testing.assert_allclose(model["Bbus"].sum(axis=1), 0.0, atol=1e-12)
    np.testing.assert_allclose(model["Bbus"] @ model["angles"], C[5:, :5], atol=1e-12)
    assert model["Bf"].shape == (20, 14)


def test_the_published_model_departs_from_the_dc_model(tool):
    published, consistent = tool.published_model(), tool.consistent_model()
    assert np.linalg.eigvalsh((published["K"] + published["K"].T) / 2)[0] > 1.0  # not a Laplacian
    injections = slice(5, None)
    gap = np.linalg.norm(published["C"][injections] - consistent["C"][injections])
    assert gap > 0.1 * np.linalg.norm(consistent["C"][injections])


def test_the_example_has_the_papers_dimensions(example):
    system = example.system
    assert (system.n, system.p) == (10, 19)
    assert (example.max_attacked, example.horizon) == (6, 20)
    assert system.sensors[:5] == tuple(f"omega-bus{b}" for b in (1, 2, 3, 6, 8))
    assert system.sensors[5:] == tuple(
        f"P-bus{b}" for b in (1, 2, 3, 6, 8, 4, 5, 7, 9, 10, 11, 12, 13, 14)
    )
    moduli = np.abs(np.linalg.eigvals(system.A))
    assert moduli.min() > 0.49 and moduli.max() < 0.97  # the swing modes, damped
    # the speed sensors read the last five states
    np.testing.assert_array_equal(system.C[:5], np.hstack([np.zeros((5, 5)), np.eye(5)]))


def test_the_example_is_observable_and_six_attacked_meters_are_correctable(example):
    check = ssecert.observability(example.system)
    assert check.verdict.value == "holds"
    assert check.value == 2
    sparse = ssecert.sparse_observability(example.system, max_attacked=example.max_attacked)
    assert sparse.verdict.value == "holds"
