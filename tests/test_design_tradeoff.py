"""``ssecert design`` against two objectives: the certified trade-off between decay and l2
gain, a default design clearly faster than the plant, and comparisons on the absolute error."""

from __future__ import annotations

import itertools
import json
import math
from types import SimpleNamespace

import numpy as np
import pytest

from ssecert.design.outcomes import DecayChoice, DecayCode
from ssecert.design.search import choose_decay, compare_designs, design_observer, no_faster
from ssecert.design.search_messages import comparison_summary, decay_text
from ssecert.simulation.metrics import absolute_error, initial_relative_error
from ssecert.system import System


def _damped_plant() -> System:
    """Stable, 4 states, 6 sensors, two lightly damped modes: rho(A) = 0.985."""
    rng = np.random.default_rng(3)

    def rot(r: float, th: float) -> np.ndarray:
        return r * np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])

    A = np.zeros((4, 4))
    A[:2, :2], A[2:, 2:] = rot(0.985, 0.3), rot(0.97, 0.8)
    T = rng.standard_normal((4, 4))
    return System(T @ A @ np.linalg.inv(T), rng.standard_normal((6, 4)))


@pytest.fixture(scope="module")
def plant() -> System:
    return _damped_plant()


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["luenberger", "elastic_net"])
def test_the_default_design_is_clearly_faster_than_a_stable_plant(plant, kind):
    result = design_observer(plant, kind, time_budget=20)
    assert result.observer is not None and result.gamma is not None
    rho = result.plant_radius
    assert rho == pytest.approx(0.985, abs=1e-9)
    # the imposed decay is at least twice the plant's (contraction <= rho^2), and the linear
    # loop is no slower than the certified contraction
    assert result.decay is not None and math.sqrt(1 - result.decay) <= rho**2 + 1e-12
    L = np.asarray(result.observer["gain"])
    radius = float(np.abs(np.linalg.eigvals(plant.A - L @ plant.C)).max())
    assert radius == pytest.approx(result.linear_radius, rel=1e-9)
    assert radius <= rho**2
    assert "clearly faster" in result.choice
    verified = [p for p in result.front if p["verified"]]
    assert len(verified) >= 3
    # a Pareto front: a slower certified decay never costs a larger certified gain
    by_speed = sorted(verified, key=lambda p: p["contraction"])
    gains = [p["gamma"] for p in by_speed]
    assert all(b <= a * (1 + 1e-3) for a, b in itertools.pairwise(gains))


def test_an_explicit_min_decay_may_give_a_design_no_faster_than_the_plant_and_names_it(plant):
    result = design_observer(plant, "luenberger", min_decay=1e-3, time_budget=20)
    assert result.observer is not None
    # the smallest gain at almost no decay: L near 0, the plant's own decay does the work
    assert result.linear_radius == pytest.approx(result.plant_radius, abs=1e-4)
    assert no_faster(result.linear_radius, result.plant_radius)
    assert "min_decay" in result.choice and "no faster than the plant" in result.choice
    # the default never chooses it
    default = design_observer(plant, "luenberger", time_budget=20)
    assert not no_faster(default.linear_radius, default.plant_radius)
    assert "no faster" not in default.choice


def _point(alpha: float, gamma: float) -> dict:
    return {"alpha": alpha, "contraction": math.sqrt(1 - alpha), "gamma": gamma, "verified": True}


def test_choose_decay_takes_the_smallest_gain_twice_as_fast_as_the_plant():
    front = [_point(0.75, 9.0), _point(0.36, 2.0), _point(0.19, 1.0), _point(0.01, 0.1)]
    choice = choose_decay(front, 0.94)  # rho^2 = 0.8836: 0.5, 0.8 qualify, 0.9 does not
    assert (choice.alpha, choice.code) == (0.36, DecayCode.TWICE_AS_FAST)
    assert choice.contraction == 0.8 and choice.plant_radius == 0.94 and choice.verified == 4
    # a slower plant lets the slower point qualify
    assert choose_decay(front, 0.95).alpha == 0.19  # rho^2 = 0.9025 >= 0.9


def test_choose_decay_takes_the_knee_when_nothing_is_twice_as_fast_or_the_plant_is_unstable():
    contractions, gains = (0.981, 0.983, 0.986, 0.989), (50.0, 3.0, 2.0, 1.5)
    front = [_point(1 - c**2, g) for c, g in zip(contractions, gains)]
    corner = 1 - 0.983**2  # the gain falls 17x to it, then little
    choice = choose_decay(front, 0.99)  # rho^2 = 0.9801: no point is that fast
    assert (choice.alpha, choice.code, choice.faster) == (corner, DecayCode.KNEE, 4)
    assert choice.plant_stable and choice.fastest == pytest.approx(0.981)
    choice = choose_decay(front, 1.0)
    assert (choice.alpha, choice.code, choice.plant_stable) == (corner, DecayCode.KNEE, False)
    # fewer than three points faster than the plant: the smallest gain among them
    choice = choose_decay(front, 0.984)
    assert (choice.alpha, choice.code, choice.faster) == (corner, DecayCode.FEW_FASTER, 2)
    # nothing faster than the plant: the fastest point, and it says so
    choice = choose_decay(front, 0.98)
    assert (choice.alpha, choice.code) == (1 - 0.981**2, DecayCode.FASTEST)
    # no front to read: 1e-3 (the linear loop's own requirement asks for speed)
    choice = choose_decay([{**_point(0.5, 1.0), "verified": False}], 0.9)
    assert (choice.alpha, choice.code, choice.verified) == (1e-3, DecayCode.TOO_FEW_POINTS, 0)
    choice = choose_decay([_point(0.5, 1.0)], 1.2)
    assert (choice.alpha, choice.code, choice.verified) == (1e-3, DecayCode.TOO_FEW_POINTS, 1)
    # a spectral radius of 1 to rounding (the thesis's normalised plants) is not stable
    assert choose_decay([_point(0.5, 1.0)], 1 - 1e-15).alpha == 1e-3
    choice = choose_decay(front, 1 - 1e-15)
    assert (choice.alpha, choice.code, choice.plant_stable) == (corner, DecayCode.KNEE, False)


def test_the_words_of_each_decay_rule():
    def words(code, **facts):
        return decay_text(DecayChoice(0.25, code, 0.99, facts.pop("stable", True), **facts))

    assert words(DecayCode.TOO_FEW_POINTS) == (
        "decay 0.25 per step imposed: the trade-off front has fewer than two verified points "
        "(its solves failed, did not verify, or ran past its share of the time budget)"
    )
    assert words(DecayCode.TWICE_AS_FAST, contraction=0.8) == (
        "decay 0.25 per step imposed, the trade-off front's smallest certified gain whose decay "
        "is clearly faster than the plant's: error contraction 0.8 per step <= rho(A)^2 = "
        "0.9801 (the plant's own state: rho(A) = 0.99)"
    )
    assert words(DecayCode.KNEE, contraction=0.9, fastest=0.85) == (
        "decay 0.25 per step imposed, the knee of the trade-off front (error contraction 0.9 "
        "per step; no certified contraction reaches rho(A)^2 = 0.9801 (the fastest: 0.85))"
    )
    assert words(DecayCode.FEW_FASTER, contraction=0.9, faster=1, stable=False) == (
        "decay 0.25 per step imposed, the smallest certified gain of the 1 verified point of "
        "the front faster than the plant (too few for a knee) (error contraction 0.9 per step; "
        "the plant is not stable (rho(A) = 0.99): every certified decay is faster than its own)"
    )
    assert words(DecayCode.FASTEST, contraction=0.995) == (
        "decay 0.25 per step imposed, the fastest the trade-off front certifies (error "
        "contraction 0.995 per step); none is faster than the plant's own (rho(A) = 0.99)"
    )
    assert words(DecayCode.NO_NOISE_BOUND) == (
        "decay 0.25 per step imposed: no point of the trade-off front has a certified ultimate "
        "error bound under the noise (its solves failed, did not verify, or ran past its share "
        "of the time budget)"
    )
    noise = {"contraction": 0.9, "noise_bound": 0.01, "verified": 3}
    assert words(DecayCode.SMALLEST_NOISE_BOUND, faster=2, **noise) == (
        "decay 0.25 per step imposed, the smallest certified ultimate error bound under noise "
        "(0.01 for the grid's middle design at that decay) of the 2 verified points of the "
        "front faster than the plant (error contraction 0.9 per step)"
    )
    assert words(DecayCode.SMALLEST_NOISE_BOUND, faster=3, **noise).endswith(
        "of the 3 verified points of the front (error contraction 0.9 per step)"
    )
    assert words(DecayCode.FASTEST_NOISE_BOUND, **noise).endswith(
        "of the fastest of the front, none being faster than the plant (rho(A) = 0.99) (error "
        "contraction 0.9 per step)"
    )
    then = DecayChoice(0.25, DecayCode.TOO_FEW_POINTS, 0.99, True)
    assert words(DecayCode.NO_NOISE, then=then) == (
        f"{decay_text(then)}; the noise bound is 0 at every point of the front (no noise)"
    )


def test_the_error_metrics_do_not_grow_when_the_state_decays():
    steps = np.arange(50)
    x = np.stack([0.5**steps, np.zeros(50)], axis=-1)[:, None, :]  # (steps, runs, n)
    x_hat = x + np.array([0.1, 0.0])  # a bias the error keeps
    x0 = x[0]
    err = absolute_error(x_hat, x)
    assert np.allclose(err, 0.1)
    np.testing.assert_allclose(initial_relative_error(err, x0), 1.0)
    from ssecert.simulation.metrics import relative_error

    assert relative_error(x_hat, x, x0[None])[-1, 0] > 1e7  # what misled (floored at 1e-9 ||x0||)


def test_the_comparison_reads_the_absolute_error_not_the_relative_one():
    def result(absolute: float, relative: float, label: str):
        sims = {
            "a": SimpleNamespace(
                relative_error=np.array([[1.0], [relative]]),
                absolute_error=np.array([[1.0], [absolute]]),
                runs=1,
                steps=1,
                seed=0,
                final=lambda: {
                    "relative_error_mean": relative,
                    "absolute_error_mean": absolute,
                    "absolute_error_q90": absolute,
                    "initial_relative_error_mean": absolute,
                },
            )
        }
        spec = SimpleNamespace(observer={"kind": label})
        cert = SimpleNamespace(get=lambda check_id: None)
        return SimpleNamespace(simulations=sims, spec=spec, certificate=cert)

    # the synthesised design has the larger relative error but the smaller absolute one
    out = compare_designs(result(2.0, 0.5, "dsso"), result(0.2, 30.0, "elastic_net"))
    assert out["scenarios"][0]["comparison"] == "better"
    assert out["scenarios"][0]["synthesised"]["mean_error"] == pytest.approx(0.6)  # (1 + 0.2) / 2
    assert out["worse_in"] == [] and "absolute" in out["metric"]
    assert out["summary"] == comparison_summary(True, 1, 1, [], [], None)
    out = compare_designs(result(0.2, 30.0, "dsso"), result(2.0, 0.5, "elastic_net"))
    assert out["scenarios"][0]["comparison"] == "worse"


@pytest.mark.slow
def test_design_on_a_stable_plant_plots_the_tradeoff_and_names_its_metric(plant, tmp_path, capsys):
    from ssecert.spec.write import dumps

    spec = {
        "name": "damped",
        "system": {"A": plant.A.tolist(), "C": plant.C.tolist()},
        "attack": {"max_attacked": 1},
        "observer": {"kind": "luenberger", "gain": "place", "poles": [0.5, 0.5, 0.6, 0.6]},
        "scenario": [
            {"name": "constant", "attack": "constant", "sensors": [0], "magnitude": [1.0, 2.0],
             "steps": 60, "runs": 4, "seed": 0}
        ],
    }  # fmt: skip
    path = tmp_path / "damped.toml"
    path.write_text(dumps(spec))
    from ssecert.cli import main

    status = main(["design", str(path), "--observer", "luenberger", "--out", str(tmp_path),
                   "--json", str(tmp_path / "r.json"), "--time-budget", "20"])  # fmt: skip
    printed = capsys.readouterr().out
    assert status == 0, printed
    assert "faster than the plant's own rho(A) = 0.985" in printed
    assert "mean error ||x_hat - x|| over the horizon" in printed
    result = json.loads((tmp_path / "r.json").read_text())
    assert result["linear_radius"] < result["plant_radius"] ** 2
    html = (tmp_path / "damped-design.html").read_text()
    assert 'id="tradeoff"' in html and "tradeoff-front" in html and "tradeoff-chosen" in html
    assert "tradeoff-spec" in html  # the spec's Luenberger design has a certified gain
    assert "of the initial error" in html


def test_assert_recovers_takes_an_absolute_tolerance_for_a_decaying_state(plant):
    from ssecert import spec_from_dict
    from ssecert.testing import assert_recovers

    design = spec_from_dict(
        {
            "name": "damped",
            "system": {"A": plant.A.tolist(), "C": plant.C.tolist()},
            "attack": {"max_attacked": 1},
            "observer": {"kind": "luenberger", "gain": "place", "poles": [0.5, 0.5, 0.6, 0.6]},
        }
    )
    # a constant attack leaves a bias: the error converges, the state decays to 0
    scenario = {"attack": "constant", "sensors": [0], "magnitude": [1.0, 1.0], "steps": 400,
                "runs": 4}  # fmt: skip
    result = assert_recovers(design, scenario, 0, atol=100.0)
    bias = float(result.absolute_error[-1].max())
    assert result.relative_error[-1].min() > 100  # what a relative tolerance would read
    with pytest.raises(AssertionError, match=r"an error \|\|x_hat - x\|\| above atol"):
        assert_recovers(design, scenario, 0, atol=0.5 * bias)
    with pytest.raises(AssertionError, match="relative state error above tol = 10"):
        assert_recovers(design, scenario, 10.0)
    # both tolerances: ||e|| <= atol + tol ||x||, as numpy.isclose combines them
    assert_recovers(design, scenario, 1e-3, atol=1.01 * bias)


@pytest.mark.slow
def test_a_fast_plant_and_a_dsso_get_designs_that_use_their_sensors():
    C = [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, -1.0]]
    fast = System(np.diag([0.3, 0.2]), np.array(C))
    result = design_observer(fast, "luenberger", time_budget=20)
    assert result.observer is not None and result.linear_radius <= 0.3**2 + 1e-6
    assert "the linear loop is required to contract by 0.09" in result.choice
    # the D-SSO's certified decay cannot beat its plant (its large-signal loop holds A):
    # the linear loop's own requirement makes it use its sensors all the same
    result = design_observer(_damped_plant(), "dsso", time_budget=20)
    assert result.observer is not None
    assert not no_faster(result.linear_radius, result.plant_radius)
    # a nilpotent plant: nothing is slower than it, a design is found
    nilpotent = System(np.array([[0.0, 1.0], [0.0, 0.0]]), np.array(C))
    result = design_observer(nilpotent, "luenberger", time_budget=20)
    assert result.observer is not None and not no_faster(result.linear_radius, 0.0)


def test_assert_recovers_names_only_what_its_scenario_uses(plant):
    from ssecert import spec_from_dict
    from ssecert.testing import assert_recovers

    design = spec_from_dict(
        {
            "name": "blind",
            "system": {"A": plant.A.tolist(), "C": plant.C.tolist()},
            "attack": {"max_attacked": 1},
            "observer": {"kind": "luenberger", "gain": np.zeros((4, 6)).tolist()},
        }
    )
    with pytest.raises(AssertionError) as info:
        assert_recovers(design, {"attack": "none", "steps": 3, "runs": 2}, 1e-6)
    assert "attack 'none'" in str(info.value) and "magnitude" not in str(info.value)
