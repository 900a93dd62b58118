"""The words of the irrepresentable check: every sentence written from an ``IrrepresentableCode``.

``ssecert.structure.irrepresentable`` decides on codes and the numbers
behind them; this module alone writes the check's summary and the sentence
that says why a rank deficiency in floating point is doubted by the exact
data, so that rewording a sentence here changes no verdict.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ..base.format import sig
from ..budget import format_count
from ..tolerances import EPS
from .outcomes import IrrepresentableCode as Code

__all__ = ["doubt", "summary"]


def doubt(facts: Mapping[str, Any]) -> str:
    """Why rows of O_tau that look rank deficient in floating point are doubted: with the data
    taken exactly they have full column rank (``n``), and either their rows overflow
    (``overflow``) or their scaled smallest singular value is within the rank tolerance band
    (``smallest``, ``rtol``, ``band``)."""
    n = facts["n"]
    if facts.get("overflow"):
        return (
            "looks rank deficient in floating point, where its rows overflow; with the data "
            f"taken exactly it has full column rank (rank {n} modulo a prime), so rho depends "
            "on digits the floating-point rows do not have."
        )
    smallest, rtol, band = facts["smallest"], facts["rtol"], facts["band"]
    return (
        f"looks rank deficient in floating point: with its rows and columns scaled by powers "
        f"of two to unit size, its smallest singular value is {smallest:.2g} times its largest "
        f"({smallest / EPS:.2g} ulp of 1; rank tolerance {rtol / EPS:.3g} ulps, borderline "
        f"band up to {band / EPS:.3g}). With the data taken exactly it has full column rank (rank "
        f"{n} modulo a prime): the plant is within the precision of its data of one where "
        "Theorem 1's assumption fails, so rho depends on digits the data do not have."
    )


def _label(facts: Mapping[str, Any]) -> str:
    """The worst support's names, with its accuracy where it is worth stating (``accuracy``:
    the relative error estimate and O_Sbar's condition number)."""
    if not facts.get("accuracy"):
        return str(facts["label"])
    estimate, kappa = facts["accuracy"]
    return (
        f"{facts['label']}; relative error about {estimate:.1g}: O_Sbar's condition number is "
        f"{kappa:.2g}"
    )


def summary(code: Code, facts: Mapping[str, Any]) -> str:
    """The check's summary for ``code`` with its facts."""
    f = facts
    if code is Code.NO_ATTACK:
        return "With no attacked entries there is nothing to misidentify."
    if code is Code.NO_ATTACK_RANK_DEFICIENT:
        return (
            f"O_tau (horizon {f['tau']}) has rank {f['rank']} < n = {f['n']}: even without "
            f"attack the state is not determined, so rho is inf."
        )
    if code is Code.SUPPORT_TOO_LARGE:
        return (
            f"The support size {f['k']:,} exceeds the {f['items']:,} available {f['noun']}: an "
            f"attack on all of them leaves nothing to estimate the state from."
        )
    if code is Code.ALL_ATTACKED:
        return (
            f"With all {f['items']} {f['noun']} attacked, O_Sbar is empty and lacks full column "
            f"rank (Theorem 1's assumption), so rho is inf."
        )
    if code is Code.TOO_MANY_SUPPORTS:
        return (
            f"C({f['items']:,}, {f['k']:,}) = {format_count(f['count'])} supports exceed the "
            f"budget of {f['max_sets']:,}; raise it with --max-sets (max_sets=...)."
        )
    if code is Code.OVER_BUDGET:
        hint = "; a shorter horizon (--horizon) makes it smaller" if f["longer_than_n"] else ""
        return f"Not attempted: {f['refusal']}{hint}."
    if code is Code.OVERFLOW:
        return f"The stacked observability matrix overflows over {f['tau']} steps."
    if code is Code.WORKERS_FAILED:
        return (
            f"The Dask workers failed twice on the supports with colex ranks {f['first']:,} to "
            f"{f['last']:,} ({f['cause']!r})."
        )
    if code is Code.RANK_UNDECIDED:
        return f"The rank of O_tau cannot be decided: {f['problem']}."
    if code is Code.O_TAU_DOUBT:
        return f"O_tau (horizon {f['tau']}) {f['doubt']}"
    if code is Code.O_TAU_RANK_DEFICIENT:
        return (
            f"O_tau (horizon {f['tau']}) has rank {f['rank']} < n = {f['n']}, so no O_Sbar has "
            f"full column rank as Theorem 1 requires; the first support {f['label']} is a "
            f"witness."
        )
    if code is Code.BORDERLINE:
        return f"{f['count']} support(s) have a borderline rank decision for O_Sbar."
    if code is Code.SUPPORT_DOUBT:
        return f"O_Sbar for the support {f['label']} {f['doubt']}"
    if code is Code.SUPPORT_RANK_DEFICIENT:
        checked, total = f["checked"], f["total"]
        of = f"{checked}" if checked == total else f"the {checked} checked (of {total})"
        return (
            f"For {f['count']} of {of} supports O_Sbar lacks full column rank (Theorem 1's "
            f"assumption); the first is {f['label']}, so rho is inf there."
        )
    if code is Code.RECOMPUTE_MISMATCH:
        return (
            f"The worst constant {f['worst']:.6g} on {f['label']} does not match its direct "
            f"recomputation {f['direct']:.6g}."
        )
    if code is Code.NOT_TOLD_FROM_ONE:
        return (
            f"The worst constant {f['worst']:.6g} on {f['label']} cannot be told from 1: its "
            f"relative error may reach {f['estimate']:.2g} (O_Sbar's condition number in the "
            f"sensors' units is {f['kappa']:.2g})."
        )
    if code is Code.BELOW_ONE:
        return (
            f"The worst irrepresentable constant is {sig(f['worst'])} < 1 (support "
            f"{_label(f)}): Lasso identifies every attack on {f['k']} {f['counted']} for small "
            f"enough lambda."
        )
    if code is Code.IMPRECISE_SUPPORTS:
        return (
            f"The largest constant computed is {sig(f['worst'])} < 1 (support {_label(f)}), "
            f"but {_imprecise_words(f)}, so it is not known to be the worst."
        )
    if code is Code.ABOVE_ONE:
        stopped = f["stopped"]
        cut = ""
        if stopped is not None:
            cut = (
                f" (the scan stopped at the time budget after {stopped:,} supports: the worst "
                f"value over all of them may be larger; --exact scans every support)"
            )
        elif f.get("imprecise") is not None:
            cut = f" ({_imprecise_words(f['imprecise'])}: the constant is at least that)"
        return (
            f"The irrepresentable constant reaches {sig(f['worst'])} >= 1 on support "
            f"{_label(f)}: Lasso's support recovery is not guaranteed there{cut}."
        )
    if code is Code.EXACTLY_AT_LEAST_ONE:
        exact = f["exact"]
        value = "exactly 1" if exact == 1 else f"{float(exact):.17g} >= 1 exactly"
        lower = (
            f" ({_imprecise_words(f['imprecise'])}: the constant is at least that)"
            if f.get("imprecise") is not None
            else ""
        )
        return (
            f"The irrepresentable constant on support {_label(f)} is {value} (computed in "
            f"rational arithmetic from the floats of A and C): Lasso's support recovery is "
            f"not guaranteed there{lower}."
        )
    exact = f["exact"]
    beside = (
        f" (its exact value on {_label(f)} is {float(exact):.17g} < 1; another support may be "
        "as close)."
        if exact is not None
        else "."
    )
    return f"The worst constant {f['worst']:.12g} is within {f['band']:g} of 1{beside}"


def _imprecise_words(f: Mapping[str, Any]) -> str:
    """The supports whose rho was computed too imprecisely to rank (IMPRECISE_SUPPORTS)."""
    count = f["count"]
    which = "support's" if count == 1 else "supports'"
    return (
        f"{count:,} {which} O_Sbar {'is' if count == 1 else 'are'} too ill-conditioned for "
        f"rho to be computed precisely (the one that may be largest, {f['imprecise_label']}, "
        f"with a relative error estimate of {f['error']:.2g}), and may be larger"
    )
