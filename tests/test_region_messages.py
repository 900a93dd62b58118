"""The region of attraction's outcomes: decisions on codes, words from one module."""

from __future__ import annotations

import numpy as np
import pytest

from ssecert.budget import Budget
from ssecert.observers import build_observer
from ssecert.observers.lure import LureModel
from ssecert.results import Verdict
from ssecert.stability import region_messages
from ssecert.stability.outcomes import Region, RegionCode
from ssecert.stability.roa import region_of_attraction
from ssecert.system import System

# the facts each code's words need
FACTS = {
    RegionCode.NOT_ATTEMPTED: {"refusal": "too big"},
    RegionCode.DEAD_ZONE_UNSTABLE: {"lyapunov": "rho = 1.5"},
    RegionCode.NO_VERIFIED_LYAPUNOV: {"lyapunov": "no P"},
    RegionCode.LEVEL_OUT_OF_RANGE: {"threshold": 1e300},
    RegionCode.EXACT_RECHECK_FAILED: {"refuted": ["ball_in_level_set"]},
    RegionCode.WITHIN_FLOOR: {"floor": 0.25},
}
CERTIFIED = (RegionCode.CERTIFIED, RegionCode.PIECEWISE_CERTIFIED)


def _model(a: float, threshold: float = 0.1) -> LureModel:
    system = System(np.array([[a]]), np.array([[1.0], [1.0], [1.0]]))
    design = build_observer(
        system,
        {"kind": "elastic_net", "gain": [[0.0, 0.0, 0.0]], "step": 0.5, "threshold": threshold,
         "shrink": 0.5},
    )  # fmt: skip
    return LureModel.from_design(design)


@pytest.mark.parametrize("code", [c for c in RegionCode if c not in CERTIFIED])
def test_every_reason_code_has_words_and_only_instability_fails(code):
    region = Region.none(code, **FACTS.get(code, {}))
    words = region_messages.reason(region)
    assert words and words == words.strip()
    expected = Verdict.FAILS if code is RegionCode.DEAD_ZONE_UNSTABLE else Verdict.INCONCLUSIVE
    assert region.verdict is expected
    check = region_messages.lure_region_check(region)
    assert check.verdict is expected and check.value == 0.0 and check.required is False
    assert check.evidence["reason"] == words and words in check.summary


def test_the_code_and_the_radius_agree():
    with pytest.raises(ValueError, match="radius"):
        Region(0.0, RegionCode.CERTIFIED)
    with pytest.raises(ValueError, match="radius"):
        Region(1.0, RegionCode.NO_DEAD_ZONE)
    assert Region(0.5, RegionCode.CERTIFIED).verdict is Verdict.HOLDS


def test_the_record_keeps_the_order_the_json_had():
    """radius, then (where the dead zone's Lyapunov analysis was the reason) unstable, the
    reason, the evidence; a nested region is written as its record without its radius."""
    nested = Region.none(RegionCode.NO_PIECEWISE_FUNCTION, {"attempts": []})
    region = Region.none(RegionCode.NO_VERIFIED_LYAPUNOV, {"piecewise": nested}, lyapunov="x")
    rec = region_messages.record(region)
    assert list(rec) == ["radius", "unstable", "reason", "piecewise"]
    assert rec["unstable"] is False and list(rec["piecewise"]) == ["reason", "attempts"]
    ok = Region(2.0, RegionCode.CERTIFIED, evidence={"level": 1.0, "P": np.eye(1)})
    assert list(region_messages.record(ok)) == ["radius", "level", "P"]


@pytest.mark.slow
def test_the_analysis_returns_the_code_of_what_it_found():
    assert region_of_attraction(_model(1.5)).code is RegionCode.DEAD_ZONE_UNSTABLE
    assert region_of_attraction(_model(0.5, threshold=0.0)).code is RegionCode.NO_DEAD_ZONE
    found = region_of_attraction(_model(0.5))
    assert found.code is RegionCode.CERTIFIED and found.radius > 0
    assert found.evidence["replay"]["confirmed"] is True
    refused = region_of_attraction(_model(0.5), budget=Budget(memory=1))
    assert refused.code is RegionCode.NOT_ATTEMPTED and refused.radius == 0.0


def test_a_certified_region_s_words_give_its_method_and_numbers():
    evidence = {
        "ball": 20.0,
        "transitions": 338,
        "dead_zone_radius": 0.1429,
        "replay": {"samples": 64},
    }
    wide = region_messages.lure_region_check(
        Region(10.0, RegionCode.PIECEWISE_CERTIFIED, {}, evidence)
    )
    assert wide.summary.startswith("From every initial estimation error with ||e(0)|| <= 10 ")
    assert "a piecewise-quadratic Lyapunov function over the soft threshold's regions" in (
        wide.summary
    )
    assert "inside the ball of radius 20 and its sublevel set" in wide.summary
    assert "(338 transitions between regions checked; the dead zone alone certifies 0.1429)" in (
        wide.summary
    )
    balanced = {
        "replay": {"samples": 32},
        "state_scaling": [1.0, 2.0**-17],
        "balanced_radius": 10.0,
    }
    region = region_messages.lure_region_check(Region(10.0, RegionCode.CERTIFIED, {}, balanced))
    assert " Proved in balanced coordinates xi = diag(2^0, 2^-17) xi_b (the states' units " in (
        region.summary
    )
    assert "for ||e_b(0)|| <= 10, which holds whenever ||e(0)|| <= 10;" in region.summary
