"""LMI certificates: confirmed by simulation, re-verified without the solver, honest failures."""

import json
from dataclasses import replace

import numpy as np
import pytest

from ssecert import System
from ssecert.examples import load_example
from ssecert.observers import build_observer
from ssecert.stability import lmi
from ssecert.stability.checks import observer_checks
from ssecert.stability.lmi import (
    LureModel,
    circle_certificate,
    circle_matrix,
    iss_certificate,
    iss_from_circle,
    verify_certificate,
)
from ssecert.stability.outcomes import LMICause
from ssecert.stability.region import region_map


def random_design(seed, *, shrink=None, step=None):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 5))
    p = int(rng.integers(n, n + 4))
    A = rng.standard_normal((n, n))
    A = A / np.abs(np.linalg.eigvals(A)).max()  # spectral radius 1, as in the thesis
    C = rng.standard_normal((p, n))
    q = float(rng.uniform(0.2, 0.7)) if shrink is None else shrink
    nu = float(rng.uniform(0.005, 0.05)) if step is None else step
    return build_observer(
        System(A, C),
        {"kind": "elastic_net", "gain": "deadbeat", "step": nu, "threshold": 0.1, "shrink": q},
    )


@pytest.mark.parametrize("seed", range(12))
def test_elastic_net_certificates_hold_along_simulated_trajectories(seed):
    design = random_design(seed)
    model = LureModel.from_design(design)
    cert = circle_certificate(model)
    assert cert.verdict == "holds"
    rng = np.random.default_rng(100 + seed)
    mags = np.exp(rng.uniform(np.log(1e-3), np.log(1e2), (300, 1)))
    xi0 = rng.standard_normal((300, model.N)) * mags
    traj = model.simulate(xi0, 200)
    V = np.einsum("kri,ij,krj->kr", traj, cert.P, traj)
    # the certified decrease holds at every step of every trajectory
    assert np.all(V[1:] <= (1 - cert.decay) * V[:-1] * (1 + 1e-9) + 1e-300)
    assert np.all(
        np.linalg.norm(traj[-1], axis=1) <= 1e-6 * np.maximum(np.linalg.norm(xi0, axis=1), 1)
    )


@pytest.mark.parametrize("kind", ["sso", "dsso"])
def test_sso_and_dsso_on_the_ugv_are_inconclusive_with_the_reason(kind):
    spec = load_example("ugv")
    obs = {"kind": kind, "step": 0.7, "threshold": 0.1}
    if kind == "dsso":
        obs["gain"] = "deadbeat"
    design = build_observer(spec.system, obs)
    model = LureModel.from_design(design)
    cert = circle_certificate(model)
    assert cert.verdict == "inconclusive" and cert.cause is LMICause.IDENTITY_IN_SECTOR
    assert cert.facts["radius"] == cert.details["spectral_radius_at_sector_vertex"] >= 1 - 1e-9
    # the mode e = v, a_hat = -C v (v the eigenvector of A at 1) is an eigenvector at 1
    v = np.array([1.0, 0.0])
    mode = np.concatenate([v, -spec.system.C @ v])
    np.testing.assert_allclose(model.vertex(1.0) @ mode, mode, atol=1e-12)


@pytest.mark.parametrize("seed", range(8))
def test_unstable_linear_error_matrix_is_never_certified(seed):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((3, 3))
    C = rng.standard_normal((4, 3))
    L = 0.1 * rng.standard_normal((3, 4))
    if np.abs(np.linalg.eigvals(A - L @ C)).max() < 1.05:
        L = np.zeros((3, 4))
        A = A / np.abs(np.linalg.eigvals(A)).max() * 1.2
    design = build_observer(
        System(A, C),
        {"kind": "elastic_net", "gain": L, "step": 0.01, "threshold": 0.1, "shrink": 0.3},
    )
    model = LureModel.from_design(design)
    cert = circle_certificate(model)
    assert cert.verdict == "fails" and cert.cause is LMICause.ERROR_MATRIX_UNSTABLE
    witness = cert.details["witness"]
    # the dead zone keeps a_hat at 0 near the origin, so a small error grows like F^k
    xi0 = np.concatenate([1e-6 * witness["initial_error"], np.zeros(model.m)])
    traj = model.simulate(xi0, 40)
    assert np.linalg.norm(traj[-1]) > 10 * np.linalg.norm(xi0)


def test_evidence_reverifies_without_the_solver():
    spec = load_example("ugv")
    checks = observer_checks(
        spec.system,
        {"kind": "elastic_net", "gain": "deadbeat", "step": 0.1, "threshold": 0.1, "shrink": 0.5},
    )
    stability = json.loads(
        json.dumps(next(c for c in checks if c.id == "observer_stability").to_dict())
    )
    assert stability["verdict"] == "holds"
    ev = stability["evidence"]
    mo = ev["model"]
    model = LureModel(
        *(np.array(mo[k], dtype=float) for k in ("A", "B", "Cw", "E", "Dw", "Ce")),
        mo["q"],
        mo["n_e"],
        mo["threshold"],
    )
    P, t = np.array(ev["P"]), np.array(ev["multipliers_T"])
    M = circle_matrix(model, P, t)
    assert np.linalg.eigvalsh(M)[-1] < -50 * ev["error_bound"] * np.linalg.norm(P, 2)
    assert np.linalg.eigvalsh(P)[0] > 0 and np.all(t >= 0)
    ok, margin, bound, _ = verify_certificate(model, P, t)
    assert ok and margin == pytest.approx(stability["margin"], rel=1e-6)


def test_iss_gain_bounds_simulated_attacks():
    design = random_design(3, shrink=0.4, step=0.02)
    model = LureModel.from_design(design)
    circle = circle_certificate(model)
    for cert in (iss_certificate(model, alpha=circle.decay / 2), iss_from_circle(model, circle)):
        assert cert.verdict == "holds"
        rng = np.random.default_rng(0)
        attacks = rng.uniform(-5, 5, (300, 50, model.r)) * (rng.random((1, 50, model.r)) < 0.3)
        traj = model.simulate(np.zeros((50, model.N)), 300, attack=attacks)
        e = traj[:-1, :, : model.n_e]
        energy_e = np.sum(e**2, axis=(0, 2))
        energy_a = np.sum(attacks**2, axis=(0, 2))
        assert np.all(energy_e <= cert.gamma**2 * energy_a * (1 + 1e-9))


def test_the_gain_lmi_s_rounding_bound_counts_the_gain():
    # the dissipation LMI subtracts g on the attack's block: its entries there round by
    # eps g, which a margin relative to ||P|| must beat whatever ||P|| is
    model = LureModel.linear(np.array([[0.5]]), np.array([[1.0]]))
    P, t = np.eye(1), np.zeros(0)
    small = verify_certificate(model, P, t, kind="iss", g=10.0)[2]
    large = verify_certificate(model, P, t, kind="iss", g=1e12)[2]
    assert large >= 1e12 * np.finfo(float).eps > 100 * small


def test_linear_observer_iss_gain():
    F = np.array([[0.5, 0.2], [0.0, 0.3]])
    L = np.array([[1.0], [0.5]])
    cert = iss_certificate(LureModel.linear(F, L))
    assert cert.verdict == "holds"
    # the l2 gain of e+ = F e + L a is at least the peak of |(zI - F)^-1 L| on the circle
    z = np.exp(1j * np.linspace(0, np.pi, 400))
    peak = max(np.linalg.norm(np.linalg.solve(zz * np.eye(2) - F, L)) for zz in z)
    assert peak <= cert.gamma <= 1.05 * peak + 1e-3


@pytest.mark.parametrize("exponent", [-12, 0, 12])
def test_a_linear_observer_iss_gain_in_any_units_of_the_attack(exponent):
    """The LMI's margin is imposed on every block: without the attack in units near the
    input's, gamma^2 could not go below it (a gain of 4e-4 read as 1e-2); the gain of the
    same loop with its attack in units 2^exponent apart is that gain times 2^-exponent,
    within the certificates' slack, and stays above the frequency response's peak."""
    F = np.array([[0.5, 0.2], [0.0, 0.3]])
    L = np.array([[1.0], [0.5]]) * 2.0**-exponent
    cert = iss_certificate(LureModel.linear(F, L))
    assert cert.verdict == "holds"
    z = np.exp(1j * np.linspace(0, np.pi, 400))
    peak = max(np.linalg.norm(np.linalg.solve(zz * np.eye(2) - F, L)) for zz in z)
    assert peak <= cert.gamma <= 1.05 * peak
    assert ("input_scaling" in cert.details["attempts"][0]) == (exponent != 0)


@pytest.mark.parametrize("exponent", [-12, 10])
def test_sensors_in_far_units_get_the_same_certificates(exponent):
    """The UGV's elastic net with its sensors in units 2^exponent apart (C times 2^exponent,
    the gain divided by it): the soft threshold's sector does not change, so the certified
    decay is of the same order and the l2 gain is 2^-exponent times (C times 1e3 read a
    decay 8,500 times smaller and a gain 380 times larger, the LMIs solved in the user's
    units)."""
    system = load_example("ugv").system
    params = {"kind": "elastic_net", "step": 0.7, "threshold": 0.1, "shrink": 0.5}
    base = build_observer(system, {**params, "gain": "deadbeat"})
    units = 2.0**exponent
    far = build_observer(
        System(system.A, system.C * units),
        {**params, "gain": (np.asarray(base.L) / units).tolist()},
    )
    model, scaled = LureModel.from_design(base), LureModel.from_design(far)
    circle, circle_far = circle_certificate(model), circle_certificate(scaled)
    assert circle.verdict == circle_far.verdict == "holds"
    assert circle_far.decay > 0.25 * circle.decay
    iss, iss_far = iss_certificate(model), iss_certificate(scaled)
    assert iss.verdict == iss_far.verdict == "holds"
    assert iss_far.gamma * units == pytest.approx(iss.gamma, rel=0.1)
    # solved in units 2^-j of the sensors (sensor_exponent), verified there, written back
    assert iss_far.details["sensor_exponent"] == lmi.sensor_units(scaled).exponent != 0
    assert lmi.sensor_units(model) is None
    # the gain from the circle certificate, computed where it was verified, in user units
    carried = iss_from_circle(scaled, circle_far)
    assert carried.verdict == "holds" and carried.gamma * units == pytest.approx(
        iss_from_circle(model, circle).gamma, rel=0.5
    )


def test_sensors_in_units_far_from_each_other_get_the_same_decay():
    """An elastic net whose six sensors are in units 2^10, 1 and 2^-10 apart (C's rows times
    them, the gain's columns divided by them): each channel is solved in units of its own
    (the multipliers are diagonal, the soft threshold homogeneous), so the certified decay
    is of the order of the balanced sensors' (one unit for all read 1.5e-9 for 0.04); the
    certificate verifies where it was solved and is written back exactly."""
    rng = np.random.default_rng(3)
    A, C = np.diag([0.5, 0.6, 0.7, 0.8]), rng.standard_normal((6, 4)).round(2)
    params = {"kind": "elastic_net", "step": 0.5, "threshold": 0.1, "shrink": 0.5}
    base = build_observer(System(A, C), {**params, "gain": "place", "poles": [0.3, 0.3, 0.4, 0.4]})
    d = 2.0 ** np.array([10, 10, 0, 0, -10, -10])
    far = build_observer(
        System(A, C * d[:, None]), {**params, "gain": (np.asarray(base.L) / d).tolist()}
    )
    model, mixed = LureModel.from_design(base), LureModel.from_design(far)
    circle, circle_mixed = circle_certificate(model), circle_certificate(mixed)
    assert circle.verdict == circle_mixed.verdict == "holds"
    assert circle_mixed.decay > 0.25 * circle.decay
    exponents = circle_mixed.details["channel_exponents"]
    assert max(exponents) - min(exponents) >= 20
    assert exponents == lmi.sensor_units(mixed).channels.tolist()
    assert lmi.sensor_units(mixed, channels=False).channels is None
    seen = {}

    def inside(scaled, cert):
        seen["verified"] = verify_certificate(scaled, cert.P, cert.multipliers)[0]
        return cert

    back = lmi.where_verified(mixed, circle_mixed, inside)
    assert seen["verified"]
    assert np.array_equal(back.P, circle_mixed.P)
    assert np.array_equal(back.multipliers, circle_mixed.multipliers)
    iss = iss_certificate(mixed)
    assert iss.verdict == "holds" and "channel_exponents" not in iss.details


def test_solver_failure_is_inconclusive(monkeypatch):
    import cvxpy

    def broken(self, *args, **kwargs):
        raise cvxpy.error.SolverError("simulated failure")

    monkeypatch.setattr(cvxpy.Problem, "solve", broken)
    cert = circle_certificate(LureModel.from_design(random_design(1)))
    assert cert.verdict == "inconclusive" and cert.cause is LMICause.CIRCLE_NOT_VERIFIED
    assert all("simulated failure" in a["status"] for a in cert.facts["attempts"])


def test_unverifiable_solution_is_inconclusive(monkeypatch):
    design = random_design(2)
    model = LureModel.from_design(design)

    def fake(model, kind, structure, alpha, options):
        return (
            np.eye(model.N),
            np.ones(model.m),
            None,
            {"structure": structure, "status": "optimal"},
        )

    monkeypatch.setattr(lmi, "_solve", fake)
    cert = circle_certificate(model)
    assert cert.verdict == "inconclusive"


def test_full_structure_agrees_with_block_diagonal():
    model = LureModel.from_design(random_design(5))
    a = circle_certificate(model, structure="block-diagonal")
    b = circle_certificate(model, structure="full")
    assert a.verdict == b.verdict == "holds"
    assert b.P.shape == (model.N, model.N)


def test_region_map_reuses_certificates_and_every_holds_reverifies():
    spec = load_example("ugv")
    design = build_observer(
        spec.system,
        {"kind": "elastic_net", "gain": "deadbeat", "step": 0.1, "threshold": 0.1, "shrink": 0.5},
    )
    rm = region_map(design, [0.3, 0.5, 0.7, 1.0], [0.05, 0.1, 0.2])
    assert rm.verdicts.shape == (4, 3)
    assert rm.reused >= 1
    assert all(
        v == "inconclusive" for v in rm.verdicts[-1]
    )  # shrink 1 on a plant with eigenvalue 1
    for i, q in enumerate(rm.shrinks):
        for j, nu in enumerate(rm.steps):
            if rm.verdicts[i, j] == "holds":
                # the stored certificate itself re-verifies, without any solver
                model = LureModel.from_design(replace(design, shrink=float(q), step=float(nu)))
                P, t = rm.certificates[(i, j)]
                assert verify_certificate(model, P, t)[0]
    json_certs = rm.to_dict()["certificates"]
    assert len(json_certs) == int(np.count_nonzero(rm.verdicts == "holds"))


def test_lure_model_matches_the_observer_simulator():
    """The Lur'e model's error trajectory is exactly the simulated observer's error."""
    from ssecert.observers import observer_from_design

    design = random_design(4, shrink=0.5, step=0.03)
    model = LureModel.from_design(design)
    system = design.system
    rng = np.random.default_rng(0)
    x = rng.standard_normal((5, system.n))
    attack = rng.uniform(-3, 3, (40, 5, system.p)) * (rng.random((1, 5, system.p)) < 0.4)
    ys, xs = [], [x]
    for k in range(40):
        ys.append(x @ system.C.T + attack[k])
        x = x @ system.A.T
        xs.append(x)
    traj = observer_from_design(design).run(np.array(ys))
    err = np.concatenate([traj.x_hat - np.array(xs), traj.a_hat], axis=-1)
    xi0 = np.concatenate([-np.array(xs[0]), np.zeros((5, system.p))], axis=1)
    model_traj = model.simulate(xi0, 40, attack=attack)
    np.testing.assert_allclose(model_traj, err, atol=1e-10)


def test_iss_evidence_reverifies_without_the_solver():
    spec = load_example("ugv")
    checks = observer_checks(
        spec.system,
        {"kind": "elastic_net", "gain": "deadbeat", "step": 0.1, "threshold": 0.1, "shrink": 0.5},
    )
    stability = next(c for c in checks if c.id == "observer_stability").to_dict()
    iss = json.loads(json.dumps(next(c for c in checks if c.id == "iss_gain").to_dict()))
    assert iss["verdict"] == "holds"
    mo = stability["evidence"]["model"]
    model = LureModel(
        *(np.array(mo[k], dtype=float) for k in ("A", "B", "Cw", "E", "Dw", "Ce")),
        mo["q"],
        mo["n_e"],
        mo["threshold"],
    )
    ev = iss["evidence"]
    ok, _, _, problem = verify_certificate(
        model,
        np.array(ev["P"]),
        np.array(ev["multipliers_T"]),
        kind="iss",
        alpha=ev["decay_alpha"],
        g=ev["gamma"] ** 2,
    )
    assert ok, problem


def test_region_map_fails_cells_carry_their_witness_and_undecided_cells_a_radius():
    spec = load_example("ugv")
    design = build_observer(spec.system, spec.observer)  # the thesis's D-SSO
    rm = region_map(design, [0.6, 1.0], [0.7, 1.4])
    # step 1.4: the large-signal loop has an eigenvalue beyond -1 (a divergent trajectory)
    assert rm.verdicts[0, 1] == "fails" and rm.witnesses[(0, 1)] == "divergent trajectory"
    assert rm.verdicts[1, 1] == "fails" and rm.radii[1, 1] == 0.0
    # shrink 1, step 0.7: undecided, with the dead zone's radius (Q = I)
    assert rm.verdicts[1, 0] == "inconclusive" and 0.1 < rm.radii[1, 0] <= 0.1 / 0.7
    assert rm.verdicts[0, 0] == "holds" and rm.radii[0, 0] == np.inf
    out = rm.to_dict()
    assert {"shrink": 0.6, "step": 1.4, "kind": "divergent trajectory"} in out["witnesses"]
    # every witness replays: the model of that cell grows from its witness
    from ssecert.stability.divergence import divergence_witness

    for i, j in rm.witnesses:
        model = LureModel.from_design(
            replace(design, shrink=float(rm.shrinks[i]), step=float(rm.steps[j]))
        )
        witness = divergence_witness(model)
        assert witness is not None and witness["growth"] >= 100


def test_region_map_starts_no_point_past_its_time_limit():
    # a D-SSO whose points need Zames-Falb multipliers mapped its grid for minutes after a
    # design search of 5 s; past the limit the points left are inconclusive and counted
    from ssecert.certify import REGION_SECONDS, region_time_limit

    spec = load_example("ugv")
    design = build_observer(
        spec.system,
        {"kind": "elastic_net", "gain": "deadbeat", "step": 0.1, "threshold": 0.1, "shrink": 0.5},
    )
    rm = region_map(design, [0.3, 0.5], [0.05, 0.1], time_limit=0.0)
    assert rm.not_reached == 4 and all(v == "inconclusive" for v in rm.verdicts.flat)
    assert rm.solves == 0 and rm.to_dict()["cells_not_reached"] == 4
    assert "cells_not_reached" not in region_map(design, [0.5], [0.1]).to_dict()
    assert region_time_limit(None) is None
    assert region_time_limit(0.0) == REGION_SECONDS and region_time_limit(500.0) == 500.0


def test_every_verification_problem_has_words():
    from ssecert.stability.lmi_messages import verify_text
    from ssecert.stability.lmi_verification import decide, definite_problem
    from ssecert.stability.outcomes import VerifyCode, VerifyProblem

    facts = {"value": -1e-3, "channel": 2, "m0": 0.5, "total": 0.6, "smallest": -1e-9,
             "margin": 1e-20, "clear": 100.0, "bound": 1e-16}  # fmt: skip
    for code in VerifyCode:
        assert verify_text(VerifyProblem(code, facts)), code
    # P not clearly definite, then a margin below its error bound: codes with the numbers
    assert definite_problem(np.diag([1.0, 1e-18]), 100.0).code is VerifyCode.NOT_CLEARLY_DEFINITE
    assert definite_problem(np.eye(2), 100.0) is None
    ok, _, _, problem = decide(np.eye(2), 1e-20, 1e-16, 100.0)
    assert not ok and problem.code is VerifyCode.MARGIN_NOT_CLEAR
    assert problem.facts == {"margin": 1e-20, "clear": 100.0, "bound": 1e-16}
    assert decide(np.eye(2), 1.0, 1e-16, 100.0) == (True, 1.0, 1e-16, None)


@pytest.mark.parametrize("key", ["multipliers", "gamma_squared", "u_delays"])
def test_a_write_back_that_would_round_into_the_subnormals_is_refused(key):
    # a certificate solved with the attack in units 2^505: its multipliers, gamma^2 and
    # delays are 4^-505 times those verified, below the normal floats where bits are lost
    from ssecert.results import Verdict
    from ssecert.stability.outcomes import LMICode

    def written_back(value: float, rounded: str | None):
        number = {k: (1.2345678901234e-5 if k == rounded else value) for k in
                  ("multipliers", "gamma_squared", "u_delays")}  # fmt: skip
        cert = lmi.LMICertificate(
            Verdict.HOLDS, "iss", P=np.array([[2.0, 0.5], [0.5, 1.0]]),
            multipliers=np.array([number["multipliers"]]), gamma=1.0, code=LMICode.VERIFIED,
            details={"gamma_squared": number["gamma_squared"], "u_delays": [[number["u_delays"]]]},
        )  # fmt: skip
        return lmi.to_original_coordinates(cert, np.array([1.0, 2.0**505]), 2, sensors=-505)

    assert written_back(0.75, key) is None
    exact = written_back(0.75, None)
    assert exact is not None and exact.multipliers[0] == np.ldexp(0.75, -1010)
    assert exact.details["gamma_squared"] == np.ldexp(0.75, -1010)
