"""The thesis's assumptions for the elastic-net observer, checked on an instance.

Chapter 5 of the thesis proves global asymptotic stability (Theorem 6) and
ISS (Theorem 7) of

    x_hat+ = A x_hat + L1 y~,   a_hat+ = Psi_q(a_hat - eps L2 y~),   Psi_q = q S_lambda,

under Assumptions 1-3, Lemma 1 and a small-gain bound (5.20) on eps.  In
ssecert's convention L1 = -L and F = A + L1 C = A - L C.  None of this is
checked on any instance in the thesis; here each item is decided on the
design at hand and returns holds (with a proof), fails (with a
counterexample or the reason) or inconclusive.  Findings on the text:

* Assumption 2's Q acts on the attack space: it is p x p (the thesis writes
  n x n).  Q = I is used for Assumptions 2 and 3.
* Lemma 1's Pi(a) = -sum_l F^(-l-1) L1 Psi_q^l(a) needs F invertible; for a
  deadbeat gain F is nilpotent, so Pi as constructed does not exist.  For
  invertible F the series is in fact finite (repeated soft thresholding
  reaches 0).  The claimed constant ||L1|| / |lambda_max(F) - q| is not what
  the series gives: ||F^-l|| is bounded by ||F^-1||^l, i.e. by the smallest
  singular value of F, not its largest eigenvalue; the proof supports
  ||L1|| ||F^-1|| / (1 - q ||F^-1||) when q ||F^-1|| < 1.
* In (5.20) the decrease terms need lower bounds: lambda_min(P) and
  lambda_min(Q), not lambda_max; and the decay of eta'P eta is
  1 - (1 + gamma_eta) rho, not gamma_eta (rho - 1) + rho.  The bound is
  sufficient, not necessary: a step above it is inconclusive.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from ..budget import Budget, Refusal
from ..design.gains import GainMethod
from ..numerics.exact import dyadic, exact_kernel_vector
from ..numerics.exact_powers import ExactMatrix
from ..observers import ObserverDesign
from ..results import Verdict, combine_verdicts
from ..tolerances import EPS
from . import thesis_messages
from .counterexample_search import (  # noqa: F401  (the search limits stay importable here)
    LOCAL_SEARCH_DIM,
    SEARCH_EVALUATIONS,
    SEARCH_FLOPS,
    SEARCH_MEMORY,
    PairSearch,
    _lipschitz_search,
    _local_search,
    _Meter,
    _sample_rows,
    _Search,
    _SearchExhausted,
)
from .lyapunov import lyapunov_certificate
from .outcomes import AssumptionCode as Code
from .outcomes import SearchStop, SeriesFailure, StopCode
from .pi_series import (  # noqa: F401  (the series stays importable here)
    MAX_SERIES_TERMS,
    SeriesError,
    _PiSeries,
    pi_map,
    series_terms,
)

__all__ = ["AssumptionResult", "thesis_assumptions", "pi_map"]


@dataclass(frozen=True)
class AssumptionResult:
    """One item of the thesis's chain of assumptions.

    ``code`` decides the verdict; ``facts`` hold the numbers its words need
    (``thesis_messages``).  ``finding`` says in one clause what a failing item
    means for the thesis's theorem (which of its sufficient conditions the
    design does not meet, or which printed statement is wrong); ``reason``
    gives the numbers.
    """

    name: str
    code: Code
    facts: Mapping[str, Any] = field(default_factory=dict)
    details: dict[str, Any] = field(default_factory=dict)

    @property
    def verdict(self) -> Verdict:
        return self.code.verdict

    @property
    def reason(self) -> str:
        return thesis_messages.reason(self.code, self.facts)

    @property
    def finding(self) -> str:
        return thesis_messages.finding(self.code, self.facts)

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"verdict": self.verdict, "reason": self.reason}
        if self.finding:
            out["finding"] = self.finding
        return {**out, **self.details}


def _psi(s: np.ndarray, q: float, lam: float) -> np.ndarray:
    return q * np.sign(s) * np.maximum(np.abs(s) - lam, 0.0)


def thesis_assumptions(
    design: ObserverDesign,
    *,
    observability_holds: bool | None = None,
    seed: int = 0,
    budget: Budget | None = None,
) -> tuple[str, list[AssumptionResult]]:
    """Check Assumptions 1-3, Lemma 1 and the epsilon bound (5.20) on a design.

    Parameters
    ----------
    design : ObserverDesign
        A sparse observer (sso, dsso or elastic_net).
    observability_holds : bool, optional
        Verdict of the observability check (Assumption 1), if known.
    seed : int, default 0
        Seed of the counterexample searches.
    budget : Budget, optional
        Memory and work allowed for the p x p matrices of the attack estimate
        (default ``Budget()``: 2 GiB, 1e12 operations); the counterexample
        searches have their own small fixed budget (``SEARCH_FLOPS``).

    Returns
    -------
    verdict : str
        fails if any item fails, else inconclusive if any is, else holds.
    items : list of AssumptionResult
    """
    rng = np.random.default_rng(seed)
    inst = _instance(design)
    items = [_assumption_1(observability_holds), _assumption_2(inst)]
    refusal = _refusal(inst, budget)
    if refusal is not None:
        for name in ("lemma_1", "assumption_3", "epsilon_bound"):
            items.append(AssumptionResult(name, Code.NOT_ATTEMPTED, {"refusal": refusal}))
        return combine_verdicts([i.verdict for i in items]).value, items
    lemma = _lemma_1(inst, rng)
    assumption_3, rho_a = _assumption_3(inst, lemma, rng)
    items += [lemma.item, assumption_3, _epsilon_bound(inst, lemma, rho_a)]
    return combine_verdicts([i.verdict for i in items]).value, items


@dataclass(frozen=True)
class _Instance:
    """A sparse design in the thesis's notation: F = A + L1 S, Psi_q = q S_lambda, step eps."""

    A: np.ndarray
    S: np.ndarray
    L1: np.ndarray
    F: np.ndarray
    L2: np.ndarray
    q: float
    lam: float
    eps: float
    exact_F: ExactMatrix | None = None  # the exact F of the spec's data
    deadbeat: bool = False  # the gain is a deadbeat design (F nilpotent in exact arithmetic)

    @property
    def p(self) -> int:
        """Entries of the attack estimate."""
        return int(self.S.shape[0])


def _instance(design: ObserverDesign) -> _Instance:
    """The design's matrices and parameters; TypeError for an observer without a step."""
    S = design.sensing
    A = design.system.A
    L1 = -design.gain.L
    F = A + L1 @ S
    q = float(design.shrink)
    lam = float(design.threshold or 0.0)
    if design.step is None:
        raise TypeError(
            f"thesis_assumptions needs a sparse observer with a step, got {design.kind}"
        )
    eps = float(design.step)
    L2 = design.L2 if design.L2 is not None else np.eye(S.shape[0])
    exact_F = design.observer_kind.exact_error(design)
    return _Instance(
        A=A,
        S=S,
        L1=L1,
        F=F,
        L2=L2,
        q=q,
        lam=lam,
        eps=eps,
        exact_F=exact_F,
        deadbeat=design.gain.method is GainMethod.DEADBEAT,
    )


def _assumption_1(observability_holds: bool | None) -> AssumptionResult:
    """Assumption 1 (observability), taken from the observability check's verdict."""
    if observability_holds is None:
        return AssumptionResult("assumption_1", Code.NOT_CHECKED)
    return AssumptionResult(
        "assumption_1", Code.OBSERVABLE if observability_holds else Code.NOT_OBSERVABLE
    )


def _assumption_2(inst: _Instance) -> AssumptionResult:
    """Assumption 2 with Q = I (p x p): holds for the shrinkage Psi_q."""
    q, lam = inst.q, inst.lam
    return AssumptionResult(
        "assumption_2",
        Code.SHRINKAGE,
        {"q": q, "lam": lam},
        {"Q": "identity", "lipschitz_psi": q},
    )


def _refusal(inst: _Instance, budget: Budget | None) -> Refusal | None:
    """Why the budget refuses the p x p work of Lemma 1 and Assumption 3 (None when it allows
    it)."""
    p = inst.p
    # the bounds below take 2-norms of p x p matrices (p = attack-estimate entries)
    return (budget or Budget()).check(
        f"checking Lemma 1 and Assumption 3 with {p} attack-estimate entries",
        nbytes=8.0 * (4 * p * p + _sample_rows(p) * p * 6),
        flops=30.0 * p**3,
    )


class _Lemma1(NamedTuple):
    """Lemma 1's item and what Assumption 3 and the epsilon bound take from it."""

    item: AssumptionResult
    holds: bool  # Pi exists with a finite Lipschitz bound
    lipschitz: float | None  # the proven Lipschitz constant of Pi
    series: _PiSeries | None  # Pi; None when F is singular


def _lemma_1(inst: _Instance, rng: np.random.Generator) -> _Lemma1:
    """Lemma 1: Pi exists (F invertible) and has the claimed Lipschitz constant."""
    F, L1 = inst.F, inst.L1
    s_F = np.linalg.svd(F, compute_uv=False)
    # singularity relative to the plant's scale (a deadbeat F can be zero to rounding)
    scale_F = max(
        float(np.linalg.norm(inst.A, 2)),
        float(np.linalg.norm(L1 @ inst.S, 2)),
        float(s_F[0]),
        np.finfo(float).tiny,
    )
    singular = s_F[-1] <= 1e3 * F.shape[0] * EPS * scale_F
    rho_F = float(np.abs(np.linalg.eigvals(F)).max())
    q = inst.q
    claimed = float(np.linalg.norm(L1, 2)) / abs(rho_F - q) if abs(rho_F - q) > 0 else np.inf
    if singular:
        return _Lemma1(_singular_F(inst, float(s_F[-1]), claimed), False, None, None)
    if s_F[-1] < SUBNORMAL_FLOOR:
        item = AssumptionResult(
            "lemma_1",
            Code.F_AT_FLOAT_FLOOR,
            {"smallest": float(s_F[-1])},
            {"smallest_singular_value_F": float(s_F[-1]), "claimed_lipschitz": claimed},
        )
        return _Lemma1(item, False, None, None)
    return _lemma_1_on_pi(inst, rng, claimed, rho_F)


# below this smallest singular value F^-1 is out of (or at the edge of) the float range
SUBNORMAL_FLOOR = 1e10 * np.finfo(float).tiny


def _singular_F(inst: _Instance, smallest: float, claimed: float) -> AssumptionResult:
    """Lemma 1 fails when F is singular in exact arithmetic (an exact kernel vector of the exact
    F of the spec's data), so Pi does not exist; singular only to rounding, it is undecided."""
    details = {"smallest_singular_value_F": smallest, "claimed_lipschitz": claimed}
    exact = inst.exact_F.value if inst.exact_F is not None else dyadic(inst.F)
    if inst.deadbeat and (exact is None or exact_kernel_vector(exact) is None):
        return AssumptionResult("lemma_1", Code.F_DEADBEAT, {"smallest": smallest}, details)
    if exact is None or exact_kernel_vector(exact) is None:
        facts = {"smallest": smallest}
        return AssumptionResult("lemma_1", Code.F_SINGULAR_TO_ROUNDING, facts, details)
    return AssumptionResult("lemma_1", Code.F_SINGULAR, {"smallest": smallest}, details)


def _lemma_1_on_pi(
    inst: _Instance, rng: np.random.Generator, claimed: float, rho_F: float
) -> _Lemma1:
    """Lemma 1 for an invertible F: the corrected bound against a search for larger ratios."""
    q, lam, L1, p = inst.q, inst.lam, inst.L1, inst.p
    F_inv = np.linalg.inv(inst.F)
    ninv = float(np.linalg.norm(F_inv, 2))
    correct = (float(np.linalg.norm(L1, 2)) * ninv / (1 - q * ninv)) if q * ninv < 1 else np.inf
    series = _PiSeries(F_inv, L1, q, lam)
    # the searches only look for counterexamples; a budget keeps them short
    # each search gets half of the budget, so that one cannot starve the other
    meter = _Meter(SEARCH_FLOPS / 2, SEARCH_EVALUATIONS / 2)

    def pi(a: np.ndarray) -> tuple[np.ndarray, SeriesFailure | None]:
        return series(a, meter)

    scale = max(lam, 1e-3)
    ratio, a1, a2, search = _lipschitz_search(pi, p, rng, scale, meter, samples=_sample_rows(p))
    details: dict[str, Any] = {
        "claimed_lipschitz": claimed,
        "correct_bound": correct,
        "empirical_ratio": ratio,
        "equation_5_9_residual": _equation_5_9_residual(inst, pi, rng, scale, search),
        "norm_F_inv": ninv,
        "spectral_radius_F": rho_F,
        "search": search.evidence(),
    }
    if ratio is not None and ratio > claimed * (1 + 1e-9):
        # the claimed constant is wrong, but Pi exists and the corrected bound is valid
        item = AssumptionResult(
            "lemma_1",
            Code.LIPSCHITZ_EXCEEDED,
            {"claimed": claimed, "ratio": ratio, "correct": correct},
            {**details, "counterexample": {"a1": a1, "a2": a2}},
        )
        finite = bool(np.isfinite(correct))
        return _Lemma1(item, finite, correct if finite else None, series)
    if correct <= claimed:
        proven = {"correct": correct, "claimed": claimed}
        item = AssumptionResult("lemma_1", Code.LIPSCHITZ_PROVEN, proven, details)
        return _Lemma1(item, True, correct, series)
    facts: dict[str, Any] = {"claimed": claimed, "correct": correct, "ratio": ratio}
    if ratio is None:
        facts.update(failure=search.failure, stopped=search.stop)
    item = AssumptionResult("lemma_1", Code.LIPSCHITZ_NOT_PROVEN, facts, details)
    return _Lemma1(item, True, correct if np.isfinite(correct) else None, series)


def _equation_5_9_residual(
    inst: _Instance, pi: Any, rng: np.random.Generator, scale: float, search: PairSearch
) -> float | None:
    """Relative residual of F Pi(a) + L1 a = Pi(Psi_q(a)) (5.9) on 200 random a.

    None when no a could be evaluated; a search that runs out of budget is
    noted in ``search`` (``late_stop``).
    """
    residual = None
    try:
        sample = rng.standard_normal((200, inst.p)) * scale * 5
        pi_a, _ = pi(sample)
        pi_psi, _ = pi(_psi(sample, inst.q, inst.lam))
        eq = inst.F @ pi_a.T + inst.L1 @ sample.T - pi_psi.T
        ok = np.all(np.isfinite(eq), axis=0)
        if np.any(ok):
            residual = float(np.abs(eq[:, ok]).max() / max(1.0, np.abs(pi_a[ok]).max()))
    except _SearchExhausted:
        search.late_stop = SearchStop(StopCode.BUDGET_EQUATION_5_9)
    return residual


def _assumption_3(
    inst: _Instance, lemma: _Lemma1, rng: np.random.Generator
) -> tuple[AssumptionResult, float | None]:
    """Assumption 3 with Q = I, and rho'' when it is proven."""
    if lemma.series is None:
        fails = lemma.item.verdict is Verdict.FAILS
        return AssumptionResult("assumption_3", Code.NO_PI, {"lemma_fails": fails}), None
    search = _Search(_Meter(SEARCH_FLOPS / 2, SEARCH_EVALUATIONS / 2))
    ratio_of = _attack_ratio(inst, lemma.series, search.meter)
    rows = _sample_rows(inst.p)
    worst_value, worst_point, evaluated, stopped = _largest_attack_ratio(
        ratio_of, search, inst, rng, rows
    )
    details: dict[str, Any] = {
        "Q": "identity",
        "largest_ratio_found": worst_value,
        "search": f"{rows} samples over magnitudes 0.05-100 lambda, then Nelder-Mead",
        "samples_evaluated": evaluated,
    }
    if stopped is not None:
        details["stopped"] = thesis_messages.search_stop(stopped)
    if search.failed and search.failure is not None:
        details["evaluations_failed"] = search.failed
        details["first_failure"] = thesis_messages.series_failure(search.failure)
    bound = None
    if lemma.lipschitz is not None:
        bound = _attack_contraction_bound(inst, lemma.lipschitz)
        details["proven_bound_sqrt_rho"] = bound
    if worst_value is not None and worst_value >= 1.0:
        return AssumptionResult(
            "assumption_3",
            Code.NOT_CONTRACTING,
            {"worst": worst_value},
            {**details, "counterexample": worst_point},
        ), None
    if bound is not None and bound < 1.0:
        rho_a = bound**2
        return AssumptionResult("assumption_3", Code.CONTRACTING, {"rho": rho_a}, details), rho_a
    if worst_value is None:
        why = {"failure": search.failure, "stopped": stopped}
        return AssumptionResult("assumption_3", Code.NOT_EVALUATED, why, details), None
    return AssumptionResult("assumption_3", Code.NO_PROOF, {"worst": worst_value}, details), None


def _attack_ratio(inst: _Instance, series: _PiSeries, meter: _Meter) -> Any:
    """The map a -> (|g(a)|^2 / |a|^2 per row, the first ``SeriesFailure`` or None), g(a) =
    Psi_q(a - eps L2 (S Pi(a) + a))."""
    S, L2, eps, q, lam = inst.S, inst.L2, inst.eps, inst.q, inst.lam

    def g(a: np.ndarray) -> tuple[np.ndarray, SeriesFailure | None]:
        a = np.atleast_2d(a)
        values, failure = series(a, meter)
        with np.errstate(over="ignore", invalid="ignore"):
            v = a - eps * (S @ values.T + a.T).T @ L2.T
            return _psi(v, q, lam), failure

    def ratio_of(a: np.ndarray) -> tuple[np.ndarray, SeriesFailure | None]:
        a = np.atleast_2d(a)
        values, failure = g(a)
        with np.errstate(over="ignore", invalid="ignore"):
            r = np.sum(values**2, axis=1) / np.sum(a**2, axis=1)
        return r, failure

    return ratio_of


def _largest_attack_ratio(
    ratio_of: Any, search: _Search, inst: _Instance, rng: np.random.Generator, rows: int
) -> tuple[float | None, np.ndarray | None, int, SearchStop | None]:
    """The largest ratio found, its a, the samples evaluated and why the search stopped early.

    ``rows`` samples over magnitudes 0.05-100 lambda, then Nelder-Mead from
    the worst one; the ratio and point are None when no sample is finite.
    """
    mags = max(inst.lam, 1e-3) * np.exp(rng.uniform(np.log(0.05), np.log(100.0), (rows, 1)))
    samples = rng.standard_normal((rows, inst.p)) * mags
    ratios = np.full(rows, np.nan)
    stopped = None
    try:
        batch = max(1, rows // 8)
        for start in range(0, rows, batch):
            sl = slice(start, start + batch)
            ratios[sl], failure = ratio_of(samples[sl])
            search.note(failure, int(np.count_nonzero(~np.isfinite(ratios[sl]))))
    except _SearchExhausted:
        stopped = SearchStop(StopCode.BUDGET_SAMPLING)
    finite = np.flatnonzero(np.isfinite(ratios))
    if not finite.size:
        return None, None, 0, stopped
    worst = int(finite[np.argmax(ratios[finite])])
    worst_value, worst_point = float(ratios[worst]), samples[worst]

    def one(a: np.ndarray) -> tuple[float, SeriesFailure | None]:
        if not float(a @ a) > 0:
            return 0.0, None
        r, failure = ratio_of(a)
        return float(r[0]), failure

    # then local optimisation from the worst sample
    if stopped is None:
        stopped = _local_search(search.objective(one), samples[worst].copy(), 400)
    if search.best_point is not None and search.best_value > worst_value:
        worst_value, worst_point = search.best_value, search.best_point
    return worst_value, worst_point, int(finite.size), stopped


def _attack_contraction_bound(inst: _Instance, ell_pi: float) -> float:
    """sqrt(rho'') = q (||I - eps L2|| + eps ||L2|| ||S|| ell_Pi), from |Psi_q(v)| <= q |v|."""
    L2, eps = inst.L2, inst.eps
    return inst.q * (
        float(np.linalg.norm(np.eye(inst.p) - eps * L2, 2))
        + eps * float(np.linalg.norm(L2, 2)) * float(np.linalg.norm(inst.S, 2)) * ell_pi
    )


def _epsilon_bound(inst: _Instance, lemma: _Lemma1, rho_a: float | None) -> AssumptionResult:
    """The epsilon bound (5.20), with the eigenvalues the inequalities need."""
    if not (lemma.holds and rho_a is not None and lemma.lipschitz is not None):
        return AssumptionResult("epsilon_bound", Code.NEEDS_LEMMA)
    lyap = lyapunov_certificate(inst.F, exact=inst.exact_F)
    if lyap.verdict != Verdict.HOLDS or lyap.P is None:
        return AssumptionResult("epsilon_bound", Code.F_NOT_CERTIFIED)
    p_eigs = np.linalg.eigvalsh(lyap.P)
    rho = 1.0 - 1.0 / float(p_eigs[-1])  # F'PF - P = -I  =>  F'PF <= rho P
    best_eps, best_par = _epsilon_star(inst, p_eigs, rho, lemma.lipschitz, rho_a)
    eps = inst.eps
    details = {
        "epsilon_star": best_eps,
        "step": eps,
        "rho_P": rho,
        "parameters_gamma_eta_gamma_a_mu": best_par,
    }
    facts = {"step": eps, "star": best_eps}
    if best_par is not None and eps <= best_eps:
        return AssumptionResult("epsilon_bound", Code.STEP_WITHIN, facts, details)
    return AssumptionResult("epsilon_bound", Code.STEP_ABOVE, facts, details)


def _epsilon_star(
    inst: _Instance, p_eigs: np.ndarray, rho: float, ell_pi: float, rho_a: float
) -> tuple[float, tuple[float, float, float] | None]:
    """The largest epsilon* of (5.20) over a grid of (gamma_eta, gamma_a, mu), and those."""
    l2, lc, lpsi = float(np.linalg.norm(inst.L2, 2)), float(np.linalg.norm(inst.S, 2)), inst.q
    normP = float(p_eigs[-1])
    best_eps, best_par = 0.0, None
    for g_eta in np.linspace(0.02, 0.98, 25) * (1 - rho) / max(rho, 1e-12):
        gamma = 1.0 - (1.0 + g_eta) * rho
        if gamma <= 0:
            continue
        c_eta = 2 * (1 + 1 / g_eta) * normP * ell_pi**2 * lpsi**2 * l2**2 * lc**2
        c_a = 2 * (1 + 1 / g_eta) * normP * ell_pi**2 * lpsi**2 * l2**2 * (1 + lc * ell_pi) ** 2
        for g_a in np.linspace(0.02, 0.98, 25) * (1 / rho_a - 1):
            rho2 = (1 + g_a) * rho_a
            if rho2 >= 1:
                continue
            d_eta = (1 + 1 / g_a) * 1.0 * lpsi**2 * l2**2 * lc**2
            for mu in np.logspace(-4, 4, 33):
                e1 = gamma * float(p_eigs[0]) / (c_eta + mu * d_eta)
                e2 = mu * (1 - rho2) * 1.0 / c_a  # lambda_min(Q) = 1
                val = min(e1, e2, 1.0)
                if val > best_eps:
                    best_eps, best_par = val, (float(g_eta), float(g_a), float(mu))
    return best_eps, best_par
