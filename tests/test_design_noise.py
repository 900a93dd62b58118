"""ssecert design under noise: the trade-off front's noise axis and the ``noise`` objective."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from ssecert.design.outcomes import DecayCode
from ssecert.design.search import (
    DEFAULT_DECAY,
    choose_decay,
    choose_noise_decay,
    design_observer,
    objective_refusal,
    tradeoff_front,
)
from ssecert.examples import load_example
from ssecert.noise import MeasurementNoise


def _point(alpha, bound, verified=True):
    return {
        "alpha": alpha,
        "contraction": math.sqrt(1 - alpha),
        "noise_bound": bound,
        "verified": verified,
    }


def test_the_noise_decay_is_the_fronts_smallest_bound_faster_than_the_plant():
    # the bound is not monotone in the decay: the middle point is the smallest
    front = [_point(0.5, 0.04), _point(0.2, 0.01), _point(0.01, 0.3)]
    choice = choose_noise_decay(front, 0.985)
    assert (choice.alpha, choice.code, choice.noise_bound) == (
        0.2,
        DecayCode.SMALLEST_NOISE_BOUND,
        0.01,
    )
    # a point no faster than the plant is not chosen, however small its bound
    slow = [_point(0.5, 0.04), _point(0.001, 0.001)]
    choice = choose_noise_decay(slow, 0.99)
    assert (choice.alpha, choice.faster, choice.verified) == (0.5, 1, 2)
    # unverified points and points without a bound do not count
    choice = choose_noise_decay([_point(0.2, None), _point(0.3, 0.1, False)], 0.9)
    assert (choice.alpha, choice.code) == (DEFAULT_DECAY, DecayCode.NO_NOISE_BOUND)
    # none faster than the plant: the fastest
    choice = choose_noise_decay([_point(0.01, 0.2), _point(0.02, 0.5)], 0.5)
    assert (choice.alpha, choice.code) == (0.02, DecayCode.FASTEST_NOISE_BOUND)
    # no noise: every bound 0, nothing to minimise; the gain objective's rule decides
    flat = [{**_point(a, 0.0), "gamma": g} for a, g in ((0.5, 3.0), (0.2, 0.5), (0.01, 0.1))]
    choice = choose_noise_decay(flat, 0.985)
    assert (choice.alpha, choice.code) == (0.2, DecayCode.NO_NOISE)
    assert choice.then == choose_decay(flat, 0.985)


def test_the_noise_objective_needs_a_noise_and_a_kind_with_decay():
    system = load_example("ugv").system
    with pytest.raises(ValueError, match="needs the measurement noise bound"):
        design_observer(system, "elastic_net", objective="noise", time_budget=1)
    for bad, words in [
        (-1.0, "noise: measurement must be >= 0"),
        (True, "noise: expected a bound >= 0 or one per sensor"),
        ([0.1, 0.2], "one bound per sensor"),
        (MeasurementNoise.uniform(0.1, 5), "each of the plant's 3 sensors, got 5"),
    ]:
        with pytest.raises(ValueError, match=words):
            design_observer(system, "elastic_net", objective="noise", noise=bad, time_budget=1)
    refusal = objective_refusal("noise", "dsso")
    assert refusal is not None and (refusal.objective, refusal.kind) == ("noise", "dsso")
    assert refusal.takers == ("the elastic-net observer", "the Luenberger observer")


@pytest.mark.slow
def test_every_front_bound_holds_along_the_noise_search_of_its_design():
    from ssecert.design.search import _template
    from ssecert.design.synthesis import with_gain
    from ssecert.stability.noise_messages import noise_search

    system = load_example("ugv").system
    noise = MeasurementNoise.uniform(1e-3, system.p)
    template = _template(system, "elastic_net", 0.3, 0.3, 0.1)
    front = tradeoff_front(template, noise=noise, points=5)
    bounded = [p for p in front if p.get("noise_bound") is not None]
    assert len(bounded) >= 3
    for point in bounded:
        assert point["verified"] and point["alpha"] > 0
    # the front's designs, run under the search's noise sequences, stay within their bounds
    from ssecert.design.synthesis import synthesize_gain

    for point in bounded:
        proposal = synthesize_gain(template, alpha=point["alpha"])
        design = with_gain(template, proposal.L)
        found = noise_search(design, noise)
        assert found["largest_error"] <= point["noise_bound"] * (1 + 1e-9), point


@pytest.mark.slow
def test_design_minimises_the_certified_noise_bound(tmp_path, capsys):
    from ssecert.cli import main

    code = main(["design", "ugv", "--objective", "noise", "--out", str(tmp_path)])
    captured = capsys.readouterr()
    assert code == 2 and "--objective noise needs the measurement noise bound" in captured.err
    code = main(
        ["design", "ugv", "--objective", "noise", "--noise", "1e-3", "--out", str(tmp_path),
         "--time-budget", "20", "--json", str(tmp_path / "result.json")]
    )  # fmt: skip
    assert code in (0, 1, 3)
    result = json.loads((tmp_path / "result.json").read_text())
    certified = [c for c in result["candidates"] if c["certified"] and c.get("decay") is not None]
    # the chosen design has the smallest certified bound among the candidates whose decay
    # is certified, and it is the bound its own certificate reports
    assert result["noise_bound"] == min(c["noise_bound"] for c in certified)
    doc = json.loads((tmp_path / "ugv-design.json").read_text())
    assert doc["checks"]["observer_noise_bound"]["value"] == result["noise_bound"]
    assert "measurement = 0.001" in (tmp_path / "ugv-design.toml").read_text()
    chosen = result["comparison"]["tradeoff"]["chosen"]
    assert chosen["noise_bound"] == result["noise_bound"]
    assert any(p.get("noise_bound") is not None for p in result["front"])
    assert "tradeoff-noise-front" in (tmp_path / "ugv-design.html").read_text()


@pytest.mark.slow
def test_the_trade_off_plot_has_a_noise_panel_only_for_positive_bounds():
    import warnings

    from ssecert.report.plots import tradeoff_plot

    front = [
        {"verified": True, "contraction": 0.8, "gamma": 1.0, "noise_bound": 0.0},
        {"verified": True, "contraction": 0.9, "gamma": 0.8, "noise_bound": 0.0},
    ]
    tradeoff = {"front": front, "chosen": {"contraction": 0.8, "gamma": 1.0}, "plant_radius": 1.0}
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a log axis of zeros warns
        assert "tradeoff-noise-front" not in tradeoff_plot(tradeoff)
        front[0]["noise_bound"], front[1]["noise_bound"] = 0.1, 0.2
        assert "tradeoff-noise-front" in tradeoff_plot(tradeoff)
    assert "tradeoff-noise-front" not in tradeoff_plot({**tradeoff, "front": front[:0]})


def test_noise_at_the_top_of_the_float_range_is_inconclusive_not_an_error():
    from ssecert.observers import build_observer
    from ssecert.stability.noise_gain import NoiseGainCode, dissipation_bound, linear_noise_bound

    assert MeasurementNoise.scale(1e308) == 2.0**1023 and MeasurementNoise.scale(0.0) == 1.0
    assert MeasurementNoise.scale(0.75) == 1.0 and MeasurementNoise.scale(3.0) == 4.0
    # 2e308 and about 8e308: beyond the floats, said so (they raised OverflowError)
    found = linear_noise_bound(np.array([[0.5]]), np.array([[1.0]]), np.array([1e308]))
    assert found.code is NoiseGainCode.OUT_OF_RANGE
    huge = dissipation_bound(np.eye(2), 0.5, 2.0, np.array([1e308, 1e308]), 1)
    assert huge.bound == math.inf and not huge.ill_conditioned
    # 1e307 stays in range: 2e307 exactly, taken up by its rounding
    near = linear_noise_bound(np.array([[0.5]]), np.array([[1.0]]), np.array([1e307]))
    assert near.code is NoiseGainCode.CERTIFIED and 2e307 <= near.bound_inf <= 2e307 * (1 + 1e-12)
    system = load_example("ugv").system
    design = build_observer(system, {"kind": "luenberger", "gain": "pinv"})
    from ssecert.stability.noise_messages import observer_noise_check

    # (it raised OverflowError): the pinv gain's F is 0 here, so the bound |L| eta fits
    check = observer_noise_check(design, MeasurementNoise.uniform(1e308, system.p))
    assert check.verdict.value == "holds" and 1e308 <= check.value < math.inf


@pytest.mark.slow
def test_a_noise_search_near_1e200_does_not_overflow_into_a_false_excess():
    from ssecert.observers import build_observer
    from ssecert.stability.checks import iss_gain_check, observer_stability_check
    from ssecert.stability.noise_messages import sparse_noise_check

    system = load_example("ugv").system
    design = build_observer(
        system,
        {"kind": "elastic_net", "gain": "deadbeat", "step": 0.1, "threshold": 0.1, "shrink": 0.3},
    )
    _, cert = observer_stability_check(design)
    iss = iss_gain_check(design, cert)
    check = sparse_noise_check(design, iss, MeasurementNoise.uniform(1e200, system.p))
    assert check.verdict.value == "holds", check.summary
    assert check.evidence["noise_search"]["largest_error"] <= check.value
