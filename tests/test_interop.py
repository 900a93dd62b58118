"""Plants from python-control and SciPy objects."""

import control as ct
import numpy as np
import pytest
from scipy import signal, sparse

from ssecert import System, analyze
from ssecert.examples import load_example
from ssecert.spec import Spec

UGV = load_example("ugv")


def test_a_python_control_state_space_gives_the_same_plant_and_verdicts():
    A, C = UGV.system.A, UGV.system.C
    plant = ct.ss(A, [[0.0], [1.0]], C, np.zeros((3, 1)), 0.01,
                  outputs=["position", "velocity-a", "velocity-b"])  # fmt: skip
    system = System.from_control(plant, name="ugv")
    assert system == UGV.system
    # B, D and the sampling time change nothing: the same certificate as the spec's plant
    ours = analyze(Spec("ugv", system, max_attacked=1, horizon=2))
    theirs = analyze(Spec("ugv", UGV.system, max_attacked=1, horizon=2))
    assert [c.verdict for c in ours.checks] == [c.verdict for c in theirs.checks]
    assert System.from_control(plant, sensors=["a", "b", "c"]).sensors == ("a", "b", "c")


def test_a_scipy_dlti_in_any_form_gives_its_state_space_plant():
    A = np.array([[0.5, 1.0], [0.0, 0.7]])
    plant = signal.dlti(A, [[0.0], [1.0]], [[1.0, 0.0]], [[0.0]], dt=0.1)
    system = System.from_scipy(plant, name="p")
    assert np.array_equal(system.A, A) and system.sensors == ("y1",)
    # a transfer function is converted to a state-space realisation
    tf = System.from_scipy(signal.dlti([1.0], [1.0, -0.5], dt=1.0))
    assert tf.n == 1 and np.allclose(tf.A, [[0.5]])


def test_continuous_time_systems_and_other_objects_are_refused_with_the_way_out():
    with pytest.raises(ValueError, match=r"discrete-time.*control\.c2d"):
        System.from_control(ct.ss([[0.0]], [[1.0]], [[1.0]], 0))
    with pytest.raises(TypeError, match="python-control StateSpace"):
        System.from_control([[1.0]])
    with pytest.raises(ValueError, match=r"to_discrete"):
        System.from_scipy(signal.lti([[0.0]], [[1.0]], [[1.0]], [[0.0]]))
    with pytest.raises(TypeError, match="scipy.signal dlti"):
        System.from_scipy(np.eye(2))
    # complex data is refused, as System refuses it, not cut to its real part
    complex_plant = signal.dlti(
        [[0.5 + 0.3j, 0.0], [0.0, 0.9]], [[0.0], [1.0]], np.eye(2), np.zeros((2, 1)), dt=1
    )
    with pytest.raises(TypeError, match="real"):
        System.from_scipy(complex_plant)


def _answers(cert) -> str:
    from ssecert.report.json import certificate_json

    document = __import__("json").loads(certificate_json(cert))
    document.pop("meta")
    return document


def test_the_top_level_functions_take_python_control_and_scipy_systems():
    import ssecert

    A, C = UGV.system.A, UGV.system.C
    plant = ct.ss(A, [[0.0], [1.0]], C, np.zeros((3, 1)), 0.01)
    observer = {"kind": "luenberger", "gain": "place", "poles": [0.5, 0.6]}
    spec = Spec("system", System.from_control(plant), max_attacked=1, horizon=2)
    direct = ssecert.analyze(spec)
    assert _answers(ssecert.analyze(plant, max_attacked=1)) == _answers(direct)
    dlti = signal.dlti(A, [[0.0], [1.0]], C, np.zeros((3, 1)), dt=0.01)
    from_scipy = Spec("system", System.from_scipy(dlti), max_attacked=1, horizon=2)
    assert _answers(ssecert.analyze(dlti, max_attacked=1)) == _answers(ssecert.analyze(from_scipy))
    result = ssecert.certify(plant, max_attacked=1, observer=observer, simulate=False)
    assert result.certificate["observer_gain"].verdict.value == "holds"
    assert result.spec.observer["kind"] == "luenberger" and result.spec.max_attacked == 1


def test_the_top_level_functions_stay_functions_beside_their_modules():
    import importlib

    import ssecert

    for name in ("analyze", "certify", "design"):
        importlib.import_module(f"ssecert.{name}")  # the module or package of that name
        assert callable(getattr(ssecert, name)), name
    from ssecert.design.gains import deadbeat_gain  # the package of gains stays importable

    assert callable(deadbeat_gain)


def test_a_spec_file_an_example_name_and_overrides_are_taken():
    import ssecert
    from ssecert.inputs import as_spec

    assert ssecert.analyze("notes-example-2").verdict.value == "fails"
    ugv = as_spec("ugv", max_attacked=0)
    assert ugv.max_attacked == 0 and ugv.observer == UGV.observer and ugv.name == UGV.name
    for name in ("ugv", "notes-example-1", "random-n15-p30"):
        spec = load_example(name)
        again = as_spec(spec, max_attacked=spec.max_attacked, horizon=spec.horizon)
        assert again.system == spec.system and again.observer == spec.observer
        assert again.scenarios == spec.scenarios and again.name == spec.name
        assert as_spec(spec) is spec


def test_a_plant_without_its_attack_bound_or_another_object_is_refused():
    from ssecert.inputs import as_spec
    from ssecert.spec import SpecError

    with pytest.raises(TypeError, match="max_attacked is required when the design is a plant"):
        as_spec(UGV.system)
    with pytest.raises(TypeError, match="design: expected a Spec, a System.*got int"):
        as_spec(42, max_attacked=1)
    with pytest.raises(SpecError, match="observer.threshold"):
        as_spec(UGV.system, max_attacked=1, observer={"kind": "sso", "step": 0.2})
    # arguments of the wrong type are named as the Python arguments they are
    for keywords, name in (
        ({"observer": "luenberger"}, "observer"),
        ({"scenarios": {"attack": "constant"}}, "scenarios"),
        ({"scenarios": ["constant"]}, "scenarios"),
        ({"max_attacked": "1"}, "max_attacked"),
        ({"horizon": 1.5}, "horizon"),
    ):
        with pytest.raises(TypeError, match=f"^{name}"):
            as_spec(UGV.system, **{"max_attacked": 1, **keywords})
    with pytest.raises(TypeError, match="toarray"):
        System(sparse.csr_matrix(np.eye(2)), np.eye(2))


def test_a_linear_observer_exports_to_python_control_and_runs_alike():
    from ssecert.inputs import as_spec
    from ssecert.observers import build_observer

    spec = as_spec("ugv", observer={"kind": "luenberger", "gain": "place", "poles": [0.5, 0.6]})
    design = build_observer(spec.system, spec.observer)
    observer = design.to_control()
    assert observer.isdtime() and list(observer.input_labels) == list(spec.system.sensors)
    assert np.allclose(np.sort(np.abs(ct.poles(observer))), [0.5, 0.6])
    # the same estimates as x_hat+ = A x_hat + L (y - C x_hat), from x_hat(0) = 0
    y = np.random.default_rng(0).standard_normal((3, 20))
    response = ct.forced_response(observer, U=y, X0=np.zeros(2))
    x_hat = np.zeros(2)
    for k in range(20):
        assert np.allclose(response.outputs[:, k], x_hat, atol=1e-12)
        x_hat = spec.system.A @ x_hat + design.L @ (y[:, k] - spec.system.C @ x_hat)
    with pytest.raises(ValueError, match="a dsso observer is not linear.*error_matrix"):
        build_observer(UGV.system, UGV.observer).to_control()


def test_an_exported_observer_takes_the_plant_s_known_input():
    # a plant driven by u: the observer without u settles 0.025 away from the state; with the
    # plant given, (B - L D) u enters it and the error vanishes, at the plant's dt
    from ssecert.observers import build_observer

    A, B = [[1.0, 0.0099], [0.0, 0.9876]], [[0.0], [0.01]]
    C, D = [[1, 0], [0, 1], [0, 1]], [[0.0], [0.5], [0.0]]
    plant = ct.ss(A, B, C, D, 0.01, outputs=["position", "velocity-a", "velocity-b"])
    design = build_observer(
        System.from_control(plant), {"kind": "luenberger", "gain": "place", "poles": [0.5, 0.6]}
    )
    T, u = np.arange(300) * 0.01, np.ones((1, 300))
    run = ct.forced_response(plant, T, u, X0=[0.3, -0.2])
    alone = ct.forced_response(design.to_control(), T, run.outputs, X0=[0, 0]).outputs
    assert np.linalg.norm(alone[:, -1] - run.states[:, -1]) > 1e-3
    observer = design.to_control(plant)
    assert observer.dt == 0.01 and list(observer.input_labels)[3:] == ["u[0]"]
    both = np.vstack([run.outputs, u])
    estimate = ct.forced_response(observer, T, both, X0=[0, 0]).outputs
    assert np.linalg.norm(estimate[:, -1] - run.states[:, -1]) <= 1e-12
    with pytest.raises(ValueError, match="plant: its A and C"):
        design.to_control(ct.ss(np.eye(2), B, C, D, 0.01))
    with pytest.raises(TypeError, match="plant must be the python-control StateSpace"):
        design.to_control("plant")
    with pytest.raises(ValueError, match="plant must be a discrete-time system"):
        design.to_control(ct.ss(A, B, C, D, 0))


def test_a_plant_s_display_name_is_written_for_the_report_files():
    # a python-control plant named "UGV plant" (or a System "ugv (lab)") was refused by
    # analyze with an error about a spec key the user never wrote
    plant = ct.ss([[1.0, 0.0099], [0.0, 0.9876]], [[0.0], [0.01]], [[1, 0], [0, 1], [0, 1]], 0,
                  0.01, name="UGV plant")  # fmt: skip
    assert analyze(plant, max_attacked=0).meta["spec"]["name"] == "UGV-plant"
    lab = System(np.eye(2), [[1, 0], [0, 1]], name="ugv (lab) " + "x" * 200)
    name = analyze(lab, max_attacked=0).meta["spec"]["name"]
    assert name.startswith("ugv-lab-x") and len(name) == 128


def test_a_design_made_in_python_says_how_to_reproduce_it(tmp_path, monkeypatch):
    # the reproduce line was "ssecert certify '<python>' --no-sim", which cannot run
    import shlex

    from ssecert import certify
    from ssecert.cli import main

    result = certify(
        System([[1.0, 0.0099], [0.0, 0.9876]], [[1, 0], [0, 1], [0, 1]], name="ugv lab"),
        max_attacked=1,
        observer={"kind": "luenberger", "gain": "deadbeat"},
        simulate=False,
    )
    command = shlex.split(result.command, comments=True)
    assert command == ["ssecert", "certify", "ugv-lab.toml", "--no-sim"]
    monkeypatch.chdir(tmp_path)
    (tmp_path / "ugv-lab.toml").write_text(result.spec.to_toml())
    assert main([*command[1:], "--out", str(tmp_path)]) == result.exit_code
    # a packaged example changed by keywords is not that example: its own file is named
    changed = certify("ugv", max_attacked=0, simulate=False)
    assert shlex.split(changed.command, comments=True)[2] == "ugv.toml"
    assert "max_attacked = 0" in changed.spec.to_toml()
    assert shlex.split(certify("ugv", simulate=False).command)[2] == "ugv"


def test_placed_poles_from_python_and_back_to_a_file():
    # poles as a numpy array or complex numbers (build_observer took them, analyze did not);
    # a spec with placed poles, its max_attacked overridden, was refused (its own parsed
    # poles are complex), and could not be written as a spec file
    import tomllib

    from ssecert import spec_from_dict
    from ssecert.inputs import as_spec

    plant = System([[1.0, 0.0099], [0.0, 0.9876]], [[1, 0], [0, 1], [0, 1]])
    for poles in (np.array([0.5, 0.6]), [0.5 + 0.1j, 0.5 - 0.1j], [(0.5, 0.1), (0.5, -0.1)]):
        spec = as_spec(plant, max_attacked=0, observer={"kind": "luenberger", "gain": "place",
                                                        "poles": poles})  # fmt: skip
        assert spec.observer["poles"] == [complex(*z) if isinstance(z, tuple) else complex(z)
                                          for z in poles]  # fmt: skip
        assert as_spec(spec, max_attacked=1).observer == spec.observer
        again = spec_from_dict(tomllib.loads(spec.to_toml()))
        assert again.observer == spec.observer


def test_a_plant_with_nan_in_its_unused_b_or_d_is_refused(tmp_path):
    # B and D are not used, but a NaN there is a broken model: it was certified ("holds")
    from ssecert import load_spec
    from ssecert.spec import SpecError

    A, C = [[1.0, 0.0099], [0.0, 0.9876]], [[1, 0], [0, 1], [0, 1]]
    nan_b, nan_d = [[0.0], [np.nan]], [[0.0], [0.0], [np.nan]]
    with pytest.raises(ValueError, match="sys.B must be finite"):
        System.from_control(ct.ss(A, nan_b, C, 0, 0.01))
    with pytest.raises(ValueError, match="sys.D must be finite"):
        System.from_control(ct.ss(A, [[0.0], [1.0]], C, nan_d, 0.01))
    with pytest.raises(ValueError, match="sys.B must be finite"):
        System.from_scipy(signal.dlti(A, nan_b, C, np.zeros((3, 1)), dt=0.01))
    path = tmp_path / "plant.npz"
    np.savez(path, A=np.array(A), B=np.array(nan_b), C=np.array(C))
    with pytest.raises(SpecError, match="'B': expected finite entries"):
        load_spec(path, max_attacked=1)
