"""The piecewise-quadratic region of attraction (ssecert.stability.piecewise) and the small
LMI layer under it (ssecert.stability._conic)."""

from __future__ import annotations

from dataclasses import replace
from fractions import Fraction
from functools import partial

import numpy as np
import pytest

from ssecert import spec_from_dict
from ssecert.examples import load_example
from ssecert.observers import build_observer
from ssecert.observers.lure import LureModel
from ssecert.stability import piecewise as pw
from ssecert.stability._conic import LMIProblem
from ssecert.stability.checks import region_of_attraction_check
from ssecert.stability.divergence import divergence_witness
from ssecert.stability.outcomes import RegionCode


def _ugv_model(step: float) -> LureModel:
    spec = load_example("ugv")
    observer = {**spec.observer, "step": step}
    return LureModel.from_design(build_observer(spec.system, observer))


def test_the_lmi_layer_uses_clarabels_triangle_convention():
    # X >= C and -X >= -C force X = C: a wrong scaling of the off-diagonal entries shows
    rng = np.random.default_rng(0)
    R = rng.standard_normal((4, 4))
    C = R @ R.T
    lp = LMIProblem()
    X = lp.block(4)
    lp.lmi(-C, [(X, np.eye(4), 1.0)])
    lp.lmi(C, [(X, np.eye(4), -1.0)])
    x, info = lp.solve()
    assert x is not None, info
    np.testing.assert_allclose(lp.matrix(x, X), C, atol=1e-6)


def test_the_lmi_layer_finds_a_lyapunov_matrix():
    A = np.array([[0.5, 2.0, 0.0], [0.0, 0.3, 1.0], [0.0, 0.0, -0.6]])
    lp = LMIProblem()
    P = lp.block(3)
    lp.lmi(-np.eye(3), [(P, np.eye(3), 1.0), (P, A, -1.0)])  # P - A' P A >= I
    x, _ = lp.solve()
    Pv = lp.matrix(x, P)
    assert np.linalg.eigvalsh(Pv - A.T @ Pv @ A)[0] >= 1 - 1e-6


def test_a_masked_nonnegative_block_has_only_its_entries():
    mask = np.zeros((3, 3), bool)
    mask[2, :] = mask[:, 2] = True
    lp = LMIProblem()
    W = lp.block(3, nonneg=True, mask=mask)
    lp.lmi(-np.ones((1, 1)), [(W, np.array([[0.0], [0.0], [1.0]]), 1.0)])  # W_33 >= 1
    x, _ = lp.solve()
    Wv = lp.matrix(x, W)
    assert Wv[2, 2] >= 1 - 1e-7 and Wv[0, 0] == Wv[0, 1] == Wv[1, 1] == 0.0
    assert len(x) == 3


def test_mirror_regions_are_the_same_lmis_conjugated():
    model = _ugv_model(0.7)
    regions = pw._Regions(model)
    J = np.diag(np.r_[-np.ones(model.N), 1.0])
    for k in range(len(regions.signs)):
        mirror = regions.mirror(k)
        np.testing.assert_array_equal(regions.T[mirror], J @ regions.T[k] @ J)
        rows = {tuple(r) for r in regions.G[k] @ J}
        assert rows == {tuple(r) for r in regions.G[mirror]}


def test_emptiness_certificates_are_exact_and_respect_the_box():
    # x >= 2 and x <= 1: empty anywhere
    H = np.array([[1.0, -2.0], [-1.0, 1.0]])
    assert pw._empty_in_box(H, 100.0) is not None
    # x >= 5: empty in the box |x| <= 3, not in |x| <= 10
    H = np.array([[1.0, -5.0]])
    assert pw._empty_in_box(H, 3.0) is not None
    assert pw._empty_in_box(H, 10.0) is None
    # 0 <= x <= 1 is not empty
    assert pw._empty_in_box(np.array([[1.0, 0.0], [-1.0, 1.0]]), 10.0) is None


def test_emptiness_of_many_sets_in_one_program_is_decided_set_by_set():
    # the sets of the test above in one linear program, each with its own box, beside a
    # two-dimensional set empty only in the small box (x >= 4, y >= 4): each answer is the
    # one of the set alone, and each certificate holds for its own set
    cases = [
        (np.array([[1.0, -2.0], [-1.0, 1.0]]), 100.0, True),
        (np.array([[1.0, -5.0]]), 3.0, True),
        (np.array([[1.0, -5.0]]), 10.0, False),
        (np.array([[1.0, 0.0], [-1.0, 1.0]]), 10.0, False),
        (np.array([[1.0, 0.0, -4.0], [0.0, 1.0, -4.0]]), 3.0, True),
        (np.array([[1.0, 0.0, -4.0], [0.0, 1.0, -4.0]]), 5.0, False),
    ]
    found = pw._empty_in_boxes([(H, box, None) for H, box, _ in cases])
    assert [y is not None for y in found] == [empty for *_, empty in cases]
    for (H, box, _), y in zip(cases, found, strict=True):
        assert (y is None) == (pw._empty_in_box(H, box) is None)
        if y is not None:  # y >= 0 and y' h + box ||H_x' y||_1 < 0, in exact arithmetic
            assert min(y) >= 0
            combo = [
                sum(yi * Fraction(float(v)) for yi, v in zip(y, col, strict=True)) for col in H.T
            ]
            assert combo[-1] + Fraction(box) * sum(abs(v) for v in combo[:-1]) < 0


@pytest.mark.slow
def test_the_ugv_dsso_region_is_far_larger_than_its_dead_zone():
    model = _ugv_model(0.7)
    found = pw.piecewise_region(model, floor=0.1429)
    assert found.code is RegionCode.PIECEWISE_CERTIFIED
    evidence = found.evidence
    assert found.radius >= 5.0 and evidence["ball"] == pytest.approx(2 * found.radius)
    assert evidence["replay"]["confirmed"] and evidence["margin"] > 100 * evidence["error_bound"]
    assert all("seconds" in a for a in evidence["attempts"])
    # independent: errors inside the radius stay in the ball and converge
    rng = np.random.default_rng(3)
    e0 = rng.standard_normal((100, model.n_e))
    e0 *= found.radius * rng.uniform(0.5, 1, (100, 1)) / np.linalg.norm(e0, axis=1)[:, None]
    xi0 = np.concatenate([e0, np.zeros((100, model.N - model.n_e))], axis=1)
    path = model.simulate(xi0, 2000)
    assert np.linalg.norm(path, axis=2).max() <= evidence["ball"]
    assert np.linalg.norm(path[-1], axis=1).max() <= 1e-9


@pytest.mark.slow
def test_the_verification_rejects_a_tampered_function():
    model = _ugv_model(0.7)
    regions = pw._Regions(model)
    unit = replace(model, threshold=1.0)
    empty = pw._empty_pairs(regions, unit, 20.0)
    found = pw._attempt(model, regions, 3.0, 6.0, 100.0, empty, set())
    assert found.ok
    functions = [P.copy() for P in found.functions]
    ok = pw._verify(model, regions, functions, found.lmis, 3.0, 6.0, 100.0)
    assert ok[2] == ""
    active = next(k for k in range(len(functions)) if k != regions.zero)
    functions[active][-1, -1] += 50.0  # a region's function raised: some decrease breaks
    bad = pw._verify(model, regions, functions, found.lmis, 3.0, 6.0, 100.0)
    assert bad[2] and bad[0] < 0


@pytest.mark.slow
def test_a_divergent_design_gets_no_region_beyond_its_divergence():
    model = _ugv_model(1.5)
    witness = divergence_witness(model)
    assert witness is not None
    found = pw.piecewise_region(model)
    assert found.radius < np.linalg.norm(witness["initial_error"])


def test_out_of_reach_models_are_refused_with_the_reason():
    spec = load_example("random-n15-p30")
    data = {
        "name": "big",
        "system": {"A": spec.system.A.tolist(), "C": spec.system.C.tolist()},
        "attack": {"max_attacked": 1, "horizon": 15},
        "observer": {"kind": "dsso", "step": 0.5, "threshold": 0.1},
    }
    design = build_observer(spec.system, spec_from_dict(data).observer)
    found = pw.piecewise_region(LureModel.from_design(design))
    assert found.radius == 0.0 and found.code is RegionCode.NOT_ATTEMPTED
    assert found.facts["channels"] > pw.MAX_CHANNELS


def test_the_check_reports_the_piecewise_region_only_when_asked():
    spec = load_example("ugv")
    design = build_observer(spec.system, spec.observer)
    plain = region_of_attraction_check(design)
    wide = region_of_attraction_check(design, piecewise=True)
    assert plain.value == pytest.approx(0.1429, abs=1e-4)
    assert wide.value >= 5 and wide.verdict.value == "holds"
    assert plain.code is RegionCode.CERTIFIED and wide.code is RegionCode.PIECEWISE_CERTIFIED
    assert wide.evidence["ball"] >= wide.value and wide.evidence["dead_zone_radius"] == plain.value


@pytest.mark.slow
def test_the_verification_requires_the_dead_zone_decrease():
    model = _ugv_model(0.7)
    regions = pw._Regions(model)
    empty = pw._empty_pairs(regions, replace(model, threshold=1.0), 20.0)
    found = pw._attempt(model, regions, 3.0, 6.0, 100.0, empty, set())
    functions = [P.copy() for P in found.functions]
    N = model.N
    functions[regions.zero][:N, :N] = np.eye(N)  # V = |xi|^2 does not decrease along A
    bad = pw._verify(model, regions, functions, found.lmis, 3.0, 6.0, 100.0)
    assert bad[2].startswith("the dead zone's decrease")


@pytest.mark.parametrize("change", [{"threshold": 1e200}, {"step": 1e300}])
def test_numbers_out_of_range_end_inconclusive_not_in_an_error(change):
    spec = load_example("ugv")
    data = {
        "name": "huge",
        "system": {"A": spec.system.A.tolist(), "C": spec.system.C.tolist()},
        "attack": {"max_attacked": 1, "horizon": 2},
        "observer": {**spec.observer, **change},
    }
    from ssecert import analyze

    cert = analyze(spec_from_dict(data))
    assert cert["region_of_attraction"].verdict.value == "inconclusive"


def test_the_replay_goes_on_while_a_slow_trajectory_stays_inside(monkeypatch):
    """A certified design that converges slowly is not refused for want of steps: the replay
    continues chunk by chunk (here chunks of 20 steps) until it converges inside the ball."""
    spec = load_example("ugv")
    model = LureModel.from_design(build_observer(spec.system, spec.observer))
    monkeypatch.setattr(pw, "STEPS", 20)
    replay = pw._replay(model, 50.0, 1e6, seed=0)
    assert replay["confirmed"] and 20 < replay["steps"] <= pw.MAX_STEPS
    assert replay["final_largest_norm"] <= 1e-6
    monkeypatch.setattr(pw, "MAX_STEPS", 40)  # not converged by then: not confirmed
    assert not pw._replay(model, 50.0, 1e6, seed=0)["confirmed"]
    assert not pw._replay(model, 50.0, 20.0, seed=0)["confirmed"]  # it leaves a smaller ball


def test_exact_combinations_are_those_of_the_exact_rows():
    # y' [G_k; G_j T_k] formed as y_1' G_k + (y_2' G_j) T_k equals y' times the rows formed
    # exactly, and those rows are the floats' (the model's rounding apart)
    from ssecert.numerics.rational import product

    model = _ugv_model(0.7)
    regions = pw._Regions(model)
    unit = replace(model, threshold=1.0)
    rng = np.random.default_rng(0)
    for k, j in [(0, 0), (4, 13), (13, 26), (1, 24)]:
        Gk, Gj = regions._exact_G(unit, k), regions._exact_G(unit, j)
        T = regions._exact_T(unit, k)
        rows = Gk + product(Gj, T)
        floats = np.vstack([regions.G[k], regions.G[j] @ regions.T[k]])
        np.testing.assert_allclose(np.array(rows, dtype=float), floats, rtol=1e-12, atol=1e-12)
        y = [Fraction(int(v), 7) for v in rng.integers(0, 9, len(rows))]
        expected = [
            sum(a * row[c] for a, row in zip(y, rows, strict=True)) for c in range(len(rows[0]))
        ]
        assert regions.exact_combination(unit, k, j, y) == expected
        inner = [row[: model.n_e] + [row[model.N]] for row in Gk]
        z = y[: len(Gk)]
        assert regions.exact_inner_combination(unit, k, z) == [
            sum(a * row[c] for a, row in zip(z, inner, strict=True)) for c in range(len(inner[0]))
        ]


@pytest.mark.slow
def test_badly_scaled_transitions_are_proved_empty_as_one_program_each_would():
    # sensors of 6e4 and 6: entries of H up to 1.7e13, where the one program for every
    # transition fails in HiGHS; the transitions are then proved one program each, and
    # every certificate holds exactly
    spec = spec_from_dict(
        {
            "name": "scaled",
            "system": {
                "A": [[-0.942, -0.877], [0.271, 0.25]],
                "C": [[24000.0, -57999.99999999999], [-5.84, -6.2], [-6280.0, -3730.0]],
            },
            "attack": {"max_attacked": 1, "horizon": 2},
            "observer": {"kind": "sso", "step": 0.5, "threshold": 0.1},
        }
    )
    model = LureModel.from_design(build_observer(spec.system, spec.observer))
    regions = pw._Regions(model)
    unit = replace(model, threshold=1.0)
    box = 20.0
    empty = pw._empty_pairs(regions, unit, box)
    seen = pw._sampled_pairs(unit, regions, box)
    candidates = [
        (k, j)
        for k in regions.representatives()
        for j in range(len(regions.signs))
        if not (k == regions.zero and j == regions.zero) and (k, j) not in seen
    ]
    alone = set()
    for k, j in candidates:
        H = np.vstack([regions.G[k], regions.G[j] @ regions.T[k]])
        y = pw._empty_in_boxes([(H, box, partial(regions.exact_combination, unit, k, j))])[0]
        if y is not None:
            alone.add((k, j))
            combo = regions.exact_combination(unit, k, j, y)
            assert min(y) >= 0 and combo[-1] + Fraction(box) * sum(abs(v) for v in combo[:-1]) < 0
    assert len(alone) > 50 and set(empty) == alone
