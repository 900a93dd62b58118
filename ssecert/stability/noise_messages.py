"""The words of the observer's noise bound: the ``observer_noise_bound`` check.

``ssecert.stability.noise_gain`` computes the bounds (``linear_noise_bound``: a
``NoiseGain`` with its ``NoiseGainCode`` for a linear observer;
``dissipation_bound`` from iss_gain's certificate for a sparse one); this
module builds the check of either (``noise_check``), with the noise search
beside it, and writes what a user reads.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from ..base.format import readable
from ..noise import MeasurementNoise
from ..observers import ObserverDesign
from ..observers.lure import scaling_text
from ..results import Check, Verdict
from .divergence import safe_norms
from .noise_gain import (
    BalancedNoise,
    DissipationBound,
    LocalNoise,
    NoiseGain,
    NoiseGainCode,
    balanced_noise_bound,
    decay_scan,
    decaying_certificate,
    dissipation_bound,
    linear_noise_bound,
    split_as_dissipation,
    split_bound,
    tighter_noise_bound,
)

__all__ = [
    "noise_check",
    "observer_noise_check",
    "sparse_noise_check",
    "reason",
    "applies_to",
    "initial_error_fading",
    "process_certificate",
    "measurement_rows",
    "ascent_text",
]

TITLE = "Ultimate error of the observer under noise"
VALUE_NAME = "certified ultimate bound of ||x_hat - x||_2"
METHOD = (
    "worst-case series sum_j |F^j L| eta (plus |F^j G| omega with process noise) in interval "
    "arithmetic, tail bounded by a power of F below 1 in norm"
)


def applies_to(design: ObserverDesign) -> bool:
    """Whether the observer is linear (no attack estimate, one sample at a time)."""
    return not design.sparse and design.window == 1


def noise_enters_as_attack(design: ObserverDesign, model: Any) -> bool:
    """Whether the error model's attack input is the observer's measurement vector (its rows
    one for one) and its first block the estimation error: then noise enters as an attack on
    every row does, and a dissipation inequality in the attack bounds the error under it."""
    return bool(model.r == design.sensing.shape[0] and model.n_e == design.system.n)


def noise_check(design: ObserverDesign, noise: MeasurementNoise, iss: Check) -> Check:
    """The ``observer_noise_bound`` check of any observer: the worst-case series of a linear
    one (``observer_noise_check``), the dissipation inequality of iss_gain's certificate for
    the others (``sparse_noise_check``)."""
    if applies_to(design):
        return observer_noise_check(design, noise, iss)
    return sparse_noise_check(design, iss, noise)


def measurement_rows(design: ObserverDesign, noise: MeasurementNoise) -> np.ndarray | None:
    """The bound on each entry of the observer's measurement vector: each sensor's bound, and
    over a window of several samples (an SSO's stacked measurements, from the window's first
    state, the one it estimates) the process noise's reach at each sample added
    (``MeasurementNoise.window_rows``); None where a bound leaves the float range."""
    system = design.system
    return noise.window_rows(system.A, system.C, design.sensing.shape[0])


def reason(found: NoiseGain) -> str:
    """Why no bound is certified (empty for a certified one)."""
    if found.code is NoiseGainCode.NOT_CONTRACTIVE:
        return (
            f"no power of F = A - L C up to F^{found.facts.get('max_terms', 0)} is proved below "
            "1 in norm (observer_gain decides its stability)"
        )
    if found.code is NoiseGainCode.OUT_OF_RANGE:
        return (
            "F, L or the noise bounds leave the floating-point range, or their rounding is unknown"
        )
    return ""


def _no_bound(
    summary: str,
    evidence: dict[str, Any],
    common: dict[str, Any],
    noise: MeasurementNoise,
    energy: float | None = None,
) -> Check:
    """An inconclusive ``observer_noise_bound`` check with its reason (and the energy gain
    where one is certified)."""
    fields: dict[str, Any] = {"ultimate_bound": math.inf, "noise": noise.to_dict()}
    if energy is not None:
        fields["energy_gain"] = energy
    return Check(
        verdict=Verdict.INCONCLUSIVE,
        summary=summary,
        value=math.inf,
        fields=fields,
        evidence=evidence,
        **common,
    )


def sparse_noise_check(design: ObserverDesign, iss: Check, noise: MeasurementNoise) -> Check:
    """The ``observer_noise_bound`` check of an observer certified by a dissipation inequality
    with decay (``iss``, the iss_gain check): noise enters the error dynamics as an attack on
    every sensor does, so V+ - V <= -alpha V - |e|^2 + gamma^2 |n|^2 gives, without attack,
    limsup V <= gamma^2 N^2 / alpha (N >= |n(k)|, each entry of the observer's measurement
    vector within its sensor's bound) and |e|^2 <= V lambda_max((P^-1)_ee); the smallest of
    that bound and of ``noise_gain.decay_scan``'s (the inequality without -|e|^2, at decays
    from iss_gain's up) is the one reported."""
    common: dict[str, Any] = {
        "id": "observer_noise_bound",
        "title": TITLE,
        "method": "ISS dissipation inequality with decay (iss_gain's verified certificate)",
        "required": False,
        "value_name": VALUE_NAME,
    }
    alpha = iss.fields.get("alpha")
    gamma = iss.fields.get("gamma")
    P = iss.evidence.get("P")
    # a Zames-Falb gain certifies no decay (alpha 0): it bounds the error's energy only
    if iss.verdict is not Verdict.HOLDS or not alpha or gamma is None or P is None:
        why = (
            "iss_gain certifies no gain"
            if iss.verdict is not Verdict.HOLDS
            else "iss_gain's certificate has no decay (alpha = 0), so it bounds the error's "
            "energy, not its size"
        )
        # without decay, iss_gain's gain still bounds the error's energy under measurement
        # noise, which enters as an attack on every row of the measurement vector does
        energy, energy_words = None, ""
        if (
            iss.verdict is Verdict.HOLDS
            and gamma is not None
            and noise.process is None
            and noise_enters_as_attack(design, design.observer_kind.lure_model(design))
        ):
            energy, energy_words = _energy(iss, design)
        local = _local_check(design, noise, common, why, energy, energy_words)
        if local is not None:
            return local
        return _no_bound(
            f"No ultimate error bound under noise is certified: {why}." + energy_words,
            {"from": "iss_gain"},
            common,
            noise,
            energy,
        )
    rows = design.sensing.shape[0]
    model = design.observer_kind.lure_model(design)
    if not noise_enters_as_attack(design, model):
        return _no_bound(
            "No ultimate error bound under noise is certified: the error model's "
            f"attack input ({model.r} entries) is not the observer's measurement vector "
            f"({rows} rows).",
            {"from": "iss_gain"},
            common,
            noise,
        )
    found_rows = measurement_rows(design, noise)
    if found_rows is None:
        return _no_bound(
            "No ultimate error bound under noise is certified: the process noise's "
            "reach at the window's samples leaves the floating-point range.",
            {"from": "iss_gain", "cause": "process noise"},
            common,
            noise,
        )
    per_row = found_rows
    n = design.system.n
    source, origin = "iss_gain's certificate", "iss_gain"
    noise_model = model
    found: DissipationBound | None = None
    T = iss.evidence.get("multipliers_T")  # the sector multipliers of the inequality used
    if noise.process is None:
        P = np.asarray(P, dtype=float)
        found = dissipation_bound(P, float(alpha), float(gamma), per_row, n)
    else:
        # the process noise enters the error as -G w: a further input of the error model, the
        # dissipation inequality certified again with it, at iss_gain's decay
        # (its columns weighed like the measurement rows, and in the spec's units: one gain
        # for both noises, so where one noise is far smaller than the other the first can be
        # far looser; the smaller bound at iss_gain's decay chooses, the scan below follows)
        rows_alone, chosen = per_row, None
        for own_units in (False, True):
            variant, w_bounds = process_model(design, model, noise, rows_alone, own_units=own_units)
            if chosen is not None and np.array_equal(w_bounds, chosen[1][rows_alone.size :]):
                break  # (the same columns: nothing new to solve)
            rows_v = np.concatenate([rows_alone, w_bounds])
            cert = decaying_certificate(variant, float(alpha))
            bound_v = None
            if cert is not None:
                P_v, a_v, g_v = np.asarray(cert.P, dtype=float), cert.decay, cert.gamma
                bound_v = dissipation_bound(P_v, float(a_v), float(g_v), rows_v, n)
            if chosen is None or (
                bound_v is not None
                and not bound_v.ill_conditioned
                and (
                    chosen[2] is None
                    or chosen[2].ill_conditioned
                    or bound_v.bound < chosen[2].bound
                )
            ):
                chosen = (variant, rows_v, bound_v, cert)
        assert chosen is not None
        noise_model, per_row, found, cert = chosen
        if cert is not None:
            P, alpha, gamma = np.asarray(cert.P, dtype=float), cert.decay, cert.gamma
            T = cert.multipliers
        source = "a dissipation inequality with the process noise as a further input"
        origin = "process noise as a further input"
        common["method"] = (
            "ISS dissipation inequality with decay, the process noise a further input of the "
            "error model (verified as iss_gain's)"
        )
    # the inequality without the output's term at iss_gain's decay and faster ones: where it
    # gives a smaller bound, that bound
    scan_tried: list[dict[str, float]] = []
    scan = decay_scan(noise_model, float(iss.fields["alpha"]), per_row, n, tried=scan_tried)
    if scan is not None and (
        found is None or found.ill_conditioned or scan.found.bound < found.bound
    ):
        found, P, alpha, gamma = scan.found, scan.P, scan.alpha, scan.gamma
        T = scan.multipliers
        if noise.process is None:
            origin = "decay scan"
        source = (
            f"a dissipation inequality V+ - V <= -alpha V + gamma^2 |n|^2 at decay "
            f"{readable(scan.alpha)}"
            + (", the process noise a further input" if noise.process is not None else "")
            + " (verified as iss_gain's, the smallest bound of the decays tried)"
        )
        common["method"] = (
            "ISS dissipation inequality with decay, the smallest ultimate bound over the decays "
            "tried" + (", the process noise a further input of the error model"
                       if noise.process is not None else "") + " (verified as iss_gain's)"
        )  # fmt: skip
    formula = "limsup V <= gamma^2 N^2 / alpha"
    weight_evidence: dict[str, Any] = {}
    weights = row_weights(per_row) if noise.process is None else None
    if weights is not None:
        # sensors of unlike noise: the same scan for the noise written n = diag(2^k) nu, each
        # row's weight near its bound over the largest, so that the LMI weighs the noisy
        # rows more than the precise ones (often far smaller; never taken when larger)
        # (from the unweighted scan's best decay, where its LMI is known to verify)
        weighted_tried: list[dict[str, float]] = []
        weighted = decay_scan(
            noise_model.input_scaled(weights),
            float(iss.fields["alpha"]) if scan is None else scan.alpha,
            per_row / np.ldexp(1.0, weights),
            n,
            tried=weighted_tried,
        )
        if weighted is not None and (
            found is None or found.ill_conditioned or weighted.found.bound < found.bound
        ):
            found, P, alpha, gamma = weighted.found, weighted.P, weighted.alpha, weighted.gamma
            T = weighted.multipliers
            origin = "decay scan, rows weighted"
            source = (
                f"a dissipation inequality V+ - V <= -alpha V + gamma^2 |nu|^2 at decay "
                f"{readable(weighted.alpha)} for the noise written n = diag(2^k) nu (each "
                "row's weight 2^k a power of two near its bound over the largest, k in the "
                "evidence's row_weights_log2, so |nu_i| <= eta_i 2^-k_i; verified as iss_gain's, "
                "the smallest bound of the decays tried)"
            )
            common["method"] = (
                "ISS dissipation inequality with decay, the noise's rows weighted, the "
                "smallest ultimate bound over the decays tried (verified as iss_gain's)"
            )
        weight_evidence = {
            "row_weights_log2": weights.tolist(),
            "weighted_decays_tried": weighted_tried,
        }
    split_evidence: dict[str, Any] = {}
    if noise.process is not None:
        # iss_gain's own inequality (measurement noise only) with the process noise's step
        # split off: no further LMI, so it holds whatever the process noise's size
        P_iss = np.asarray(iss.evidence["P"], dtype=float)
        a_iss, g_iss = float(iss.fields["alpha"]), float(iss.fields["gamma"])
        process = noise.process
        G, omega = process.input, process.omega
        split = split_bound(P_iss, a_iss, g_iss, found_rows, G, omega, n)
        # faster decays of the measurement-noise inequality (the decay scan without w as an
        # input) split the same way: often much smaller (and, as the process noise vanishes,
        # the bound without it)
        faster = None
        if math.isfinite(split.bound):
            faster = decay_scan(
                model, a_iss, found_rows, n,
                bound_of=lambda P_, a_, g_: split_as_dissipation(
                    split_bound(P_, a_, g_, found_rows, G, omega, n)
                ),
            )  # fmt: skip
        smallest = split.bound
        if faster is not None and faster.found.bound < smallest:
            smallest = faster.found.bound
        if math.isfinite(smallest) and (
            found is None or found.ill_conditioned or smallest < found.bound
        ):
            found = split_as_dissipation(split)
            P, alpha, gamma = P_iss, a_iss, g_iss
            T = iss.evidence.get("multipliers_T")
            source = (
                "iss_gain's inequality (measurement noise only) with the process noise's step "
                "split off"
            )
            if faster is not None and faster.found.bound < found.bound:
                P, alpha, gamma, scan = faster.P, faster.alpha, faster.gamma, faster
                T = faster.multipliers
                scan_tried = faster.tried
                split = split_bound(P, alpha, gamma, found_rows, G, omega, n)
                found = split_as_dissipation(split)
                source = (
                    "a measurement-noise inequality V+ - V <= -alpha V + gamma^2 |n|^2 at "
                    f"decay {readable(alpha)} (verified as iss_gain's, the smallest bound of the "
                    "decays tried) with the process noise's step split off"
                )
            origin = "process noise split off"
            formula = (
                "limsup V <= ((1 + eps) gamma^2 N^2 + (1 + 1/eps) W^2) / (1 - (1 + eps)(1 - "
                f"alpha)) at eps = {readable(split.split)} and W = {readable(split.process_reach)} "
                "(the process noise's largest step in V's norm),"
            )
            common["method"] = (
                "ISS dissipation inequality with decay (iss_gain's), the process noise's step "
                "split off"
            )
            split_evidence = {
                "process_reach_P": split.process_reach,
                "split": split.split,
                "P": np.asarray(P, dtype=float),
            }
    if found is None:
        return _no_bound(
            "No ultimate error bound under noise is certified: no dissipation "
            "inequality with decay is verified with the process noise as a further input "
            f"of the error model (at iss_gain's decay {readable(float(alpha))} or faster).",
            {"from": "process noise as a further input", "cause": "process noise"},
            common,
            noise,
        )
    cond, top, bound = found.condition, found.top, found.bound
    if found.ill_conditioned:
        return _no_bound(
            "No ultimate error bound under noise is certified: iss_gain's P is too "
            f"ill-conditioned (condition number {readable(cond)}) to invert with a known error.",
            {"from": origin, "condition_P": cond},
            common,
            noise,
        )
    search = noise_search(design, noise)
    # iss_gain's energy gain is from the measurement noise alone: with process noise, none
    energy, energy_words = _energy(iss, design) if noise.process is None else (None, "")
    if math.isfinite(bound) and not search["largest_error"] <= bound:
        return _no_bound(
            "No ultimate error bound under noise is certified: a simulated noise "
            f"within the bounds drove the error to {readable(search['largest_error'])}, above "
            f"the bound {readable(bound)} {source} gives (please report this design).",
            {"from": origin, "noise_search": search, "bound_found": bound},
            common,
            noise,
        )
    if not math.isfinite(bound):
        return _no_bound(
            "No ultimate error bound under noise is certified: it leaves the floating-point range.",
            {"from": origin},
            common,
            noise,
        )
    if 0 < bound < 2.0**-1022:  # a subnormal product is rounded: take it up
        bound = float(np.nextafter(bound, np.inf))
    hardening: dict[str, Any] = {}
    harden_words = ""
    if noise.process is None:
        # the same inequality bounds the error under any smaller noise: N from the rows of
        # the noise with one sensor's bound halved (divided by the rows' weights, if any)
        by_rows = origin == "decay scan, rows weighted"
        divide = np.ldexp(1.0, weights) if by_rows and weights is not None else 1.0

        def harden(scale: np.ndarray) -> float:
            rows = measurement_rows(design, _scaled_noise(noise, scale))
            if rows is None:
                return math.inf
            return dissipation_bound(P, float(alpha), float(gamma), rows / divide, n).bound

        hardening, harden_words = _hardening_fields(
            design, noise.eta, sensor_hardening(noise.eta, harden)
        )
    return Check(
        verdict=Verdict.HOLDS,
        summary=f"Without attack and with noise within the spec's bounds on every sample, the "
        f"estimation error {settles(bound)} (2-norm), from {source}: "
        f"{formula} with gamma = {readable(float(gamma))}, "
        f"alpha = {readable(float(alpha))} and N = {readable(found.noise_norm)}. A search "
        f"over {search['sequences']} noise sequences within the bounds (from zero error, "
        f"{search['steps']} steps{ascent_text(search)}) reached "
        f"{readable(search['largest_error'])}." + harden_words + energy_words,
        value=bound,
        fields={
            "ultimate_bound": bound,
            "energy_gain": energy,
            "noise": noise.to_dict(),
            **hardening,
        },
        evidence={
            "from": origin,
            "gamma": gamma,
            "alpha": alpha,
            "noise_norm_per_step": found.noise_norm,
            "lambda_max_P_inverse_ee": top,
            "lambda_max_P_ee": float(np.max(np.linalg.eigvalsh(0.5 * (P[:n, :n] + P[:n, :n].T)))),
            "condition_P": cond,
            "noise_search": search,
            # the decays the inequality without the output's term was tried at, and the bound of
            # each (inf: not verified); the smallest bound of these and iss_gain's is the one
            "decays_tried": scan_tried,
            "P": np.asarray(P, dtype=float),
            # the sector multipliers T of the dissipation inequality the summary names (with
            # P, alpha and gamma: its LMI is iss_gain's, of the error model it names)
            "multipliers_T": None if T is None else np.asarray(T, dtype=float),
            **weight_evidence,
            **split_evidence,
        },
        **common,
    )


HARDEN_SENSORS = 64  # sensors whose noise is halved one at a time (the noisiest, beyond)


def sensor_hardening(
    eta: np.ndarray, bound_of: Callable[[np.ndarray], float]
) -> tuple[int | None, float, int] | None:
    """The sensor to harden: the one whose noise bound halved lowers the certified bound the
    most (None where several lower it alike, to a relative 1e-9: the certificate does not
    tell them apart), that bound (``bound_of(scale)`` certifies one with sensor i's bound
    times scale[i], from the same certificate), and how many sensors were tried (every
    sensor with noise, or the ``HARDEN_SENSORS`` noisiest); None where no sensor has noise.

    Examples
    --------
    >>> sensor_hardening(np.array([1.0, 3.0]), lambda scale: float(scale @ [1.0, 3.0]))
    (1, 2.5, 2)
    >>> sensor_hardening(np.array([1.0, 1.0]), lambda scale: float(scale @ [1.0, 1.0]))
    (None, 1.5, 2)
    """
    noisy = np.flatnonzero(np.asarray(eta) > 0)
    if noisy.size > HARDEN_SENSORS:
        noisy = np.sort(noisy[np.argsort(-eta[noisy], kind="stable")[:HARDEN_SENSORS]])
    bounds = []
    for i in noisy.tolist():
        scale = np.ones(eta.size)
        scale[i] = 0.5
        bounds.append(float(bound_of(scale)))
    if not bounds:
        return None
    best = int(np.argmin(bounds))
    tied = sum(1 for b in bounds if b <= bounds[best] * (1 + 1e-9))
    return (int(noisy[best]) if tied == 1 else None), bounds[best], int(noisy.size)


def _hardening_fields(
    design: ObserverDesign, eta: np.ndarray, found: tuple[int | None, float, int] | None
) -> tuple[dict[str, Any], str]:
    """The check's fields naming the sensor to harden (None where the certificate does not
    tell the sensors apart), and the summary's sentence."""
    if found is None or not math.isfinite(found[1]):
        return {}, ""
    sensor, bound, tried = found
    noisy = int(np.count_nonzero(eta > 0))
    among = "" if tried >= noisy else f" (of the {tried} noisiest sensors)"
    if sensor is None:
        return (
            {"worst_sensor": None, "hardened_bound": bound},
            f" Halving the noise bound of any one of several sensors lowers it alike{among}, "
            f"to {readable(bound)} (the certificate does not tell them apart).",
        )
    name = design.system.sensors[sensor]
    return (
        {"worst_sensor": name, "hardened_bound": bound},
        f" Halving sensor {name}'s noise bound lowers it the most{among}, to {readable(bound)}.",
    )


def _scaled_noise(noise: MeasurementNoise, scale: np.ndarray) -> MeasurementNoise:
    """``noise`` with each sensor's bound times ``scale``."""
    return replace(noise, eta=noise.eta * scale)


def settles(bound: float) -> str:
    """What an ultimate bound says of the error: it eventually stays within a positive one;
    with 0 (the noise does not reach the error) it converges to 0, which it may never reach.

    Examples
    --------
    >>> settles(0.0), settles(0.25)
    ('converges to 0', 'eventually stays within 0.25')
    """
    return "converges to 0" if bound == 0 else f"eventually stays within {readable(bound)}"


WEIGHT_FLOOR = -20  # the smallest row weight, 2^-20 (a row without noise gets it)


def row_weights(per_row: np.ndarray) -> np.ndarray | None:
    """The exponents k of the rows' weights 2^k: each row's bound over the largest, rounded to
    a power of two, at least 2^``WEIGHT_FLOOR``; None where they are all 1 (the rows' bounds
    within a factor of sqrt(2) of the largest) or no row has noise.

    Examples
    --------
    >>> row_weights(np.array([1e-3, 1e-3, 1e-1, 0.0])).tolist()
    [-7, -7, 0, -20]
    """
    rows = np.asarray(per_row, dtype=float)
    top = float(np.max(rows, initial=0.0))
    if not top > 0 or not math.isfinite(top):
        return None
    with np.errstate(divide="ignore"):
        k = np.round(np.log2(rows / top))
    k = np.maximum(np.where(rows > 0, k, WEIGHT_FLOOR), WEIGHT_FLOOR).astype(np.int64)
    return k if np.any(k) else None


def _error_model(design: ObserverDesign) -> Any:
    """The observer's Lur'e model, or for a design without one (an SSO with several inner
    steps a sample) its dead zone's with the noise as its input (``dead_zone_model``: the
    error dynamics while it estimates no attack); None when there is neither."""
    kind = design.observer_kind
    try:
        return kind.lure_model(design)
    except NotImplementedError:
        if kind.dead_zone_refusal(design):
            return None
        return kind.dead_zone_model(design, noise=True)


def _local_check(
    design: ObserverDesign,
    noise: MeasurementNoise,
    common: dict[str, Any],
    why: str,
    energy: float | None,
    energy_words: str,
) -> Check | None:
    """The ``observer_noise_bound`` check of a sparse observer certified only near zero error
    (``noise_gain.local_noise_bound`` in the dead zone's invariant set, its Lyapunov matrix
    that of the region of attraction's dead zone), holding from the initial errors it names;
    None where the observer has no dead zone, the noise does not enter as an attack or the
    dead zone's region is not certified (the global reason then stands), an inconclusive
    check with the local reason where the dead zone's function does not absorb the noise."""
    from .roa import dead_zone_region

    model = _error_model(design)
    if model is None:
        return None
    if model.m == 0 or not model.threshold > 0 or not noise_enters_as_attack(design, model):
        return None
    per_row = measurement_rows(design, noise)
    if per_row is None:
        return None
    measured = per_row.size
    region, q_identity = dead_zone_region(model)
    if region.radius <= 0 or region.evidence.get("P") is None:
        return None
    noise_model = model
    if noise.process is not None:
        noise_model, w_bounds = process_model(design, model, noise, per_row)
        per_row = np.concatenate([per_row, w_bounds])
    n = design.system.n
    # the region's P (chosen for the largest region, often with a slow decrease) and the
    # discrete Lyapunov equation's with Q = I (a faster one): the smaller bound
    candidates = [(np.asarray(region.evidence["P"], dtype=float), region.evidence.get("P_from"))]
    if q_identity is not None:  # (the region's own first candidate, solved once)
        candidates.append(
            (np.asarray(q_identity, dtype=float), "discrete Lyapunov equation with Q = I")
        )
    functions = [(LocalNoise(noise_model, P, n), P, by) for P, by in candidates]
    tried = [(f.bound(per_row), f, P, by) for f, P, by in functions]
    found, function, P, P_from = min(tried, key=lambda t: (t[0].bound, -t[0].radius))
    evidence: dict[str, Any] = {
        "from": "dead zone",
        "global_reason": why,
        "rho": found.rho,
        "noise_reach": found.reach,
        "noise_into_dead_zone": found.into_dead_zone,
        "threshold": float(model.threshold),
        "inner_level": found.inner,
        "outer_level": found.outer,
        "P": P,
        "P_from": P_from,
        "condition_P": found.condition,
    }
    common = {**common, "method": "dead zone's Lyapunov function with noise (local)"}
    if found.problem:
        return _no_bound(
            f"No ultimate error bound under noise is certified: {why}, and near zero error, "
            f"where the observer is linear (its dead zone), {found.problem}." + energy_words,
            {**evidence, "problem": found.problem},
            common,
            noise,
            energy,
        )
    search = noise_search(design, noise)
    bound, radius = found.bound, found.radius
    if not search["largest_error"] <= bound:
        return _no_bound(
            "No ultimate error bound under noise is certified: a simulated noise within the "
            f"bounds drove the error to {readable(search['largest_error'])}, above the local "
            f"bound {readable(bound)} the dead zone's function gives (please report this "
            "design).",
            {**evidence, "noise_search": search, "bound_found": bound},
            common,
            noise,
            energy,
        )
    extra = per_row[measured:]  # (the process noise's bounds, unchanged)

    def harden(scale: np.ndarray) -> float:
        rows = measurement_rows(design, _scaled_noise(noise, scale))
        return math.inf if rows is None else function.bound(np.concatenate([rows, extra])).bound

    hardening, harden_words = _hardening_fields(
        design, noise.eta, sensor_hardening(noise.eta, harden)
    )
    evidence.update(
        lambda_max_P_inverse_ee=found.top,
        lambda_max_P_ee=found.top_ee,
        noise_search=search,
    )
    return Check(
        verdict=Verdict.HOLDS,
        summary=f"Without attack and with noise within the spec's bounds on every sample, from "
        f"every initial error with ||e(0)|| <= {readable(radius)} (attack estimate 0) the "
        f"estimation error {settles(bound)} (2-norm); no global "
        f"bound ({why}). Near zero error the observer estimates no attack (its dead zone) and "
        f"is linear: sqrt(V), V = xi' P xi, contracts by {readable(found.rho)} per step and "
        f"a sample of noise moves it by at most {readable(found.reach)}, so it falls to "
        f"{readable(found.inner)}, and while sqrt(V) <= {readable(found.outer)} every "
        f"channel's input, noise included, stays within the threshold "
        f"{readable(float(model.threshold))}. A "
        f"search over {search['sequences']} noise sequences within the bounds (from zero "
        f"error, {search['steps']} steps{ascent_text(search)}) reached "
        f"{readable(search['largest_error'])}." + harden_words + energy_words,
        value=bound,
        fields={
            "ultimate_bound": bound,
            "energy_gain": energy,
            "region_radius": radius,
            "noise": noise.to_dict(),
            **hardening,
        },
        evidence=evidence,
        **common,
    )


SEARCH_STEPS = 300
SEARCH_RANDOM = 24


def _process_columns(G: np.ndarray, omega: np.ndarray, scale: float | None) -> tuple[Any, Any]:
    """The process noise's columns G_j 2^(k_j) and bounds omega_j 2^(-k_j) (the same G w,
    exactly), k_j bringing each bound near ``scale`` (the measurement rows' largest bound):
    one gain for both noises then weighs them alike, whatever units w is written in; with
    ``scale`` None, k_j = 0 (w in the spec's units).  The columns with no bound or no entry
    are left out; a scaling that would not be exact is not made."""
    columns, bounds = [], []
    for j in range(G.shape[1]):
        col, bound = G[:, j], float(omega[j])
        if bound == 0 or not np.any(col):
            continue
        # (the exponents' difference: bound / scale overflows for a scale of 5e-324)
        k = math.frexp(bound)[1] - math.frexp(scale)[1] if scale is not None and scale > 0 else 0
        with np.errstate(over="ignore", under="ignore"):  # a scaling out of range is not made
            scaled, shrunk = np.ldexp(col, k), math.ldexp(bound, -k)
            exact = np.all(np.isfinite(scaled)) and np.array_equal(np.ldexp(scaled, -k), col)
        if not (exact and math.isfinite(shrunk) and math.ldexp(shrunk, k) == bound):
            scaled, shrunk = col, bound
        columns.append(scaled)
        bounds.append(shrunk)
    return np.stack(columns, axis=1), np.array(bounds)


def process_model(
    design: ObserverDesign,
    model: Any,
    noise: MeasurementNoise,
    rows: Any,
    *,
    own_units: bool = False,
) -> tuple[Any, np.ndarray]:
    """The error model with the process noise as a further input (xi+ = ... + [-G; 0] w, its
    columns scaled by powers of two to the measurement rows' bounds ``rows``,
    ``_process_columns``, or in the spec's units with ``own_units``) and the bounds of that
    input's entries."""
    assert noise.process is not None  # a process noise that moves the state: a column left
    top = float(np.max(rows)) if np.size(rows) else 0.0
    scale = None if own_units else top
    G, bounds = _process_columns(noise.process.input, noise.process.omega, scale)
    return model.with_input(_error_input(model, design.system.n, G)), bounds


def process_certificate(
    design: ObserverDesign, model: Any, noise: MeasurementNoise, alpha: float, rows: Any
) -> tuple[Any, np.ndarray] | None:
    """The verified ISS certificate (``lmi.iss_certificate`` at decay ``alpha``) of the error
    model with the process noise as a further input (xi+ = ... + [-G; 0] w: e = x_hat - x
    takes -G w from x+ = A x + G w, w not in the nonlinearity's argument; its columns scaled
    by powers of two to the measurement rows' bounds ``rows``, ``_process_columns``) and the
    bounds of that input's entries, or None where it does not hold with a decay.

    Over a window (an SSO's stacked measurements) the error is that of the window's first
    state, z+ = A z + G w, and the process noise of the window's later steps reaches the
    stacked measurements: ``rows`` then bound them with it (``measurement_rows``).  The
    inequality holds for every input at every step, so the w in the rows and the w in the
    state may be the same or not: the bound covers both."""
    noise_model, bounds = process_model(design, model, noise, rows)
    cert = decaying_certificate(noise_model, alpha)
    return None if cert is None else (cert, bounds)


def noise_search(design: ObserverDesign, noise: MeasurementNoise, seed: int = 0) -> dict[str, Any]:
    """The largest error ||x_hat - x||_2 a search over noise sequences within the bounds
    drives the observer to, from zero error and no attack (x = 0 without process noise, so the
    measurements are the noise): for each state component, the signs that make the linear
    part's series sum_j |F^j L| eta (and |F^j G| omega with process noise) add up at the last
    step, and random sign and uniform sequences; the plant driven by the process noise where
    there is one; run through the observer's own simulator."""
    from ..observers import observer_from_design

    p, n = design.system.p, design.system.n
    eta = noise.eta  # each sample within it (a window's 2-norm bound bounds each sample too)
    G = None if noise.process is None else noise.process.input
    omega = np.zeros(0) if noise.process is None else noise.process.omega
    m = omega.size
    rng = np.random.default_rng(seed)
    sequences, inputs = [], []
    if design.window == 1:
        F, L = np.asarray(design.error_matrix, dtype=float), np.asarray(design.L, dtype=float)
        terms = _powers_times(F, L, SEARCH_STEPS)
        # e+ = F e + L n - G w: w against the signs of F^(K-1-k) G
        reach = [] if G is None else _powers_times(F, G, SEARCH_STEPS)[::-1]
        for i in range(n):
            signs = np.array([np.sign(T[i]) for T in terms[::-1]])  # step k: F^(K-1-k) L
            sequences.append(signs * eta)
            if reach:
                inputs.append(-np.array([np.sign(T[i]) for T in reach]) * omega)
    for _ in range(SEARCH_RANDOM):
        sequences.append(rng.choice([-1.0, 1.0], (SEARCH_STEPS, p)) * eta)
        sequences.append(rng.uniform(-1.0, 1.0, (SEARCH_STEPS, p)) * eta)
        if G is not None:
            inputs.append(rng.choice([-1.0, 1.0], (SEARCH_STEPS, m)) * omega)
            inputs.append(rng.uniform(-1.0, 1.0, (SEARCH_STEPS, m)) * omega)
    y = np.stack(sequences, axis=1)  # (steps, runs, p)
    w = np.stack(inputs, axis=1) if G is not None else None  # (steps, runs, m)
    simulator = observer_from_design(design)
    errors = _driven_errors(design, simulator, y, w, G)
    largest = float(np.max(errors)) if errors.size else 0.0
    out: dict[str, Any] = {
        "largest_error": largest,
        "sequences": len(sequences),
        "steps": SEARCH_STEPS,
    }
    if design.sparse and design.window == 1 and errors.size:
        # projected gradient ascent from the sequences that went furthest, through the error's
        # Lur'e model (its attack input is the measurement vector: the noise; the process
        # noise a further input), each result run through the observer's own simulator as the
        # others are
        best = np.argsort(np.max(errors, axis=0))[-GRADIENT_STARTS:]
        starts = y[:, best, :] if w is None else np.concatenate([y, w], axis=2)[:, best, :]
        ascent = _gradient_ascent(design, starts, np.concatenate([eta, omega]), G)
        if ascent is not None:
            ascended, iterations = ascent
            found = _driven_errors(
                design, simulator, ascended[:, :, :p], None if w is None else ascended[:, :, p:], G
            )
            out["largest_error"] = max(largest, float(np.max(found)))
            out["sequences"] += ascended.shape[1]
            out["gradient_ascent"] = {
                "starts": int(ascended.shape[1]),
                "iterations": iterations,
                "largest_error": float(np.max(found)),
            }
    return out


def _powers_times(F: np.ndarray, G: np.ndarray, steps: int) -> list[np.ndarray]:
    """G, F G, ..., F^(steps - 1) G."""
    terms = [G]
    for _ in range(steps - 1):
        terms.append(F @ terms[-1])
    return terms


def _error_input(model: Any, n: int, G: np.ndarray) -> np.ndarray:
    """The error model's input matrix of the process noise: e = x_hat - x takes -G w from
    x+ = A x + G w, the model's other states (the attack estimate) nothing."""
    extra = np.zeros((model.N, G.shape[1]))
    extra[:n] = -G
    return extra


def _driven_errors(
    design: ObserverDesign,
    simulator: Any,
    noise: np.ndarray,
    process: np.ndarray | None,
    G: np.ndarray | None,
) -> np.ndarray:
    """||x_hat(k) - x(k - d)|| (steps + 1, runs) from zero with measurement noise ``noise``
    (steps, runs, p) and the plant x+ = A x + G w driven by ``process`` (steps, runs, m; x = 0
    when None): the observer's own simulator on y = C x + n, its estimate at k that of the
    state d = its delay steps before (a window's first state; x(j) = 0 for j < 0).

    Driven by process noise, an unstable plant's state grows, and x_hat - x then holds the
    rounding of both (about 1e-16 of their size, times what the observer's arithmetic
    amplifies): each error is taken less 2^-40 ||x||, what the simulation resolves (0 where x
    left the float range), so that rounding is never reported as an error the noise drove."""
    with np.errstate(all="ignore"):
        if process is None or G is None:
            return safe_norms(simulator.run(noise).x_hat)  # an estimate of 1e200 is finite
        A, C = design.system.A, design.system.C
        steps, runs, _ = noise.shape
        x = np.zeros((steps + 1, runs, design.system.n))
        for k in range(steps):
            x[k + 1] = x[k] @ A.T + process[k] @ G.T
        y = x[:-1] @ C.T + noise
        run = simulator.run(y)
        d = int(run.delay)
        reference = x if d == 0 else np.concatenate([np.zeros_like(x[:d]), x[:-d]], axis=0)
        # (the plant's size: an estimate that diverges from a modest state stays an error)
        resolution = 2.0**-40 * safe_norms(reference)
        errors = safe_norms(run.x_hat - reference)
        resolved = np.isfinite(resolution)
        return np.where(
            resolved, np.maximum(errors - np.where(resolved, resolution, 0.0), 0.0), 0.0
        )


GRADIENT_STARTS = 8
GRADIENT_ITERATIONS = 6  # at most: the ascent stops at a vertex its linearisation keeps


def ascent_text(search: Mapping[str, Any]) -> str:
    """How the search's projected gradient ascent took part (``noise_search``'s record; ''
    without one)."""
    ascent = search.get("gradient_ascent")
    if not ascent:
        return ""
    steps = ascent["iterations"]
    return (
        f"; the {ascent['starts']} that went furthest then moved by {steps} "
        f"step{'' if steps == 1 else 's'} of projected gradient ascent"
    )


def _gradient_ascent(
    design: ObserverDesign, starts: np.ndarray, eta: np.ndarray, G: np.ndarray | None = None
) -> tuple[np.ndarray, int] | None:
    """Noise sequences (steps, runs, p) within +-eta that drive the error of a one-sample
    sparse observer far, from ``starts``: each iteration simulates its Lur'e model xi+ = A xi
    + B phi(Cw xi + Dw n) + E n (an SSO with several inner steps a sample: its dead zone's,
    linear) from zero, takes the gradient of u' Ce xi at the step where
    the error is largest (u its direction; the adjoint through phi's slopes, 0 or q), and
    moves every sample to the bound in the gradient's direction (the box's vertex that
    maximises the linearised error), until it stays there or ``GRADIENT_ITERATIONS``; the
    best sequences and the gradients taken.  None when the model's attack input is not the
    measurement vector.  With the process noise's G, each sequence's last entries are w, a
    further input of the model (-G w on the error), within the last entries of ``eta``."""
    model = _error_model(design)
    runs = starts.shape[1]
    if model is None or not (noise_enters_as_attack(design, model) and model.finite()):
        return None
    if G is not None:
        model = model.with_input(_error_input(model, design.system.n, G))
    noise = starts.copy()
    best = noise.copy()
    best_value = np.full(runs, -np.inf)
    taken = 0
    with np.errstate(all="ignore"):
        while taken < GRADIENT_ITERATIONS:
            value, grad = error_gradient(model, noise)
            taken += 1
            better = value > best_value
            best[:, better], best_value[better] = noise[:, better], value[better]
            step = np.sign(grad) * eta
            moved = np.where(step != 0, step, noise)
            if not np.all(np.isfinite(moved)) or np.array_equal(moved, noise):
                break  # at a vertex the linearisation keeps: the next steps would repeat it
            noise = moved
    return best, taken


def error_gradient(model: Any, noise: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each run of ``noise`` (steps, runs, r) through the Lur'e model from zero: the
    largest error ||Ce xi_k|| over the steps, and the gradient of u' Ce xi_k at that step
    (u its direction) with respect to every noise sample, by the adjoint of xi+ = A xi +
    B phi(Cw xi + Dw n) + E n through phi's slopes (0 in the dead zone, q outside)."""
    steps, runs, _ = noise.shape
    xi = model.simulate(np.zeros((runs, model.N)), steps, attack=noise)
    e = xi @ model.Ce.T  # (steps + 1, runs, n_e)
    size = safe_norms(e)
    top = np.argmax(size, axis=0)  # the step of each run's largest error
    value = size[top, np.arange(runs)]
    direction = e[top, np.arange(runs)] / np.where(value > 0, value, 1.0)[:, None]
    N, m = model.N, model.m
    measured = direction @ model.Ce  # the objective's term, entering at its run's step
    slopes = model.q * (np.abs(xi[:-1] @ model.Cw.T + noise @ model.Dw.T) > model.threshold)
    ABE = np.hstack([model.A, model.B, model.E])  # one product per step for the three
    CD = np.hstack([model.Cw, model.Dw])
    adjoint = np.zeros((runs, N))
    grad = np.zeros_like(noise)
    for k in range(steps - 1, -1, -1):
        adjoint = adjoint + np.where((top == k + 1)[:, None], measured, 0.0)
        products = adjoint @ ABE
        through = slopes[k] * products[:, N : N + m]  # (runs, m)
        back = through @ CD
        grad[k] = products[:, N + m :] + back[:, N:]
        adjoint = products[:, :N] + back[:, :N]
    return value, grad


def initial_error_fading(design: ObserverDesign, check: Check) -> Callable[[int, int], float]:
    """(start, stop) -> the largest factor c over the steps start..stop with ||part of e(k)
    due to e(0)|| <= c ||e(0)|| (a_hat(0) = 0), as the noise bound's certificate gives it:
    ||F^k||_2 for a linear observer (the powers taken one after the other); from iss_gain's
    dissipation inequality sqrt(lambda_max((P^-1)_ee) (1 - alpha)^k lambda_max(P_ee)), largest
    at the start."""
    if applies_to(design):  # the series of F's powers

        def powers(start: int, stop: int) -> float:
            F = np.asarray(design.error_matrix, dtype=float)
            M = np.linalg.matrix_power(F, start)
            largest = float(np.linalg.norm(M, 2))
            for _ in range(start, stop):
                M = M @ F
                largest = max(largest, float(np.linalg.norm(M, 2)))
            return largest

        return powers
    evidence = check.evidence  # iss_gain's certificate (sparse_noise_check)
    top = float(evidence["lambda_max_P_inverse_ee"])
    alpha = float(evidence["alpha"])
    ee = float(evidence["lambda_max_P_ee"])
    return lambda start, stop: math.sqrt(top * ee * (1.0 - alpha) ** start)


def _tightness(found: NoiseGain) -> str:
    """How close the bound is to the worst case reached, in words computed from both."""
    if found.lower <= 0:
        return ""
    if readable(found.lower) == readable(found.bound_inf):
        return ": the bound is the exact worst case to the digits shown"
    return f" (the worst case lies between, within {readable(found.bound_inf / found.lower)}x)"


def _energy(iss: Check | None, design: ObserverDesign) -> tuple[float | None, str]:
    """The energy gain from noise to error, iss_gain's l2 gain (the noise enters as an attack on
    every sensor does), and its sentence ('' without one)."""
    if iss is None or iss.verdict is not Verdict.HOLDS or iss.fields.get("gamma") is None:
        return None, ""
    gamma = float(iss.fields["gamma"])
    stacked = "" if design.window == 1 else " (n the stacked noise of each window)"
    return gamma, (
        f" Its energy: sum_k |e(k)|^2 <= gamma^2 sum_k |n(k)|^2 + V(xi(0)) with gamma = "
        f"{readable(gamma)}{stacked} (iss_gain)."
    )


def observer_noise_check(
    design: ObserverDesign, noise: MeasurementNoise, iss: Check | None = None
) -> Check:
    """The ``observer_noise_bound`` check (advisory) of a linear observer: without attack, the
    error e+ = F e + L n eventually stays within the certified bound; with the iss_gain check
    ``iss``, also the energy gain from noise to error."""
    F = design.error_matrix
    kind = design.observer_kind
    rounding_F = kind.exact_error(design).rounding(F)
    rounding_L = kind.gain_rounding(design)
    # process noise: x+ = A x + G w, so e+ = F e + L n - G w, the inputs side by side (G
    # is the spec's, exact: L's rounding bounds its entries' too, as nothing)
    inputs, bounds = design.L, noise.eta
    if noise.process is not None:
        inputs = np.hstack([design.L, noise.process.input])
        bounds = np.concatenate([noise.eta, noise.process.omega])
    exact_F = kind.exact_error(design)

    def bound_of(noise_bounds: np.ndarray) -> tuple[NoiseGain, BalancedNoise | None, bool]:
        """The bound in the spec's units and, where the states' units are far apart, in
        balanced state coordinates (with their s and roundings), componentwise the smaller
        where both are certified (and whether both were)."""
        found = linear_noise_bound(
            F, inputs, noise_bounds, rounding_F=rounding_F, rounding_L=rounding_L
        )
        balanced = balanced_noise_bound(F, inputs, noise_bounds, exact_F, rounding_L=rounding_L)
        if balanced is None or balanced.found.code is not NoiseGainCode.CERTIFIED:
            return found, None, False
        if found.code is not NoiseGainCode.CERTIFIED:
            return balanced.found, balanced, False
        return tighter_noise_bound(found, balanced.found), balanced, True

    found, balanced, both = bound_of(bounds)

    # a sign pattern of +-eta on every sample reaches the series: within a per-sample bound,
    # not within a window's 2-norm bound (which bounds each sample, so the upper bound holds)
    lower = found.lower if noise.per_sample else 0.0
    # iss_gain's energy gain is from the measurement noise alone: with process noise, none
    energy, energy_words = _energy(iss, design) if noise.process is None else (None, "")
    fields: dict[str, Any] = {
        "ultimate_bound": found.bound_2,
        "ultimate_bound_inf": found.bound_inf,
        "componentwise": found.componentwise,
        "lower_bound": lower,
        "energy_gain": energy,
        "noise": noise.to_dict(),
    }
    evidence: dict[str, Any] = {
        "reached_componentwise": found.reached,
        "terms": found.terms,
        "contraction_power": found.power,
        "contraction_bound": found.contraction,
        "tail_bound": found.tail,
        "rounding_F": rounding_F,
        "rounding_L": rounding_L,
        "code": found.code.value,
    }
    if balanced is not None:
        evidence["state_scaling"] = balanced.scaling
        evidence["note"] = balanced_noise_note(balanced.scaling, both)
        if not both:  # (the series is the balanced coordinates', and so are its roundings)
            evidence.update(rounding_F=balanced.rounding_F, rounding_L=balanced.rounding_L)
    common: dict[str, Any] = {
        "id": "observer_noise_bound",
        "title": TITLE,
        "method": METHOD,
        "required": False,
        "value_name": VALUE_NAME,
        "fields": fields,
        "evidence": evidence,
    }
    if found.code is not NoiseGainCode.CERTIFIED:
        return Check(
            verdict=Verdict.INCONCLUSIVE,
            summary=f"No ultimate error bound under noise is certified: {reason(found)}.",
            value=math.inf,
            **common,
        )
    p = design.system.p

    def harden(scale: np.ndarray) -> float:
        scaled = bounds.copy()
        scaled[:p] *= scale
        again = bound_of(scaled)[0]
        return again.bound_2 if again.code is NoiseGainCode.CERTIFIED else math.inf

    hardening, harden_words = _hardening_fields(
        design, noise.eta, sensor_hardening(noise.eta, harden)
    )
    fields.update(hardening)
    eta = noise.eta
    each = (
        f"{readable(float(eta[0]))} on every sample of every sensor"
        if eta.size and bool((eta == eta[0]).all())
        else "the spec's bound on every sample of each sensor"
    )
    per_sample = "" if noise.per_sample else " (a window's 2-norm bound bounds each sample)"
    if noise.process is not None:
        omega = noise.process.omega
        per_sample += (
            f" and process noise within {readable(float(omega[0]))} on every entry of w at "
            "every step"
            if omega.size and bool((omega == omega[0]).all())
            else " and process noise within the spec's bound on each entry of w at every step"
        )
    return Check(
        verdict=Verdict.HOLDS,
        summary=f"Without attack and with noise within {each}{per_sample}, the estimation "
        + (
            f"error {settles(found.bound_2)} (2-norm; each component within "
            f"{readable(found.bound_inf)} at most), whatever the initial error."
            if found.bound_2 > 0
            else "error converges to 0 whatever the initial error (the noise does not reach it)."
        )
        + (
            f" Some noise within the bounds drives a component to {readable(lower)}"
            f"{_tightness(found)}."
            if lower > 0
            else ""
        )
        + ("" if balanced is None else " " + balanced_noise_note(balanced.scaling, both))
        + harden_words
        + energy_words,
        value=found.bound_2,
        **common,
    )


def balanced_noise_note(scaling: np.ndarray, both: bool = False) -> str:
    """A sentence when a linear observer's noise bound was computed in balanced state
    coordinates (``noise_gain.balanced_noise_bound``), with ``both`` where the spec's
    coordinates certified one too (``noise_gain.tighter_noise_bound``)."""
    where = f"balanced state coordinates e = {scaling_text(scaling)} e_b"
    if both:
        return (
            f"The series was also bounded in {where} (an exact change of variables: the "
            "states' units differ widely) and written back, |e_i| <= s_i |e_b,i|: each "
            "component's bound is the smaller of the two (its terms, contraction and tail "
            "are the spec's coordinates')."
        )
    return (
        f"The series was bounded in {where} (an exact change of variables: the states' units "
        "differ widely) and written back componentwise, |e_i| <= s_i |e_b,i|; its terms, "
        "contraction and tail, and the roundings rounding_F and rounding_L of F and L it "
        "took in, are those coordinates'."
    )
