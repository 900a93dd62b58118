"""Observer checks for the ``[observer]`` section: gain, stability, ISS gain, thesis assumptions.

JSON ids: ``observer_gain`` and ``observer_stability`` (required),
``iss_gain`` and ``thesis_assumptions`` (advisory).
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import partial
from typing import Any

import numpy as np

from .._format import sig
from ..budget import Budget, ResourceLimitError
from ..context import OBSERVER, AnalysisContext, shared
from ..design.gains import GainError
from ..observers import ObserverDesign, build_observer
from ..observers.lure import LureModel
from ..results import Check, Verdict
from ..system import System
from ..tolerances import Tolerances
from .lmi import (
    ETA,
    LMICertificate,
    circle_certificate,
    iss_certificate,
    iss_from_circle,
    lure_model_cost,
)
from .lyapunov import LyapunovCertificate, lyapunov_certificate
from .thesis import thesis_assumptions

__all__ = [
    "observer_checks",
    "observer_gain_check",
    "observer_stability_check",
    "iss_gain_check",
    "thesis_assumptions_check",
]

ISS_OPTIMIZE_LIMIT = 60  # largest dissipation LMI solved directly


def _lyapunov_evidence(cert) -> dict[str, Any]:
    return {
        "P": cert.P,
        "decrease_P_minus_FtPF": cert.decrease,
        "margin": cert.margin,
        "error_bound": cert.error_bound,
        "contraction": cert.contraction,
        "condition_number_P": cert.condition,
        "residual": cert.residual,
        "margin_definition": (
            "lambda_min(P - F'PF) / ||P||, recomputed from P"
            if cert.method == "lyapunov"
            else "1 - (certified upper bound on the spectral radius of the exact F)"
        ),
        "certificate": cert.method,
        "exact_decision": cert.proof,
    }


EXACT_LIMIT = 6  # largest n verified exactly in rational arithmetic


def _exact_deadbeat(system: System) -> dict[str, Any]:
    """The deadbeat construction redone in rationals on the exact values of the floats."""
    from ..design.gains import exact_deadbeat_gain

    try:
        exact = exact_deadbeat_gain(system.A.tolist(), system.C.tolist())
    except GainError as exc:
        return {"verified": False, "reason": str(exc)}
    return {
        "verified": exact.verified,
        "exact_index": exact.details["exact_index"],
        "L_exact": exact.details["L_exact"],
        "note": (
            "A and C taken as the exact rational values of their floating-point entries; "
            "F^k == 0 and F^(k-1) != 0 checked exactly"
        ),
    }


def _decided_by(tol: Tolerances, **extra: Any) -> dict[str, Any]:
    """The tolerances an observer check's verdict rests on, for its JSON."""
    return {"clear_factor": tol.certificate_clear, **extra}


def observer_gain_check(design: ObserverDesign, *, tolerances: Tolerances | None = None) -> Check:
    """Is the gain what was asked for, and is the linear error matrix F = A - L S stable?

    Every number is about the gain as printed: F is formed exactly from the
    floats of A, L and S.  For a deadbeat gain on a small plant the exact
    rational gain is also computed; it is evidence about the plant, and the
    verdict never rests on it.  ``tolerances.certificate_clear`` is the
    factor by which a Lyapunov decrease must beat its error bound.
    """
    tol = Tolerances.check(tolerances)
    gain = design.gain
    F = design.error_matrix
    parts = _parts(design)
    computed_radius = float(np.abs(np.linalg.eigvals(F)).max())
    fields: dict[str, Any] = {"L": gain.L, "gain_method": gain.method, "kind": design.kind}
    title = f"Observer gain ({gain.method})"
    evidence: dict[str, Any] = {
        "details": gain.details,
        "computed_eigenvalue_radius": computed_radius,
    }
    if gain.method == "deadbeat":
        return _deadbeat_check(design, fields, evidence, title)
    cert = lyapunov_certificate(F, parts=parts, clear=tol.certificate_clear)
    fields["spectral_radius"] = cert.spectral_radius
    evidence.update(_lyapunov_evidence(cert))
    verdict = Verdict(cert.verdict)
    if verdict is Verdict.HOLDS and cert.method == "exact powers":
        fields["spectral_radius"] = cert.contraction
        summary = f"The linear error dynamics e+ = (A - L C) e are stable: {cert.reason}."
    elif verdict is Verdict.HOLDS:
        summary = (
            f"The linear error dynamics e+ = (A - L C) e are stable (spectral radius "
            f"{sig(_known(cert.spectral_radius))}), certified by a Lyapunov matrix P: the error "
            f"contracts at least by {sig(_known(cert.contraction))} per step in the P-norm."
        )
    elif verdict is Verdict.FAILS:
        summary = (
            f"A - L C is not stable: {cert.reason}. With this gain the error does not "
            f"vanish even without attack."
        )
    else:
        summary = f"The stability of A - L C could not be certified: {cert.reason}."
    return Check(
        id="observer_gain",
        title=title,
        verdict=verdict,
        summary=summary,
        value=fields["spectral_radius"],
        margin=cert.margin,
        method="discrete Lyapunov (dlyap)"
        if cert.method == "lyapunov"
        else "exact powers of A - L C",
        fields=fields,
        evidence=evidence,
        witness=cert.witness if verdict is Verdict.FAILS else None,
        tolerances=_decided_by(tol, error_bound=cert.error_bound),
    )


def _known(value: float | None) -> float:
    """A number a holding certificate always carries (its radius, contraction, gain)."""
    if value is None:  # pragma: no cover - certificates that hold set it
        raise RuntimeError("a holding certificate is missing the number it certifies")
    return value


def _parts(design: ObserverDesign) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(A, L, S) whose exact combination A - L S is the error matrix, when it is one."""
    return design.observer_kind.exact_parts(design)


def _deadbeat_check(
    design: ObserverDesign, fields: dict[str, Any], evidence: dict[str, Any], title: str
) -> Check:
    """The observer_gain check of a deadbeat gain, from the power test its build ran."""
    details = design.gain.details
    exact_note = _exact_deadbeat_note(design, evidence)
    fields["nilpotency_index"] = details.get("nilpotency_index")
    fields["observability_index"] = details.get("observability_index")
    fields["spectral_radius"] = details.get("spectral_radius_upper_bound")
    fields["spectral_radius_lower_bound"] = details.get("spectral_radius_lower_bound")
    check = partial(
        Check,
        id="observer_gain",
        title=title,
        method="deadbeat (exact powers of the printed A - L C)",
        fields=fields,
        evidence=evidence,
        tolerances=_deadbeat_tolerances(details),
    )
    if design.gain.verified:
        summary = _nilpotent_summary(details, fields) + exact_note
        upper = _known(details.get("spectral_radius_upper_bound"))
        return check(
            verdict=Verdict.HOLDS,
            summary=summary,
            value=fields["nilpotency_index"],  # the exact index when it differs
            margin=1.0 - upper,
        )
    problem = details.get("problem") or "the power test did not conclude"
    witness = _deadbeat_instability(design)
    if witness is not None:
        return check(
            verdict=Verdict.FAILS,
            summary=(
                f"The deadbeat construction's printed gain is not deadbeat: {problem}. "
                f"Rounding L to floats destroys the nilpotency of this plant's "
                f"deadbeat loop." + exact_note
            ),
            value=details.get("nilpotency_index"),
            margin=None,
            witness=witness,
        )
    return check(
        verdict=Verdict.INCONCLUSIVE,
        summary=f"The deadbeat gain could not be verified for the printed L: {problem}."
        + exact_note,
        value=details.get("nilpotency_index"),
    )


def _exact_deadbeat_note(design: ObserverDesign, evidence: dict[str, Any]) -> str:
    """The summary's sentence on the exact rational gain (small plants; '' otherwise).

    The exact construction is recorded in ``evidence["exact"]``.
    """
    if design.system.n > EXACT_LIMIT:
        return ""
    evidence["exact"] = _exact_deadbeat(design.system)
    if not evidence["exact"].get("verified"):
        return ""
    return (
        f" In exact arithmetic the rational gain L_exact (evidence) is nilpotent "
        f"with index {evidence['exact']['exact_index']}."
    )


def _deadbeat_tolerances(details: Mapping[str, Any]) -> dict[str, Any]:
    """The tolerances of the power test, which ran when the gain was built with the run's."""
    return {
        "deadbeat_rtol": details.get("deadbeat_rtol", Tolerances().deadbeat_rtol),
        "clear_factor": details.get("clear_factor", Tolerances().certificate_clear),
    }


def _nilpotent_summary(details: Mapping[str, Any], fields: dict[str, Any]) -> str:
    """What a verified deadbeat gain's check says.

    An exact nilpotency index that differs from the index to rounding
    becomes ``fields["nilpotency_index"]``, beside
    ``nilpotency_index_to_rounding``.
    """
    index = int(_known(details.get("nilpotency_index")))
    upper = _known(details.get("spectral_radius_upper_bound"))
    rel = details["relative_power_norms"][index - 1]
    exactly = details.get("exactly_nilpotent")
    exact_index = details.get("exact_nilpotency_index")
    if exactly and exact_index is not None and exact_index != index:
        fields["nilpotency_index"] = exact_index
        fields["nilpotency_index_to_rounding"] = index
    if exactly and exact_index is not None:
        exact = (
            f"A - L C with the printed L is exactly nilpotent with index {exact_index}: the "
            f"error vanishes in {exact_index} step{'s' if exact_index != 1 else ''} without "
            f"attack"
        )
        if exact_index == index:
            return exact + "."
        rounded = f"||(A - L C)^{index}|| <= {rel:.1e} ||A||^{index}"
        return exact + f" (to rounding already in {index}: {rounded})."
    return (
        f"With the printed L, ||(A - L C)^{index}|| <= {rel:.1e} ||A||^{index} (powers "
        f"computed exactly from the floats): the error vanishes to rounding in {index} "
        f"step{'s' if index != 1 else ''} without attack{_fastest_note(details)}, and the "
        f"spectral radius is certified <= {upper:.3g}."
    )


def _fastest_note(details: Mapping[str, Any]) -> str:
    """Whether the deadbeat index is the observability index, the fastest possible."""
    nu = details.get("observability_index")
    if nu is None:
        return ""
    if details.get("minimal"):
        return ", the observability index"
    return f" (the observability index is {nu}: a faster deadbeat gain exists)"


def _deadbeat_instability(design: ObserverDesign) -> dict[str, Any] | None:
    """A verified instability witness of the printed A - L C, when its radius exceeds 1."""
    lower = design.gain.details.get("spectral_radius_lower_bound")
    if lower is None or not lower > 1:
        return None
    from .lyapunov import instability_witness

    witness = instability_witness(design.error_matrix, parts=_parts(design))
    if witness is not None and witness["verified"]:
        return witness
    return None


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
        lyap = lyapunov_certificate(
            design.error_matrix, parts=_parts(design), clear=tol.certificate_clear
        )
        return _linear_stability_check(lyap, tol, title), lyap
    gap = design.observer_kind.lure_gap(design)
    if gap:
        return _no_certificate(title, gap, "circle criterion"), None
    refusal = _lure_model_refusal(design, budget)
    if refusal:
        summary = f"No stability certificate: not attempted: {refusal}."
        return _no_certificate(title, summary, "circle criterion (LMI, Clarabel)"), None
    model = design.observer_kind.lure_model(design)
    cert = circle_certificate(model, budget=budget, clear=tol.certificate_clear)
    return _circle_stability_check(design, model, cert, tol, title), (model, cert)


def _linear_stability_check(lyap: LyapunovCertificate, tol: Tolerances, title: str) -> Check:
    """observer_stability of a linear observer, from its Lyapunov certificate."""
    verdict = Verdict(lyap.verdict)
    if verdict is Verdict.HOLDS and lyap.method == "exact powers":
        summary = f"The error dynamics are linear and stable: {lyap.reason}."
    elif verdict is Verdict.HOLDS:
        summary = (
            f"The error dynamics are linear and certified stable by a Lyapunov matrix "
            f"(contraction {sig(_known(lyap.contraction))} per step)."
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
        margin=lyap.margin,
        method="discrete Lyapunov" if lyap.method == "lyapunov" else "exact powers of A - L C",
        fields={"decay_rate": None if lyap.contraction is None else 1 - lyap.contraction},
        evidence=_lyapunov_evidence(lyap),
        witness=lyap.witness if verdict is Verdict.FAILS else None,
        tolerances=_decided_by(tol, error_bound=lyap.error_bound),
    )


def _no_certificate(title: str, summary: str, method: str) -> Check:
    """An inconclusive observer_stability: no certificate was attempted."""
    return Check(
        id="observer_stability",
        title=title,
        verdict=Verdict.INCONCLUSIVE,
        summary=summary,
        method=method,
        fields={},
    )


def _lure_model_refusal(design: ObserverDesign, budget: Budget | None) -> str:
    """Why the budget refuses the memory of the design's Lur'e model ('' when it fits)."""
    m = design.sensing.shape[0]
    return (budget or Budget()).refusal(
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
            f"{1 - _known(cert.decay):.6g} per step (circle criterion with a diagonal multiplier, "
            f"{cert.structure} P, verified margin {cert.margin:.3g} against an error bound "
            f"{cert.error_bound:.1e})."
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
        method="circle criterion (LMI, Clarabel)",
        fields=fields,
        evidence=_circle_evidence(model, cert),
        witness=cert.details.get("witness") if verdict is Verdict.FAILS else None,
        tolerances=_decided_by(tol, error_bound=cert.error_bound, lmi_eta=ETA),
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
) -> Check:
    """l2 gain from attack to estimation error (and ISS decay), advisory."""
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
            )
        model, circle = stability
        cert = iss_from_circle(model, circle, clear=clear)
        if model.N + model.m + model.r <= ISS_OPTIMIZE_LIMIT:
            direct = iss_certificate(
                model, alpha=0.5 * float(circle.decay or 0.0), budget=budget, clear=clear
            )
            if direct.verdict == Verdict.HOLDS and (
                cert.gamma is None or _known(direct.gamma) < cert.gamma
            ):
                cert = direct
    verdict = Verdict(cert.verdict)
    fields = {"gamma": cert.gamma, "alpha": cert.decay, "norm": norm}
    if verdict is Verdict.HOLDS:
        summary = (
            f"V(xi+) - V(xi) <= -{cert.decay:.3g} V(xi) - |e|^2 + gamma^2 |a|^2 holds with "
            f"gamma = {cert.gamma:.4g}: the estimation error is input-to-state stable with "
            f"respect to the attack, with l2 gain at most {cert.gamma:.4g}."
        )
    else:
        summary = f"No ISS gain certified: {cert.reason}."
    evidence = cert.evidence()
    evidence["inequality"] = "V(xi+) - V(xi) <= -alpha V(xi) - |e|^2 + gamma^2 |a|^2"
    return Check(
        id="iss_gain",
        title=title,
        verdict=verdict,
        summary=summary,
        required=False,
        value=cert.gamma,
        margin=cert.margin,
        method="dissipation inequality (LMI)",
        fields=fields,
        evidence=evidence,
        tolerances=_decided_by(tol, error_bound=cert.error_bound),
    )


def thesis_assumptions_check(
    design: ObserverDesign,
    observability: Check | None,
    *,
    seed: int = 0,
    budget: Budget | None = None,
) -> Check:
    """The thesis's Assumptions 1-3, Lemma 1 and epsilon bound (5.20), advisory."""
    holds = None if observability is None else observability.verdict is Verdict.HOLDS
    verdict, items = thesis_assumptions(design, observability_holds=holds, seed=seed, budget=budget)
    failing = [i.name for i in items if i.verdict == Verdict.FAILS]
    if verdict == Verdict.HOLDS:
        summary = "Every assumption of the thesis's stability proof holds on this design."
    elif verdict == Verdict.FAILS:
        summary = (
            "The thesis's stability proof does not apply to this design: "
            + "; ".join(f"{i.name}: {i.reason}" for i in items if i.verdict == Verdict.FAILS)[:600]
        )
    else:
        summary = (
            "Not all assumptions could be decided: "
            + "; ".join(
                f"{i.name}: {i.reason}" for i in items if i.verdict == Verdict.INCONCLUSIVE
            )[:600]
        )
    return Check(
        id="thesis_assumptions",
        title="Thesis assumptions (Ch. 5)",
        verdict=Verdict(verdict),
        summary=summary,
        required=False,
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

    Returns
    -------
    list of Check
        ``observer_gain``, ``observer_stability`` and, when a gain exists,
        ``iss_gain`` and (sparse observers) ``thesis_assumptions``.

    Examples
    --------
    >>> from ssecert.examples import load_example
    >>> spec = load_example("ugv")
    >>> [(c.id, c.verdict.value) for c in observer_checks(spec.system, spec.observer)]
    ... # doctest: +NORMALIZE_WHITESPACE
    [('observer_gain', 'holds'), ('observer_stability', 'inconclusive'),
     ('iss_gain', 'inconclusive'), ('thesis_assumptions', 'fails')]
    """
    tol = Tolerances.check(tolerances)
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
    checks = [observer_gain_check(design, tolerances=tol)]
    stability, cert = observer_stability_check(design, budget=budget, tolerances=tol)
    checks.append(stability)
    checks.append(iss_gain_check(design, cert, budget=budget, tolerances=tol))
    if design.sparse:
        checks.append(thesis_assumptions_check(design, observability, seed=seed, budget=budget))
    return checks
