"""Plants from python-control and SciPy objects."""

import control as ct
import numpy as np
import pytest
from scipy import signal

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
