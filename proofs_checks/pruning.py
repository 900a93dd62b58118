"""Claims of 003, Zheng and Anubi, *Attack-resilient weighted l1 observer with prior pruning*:
the successful attack of Theorem 2.1 and its proof, the stacked model (3), the Poisson-binomial
pmf (Lemma 3.1), the pruning (13)-(14) and its guarantee (21)-(22), and the simulation of Fig. 1.

Notation: the paper writes m for the sensors per step, k for the attacked ones, T for the window,
H = [C; CA; ...; CA^(T-1)] for the stacked matrix with N = Tm rows, (U_1, Sigma_1, V) for its
thin SVD and T (calligraphic) for the attacked rows; ssecert writes p for the sensors and s for
the attacked ones and passes H as one matrix ``M`` with one row per measurement. A window of
T = 1 step makes H = C, which the small counterexamples use.
"""

from __future__ import annotations

import functools
import itertools
import math
from fractions import Fraction
from typing import NamedTuple

import numpy as np
import scipy.optimize
import sympy as sp

from ssecert.estimators.pruning import (
    l1_decode,
    poisson_binomial_pmf,
    prune_support_prior,
    pruned_weighted_l1_window_observer,
)
from ssecert.estimators.pruning_attacks import successful_attack

from ._core import Finding, claim

__all__: list[str] = []


# -- Theorem 2.1: helpers shared by its three claims -----------------------------------------------


def _l1_minimisers_1d(h: list[int], y: list[Fraction]) -> tuple[list[Fraction], Fraction]:
    """Exact l1 decoder for one state: the minimisers of sum_i |y_i - h_i x| and the minimum.

    The objective is piecewise linear and convex with breakpoints y_i / h_i, so its minimum is
    attained at a breakpoint; two optimal breakpoints would make the whole segment optimal.
    """
    cost = lambda x: sum(abs(yi - hi * x) for hi, yi in zip(h, y))  # noqa: E731
    points = sorted({Fraction(yi) / hi for hi, yi in zip(h, y) if hi})
    best = min(cost(x) for x in points)
    return [x for x in points if cost(x) == best], best


def _l1_decode_lp(H: np.ndarray, y: np.ndarray) -> np.ndarray:
    """An l1 decoder of its own (min sum t s.t. -t <= y - H x <= t), independent of ssecert's."""
    N, n = H.shape
    eye = np.eye(N)
    A_ub = np.block([[-H, -eye], [H, -eye]])
    b_ub = np.concatenate([-y, y])
    cost = np.concatenate([np.zeros(n), np.ones(N)])
    bounds = [(None, None)] * n + [(0.0, None)] * N
    solution = scipy.optimize.linprog(cost, A_ub=A_ub, b_ub=b_ub, bounds=bounds, method="highs")
    if solution.status != 0:
        raise RuntimeError(f"the l1 linear program failed: {solution.message}")
    return np.asarray(solution.x[:n])


@functools.cache
def _thm21_instances() -> dict[str, np.ndarray]:
    """Random instances meeting Theorem 2.1's hypothesis (see _THM21_DRAWS), decoded by our LP.

    Safe rows are scaled (Gaussian rows alone rarely meet the condition) and of full column rank
    (else (7) is unbounded). With delta = V Sigma_1^-1 z, (7) maximises ||delta|| subject to
    ||H_(T^c) delta||_2 <= eps: delta = eps v / s for (s, v) the smallest singular pair of
    H_(T^c), and e_T = H_T delta. Fields: dev, alpha (printed), alpha2 (factor 2 restored), res
    (l1 residual), bound / bound2 (printed / corrected residual bounds), zl1, zl2 (norms of
    z_e^perp), wl1 (||U_(1,T^c) z_e||_1), gap (relative distance to ssecert's attack), draws.
    """
    rng = np.random.default_rng(2101)
    names = ("dev", "alpha", "alpha2", "res", "bound", "bound2", "zl1", "zl2", "wl1", "gap")
    rows: list[tuple[float, ...]] = []
    draws = 0
    while len(rows) < 60:
        draws += 1
        n = int(rng.integers(1, 4))
        N = int(rng.integers(n + 2, 9))
        n_safe = int(rng.integers(n, N))
        H = rng.standard_normal((N, n))
        safe = np.sort(rng.choice(N, n_safe, replace=False))
        attacked = np.setdiff1d(np.arange(N), safe)
        H[safe] *= 10.0 ** rng.uniform(-2.0, 1.0)
        U1, sig, Vt = np.linalg.svd(H, full_matrices=False)
        sig_bar = float(np.linalg.norm(U1[safe], 2))
        _, s_safe, Vt_safe = np.linalg.svd(H[safe])
        root = math.sqrt(n_safe)
        if sig_bar * root >= 1.0 or s_safe[-1] < 1e-9 * sig[0]:
            continue
        delta = Vt_safe[n - 1] / s_safe[n - 1]  # eps = 1
        e = np.zeros(N)
        e[attacked] = H[attacked] @ delta
        x_star = rng.standard_normal(n)
        y = H @ x_star + e
        x_hat = _l1_decode_lp(H, y)
        z_perp = sig * (Vt @ (delta - x_hat + x_star))  # x_hat = V Sigma^-1 (z* + z_e - z_perp)
        ref = successful_attack(H, attacked.tolist(), 1.0, scaling="paper", max_shift=1e12).attack
        rows.append(
            (
                float(np.linalg.norm(x_hat - x_star)),
                (1 - sig_bar * root) / (sig[-1] * sig_bar),
                (1 / sig_bar - 2 * root) / sig[-1],
                float(np.abs(y - H @ x_hat).sum()),
                root * sig_bar,
                root,
                float(np.abs(z_perp).sum()),
                float(np.linalg.norm(z_perp)),
                float(np.abs(H[safe] @ delta).sum()),
                min(np.abs(ref - e).max(), np.abs(ref + e).max()) / np.abs(e).max(),
            )
        )
    out = dict(zip(names, np.array(rows).T))
    out["draws"] = np.array(draws)
    return out


_THM21_DRAWS = (
    "60 instances meeting the hypothesis (kept from the draws), seed 2101: n ~ U{1,2,3}, N = Tm "
    "~ U{n+2..8}, |T^c| ~ U{n..N-1}, H Gaussian with its safe rows scaled by 10^U(-2,1), x* ~ "
    "N(0, I), eps = 1; attack (7)-(8) solved exactly, decoded by an LP (HiGHS) of the check's own"
)


class _Exact(NamedTuple):
    e: list[int]
    x_hat: list[Fraction]  # every minimiser of the l1 decoder
    residual: Fraction
    sig_bar: sp.Expr
    condition: bool  # sigma_bar_(T^c) sqrt(Tm - |T|) < 1
    alpha: sp.Expr


def _thm21_exact(h: list[int], eps: int) -> _Exact:
    """Exact quantities of Theorem 2.1 for n = 1, one step (H = C = h), row 1 attacked, x* = 0.

    U_1 = h/||h||, sigma = ||h||, sigma_bar_(T^c) = ||h_safe||/||h||; (7) gives V Sigma_1^-1 z_e
    = eps/||h_safe|| (an integer here), so e = (h_1 eps/||h_safe||, 0, ..., 0).
    """
    safe_sq = sum(v * v for v in h[1:])
    safe_norm = math.isqrt(safe_sq)
    if safe_norm**2 != safe_sq or eps % safe_norm:
        raise ValueError("the counterexamples use safe rows of integer norm dividing eps")
    e = [h[0] * eps // safe_norm] + [0] * (len(h) - 1)
    minimisers, residual = _l1_minimisers_1d(h, [Fraction(v) for v in e])
    sig_bar = sp.Integer(safe_norm) / sp.sqrt(sum(v * v for v in h))
    condition = sig_bar * sp.sqrt(len(h) - 1)
    alpha = eps / (sp.sqrt(sum(v * v for v in h)) * sig_bar) * (1 - condition)
    return _Exact(e, minimisers, residual, sig_bar, bool(condition < 1), alpha)


@claim(
    "pruning.thm2_1",
    where="003 Thm 2.1, (6)-(8)",
    statement="Given attack supports with |T_i| <= k and z_e optimal for (7) (maximise "
    "||Sigma_1^-1 z||_2 s.t. ||U_(1,T^c) z||_2 <= eps): if sigma_bar_(T^c) sqrt(Tm - |T|) < 1, "
    "the FDIA (8) e_T = U_(1,T) z_e, e_(T^c) = 0 is (eps, alpha)-successful against the l1 "
    "decoder (4) and detector (5), i.e. ||x* - D(y_T)|| >= alpha and D_eps(y_T) = 0, with "
    "alpha = eps / (sigma sigma_bar_(T^c)) (1 - sigma_bar_(T^c) sqrt(Tm - |T|)).",
    recorded="fails",
)
def thm2_1() -> Finding:
    ex = _thm21_exact([6, 3, 4], 5)
    if not (ex.x_hat == [0] and ex.residual == 6 and ex.condition):
        raise AssertionError("the counterexample of Theorem 2.1 did not come out as expected")
    inst = _thm21_instances()
    dev, alp, res = inst["dev"], inst["alpha"], inst["res"]
    short, loud = dev < alp - 1e-9, res > 1.0 + 1e-9
    return Finding(
        "fails",
        "Theorem 2.1 fails on both counts of (6). With one step (H = C = (6, 3, 4)^T, n = 1) "
        "and sensor 1 attacked, sigma_bar_(T^c) sqrt(Tm - |T|) = sqrt(50/61) < 1, yet the "
        "attack (8) e = (6, 0, 0) built from (7) with eps = 5 is rejected by the l1 decoder "
        "(the safe rows outweigh the attacked one: D(y_T) = x*) and sets the detector off "
        "(residual 6 > eps). The proof's two bounds are wrong (pruning.thm2_1_alpha, "
        "pruning.thm2_1_detector). (With fewer than n safe rows, or safe rows of deficient "
        "rank, (7) is unbounded and has no optimal z_e: the theorem then says nothing.) On "
        f"{len(dev)} random instances meeting the hypothesis the "
        f"deviation fell short of alpha in {int(short.sum())} (worst margin "
        f"{float((dev - alp).min()):.2g}) and the detector fired in {int(loud.sum())}.",
        {
            "method": "exhaustive+randomised",
            "counterexample_check": "exact: the 1-state l1 objective in rationals at all its "
            "breakpoints; alpha and the condition in sympy",
            "alpha_exact": str(ex.alpha),
            "condition_value": math.sqrt(50 / 61),
            "random_instances": len(dev),
            "random_distribution": _THM21_DRAWS,
            "draws": int(inst["draws"]),
            "deviation_below_alpha": int(short.sum()),
            "detector_fired": int(loud.sum()),
            "worst_deviation_minus_alpha": float((dev - alp).min()),
            "largest_residual_over_eps": float(res.max()),
            "ssecert_successful_attack_max_relative_gap": float(inst["gap"].max()),
        },
        counterexample={
            "T": 1,
            "C": [[6], [3], [4]],
            "attacked_rows": [1],
            "eps": 5,
            "x_star": [0],
            "e": [6, 0, 0],
            "alpha": float(ex.alpha),
            "shows": "H = C; (7) gives z_e = sqrt(61), V Sigma_1^-1 z_e = 1. sigma_bar_(T^c) = "
            "||U_1 rows 2,3|| = 5/sqrt(61), sqrt(Tm - |T|) = sqrt(2): the condition is "
            "sqrt(50/61) = 0.905 < 1. D(y_T) = argmin_x |6 - 6x| + 3|x| + 4|x| = 0 (cost 6; "
            "x = 1 costs 7), so ||x* - D(y_T)|| = 0 < alpha = 1 - sqrt(50/61) = 0.0946, and "
            "||y_T - H D(y_T)||_1 = 6 > eps = 5: D_eps(y_T) = 1. Any x* gives the same.",
        },
    )


@claim(
    "pruning.thm2_1_alpha",
    where="003 Thm 2.1, proof and footnote 1",
    statement="In the proof of Theorem 2.1: ||z_e^perp||_2 <= ||z_e^perp||_1 <= "
    "||U_(1,T^c) z_e||_1 (footnote 1: f(z_e^perp) <= f(0)), hence ||x_hat - x*||_2 >= "
    "eps/sigma (1/sigma_bar_(T^c) - sqrt(Tm - |T|)) = alpha.",
    recorded="fails",
)
def thm2_1_alpha() -> Finding:
    ex = _thm21_exact([1, 2], 2)  # z_e = sqrt(5); z_perp = z_e - sqrt(5) D(y_T) = sqrt(5) > 2
    if not (ex.x_hat == [0] and ex.residual == 1 and ex.condition):
        raise AssertionError("the counterexample of the alpha bound did not come out as expected")
    inst = _thm21_instances()
    dev, alp, alc = inst["dev"], inst["alpha"], inst["alpha2"]
    zl1, zl2, wl1 = inst["zl1"], inst["zl2"], inst["wl1"]
    return Finding(
        "fails",
        "Footnote 1 only gives f(z_e^perp) <= f(0), i.e. ||U_1 z_e^perp - w||_1 <= ||w||_1 with "
        "w the safe part U_(1,T^c) z_e placed in its rows; that bounds ||U_1 z_e^perp||_1 by "
        "2 ||w||_1 (triangle inequality), not ||z_e^perp||_1 by ||w||_1. The factor 2 is "
        "lost, so alpha as printed is no lower bound on the decoder's deviation: for H = C = "
        "(1, 2)^T, sensor 1 attacked and eps = 2 the decoder ignores the attack (deviation 0 < "
        "alpha = 0.106) while the detector is silent. The corrected alpha' = eps/sigma "
        "(1/sigma_bar - 2 sqrt(Tm - |T|)) held on every random instance (positive on "
        f"{int((alc > 0).sum())}; worst deviation - alpha' = {float((dev - alc).min()):.3g}); "
        "alpha as printed failed on "
        f"{int((dev < alp - 1e-9).sum())} of {len(dev)}, the footnote's inequality on "
        f"{int((zl1 > wl1 + 1e-9).sum())}.",
        {
            "method": "exhaustive+randomised",
            "random_instances": len(dev),
            "random_distribution": _THM21_DRAWS,
            "alpha_printed_violated": int((dev < alp - 1e-9).sum()),
            "footnote_inequality_violated": int((zl1 > wl1 + 1e-9).sum()),
            "corrected_alpha_violated": int((dev < alc - 1e-9).sum()),
            "corrected_alpha_positive": int((alc > 0).sum()),
            "corrected_alpha_worst_margin": float((dev - alc).min()),
            "corrected_z_perp_bound_worst_margin": float((2 * wl1 - zl2).min()),
        },
        counterexample={
            "T": 1,
            "C": [[1], [2]],
            "attacked_rows": [1],
            "eps": 2,
            "x_star": [0],
            "e": [1, 0],
            "alpha": float(ex.alpha),
            "shows": "H = C; U_1 = (1, 2)^T/sqrt(5), z_e = sqrt(5), sigma = sqrt(5), "
            "sigma_bar_(T^c) = 2/sqrt(5) (condition 0.894 < 1). w = (0, 2): z_e^perp = argmin_z "
            "|z/sqrt(5)| + |2z/sqrt(5) - 2| = sqrt(5), so ||z_e^perp||_1 = 2.236 > ||w||_1 = 2. "
            "D(y_T) = argmin_x |1 - x| + 2|x| = 0 = x*: deviation 0 < alpha = 1 - 2/sqrt(5) = "
            "0.106, with residual 1 <= eps (detector silent).",
        },
    )


@claim(
    "pruning.thm2_1_detector",
    where="003 Thm 2.1, proof, last display",
    statement="In the proof of Theorem 2.1: ||y_T - H x_hat||_1 <= sqrt(Tm - |T|) "
    "sigma_bar_(T^c) eps, so the detector (5) stays silent when sigma_bar_(T^c) sqrt(Tm - |T|) "
    "< 1.",
    recorded="fails",
)
def thm2_1_detector() -> Finding:
    ex = _thm21_exact([10, 3, 4], 5)
    bound = float(ex.sig_bar * sp.sqrt(2) * 5)
    if not (ex.x_hat == [1] and ex.residual == 7 and ex.condition):
        raise AssertionError("the counterexample of the residual bound did not come out")
    inst = _thm21_instances()
    res, printed, corrected = inst["res"], inst["bound"], inst["bound2"]
    return Finding(
        "fails",
        "The last display bounds the decoder's l1 residual by sqrt(Tm - |T|) sigma_bar eps, "
        "but f(z_e^perp) <= f(0) = ||U_(1,T^c) z_e||_1 <= sqrt(Tm - |T|) ||U_(1,T^c) z_e||_2 "
        "<= sqrt(Tm - |T|) eps: the constraint of (7) already bounds the l2 norm by eps, the "
        "factor sigma_bar has no ground. With H = C = (10, 3, 4)^T, sensor 1 attacked and "
        "eps = 5 the condition holds (sqrt(2/5) < 1), the attack shifts the estimate by 1 but "
        "leaves residual 7 > sqrt(10) = 3.16 (the printed bound) and > eps: the detector "
        "fires. With one safe row the corrected bound is eps itself; with more, (7) would need "
        "the budget eps / sqrt(Tm - |T|) for the detector to stay silent. On the random "
        f"instances the printed bound failed in {int((res > printed + 1e-9).sum())} of "
        f"{len(res)}, the corrected one in {int((res > corrected + 1e-9).sum())}.",
        {
            "method": "exhaustive+randomised",
            "random_instances": len(res),
            "random_distribution": _THM21_DRAWS,
            "printed_bound_violated": int((res > printed + 1e-9).sum()),
            "corrected_bound_violated": int((res > corrected + 1e-9).sum()),
            "corrected_bound_worst_margin": float((corrected - res).min()),
            "largest_residual_over_printed_bound": float((res / printed).max()),
        },
        counterexample={
            "T": 1,
            "C": [[10], [3], [4]],
            "attacked_rows": [1],
            "eps": 5,
            "x_star": [0],
            "e": [10, 0, 0],
            "shows": "H = C; U_1 = H/sqrt(125), sigma_bar_(T^c) = 1/sqrt(5), sqrt(Tm - |T|) = "
            "sqrt(2): condition 0.632 < 1. (7) gives V Sigma_1^-1 z_e = eps/||(3, 4)|| = 1. "
            "D(y_T) = argmin_x 10|1 - x| + 7|x| = 1, residual ||y_T - H D(y_T)||_1 = 7 > "
            f"sqrt(2) sigma_bar eps = {bound:.4f} and > eps = 5: D_eps(y_T) = 1.",
        },
    )


# -- The stacked model (3) -------------------------------------------------------------------------


@claim(
    "pruning.eq3_order",
    where="003 Sec. II, (3)",
    statement="Iterating (2) over T steps gives y_T = H x_(i-T+1) + e_T with y_T = [y_i; "
    "y_(i-1); ...; y_(i-T+1)] and H = [C; CA; ...; CA^(T-1)].",
    recorded="fails",
)
def eq3_order() -> Finding:
    a, c, x = sp.symbols("a c x")  # scalar A = a, C = c, x = x_(i-2), window T = 3
    y_oldest_first = sp.Matrix([c * a**j * x for j in range(3)])  # y_(i-2), y_(i-1), y_i by (2)
    H = sp.Matrix([c, c * a, c * a**2])
    gap = sp.factor((sp.Matrix(y_oldest_first[::-1]) - H * x)[0])
    if gap == 0 or sp.expand(y_oldest_first - H * x) != sp.zeros(3, 1):
        raise AssertionError("the symbolic check of (3) did not come out")
    return Finding(
        "fails",
        "Iterating (2), y_i, the newest measurement, is C A^(T-1) x_(i-T+1), while the first "
        "block row of H is C: as printed, (3) pairs y_i with C. It holds with y_T stacked "
        "oldest first (or H reversed), which is what ssecert does (row j*m + i is sensor i at "
        "step j of the window). As printed (3) is well-formed and false, so it fails; it looks "
        "like a misprint of the stacking order, and corrected to y_T = [y_(i-T+1); ...; y_i] "
        "it holds (sympy). The slip only reorders rows and changes no later argument.",
        {"method": "symbolic", "scalar_T3_first_entry_of_y_T_minus_H_x": str(gap)},
        counterexample={
            "A": [[2]],
            "C": [[1]],
            "T": 2,
            "x_(i-1)": [1],
            "e_T": [0, 0],
            "shows": "y_(i-1) = C x_(i-1) = 1 and y_i = C A x_(i-1) = 2, so y_T = [y_i; y_(i-1)] = "
            "(2, 1), while H x_(i-1) = [C; C A] x_(i-1) = (1, 2).",
        },
    )


# -- Lemma 3.1 and the pruning (13)-(14) -----------------------------------------------------------


def _exact_pmf(probs: list[Fraction]) -> list[Fraction]:
    """Pr{sum eps_i = j}, j = 0..N, by enumerating the 2^N outcomes (exact)."""
    pmf = [Fraction(0)] * (len(probs) + 1)
    for outcome in itertools.product((0, 1), repeat=len(probs)):
        pmf[sum(outcome)] += math.prod(
            (p if o else 1 - p for p, o in zip(probs, outcome)), start=Fraction(1)
        )
    return pmf


def _lemma_pmf(probs: list[Fraction]) -> list[Fraction]:
    """Lemma 3.1 as printed: beta * [-s_1; 1] * ... * [-s_N; 1], s_i = -(1 - p_i)/p_i."""
    r = [Fraction(1)]
    for p in probs:  # convolve with [-s_i; 1] = [(1 - p_i)/p_i; 1]
        r = [a * (1 - p) / p + b for a, b in zip([*r, Fraction(0)], [Fraction(0), *r])]
    beta = Fraction(1)
    for p in probs:
        beta *= p
    return [beta * v for v in r]


@claim(
    "pruning.lemma3_1",
    where="003 Lemma 3.1, (12)",
    statement="For independent eps_i ~ B(1, p_i), i = 1..Tm: Pr{sum_i eps_i = k - 1} = r(k), "
    "k = 1..Tm+1, where r = beta [-s_1; 1] * [-s_2; 1] * ... * [-s_Tm; 1] (* convolution), "
    "beta = prod_i p_i and s_i = -(1 - p_i)/p_i.",
    recorded="holds",
)
def lemma3_1() -> Finding:
    t = sp.symbols("t")
    for N in (1, 2, 3, 4):
        p = sp.symbols(f"p1:{N + 1}", positive=True)
        # convolving the vectors [-s_i; 1] multiplies the polynomials -s_i + t
        coeffs = sp.Poly(sp.prod([(1 - pi) / pi + t for pi in p]), t).all_coeffs()[::-1]
        for j in range(N + 1):
            brute = sum(
                sp.prod([p[i] if i in chosen else 1 - p[i] for i in range(N)])
                for chosen in itertools.combinations(range(N), j)
            )
            if sp.expand(sp.prod(p) * coeffs[j] - brute) != 0:
                raise AssertionError(f"Lemma 3.1 differs from the pmf at Tm = {N}, k = {j + 1}")
    grid = [Fraction(1, 4), Fraction(1, 2), Fraction(3, 4), Fraction(1)]
    count, worst = 0, 0.0
    for N in (1, 2, 3):
        for ps in itertools.product(grid, repeat=N):
            exact = _exact_pmf(list(ps))
            if _lemma_pmf(list(ps)) != exact:
                raise AssertionError(f"Lemma 3.1 fails for p = {ps}")
            ours = poisson_binomial_pmf(np.array(ps, dtype=float))
            worst = max(worst, float(np.abs(ours - np.array(exact, dtype=float)).max()))
            count += 1
    return Finding(
        "holds",
        "Convolving the vectors [-s_i; 1] multiplies the polynomials (1 - p_i)/p_i + t, and "
        "beta times their product is prod_i (1 - p_i + p_i t), the probability generating "
        "function of sum_i eps_i; so r(k), the coefficient of t^(k-1), is Pr{sum eps_i = k - "
        "1} (by induction on Tm, one factor per Bernoulli variable). Convolution of arrays "
        "does not depend on which end holds the constant term, so either reading of the "
        "vectors gives the same r. The formula needs p_i > 0 (s_i divides by p_i), which the "
        "model (10) grants (p_i in R_+); ssecert's poisson_binomial_pmf uses the product form, "
        "which also allows p_i = 0.",
        {
            "method": "symbolic+exhaustive",
            "symbolic": "sympy, symbolic p_i > 0, Tm = 1..4: beta * coefficients of "
            "prod((1 - p_i)/p_i + t) against the sum over subsets of prod p_i prod (1 - p_j)",
            "exhaustive": "exact rationals, every p in {1/4, 1/2, 3/4, 1}^Tm, Tm = 1..3, "
            "against the enumeration of the 2^Tm outcomes",
            "exhaustive_instances": count,
            "ssecert_poisson_binomial_pmf_max_abs_error": worst,
        },
    )


def _l_first(tail: list[Fraction], eta: Fraction) -> int:
    """(13), first form: max{k : Pr{S >= k} >= eta} (k = 0 always qualifies)."""
    return max(k for k in range(len(tail)) if tail[k] >= eta)


@claim(
    "pruning.eq13_index",
    where="003 (13)",
    statement="l_eta = max{k | Pr{sum_(i in T_hat^c) eps_i >= k} >= eta} = max{k | "
    "sum_(i=1)^(k+1) r_(T_hat^c)(i) <= 1 - eta}, with r from (12).",
    recorded="fails",
)
def eq13_index() -> Finding:
    grid = [Fraction(i, 5) for i in range(1, 6)]
    cases = one_less = empty = 0
    for N in (1, 2, 3, 4):
        for ps in itertools.combinations_with_replacement(grid, N):
            pmf = _exact_pmf(list(ps))
            tail = [sum(pmf[k:], Fraction(0)) for k in range(N + 1)]
            for eta in (Fraction(i, 10) for i in range(1, 10)):
                first = _l_first(tail, eta)
                second = [k for k in range(N + 1) if sum(pmf[: k + 1]) <= 1 - eta]
                upper_k = max(k for k in range(N + 1) if sum(pmf[:k]) <= 1 - eta)
                if upper_k != first:
                    raise AssertionError(f"(13) with the sum to k differs at p = {ps}, eta = {eta}")
                cases += 1
                if first >= 1 and max(second) == first - 1:
                    one_less += 1
                elif first == 0 and not second:
                    empty += 1
                else:
                    raise AssertionError(f"unexpected (13) case p = {ps}, eta = {eta}")
    return Finding(
        "fails",
        "With r(i) = Pr{S = i - 1} from (12), sum_(i=1)^(k+1) r(i) = Pr{S <= k}, so the second "
        "form's condition for k is Pr{S >= k + 1} >= eta, the first form's condition for k + "
        "1: the second form gives l_eta - 1 (and an empty set, no maximum, when l_eta = 0). "
        "The words ('the maximum number of safe nodes correctly localized with probability at "
        "least eta') are the first form, which ssecert follows; the printed second form prunes "
        "one row more, harmless for (22) but not the same l_eta. The code published with the "
        "paper computes the second form. As printed the second form is well-formed and false, "
        "so (13) fails; it looks like a misprint of the upper limit: with sum_(i=1)^k r(i) <= 1 - "
        "eta it is the first form (Pr{S <= k - 1} <= 1 - eta iff Pr{S >= k} >= eta), which held "
        "on every case.",
        {
            "method": "symbolic+exhaustive",
            "identity": "sum_(i=1)^(k+1) r(i) <= 1 - eta <=> Pr{S <= k} <= 1 - eta <=> "
            "Pr{S >= k + 1} >= eta",
            "exhaustive": "exact rationals: Tm = 1..4 rows, every multiset of p_i in {1/5, "
            "2/5, ..., 1}, eta in {1/10, ..., 9/10}",
            "cases": cases,
            "second_form_one_less": one_less,
            "second_form_empty": empty,
        },
        counterexample={
            "p": [0.9],
            "eta": 0.8,
            "r": [0.1, 0.9],
            "shows": "one row, p_1 = 9/10, eta = 4/5: Pr{S >= 1} = 9/10 >= 4/5, so the first "
            "form gives l_eta = 1; the second needs r(1) + r(2) = 1 <= 1/5 for k = 1 (false) "
            "and r(1) = 1/10 <= 1/5 for k = 0, so it gives l_eta = 0.",
        },
    )


def _bound17(probs: np.ndarray, safe_count: float, literal: bool = False) -> float:
    """The right side of (17): 1 - e (1 - (e - 1) sum p_i / (e |T^c|))^|T^c|, the proof's
    binomial-MGF bound; with ``literal``, e^|T^c| in place of e |T^c|, as the text prints it."""
    scale = math.e**safe_count if literal else math.e * safe_count
    return 1.0 - math.e * (1.0 - (math.e - 1) * float(np.sum(probs)) / scale) ** safe_count


@claim(
    "pruning.ppv",
    where="003 Thm 3.2, proof, (21)-(22)",
    statement="Under the uncertainty model (10), (16) and eta satisfying (17), with l_eta from "
    "(13) and the pruned prior T_hat_eta^c from (14): Pr{0 <= l_eta <= ||q o q_hat||_0} >= eta "
    "(21), hence Pr{PPV_eta = 1} >= eta (22).",
    recorded="fails",
)
def ppv() -> Finding:
    # Tm = 4 rows, all declared safe by the prior, p_i = 7/10, eta = 3/5
    p, eta = Fraction(7, 10), Fraction(3, 5)
    tail = [sum(_exact_pmf([p] * 4)[k:], Fraction(0)) for k in range(5)]
    l_eta = _l_first(tail, eta)
    ppv_one = p**l_eta  # the kept rows are right independently, each with probability p
    b17 = (_bound17(np.full(4, 0.7), 4), _bound17(np.full(4, 0.7), 2.8))
    lit17 = (_bound17(np.full(4, 0.7), 4, True), _bound17(np.full(4, 0.7), 2.8, True))
    pruned = prune_support_prior(range(4), np.full(4, 0.7), reliability=0.6)
    if not (l_eta == pruned.count == 3 and ppv_one < eta <= min(b17) and max(lit17) < 0):
        raise AssertionError("the counterexample of (22) did not come out as expected")
    p_A = Fraction(3, 10)  # (16): sum p_i = 28/10 > Tm p_A = 12/10
    if not 4 * p > 4 * p_A:
        raise AssertionError("(16) does not hold in the counterexample")
    draws = np.random.default_rng(2202).random((20000, 4)) < 0.7  # eps_i of (10)
    frequency = float(np.mean(draws[:, list(pruned.trusted)].all(axis=1)))
    # random instances: every row declared safe, p_i ~ U(0.5, 1), eta ~ U(0.5, bound of (17))
    rng = np.random.default_rng(2203)
    margins: list[float] = []
    eq21 = True
    while len(margins) < 200:
        probs = rng.uniform(0.5, 1.0, int(rng.integers(3, 31)))
        top = _bound17(probs, probs.size)
        if top <= 0.5:
            continue
        eta_r = float(rng.uniform(0.5, top))
        pr = prune_support_prior(range(probs.size), probs, reliability=eta_r)
        margins.append(float(np.prod(probs[list(pr.trusted)])) - eta_r)
        pmf = functools.reduce(np.convolve, ([1 - q, q] for q in probs), np.ones(1))
        eq21 &= float(pmf[pr.count :].sum()) >= eta_r - 1e-12  # (21), independently of ssecert
    bad = int((np.array(margins) < 0).sum())
    return Finding(
        "fails",
        "(21) holds: it is the definition (13) of l_eta (Pr{S >= l_eta} >= eta for S the number "
        "of prior-safe rows on which the prior is right). The step to (22) does not: knowing "
        "that at least l_eta rows of the prior are right does not make the l_eta rows chosen "
        "by (14) (largest p_i) the right ones; under (10) each kept row is right independently "
        "with probability p_i, so Pr{PPV_eta = 1} = prod of the kept p_i, far below eta once "
        "l_eta > 1. With 4 rows declared safe, p_i = 7/10, p_A = 3/10 and eta = 3/5, which "
        "satisfy (16) and (17), l_eta = 3 and Pr{PPV_eta = 1} = 0.343 < 0.6. On 200 random "
        f"instances meeting (17), (22) failed in {bad}. How (17) is read: the conversion prints "
        "e^{|T^c|} in its denominator; the check uses e |T^c|, the binomial moment generating "
        "function at -1 that the proof invokes (M(-1) = (1 - (e - 1) sum p_i / (e |T^c|))^|T^c| "
        "for the binomial approximation). Read literally, no eta in (0, 1) satisfies (17) here: "
        f"its right side is {lit17[0]:.4f} with |T^c| = 4 ({lit17[1]:.4f} with |T^c| = 2.8).",
        {
            "method": "exhaustive+randomised",
            "counterexample_exact": f"Pr{{S >= 3}} = {tail[3]}, Pr{{S >= 4}} = {tail[4]}, "
            f"Pr{{PPV = 1}} = {ppv_one}; ssecert's pruning keeps rows {pruned.trusted}",
            "monte_carlo": f"20000 draws of eps (seed 2202): PPV_eta = 1 in {frequency:.4f}",
            "bound_17_with_|T^c|_4_and_2.8": list(b17),
            "bound_17_read_literally_e^|T^c|_with_|T^c|_4_and_2.8": list(lit17),
            "random_instances": len(margins),
            "random_distribution": "seed 2203: Tm ~ U{3..30} rows all declared safe, p_i ~ "
            "U(0.5, 1), eta ~ U(0.5, right side of (17) with |T^c| = Tm); draws whose (17) "
            "bound is <= 0.5 skipped",
            "violations_of_22": bad,
            "worst_margin_Pr_minus_eta": min(margins),
            "eq21_held_on_all": bool(eq21),
        },
        counterexample={
            "Tm": 4,
            "q_hat": [1, 1, 1, 1],
            "p": [0.7, 0.7, 0.7, 0.7],
            "p_A": 0.3,
            "eta": 0.6,
            "l_eta": 3,
            "shows": "S = sum eps_i ~ Binomial(4, 7/10): Pr{S >= 3} = 0.6517 >= 3/5 > Pr{S >= 4} "
            "= 0.2401, so l_eta = 3 and (14) keeps 3 rows; each is right with probability 7/10 "
            "independently, so Pr{PPV_eta = 1} = (7/10)^3 = 0.343 < eta = 0.6. (16) with p_A = "
            "3/10: sum p_i = 2.8 > Tm p_A = 1.2 (expected attacked rows). (17) read with e |T^c| "
            "(the proof's binomial MGF bound; the text prints e^{|T^c|}): its right side 1 - e (1 "
            "- (e - 1) sum p_i / (e |T^c|))^|T^c| is "
            f"{b17[0]:.3f} with |T^c| = 4 and {b17[1]:.3f} with |T^c| = 2.8 (= Tm (1 - p_A)), "
            "both >= 0.6. Read literally with e^{|T^c|}, it is "
            f"{lit17[0]:.4f} and {lit17[1]:.4f}: no eta in (0, 1) would satisfy (17).",
        },
    )


# -- Sec. IV-A, Fig. 1: the success rate beyond 50 % attacked sensors ------------------------------

# m = 20 sensors, n = 10 states, a window of T = 5 steps, 20 runs per attacked-sensor count
_M, _N, _WINDOW, _RUNS, _LEVELS, _SEED = 20, 10, 5, 20, (12, 14, 16), 1901
_T_R, _ETA, _OMEGA = 0.6, 0.9, 0.05  # true rate, reliability of (13), weight of (15)


def _fig1_run(rng: np.random.Generator, attacked: int) -> dict[str, bool]:
    """One trial: a plant, an attack (8) on `attacked` sensors, the l1 and pruned estimates."""
    A = rng.standard_normal((_N, _N))
    A /= np.max(np.abs(np.linalg.eigvals(A)))
    C = rng.standard_normal((_M, _N))
    H = np.vstack([C @ np.linalg.matrix_power(A, j) for j in range(_WINDOW)])  # oldest first
    x = rng.standard_normal(_N)
    y = H @ x
    sensors = rng.choice(_M, attacked, replace=False)
    rows = np.array([j * _M + i for j in range(_WINDOW) for i in sensors])
    safe = np.ones(_WINDOW * _M, dtype=bool)
    safe[rows] = False
    # (7)-(8): the state shift along the weakest direction of the safe rows, sized in l1 so
    # that the detector (5) cannot fire (its residual is at most ||H_(T^c) delta||_1)
    eps = 0.01 * float(np.abs(y).sum())
    direction = np.linalg.svd(H[safe])[2][-1]
    y[rows] += H[rows] @ direction * 0.999 * eps / float(np.abs(H[safe] @ direction).sum())

    def ok(x_hat: np.ndarray) -> bool:
        return bool(np.linalg.norm(x_hat - x) < 1e-3 * np.linalg.norm(x))

    x_l1 = l1_decode(H, y)
    out = {"l1": ok(x_l1), "silent": float(np.abs(y - H @ x_l1).sum()) <= eps}
    N = _WINDOW * _M
    for model in ("paper", "code"):
        if model == "paper":  # (10): p_i with mean T_r, the prior right w.p. p_i independently
            probs = rng.uniform(2 * _T_R - 1, 1.0, N)
            right = rng.random(N) < probs
        else:  # the published code: p_i >= 1/2 w.p. T_r, the prior right iff p_i > 1/2
            high = rng.random(N) < _T_R
            probs = np.where(high, rng.uniform(0.5, 1.0, N), rng.uniform(0.0, 0.5, N))
            right = probs > 0.5
        prior_safe = np.flatnonzero(np.where(right, safe, np.logical_not(safe))).tolist()
        estimate = pruned_weighted_l1_window_observer(
            H, y, prior_safe, probs, sensors=_M, reliability=_ETA, omega=_OMEGA
        )
        out[model] = ok(estimate.x_hat)
        out[model + "_ppv1"] = bool(np.all(safe[list(estimate.trusted)]))
    return out


def _ppv_one(P_A: float, draws: int, seed: int) -> tuple[float, float, float]:
    """Pr{PPV_eta = 1} of the pruned prior at attacked share P_A (m = 20, T = 5, T_r = 0.6,
    eta = 0.9), computed for each prior drawn as in _fig1_run's model (10): l_eta from the
    Poisson-binomial pmf (12) by convolution, the kept rows by (14), and Pr{PPV_eta = 1 | prior}
    = prod of the kept p_i (under (10) each is safe with probability p_i).  Returns its mean
    and largest value over the priors, and the mean when each row is attacked with prior
    probability P_A (Bayes: safe given the prior with p_i (1 - P_A) / (p_i (1 - P_A) +
    (1 - p_i) P_A))."""
    rng = np.random.default_rng([seed, round(100 * P_A)])
    N, paper, bayes = _WINDOW * _M, [], []
    for _ in range(draws):
        safe = np.ones(_M, dtype=bool)
        safe[rng.choice(_M, round(P_A * _M), replace=False)] = False
        probs = rng.uniform(2 * _T_R - 1, 1.0, N)
        right = rng.random(N) < probs
        prior_safe = np.flatnonzero(
            np.where(right, np.tile(safe, _WINDOW), ~np.tile(safe, _WINDOW))
        )
        pmf = functools.reduce(np.convolve, ([1 - v, v] for v in probs[prior_safe]), np.ones(1))
        tail = np.cumsum(pmf[::-1])[::-1]  # Pr{S >= k}, k = 0..|T_hat^c|
        l_eta = int(np.flatnonzero(tail >= _ETA).max())
        kept = probs[prior_safe][np.argsort(-probs[prior_safe], kind="stable")[:l_eta]]
        paper.append(float(np.prod(kept)))
        posterior = kept * (1 - P_A) / (kept * (1 - P_A) + (1 - kept) * P_A)
        bayes.append(float(np.prod(posterior)))
    return float(np.mean(paper)), float(np.max(paper)), float(np.mean(bayes))


@claim(
    "pruning.fifty_percent",
    where="003 Sec. I and Sec. IV-A (Fig. 1)",
    statement="The l1 observer without prior cannot work when more than 1/2 of the nodes are "
    "attacked; the weighted l1 observer with the pruned prior (T_r = 0.6, m = 20, n = 10, "
    "attack (8)) keeps working beyond 50 % attacked nodes ('the resiliency is improved a lot').",
    recorded="conditional",
)
def fifty_percent() -> Finding:
    keys = ("l1", "paper", "code", "paper_ppv1", "code_ppv1", "silent")
    rates: dict[str, list[float]] = {k: [] for k in keys}
    for attacked in _LEVELS:
        runs = [
            _fig1_run(np.random.default_rng([_SEED, attacked, r]), attacked) for r in range(_RUNS)
        ]
        for key in keys:
            rates[key].append(float(np.mean([run[key] for run in runs])))
    P_A = [a / _M for a in _LEVELS]
    levels = ", ".join(f"{p:.1f}" for p in P_A)
    ppv = {f"{P:.1f}": _ppv_one(P, 100, 1902) for P in (0.5, 0.6, 0.7, 0.8)}
    if max(v[1] for v in ppv.values()) > 0.1:
        raise AssertionError(f"the pruned prior is entirely right too often: {ppv}")
    l1_fails = max(rates["l1"]) <= 0.1
    code_works = [rate >= 0.5 for rate in rates["code"]]
    upto = max((P for P, w in zip(P_A, code_works) if w), default=0.5)
    if l1_fails and min(rates["paper"]) >= 0.5 and all(code_works):
        verdict = "holds"
    else:
        verdict = "conditional" if l1_fails and code_works[0] else "fails"
    pct = lambda v: ", ".join(f"{100 * r:.0f}%" for r in v)  # noqa: E731
    return Finding(
        verdict,
        f"Measured at P_A = {levels} ({_RUNS} random plants each, attack (8) "
        "silent to the detector, success = relative error < 0.1 %): the l1 observer without "
        f"prior succeeds in {pct(rates['l1'])}, so it does fail beyond 1/2. The pruned weighted "
        f"l1 observer succeeds in {pct(rates['paper'])} under the paper's own uncertainty model "
        "(10) (each prior answer right independently with probability p_i, E[p_i] = T_r = "
        "0.6), where the pruned prior is almost never entirely right (PPV_eta = 1 in "
        f"{pct(rates['paper_ppv1'])}; see pruning.ppv): pruning does not keep it working beyond "
        "50 %. Computed rather than sampled (l_eta from the Poisson-binomial pmf (12), then "
        "Pr{PPV_eta = 1 | prior} = prod of the kept p_i, averaged over 100 priors per level), "
        "Pr{PPV_eta = 1} under (10) is "
        + ", ".join(f"{v[0]:.4f}" for v in ppv.values())
        + " at P_A = 0.5, 0.6, 0.7, 0.8 (at most "
        + f"{max(v[1] for v in ppv.values()):.3f} for any prior; smaller still, "
        + ", ".join(f"{v[2]:.1e}" for v in ppv.values())
        + ", with P_A as the prior probability that a row is attacked, by Bayes), against "
        "the eta = 0.9 that (22) promises. Under the model of the code published with the paper (p_i >= 1/2 with "
        "probability T_r and the prior right exactly when p_i > 1/2, so the most confident "
        f"rows are always right) it succeeds in {pct(rates['code'])}: Fig. 1's behaviour needs "
        f"that model, and holds up to about P_A = {upto:.1f}. The rates come from {_RUNS} runs "
        "per level (about +-0.1 each); benchmarks/exp_pruning.py gives the full curves. "
        "Departure from the paper: the attack takes the direction of (7) (the weakest direction "
        "of the safe rows) but is sized with an l1 budget, ||H_(T^c) delta||_1 = 0.999 eps, so "
        "that the detector (5) stays silent, where (7) has the l2 budget ||U_(1,T^c) z||_2 <= "
        "eps, which can set the detector off (pruning.thm2_1_detector).",
        {
            "method": "randomised",
            "setup": dict(m=_M, n=_N, T=_WINDOW, runs=_RUNS, T_r=_T_R, eta=_ETA, omega=_OMEGA),
            "setup_notes": "A, C Gaussian, A scaled to spectral radius 1, a window of T = 5 "
            "steps stacked oldest first (the paper gives no T; its code uses 11), the same "
            "sensors attacked over the window, x ~ N(0, I), eps = 0.01 ||H x||_1, delta along "
            "the smallest right singular vector of H_(T^c) with ||H_(T^c) delta||_1 = 0.999 "
            "eps; model (10) with p_i ~ U[2 T_r - 1, 1]; omega = 0.05 (Remark 5: small, not "
            "zero; the published code uses 0); seeds [1901, attacked sensors, run]; 'works' = "
            "success rate >= 1/2",
            "P_A": P_A,
            "success": {k: rates[k] for k in ("l1", "paper", "code")},
            "PPV_eta_1": {k: rates[k + "_ppv1"] for k in ("paper", "code")},
            "detector_silent": rates["silent"],
            "Pr_PPV_eta_1_model_10": {
                "P_A": list(ppv),
                "mean_over_priors": [v[0] for v in ppv.values()],
                "largest_over_priors": [v[1] for v in ppv.values()],
                "mean_with_P_A_as_prior_attack_probability": [v[2] for v in ppv.values()],
                "how": "100 priors per level drawn as in the simulation (seeds [1902, 100 P_A]); "
                "for each, l_eta exactly from the Poisson-binomial pmf (12) of its prior-safe "
                "rows, the kept rows by (14), and Pr{PPV_eta = 1 | prior} = prod of the kept p_i",
            },
        },
        counterexample={
            "m": 20,
            "n": 10,
            "T": 5,
            "T_r": 0.6,
            "eta": 0.9,
            "omega": 0.05,
            "P_A": P_A,
            "success_pruned_model_10": rates["paper"],
            "attack_budget": "l1: ||H_(T^c) delta||_1 = 0.999 eps (detector silent); (7) has "
            "an l2 budget",
            "P_A_for_PPV": [0.5, 0.6, 0.7, 0.8],
            "Pr_PPV_eta_1_model_10": [round(v[0], 6) for v in ppv.values()],
            "shows": f"seeds [1901, 20 P_A, r], r < {_RUNS}: under model (10) "
            f"the pruned observer succeeds in {pct(rates['paper'])} of the runs at P_A = "
            f"{levels}, below 1/2 beyond 50 % attacked; with the published code's prior model, "
            f"{pct(rates['code'])}. The cause: under (10) the pruned prior is entirely right "
            "with probability Pr{PPV_eta = 1} = "
            + ", ".join(f"{v[0]:.4f}" for v in ppv.values())
            + " at P_A = 0.5, 0.6, 0.7, 0.8 (mean over 100 priors, each computed exactly), far "
            "below eta = 0.9. The attack departs from (7): its l1 budget 0.999 eps keeps the "
            "detector silent.",
        },
        condition="The prior is right on the rows it is most confident about (the published "
        "code's model: row i's prior answer is right exactly when p_i > 1/2, rather than with "
        f"probability p_i as in (10)), and P_A <= {upto:.1f} (m = 20, n = 10).",
    )
