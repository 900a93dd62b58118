"""observer_stability fails with a replayed divergent trajectory when the large-signal loop of a
sparse observer has an eigenvalue outside the unit circle, and only then; region_of_attraction
certifies the invariant part of the dead zone."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ssecert import analyze, spec_from_dict
from ssecert.examples import load_example
from ssecert.observers import build_observer
from ssecert.observers.lure import LureModel
from ssecert.stability import observer_messages
from ssecert.stability.checks import observer_stability_check
from ssecert.stability.divergence import GROWTH, divergence_witness
from ssecert.stability.equilibria import nonzero_equilibrium
from ssecert.stability.outcomes import SearchCode, WitnessKind
from ssecert.stability.roa import region_of_attraction


def _ugv_dsso(step: float) -> dict:
    spec = load_example("ugv")
    return {
        "name": f"ugv-step-{step}",
        "system": {
            "A": np.asarray(spec.system.A).tolist(),
            "C": np.asarray(spec.system.C).tolist(),
        },
        "attack": {"max_attacked": 1},
        "observer": {"kind": "dsso", "gain": "deadbeat", "step": step, "threshold": 0.1},
    }


def test_a_dsso_with_step_1_5_on_the_ugv_diverges_and_the_witness_replays():
    cert = analyze(spec_from_dict(_ugv_dsso(1.5)))
    check = cert["observer_stability"]
    assert check.verdict.value == "fails"
    w = check.witness
    assert w["kind"] == "divergent trajectory" and w["verified"]
    assert abs(w["large_signal_eigenvalue"].real + 1.5) < 1e-9 and check.margin > 0.49
    # the replay, written out: e+ and a_hat+ of the Lur'e model, from the witness, no attack
    model = LureModel.from_design(build_observer(spec_from_dict(_ugv_dsso(1.5)).system,
                                                 spec_from_dict(_ugv_dsso(1.5)).observer))  # fmt: skip
    xi = np.concatenate([w["initial_error"], w["initial_attack_estimate"]])
    assert not np.any(w["initial_attack_estimate"])  # the observer's own start: a_hat(0) = 0
    for _ in range(w["steps"]):
        v = model.Cw @ xi
        xi = model.A @ xi + model.B @ (model.q * np.sign(v) * np.maximum(np.abs(v) - 0.1, 0))
    assert np.linalg.norm(xi) >= 100 * np.linalg.norm(
        np.concatenate([w["initial_error"], w["initial_attack_estimate"]])
    )
    assert check.witness["growth"] >= 100 and cert.exit_code == 1
    # replayed through the observer's own simulator too, not only its Lur'e model
    replay = check.witness["observer_replay"]
    assert replay["simulator"] == "SparseSoftObserver" and replay["agrees"]
    assert replay["growth"] >= 100


def test_the_thesis_design_is_not_called_divergent():
    # the thesis's own step 0.7: the large-signal loop has spectral radius exactly 1
    check = analyze(load_example("ugv"))["observer_stability"]
    assert check.verdict.value == "inconclusive"


@pytest.mark.slow
@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    step=st.floats(0.05, 2.5),
    threshold=st.floats(0.01, 1.0),
    shrink=st.sampled_from([1.0, 0.9, 0.5]),
)
def test_a_divergence_witness_diverges_and_a_holds_converges(seed, step, threshold, shrink):
    # random small plants and sparse observers: a fails from the divergence search must come with
    # a trajectory that grows; a holds must converge from every sampled initial error
    rng = np.random.default_rng(seed)
    n, p = 2, 3
    A = rng.uniform(-1.2, 1.2, (n, n))
    C = rng.integers(-2, 3, (p, n)).astype(float)
    if np.linalg.matrix_rank(C) < n:
        C[:n] += np.eye(n)
    kind = "elastic_net" if shrink < 1 else "dsso"
    observer = {"kind": kind, "gain": "pinv", "step": step, "threshold": threshold}
    if kind == "elastic_net":
        observer["shrink"] = shrink
    spec = spec_from_dict(
        {"name": "r", "system": {"A": A.tolist(), "C": C.tolist()}, "attack": {"max_attacked": 0},
         "observer": observer}
    )  # fmt: skip
    try:
        design = build_observer(spec.system, spec.observer)
    except Exception:  # a design the spec validation lets through but no gain exists for
        return
    check, _ = observer_stability_check(design)
    model = LureModel.from_design(design)
    if check.verdict.value == "fails" and check.witness.get("kind") == "divergent trajectory":
        w = check.witness
        xi0 = np.concatenate([w["initial_error"], w["initial_attack_estimate"]])
        path = model.simulate(xi0, w["steps"])
        assert np.linalg.norm(path[-1]) >= 10 * np.linalg.norm(xi0)
    if check.verdict.value == "fails" and check.witness.get("kind") == "nonzero equilibrium":
        w = check.witness
        xi0 = np.concatenate([w["initial_error"], w["initial_attack_estimate"]])
        assert np.linalg.norm(xi0) > 0
        after = model.simulate(xi0, 50)[-1]
        assert np.linalg.norm(after - xi0) <= 1e-9 * np.linalg.norm(xi0)
    if check.verdict.value == "holds" and check.method.startswith("Zames-Falb"):
        # the multiplier proves sum_k |xi_k|^2 <= factor |xi_0|^2 (no decreasing V of xi alone)
        starts = rng.standard_normal((20, model.N)) * 10.0 ** rng.uniform(-2, 3, (20, 1))
        path = model.simulate(starts, 20_000)
        sums = (path**2).sum(axis=(0, 2))
        assert np.all(sums <= check.evidence["sum_bound_factor"] * (starts**2).sum(1) * 1.000001)
        assert np.all(np.linalg.norm(path[-1], axis=1) <= 1e-3 * np.linalg.norm(starts, axis=1))
    elif check.verdict.value == "holds":
        # converges: to zero within the steps simulated, or (a weak certificate, slow for large
        # errors) with the certificate's V = xi' P xi decreasing all along and well on its way
        starts = rng.standard_normal((20, model.N)) * 10.0 ** rng.uniform(-2, 3, (20, 1))
        path = model.simulate(starts, 20_000)
        norms = np.linalg.norm(path, axis=2)
        P = np.asarray(check.evidence["P"])
        V = np.einsum("ksi,ij,ksj->ks", path, P, path)
        done = norms[-1] <= 1e-6 * norms[0] + 1e-9
        on_its_way = np.all(np.diff(V, axis=0) <= 1e-12 * V[:-1] + 1e-300, axis=0) & (
            V[-1] <= 0.5 * V[0]
        )
        assert np.all(done | on_its_way)
    region = region_of_attraction(model, seed=seed)
    if region.radius > 0:  # a certified region: errors inside it never leave it
        e0 = rng.standard_normal((20, model.n_e))
        e0 *= region.radius / np.linalg.norm(e0, axis=1, keepdims=True)
        xi0 = np.concatenate([e0, np.zeros((20, model.N - model.n_e))], axis=1)
        path = model.simulate(xi0, 300)
        V = np.einsum("ksi,ij,ksj->ks", path, region.evidence["P"], path)
        assert V.max() <= region.evidence["level"] * (1 + 1e-6)


def test_no_witness_without_an_eigenvalue_outside_the_unit_circle():
    model = LureModel(
        A=np.array([[0.5, -1.0], [0.0, 0.0]]),
        B=np.array([[0.0], [1.0]]),
        Cw=np.array([[0.3, 0.2]]),
        E=np.zeros((2, 1)),
        Dw=np.zeros((1, 1)),
        Ce=np.array([[1.0, 0.0]]),
        q=1.0,
        n_e=1,
        threshold=0.1,
    )
    assert max(abs(np.linalg.eigvals(model.vertex(1.0)))) < 1
    assert divergence_witness(model) is None
    assert GROWTH >= 100


def test_the_ugv_dsso_converges_from_its_certified_region():
    cert = analyze(load_example("ugv"))
    region = cert["region_of_attraction"]
    assert region.verdict.value == "holds" and not region.required
    radius = region.fields["radius"]
    # the piecewise-quadratic function certifies far more than the dead zone (threshold / step)
    assert radius >= 5 and region.evidence["dead_zone_radius"] == pytest.approx(0.1 / 0.7, 1e-3)
    assert "piecewise-quadratic" in region.method
    # the undecided stability check reports the certified region beside it
    stability = cert["observer_stability"]
    assert stability.evidence["certified_region_radius"] == radius
    assert stability.summary.endswith(observer_messages.region_proved_text(radius))
    # independent replay: initial errors inside the radius, a_hat(0) = 0, converge
    spec = load_example("ugv")
    model = LureModel.from_design(build_observer(spec.system, spec.observer))
    rng = np.random.default_rng(7)
    e0 = rng.standard_normal((200, model.n_e))
    e0 *= radius * rng.uniform(0, 1, (200, 1)) / np.linalg.norm(e0, axis=1, keepdims=True)
    xi0 = np.concatenate([e0, np.zeros((200, model.N - model.n_e))], axis=1)
    path = model.simulate(xi0, 1000)  # far from the origin it falls by a constant per step
    assert np.max(np.linalg.norm(path, axis=2)) <= region.evidence["ball"]
    assert np.max(np.linalg.norm(path[-1], axis=1)) <= 1e-9 * radius


def test_no_region_when_the_dead_zone_dynamics_are_unstable():
    spec = _ugv_dsso(0.7)
    spec["observer"]["gain"] = [[2.5, 0.0, 0.0], [0.0, 0.5, 0.5]]  # rho(A - L C) = 1.5
    cert = analyze(spec_from_dict(spec))
    assert cert["region_of_attraction"].verdict.value == "fails"
    assert cert["region_of_attraction"].fields["radius"] == 0.0
    assert cert["observer_stability"].verdict.value == "fails"


def test_a_planted_nonzero_equilibrium_is_found_and_confirmed_exactly():
    # xi+ = xi / 2 + S(xi), threshold 1/10: xi = +-1/5 are fixed points (1/10 + 1/10)
    model = LureModel(
        A=np.array([[0.5]]), B=np.array([[1.0]]), Cw=np.array([[1.0]]), E=np.zeros((1, 1)),
        Dw=np.zeros((1, 1)), Ce=np.array([[1.0]]), q=1.0, n_e=1, threshold=0.1,
    )  # fmt: skip
    witness, searched = nonzero_equilibrium(model)
    assert witness is not None and witness["exact"]
    assert abs(abs(witness["initial_error"][0]) - 0.2) < 1e-15
    assert witness["float_residual"] <= 1e-15 and searched.code is SearchCode.FIRST_FOUND
    assert searched.facts["tried"] <= searched.facts["count"] == 3


def test_the_ugv_search_finds_no_equilibrium_and_says_what_it_searched():
    check = analyze(load_example("ugv"))["observer_stability"]
    searches = check.evidence["searches"]
    assert "none among the 27 active/sign patterns" in searches["nonzero_equilibrium"]
    assert "spectral radius 1" in searches["divergent_trajectory"]


def test_a_dsso_with_a_nonzero_equilibrium_fails_and_its_simulator_stays_there():
    # found by a search over small rational designs: rho(A - L C) = 0.54, the large-signal
    # loop's spectral radius at most 1, and yet a wrong estimate that the observer keeps
    data = {
        "name": "wrong-estimate",
        "system": {"A": [[0.9]], "C": [[-0.2], [1.2]]},
        "attack": {"max_attacked": 0, "horizon": 1},
        "observer": {"kind": "dsso", "gain": [[1.8, 0.9]], "step": 1.1, "threshold": 0.1},
    }
    cert = analyze(spec_from_dict(data))
    check = cert["observer_stability"]
    assert check.verdict.value == "fails" and check.witness["kind"] == "nonzero equilibrium"
    assert check.witness["exact"] and check.witness["observer_replay"]["agrees"]
    # by hand: x_hat = e, a_hat = (0, a2): e = 0.9 e + L (y - C e - a_hat) with y = 0, and
    # a2 = S(a2 + 1.1 (-1.2 e - a2)) with the threshold 0.1
    e, a2 = (
        float(check.witness["initial_error"][0]),
        float(check.witness["initial_attack_estimate"][1]),
    )
    r = np.array([0.2 * e, -1.2 * e - a2])
    assert abs(0.9 * e + np.array([1.8, 0.9]) @ r - e) < 1e-12
    w = a2 + 1.1 * r[1]
    assert abs(np.sign(w) * max(abs(w) - 0.1, 0.0) - a2) < 1e-12


def _lasso_sso(window: int, step: float) -> dict:
    # the Lasso paper's Sec. 5.2 set-up: n = 10, p = 15, s = 3, 5 tau inner ISTA steps
    rng = np.random.default_rng(5)
    A = rng.standard_normal((10, 10))
    A /= np.abs(np.linalg.eigvals(A)).max()
    C = rng.standard_normal((15, 10))
    return {
        "name": "lasso-sso",
        "system": {"A": A.tolist(), "C": C.tolist()},
        "attack": {"max_attacked": 3, "horizon": 1},
        "observer": {
            "kind": "sso",
            "step": step,
            "threshold": 0.001,
            "window": window,
            "inner_steps": 5 * window,
        },
    }


@pytest.mark.slow
def test_an_sso_with_inner_steps_gets_the_radius_its_dead_zone_proves():
    cert = analyze(spec_from_dict(_lasso_sso(1, 0.01)))
    assert cert["observer_stability"].verdict.value == "inconclusive"
    region = cert["region_of_attraction"]
    assert region.verdict.value == "holds" and region.value > 0
    replay = region.evidence["replay"]
    assert replay["simulator"] == "WindowSSO" and replay["confirmed"]
    assert replay["largest_attack_estimate"] == 0.0
    stability = cert["observer_stability"]
    assert stability.evidence["certified_region_radius"] == region.value
    assert stability.summary.endswith(observer_messages.region_proved_text(region.value))


@pytest.mark.slow
def test_the_lasso_papers_sso_with_tau_n_gets_a_region_and_a_local_noise_bound():
    # tau = n = 10, 50 inner steps, the paper's step 1 / ||[O I]||^2 and threshold step *
    # 0.1: the inner steps' exact matrices are beyond their budget, so the dead zone's region
    # rests on the floats and the model's a-priori rounding; under noise 1e-4 on every sample
    # the error stays within the local bound, through the observer's own simulator
    data = _lasso_sso(10, 1.0)
    A, C = np.array(data["system"]["A"]), np.array(data["system"]["C"])
    O = np.vstack([C @ np.linalg.matrix_power(A, k) for k in range(10)])
    step = 1.0 / np.linalg.norm(np.hstack([O, np.eye(O.shape[0])]), 2) ** 2
    data["observer"].update(step=step, threshold=0.1 * step)
    data["noise"] = {"measurement": 1e-4}
    spec = spec_from_dict(data)
    cert = analyze(spec)
    region, local = cert["region_of_attraction"], cert["observer_noise_bound"]
    assert region.verdict.value == "holds" and region.value > 0
    assert isinstance(region.evidence["exact_recheck"], str)  # (not run: floats only)
    assert local.verdict.value == "holds" and local.evidence["from"] == "dead zone"
    assert 0 < local.fields["region_radius"] <= region.value
    design = build_observer(spec.system, spec.observer)
    model = design.observer_kind.dead_zone_model(design, noise=True)
    assert model.exact() is None and 0 < model.rounding < 1e-6
    simulator = design.observer_kind.simulator(design)
    rng = np.random.default_rng(6)
    runs, steps = 16, 60
    e0 = rng.standard_normal((runs, 10))
    e0 *= local.fields["region_radius"] / np.linalg.norm(e0, axis=1, keepdims=True)
    noise = rng.choice([-1e-4, 1e-4], (steps, runs, 15))
    path = simulator.run(noise, state={**simulator.initial_state(runs), "x_hat": e0})
    assert not np.any(path.a_hat)  # the attack estimate stays 0: inside the dead zone
    assert np.max(np.linalg.norm(path.x_hat[-10:], axis=-1)) <= local.value


def test_an_sso_whose_gradient_step_is_too_long_fails_near_the_origin():
    # step 0.01 against ||O' O|| ~ 1500 for tau = 10: each inner step expands the error
    cert = analyze(spec_from_dict(_lasso_sso(10, 0.01)))
    stability = cert["observer_stability"]
    # decided by the dead zone's linear map e+ = A (I - step S' S)^m e, proved unstable
    assert stability.verdict.value == "fails" and stability.code is WitnessKind.LOCAL_INSTABILITY
    assert cert["region_of_attraction"].verdict.value == "fails"


@pytest.mark.parametrize(
    ("A", "C", "observer", "period"),
    [
        ([[-0.9]], [[-1.7], [1.1]], {"kind": "dsso", "gain": [[-0.9, -1.4]], "step": 0.4}, 2),
        (
            [[-1.0]],
            [[-2.0], [0.5]],
            {"kind": "elastic_net", "gain": [[0.8, 1.6]], "step": 1.0, "shrink": 0.9},
            4,
        ),
    ],
)
def test_a_design_that_cycles_fails_with_its_exact_periodic_orbit(A, C, observer, period):
    # found by a search over small rational designs: rho(A - L C) < 0.95, no divergent
    # direction, no nonzero equilibrium, and yet the error never settles
    data = {
        "name": "cycles",
        "system": {"A": A, "C": C},
        "attack": {"max_attacked": 0, "horizon": 1},
        "observer": {**observer, "threshold": 0.1},
    }
    spec = spec_from_dict(data)
    check = analyze(spec)["observer_stability"]
    assert check.verdict.value == "fails" and check.witness["kind"] == "periodic orbit"
    assert check.witness["period"] == period and check.witness["exact"]
    assert check.witness["observer_replay"]["agrees"]
    # independently: the observer's own simulator, started on the orbit, keeps cycling
    from ssecert.observers import observer_from_design

    sim = observer_from_design(build_observer(spec.system, spec.observer))
    e0 = np.asarray(check.witness["initial_error"])[None]
    a0 = np.asarray(check.witness["initial_attack_estimate"])[None]
    traj = sim.run(np.zeros((100 * period, 1, 2)), state={"x_hat": e0, "a_hat": a0})
    assert np.allclose(traj.x_hat[-1], e0, atol=1e-9)
    moved = np.concatenate([traj.x_hat[1, 0], traj.a_hat[1, 0]]) - np.concatenate([e0[0], a0[0]])
    assert np.linalg.norm(moved) > 1e-6  # an orbit, not an equilibrium
