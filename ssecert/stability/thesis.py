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

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..design.observer import ObserverDesign
from ..tolerances import EPS
from .lyapunov import lyapunov_certificate

__all__ = ["AssumptionResult", "thesis_assumptions", "pi_map"]


@dataclass(frozen=True)
class AssumptionResult:
    """One item of the thesis's chain of assumptions."""

    name: str
    verdict: str
    reason: str
    details: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {"verdict": self.verdict, "reason": self.reason, **self.details}


def _psi(s: np.ndarray, q: float, lam: float) -> np.ndarray:
    return q * np.sign(s) * np.maximum(np.abs(s) - lam, 0.0)


def pi_map(
    a: np.ndarray, F_inv: np.ndarray, L1: np.ndarray, q: float, lam: float, *, max_terms: int = 10_000
) -> np.ndarray:
    """Pi(a) = -sum_l F^(-l-1) L1 Psi_q^l(a) for a batch of a (rows).

    The sum is finite: Psi_q^l(a) is exactly zero after finitely many
    iterations when lambda > 0 or q < 1.
    """
    a = np.atleast_2d(np.asarray(a, dtype=float))
    out = np.zeros((a.shape[0], F_inv.shape[0]))
    term = a.copy()
    Fpow = F_inv.copy()
    for _ in range(max_terms):
        if not np.any(term):
            return out
        out -= term @ (Fpow @ L1).T
        term = _psi(term, q, lam)
        Fpow = Fpow @ F_inv
        if not np.all(np.isfinite(out)):
            break
    raise ArithmeticError("the series for Pi did not terminate")


def _lipschitz_search(
    f, dim: int, rng: np.random.Generator, scale: float, samples: int = 4000
) -> tuple[float, np.ndarray, np.ndarray]:
    """Largest ||f(a1) - f(a2)|| / ||a1 - a2|| found by sampling and local refinement."""
    from scipy.optimize import minimize

    mags = scale * np.exp(rng.uniform(np.log(0.05), np.log(50.0), (samples, 1)))
    a1 = rng.standard_normal((samples, dim)) * mags
    d = rng.standard_normal((samples, dim)) * mags * np.exp(rng.uniform(np.log(1e-3), 0, (samples, 1)))
    a2 = a1 + d
    num = np.linalg.norm(f(a1) - f(a2), axis=1)
    den = np.linalg.norm(a1 - a2, axis=1)
    ratios = num / den
    best = int(np.argmax(ratios))

    def neg(x: np.ndarray) -> float:
        x1, x2 = x[:dim], x[dim:]
        den = np.linalg.norm(x1 - x2)
        return 0.0 if den == 0 else -float(np.linalg.norm(f(x1) - f(x2)) / den)

    res = minimize(neg, np.concatenate([a1[best], a2[best]]), method="Nelder-Mead",
                   options={"maxiter": 2000, "xatol": 1e-10, "fatol": 1e-12})
    if -res.fun > ratios[best]:
        return float(-res.fun), res.x[:dim], res.x[dim:]
    return float(ratios[best]), a1[best], a2[best]


def thesis_assumptions(
    design: ObserverDesign,
    *,
    observability_holds: bool | None = None,
    seed: int = 0,
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

    Returns
    -------
    verdict : str
        fails if any item fails, else inconclusive if any is, else holds.
    items : list of AssumptionResult
    """
    rng = np.random.default_rng(seed)
    S = design.sensing
    A = design.system.A
    L1 = -design.gain.L
    F = A + L1 @ S
    q = float(design.shrink)
    lam = float(design.threshold or 0.0)
    eps = float(design.step)
    L2 = design.L2 if design.L2 is not None else np.eye(S.shape[0])
    p = S.shape[0]
    items: list[AssumptionResult] = []

    # Assumption 1
    if observability_holds is None:
        items.append(AssumptionResult("assumption_1", "inconclusive", "observability not checked"))
    else:
        items.append(AssumptionResult(
            "assumption_1", "holds" if observability_holds else "fails",
            "(A, C) is observable (see the observability check)" if observability_holds
            else "(A, C) is not observable (see the observability check)"))

    # Assumption 2 with Q = I (p x p)
    items.append(AssumptionResult(
        "assumption_2", "holds",
        "With Q = I (p x p; the thesis's n x n is a typo): Psi_q(0) = 0; |Psi_q(s)_i| = "
        f"q max(|s_i| - lambda, 0) < |s_i| for s_i != 0 (q = {q:g}, lambda = {lam:g}), so "
        "Psi_q(s)' Q Psi_q(s) < s' Q s for s != 0; and Psi_q is Lipschitz with constant q "
        "because soft thresholding is 1-Lipschitz. The property (5.21) "
        "Psi_q(s)' Q Psi_q(s) <= q^2 s' Q s also holds for this diagonal Q (it can fail for a "
        "non-diagonal Q).",
        {"Q": "identity", "lipschitz_psi": q}))

    # Lemma 1
    s_F = np.linalg.svd(F, compute_uv=False)
    # singularity relative to the plant's scale (a deadbeat F can be zero to rounding)
    scale_F = max(float(np.linalg.norm(A, 2)), float(np.linalg.norm(L1 @ S, 2)), float(s_F[0]),
                  np.finfo(float).tiny)
    singular = s_F[-1] <= 1e3 * F.shape[0] * EPS * scale_F
    rho_F = float(np.abs(np.linalg.eigvals(F)).max())
    claimed = float(np.linalg.norm(L1, 2)) / abs(rho_F - q) if abs(rho_F - q) > 0 else np.inf
    lemma_ok = False
    ell_pi = None
    F_inv = None
    if singular:
        items.append(AssumptionResult(
            "lemma_1", "fails",
            f"F = A + L1 C is singular (smallest singular value {s_F[-1]:.2e}; a deadbeat gain "
            f"makes it nilpotent), so Pi(a) = -sum F^(-l-1) L1 Psi_q^l(a) does not exist and the "
            f"change of variable eta = e - Pi(a_hat) of the proof is unavailable.",
            {"smallest_singular_value_F": float(s_F[-1]), "claimed_lipschitz": claimed}))
    else:
        F_inv = np.linalg.inv(F)
        ninv = float(np.linalg.norm(F_inv, 2))
        correct = (float(np.linalg.norm(L1, 2)) * ninv / (1 - q * ninv)) if q * ninv < 1 else np.inf

        def pi(a: np.ndarray) -> np.ndarray:
            return pi_map(a, F_inv, L1, q, lam)

        scale = max(lam, 1e-3)
        try:
            with np.errstate(over="raise", invalid="raise"):
                ratio, a1, a2 = _lipschitz_search(pi, p, rng, scale)
                sample = rng.standard_normal((200, p)) * scale * 5
                eq = F @ pi(sample).T + L1 @ sample.T - pi(_psi(sample, q, lam)).T
                residual = float(np.abs(eq).max() / max(1.0, np.abs(pi(sample)).max()))
        except (ArithmeticError, FloatingPointError):
            ratio = None
        if ratio is None:
            items.append(AssumptionResult(
                "lemma_1", "inconclusive",
                f"Pi cannot be evaluated in floating point: the powers of F^-1 overflow before "
                f"the series ends (||F^-1|| = {ninv:.3g})",
                {"claimed_lipschitz": claimed, "correct_bound": correct, "norm_F_inv": ninv}))
            F_inv = None
    if F_inv is not None and not singular:
        details = {"claimed_lipschitz": claimed, "correct_bound": correct,
                   "empirical_ratio": ratio, "equation_5_9_residual": residual,
                   "norm_F_inv": ninv, "spectral_radius_F": rho_F}
        if ratio > claimed * (1 + 1e-9):
            # the claimed constant is wrong, but Pi exists and the corrected bound is valid
            lemma_ok, ell_pi = bool(np.isfinite(correct)), (correct if np.isfinite(correct) else None)
            items.append(AssumptionResult(
                "lemma_1", "fails",
                f"the claimed Lipschitz constant ||L1|| / |lambda_max(F) - q| = {claimed:.4g} is "
                f"exceeded: |Pi(a1) - Pi(a2)| / |a1 - a2| = {ratio:.4g} for the pair in the "
                f"counterexample",
                {**details, "counterexample": {"a1": a1, "a2": a2}}))
        elif correct <= claimed:
            lemma_ok, ell_pi = True, correct
            items.append(AssumptionResult(
                "lemma_1", "holds",
                f"Pi exists (the series is finite) and is Lipschitz with constant <= {correct:.4g} "
                f"(= ||L1|| ||F^-1|| / (1 - q ||F^-1||)) <= the claimed {claimed:.4g}",
                details))
        else:
            lemma_ok, ell_pi = True, correct if np.isfinite(correct) else None
            items.append(AssumptionResult(
                "lemma_1", "inconclusive",
                f"Pi exists, but the claimed constant {claimed:.4g} is not proven: the series "
                f"gives {correct:.4g}; sampling found ratios up to {ratio:.4g}",
                details))

    # Assumption 3 with Q = I
    rho_a = None
    if F_inv is None:
        items.append(AssumptionResult(
            "assumption_3", "inconclusive",
            "it is stated in terms of Pi from Lemma 1, which does not exist for this gain"))
    else:
        def g(a: np.ndarray) -> np.ndarray:
            a = np.atleast_2d(a)
            v = a - eps * (S @ pi_map(a, F_inv, L1, q, lam).T + a.T).T @ L2.T
            return _psi(v, q, lam)

        mags = max(lam, 1e-3) * np.exp(rng.uniform(np.log(0.05), np.log(100.0), (4000, 1)))
        samples = rng.standard_normal((4000, p)) * mags
        ratios = np.sum(g(samples) ** 2, axis=1) / np.sum(samples**2, axis=1)
        worst = int(np.argmax(ratios))
        # then local optimisation from the worst samples
        from scipy.optimize import minimize

        def neg_ratio(a: np.ndarray) -> float:
            den = float(a @ a)
            return 0.0 if den == 0 else -float(np.sum(g(a) ** 2)) / den

        for start in np.argsort(ratios)[-1:]:
            res = minimize(neg_ratio, samples[start], method="Nelder-Mead",
                           options={"maxiter": 400, "xatol": 1e-10, "fatol": 1e-12})
            if -res.fun > ratios[worst]:
                samples = np.vstack([samples, res.x])
                ratios = np.append(ratios, -res.fun)
                worst = ratios.size - 1
        details = {"Q": "identity", "largest_ratio_found": float(ratios[worst]),
                   "search": "4000 samples over magnitudes 0.05-100 lambda, then Nelder-Mead"}
        bound = None
        if ell_pi is not None:
            bound = q * (float(np.linalg.norm(np.eye(p) - eps * L2, 2))
                         + eps * float(np.linalg.norm(L2, 2)) * float(np.linalg.norm(S, 2)) * ell_pi)
            details["proven_bound_sqrt_rho"] = bound
        if ratios[worst] >= 1.0:
            items.append(AssumptionResult(
                "assumption_3", "fails",
                f"for the a_hat in the counterexample the left side is {ratios[worst]:.4g} times "
                f"a_hat' Q a_hat, so no rho'' < 1 works",
                {**details, "counterexample": samples[worst]}))
        elif bound is not None and bound < 1.0:
            rho_a = bound**2
            items.append(AssumptionResult(
                "assumption_3", "holds",
                f"proven with rho'' = {rho_a:.4g} < 1 from |Psi_q(v)| <= q |v| and the Lipschitz "
                f"bound of Pi", details))
        else:
            items.append(AssumptionResult(
                "assumption_3", "inconclusive",
                f"no counterexample found (largest ratio found {ratios[worst]:.4g}) but no "
                f"proof either", details))

    # epsilon bound (5.20), with the eigenvalues the inequalities need
    if not (lemma_ok and rho_a is not None and ell_pi is not None):
        items.append(AssumptionResult(
            "epsilon_bound", "inconclusive",
            "the bound (5.20) needs Lemma 1 and Assumption 3, which are not established here"))
    else:
        lyap = lyapunov_certificate(F)
        if lyap.verdict != "holds" or lyap.P is None:
            items.append(AssumptionResult("epsilon_bound", "inconclusive",
                                          "F is not certified stable, so no P exists"))
        else:
            P = lyap.P
            p_eigs = np.linalg.eigvalsh(P)
            rho = 1.0 - 1.0 / float(p_eigs[-1])  # F'PF - P = -I  =>  F'PF <= rho P
            l2, lc, lpsi = float(np.linalg.norm(L2, 2)), float(np.linalg.norm(S, 2)), q
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
            details = {"epsilon_star": best_eps, "step": eps, "rho_P": rho,
                       "parameters_gamma_eta_gamma_a_mu": best_par}
            if best_par is not None and eps <= best_eps:
                items.append(AssumptionResult(
                    "epsilon_bound", "holds",
                    f"step = {eps:g} <= epsilon* = {best_eps:.4g} (corrected constants)", details))
            else:
                items.append(AssumptionResult(
                    "epsilon_bound", "inconclusive",
                    f"step = {eps:g} exceeds epsilon* = {best_eps:.4g}; the bound is sufficient, "
                    f"not necessary", details))

    verdicts = [i.verdict for i in items]
    overall = "fails" if "fails" in verdicts else ("inconclusive" if "inconclusive" in verdicts
                                                   else "holds")
    return overall, items
