"""Nonzero equilibria of a sparse observer's error dynamics without attack.

The nonlinearity q S(w) of the Lur'e model (``ssecert.observers.lure``) is
affine on each region of w where every entry is either in the dead zone
(|w_i| <= threshold, output 0) or active with a sign s_i (output
q (w_i - threshold s_i)).  On the region of a pattern s in {-1, 0, 1}^m the
fixed points solve the linear equations

    (I - A - q B D Cw) xi = -q threshold B s,   D = diag(|s|),

and a solution is an equilibrium when it lies in its own region.  Every
pattern is tried (3^m, batched) for small m; for larger m a mixed-integer
program (``scipy.optimize.milp``, HiGHS) searches the patterns at once, with
two binaries per channel (active positive, active negative), big-M region
constraints on |w_i| <= ``MILP_BOX`` thresholds and at least one active
channel (an equilibrium with every channel in the dead zone is the origin
when F is Schur).  An equilibrium other than the origin is confirmed in
exact rational arithmetic on the model's exact matrices (formed from the spec's
data, not from their floating-point products) before it is reported: the
observer then settles on a wrong estimate with no attack, and is not
globally asymptotically stable.
"""

from __future__ import annotations

import time
from dataclasses import replace
from fractions import Fraction
from typing import Any

import numpy as np

from ..budget import Budget
from ..numerics.rational import product, solve
from ..observers.lure import LureModel
from .outcomes import SearchCode, Searched, WitnessKind

__all__ = ["nonzero_equilibrium", "attacked_equilibria", "MAX_PATTERNS"]

MAX_PATTERNS = 3**10  # patterns tried exhaustively (59,049)
_BATCH = 4096
MILP_BOX = 1e4  # the mixed-integer search looks at |w_i| <= MILP_BOX * threshold
MILP_SECONDS = 10.0  # time limit of the mixed-integer search, all its solves together
MILP_ROUNDS = 5  # solves, each excluding the patterns that exact arithmetic refused


def milp_cost(model: LureModel) -> tuple[float, float]:
    """Bytes of the mixed-integer program's dense constraint matrix (with the solver's copies)
    and the operations of the exact confirmation of a candidate (a solve of N equations)."""
    N, m = model.N, model.m
    rows, cols = N + 6 * m, N + 3 * m
    return 8.0 * 3 * rows * cols, 10.0 * MILP_ROUNDS * N**3


def nonzero_equilibrium(
    model: LureModel, *, milp: bool = True, budget: Budget | None = None
) -> tuple[dict[str, Any] | None, Searched]:
    """An exactly confirmed nonzero equilibrium (the witness) or None, with what was searched
    (its words: ``search_messages.searched_text``).

    More than ``MAX_PATTERNS`` patterns are searched by mixed-integer programming, unless
    ``milp`` is False or the program does not fit ``budget`` (default ``Budget()``; then they
    are not searched).
    """
    if model.m == 0 or model.q <= 0:
        return None, Searched(SearchCode.NO_NONLINEARITY)
    if milp and 3**model.m > MAX_PATTERNS and model.threshold > 0:
        nbytes, flops = milp_cost(model)
        refusal = (budget or Budget()).check(
            f"the mixed-integer program over the {model.m:,} soft-threshold channels",
            nbytes=nbytes,
            flops=flops,
        )
        if refusal is not None:
            return None, Searched(SearchCode.REFUSED, {"refusal": refusal})
        return _milp_search(model)
    found, searched, _ = _search(model, None, first=True)
    return (found[0] if found else None), searched


def _milp_search(model: LureModel) -> tuple[dict[str, Any] | None, Searched]:
    """A nonzero equilibrium by mixed-integer programming (too many patterns to enumerate).

    Variables xi (N), u (m, the nonlinearity's output) and binaries p, n (m each):
    xi = A xi + B u, w = Cw xi; p_i = 1 means w_i >= threshold and u_i = q (w_i - threshold),
    n_i = 1 means w_i <= -threshold and u_i = q (w_i + threshold), neither means |w_i| <=
    threshold and u_i = 0; p_i + n_i <= 1 and sum (p + n) >= 1.  A solution's pattern is
    confirmed in exact arithmetic; one that is not is cut off and the search repeated.
    """
    from scipy.optimize import Bounds, LinearConstraint, milp

    # in units of the threshold: the equilibrium equations are homogeneous in (xi, u,
    # threshold), so a pattern's equilibria scale with the threshold, and big-M constants of
    # the threshold's size (1e12 for a threshold of 1e8) would make HiGHS misjudge feasibility
    N, m, q, lam = model.N, model.m, float(model.q), 1.0
    W = MILP_BOX * lam
    big = W + lam  # region constraints
    big_u = 3.0 * q * (W + lam)  # output constraints (|u - q w| stays below it in the box)
    # variable order: xi (N), u (m), p (m), n (m)
    nv = N + 3 * m
    Cw = model.Cw
    rows: list[np.ndarray] = []
    lo: list[float] = []
    hi: list[float] = []

    def add(coef: np.ndarray, low: float, high: float) -> None:
        rows.append(coef)
        lo.append(low)
        hi.append(high)

    fixed = np.zeros((N, nv))  # (I - A) xi - B u = 0
    fixed[:, :N] = np.eye(N) - model.A
    fixed[:, N : N + m] = -model.B
    for r in range(N):
        add(fixed[r], 0.0, 0.0)
    for i in range(m):
        w = np.zeros(nv)
        w[:N] = Cw[i]
        U, P, Nn = N + i, N + m + i, N + 2 * m + i
        c = w.copy()  # w_i - big p_i >= lam - big  (p_i = 1: w_i >= lam)
        c[P] -= big
        add(c, lam - big, np.inf)
        c = w.copy()  # w_i + big n_i <= -lam + big  (n_i = 1: w_i <= -lam)
        c[Nn] += big
        add(c, -np.inf, -lam + big)
        c = w.copy()  # dead: |w_i| <= lam + big (p_i + n_i)
        c[P] -= big
        c[Nn] -= big
        add(c, -np.inf, lam)
        c = w.copy()
        c[P] += big
        c[Nn] += big
        add(c, -lam, np.inf)
        for sign, b in ((1.0, P), (-1.0, Nn)):  # b = 1: u_i - q w_i = -q sign lam
            c = -q * w
            c[U] += 1.0
            c[b] += big_u  # u - q w <= -q sign lam + big_u (1 - b)
            add(c, -np.inf, -q * sign * lam + big_u)
            c = -q * w
            c[U] += 1.0
            c[b] -= big_u  # u - q w >= -q sign lam - big_u (1 - b)
            add(c, -q * sign * lam - big_u, np.inf)
        c = np.zeros(nv)  # dead: |u_i| <= big_u (p_i + n_i)
        c[U] = 1.0
        c[P] = c[Nn] = -big_u
        add(c, -np.inf, 0.0)
        c = np.zeros(nv)
        c[U] = 1.0
        c[P] = c[Nn] = big_u
        add(c, 0.0, np.inf)
        c = np.zeros(nv)
        c[P] = c[Nn] = 1.0
        add(c, 0.0, 1.0)
    c = np.zeros(nv)
    c[N + m :] = 1.0
    add(c, 1.0, np.inf)
    lower = np.concatenate([np.full(N, -np.inf), np.full(m, -q * (W + lam)), np.zeros(2 * m)])
    upper = np.concatenate([np.full(N, np.inf), np.full(m, q * (W + lam)), np.ones(2 * m)])
    integrality = np.concatenate([np.zeros(N + m), np.ones(2 * m)])
    refused = 0
    deadline = time.monotonic() + MILP_SECONDS
    for _ in range(MILP_ROUNDS):
        left = deadline - time.monotonic()
        if left <= 0:
            break
        result = milp(
            np.zeros(nv),
            constraints=LinearConstraint(np.array(rows), lo, hi),
            integrality=integrality,
            bounds=Bounds(lower, upper),
            options={"time_limit": left},
        )
        if result.x is None:
            return None, Searched(
                SearchCode.MILP_NONE,
                {
                    "status": int(result.status),
                    "message": str(result.message).strip(),
                    "m": m,
                    "box": MILP_BOX,
                    "seconds": MILP_SECONDS,
                    "refused": refused,
                },
            )
        signs = np.round(result.x[N + m : N + 2 * m]) - np.round(result.x[N + 2 * m :])
        witness = _confirm(model, signs)
        if witness is not None:
            return witness, Searched(SearchCode.MILP_FOUND, {"m": m})
        refused += 1
        cut = np.zeros(nv)  # exclude this pattern: sum of the binaries that differ >= 1
        ones = np.concatenate([signs > 0, signs < 0])
        cut[N + m :] = np.where(ones, -1.0, 1.0)
        add(cut, 1.0 - float(ones.sum()), np.inf)
    return None, Searched(
        SearchCode.MILP_REFUSED,
        {"m": m, "refused": refused, "seconds": MILP_SECONDS, "timed_out": refused != MILP_ROUNDS},
    )


def attacked_equilibria(
    model: LureModel, attack: np.ndarray
) -> tuple[list[dict[str, Any]], Searched, int]:
    """Every equilibrium of the error dynamics under the constant attack ``attack`` (length
    r), each confirmed in exact arithmetic, with what was searched and the number of patterns
    whose equations were too ill-conditioned to decide (0 means the list is complete)."""
    a = np.asarray(attack, dtype=float)
    if model.m == 0 or model.q <= 0:
        K = np.eye(model.N) - model.A
        try:
            xi = np.linalg.solve(K, model.E @ a)
        except np.linalg.LinAlgError:
            return [], Searched(SearchCode.LINEAR_SINGULAR), 1
        witness = {"initial_error": xi[: model.n_e], "attack_estimate": xi[model.n_e :],
                   "exact": False, "active_signs": np.zeros(0, int),
                   "error_is_zero": not np.any(xi[: model.n_e])}  # fmt: skip
        return [witness], Searched(SearchCode.LINEAR_UNIQUE), 0
    scaling = model.balancing()
    if scaling is None:
        return _search(model, a, first=False)
    # the patterns' equations in balanced state coordinates (their conditioning does not
    # depend on the states' units there), each equilibrium scaled back exactly
    found, searched, undecided = _search(model.scaled(scaling), a, first=False)
    n_e = model.n_e
    for eq in found:
        eq["point"] = eq["point"] * scaling
        eq["initial_error"] = eq["initial_error"] * scaling[:n_e]
        eq["attack_estimate"] = eq["attack_estimate"] * scaling[n_e:]
    return found, replace(searched, balanced=True), undecided


def _search(
    model: LureModel, attack: np.ndarray | None, *, first: bool
) -> tuple[list[dict[str, Any]], Searched, int]:
    """Equilibria of the soft threshold's active/sign patterns (nonzero ones without attack),
    confirmed exactly (the first only, or all), what was searched, and how many patterns were
    too ill-conditioned to decide."""
    m = model.m
    count = 3**m
    if count > MAX_PATTERNS:
        too_many = {"m": m, "count": count, "most": MAX_PATTERNS}
        return [], Searched(SearchCode.TOO_MANY_PATTERNS, too_many), count
    N, lam, q = model.N, model.threshold, model.q
    shift = np.zeros(m) if attack is None else model.Dw @ attack  # w = Cw xi + Dw a
    push = np.zeros(N) if attack is None else model.E @ attack
    singular = 0
    found: list[dict[str, Any]] = []
    for start in range(0, count, _BATCH):
        signs = _patterns(m, start, min(start + _BATCH, count))
        active = np.abs(signs)
        K = np.eye(N) - model.A - q * np.einsum("ij,pj,jk->pik", model.B, active, model.Cw)
        rhs = q * (active * shift - lam * signs) @ model.B.T + push
        cond = np.linalg.cond(K)
        ok = np.isfinite(cond) & (cond < 1e12)
        singular += int(np.count_nonzero(~ok))
        if not ok.any():
            continue
        xi = np.linalg.solve(K[ok], rhs[ok][..., None])[..., 0]
        w = xi @ model.Cw.T + shift
        s = signs[ok]
        slack = 1e-9 * max(lam, 1.0)
        inside = np.where(s != 0, s * w > lam - slack, np.abs(w) < lam + slack).all(axis=1)
        if attack is None:
            inside &= np.any(xi != 0, axis=1)
        for i in np.flatnonzero(inside):
            witness = _confirm(model, s[i], attack)
            if witness is not None and not any(
                np.array_equal(witness["point"], other["point"]) for other in found
            ):
                found.append(witness)
                if first:
                    tried = {"tried": start + i + 1, "count": count}
                    return found, Searched(SearchCode.FIRST_FOUND, tried), singular
    tried = {"found": len(found), "count": count, "nonzero": attack is None, "singular": singular}
    return found, Searched(SearchCode.PATTERNS_TRIED, tried), singular


def _patterns(m: int, start: int, stop: int) -> np.ndarray:
    """Patterns ``start`` to ``stop`` of {-1, 0, 1}^m (base-3 digits), shape (stop - start, m)."""
    index = np.arange(start, stop)[:, None]
    digits = (index // 3 ** np.arange(m)[None, :]) % 3
    return (digits - 1).astype(float)


def _confirm(
    model: LureModel, signs: np.ndarray, attack: np.ndarray | None = None
) -> dict[str, Any] | None:
    """Solve the pattern's fixed-point equations exactly; the witness if the solution is an
    equilibrium in its region (nonzero without attack), else None."""
    N = model.N
    exact = model.exact()
    if exact is None:  # the spec's exact data is beyond its budget: nothing is confirmed
        return None
    lam, q = Fraction(model.threshold), Fraction(model.q)
    A, B, Cw = exact.fractions("A"), exact.fractions("B"), exact.fractions("Cw")
    on = [j for j in range(model.m) if signs[j] != 0]
    BDCw = product([[B[i][j] for j in on] for i in range(N)], [Cw[j] for j in on]) if on else None
    K = [[(1 if i == k else 0) - A[i][k] - (q * BDCw[i][k] if BDCw else 0) for k in range(N)]
         for i in range(N)]  # fmt: skip
    if attack is None:
        shift = [Fraction(0)] * model.m
        push = [Fraction(0)] * N
    else:
        aq = [[Fraction(float(v))] for v in attack]
        shift = [row[0] for row in product(exact.fractions("Dw"), aq)]
        push = [row[0] for row in product(exact.fractions("E"), aq)]
    rhs = [
        push[i] + q * sum((B[i][j] * (shift[j] - lam * int(signs[j])) for j in on), Fraction(0))
        for i in range(N)
    ]
    xi = solve(K, rhs)
    if xi is None or (attack is None and not any(xi)):
        return None
    w = [row[0] + shift[j] for j, row in enumerate(product(Cw, [[v] for v in xi]))]
    for wi, si in zip(w, signs):
        if (si != 0 and not si * wi > lam) or (si == 0 and not abs(wi) <= lam):
            return None
    point = np.array([float(v) for v in xi])
    if attack is not None:
        step = model.simulate(point, 1, np.asarray(attack, float)[None])[-1]
        return {
            "point": point,
            "initial_error": point[: model.n_e],
            "attack_estimate": point[model.n_e :],
            "error_is_zero": not any(xi[: model.n_e]),
            "active_signs": signs.astype(int),
            "exact": True,
            "float_residual": float(np.linalg.norm(step - point)),
        }
    step = model.simulate(point, 1)[-1]
    local = model.A + model.q * model.B @ np.diag(np.abs(signs)) @ model.Cw
    with np.errstate(all="ignore"):
        moduli = np.sort(np.abs(np.linalg.eigvals(local)))[::-1]
    return {
        "kind": WitnessKind.NONZERO_EQUILIBRIUM,
        # near the equilibrium the error follows its pattern's affine map: eigenvalues of its
        # linear part beyond 1 make it repelling (still an equilibrium, kept only exactly)
        "local_loop_moduli": moduli[: min(4, moduli.size)],
        "repelling": bool(moduli.size and moduli[0] > 1 + 1e-9),
        "initial_error": point[: model.n_e],
        "initial_attack_estimate": point[model.n_e :],
        "active_signs": signs.astype(int),
        "exact": True,
        "float_residual": float(np.linalg.norm(step - point)),
        "replay": "xi is a fixed point of xi+ = A xi + B q S(Cw xi) (no attack): the observer "
        "stays at this wrong estimate",
    }
