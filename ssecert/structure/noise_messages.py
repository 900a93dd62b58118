"""The words of the decoder error bound: the ``decoder_error_bound`` check from its outcome.

``ssecert.structure.noise.decoder_error_bound`` returns a
``DecoderErrorBound`` (numbers and a ``BoundCode``); this module alone
writes what a user reads about it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..base.format import readable
from ..noise import MeasurementNoise
from ..results import Check, Verdict
from ..system import System
from .l1_bound import L1BoundCode, L1ErrorBound
from .lasso_bound import LassoBoundCode, LassoErrorBound, lasso_worst_case
from .noise import BoundCode, DecoderErrorBound, worst_case_pair

__all__ = [
    "decoder_bound_check",
    "l1_bound_check",
    "l1_reason",
    "lasso_bound_check",
    "lasso_reason",
    "reason",
]

TITLE = "Worst-case error of the l0 decoder under noise"
VALUE_NAME = "certified bound of ||x_hat - x||_2"
METHOD = "l0 decoder's optimality on every set of p - 2s sensors (verified sigma_min of O_K)"


_TOO_FEW = "with {s} attacked sensors no sensor is left unattacked (s >= p)"
_OUT_OF_RANGE = "the observability matrix or the noise bounds leave the floating-point range"
_RECHECK = "the bound did not survive its re-check in rational arithmetic (please report it)"


def _no_margin(system: System, removed: tuple[int, ...]) -> str:
    if not removed:
        return "the sensors over the window do not determine the state with a margin above rounding"
    return (
        f"without the sensors {_names(system, removed)} the others do not determine the state "
        "with a margin above rounding"
    )


def _window_short(
    system: System, removed: tuple[int, ...], horizon: int, longer_helps: bool
) -> str:
    kept = [i for i in range(system.p) if i not in set(removed)]
    steps = f"{horizon} step{'' if horizon == 1 else 's'}"
    attack = (
        f"an attack on {_names(system, removed)} then makes two states give the same data"
        if removed
        else "two states give the same data"
    )
    return (
        f"sensors {_names(system, tuple(kept))} over the window of {steps} do not determine the "
        f"state (an exact kernel vector of their observability matrix): {attack}, so no decoder "
        "over this window has a finite worst-case error"
        + ("; a window of n steps would determine it" if longer_helps else "")
    )


def reason(found: DecoderErrorBound) -> str:
    """Why no finite bound is certified (empty for a certified one)."""
    code, s = found.code, found.max_attacked
    if code is BoundCode.TOO_FEW_SENSORS:
        return (
            f"with {s} attacked sensors no set of sensors is left unattacked in both of two "
            f"explanations of the data (2s = {2 * s} >= p)"
        )
    if code is BoundCode.TOO_MANY_SETS:
        return (
            f"{found.sets:,} sets of p - 2s sensors, more than the limit of "
            f"{found.facts['limit']:,}"
        )
    if code is BoundCode.NO_MARGIN:
        return (
            "some set of p - 2s sensors does not determine the state with a margin above "
            "rounding (its smallest singular value is not proved positive)"
        )
    if code is BoundCode.OUT_OF_RANGE:
        return _OUT_OF_RANGE
    if code is BoundCode.WINDOW_TOO_SHORT:
        return (
            f"sensors {list(found.worst_kept)} over the window of {found.horizon} step"
            f"{'' if found.horizon == 1 else 's'} do not determine the state (an exact kernel "
            "vector of their observability matrix), so no decoder over this window has a finite "
            "worst-case error; a longer horizon may"
        )
    if code is BoundCode.RECHECK_FAILED:
        return _RECHECK
    return ""


def _names(system: System, sensors: tuple[int, ...]) -> str:
    return ", ".join(system.sensors[i] for i in sensors)


def _sensors(count: int) -> str:
    return f"{count} sensor{'' if count == 1 else 's'}"


def _noise_words(found: DecoderErrorBound | LassoErrorBound | L1ErrorBound) -> str:
    if found.sources is None or found.sources.process is None:
        return f"noise within {_bound_words(found.noise, found.horizon)}"
    omega = found.sources.process.omega
    each = (
        f"{readable(float(omega[0]))} on every entry of w"
        if omega.size and (omega == omega[0]).all()
        else "the spec's bound on each entry of w"
    )
    how = (
        "on every sample"
        if found.noise.per_sample
        else f"in 2-norm over the window of {found.horizon} steps"
    )
    top = readable(float(np.max(found.noise.eta))) if found.noise.eta.size else "0"
    return (
        f"measurement noise within {_bound_words(found.sources, found.horizon)} and process "
        f"noise within {each} at every step (together at most {top} at a sensor, {how})"
    )


def _bound_words(noise: MeasurementNoise, horizon: int) -> str:
    eta = noise.eta
    each = (
        f"{readable(float(eta[0]))} on every sensor"
        if eta.size and (eta == eta[0]).all()
        else "the spec's bound on each sensor"
    )
    how = "on every sample" if noise.per_sample else f"in 2-norm over the window of {horizon} steps"
    return f"{each} ({how})"


def noise_fields(found: DecoderErrorBound | LassoErrorBound | L1ErrorBound) -> dict[str, Any]:
    """The check's ``noise`` field (the per-sensor bounds the bound is certified for) and, with
    process noise, ``noise_sources`` (the spec's measurement and process noise they come
    from)."""
    out: dict[str, Any] = {"noise": found.noise.to_dict()}
    if found.sources is not None:
        out["noise_sources"] = found.sources.to_dict()
    return out


def _breaking(system: System, s: int, breaking_set: list[int], common: dict[str, Any]) -> Check:
    """A decoder check that fails with sparse_observability's breaking set: no decoder has a
    finite worst-case error."""
    return Check(
        verdict=Verdict.FAILS,
        summary=f"No decoder has a finite worst-case error: removing sensors "
        f"{_names(system, tuple(breaking_set))} leaves the state unobservable "
        f"(sparse_observability), so two states explain the same data with at most "
        f"{_sensors(s)} attacked, even without noise.",
        value=float("inf"),
        witness={"breaking_set": list(breaking_set)},
        **common,
    )


def _window_fails(
    system: System, removed: tuple[int, ...], horizon: int, why: str, common: dict[str, Any]
) -> Check:
    """A decoder check that fails because the sensors outside ``removed`` over the window
    exactly cannot determine the state (``why`` says so)."""
    kept = [i for i in range(system.p) if i not in set(removed)]
    return Check(
        verdict=Verdict.FAILS,
        summary=f"No worst-case error bound exists: {why}.",
        value=float("inf"),
        witness={"kept_sensors": kept, "horizon": horizon},
        **common,
    )


def decoder_bound_check(system: System, found: DecoderErrorBound) -> Check:
    """The ``decoder_error_bound`` check (advisory) of ``found``: holds with a certified
    bound, fails when a breaking set of at most 2s sensors proves no bound exists, else
    inconclusive with the reason."""
    s, tau = found.max_attacked, found.horizon
    fields: dict[str, Any] = {
        "bound": found.bound,
        "lower_bound": found.lower,
        "worst_kept_sensors": list(found.worst_kept),
        "hardened_bound": found.hardened,
        "sigma_min": found.sigma,
        "smallest_sigma_min": found.smallest_sigma,
        **noise_fields(found),
        "horizon": tau,
        "decoder": "l0",
    }
    evidence: dict[str, Any] = {
        "sets": found.sets,
        "sets_refined_by_svd": found.refined,
        "smallest_sigma_min": found.smallest_sigma,
        "smallest_sigma_kept_sensors": list(found.smallest_kept),
        "noise_block_bounds": found.noise.block_bounds(tau),
        "code": found.code.value,
        "sigma_rechecked_exactly": found.facts.get("sigma_rechecked_exactly"),
    }
    if found.curve:
        evidence["hardening_curve"] = {
            "scale": [f for f, _ in found.curve],
            "bound": [b for _, b in found.curve],
        }
    common: dict[str, Any] = {
        "id": "decoder_error_bound",
        "title": TITLE,
        "method": METHOD,
        "required": False,
        "value_name": VALUE_NAME,
        "fields": fields,
        "code": found.code,
    }
    if found.code is BoundCode.NOT_SPARSE_OBSERVABLE:
        breaking_set = list(found.facts["breaking_set"])
        return _breaking(system, s, breaking_set, {**common, "evidence": evidence})
    if found.code is BoundCode.WINDOW_TOO_SHORT:
        return Check(
            verdict=Verdict.FAILS,
            summary=f"No worst-case error bound exists: {reason(found)}.",
            value=float("inf"),
            evidence=evidence,
            witness={"kept_sensors": list(found.worst_kept), "horizon": tau},
            **common,
        )
    if found.code is not BoundCode.CERTIFIED:
        return Check(
            verdict=Verdict.INCONCLUSIVE,
            summary=f"No worst-case error bound is certified: {reason(found)}.",
            value=float("inf"),
            evidence=evidence,
            **common,
        )
    pair = worst_case_pair(system, found)
    if pair is not None:
        evidence["lower_bound_construction"] = {
            "direction": pair["direction"],
            "scale": pair["scale"],
            "attacked": pair["attacked"],
            "attacked_other": pair["attacked_other"],
            "kept": list(found.lower_kept),
            "measurements": pair["measurements"],
        }
    kept = _names(system, found.worst_kept)
    tolerance = (
        f" A decoder that accepts residuals within rtol ||y|| of the least (ssecert's "
        f"l0_decoder: rtol = 1e-9) may be off by up to rtol ||y|| / "
        f"{readable(found.smallest_sigma)} more."
        if found.smallest_sigma > 0
        else ""
    )
    lower = (
        f"; no decoder can guarantee less than {readable(found.lower)} (two states explain the "
        f"same data with the noise and attacks allowed)"
        if found.lower > 0
        else ""
    )
    return Check(
        verdict=Verdict.HOLDS,
        summary=f"With {_noise_words(found)} and any attack on at most {_sensors(s)}, the l0 "
        f"decoder's estimate of the window's first state (the support of {_sensors(s)} whose "
        f"removal leaves the least residual) is within {readable(found.bound)} of the truth "
        f"(2-norm){lower}. The bound is largest with sensors {kept} kept (smallest singular "
        f"value of their observability matrix at least {readable(found.sigma)}"
        + (
            ", re-checked in rational arithmetic on the exact data"
            if found.facts.get("sigma_rechecked_exactly")
            else ""
        )
        + f"); halving their {'measurement noise' if found.sources is not None else 'noise'} "
        f"gives {readable(found.hardened)}"
        + (" (the process noise's reach stays)" if found.sources is not None else "")
        + f".{tolerance}",
        value=found.bound,
        evidence=evidence,
        **common,
    )


LASSO_TITLE = "Worst-case error of the Lasso decoder under noise"
LASSO_VALUE_NAME = "certified bound of ||x_hat - x||_2 (lambda -> lambda_min)"
LASSO_METHOD = (
    "primal-dual witness on every support of s sensors: the irrepresentable constant below 1 "
    "and lambda above the noise's reach, verified for the exact plant"
)


def lasso_reason(found: LassoErrorBound, system: System) -> str:
    """Why no finite Lasso bound is certified (empty for a certified one)."""
    code, s = found.code, found.max_attacked
    if code is LassoBoundCode.NOT_IRREPRESENTABLE:
        return (
            f"the irrepresentable constant reaches {readable(found.rho)} >= 1 on the attack "
            f"support {_names(system, found.rho_support)} (the largest of the {found.sets:,} "
            "supports), so the witness that bounds the Lasso's error does not exist there; the "
            "condition is sufficient, not necessary: the Lasso may still do well, but nothing "
            "here proves it"
        )
    if code is LassoBoundCode.LAMBDA_TOO_SMALL:
        return (
            f"lambda = {readable(found.lam)} is not above lambda_min = "
            f"{readable(found.lam_min)}, below which the noise alone may move the attack "
            "estimate off its support"
        )
    if code is LassoBoundCode.NO_MARGIN:
        return (
            f"{_no_margin(system, found.worst_support)} (the Lasso's solution is not proved unique)"
        )
    if code is LassoBoundCode.WINDOW_TOO_SHORT:
        return _window_short(
            system,
            found.worst_support,
            found.horizon,
            bool(found.facts.get("longer_horizon_helps")),
        )
    if code is LassoBoundCode.TOO_FEW_SENSORS:
        return _TOO_FEW.format(s=s)
    if code is LassoBoundCode.TOO_MANY_SETS:
        facts = found.facts
        return (
            f"{found.sets:,} supports of s sensors (the limit: {facts['limit']:,}), about "
            f"{facts['work']:.2g} floating-point operations (the limit: "
            f"{facts['work_limit']:.2g})"
        )
    if code is LassoBoundCode.OUT_OF_RANGE:
        return _OUT_OF_RANGE
    if code is LassoBoundCode.RECHECK_FAILED:
        return _RECHECK
    return ""


def lasso_bound_check(
    system: System, found: LassoErrorBound, breaking_set: list[int] | None = None
) -> Check:
    """The ``lasso_error_bound`` check (advisory) of ``found``: holds with a certified bound,
    fails when sparse_observability's breaking set proves no decoder has one, else
    inconclusive with the reason."""
    s, tau = found.max_attacked, found.horizon
    certified = found.code is LassoBoundCode.CERTIFIED
    fields: dict[str, Any] = {
        "bound": found.bound,
        "lambda": found.lam if certified else None,
        "lambda_min": found.lam_min,
        "noise_term": found.noise_term,
        "bias_per_lambda": found.kappa,
        "irrepresentable_constant": found.rho,
        "irrepresentable_support": list(found.rho_support),
        "lambda_support": list(found.lam_support),
        "worst_support": list(found.worst_support),
        "sigma_min": found.sigma,
        **noise_fields(found),
        "horizon": tau,
        "decoder": "lasso",
    }
    evidence: dict[str, Any] = {"supports": found.sets, "code": found.code.value}
    if certified:
        evidence["deciding_support_terms"] = {
            "lambda_support": {
                "rho": found.facts["deciding_rho"],
                "delta": found.facts["deciding_delta"],
            },
            "worst_support": {
                "beta": found.facts["worst_beta"],
                "kappa": found.facts["worst_kappa"],
            },
        }
    common: dict[str, Any] = {
        "id": "lasso_error_bound",
        "title": LASSO_TITLE,
        "method": LASSO_METHOD,
        "required": False,
        "value_name": LASSO_VALUE_NAME,
        "fields": fields,
        "code": found.code,
        "evidence": evidence,
    }
    if breaking_set is not None:
        return _breaking(system, s, breaking_set, common)
    if found.code is LassoBoundCode.WINDOW_TOO_SHORT:
        why = lasso_reason(found, system)
        return _window_fails(system, found.worst_support, tau, why, common)
    if not certified:
        return Check(
            verdict=Verdict.INCONCLUSIVE,
            summary=f"No worst-case error bound of the Lasso decoder is certified: "
            f"{lasso_reason(found, system)}.",
            value=float("inf"),
            **common,
        )
    noise_words = _noise_words(found)
    reached = lasso_worst_case(system, found)
    lower = ""
    if reached is not None:
        fields["lower_bound"] = reached["lower"]
        evidence["lower_bound_construction"] = {
            "support": list(reached["support"]),
            "lambda": reached["lam"],
            "attack": reached.get("attack"),
            "noise": reached.get("noise"),
            "error": reached.get("error"),
        }
        if reached["lower"] > 0:
            attack = (
                f" and an attack on {_names(system, reached['support'])} drive"
                if reached["support"]
                else " drives"
            )
            lower = (
                f" A noise within the bounds{attack} its error to "
                f"{readable(reached['lower'])} at lambda = {readable(reached['lam'])} (from "
                f"x = 0: lower_bound_construction): the worst case lies between the two."
            )
    return Check(
        verdict=Verdict.HOLDS,
        summary=f"With {noise_words} and any attack on at most {_sensors(s)}, the partial Lasso "
        f"decoder (1/2 ||Y - O x - a||^2 + lambda ||a||_1 over the window) with any weight "
        f"lambda > {readable(found.lam_min)} estimates the window's first state within "
        f"{readable(found.noise_term)} + {readable(found.kappa)} lambda of the truth (2-norm): "
        f"the noise's reach on the sensors outside the attack, plus the l1 penalty's bias; "
        f"{readable(found.bound)} as lambda comes down to lambda_min. The irrepresentable "
        f"constant is at most {readable(found.rho)} < 1 on every support of {_sensors(s)} "
        f"(largest on {_names(system, found.rho_support) or 'the empty support'}), so the "
        f"attack estimate stays on the attacked sensors; lambda_min is set by the support "
        f"{_names(system, found.lam_support) or 'of no sensor'}.{lower}",
        value=found.bound,
        **common,
    )


L1_TITLE = "Worst-case error of the l1 decoder under noise"
L1_VALUE_NAME = "certified bound of ||x_hat - x||_2"
L1_METHOD = (
    "the l1 decoder's optimality on every set of s sensors, with the null-space constant bounded "
    "by linear-programming duals made exactly feasible"
)


def l1_reason(found: L1ErrorBound, system: System) -> str:
    """Why no finite l1 bound is certified (empty for a certified one)."""
    code, s = found.code, found.max_attacked
    if code is L1BoundCode.NOT_NULL_SPACE and not math.isfinite(found.theta):
        return (
            f"the null-space constant of sensors {_names(system, found.theta_support)} is not "
            "proved below 1 (its linear programs' duals did not bound it)"
        )
    if code is L1BoundCode.NOT_NULL_SPACE:
        return (
            f"the null-space constant reaches {readable(found.theta)} >= 1 on sensors "
            f"{_names(system, found.theta_support)}: an attack there may move the l1 "
            "decoder's estimate even without noise (or the bound is not proved below 1)"
        )
    if code is L1BoundCode.NO_MARGIN:
        return _no_margin(system, found.worst_support)
    if code is L1BoundCode.WINDOW_TOO_SHORT:
        return _window_short(
            system,
            found.worst_support,
            found.horizon,
            bool(found.facts.get("longer_horizon_helps")),
        )
    if code is L1BoundCode.TOO_FEW_SENSORS:
        return _TOO_FEW.format(s=s)
    if code is L1BoundCode.TOO_MANY_PROGRAMS:
        count = f"{found.programs:,}" if found.programs < 10**7 else f"about {found.programs:.2g}"
        return (
            f"{count} linear programs (sets of s sensors times the sign patterns of their rows "
            f"over the window), more than the limit of {found.facts['limit']:,}"
        )
    if code is L1BoundCode.NOT_SOLVED:
        return "a linear program was not solved, or the numbers leave the floating-point range"
    if code is L1BoundCode.RECHECK_FAILED:
        return _RECHECK
    return ""


def _l1_lower_words(system: System, found: L1ErrorBound) -> str:
    """The sentence on the l1 decoder's own worst case beside its bound (empty without one)."""
    if not found.lower > 0:
        return ""
    attacked = tuple(i for i in range(system.p) if i not in found.lower_kept)
    return (
        f" The decoder itself errs by {readable(found.lower)} on a window built for it "
        f"(noise within the bounds on {_names(system, found.lower_kept)}, an attack on "
        f"{_names(system, attacked) or 'no sensor'}: data explained exactly by a state that "
        f"far away, which it returns), so the bound is within "
        f"{readable(found.bound / found.lower)}x of its worst case."
    )


def l1_bound_check(
    system: System, found: L1ErrorBound, breaking_set: list[int] | None = None
) -> Check:
    """The ``l1_error_bound`` check (advisory) of ``found``: holds with a certified bound,
    fails when sparse_observability's breaking set proves no decoder has one, else
    inconclusive with the reason."""
    s = found.max_attacked
    fields: dict[str, Any] = {
        "bound": found.bound,
        "lower_bound": found.lower,
        "null_space_constant": found.theta,
        "null_space_support": list(found.theta_support),
        "worst_support": list(found.worst_support),
        "sigma_min": found.sigma,
        "inverse_reach": found.reach,
        "noise_l1": found.noise_l1,
        **noise_fields(found),
        "horizon": found.horizon,
        "decoder": "l1",
    }
    evidence: dict[str, Any] = {
        "sets": found.sets,
        "linear_programs": found.programs,
        "code": found.code.value,
        "lower_bound_kept_sensors": list(found.lower_kept),
    }
    common: dict[str, Any] = {
        "id": "l1_error_bound",
        "title": L1_TITLE,
        "method": L1_METHOD,
        "required": False,
        "value_name": L1_VALUE_NAME,
        "fields": fields,
        "code": found.code,
        "evidence": evidence,
    }
    if breaking_set is not None:
        return _breaking(system, s, breaking_set, common)
    if found.code is L1BoundCode.WINDOW_TOO_SHORT:
        why = l1_reason(found, system)
        return _window_fails(system, found.worst_support, found.horizon, why, common)
    if found.code is not L1BoundCode.CERTIFIED:
        return Check(
            verdict=Verdict.INCONCLUSIVE,
            summary=f"No worst-case error bound of the l1 decoder is certified: "
            f"{l1_reason(found, system)}.",
            value=float("inf"),
            **common,
        )
    return Check(
        verdict=Verdict.HOLDS,
        summary=f"With {_noise_words(found)} and any attack on at most {_sensors(s)}, the l1 "
        f"decoder (argmin ||Y - O x||_1 over the window) estimates the window's first state "
        f"within {readable(found.bound)} of the truth (2-norm). The null-space constant is at "
        f"most {readable(found.theta)} < 1 on every set of {_sensors(s)} (largest on "
        f"{_names(system, found.theta_support) or 'the empty set'}); the bound is largest with "
        f"the attack on {_names(system, found.worst_support) or 'no sensor'}: 2 ||w_K||_1 "
        f"||O_K^+||_(1->2) / (1 - theta), ||O_K^+||_(1->2) at most {readable(found.reach)}."
        + _l1_lower_words(system, found),
        value=found.bound,
        **common,
    )
