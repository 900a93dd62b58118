"""Many small LMIs in symmetric matrix variables, passed to Clarabel without a modelling layer.

A problem with hundreds of small LMIs (the piecewise-quadratic certificates)
spends most of its time in cvxpy's canonicalisation; here each LMI is a sum
of congruences F' X F of symmetric variables X plus scalar variables times
constant matrices, and its coefficients are assembled in a few numpy calls
into Clarabel's form A x + s = b, s in the cone.  Variables are symmetric
blocks (free, or entrywise nonnegative) and nonnegative scalars.  Only the
solver's candidate comes out of here: callers verify it.

Clarabel, the default, gets that form directly.  Another solver chosen with
``ssecert.solvers.using_solver`` (``--solver``) gets the same problem through
cvxpy: one vector variable x, b - A x nonnegative on the first rows and each
LMI's block of rows, unpacked into its symmetric matrix, positive semidefinite.
"""

from __future__ import annotations

import functools
import time
from typing import Any, NamedTuple

import numpy as np

__all__ = ["LMIProblem"]


@functools.lru_cache(maxsize=64)
def _triu(d: int) -> tuple[np.ndarray, np.ndarray]:
    """Row and column indices of the upper triangle, column by column (Clarabel's order);
    read-only and remembered (the piecewise search asks for the same few sizes thousands
    of times)."""
    cols, rows = np.tril_indices(d)  # the lower triangle row by row, transposed
    rows.flags.writeable = False
    cols.flags.writeable = False
    return rows, cols


class LMIProblem:
    """Feasibility of LMIs ``sum_k F_k' X_k F_k + sum_j s_j M_j + C >= delta I``, or the
    largest scalar variable among their solutions (``maximize``)."""

    def __init__(self) -> None:
        self._maximized: int | None = None  # the handle of the scalar to maximise
        # (offset, size, nonneg, rows, columns of the entries that are variables)
        self._blocks: list[tuple[int, int, bool, np.ndarray, np.ndarray]] = []
        self._size = 0
        self._lmis: list[tuple[int, list[tuple[int, np.ndarray, float]], list, np.ndarray]] = []

    def block(self, size: int, *, nonneg: bool = False, mask: np.ndarray | None = None) -> int:
        """A symmetric size x size variable (its upper triangle; with ``mask``, only the entries
        it marks, the others zero); returns its handle."""
        rows, cols = _triu(size)
        if mask is not None:
            keep = np.asarray(mask, bool)[rows, cols] | np.asarray(mask, bool)[cols, rows]
            rows, cols = rows[keep], cols[keep]
        self._blocks.append((self._size, size, nonneg, rows, cols))
        self._size += len(rows)
        return len(self._blocks) - 1

    def scalar(self) -> int:
        """A nonnegative scalar variable (a 1 x 1 nonnegative block)."""
        return self.block(1, nonneg=True)

    def lmi(
        self,
        constant: np.ndarray,
        terms: list[tuple[int, np.ndarray, float]],
        scalars: list[tuple[int, np.ndarray, float]] = (),  # type: ignore[assignment]
        *,
        delta: float = 0.0,
    ) -> None:
        """Require ``constant + sum sign F' X F + sum sign s M >= delta I`` (terms (handle, F,
        sign) with X the block's matrix, scalars (handle, M, sign))."""
        d = constant.shape[0]
        self._lmis.append((d, list(terms), list(scalars), constant - delta * np.eye(d)))

    def matrix(self, x: np.ndarray, handle: int) -> np.ndarray:
        """A block's symmetric matrix from the solution vector."""
        offset, size, _, rows, cols = self._blocks[handle]
        X = np.zeros((size, size))
        X[rows, cols] = x[offset : offset + len(rows)]
        X[cols, rows] = X[rows, cols]
        return X

    def value(self, x: np.ndarray, handle: int) -> float:
        return float(x[self._blocks[handle][0]])

    def maximize(self, handle: int) -> None:
        """Maximise the scalar ``handle`` (a ``scalar()``) instead of finding any solution."""
        self._maximized = handle

    def _objective(self) -> np.ndarray:
        """q of the objective q' x that the solver minimises."""
        q = np.zeros(self._size)
        if self._maximized is not None:
            q[self._blocks[self._maximized][0]] = -1.0
        return q

    def solve(
        self, *, time_limit: float = 60.0, max_iter: int = 50
    ) -> tuple[np.ndarray | None, dict[str, Any]]:
        """The solver's candidate x (None on failure) and what it reported: Clarabel's own
        interface, or cvxpy with the solver ``ssecert.solvers.solver_name`` names."""
        from ..solvers import solver_name

        start = time.perf_counter()
        A, b, nonneg, sizes = self._standard_form()
        name = solver_name()
        iterations: int | None
        form = _Form(self._objective(), A, b, nonneg, sizes)
        if name == "CLARABEL":
            x, status, iterations = _clarabel(form, time_limit, max_iter)
        else:
            x, status, iterations = _through_cvxpy(form, time_limit, max_iter)
        info = {
            "solver": name,
            "status": status,
            "variables": self._size,
            "lmis": len(self._lmis),
            "iterations": iterations,
            "seconds": round(time.perf_counter() - start, 3),
        }
        if x is None:
            return None, info
        return (x if np.all(np.isfinite(x)) else None), info

    def _standard_form(self) -> tuple[Any, np.ndarray, int, list[int]]:
        """A (sparse), b, the number of nonnegative rows (first) and each LMI's size: the
        problem is b - A x in the nonnegative cone, then in each LMI's PSD triangle cone
        (Clarabel's svec: the upper triangle column by column, off-diagonals times sqrt 2)."""
        from scipy import sparse

        data: list[np.ndarray] = []
        row_index: list[np.ndarray] = []
        col_index: list[np.ndarray] = []
        b_parts: list[np.ndarray] = []
        row = 0
        nonneg = [(o, len(r)) for o, _, nn, r, _ in self._blocks if nn]
        if nonneg:
            idx = np.concatenate([np.arange(o, o + k) for o, k in nonneg])
            data.append(-np.ones(len(idx)))
            row_index.append(np.arange(len(idx)))
            col_index.append(idx)
            b_parts.append(np.zeros(len(idx)))
            row = len(idx)
        first = row
        sizes = []
        for d, terms, scalars, constant in self._lmis:
            r_out, c_out = _triu(d)
            scale = np.where(r_out == c_out, 1.0, np.sqrt(2.0))
            b_parts.append(scale * constant[r_out, c_out])
            for handle, F, sign in terms:
                offset, _, _, ra, ca = self._blocks[handle]
                # F' E_ab F for the basis E_ab of the block's entry (a, b)
                # (data beyond the floats' range become inf or NaN here, which the solver
                # refuses by name: no warning of their own)
                # (the products F[a, i] F[b, j] of the entries asked only, each as it is)
                with np.errstate(over="ignore", invalid="ignore"):
                    Fa, Fb = F[ra], F[ca]
                    basis = Fa[:, r_out] * Fb[:, c_out] + np.where(
                        (ra != ca)[:, None], Fb[:, r_out] * Fa[:, c_out], 0.0
                    )
                    coeff = -sign * scale[None, :] * basis  # (entries, svec)
                entry, out = np.nonzero(coeff)
                data.append(coeff[entry, out])
                row_index.append(row + out)
                col_index.append(offset + entry)
            for handle, M, sign in scalars:
                v = -sign * scale * M[r_out, c_out]
                (where,) = np.nonzero(v)
                data.append(v[where])
                row_index.append(row + where)
                col_index.append(np.full(len(where), self._blocks[handle][0]))
            sizes.append(d)
            row += len(r_out)
        A = sparse.csc_matrix(
            (np.concatenate(data), (np.concatenate(row_index), np.concatenate(col_index))),
            shape=(row, self._size),
        )
        return A, np.concatenate(b_parts), first, sizes


class _Form(NamedTuple):
    """The problem minimise q' x with b - A x in the cones: the nonnegative one on the first
    ``nonneg`` rows, then each LMI's PSD triangle cone of the given sizes."""

    q: np.ndarray
    A: Any
    b: np.ndarray
    nonneg: int
    sizes: list[int]


def _clarabel(form: _Form, time_limit: float, max_iter: int) -> tuple[np.ndarray | None, str, int]:
    """Clarabel's x (None unless solved or almost), its status and iterations."""
    import clarabel
    from scipy import sparse

    q, A, b, nonneg, sizes = form
    cones: list[Any] = [clarabel.NonnegativeConeT(nonneg)] if nonneg else []
    cones += [clarabel.PSDTriangleConeT(d) for d in sizes]
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.time_limit = float(time_limit)
    settings.max_iter = int(max_iter)
    size = A.shape[1]
    solver = clarabel.DefaultSolver(sparse.csc_matrix((size, size)), q, A, b, cones, settings)
    solution = solver.solve()
    status = str(solution.status)
    if solution.status not in (clarabel.SolverStatus.Solved, clarabel.SolverStatus.AlmostSolved):
        return None, status, int(solution.iterations)
    return np.asarray(solution.x, dtype=float), status, int(solution.iterations)


@functools.lru_cache(maxsize=64)
def _unpack(d: int) -> Any:
    """The sparse map from an svec of size d (Clarabel's order and scaling) to the
    column-major entries of its symmetric d x d matrix."""
    from scipy import sparse

    rows, cols = _triu(d)
    scale = np.where(rows == cols, 1.0, 1.0 / np.sqrt(2.0))
    k = np.arange(len(rows))
    upper, lower = rows + d * cols, cols + d * rows
    off = rows != cols
    return sparse.csr_matrix(
        (np.r_[scale, scale[off]], (np.r_[upper, lower[off]], np.r_[k, k[off]])),
        shape=(d * d, len(rows)),
    )


def _through_cvxpy(
    form: _Form, time_limit: float, max_iter: int
) -> tuple[np.ndarray | None, str, int | None]:
    """The same problem as cvxpy constraints, solved by ``ssecert.solvers.solve_conic``
    (Clarabel's options translated for the chosen solver): x (None unless the status is
    optimal or optimal_inaccurate), cvxpy's status, the solver's iterations when it says."""
    import warnings

    import cvxpy as cp

    from ..solvers import solve_conic, solved

    q, A, b, nonneg, sizes = form
    x = cp.Variable(A.shape[1])
    constraints = []
    if nonneg:
        constraints.append(A[:nonneg] @ x <= b[:nonneg])
    row = nonneg
    for d in sizes:
        k = d * (d + 1) // 2
        vec = _unpack(d) @ (b[row : row + k] - A[row : row + k] @ x)
        S = cp.reshape(vec, (d, d), order="F")
        constraints.append(0.5 * (S + S.T) >> 0)
        row += k
    problem = cp.Problem(cp.Minimize(q @ x if np.any(q) else 0), constraints)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # verified by the caller, not trusted
            solve_conic(problem, time_limit=time_limit, max_iter=max_iter)
    except Exception as exc:  # a solver failure is an answer: no candidate
        return None, f"solver error: {type(exc).__name__}: {exc}".rstrip(": "), None
    stats = problem.solver_stats
    iterations = getattr(stats, "num_iters", None) if stats is not None else None
    status = str(problem.status)
    if not solved(problem) or x.value is None:
        return None, status, iterations
    return np.asarray(x.value, dtype=float), status, iterations
