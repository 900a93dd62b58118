"""The circle and dissipation LMIs as cvxpy problems, solved with Clarabel.

P has the structure asked for (block diagonal between e and a_hat with a
diagonal a_hat block, the same with a full cross block, or full), P >= I,
the multipliers T >= 1e-6, and the LMI is imposed with the margin ``ETA``.
What the solver returns is only a candidate: ``ssecert.stability.lmi``
re-verifies it (``verify_certificate``) before any verdict.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..observers.lure import LureModel
from ..solvers import solve_conic, solved, solver_name

__all__ = ["ETA", "lmi_cost"]

ETA = 1e-4  # margin imposed in the LMIs, relative to P >= I


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
    info: dict[str, Any] = {"solver": solver_name(), "structure": structure, "lmi_size": size}
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
    with np.errstate(over="ignore", invalid="ignore"):  # inf data: the solver refuses it
        CeCe = model.Ce.T @ model.Ce
    top = CeCe - (1.0 - alpha) * P
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

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # verified below, not trusted
            solve_conic(problem, **options)
    except Exception as exc:  # solver failure is an answer: inconclusive
        info.update(
            status=f"solver error: {type(exc).__name__}: {exc}".rstrip(": "),
            seconds=time.perf_counter() - start,
        )
        return False
    info.update(status=str(problem.status), seconds=time.perf_counter() - start)
    return solved(problem)


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
