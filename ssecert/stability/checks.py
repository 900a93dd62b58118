"""Observer checks for the ``[observer]`` section: gain, stability, ISS gain, thesis assumptions.

JSON ids: ``observer_gain`` and ``observer_stability`` (required),
``iss_gain`` and ``thesis_assumptions`` (advisory).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from enum import Enum
from typing import Any

import numpy as np

from ..base.format import one_minus, sig
from ..budget import Budget, Laps, Refusal, ResourceLimitError, stage
from ..context import OBSERVER, AnalysisContext, shared
from ..design.gains import GainError
from ..noise import MeasurementNoise
from ..observers import ObserverDesign, build_observer
from ..observers.lure import LureModel
from ..results import Check, Step, Verdict, Withdrawn, decide, withdraw
from ..solvers import solver_label
from ..system import System
from ..tolerances import Tolerances
from . import noise_messages, observer_messages, region_messages
from .constant_attack import constant_attack_outcomes
from .divergence import divergence_witness
from .equilibria import nonzero_equilibrium
from .gain_check import (
    EXACT_LIMIT,  # noqa: F401  (stays importable here)
    _decided_by,
    _exact,
    _lyapunov_evidence,
    exact_radius,
    observer_gain_check,
    overflow_reason,
)
from .lmi import (
    ETA,
    LMICertificate,
    circle_certificate,
    iss_certificate,
    iss_from_circle,
    lure_model_cost,
)
from .lyapunov import LyapunovCertificate, LyapunovMethod, lyapunov_certificate
from .outcomes import LMICause, LMICode, Region, RegionCode, SchurCode, WitnessKind, known
from .periodic import periodic_orbit
from .roa import region_of_attraction
from .search_messages import searched_text
from .thesis import thesis_assumptions
from .zames_falb import zames_falb_certificate, zames_falb_gain

__all__ = [
    "observer_checks",
    "observer_gain_check",
    "observer_stability_check",
    "iss_gain_check",
    "thesis_assumptions_check",
]

ISS_OPTIMIZE_LIMIT = 60  # largest dissipation LMI solved directly


def observer_stability_check(
    design: ObserverDesign,
    *,
    budget: Budget | None = None,
    tolerances: Tolerances | None = None,
) -> tuple[Check, Any]:
    """Global asymptotic stability of the observer's error dynamics without attack.

    Returns the Check and the underlying certificate (for the ISS check).
    ``budget`` bounds the Lur'e model and each LMI solve (default ``Budget()``);
    ``tolerances.certificate_clear`` is the factor by which a certificate's
    margin must beat its error bound.
    """
    tol = Tolerances.check(tolerances)
    title = f"Observer stability ({design.kind})"
    if not design.sparse:
        with stage("Lyapunov certificate"):
            lyap = lyapunov_certificate(
                design.error_matrix, exact=_exact(design), clear=tol.certificate_clear
            )
        return _linear_stability_check(lyap, tol, title), lyap
    gap = design.observer_kind.lure_gap(design)
    if gap:
        return _without_lure_model(design, gap, tol, title), None
    refusal = _lure_model_refusal(design, budget)
    if refusal is not None:
        summary = f"No stability certificate: not attempted: {refusal}."
        method = f"circle criterion (LMI, {solver_label()})"
        return _no_certificate(title, summary, method, LMICause.REFUSED), None
    model = design.observer_kind.lure_model(design)
    if not model.finite():
        summary = (
            "No stability certificate: the error dynamics' matrices leave the float range (an "
            "entry of A - L C, the gain or the sector's vertex loop beyond 1.8e308), so nothing "
            "can be computed or replayed in floating point."
        )
        method = f"circle criterion (LMI, {solver_label()})"
        return _no_certificate(title, summary, method, LMICause.NOT_FINITE), None
    with stage("circle criterion LMIs"):
        cert = circle_certificate(model, budget=budget, clear=tol.certificate_clear)
    if cert.code is LMICode.NOT_VERIFIED:
        # the LMIs were solved and failed: a dynamic multiplier may succeed
        with stage("Zames-Falb multiplier LMIs"):
            zf = zames_falb_certificate(model, budget=budget, clear=tol.certificate_clear)
        if zf.verdict is Verdict.HOLDS:
            return _zames_falb_stability_check(design, model, zf, tol, title), (model, zf)
        cert = replace(
            cert.noted(f"; {zf.reason}"), details={**cert.details, "zames_falb": zf.details}
        )
    if cert.verdict is Verdict.INCONCLUSIVE:
        with stage("divergent trajectory search"):
            witness, searched, cycled = divergence_witness(model), None, None
        if witness is None:
            with stage("nonzero equilibrium search"):
                witness, searched = nonzero_equilibrium(model, budget=budget)
        if witness is None:
            with stage("periodic orbit search"):
                witness, cycled = periodic_orbit(model, budget=budget)
        if witness is not None:
            return _witnessed_failure(design, model, cert, witness, tol, title), (model, cert)
        check = _circle_stability_check(design, model, cert, tol, title)
        radius = float(np.max(np.abs(np.linalg.eigvals(model.vertex(model.q)))))
        why = "not clearly above 1" if radius <= 1 + 1e-6 else "but no replay confirmed growth"
        searches = {
            "divergent_trajectory": "none: the large-signal loop A + shrink B Cw has spectral "
            f"radius {sig(radius, 6)}, {why}",
            "nonzero_equilibrium": searched_text(searched),
            "periodic_orbit": searched_text(cycled),
        }
        return replace(check, evidence={**check.evidence, "searches": searches}), (model, cert)
    return _circle_stability_check(design, model, cert, tol, title), (model, cert)


def _failure_words(
    model: LureModel, witness: dict[str, Any]
) -> tuple[str, str, float | None, float]:
    """(summary, method, margin, error bound) of a failing observer_stability, by the kind of
    its witness: a divergent trajectory of the large-signal loop, or an exactly confirmed
    nonzero equilibrium (a wrong estimate kept with no attack) or periodic orbit (the summary:
    ``observer_messages.failure_summary``)."""
    summary = observer_messages.failure_summary(witness)
    if witness["kind"] is WitnessKind.PERIODIC_ORBIT:
        return summary, "periodic orbit search (simulated tails, confirmed exactly)", None, 0.0
    if witness["kind"] is WitnessKind.NONZERO_EQUILIBRIUM:
        return summary, "equilibrium search (active/sign patterns, exact)", None, 0.0
    mu = witness["large_signal_eigenvalue"]
    return (
        summary,
        "large-signal divergence (eigenvector bound, replayed)",
        abs(mu) - 1.0,
        witness["eigenvalue_error_bound"],
    )


def _witnessed_failure(
    design: ObserverDesign,
    model: LureModel,
    cert: LMICertificate,
    witness: dict[str, Any],
    tol: Tolerances,
    title: str,
) -> Check:
    """A failing observer_stability with the witness a search found (``_failure_words``); the
    circle certificate that was not found stays in the evidence, and a divergence's
    large-signal loop."""
    witness = {**witness, "observer_replay": _observer_replay(design, witness)}
    summary, method, margin, error_bound = _failure_words(model, witness)
    evidence = _circle_evidence(model, cert)
    evidence["no_certificate"] = cert.reason
    if witness["kind"] is WitnessKind.DIVERGENT_TRAJECTORY:
        evidence["large_signal_loop"] = model.vertex(model.q)
    return Check(
        id="observer_stability",
        title=title,
        verdict=Verdict.FAILS,
        summary=summary,
        value=None,
        margin=margin,
        method=method,
        margin_name="|mu| - 1 of the large-signal eigenvalue" if margin is not None else "",
        fields={
            "decay_rate": None,
            "structure": cert.structure,
            "shrink": design.shrink,
            "step": design.step,
            "threshold": design.threshold,
        },
        evidence=evidence,
        witness=witness,
        tolerances=_decided_by(tol, error_bound=error_bound, lmi_eta=ETA),
        code=witness["kind"],
    )


def _observer_replay(design: ObserverDesign, witness: dict[str, Any]) -> dict[str, Any]:
    """The witness replayed through the observer's own simulator (not the Lur'e model): true
    state 0 and no attack, so x_hat is the estimation error."""
    from ..observers import observer_from_design

    e0 = np.asarray(witness["initial_error"], dtype=float)
    a0 = np.asarray(witness["initial_attack_estimate"], dtype=float)
    steps = int(witness.get("steps", 50))
    try:
        sim = observer_from_design(design)
        y = np.zeros((steps, 1, design.system.p))
        traj = sim.run(y, state={"x_hat": e0[None], "a_hat": a0[None]})
    except (KeyError, ValueError, NotImplementedError) as exc:  # a windowed observer's state
        return {"replayed": False, "reason": f"not replayed: {exc}"}
    if traj.a_hat is None:
        return {"replayed": False, "reason": "not replayed: the simulator has no attack estimate"}
    path = np.concatenate([traj.x_hat[:, 0], traj.a_hat[:, 0]], axis=1)
    start = float(np.linalg.norm(path[0]))
    out: dict[str, Any] = {"replayed": True, "simulator": type(sim).__name__, "steps": steps}
    if witness.get("kind") is WitnessKind.NONZERO_EQUILIBRIUM:
        drift = float(np.max(np.linalg.norm(path - path[0], axis=1)))
        out.update(largest_drift=drift, agrees=drift <= 1e-9 * max(start, 1.0))
    elif witness.get("kind") is WitnessKind.PERIODIC_ORBIT:
        back = float(np.linalg.norm(path[-1] - path[0]))
        out.update(return_residual=back, agrees=back <= 1e-9 * max(start, 1.0))
    else:
        from .divergence import safe_norms

        growth = float(safe_norms(path[-1]) / start) if start > 0 else float("nan")
        out.update(growth=growth, agrees=bool(growth >= 0.5 * float(witness.get("growth", 0))))
    return out


def _linear_stability_check(lyap: LyapunovCertificate, tol: Tolerances, title: str) -> Check:
    """observer_stability of a linear observer, from its Lyapunov certificate."""
    verdict = Verdict(lyap.verdict)
    shown = exact_radius(lyap)
    if verdict is Verdict.HOLDS and lyap.method is not LyapunovMethod.LYAPUNOV:
        summary = f"The error dynamics are linear and stable: {lyap.reason}."
    elif verdict is Verdict.HOLDS:
        summary = (
            f"The error dynamics are linear and certified stable by a Lyapunov matrix "
            f"(contraction {sig(known(lyap.contraction))} per step)."
            + observer_messages.balanced_lyapunov_note(lyap.proof)
        )
    elif verdict is Verdict.FAILS:
        summary = f"The error dynamics are unstable: {lyap.reason}."
    else:
        summary = f"Stability could not be certified: {lyap.reason}."
    return Check(
        id="observer_stability",
        title=title,
        verdict=verdict,
        summary=summary,
        value=lyap.contraction,
        # (an exact instability has no margin: that of the Lyapunov solution that did not
        # verify is not "1 - spectral radius bound")
        margin=lyap.margin
        if lyap.method is LyapunovMethod.LYAPUNOV or verdict is Verdict.HOLDS
        else None,
        method="discrete Lyapunov"
        if lyap.method is LyapunovMethod.LYAPUNOV
        else f"{lyap.method.value} of A - L C",
        value_name="contraction per step (P-norm)"
        if lyap.method is LyapunovMethod.LYAPUNOV
        else "spectral radius bound of A - L C",
        margin_name="Lyapunov margin"
        if lyap.method is LyapunovMethod.LYAPUNOV
        else "1 - spectral radius bound",
        value_text=shown.text if verdict is Verdict.HOLDS and shown is not None else "",
        fields={"decay_rate": None if lyap.contraction is None else 1 - lyap.contraction},
        evidence=_lyapunov_evidence(lyap),
        witness=lyap.witness if verdict is Verdict.FAILS else None,
        tolerances=_decided_by(tol, error_bound=lyap.error_bound),
        code=lyap.decided_by,
    )


def _without_lure_model(design: ObserverDesign, gap: str, tol: Tolerances, title: str) -> Check:
    """observer_stability of a design without a Lur'e form: it fails when the linear map its
    error follows near the origin (every soft threshold in its dead zone) is proved unstable,
    and is inconclusive otherwise."""
    kind = design.observer_kind
    if not np.all(np.isfinite(design.error_matrix)):
        summary = f"{gap} {overflow_reason(design)}."
        return _no_certificate(title, summary, "circle criterion", SchurCode.NON_FINITE)
    if kind.dead_zone_refusal(design) or kind.dead_zone_model(design) is not None:
        # the dead zone's linear map is the error matrix (F = A (I - step S' S)^m for an SSO)
        lyap = lyapunov_certificate(
            design.error_matrix, exact=kind.exact_error(design), clear=tol.certificate_clear
        )
        if lyap.verdict is Verdict.FAILS:
            return Check(
                id="observer_stability",
                title=title,
                verdict=Verdict.FAILS,
                summary="The observer is not stable: near the origin every soft threshold is in "
                "its dead zone, so the error follows the linear map e+ = A (I - step S' S)^m e "
                f"exactly, and that map is not stable: {lyap.reason}.",
                method=f"local linear map ({lyap.method})",
                fields={},
                evidence={"no_certificate": gap},
                tolerances=_decided_by(tol),
                code=WitnessKind.LOCAL_INSTABILITY,
            )
    return _no_certificate(title, gap, "circle criterion")


def _no_certificate(title: str, summary: str, method: str, code: Enum | None = None) -> Check:
    """An inconclusive observer_stability: no certificate was attempted (``code``: why, where
    a typed outcome says so)."""
    return Check(
        id="observer_stability",
        title=title,
        verdict=Verdict.INCONCLUSIVE,
        summary=summary,
        method=method,
        fields={},
        code=code,
    )


def _lure_model_refusal(design: ObserverDesign, budget: Budget | None) -> Refusal | None:
    """Why the budget refuses the memory of the design's Lur'e model (None when it fits)."""
    m = design.sensing.shape[0]
    return (budget or Budget()).check(
        f"the Lur'e model of the {design.kind} observer",
        nbytes=lure_model_cost(design.system.n, m, m)[0],
    )


def _circle_stability_check(
    design: ObserverDesign, model: LureModel, cert: LMICertificate, tol: Tolerances, title: str
) -> Check:
    """observer_stability of a sparse observer, from its circle-criterion certificate."""
    verdict = Verdict(cert.verdict)
    fields = {
        "decay_rate": cert.decay,
        "structure": cert.structure,
        "shrink": design.shrink,
        "step": design.step,
        "threshold": design.threshold,
    }
    if verdict is Verdict.HOLDS:
        summary = (
            f"The error state (e, a_hat) converges to 0 from every initial condition "
            f"without attack: V = xi' P xi decreases by at least a factor "
            f"{one_minus(known(cert.decay))} per step (circle criterion with a diagonal multiplier, "
            f"{cert.structure} P, verified margin {cert.margin:.3g} against an error bound "
            f"{cert.error_bound:.1e})." + _balanced_note(cert)
        )
    elif verdict is Verdict.FAILS:
        summary = f"The observer is not globally asymptotically stable: {cert.reason}."
    else:
        summary = f"No stability certificate: {cert.reason}."
    return Check(
        id="observer_stability",
        title=title,
        verdict=verdict,
        summary=summary,
        value=cert.decay,
        margin=cert.margin,
        method=f"circle criterion (LMI, {solver_label()})",
        fields=fields,
        evidence=_circle_evidence(model, cert),
        witness=cert.details.get("witness") if verdict is Verdict.FAILS else None,
        tolerances=_decided_by(tol, error_bound=cert.error_bound, lmi_eta=ETA),
        code=cert.cause,
    )


def _zames_falb_stability_check(
    design: ObserverDesign, model: LureModel, cert: LMICertificate, tol: Tolerances, title: str
) -> Check:
    """observer_stability of a sparse observer certified by a Zames-Falb multiplier."""
    order = cert.details["order"]
    summary = observer_messages.zames_falb_summary(
        order,
        incremental=bool(cert.details.get("incremental")),
        sum_bound_factor=cert.details["sum_bound_factor"],
        margin=known(cert.margin),
        error_bound=cert.error_bound,
    ) + _balanced_note(cert)
    evidence = _circle_evidence(model, cert)
    evidence["lmi"] = (
        "G' P G - diag(P, 0) + sum_i m0_i K0_i - sum_ij (a_ij Ka_ij + b_ij Kb_ij) <= -margin ||P|| I "
        "over z = (xi, u(k-1..k-order), v(k-1..k-order), u(k)), u = phi(w), v = shrink w - u, "
        "with m0_i >= sum_j |a_ij| + |b_ij| (ssecert.stability.zames_falb)"
    )
    evidence["multipliers_m0"] = evidence.pop("multipliers_T")
    return Check(
        id="observer_stability",
        title=title,
        verdict=Verdict.HOLDS,
        summary=summary,
        value=None,
        margin=cert.margin,
        method=f"Zames-Falb multiplier of order {order} (LMI, {solver_label()})",
        fields={
            "decay_rate": None,
            "structure": "zames-falb",
            "shrink": design.shrink,
            "step": design.step,
            "threshold": design.threshold,
        },
        evidence=evidence,
        tolerances=_decided_by(tol, error_bound=cert.error_bound, lmi_eta=ETA),
        code=cert.cause,
    )


def _balanced_note(cert: LMICertificate) -> str:
    """A sentence when the certificate was solved and verified in balanced state coordinates
    (``observer_messages.balanced_lmi_note``)."""
    return observer_messages.balanced_lmi_note(
        cert.details.get("state_scaling"), cert.details.get("sensor_exponent")
    )


def _circle_evidence(model: LureModel, cert: LMICertificate) -> dict[str, Any]:
    """The certificate's evidence with the LMI it solves and the Lur'e model's matrices."""
    evidence = cert.evidence()
    evidence["lmi"] = (
        "[A B]' P [A B] - diag(P, 0) + [[0, q Cw' T], [q T Cw, -2 T]] <= -margin ||P|| I"
        " with xi = (e, a_hat), A = [[F, -L], [0, 0]], B = [[0], [I]], "
        "Cw = [-step L2 S, I - step L2]"
    )
    evidence["model"] = {
        "A": model.A,
        "B": model.B,
        "Cw": model.Cw,
        "E": model.E,
        "Dw": model.Dw,
        "Ce": model.Ce,
        "q": model.q,
        "n_e": model.n_e,
        "threshold": model.threshold,
    }
    return evidence


def iss_gain_check(
    design: ObserverDesign,
    stability: Any,
    *,
    budget: Budget | None = None,
    tolerances: Tolerances | None = None,
    constant_attacks: Sequence[tuple[str, np.ndarray]] = (),
) -> Check:
    """l2 gain from attack to estimation error (and ISS decay), advisory; with
    ``constant_attacks`` ((name, attack vector) pairs), where the error goes under each
    (``constant_attacks`` in the evidence, ``ssecert.stability.constant_attack``)."""
    check = _iss_gain(design, stability, budget=budget, tolerances=tolerances)
    if not constant_attacks:
        return check
    if not design.sparse:
        model, certified = (
            design.observer_kind.lure_model(design),
            stability is not None and (stability.verdict == Verdict.HOLDS),
        )
    elif stability is not None:
        # a Zames-Falb certificate proves the increments converge only with nonnegative
        # coefficients (the increments' nonlinearity is slope-restricted but not odd)
        model, certified = (
            stability[0],
            stability[1].verdict == Verdict.HOLDS and stability[1].details.get("incremental", True),
        )
    else:
        return check
    records = constant_attack_outcomes(model, constant_attacks, certified=certified, budget=budget)
    if not records:
        return check
    return replace(
        check,
        summary=f"{check.summary} {observer_messages.constant_attack_text(records)}",
        evidence={**check.evidence, "constant_attacks": records},
    )


def _iss_gain(
    design: ObserverDesign,
    stability: Any,
    *,
    budget: Budget | None = None,
    tolerances: Tolerances | None = None,
) -> Check:
    """``iss_gain_check`` without the constant attacks."""
    tol = Tolerances.check(tolerances)
    clear = tol.certificate_clear
    title = "ISS gain from attack to estimation error"
    norm = (
        "l2 gain: sum_k |e(k)|^2 <= gamma^2 sum_k |a(k)|^2 + V(xi(0)), with a the "
        + ("stacked " if design.window > 1 else "")
        + "attack and e the state estimation error"
    )
    if not design.sparse:
        model = design.observer_kind.lure_model(design)
        cert = iss_certificate(model, alpha=0.0, budget=budget, clear=clear)
    else:
        if stability is None or stability[1].verdict != Verdict.HOLDS:
            return Check(
                id="iss_gain",
                title=title,
                verdict=Verdict.INCONCLUSIVE,
                required=False,
                summary="No ISS gain without a stability certificate.",
                method="dissipation inequality",
                fields={"norm": norm},
                code=LMICause.NO_BASE,
            )
        model, circle = stability
        if circle.kind == "zames-falb":
            cert = zames_falb_gain(model, circle, budget=budget, clear=clear)
            return _zames_falb_gain_check(cert, tol, title, norm)
        cert = iss_from_circle(model, circle, clear=clear)
        if model.N + model.m + model.r <= ISS_OPTIMIZE_LIMIT:
            direct = iss_certificate(
                model, alpha=0.5 * float(circle.decay or 0.0), budget=budget, clear=clear
            )
            if direct.verdict == Verdict.HOLDS and (
                cert.gamma is None or known(direct.gamma) < cert.gamma
            ):
                cert = direct
    decay = float(cert.decay or 0.0)
    decrease = f"-{decay:.3g} V(xi) " if decay > 0 else ""
    stacked = "stacked " if design.window > 1 else ""
    holds = (
        f"V(xi+) - V(xi) <= {decrease}- |e|^2 + gamma^2 |a|^2 holds with "
        f"gamma = {known(cert.gamma):.4g}: the estimation error is input-to-state stable with "
        f"respect to the {stacked}attack, with l2 gain at most {known(cert.gamma):.4g}"
        + (
            f" (a the attack stacked over the window of {design.window} samples: each sample "
            f"enters up to {design.window} times, so the gain from the attack itself is at most "
            f"sqrt({design.window}) times that)."
            if stacked
            else "."
        )
        if cert.verdict == Verdict.HOLDS
        else ""
    )
    inequality = "V(xi+) - V(xi) <= -alpha V(xi) - |e|^2 + gamma^2 |a|^2"
    return _gain_check(cert, tol, title, norm, holds, inequality, "dissipation inequality (LMI)")


def _zames_falb_gain_check(cert: LMICertificate, tol: Tolerances, title: str, norm: str) -> Check:
    """iss_gain from a Zames-Falb dissipation certificate (no decay is certified)."""
    holds = (
        f"V(zeta+) - V(zeta) + sigma <= -|e|^2 + gamma^2 |a|^2 holds with gamma = "
        f"{known(cert.gamma):.4g} and a Zames-Falb multiplier of order "
        f"{cert.details.get('order')} (sum_k sigma_k >= 0): the l2 gain from attack to "
        f"estimation error is at most {known(cert.gamma):.4g}."
        if cert.verdict == Verdict.HOLDS
        else ""
    )
    inequality = "V(zeta+) - V(zeta) + sigma <= -|e|^2 + gamma^2 |a|^2"
    method = "dissipation inequality with a Zames-Falb multiplier (LMI)"
    return _gain_check(cert, tol, title, norm, holds, inequality, method)


def _gain_check(
    cert: LMICertificate,
    tol: Tolerances,
    title: str,
    norm: str,
    holds: str,
    inequality: str,
    method: str,
) -> Check:
    """The iss_gain Check of a dissipation certificate: ``holds`` is its summary when verified."""
    verdict = Verdict(cert.verdict)
    evidence = cert.evidence()
    evidence["inequality"] = inequality
    return Check(
        id="iss_gain",
        title=title,
        verdict=verdict,
        summary=holds + _balanced_note(cert)
        if verdict is Verdict.HOLDS
        else f"No ISS gain certified: {cert.reason}.",
        required=False,
        value=cert.gamma,
        margin=cert.margin,
        method=method,
        fields={"gamma": cert.gamma, "alpha": cert.decay, "norm": norm},
        evidence=evidence,
        tolerances=_decided_by(tol, error_bound=cert.error_bound),
        code=cert.cause,
    )


def thesis_assumptions_check(
    design: ObserverDesign,
    observability: Check | None,
    *,
    seed: int = 0,
    budget: Budget | None = None,
) -> Check:
    """The thesis's Assumptions 1-3, Lemma 1 and epsilon bound (5.20), advisory.

    They are sufficient conditions of the thesis's stability theorem: when one
    fails, the check fails (the answer to its question) and does not apply
    (``applies=False``): the theorem says nothing about this design, and no
    verdict of the certificate relies on it.
    """
    holds = None if observability is None else observability.verdict is Verdict.HOLDS
    verdict, items = thesis_assumptions(design, observability_holds=holds, seed=seed, budget=budget)
    failing = [i for i in items if i.verdict is Verdict.FAILS]
    summary = observer_messages.thesis_summary(Verdict(verdict), items)
    return Check(
        id="thesis_assumptions",
        title="Thesis assumptions (Ch. 5)",
        verdict=Verdict(verdict),
        summary=summary,
        required=False,
        applies=verdict != Verdict.FAILS,
        value=len(failing),
        method="proof or counterexample search",
        fields={"items": {i.name: i.verdict for i in items}},
        evidence={i.name: i.to_dict() for i in items},
    )


def observer_checks(
    system: System,
    observer: Mapping[str, Any],
    *,
    observability: Check | None = None,
    seed: int = 0,
    budget: Budget | None = None,
    context: AnalysisContext | None = None,
    tolerances: Tolerances | None = None,
    constant_attacks: Sequence[tuple[str, np.ndarray]] = (),
    timings: dict[str, float] | None = None,
    noise: MeasurementNoise | None = None,
) -> list[Check]:
    """All observer checks of a spec's ``[observer]`` section.

    Parameters
    ----------
    system : System
    observer : mapping
        The validated ``[observer]`` section.
    observability : Check, optional
        The plant's observability check (decides Assumption 1, and whether
        a failing gain is the plant's fault).
    seed : int, default 0
    budget : Budget, optional
        Memory and work allowed for the observer's matrices and each LMI
        (default ``Budget()``: 2 GiB, 1e12 operations); what does not fit is
        inconclusive with the estimate.
    context : AnalysisContext, optional
        The run's shared results: the observer is built once and kept there
        for the simulations.
    tolerances : Tolerances, optional
        ``certificate_clear`` decides when a certificate's margin beats its
        error bound; every check reports the tolerances it rests on.
    constant_attacks : sequence of (str, ndarray), optional
        Named constant attack vectors (length p): ``iss_gain`` reports where
        the error goes under each (``ssecert.stability.constant_attack``;
        ``analyze`` passes ``default_attacks`` of the spec).
    timings : dict, optional
        Filled with the wall-clock seconds of each check (building the observer counted in
        ``observer_gain``), as ``meta.timings`` reports them.
    noise : MeasurementNoise, optional
        Bounded measurement noise: a linear observer gets ``observer_noise_bound``.

    Returns
    -------
    list of Check
        ``observer_gain``, ``observer_stability`` and, when a gain exists,
        ``iss_gain``, with noise and a linear observer ``observer_noise_bound``, and
        (sparse observers) ``thesis_assumptions`` and ``region_of_attraction``.

    Examples
    --------
    >>> from ssecert.examples import load_example
    >>> spec = load_example("ugv")
    >>> [(c.id, c.verdict.value) for c in observer_checks(spec.system, spec.observer)]
    ... # doctest: +NORMALIZE_WHITESPACE
    [('observer_gain', 'holds'), ('observer_stability', 'inconclusive'),
     ('iss_gain', 'inconclusive'), ('thesis_assumptions', 'fails'),
     ('region_of_attraction', 'holds')]
    """
    tol = Tolerances.check(tolerances)
    clock = Laps(timings)
    clock.begin("observer_gain")  # building the observer is part of it
    try:
        design = shared(
            context,
            OBSERVER,
            lambda: build_observer(system, observer, budget=budget, tolerances=tol),
        )
    except ResourceLimitError as exc:
        gain = Check(
            id="observer_gain",
            title="Observer gain",
            verdict=Verdict.INCONCLUSIVE,
            summary=f"The observer was not built: {exc}.",
            method=str(observer.get("gain", observer["kind"])),
            fields={"L": None, "spectral_radius": None, "kind": observer["kind"]},
        )
        stab = Check(
            id="observer_stability",
            title="Observer stability",
            verdict=Verdict.INCONCLUSIVE,
            summary=f"No stability analysis: the observer was not built ({exc}).",
            method="",
            fields={},
        )
        return [gain, stab]
    except GainError as exc:
        unobservable = observability is not None and observability.verdict is Verdict.FAILS
        verdict = Verdict.FAILS if unobservable else Verdict.INCONCLUSIVE
        gain = Check(
            id="observer_gain",
            title="Observer gain",
            verdict=verdict,
            summary=f"The requested gain cannot be computed: {exc}.",
            method=str(observer.get("gain", observer["kind"])),
            fields={"L": None, "spectral_radius": None, "kind": observer["kind"]},
        )
        stab = Check(
            id="observer_stability",
            title="Observer stability",
            verdict=Verdict.INCONCLUSIVE,
            summary="No gain, so no stability analysis.",
            method="",
            fields={},
        )
        return [gain, stab]
    # what each check needs comes before it; each is built once (``decide``)
    sparse = design.sparse
    steps = [
        Step("observer_gain", lambda: observer_gain_check(design, tolerances=tol)),
        Step(
            "observer_stability",
            lambda gain: _against_gain(
                observer_stability_check(design, budget=budget, tolerances=tol), gain, design
            ),
            needs=("observer_gain",),
        ),
        Step(
            "region_of_attraction",
            lambda stability: (
                region_of_attraction_check(design, seed=seed, budget=budget, stability=stability[0])
                if sparse
                else None
            ),
            needs=("observer_stability",),
        ),
        Step(
            "stability_check",
            lambda stability, region: _stability_with_region(stability[0], region),
            needs=("observer_stability", "region_of_attraction"),
            timed=False,
        ),
        Step(
            "iss_gain",
            lambda stability: iss_gain_check(
                design,
                stability[1],
                budget=budget,
                tolerances=tol,
                constant_attacks=constant_attacks,
            ),
            needs=("observer_stability",),
        ),
    ]
    if sparse:
        steps.append(
            Step(
                "thesis_assumptions",
                lambda: thesis_assumptions_check(design, observability, seed=seed, budget=budget),
            )
        )
    if noise is not None:
        steps.append(
            Step(
                "observer_noise_bound",
                lambda iss: noise_messages.noise_check(design, noise, iss),
                needs=("iss_gain",),
            )
        )
    out = decide(steps, clock)
    order = (
        "observer_gain", "stability_check", "iss_gain", "observer_noise_bound",
        "thesis_assumptions",
    )  # fmt: skip
    checks = [out[name] for name in order if name in out]
    if out["region_of_attraction"] is not None:
        checks.append(out["region_of_attraction"])
    return checks


def _against_gain(
    stability: tuple[Check, Any], gain: Check, design: ObserverDesign
) -> tuple[Check, Any]:
    """The stability check (and its certificate) as reported: withdrawn (``withdraw``) where
    it contradicts the gain check decided before it, which decides the stability of the
    same error matrix A - L C for an observer without an attack estimate, and whose proved
    instability of A - L C rules out a stable observer of any kind (near e = 0 the error
    follows e+ = (A - L C) e).  On a correct run it finds nothing: what it finds is a
    defect, reported by the check that sees it."""
    check, certificate = stability
    decided = {gain.verdict, check.verdict}
    why = None
    if not design.observer_kind.estimates_attack and decided == {Verdict.HOLDS, Verdict.FAILS}:
        why = "both decide the stability of the same linear error matrix A - L C"
    elif (
        gain.verdict is Verdict.FAILS
        and check.verdict is Verdict.HOLDS
        and gain.witness is not None
    ):
        why = (
            "an unstable A - L C (proved by the gain check) rules out a stable observer: near "
            "e = 0 the error follows e+ = (A - L C) e"
        )
    if why is None:
        return check, certificate
    # nothing after it rests on a certificate its own check withdrew (the ISS gain, the noise
    # bound: inconclusive without a stability certificate)
    return withdraw(check, gain, why), None


def _stability_with_region(stability: Check, region: Check | None) -> Check:
    """observer_stability as reported: an undecided stability check says what
    region_of_attraction proves (the step after both in ``observer_checks``); a withdrawn one
    stays as it was withdrawn."""
    undecided = stability.verdict is Verdict.INCONCLUSIVE and stability.code is not (
        Withdrawn.CONTRADICTS
    )
    if region is None or not undecided or not region.value:
        return stability
    return replace(
        stability,
        summary=f"{stability.summary} {observer_messages.region_proved_text(region.value)}",
        evidence={**stability.evidence, "certified_region_radius": region.value},
    )


def region_of_attraction_check(
    design: ObserverDesign,
    *,
    seed: int = 0,
    piecewise: bool = False,
    budget: Budget | None = None,
    stability: Check | None = None,
) -> Check | None:
    """Advisory: the radius of initial estimation errors from which a sparse observer provably
    converges without attack (the invariant part of its dead zone, and with ``piecewise`` a
    piecewise-quadratic Lyapunov function when it certifies more); None for a design without
    a Lur'e model.

    With the observer's ``stability`` check: the piecewise function is tried when it is
    undecided, and when it holds the region is every initial error (its certificate is
    global), the dead zone's radius kept in the evidence."""
    if stability is not None:
        piecewise = stability.verdict is Verdict.INCONCLUSIVE
    alone = _region_alone(design, seed=seed, piecewise=piecewise, budget=budget)
    if alone is None:
        return None
    check, region = alone
    if stability is None or stability.verdict is not Verdict.HOLDS:
        return check
    return region_messages.global_region_check(check, region)


def _region_alone(
    design: ObserverDesign, *, seed: int, piecewise: bool, budget: Budget | None
) -> tuple[Check, Region] | None:
    """``region_of_attraction_check`` from the observer's dead zone (and piecewise function)
    alone, with the region it rests on."""
    if design.observer_kind.lure_gap(design) is None:
        refusal = _lure_model_refusal(design, budget)
        if refusal is not None:
            region = Region.none(RegionCode.NOT_ATTEMPTED, refusal=refusal)
            return region_messages.refused_region_check(region), region
    try:
        model = design.observer_kind.lure_model(design)
    except NotImplementedError:
        reason = design.observer_kind.dead_zone_refusal(design)
        if reason:
            region = Region.none(RegionCode.NOT_ATTEMPTED, refusal=reason, as_given=True)
            return region_messages.refused_region_check(region), region
        dead_zone = design.observer_kind.dead_zone_model(design)
        if dead_zone is None:
            return None
        region = _dead_zone_only_region(design, dead_zone, seed)
        return region_messages.inner_steps_region_check(region, dead_zone.m), region
    region = region_of_attraction(model, seed=seed, piecewise=piecewise, budget=budget)
    return region_messages.lure_region_check(region), region


def _dead_zone_only_region(design: ObserverDesign, model: LureModel, seed: int) -> Region:
    """The region of a design known only in its dead zone (an SSO with several inner steps per
    sample): the invariant sublevel set of the dead zone's linear map, replayed through the
    observer's own simulator (the attack estimate must stay 0 and the error converge)."""
    found = region_of_attraction(model, seed=seed)
    evidence = {k: v for k, v in found.evidence.items() if k != "replay"}
    if found.radius <= 0:
        return replace(found, evidence=evidence)
    replay = _simulator_region_replay(design, found.radius, seed)
    evidence["replay"] = replay
    if not replay["confirmed"]:
        return Region.none(RegionCode.SIMULATOR_REPLAY_FAILED, evidence)
    return replace(found, evidence=evidence)


def _simulator_region_replay(design: ObserverDesign, radius: float, seed: int) -> dict[str, Any]:
    """Initial errors on the sphere of ``radius`` through the observer's simulator, no attack
    and true state 0: the attack estimate stays 0 and the error shrinks."""
    from ..observers import observer_from_design

    samples, steps = 32, 200
    rng = np.random.default_rng(seed)
    e0 = rng.standard_normal((samples, design.system.n))
    e0 *= radius / np.linalg.norm(e0, axis=1, keepdims=True)
    sim = observer_from_design(design)
    state = sim.initial_state(samples)
    state["x_hat"] = e0
    traj = sim.run(np.zeros((steps, samples, design.system.p)), state=state)
    a_max = float(np.abs(traj.a_hat).max()) if traj.a_hat is not None else 0.0
    final = float(np.linalg.norm(traj.x_hat[-1], axis=1).max())
    return {
        "samples": samples,
        "steps": steps,
        "simulator": type(sim).__name__,
        "largest_attack_estimate": a_max,
        "final_largest_error": final,
        "confirmed": a_max == 0.0 and final < radius,
    }
