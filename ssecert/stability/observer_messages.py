"""The words of the observer checks: observer_gain, observer_stability and iss_gain.

``ssecert.stability.gain_check`` and ``ssecert.stability.checks`` decide each
check on typed outcomes (a ``LyapunovCertificate``, an ``LMICertificate``, a
witness and its kind, the deadbeat test's numbers) and set its ``Check.code``;
this module writes the sentences of their summaries from those outcomes and
numbers alone, so that rewording a sentence here changes no verdict.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..base.format import sig
from ..observers.lure import scaling_text
from ..results import Verdict
from .lyapunov import LyapunovCertificate, LyapunovMethod
from .outcomes import WitnessKind, known

__all__ = [
    "balanced_lmi_note",
    "balanced_lyapunov_note",
    "constant_attack_text",
    "deadbeat_failure",
    "exact_deadbeat_note",
    "failure_summary",
    "linear_gain_summary",
    "nilpotent_summary",
    "region_proved_text",
    "thesis_summary",
    "zames_falb_summary",
]


def linear_gain_summary(cert: LyapunovCertificate, what: str, *, zero: bool) -> str:
    """The summary of an observer_gain decided by a Lyapunov certificate of F = ``what``.

    Parameters
    ----------
    cert : LyapunovCertificate
        The certificate of the linear error matrix (its verdict, method and reason).
    what : str
        The error matrix in words: ``"A - L C"``, or ``"A (I - step S' S)^m"`` for an SSO
        with m inner steps per sample.
    zero : bool
        Whether the floats of F are the zero matrix (they may have underflowed).
    """
    verdict = Verdict(cert.verdict)
    if verdict is Verdict.HOLDS and cert.method is not LyapunovMethod.LYAPUNOV:
        return f"The linear error dynamics e+ = ({what}) e are stable: {cert.reason}."
    if verdict is Verdict.HOLDS:
        radius = f"spectral radius {sig(known(cert.spectral_radius))}"
        if zero:
            radius = "its floats are the zero matrix, computed spectral radius 0"
        return (
            f"The linear error dynamics e+ = ({what}) e are stable ({radius}), certified by a "
            f"Lyapunov matrix P: the error "
            f"contracts at least by {sig(known(cert.contraction))} per step in the P-norm."
            + balanced_lyapunov_note(cert.proof)
        )
    if verdict is Verdict.FAILS:
        return (
            f"{what} is not stable: {cert.reason}. With this gain the error does not "
            f"vanish even without attack."
        )
    return f"The stability of {what} could not be certified: {cert.reason}."


def balanced_lyapunov_note(proof: Mapping[str, Any] | None) -> str:
    """A sentence when the Lyapunov matrix was verified in balanced state coordinates (the
    certificate's ``proof`` has their ``state_scaling``; '' otherwise)."""
    if not proof or "state_scaling" not in proof:
        return ""
    return (
        f" P was found and verified in balanced state coordinates e = "
        f"{scaling_text(proof['state_scaling'])} e_b (the states' units differ widely) and "
        f"written back exactly."
    )


def balanced_lmi_note(scaling: Any, sensors: Any = None) -> str:
    """A sentence when an LMI certificate was solved and verified in balanced coordinates
    (``scaling``: its ``state_scaling``, None for none; '' then), with ``sensors`` its
    ``sensor_exponent`` where the sensors were put in units of their own there."""
    if scaling is None:
        return ""
    why = "the states' units differ widely"
    if sensors is not None:
        why = "the sensors' units are far from 1 or from each other (sensor_exponent, channel_exponents)"
    return (
        f" The LMI was solved and verified in balanced coordinates xi = {scaling_text(scaling)} "
        f"xi_b (an exact change of variables: {why}); P is given for the spec's coordinates."
    )


def nilpotent_summary(details: Mapping[str, Any]) -> str:
    """What a verified deadbeat gain's check says, from its power test's ``details``: the
    exact nilpotency index of the printed A - L C where its exact powers vanish, else the
    index to rounding and the certified spectral radius bound."""
    index = int(known(details.get("nilpotency_index")))
    upper = known(details.get("spectral_radius_upper_bound"))
    rel = details["relative_power_norms"][index - 1]
    exact_index = details.get("exact_nilpotency_index")
    if details.get("exactly_nilpotent") and exact_index is not None:
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
        f"computed exactly from the floats, norms in balanced power-of-two state units): the "
        f"error vanishes to rounding in {index} "
        f"step{'s' if index != 1 else ''} without attack{_fastest_note(details)}, and the "
        f"spectral radius is certified <= {sig(upper, 3)}."
    )


def _fastest_note(details: Mapping[str, Any]) -> str:
    """Whether the deadbeat index is the observability index, the fastest possible."""
    nu = details.get("observability_index")
    if nu is None:
        return ""
    if details.get("minimal"):
        return ", the observability index"
    return f" (the observability index is {nu}: a faster deadbeat gain exists)"


def deadbeat_failure(problem: str) -> str:
    """The summary of a deadbeat gain whose printed floats are proved not deadbeat."""
    return (
        f"The deadbeat construction's printed gain is not deadbeat: {problem}. "
        f"Rounding L to floats destroys the nilpotency of this plant's "
        f"deadbeat loop."
    )


def exact_deadbeat_note(exact_index: int | None) -> str:
    """The sentence on the exact rational deadbeat gain of a small plant ('' when it was not
    verified: ``exact_index`` None)."""
    if exact_index is None:
        return ""
    return (
        f" In exact arithmetic the rational gain L_exact (evidence) is nilpotent "
        f"with index {exact_index}."
    )


def failure_summary(witness: Mapping[str, Any]) -> str:
    """The summary of a failing observer_stability, by the kind of its witness: an exactly
    confirmed periodic orbit or nonzero equilibrium (a wrong estimate kept with no attack),
    or a divergent trajectory of the large-signal loop; with what the observer's own
    simulator showed when it did not reproduce it (``witness["observer_replay"]``)."""
    e = np.array2string(np.asarray(witness["initial_error"]), precision=4)
    start = "The observer is not globally asymptotically stable: "
    if witness["kind"] is WitnessKind.PERIODIC_ORBIT:
        return (
            f"{start}without attack its error cycles for ever with period {witness['period']}, "
            f"confirmed in exact arithmetic: from the estimation error e = {e} and the attack "
            f"estimate it pairs with, the error returns to the same point every "
            f"{witness['period']} steps." + _replay_disagrees(witness, "return_residual")
        )
    if witness["kind"] is WitnessKind.NONZERO_EQUILIBRIUM:
        return (
            f"{start}it has a nonzero equilibrium, confirmed in exact arithmetic: from the "
            f"estimation error e = {e} and the attack estimate it pairs with, the error stays "
            f"there forever without attack (active soft-threshold channels "
            f"{np.flatnonzero(witness['active_signs']).tolist()})."
            + _equilibrium_replay_words(witness)
        )
    mu = witness["large_signal_eigenvalue"]
    return (
        f"{start}far from the origin the soft "
        f"threshold is the identity minus a bounded term, and that large-signal loop has the "
        f"eigenvalue {sig(mu.real) if mu.imag == 0 else f'{mu.real:.4g} {mu.imag:+.4g}i'} "
        f"(modulus {sig(abs(mu), 6)} > 1). "
        f"Along its left eigenvector w the error obeys |w' xi+| >= {abs(mu):.6g} |w' xi| - "
        f"{witness['beta']:.3g}, so it grows without bound once |w' xi| > "
        f"{witness['escape_level']:.3g}; replayed: from an initial error of norm "
        f"{witness['norms'][0]:.3g} (a_hat(0) = "
        f"{'0' if not np.any(witness['initial_attack_estimate']) else 'as given'}) the error "
        f"state (e, a_hat) reaches norm {witness['norms'][1]:.3g} in {witness['steps']} "
        f"step{'' if witness['steps'] == 1 else 's'} without attack."
        + _replay_disagrees(witness, "growth")
    )


def _replay_disagrees(witness: Mapping[str, Any], measure: str) -> str:
    """A sentence when the observer's own simulator did not reproduce the witness ('' else)."""
    replay = witness.get("observer_replay") or {}
    if not replay.get("replayed") or replay.get("agrees", True):
        return ""
    name = measure.replace("_", " ")
    return (
        f" The observer's own simulator did not reproduce it in floating point ({name} "
        f"{replay.get(measure, float('nan')):.3g} over {replay.get('steps')} steps); the "
        f"proof above does not rest on that replay."
    )


def _equilibrium_replay_words(witness: Mapping[str, Any]) -> str:
    """What the replay of an equilibrium showed, when it did not stay there, and why."""
    replay = witness.get("observer_replay") or {}
    moduli = np.asarray(witness.get("local_loop_moduli", []), dtype=float)
    shown = ", ".join(sig(v, 3) for v in moduli[moduli > 1 + 1e-9][:3])
    repelling = (
        f" It is repelling: the linear part of the error's map near it has eigenvalues of "
        f"modulus {shown} > 1, so any error off it by rounding moves away"
        if witness.get("repelling")
        else ""
    )
    if not replay.get("replayed") or replay.get("agrees", True):
        return f"{repelling}." if repelling else ""
    drift = f"{replay.get('largest_drift', float('nan')):.2g}"
    steps = replay.get("steps")
    return (
        f"{repelling}; the observer's own simulator, started there in floating point (the "
        f"point rounded), drifted off it by {drift} in {steps} steps."
        if repelling
        else f" The observer's own simulator, started there in floating point, drifted off it "
        f"by {drift} in {steps} steps: the equilibrium is shown in exact arithmetic only."
    )


def constant_attack_text(records: Sequence[Mapping[str, Any]]) -> str:
    """One sentence on where the error goes under the constant attacks analysed
    (``ssecert.stability.constant_attack``'s records; the first three, then how many more)."""
    parts = []
    for rec in records[:3]:
        outcome = rec["outcome"]
        if outcome == "converges to a bias":
            outcome += f" of norm {rec['bias_norm']:.3g}"
        parts.append(f"{rec['attack']}: {outcome} ({'proved' if rec['proved'] else 'observed'})")
    more = f"; {len(records) - 3} more in the evidence" if len(records) > 3 else ""
    return "Under a constant attack, from zero error: " + "; ".join(parts) + more + "."


def thesis_summary(verdict: Verdict, items: Sequence[Any]) -> str:
    """The summary of the thesis_assumptions check from its items (``name``, ``verdict``,
    ``reason`` and, for a failing one, ``finding``: ``ssecert.stability.thesis``).

    A failure says that the stability theorem does not apply (or, where Lemma 1 alone fails
    and its corrected bound carries Assumption 3 and the epsilon bound, that its argument
    does with the corrected constant) and that no verdict relies on it.
    """
    if verdict is Verdict.HOLDS:
        return "Every assumption of the thesis's stability proof holds on this design."
    if verdict is Verdict.FAILS:
        by_name = {i.name: i for i in items}
        failing = [i for i in items if i.verdict is Verdict.FAILS]
        findings = "; ".join(i.finding or f"{i.name}: {i.reason}" for i in failing)
        corrected = [i.name for i in failing] == ["lemma_1"] and all(
            by_name[name].verdict is Verdict.HOLDS for name in ("assumption_3", "epsilon_bound")
        )
        if corrected:
            summary = (
                f"{findings}. With that bound Assumption 3 and the epsilon bound (5.20) hold: "
                f"the thesis's stability theorem does not apply as printed, but its argument "
                f"with the corrected constant does."
            )
        else:
            summary = (
                f"{findings}. The thesis's stability theorem therefore does not apply to this "
                f"design."
            )
        return summary + " Advisory: no verdict of this certificate relies on it."
    return "Not all assumptions could be decided: " + "; ".join(
        f"{i.name}: {i.reason}" for i in items if i.verdict == Verdict.INCONCLUSIVE
    )


def zames_falb_summary(
    order: int, *, incremental: bool, sum_bound_factor: float, margin: float, error_bound: float
) -> str:
    """The summary of an observer_stability certified by a Zames-Falb multiplier of ``order``
    (``incremental``: its delayed coefficients are nonnegative, so it holds for increments)."""
    nature = (
        "slope-restricted in [0, shrink]; nonnegative coefficients, so the certificate also "
        "holds for increments"
        if incremental
        else "odd and slope-restricted in [0, shrink]"
    )
    return (
        f"The error state (e, a_hat) converges to 0 from every initial condition without "
        f"attack: with a Zames-Falb multiplier of order {order} (the soft threshold is "
        f"{nature}), V(zeta) = zeta' P zeta over the error state and the "
        f"last {order} nonlinearity inputs and outputs satisfies V(zeta+) - V(zeta) + sigma <= "
        f"-eta |xi|^2 with sum_k sigma_k >= 0, so sum_k |xi(k)|^2 <= "
        f"{sum_bound_factor:.4g} |xi(0)|^2 (verified margin {margin:.3g} "
        f"against an error bound {error_bound:.1e}). No decay rate is certified: the "
        f"circle criterion found no quadratic Lyapunov function."
    )


def region_proved_text(radius: float) -> str:
    """What an undecided stability check says region_of_attraction proves.

    Examples
    --------
    >>> region_proved_text(0.25)[-57:]
    '||e(0)|| <= 0.25 and a_hat(0) = 0 (region_of_attraction).'
    """
    return (
        f"What is proved: the error converges from every initial error with ||e(0)|| <= "
        f"{radius:.3g} and a_hat(0) = 0 (region_of_attraction)."
    )
