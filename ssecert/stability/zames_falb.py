"""Zames-Falb certificates: dynamic multipliers for the slope-restricted soft threshold.

The nonlinearity of a sparse observer's Lur'e model (``ssecert.observers.lure``),
phi = q * soft_threshold, is odd and slope-restricted in [0, q], channel by
channel.  With u = phi(w) and v = q w - u, the pair (v, u) of each channel is a
monotone relation through the origin (u is a subgradient of a convex function
of v: here the indicator of [-q threshold, q threshold]), and Fenchel's
inequality, summed over k = 0..T with u and v taken as 0 before time 0, gives
for every j >= 1

    |sum_k v_k u_(k-j)| <= sum_k v_k u_k   and   |sum_k v_(k-j) u_k| <= sum_k v_k u_k.

So for coefficients with m0_i >= sum_j (|a_ij| + |b_ij|), channel by channel,

    sum_(k=0..T) sigma_k >= 0,
    sigma_k = sum_i v_ik (m0_i u_ik - sum_j a_ij u_i(k-j)) - sum_j b_ij v_i(k-j) u_ik,

a "hard" integral quadratic constraint (a causal FIR Zames-Falb multiplier of
order nu).  Extend the state with the last nu values of u and v (zero at the
start): zeta = (xi, u_(k-1..k-nu), v_(k-1..k-nu)).  If a P > 0 satisfies

    V(zeta+) - V(zeta) + sigma <= -eta |(zeta, u)|^2      (the LMI below),

summing from 0 to T gives eta sum_k |xi_k|^2 <= V(zeta_0) = xi_0' P_xx xi_0 for
every T: the error state is square-summable, so it converges to 0 from every
initial condition, and stays within sqrt(lambda_max(P_xx) / eta) |xi_0|.
No decay rate is claimed.  The circle criterion is the case nu = 0; the
multipliers certify designs it cannot (any design whose linear loops
A + B diag(k) Cw, k_i in [0, q], are all Schur is a candidate, which is the
best a certificate that treats the channels as separate nonlinearities can
ask for: ``channel_vertex_instability`` checks the corners first).

With the attack as an input (w = Cw xi + Dw a) and -|e|^2 + g |a|^2 on the
right, the same sum gives sum_k |e_k|^2 <= g sum_k |a_k|^2 + V(zeta_0): an l2
gain sqrt(g) from attack to estimation error.

The slope restriction is what makes the relation between v and u monotone;
the inequality uses oddness only when a coefficient is negative.  For the
increments of two trajectories under the same constant attack the
nonlinearity is still slope-restricted but not odd, so a certificate whose
coefficients are all nonnegative also proves convergence to the attacked
equilibrium (``incremental`` in the evidence).

Nothing is taken from the solver: the LMI is recomputed in numpy, its
largest eigenvalue must beat a rounding bound by the factor ``clear``, P must
pass a Cholesky test with a margin, and the coefficient condition is checked
with a rounding guard.
"""

from __future__ import annotations

import math
import time
from functools import partial
from typing import Any

import numpy as np

from ..budget import Budget, Refusal, Resource
from ..observers.lure import LureModel
from ..results import Verdict
from ..solvers import solver_label, solver_name
from ..tolerances import EPS
from .lmi import (
    LMICertificate,
    balanced_retry,
    channel_vertex_instability,
    in_input_units,
    in_sensor_units,
    input_units,
    input_units_note,
    output_scaled,
    where_verified,
)
from .lmi_messages import verify_text
from .lmi_solver import ETA, _run_clarabel
from .lmi_verification import decide
from .outcomes import LMICause, LMICode, VerifyCode, VerifyProblem

__all__ = [
    "ORDERS",
    "ZF_LIMIT",
    "zames_falb_certificate",
    "zames_falb_gain",
    "zames_falb_matrix",
    "verify_zames_falb",
]

ORDERS = (1, 2, 3)  # FIR lengths tried, shortest first
ZF_LIMIT = 60  # largest LMI (rows) attempted
GUARD = 1e-6  # the solve asks m0 (1 - GUARD) >= sum |a| + |b|


def _lifted(model: LureModel, nu: int, attack: bool) -> dict[str, Any]:
    """The extended dynamics zeta+ = G z, z = (zeta, u[, a]), and the multiplier's terms.

    ``terms`` has one Z x Z symmetric matrix per coefficient (m0_i, then
    a_ji, then b_ji, channel fastest): sigma = z' (sum_c coef_c K_c) z.
    """
    N, m, q = model.N, model.m, model.q
    r = model.r if attack else 0
    D = N + 2 * m * nu
    Z = D + m + r
    Xi = np.zeros((N, Z))
    Xi[:, :N] = np.eye(N)
    Hu = np.zeros((m, Z))
    Hu[:, D : D + m] = np.eye(m)
    Ha = np.zeros((r, Z))
    Ha[:, D + m :] = np.eye(r)
    Hv = q * model.Cw @ Xi - Hu + (q * model.Dw @ Ha if attack else 0.0)
    U = [np.zeros((m, Z)) for _ in range(nu)]  # u_(k-1-j)
    V = [np.zeros((m, Z)) for _ in range(nu)]  # v_(k-1-j)
    for j in range(nu):
        U[j][:, N + m * j : N + m * (j + 1)] = np.eye(m)
        V[j][:, N + m * (nu + j) : N + m * (nu + j + 1)] = np.eye(m)
    xi_next = model.A @ Xi + model.B @ Hu + (model.E @ Ha if attack else 0.0)
    G = np.vstack([xi_next, Hu, *U[:-1], Hv, *V[:-1]])
    terms = np.empty((m * (1 + 2 * nu), Z, Z))

    def sym(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return 0.5 * (np.outer(x, y) + np.outer(y, x))

    for i in range(m):
        terms[i] = sym(Hv[i], Hu[i])
        for j in range(nu):
            terms[m * (1 + j) + i] = -sym(Hv[i], U[j][i])
            terms[m * (1 + nu + j) + i] = -sym(V[j][i], Hu[i])
    return {"G": G, "D": D, "Z": Z, "Xi": Xi, "Ha": Ha, "terms": terms}


def _coefficients(m0: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.concatenate([np.ravel(m0), np.ravel(a), np.ravel(b)])


def zames_falb_matrix(
    model: LureModel,
    P: np.ndarray,
    m0: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    g: float | None = None,
) -> np.ndarray:
    """The LMI in z = (zeta, u[, a]) recomputed in numpy and symmetrised.

    G' P G - diag(P, 0) + sum_c coef_c K_c, plus Ce'Ce on xi and -g I on the
    attack when ``g`` is given (the l2 gain form).
    """
    nu = np.asarray(a).shape[0]
    lift = _lifted(model, nu, g is not None)
    G, D = lift["G"], lift["D"]
    M = G.T @ P @ G
    M[:D, :D] -= P
    M += np.tensordot(_coefficients(m0, a, b), lift["terms"], axes=1)
    if g is not None:
        Ce = model.Ce @ lift["Xi"]
        M += Ce.T @ Ce - g * lift["Ha"].T @ lift["Ha"]
    return 0.5 * (M + M.T)


def verify_zames_falb(
    model: LureModel,
    P: np.ndarray,
    m0: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    *,
    g: float | None = None,
    clear: float = 100.0,
) -> tuple[bool, float, float, VerifyProblem | None]:
    """Re-verify a Zames-Falb certificate without the solver: (ok, margin, bound, problem or
    None).

    margin is ``-lambda_max(LMI) / ||P||``; bound its rounding error bound.
    """
    P = 0.5 * (np.asarray(P, dtype=float) + np.asarray(P, dtype=float).T)
    m0, a, b = (np.asarray(x, dtype=float) for x in (m0, a, b))
    if not all(np.all(np.isfinite(x)) for x in (P, m0, a, b)):
        return False, float("nan"), 0.0, VerifyProblem(VerifyCode.NON_FINITE)
    nu = a.shape[0]
    total = np.abs(a).sum(axis=0) + np.abs(b).sum(axis=0)
    guard = 1.0 + 4.0 * (2 * nu + 2) * EPS
    short = m0 < guard * total
    if np.any(short) or np.any(m0 < 0):
        i = int(np.argmax(short | (m0 < 0)))
        facts = {"channel": i, "m0": float(m0[i]), "total": float(total[i])}
        return False, float("nan"), 0.0, VerifyProblem(VerifyCode.CHANNEL_SHORT, facts)
    M = zames_falb_matrix(model, P, m0, a, b, g)
    normP = max(float(np.linalg.norm(P, 2)), np.finfo(float).tiny)
    margin = -float(np.linalg.eigvalsh(M)[-1]) / normP
    lift_norm = float(np.linalg.norm(_lifted(model, nu, g is not None)["G"], 2))
    coef = float(np.abs(_coefficients(m0, a, b)).sum())
    # (the attack's Dw is in the LMI only in its gain form)
    Cw = np.hstack([model.Cw, model.Dw]) if g is not None else model.Cw
    side = float(np.linalg.norm(Cw, 2)) * model.q + 1.0
    # the |e|^2 - g |a|^2 terms are in the LMI only in its gain form
    extra = float(np.linalg.norm(model.Ce, 2)) ** 2 + abs(g) if g is not None else 0.0
    raw = (lift_norm**2 + 2.0) * normP + 2.0 * coef * side**2 + extra
    # the model's floats are within d of the spec's exact data: the lifted G within (1 + q) d,
    # each multiplier term sym(Hv_i, .) within q d
    d = model.rounding
    dG = (1.0 + model.q) * d
    data = (2.0 * lift_norm + dG) * dG * normP + 2.0 * coef * model.q * d
    bound = 10.0 * M.shape[0] * EPS * raw / normP + data * (1 + 1e-12) / normP
    return decide(P, margin, bound, clear)


def zf_cost(model: LureModel, nu: int, attack: bool = False) -> tuple[int, float, float]:
    """Rows, bytes and operations of one Zames-Falb LMI of order nu (full P; high side)."""
    D = model.N + 2 * model.m * nu
    size = D + model.m + (model.r if attack else 0)
    T = size * (size + 1) / 2
    v = D * (D + 1) / 2 + model.m * (1 + 2 * nu)
    return size, 64 * 2**20 + 48.0 * (T + v) ** 2, 10.0 * (T + v) ** 3


def _solve(
    model: LureModel, nu: int, attack: bool, options: dict[str, Any], signed: bool = True
) -> tuple[tuple[np.ndarray, ...] | None, float | None, dict[str, Any]]:
    """One Zames-Falb LMI with cvxpy and Clarabel: ((P, m0, a, b), g, info), None on failure.

    ``signed`` False asks for nonnegative delayed coefficients (a certificate that also holds
    for increments).
    """
    import cvxpy as cp

    start = time.perf_counter()
    lift = _lifted(model, nu, attack)
    G, D, Z, m = lift["G"], lift["D"], lift["Z"], model.m
    P = cp.Variable((D, D), symmetric=True)
    m0 = cp.Variable(m)
    a = cp.Variable((nu, m), nonneg=not signed)
    b = cp.Variable((nu, m), nonneg=not signed)
    a_abs = cp.Variable((nu, m), nonneg=True)
    b_abs = cp.Variable((nu, m), nonneg=True)
    coef = cp.hstack([m0, cp.vec(a, order="C"), cp.vec(b, order="C")])
    K = lift["terms"].reshape(lift["terms"].shape[0], Z * Z)
    M = G.T @ P @ G - cp.bmat(
        [[P, np.zeros((D, Z - D))], [np.zeros((Z - D, D)), np.zeros((Z - D, Z - D))]]
    )
    M = M + cp.reshape(K.T @ coef, (Z, Z), order="C")
    g = cp.Variable(nonneg=True) if attack else None
    if g is not None:
        Ce = model.Ce @ lift["Xi"]
        M = M + Ce.T @ Ce - g * (lift["Ha"].T @ lift["Ha"])
    cons = [
        P >> np.eye(D),
        0.5 * (M + M.T) << -ETA * np.eye(Z),
        a_abs >= a,
        a_abs >= -a,
        b_abs >= b,
        b_abs >= -b,
        (1 - GUARD) * m0 >= cp.sum(a_abs, axis=0) + cp.sum(b_abs, axis=0),
    ]
    problem = cp.Problem(cp.Minimize(g) if g is not None else cp.Minimize(0), cons)
    info: dict[str, Any] = {
        "solver": solver_name(),
        "order": nu,
        "coefficients": "signed" if signed else "nonnegative",
        "lmi_size": Z,
    }
    if not _run_clarabel(problem, options, info, start):
        return None, None, info
    values = [P.value, m0.value, a.value, b.value]
    if any(v is None or not np.all(np.isfinite(v)) for v in values):
        info["status"] = f"{problem.status}, but the solver returned no finite values"
        return None, None, info
    Pv = np.asarray(values[0], dtype=float)
    sol = (0.5 * (Pv + Pv.T), *(np.asarray(v, dtype=float) for v in values[1:]))
    return sol, (float(g.value) if g is not None and g.value is not None else None), info


def _refusal(model: LureModel, nu: int, attack: bool, budget: Budget) -> Refusal | None:
    size, nbytes, flops = zf_cost(model, nu, attack)
    if size > ZF_LIMIT:
        return Refusal(f"the order-{nu} LMI", Resource.ROWS, size, ZF_LIMIT)
    return budget.check(
        f"the order-{nu} Zames-Falb LMI with {size} rows (cvxpy and {solver_label()})",
        nbytes=nbytes,
        flops=flops,
    )


def zames_falb_certificate(
    model: LureModel,
    *,
    orders: tuple[int, ...] = ORDERS,
    clear: float = 100.0,
    budget: Budget | None = None,
    solver_options: dict[str, Any] | None = None,
    balance: bool = True,
) -> LMICertificate:
    """Global convergence without attack by a Zames-Falb multiplier (kind ``"zames-falb"``).

    Tries FIR multipliers of each order in ``orders`` (shortest first), with
    nonnegative delayed coefficients and then with signed ones, and returns
    the first verified; ``multipliers`` holds m0, ``details`` the
    delayed coefficients (``u_delays`` a, ``v_delays`` b), the order and
    whether the certificate also holds for increments. ``decay`` is None: the
    certificate proves square-summability, not a rate.  With ``balance``, a model
    that nothing certifies is tried again in balanced state coordinates
    (``lmi.balanced_retry``).
    """
    budget = budget or Budget()
    attempts: list[dict[str, Any]] = []
    if model.m == 0:
        return LMICertificate(
            Verdict.INCONCLUSIVE,
            "zames-falb",
            code=LMICode.DECIDED_BEFORE,
            cause=LMICause.NO_NONLINEARITY,
        )
    corner = channel_vertex_instability(model)
    if corner is not None:
        return LMICertificate(
            Verdict.INCONCLUSIVE,
            "zames-falb",
            details={"channel_corner": corner},
            code=LMICode.DECIDED_BEFORE,
            cause=LMICause.CORNER_UNSTABLE,
            facts={"corner": corner},
        )
    again = partial(
        zames_falb_certificate,
        orders=orders,
        clear=clear,
        budget=budget,
        solver_options=solver_options,
        balance=False,
    )
    if balance:  # first in the sensors' units where they are far from 1 or from each other
        first = in_sensor_units(model, again)
        if first is not None:
            return first
    # nonnegative coefficients first (the certificate then also proves convergence to the
    # equilibrium of every constant attack), then signed ones (the soft threshold is odd)
    for signed, nu in [(False, nu) for nu in orders] + [(True, nu) for nu in orders]:
        skip = _refusal(model, nu, False, budget)
        if skip is not None:
            if not signed:
                attempts.append({"order": nu, "status": f"skipped: {skip}"})
            continue
        sol, _, info = _solve(model, nu, False, solver_options or {}, signed)
        attempts.append(info)
        if sol is None:
            continue
        P, m0, a, b = sol
        ok, margin, bound, problem = verify_zames_falb(model, P, m0, a, b, clear=clear)
        info["verified"] = ok
        if ok:
            return _certificate(model, sol, margin, bound, attempts)
        info["verification_problem"] = verify_text(problem)
    retry, note = balanced_retry(model, again, enabled=balance, attempts=attempts)
    if retry is not None:
        return retry
    return LMICertificate(
        Verdict.INCONCLUSIVE,
        "zames-falb",
        details={"attempts": attempts},
        code=LMICode.NOT_VERIFIED,
        cause=LMICause.ZAMES_FALB_NOT_VERIFIED,
        facts={"attempts": tuple(dict(a) for a in attempts), "notes": (note,)},
    )


def _certificate(
    model: LureModel,
    sol: tuple[np.ndarray, ...],
    margin: float,
    bound: float,
    attempts: list[dict[str, Any]],
    gamma_squared: float | None = None,
) -> LMICertificate:
    P, m0, a, b = sol
    N = model.N
    # eta sum |xi|^2 <= xi0' P_xx xi0 with eta = (margin - its rounding bound) ||P||
    eta = (margin - bound) * float(np.linalg.norm(P, 2))
    details = {
        "order": int(a.shape[0]),
        "u_delays": a,
        "v_delays": b,
        "incremental": bool(np.all(a >= 0) and np.all(b >= 0)),
        "eta": eta,
        "sum_bound_factor": float(np.linalg.eigvalsh(P[:N, :N])[-1]) / eta,
        "attempts": attempts,
    }
    if gamma_squared is not None:
        details["gamma_squared"] = gamma_squared
    return LMICertificate(
        Verdict.HOLDS,
        "zames-falb",
        P=P,
        multipliers=m0,
        margin=margin,
        error_bound=bound,
        decay=None,
        gamma=None if gamma_squared is None else float(np.sqrt(gamma_squared)),
        structure="full",
        details=details,
        code=LMICode.VERIFIED,
    )


def zames_falb_gain(
    model: LureModel,
    stability: LMICertificate,
    *,
    clear: float = 100.0,
    budget: Budget | None = None,
    solver_options: dict[str, Any] | None = None,
    balance: bool = True,
) -> LMICertificate:
    """The l2 gain from attack to estimation error with a Zames-Falb multiplier.

    Solves the LMI with the attack as input at the order that certified
    ``stability`` (a verified ``zames_falb_certificate``), minimising g; the
    certificate holds for g slightly above the optimum, re-verified.  A stability
    certificate verified in balanced state coordinates (``state_scaling``) has its gain
    solved there too, and written back.
    """
    elsewhere = where_verified(
        model,
        stability,
        partial(zames_falb_gain, clear=clear, budget=budget, solver_options=solver_options),
    )
    if elsewhere is not None:
        return elsewhere
    budget = budget or Budget()
    nu = int(stability.details.get("order", ORDERS[0]))
    skip = _refusal(model, nu, True, budget)
    if skip is not None:
        return LMICertificate(
            Verdict.INCONCLUSIVE,
            "iss",
            code=LMICode.NOT_ATTEMPTED,
            cause=LMICause.REFUSED,
            facts={"refusal": skip},
        )
    c, solved = output_scaled(model)  # solved with e in units c, the certificate scaled back
    k, solved = input_units(solved)  # and with a = 2^k a_b: gamma^2 scaled back by 4^-k
    sol, g, info = _solve(solved, nu, True, solver_options or {})
    if c != 1.0 and sol is not None and g is not None:
        sol, g = tuple(x * c**2 for x in sol), g * c**2
        info["output_scaling"] = c
    if k and g is not None:
        g = math.ldexp(g, -2 * k)
        info["input_scaling"] = f"2^{k}"
    if sol is None or g is None:
        return _gain_retry(
            model,
            stability,
            LMICause.ZAMES_FALB_NO_DISSIPATION,
            {"order": nu, "status": info["status"]},
            {"attempts": [info]},
            clear,
            budget,
            solver_options,
            balance,
        )
    problem = None
    # (the absolute parts of the slack in the units the LMI was solved in)
    slack = math.ldexp(c**2, -2 * k)
    for g_cert in (g * (1 + 1e-6) + 1e-9 * slack, g * 1.01 + 1e-6 * slack):
        ok, margin, bound, problem = verify_zames_falb(model, *sol, g=g_cert, clear=clear)
        where: dict[str, str] = {}
        if not ok and k:
            # the same inequality with a = 2^k a_b (gamma^2 times 4^k), where it was solved
            ok, margin, bound, problem = verify_zames_falb(
                in_input_units(model, k), *sol, g=math.ldexp(g_cert, 2 * k), clear=clear
            )
            where = input_units_note(k)
        if ok:
            cert = _certificate(model, sol, margin, bound, [info], gamma_squared=g_cert)
            return LMICertificate(
                Verdict.HOLDS,
                "iss",
                P=cert.P,
                multipliers=cert.multipliers,
                margin=margin,
                error_bound=bound,
                decay=0.0,
                gamma=cert.gamma,
                structure="zames-falb",
                details={
                    **cert.details,
                    "method": f"Zames-Falb multiplier of order {nu} (dissipation with the "
                    "attack as input)",
                    **where,
                },
                code=LMICode.VERIFIED,
            )
    return _gain_retry(
        model,
        stability,
        LMICause.ZAMES_FALB_GAIN_NOT_VERIFIED,
        {"problem": problem},
        {"attempts": [info]},
        clear,
        budget,
        solver_options,
        balance,
    )


def _gain_retry(
    model: LureModel,
    stability: LMICertificate,
    cause: LMICause,
    facts: dict[str, Any],
    details: dict[str, Any],
    clear: float,
    budget: Budget,
    solver_options: dict[str, Any] | None,
    balance: bool,
) -> LMICertificate:
    """The gain solved again in balanced state coordinates, or inconclusive for ``cause``
    (with its ``facts``)."""
    retry, note = balanced_retry(
        model,
        partial(
            zames_falb_gain,
            stability=stability,
            clear=clear,
            budget=budget,
            solver_options=solver_options,
            balance=False,
        ),
        enabled=balance,
    )
    if retry is not None:
        return retry
    return LMICertificate(
        Verdict.INCONCLUSIVE,
        "iss",
        details=details,
        code=LMICode.NOT_VERIFIED,
        cause=cause,
        facts={**facts, "notes": (note,)},
    )
