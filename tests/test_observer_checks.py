"""analyze with an [observer] section: ids, required/advisory, every kind."""

import json

import numpy as np
import pytest

from ssecert import analyze, spec_from_dict
from ssecert.cli import main

PLANT = {"A": [[0.9, 0.2], [0.0, 0.7]], "C": [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]}


def spec_with(observer):
    return spec_from_dict(
        {"name": "demo", "system": PLANT, "attack": {"max_attacked": 0}, "observer": observer}
    )


@pytest.mark.parametrize(
    "observer, stability",
    [
        ({"kind": "luenberger", "gain": "place", "poles": [0.1, 0.2]}, "holds"),
        ({"kind": "luenberger", "gain": "deadbeat"}, "holds"),
        ({"kind": "ogd", "step": 0.2}, "holds"),
        ({"kind": "dsso", "gain": "pinv", "step": 0.1, "threshold": 0.1}, "holds"),
        ({"kind": "sso", "step": 0.2, "threshold": 0.1}, "holds"),
        ({"kind": "sso", "step": 0.2, "threshold": 0.1, "window": 2}, None),
        ({"kind": "sso", "step": 0.2, "threshold": 0.1, "inner_steps": 3}, "inconclusive"),
        (
            {
                "kind": "elastic_net",
                "gain": "deadbeat",
                "step": 0.05,
                "threshold": 0.1,
                "shrink": 0.5,
            },
            "holds",
        ),
    ],
)
@pytest.mark.slow
def test_every_kind_gets_its_checks(observer, stability):
    cert = analyze(spec_with(observer))
    ids = [c.id for c in cert.checks]
    assert ids[:5] == [
        "observability",
        "sparse_observability",
        "irrepresentable",
        "observer_gain",
        "observer_stability",
    ]
    assert "iss_gain" in ids
    assert ("thesis_assumptions" in ids) == (observer["kind"] in ("sso", "dsso", "elastic_net"))
    assert cert["observer_gain"].required and cert["observer_stability"].required
    assert not cert["iss_gain"].required
    if stability is not None:
        assert cert["observer_stability"].verdict.value == stability
    json.dumps(cert.to_dict(), allow_nan=False)


def test_unstable_gain_fails_the_required_checks():
    cert = analyze(spec_with({"kind": "luenberger", "gain": [[-1.0, 0.0, 0.0], [0.0, 0.0, 0.0]]}))
    assert cert["observer_gain"].verdict.value == "fails"
    assert cert.exit_code == 1


def test_ugv_cli_reports_observer_checks(capsys):
    code = main(["analyze", "ugv", "--json", "-"])
    data = json.loads(capsys.readouterr().out)
    assert code == 1
    checks = data["checks"]
    assert checks["observer_gain"]["verdict"] == "holds"
    assert checks["observer_gain"]["nilpotency_index"] == 1
    assert np.array(checks["observer_gain"]["L"]).shape == (2, 3)
    assert checks["observer_stability"]["verdict"] == "inconclusive"
    assert checks["observer_stability"]["shrink"] == 1
    assert checks["thesis_assumptions"]["items"]["lemma_1"] == "fails"
    assert checks["iss_gain"]["required"] is False


def test_ugv_stability_is_undecided_because_its_sector_contains_the_identity():
    # shrink = 1: no circle certificate can exist, which the check says by its cause
    from ssecert.examples import load_example
    from ssecert.observers import build_observer
    from ssecert.stability.checks import observer_stability_check
    from ssecert.stability.outcomes import LMICause

    spec = load_example("ugv")
    check, _ = observer_stability_check(build_observer(spec.system, spec.observer))
    assert check.verdict.value == "inconclusive" and check.fields["shrink"] == 1
    assert check.code is LMICause.IDENTITY_IN_SECTOR


def test_the_region_check_reads_a_flag_not_a_sentence(monkeypatch):
    """An unstable dead zone fails the region check because ``region_of_attraction``'s code says
    so; the same words under another code leave it inconclusive."""
    from ssecert.observers import build_observer
    from ssecert.stability import checks
    from ssecert.stability.checks import region_of_attraction_check
    from ssecert.stability.outcomes import Region, RegionCode
    from ssecert.system import System

    system = System(np.array([[1.5]]), np.array([[1.0], [1.0], [1.0]]))
    design = build_observer(
        system,
        {"kind": "elastic_net", "gain": [[0.0, 0.0, 0.0]], "step": 0.5, "threshold": 0.1,
         "shrink": 0.5},
    )  # fmt: skip
    check = region_of_attraction_check(design)
    assert check.verdict.value == "fails" and check.evidence["unstable"] is True
    # the same words under another code: undecided
    reworded = Region.none(RegionCode.NO_VERIFIED_LYAPUNOV, lyapunov="it is not stable")
    monkeypatch.setattr(checks, "region_of_attraction", lambda *a, **k: reworded)
    check = region_of_attraction_check(design)
    assert check.verdict.value == "inconclusive" and check.code is RegionCode.NO_VERIFIED_LYAPUNOV
