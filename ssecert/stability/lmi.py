"""LMI certificates for the sparse observers, written as Lur'e systems.

With e = x_hat - x and the attack estimate a_hat, every sparse observer
(SSO, D-SSO, the elastic-net observer) is

    xi(k+1) = A xi(k) + B phi(w(k)) + E a(k),    xi = (e, a_hat),
    w(k)    = Cw xi(k) + Dw a(k),
    A = [[F, -L], [0, 0]],  B = [[0], [I]],  Cw = [-step L2 S, I - step L2],
    E = [[L], [0]],         Dw = step L2,

where F = A_plant - L S and phi = shrink * soft_threshold acts componentwise:
it lies in the sector [0, q] (q = shrink) and is slope-restricted in [0, q].

* ``circle_certificate``: V = xi' P xi decreases along every trajectory
  without attack, by the S-procedure with a diagonal multiplier T >= 0 on
  phi_i (q w_i - phi_i) >= 0.  Two structural facts come first:
  near the origin phi = 0 (dead zone), so an unstable F makes the origin
  locally unstable (fails); and the sector contains the linear map
  phi = q w, so if that closed loop A + q B Cw is not Schur no sector
  certificate can exist (inconclusive, with the reason; for shrink = 1 and
  an eigenvalue of A at 1 it has that eigenvalue: e = v, a_hat = -C v);
* ``iss_certificate``: V(xi+) - V(xi) <= -alpha V(xi) - |e|^2 + gamma^2 |a|^2,
  which gives input-to-state stability with decay alpha and the l2 gain
  gamma from attack to estimation error.

The LMIs are solved with cvxpy and Clarabel, first with the structure the
proof needs (P block diagonal between e and a_hat, diagonal on a_hat: ten
times faster on the thesis-sized plant), then, if that fails and the LMI is
small enough, with a full P.  Nothing is taken from the solver's status:
the LMI is recomputed in numpy from the returned P and T, symmetrised, and
its largest eigenvalue must beat a floating-point error bound by a factor
``clear``; P must pass a Cholesky test with a margin and T must be
nonnegative.  Otherwise the verdict is inconclusive.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..budget import Budget
from ..observers.lure import LureModel
from ..results import Verdict
from ..tolerances import EPS

__all__ = [
    "LureModel",
    "LMICertificate",
    "circle_certificate",
    "iss_certificate",
    "iss_from_circle",
    "circle_matrix",
    "iss_matrix",
    "verify_certificate",
    "lmi_cost",
    "lure_model_cost",
]

ETA = 1e-4  # margin imposed in the LMIs, relative to P >= I
FULL_LIMIT = 80  # largest LMI dimension tried with a full P
# Lyapunov structures, cheapest first: P = diag(P1, D) with D diagonal; the
# same with a full cross block P12; a full P.
STRUCTURES = ("block-diagonal", "cross", "full")


def lure_model_cost(n: int, m: int, r: int) -> tuple[float, float]:
    """Bytes and operations of a Lur'e model with n error states, m nonlinearities and r
    attack inputs: its matrices, and the eigenvalues of its N x N closed loops (N = n + m)."""
    N = n + m
    nbytes = 8.0 * (3 * N * N + 2 * N * m + 2 * N * r + m * r + n * N + 2 * m * m)
    return nbytes, 30.0 * N**3


def lmi_cost(model: LureModel, kind: str, structure: str) -> tuple[float, float]:
    """Estimated peak bytes and operations of solving one LMI with cvxpy and Clarabel.

    Fitted to measurements (2 cores, Clarabel 0.x) of circle and ISS LMIs of
    24 to 312 rows: with T = size (size + 1) / 2 entries in the semidefinite
    cone, the block-diagonal structure keeps the problem sparse (memory and
    time grow like T * size), while a cross block or a full P makes the
    factorised system dense in T plus the number of variables v (memory like
    (T + v)^2, time like (T + v)^3).  The estimates err on the high side.
    """
    N, m, r, n = model.N, model.m, model.r, model.n_e
    size = N + m + (r if kind == "iss" else 0)
    T = size * (size + 1) / 2
    if structure == "block-diagonal":
        factor = 2.0 if kind == "iss" else 1.0
        return 64 * 2**20 + factor * 450.0 * T * size, factor * 3e5 * T * size
    if structure == "cross":
        v = n * (n + 1) / 2 + n * (N - n) + (N - n) + m
    else:
        v = N * (N + 1) / 2 + m
    return 64 * 2**20 + 48.0 * (T + v) ** 2, 10.0 * (T + v) ** 3


@dataclass(frozen=True)
class LMICertificate:
    """A verified (or not) LMI certificate.

    Attributes
    ----------
    verdict : Verdict
        Given as a Verdict or its name (``"holds"``, ``"fails"``,
        ``"inconclusive"``).
    kind : str
        ``"circle"`` or ``"iss"``.
    P : ndarray or None
        Lyapunov matrix (full, symmetric).
    multipliers : ndarray or None
        Diagonal of T.
    margin : float or None
        ``-lambda_max(LMI) / ||P||`` of the recomputed LMI.
    error_bound : float
        Floating-point error bound on that eigenvalue, same units.
    decay : float or None
        alpha with V(xi+) <= (1 - alpha) V(xi) (circle: without attack).
    gamma : float or None
        l2 gain from attack to estimation error (ISS).
    structure : str
        ``"block-diagonal"`` or ``"full"``.
    reason : str
    details : dict
        Solver status and times, pre-check results, witness.
    """

    verdict: Verdict
    kind: str
    P: np.ndarray | None = None
    multipliers: np.ndarray | None = None
    margin: float | None = None
    error_bound: float = 0.0
    decay: float | None = None
    gamma: float | None = None
    structure: str = ""
    reason: str = ""
    details: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "verdict", Verdict(self.verdict))  # a name is accepted too

    def evidence(self) -> dict[str, Any]:
        """JSON-serialisable evidence for re-verification."""
        return {
            "P": self.P,
            "multipliers_T": self.multipliers,
            "margin": self.margin,
            "error_bound": self.error_bound,
            "decay_alpha": self.decay,
            "gamma": self.gamma,
            "structure": self.structure,
            **self.details,
        }


# ---------------------------------------------------------------------------
# recomputation outside the solver


def circle_matrix(model: LureModel, P: np.ndarray, t: np.ndarray, alpha: float = 0.0) -> np.ndarray:
    """The circle-criterion LMI in (xi, phi), recomputed in numpy and symmetrised.

    [A B]' P [A B] - diag((1 - alpha) P, 0) + sym([[0, q Cw' T], [q T Cw, -2 T]])
    """
    G = np.hstack([model.A, model.B])
    N = model.N
    M = G.T @ P @ G
    M[:N, :N] -= (1.0 - alpha) * P
    T = np.diag(t)
    M[:N, N:] += model.q * model.Cw.T @ T
    M[N:, :N] += model.q * T @ model.Cw
    M[N:, N:] -= 2.0 * T
    return 0.5 * (M + M.T)


def iss_matrix(
    model: LureModel, P: np.ndarray, t: np.ndarray, alpha: float, g: float
) -> np.ndarray:
    """The dissipation LMI in (xi, phi, a), recomputed in numpy and symmetrised.

    V(xi+) - (1 - alpha) V(xi) + |e|^2 - g |a|^2 plus the sector terms with
    w = Cw xi + Dw a.
    """
    H = np.hstack([model.A, model.B, model.E])
    N, m, r = model.N, model.m, model.r
    M = H.T @ P @ H
    M[:N, :N] += model.Ce.T @ model.Ce - (1.0 - alpha) * P
    M[N + m :, N + m :] -= g * np.eye(r)
    if m:
        T = np.diag(t)
        qTC = model.q * T @ model.Cw
        qTD = model.q * T @ model.Dw
        M[N : N + m, :N] += qTC
        M[:N, N : N + m] += qTC.T
        M[N : N + m, N + m :] += qTD
        M[N + m :, N : N + m] += qTD.T
        M[N : N + m, N : N + m] -= 2.0 * T
    return 0.5 * (M + M.T)


def _error_bound(model: LureModel, P: np.ndarray, t: np.ndarray, size: int) -> float:
    """Rounding error bound on the eigenvalues of the recomputed LMI, relative to ||P||."""
    normP = max(float(np.linalg.norm(P, 2)), np.finfo(float).tiny)
    G = np.hstack([model.A, model.B, model.E])
    normG = float(np.linalg.norm(G, 2))
    tmax = float(np.abs(t).max(initial=0.0))
    normC = float(np.linalg.norm(np.hstack([model.Cw, model.Dw]), 2)) if model.m else 0.0
    normCe = float(np.linalg.norm(model.Ce, 2))
    raw = (normG**2 + 2.0) * normP + (2 * model.q * normC + 2) * tmax + normCe**2
    return 10.0 * size * EPS * raw / normP


def verify_certificate(
    model: LureModel,
    P: np.ndarray,
    t: np.ndarray,
    *,
    kind: str = "circle",
    alpha: float = 0.0,
    g: float = 0.0,
    clear: float = 100.0,
) -> tuple[bool, float, float, str]:
    """Re-verify a certificate without the solver.

    Returns
    -------
    ok : bool
    margin : float
        ``-lambda_max(LMI) / ||P||``.
    bound : float
        Error bound on that quantity.
    problem : str
        Empty when ok.
    """
    P = 0.5 * (np.asarray(P, dtype=float) + np.asarray(P, dtype=float).T)
    t = np.asarray(t, dtype=float)
    if not (np.all(np.isfinite(P)) and np.all(np.isfinite(t))):
        return False, float("nan"), 0.0, "the certificate has non-finite entries"
    if model.m and t.min(initial=0.0) < 0:
        return False, float("nan"), 0.0, f"a multiplier is negative ({t.min():.2e})"
    M = circle_matrix(model, P, t, alpha) if kind == "circle" else iss_matrix(model, P, t, alpha, g)
    normP = max(float(np.linalg.norm(P, 2)), np.finfo(float).tiny)
    lam = float(np.linalg.eigvalsh(M)[-1])
    margin = -lam / normP
    bound = _error_bound(model, P, t, M.shape[0])
    p_eigs = np.linalg.eigvalsh(P)
    if p_eigs[0] <= clear * 10 * P.shape[0] * EPS * normP:
        return (
            False,
            margin,
            bound,
            f"P is not clearly positive definite (lambda_min {p_eigs[0]:.2e})",
        )
    try:
        np.linalg.cholesky(P - 0.5 * p_eigs[0] * np.eye(P.shape[0]))
    except np.linalg.LinAlgError:
        return False, margin, bound, "P fails the Cholesky test"
    if margin <= clear * bound:
        return (
            False,
            margin,
            bound,
            (
                f"the recomputed LMI has largest eigenvalue {-margin:.2e} ||P||, not below "
                f"-{clear:g} x the error bound {bound:.2e}"
            ),
        )
    return True, margin, bound, ""


# ---------------------------------------------------------------------------
# solving


def _solve(
    model: LureModel, kind: str, structure: str, alpha: float, options: dict[str, Any]
) -> tuple[np.ndarray | None, np.ndarray | None, float | None, dict[str, Any]]:
    """One LMI solved with cvxpy and Clarabel: (P, t, g, info), the values None on failure.

    g is None for the circle LMI; ``info`` records the solver, the structure,
    the LMI's size, the status and the time.
    """
    import cvxpy as cp

    N, m = model.N, model.m
    start = time.perf_counter()
    t = cp.Variable(m) if m else None
    P, cons = _lyapunov_variable(N, model.n_e, structure)
    T = None
    if t is not None:  # m > 0
        cons.append(t >= 1e-6)
        T = cp.diag(t)
    g = None
    if kind == "circle":
        M, size = _circle_lmi(model, P, T, alpha)
    else:
        g = cp.Variable(nonneg=True)
        M, size = _iss_lmi(model, P, T, alpha, g)
    M = 0.5 * (M + M.T)
    cons.append(M << -ETA * np.eye(size))
    objective = cp.Minimize(g) if g is not None else cp.Minimize(0)
    problem = cp.Problem(objective, cons)
    info: dict[str, Any] = {"solver": "CLARABEL", "structure": structure, "lmi_size": size}
    if not _run_clarabel(problem, options, info, start):
        return None, None, None, info
    return _solution(problem, P, t, g, info)


def _lyapunov_variable(N: int, n: int, structure: str) -> tuple[Any, list[Any]]:
    """P as cvxpy variables in the given structure, and its constraints (P >= I)."""
    import cvxpy as cp

    if structure in ("block-diagonal", "cross") and n < N:
        P1 = cp.Variable((n, n), symmetric=True)
        d = cp.Variable(N - n)
        P12 = cp.Variable((n, N - n)) if structure == "cross" else np.zeros((n, N - n))
        P = cp.bmat([[P1, P12], [P12.T, cp.diag(d)]])
        cons = [P >> np.eye(N)] if structure == "cross" else [P1 >> np.eye(n), d >= 1]
    elif structure == "block-diagonal":
        P = cp.Variable((n, n), symmetric=True)
        cons = [P >> np.eye(n)]
    else:
        P = cp.Variable((N, N), symmetric=True)
        cons = [P >> np.eye(N)]
    return P, cons


def _circle_lmi(model: LureModel, P: Any, T: Any, alpha: float) -> tuple[Any, int]:
    """The circle-criterion LMI as a cvxpy expression (``circle_matrix``), and its size."""
    import cvxpy as cp

    N, m = model.N, model.m
    G = np.hstack([model.A, model.B])
    M = G.T @ P @ G
    Z = np.zeros
    M = M - (1.0 - alpha) * cp.bmat([[P, Z((N, m))], [Z((m, N)), Z((m, m))]])
    if m:
        qCT = model.q * model.Cw.T @ T
        M = M + cp.bmat([[Z((N, N)), qCT], [qCT.T, -2 * T]])
    return M, N + m


def _iss_lmi(model: LureModel, P: Any, T: Any, alpha: float, g: Any) -> tuple[Any, int]:
    """The dissipation LMI as a cvxpy expression (``iss_matrix`` with g), and its size."""
    import cvxpy as cp

    N, m, r = model.N, model.m, model.r
    H = np.hstack([model.A, model.B, model.E])
    Z = np.zeros
    M = H.T @ P @ H
    top = model.Ce.T @ model.Ce - (1.0 - alpha) * P
    M = M + cp.bmat(
        [
            [top, Z((N, m + r))],
            [
                Z((m + r, N)),
                cp.bmat([[Z((m, m)), Z((m, r))], [Z((r, m)), -g * np.eye(r)]])
                if m
                else -g * np.eye(r),
            ],
        ]
    )
    if m:
        qTC = model.q * T @ model.Cw
        qTD = model.q * T @ model.Dw
        M = M + cp.bmat(
            [[Z((N, N)), qTC.T, Z((N, r))], [qTC, -2 * T, qTD], [Z((r, N)), qTD.T, Z((r, r))]]
        )
    return M, N + m + r


def _run_clarabel(
    problem: Any, options: dict[str, Any], info: dict[str, Any], start: float
) -> bool:
    """Solve with Clarabel, recording the status and time in ``info``; True when optimal."""
    import warnings

    import cvxpy as cp

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # verified below, not trusted
            problem.solve(solver=cp.CLARABEL, **options)
    except Exception as exc:  # solver failure is an answer: inconclusive
        info.update(
            status=f"solver error: {type(exc).__name__}: {exc}".rstrip(": "),
            seconds=time.perf_counter() - start,
        )
        return False
    info.update(status=str(problem.status), seconds=time.perf_counter() - start)
    return problem.status in ("optimal", "optimal_inaccurate")


def _solution(
    problem: Any, P: Any, t: Any, g: Any, info: dict[str, Any]
) -> tuple[np.ndarray | None, np.ndarray | None, float | None, dict[str, Any]]:
    """The solved P (symmetrised), t and g, or None when the solver returned no finite values."""
    values = [P.value, t.value if t is not None else np.zeros(0), g.value if g is not None else 0.0]
    if any(v is None for v in values) or not all(
        np.all(np.isfinite(np.asarray(v, dtype=float))) for v in values
    ):
        info["status"] = f"{problem.status}, but the solver returned no finite values"
        return None, None, None, info
    Pv = np.asarray(values[0], dtype=float)
    tv = np.asarray(values[1], dtype=float).reshape(-1)
    return 0.5 * (Pv + Pv.T), tv, (float(values[2]) if g is not None else None), info


def _model_refusal(model: LureModel, budget: Budget) -> str:
    """Why the structural pre-checks (eigenvalues of N x N closed loops) are not affordable."""
    nbytes, flops = lure_model_cost(model.n_e, model.m, model.r)
    return budget.refusal(
        f"the Lur'e model with {model.N} states and {model.m} nonlinearities",
        nbytes=nbytes,
        flops=flops,
    )


def _solve_refusal(model: LureModel, kind: str, structure: str, budget: Budget) -> str:
    nbytes, flops = lmi_cost(model, kind, structure)
    size = model.N + model.m + (model.r if kind == "iss" else 0)
    return budget.refusal(
        f"the {structure} LMI with {size} rows (cvxpy and Clarabel)", nbytes=nbytes, flops=flops
    )


def _prechecks(model: LureModel) -> tuple[Verdict | None, str, dict[str, Any]]:
    """Structural facts that decide before any LMI is solved."""
    from .lyapunov import instability_witness

    n = model.n_e
    F = model.A[:n, :n]
    details: dict[str, Any] = {}
    rho_F = float(np.abs(np.linalg.eigvals(F)).max()) if n else 0.0
    details["spectral_radius_F"] = rho_F
    if rho_F >= 1 - 1e-12:
        from .spectral import schur_decision

        decision = schur_decision(F)
        details["exact_decision"] = decision.to_dict()
        if decision.state != "stable":
            witness = instability_witness(F, decision=decision)
            details["witness"] = witness
            where = (
                "near the origin the soft threshold is zero (dead zone), so the error "
                "follows e+ = F e and "
                if model.m
                else ""
            )
            if witness is not None and witness["verified"]:
                return (
                    Verdict.FAILS,
                    (
                        f"the linear error matrix F = A - L C is not stable: {decision.reason}; "
                        f"{where}the origin is not asymptotically stable"
                    ),
                    details,
                )
            return (
                Verdict.INCONCLUSIVE,
                (
                    f"the computed spectral radius of F = A - L C is {rho_F:.12g}, and its stability "
                    f"cannot be decided: {decision.reason}; no certificate is attempted"
                ),
                details,
            )
    if model.m:
        rho_q = float(np.abs(np.linalg.eigvals(model.vertex(model.q))).max())
        details["spectral_radius_at_sector_vertex"] = rho_q
        if rho_q >= 1 - 1e-9:
            if model.q >= 1 - 1e-12:
                why = (
                    f"with shrink = 1 the sector [0, 1] contains the identity, and the linear "
                    f"loop it then contains has spectral radius {rho_q:.6g} (exactly 1 whenever "
                    f"A has an eigenvalue at 1: e = v, a_hat = -C v); no sector certificate can "
                    f"exist, which does not mean the observer is unstable. Shrink < 1 (the "
                    f"elastic-net observer) is what makes a certificate possible"
                )
            else:
                why = (
                    f"the sector [0, {model.q:g}] contains the linear map phi = {model.q:g} w, "
                    f"whose closed loop has spectral radius {rho_q:.6g} >= 1; no sector "
                    f"certificate can exist"
                )
            return Verdict.INCONCLUSIVE, why, details
    return None, "", details


def circle_certificate(
    model: LureModel,
    *,
    structure: str = "auto",
    solver_options: dict[str, Any] | None = None,
    clear: float = 100.0,
    reuse: Sequence[tuple[np.ndarray, np.ndarray]] = (),
    budget: Budget | None = None,
) -> LMICertificate:
    """Circle-criterion certificate of global asymptotic stability without attack.

    Parameters
    ----------
    model : LureModel
    structure : {"auto", "block-diagonal", "cross", "full"}, default "auto"
        ``auto`` tries, cheapest first, P = diag(P1, D) with D diagonal
        (error and attack estimate decoupled), then the same with a full
        cross block, then a full P when the LMI has at most 80 rows.
    solver_options : dict, optional
        Passed to Clarabel.
    clear : float, default 100
        Required ratio of the verified margin to the error bound.
    reuse : sequence of (P, t)
        Candidate certificates (for example from a neighbouring design)
        tried by verification alone before any solve.
    budget : Budget, optional
        Memory and work allowed for one solve (default ``Budget()``: 2 GiB,
        1e12 operations); a structure whose estimated cost (``lmi_cost``)
        exceeds it is skipped, with the estimate in the reason.

    Returns
    -------
    LMICertificate
    """
    budget = budget or Budget()
    refusal = _model_refusal(model, budget)
    if refusal:
        return LMICertificate(
            Verdict.INCONCLUSIVE,
            "circle",
            reason=f"not attempted: {refusal}",
            details={"budget": budget.to_dict()},
        )
    verdict, reason, details = _prechecks(model)
    if verdict is not None:
        return LMICertificate(verdict, "circle", reason=reason, details=details)
    for P_old, t_old in reuse:
        ok, margin, bound, _ = verify_certificate(model, P_old, t_old, clear=clear)
        if ok:
            return _holds(model, P_old, t_old, margin, bound, "reused", {**details, "reused": True})
    attempts = []
    structures = STRUCTURES if structure == "auto" else [structure]
    for st in structures:
        if st == "full" and structure == "auto" and model.N + model.m > FULL_LIMIT:
            attempts.append(
                {"structure": "full", "status": f"skipped: LMI larger than {FULL_LIMIT}"}
            )
            continue
        skip = _solve_refusal(model, "circle", st, budget)
        if skip:
            attempts.append({"structure": st, "status": f"skipped: {skip}"})
            continue
        P, t, _, info = _solve(model, "circle", st, 0.0, solver_options or {})
        attempts.append(info)
        if P is None or t is None:  # t is None only when the solve failed
            continue
        ok, margin, bound, problem = verify_certificate(model, P, t, clear=clear)
        info["verified"] = ok
        if ok:
            return _holds(model, P, t, margin, bound, st, {**details, "attempts": attempts})
        info["verification_problem"] = problem
    return LMICertificate(
        Verdict.INCONCLUSIVE,
        "circle",
        reason=(
            "no circle-criterion certificate was found or verified (LMI "
            + "; ".join(f"{a['structure']}: {a['status']}" for a in attempts)
            + "); this does not show the observer is unstable"
        ),
        details={**details, "attempts": attempts},
    )


def _holds(
    model: LureModel,
    P: np.ndarray,
    t: np.ndarray,
    margin: float,
    bound: float,
    structure: str,
    details: dict[str, Any],
) -> LMICertificate:
    lam_max_P = float(np.linalg.eigvalsh(P)[-1])
    normP = float(np.linalg.norm(P, 2))
    # V(xi+) - V(xi) <= -margin ||P|| |xi|^2 <= -(margin ||P|| / lambda_max(P)) V(xi)
    decay = min(1.0, margin * normP / lam_max_P)
    return LMICertificate(
        Verdict.HOLDS,
        "circle",
        P=P,
        multipliers=t,
        margin=margin,
        error_bound=bound,
        decay=decay,
        structure=structure,
        details=details,
    )


def iss_certificate(
    model: LureModel,
    *,
    alpha: float = 0.0,
    structure: str = "auto",
    solver_options: dict[str, Any] | None = None,
    clear: float = 100.0,
    budget: Budget | None = None,
) -> LMICertificate:
    """Dissipation certificate V+ - V <= -alpha V - |e|^2 + gamma^2 |a|^2.

    Parameters
    ----------
    model : LureModel
    alpha : float, default 0
        Decay to keep (for example half the circle certificate's).
    structure, solver_options, clear, budget
        As in ``circle_certificate``.

    Returns
    -------
    LMICertificate
        ``gamma`` is the verified l2 gain from attack to estimation error;
        with ``alpha > 0`` the error dynamics are also input-to-state stable.
    """
    budget = budget or Budget()
    refusal = _model_refusal(model, budget)
    if refusal:
        return LMICertificate(
            Verdict.INCONCLUSIVE,
            "iss",
            reason=f"not attempted: {refusal}",
            details={"budget": budget.to_dict()},
        )
    verdict, reason, details = _prechecks(model)
    if verdict is not None:
        return LMICertificate(verdict, "iss", reason=reason, details=details)
    attempts = []
    structures = STRUCTURES if structure == "auto" else [structure]
    for st in structures:
        if st == "full" and structure == "auto" and model.N + model.m + model.r > FULL_LIMIT:
            attempts.append(
                {"structure": "full", "status": f"skipped: LMI larger than {FULL_LIMIT}"}
            )
            continue
        skip = _solve_refusal(model, "iss", st, budget)
        if skip:
            attempts.append({"structure": st, "status": f"skipped: {skip}"})
            continue
        P, t, g, info = _solve(model, "iss", st, alpha, solver_options or {})
        attempts.append(info)
        if P is None or t is None or g is None:  # None only when the solve failed
            continue
        # certify a slightly larger gain than the optimum so that the margin survives
        g_cert = g * (1 + 1e-6) + 1e-9
        ok, margin, bound, problem = verify_certificate(
            model, P, t, kind="iss", alpha=alpha, g=g_cert, clear=clear
        )
        info["verified"] = ok
        if ok:
            return LMICertificate(
                Verdict.HOLDS,
                "iss",
                P=P,
                multipliers=t,
                margin=margin,
                error_bound=bound,
                decay=alpha,
                gamma=float(np.sqrt(g_cert)),
                structure=st,
                details={**details, "attempts": attempts, "gamma_squared": g_cert},
            )
        info["verification_problem"] = problem
    return LMICertificate(
        Verdict.INCONCLUSIVE,
        "iss",
        reason=(
            "no dissipation certificate was found or verified (LMI "
            + "; ".join(f"{a['structure']}: {a['status']}" for a in attempts)
            + ")"
        ),
        details={**details, "attempts": attempts},
    )


def iss_from_circle(
    model: LureModel, circle: LMICertificate, *, clear: float = 100.0
) -> LMICertificate:
    """ISS decay and l2 gain from a verified circle certificate, without a new SDP.

    With (kappa P, kappa T) from the circle certificate and alpha = decay / 2,
    the dissipation LMI is [[Z(kappa), X(kappa)], [X', Y(kappa) - g I]] and
    the smallest admissible g is the largest eigenvalue of the Schur
    complement Y - X' Z^-1 X; it is minimised over kappa by a 1-D search and
    the result re-verified like any other certificate.

    Parameters
    ----------
    model : LureModel
    circle : LMICertificate
        A verified (``holds``) circle certificate of ``model``.
    clear : float, default 100

    Returns
    -------
    LMICertificate
    """
    if circle.verdict != Verdict.HOLDS or circle.P is None:
        return LMICertificate(
            Verdict.INCONCLUSIVE, "iss", reason="no circle certificate to build on"
        )
    P, t = circle.P, circle.multipliers if circle.multipliers is not None else np.zeros(0)
    alpha = 0.5 * float(circle.decay or 0.0)
    k = model.N + model.m
    perf = iss_matrix(model, np.zeros_like(P), np.zeros_like(t), alpha, 0.0)  # |e|^2 only
    base = iss_matrix(model, P, t, alpha, 0.0) - perf
    x, g = _smallest_gain(_schur_gain(base, perf, k), _scale_grid(model, base, k))
    if not np.isfinite(g):
        return LMICertificate(
            Verdict.INCONCLUSIVE,
            "iss",
            reason=(
                "no finite gain from the circle certificate (the Schur complement in the attack "
                "is not defined for any scaling tried)"
            ),
        )
    kappa = float(np.exp(x))
    ok, margin, bound, problem, g_cert = _verified_gain(
        model, kappa * P, kappa * t, alpha, g, clear
    )
    if not ok:
        return LMICertificate(Verdict.INCONCLUSIVE, "iss", reason=f"gain not verified: {problem}")
    return LMICertificate(
        Verdict.HOLDS,
        "iss",
        P=kappa * P,
        multipliers=kappa * t,
        margin=margin,
        error_bound=bound,
        decay=alpha,
        gamma=float(np.sqrt(g_cert)),
        structure=circle.structure,
        details={
            "method": "from the circle certificate (scaled, Schur complement in the attack)",
            "kappa": kappa,
            "gamma_squared": g_cert,
        },
    )


def _schur_gain(base: np.ndarray, perf: np.ndarray, k: int) -> Callable[[float], float]:
    """g(log kappa): the largest eigenvalue of the Schur complement of kappa base + perf.

    Infinite where Z (its leading k x k block) is not negative definite.
    """

    def gain(log_kappa: float) -> float:
        with np.errstate(over="ignore", invalid="ignore"):
            kappa = float(np.exp(log_kappa))
            M = kappa * base + perf
        if not np.all(np.isfinite(M)):
            return np.inf
        Z, X, Y = M[:k, :k], M[:k, k:], M[k:, k:]
        try:
            zmax = float(np.linalg.eigvalsh(Z)[-1])
            if zmax >= 0:
                return np.inf
            S = Y - X.T @ np.linalg.solve(Z, X)
            value = float(np.linalg.eigvalsh(0.5 * (S + S.T))[-1])
        except np.linalg.LinAlgError:  # singular Z: this kappa gives no gain
            return np.inf
        return value if np.isfinite(value) else np.inf

    return gain


def _scale_grid(model: LureModel, base: np.ndarray, k: int) -> np.ndarray:
    """60 values of log kappa over 8 decades, from where Z can first be negative definite."""
    # kappa must make Z negative definite: Z = kappa Zc + diag(Ce'Ce, 0)
    zc = float(np.linalg.eigvalsh(base[:k, :k])[-1])
    ce = float(np.linalg.norm(model.Ce, 2)) ** 2
    lo = np.log(1.01 * ce / max(-zc, np.finfo(float).tiny))
    return lo + np.linspace(0.0, np.log(1e8), 60)


def _smallest_gain(gain: Callable[[float], float], grid: np.ndarray) -> tuple[float, float]:
    """(log kappa, g) of the smallest gain: the grid's best, refined between its neighbours."""
    from scipy.optimize import minimize_scalar

    values = np.array([gain(x) for x in grid])
    best = int(np.argmin(values))
    a, b = grid[max(best - 1, 0)], grid[min(best + 1, grid.size - 1)]
    if not np.isfinite(values[best]):
        return float(grid[best]), float(values[best])
    refined = minimize_scalar(gain, bounds=(a, b), method="bounded")
    if refined.fun <= values[best]:
        return float(refined.x), float(refined.fun)
    return float(grid[best]), float(values[best])


def _verified_gain(
    model: LureModel, P: np.ndarray, t: np.ndarray, alpha: float, g: float, clear: float
) -> tuple[bool, float, float, str, float]:
    """``verify_certificate``'s answer for gamma^2 slightly above g, and that gamma^2.

    The Schur complement is tight by construction, so a relative margin of
    1e-6 is tried first, then one of 1 %.
    """
    g_cert = max(g, 0.0) * (1 + 1e-6) + 1e-9
    ok, margin, bound, problem = verify_certificate(
        model, P, t, kind="iss", alpha=alpha, g=g_cert, clear=clear
    )
    if not ok:
        # the Schur complement is tight by construction: keep a relative margin
        g_cert = max(g, 0.0) * 1.01 + 1e-6
        ok, margin, bound, problem = verify_certificate(
            model, P, t, kind="iss", alpha=alpha, g=g_cert, clear=clear
        )
    return ok, margin, bound, problem, g_cert
