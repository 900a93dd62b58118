"""Where the error goes under a constant attack (iss_gain evidence, constant_attacks)."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from ssecert import analyze, spec_from_dict
from ssecert.examples import example_path
from ssecert.observers import build_observer
from ssecert.observers.lure import LureModel
from ssecert.stability import observer_messages
from ssecert.stability.constant_attack import constant_attack_outcomes, default_attacks


def _ugv(observer: dict) -> dict:
    with open(example_path("ugv"), "rb") as fh:
        data = tomllib.load(fh)
    data["observer"] = observer
    return data


def _records(cert) -> list[dict]:
    return cert["iss_gain"].evidence["constant_attacks"]


def test_a_linear_observer_converges_to_its_exact_bias():
    cert = analyze(spec_from_dict(_ugv({"kind": "luenberger", "gain": "deadbeat"})))
    (rec,) = _records(cert)
    assert rec["outcome"] == "converges to a bias" and rec["proved"]
    L = np.asarray(cert["observer_gain"].fields["L"])
    A = np.array([[1.0, 0.0099], [0.0, 0.9876]])
    F = A - L @ np.array([[1, 0], [0, 1], [0, 1]])
    a = np.array([0.0, 5.0, 0.0])
    bias = np.linalg.solve(np.eye(2) - F, L @ a)  # e* = F e* + L a
    np.testing.assert_allclose(np.abs(rec["bias"]), np.abs(bias), rtol=1e-9)
    # the summary says where the named attack takes the error, in observer_messages' words
    assert rec["attack"] == "scenario constant-velocity-a"
    assert cert["iss_gain"].summary.endswith(observer_messages.constant_attack_text([rec]))


def test_an_attack_the_gain_ignores_leaves_no_bias():
    data = _ugv({"kind": "luenberger", "gain": [[1.0, 0.0, 0.0], [0.0, 0.5, 0.0]]})
    data["scenario"] = [
        {"name": "ignored", "attack": "constant", "sensors": [2], "magnitude": 3.0, "steps": 10}
    ]
    (rec,) = _records(analyze(spec_from_dict(data)))
    assert rec["outcome"] == "converges to zero" and rec["proved"]


def test_a_certified_elastic_net_observer_converges_to_the_same_bias_from_anywhere():
    obs = {"kind": "elastic_net", "gain": "deadbeat", "step": 0.7, "threshold": 0.1, "shrink": 0.5}
    spec = spec_from_dict(_ugv(obs))
    cert = analyze(spec)
    assert cert["observer_stability"].verdict.value == "holds"
    (rec,) = _records(cert)
    assert rec["proved"] and rec["outcome"] == "converges to a bias" and rec["exact"]
    # the certificate's claim, replayed: every initial error goes to the same equilibrium
    model = LureModel.from_design(build_observer(spec.system, spec.observer))
    a = np.asarray(rec["vector"])
    rng = np.random.default_rng(1)
    starts = rng.standard_normal((30, model.N)) * 10.0 ** rng.uniform(-1, 2, (30, 1))
    end = model.simulate(starts, 4000, np.tile(a, (4000, 30, 1)))[-1]
    np.testing.assert_allclose(end[:, : model.n_e], np.tile(rec["bias"], (30, 1)), atol=1e-8)


def test_the_thesis_dsso_settles_on_a_bias_that_is_observed_not_proved():
    with open(example_path("ugv"), "rb") as fh:
        cert = analyze(spec_from_dict(tomllib.load(fh)))
    (rec,) = _records(cert)
    assert rec["outcome"] == "converges to a bias" and not rec["proved"]
    assert rec["bias_norm"] == pytest.approx(0.1394, abs=1e-4) and rec["exact"]


def test_an_unstable_observer_is_unbounded_under_attack():
    data = _ugv({"kind": "luenberger", "gain": [[2.5, 0.0, 0.0], [0.0, 0.5, 0.5]]})
    (rec,) = _records(analyze(spec_from_dict(data)))
    assert rec["outcome"] == "unbounded" and rec["simulation"]["growth"] > 1e7


def test_default_attacks_without_a_constant_scenario_are_unit_attacks_on_s_sensors():
    attacks = default_attacks(4, 2)
    assert len(attacks) == 6 and all(a.sum() == 2 for _, a in attacks)
    assert default_attacks(3, 0) == []


def test_a_stacked_attack_of_the_wrong_length_is_skipped():
    model = LureModel.linear(np.array([[0.5]]), np.array([[1.0, 1.0]]))
    assert constant_attack_outcomes(model, [("x", np.ones(3))], certified=True) == []


_BIG_SENSOR = {
    "name": "big-sensor",
    "system": {
        "A": [[-0.4, -0.9], [1.1, -0.4]],
        "C": [[9e8, -2e8], [0.7, 0.5], [0.8, 0.7]],
    },
    "attack": {"max_attacked": 1},
    "observer": {
        "kind": "elastic_net",
        "gain": [
            [6.133836580638581e-10, -0.4952565541160872, -0.7567071304702643],
            [1.3779455268795268e-09, 0.01581148627970962, -0.18902376823421455],
        ],
        "step": 1.0,
        "threshold": 0.1,
        "shrink": 0.8,
    },
}


def test_an_attack_estimate_large_in_its_sensors_units_is_not_growth():
    # sensor 0 reads in units 1e9 times smaller: the estimate of its attack settles near
    # 6.5e7 (an error of 0.07 there), after a transient of 3.6e8, more than 1e8 times a unit
    # attack on sensor 1; the error itself settles at 0.134
    spec = spec_from_dict(_BIG_SENSOR)
    model = LureModel.from_design(build_observer(spec.system, spec.observer))
    records = constant_attack_outcomes(model, default_attacks(3, 1), certified=False)
    assert [r["outcome"] for r in records] == ["converges to a bias"] * 3
    assert records[1]["bias_norm"] == pytest.approx(0.1338, abs=1e-4)
    assert abs(records[1]["attack_estimate"][0]) > 1e7  # large in sensor 0's units
    # the same plant with twice the gain (rho(F) = 1.07): still unbounded
    gain = (2 * np.array(_BIG_SENSOR["observer"]["gain"])).tolist()
    spec = spec_from_dict({**_BIG_SENSOR, "observer": {**_BIG_SENSOR["observer"], "gain": gain}})
    model = LureModel.from_design(build_observer(spec.system, spec.observer))
    records = constant_attack_outcomes(model, default_attacks(3, 1), certified=False)
    assert [r["outcome"] for r in records] == ["unbounded"] * 3


_MIXED_UNITS = {
    "name": "mixed-units",
    "system": {
        "A": [[0.658, -2.593, 1.802], [0.888, -1.069, 1.156], [0.725, 0.585, 0.057]],
        "C": [
            [-790273982.464, -175019917.312, -517543559.168],
            [0.0005849609375, 3.90625e-05, -0.00028515625],
            [-800.768, -263.168, 8.192],
            [-0.276, 1.294, 1.007],
            [-2.524815499782562e-09, -1.759268343448639e-09, -1.6298145055770873e-10],
        ],
    },
    "attack": {"max_attacked": 1},
    "observer": {
        "kind": "elastic_net",
        "gain": [
            [-5.519999129611056e-09, 0.0, 0.0, -0.8173831057367233, 1421850203.647768],
            [-3.1372517268441423e-09, 0.0, 0.0, -0.35610660224971524, 669187050.9079216],
            [7.096049067183165e-10, 0.0, 0.0, -0.12563046212518136, -495524638.6001171],
        ],
        "step": 1.2,
        "threshold": 0.1,
        "shrink": 0.5,
    },
}


def test_large_biases_and_cycles_are_not_growth_and_the_nearest_equilibrium_is_taken():
    # sensors in units from 2^-30 to 2^30 apart (C's rows, the gain's columns divided):
    # a unit attack on sensor 4 settles on an error of 4.4e8 (sensor 4 reads it as 1), on
    # sensors 0 and 3 the run ends in a cycle of period 2 near an error of 1.1e8, more than
    # 1e8 times the attack but not growing: neither is unbounded.  Sensors 1 and 2 have
    # zero columns in the gain: the error stays exactly 0, and an equilibrium with a bias of
    # 3.5e-10 within the tolerance of the one reached is not taken for it.
    spec = spec_from_dict(_MIXED_UNITS)
    model = LureModel.from_design(build_observer(spec.system, spec.observer))
    records = constant_attack_outcomes(model, default_attacks(5, 1), certified=False)
    outcomes = [r["outcome"] for r in records]
    assert outcomes == ["undecided", "converges to zero", "converges to zero", "undecided",
                        "converges to a bias"]  # fmt: skip
    assert records[4]["bias_norm"] > 1e8
    # the cycle, replayed: every other step the same state, consecutive ones far apart
    a = np.zeros(5)
    a[0] = 1.0
    end = model.simulate(np.zeros(model.N), 3001, np.tile(a, (3001, 1)))[-3:]
    n = model.n_e
    assert np.linalg.norm(end[2, :n] - end[0, :n]) <= 1e-9 * np.linalg.norm(end[0, :n])
    assert np.linalg.norm(end[1] - end[0]) > 1e-3 * np.linalg.norm(end[0])
    assert 1e8 < np.linalg.norm(end[0, :n]) < 1e9


def test_growth_from_a_huge_attack_is_measured_past_the_squares_overflow():
    # error e+ = 1.01 e + a with a = 1e150: past 1e154 the squares of the error overflow
    # (numpy's norm reads inf there); the run must still be seen to grow 1e8 times past the
    # attack and 1e8 times further (about 3,700 steps), not end undecided
    model = LureModel.linear(np.array([[1.01]]), np.array([[1.0]]))
    records = constant_attack_outcomes(model, [("huge", np.array([1e150]))], certified=False)
    assert [r["outcome"] for r in records] == ["unbounded"]
    assert records[0]["simulation"]["steps"] < 5000


def test_a_run_that_settles_off_the_confirmed_equilibria_is_not_said_to_wander():
    # duplicate sensors 0 and 1: under an attack on sensor 0 the D-SSO settles in 41 steps on
    # a point of a family of equilibria, in a pattern whose equations are singular (the
    # search confirms none of it): undecided, with what the search found, not "did not settle"
    spec = spec_from_dict(
        {
            "name": "dup",
            "system": {"A": [[1.0, 0.1], [0.0, 0.5]], "C": [[1, 0], [1, 0], [0, 1]]},
            "attack": {"max_attacked": 1},
            "observer": {"kind": "dsso", "gain": "deadbeat", "step": 0.5, "threshold": 0.1},
        }
    )
    model = LureModel.from_design(build_observer(spec.system, spec.observer))
    (record,) = constant_attack_outcomes(model, [("c", np.array([2.0, 0, 0]))], certified=False)
    assert record["simulation"]["settled"] and record["outcome"] == "undecided"
    assert record["equilibrium_search"] and record["equilibrium_search"] in record["how"]
