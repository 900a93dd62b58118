"""Irrepresentable constant of the partial Lasso (Theorem 1 of the Lasso paper).

For the stacked model y = O_tau x + a with attack support S (the rows of
O_tau of the attacked sensors at all tau steps in block mode, or any h
entries of the stacked vector in entrywise mode),

    rho(S) = || O_Sbar^{dagger T} O_S^T ||_inf      (largest row sum of |.|)

with O_Sbar^{dagger T} = O_Sbar (O_Sbar^T O_Sbar)^{-1}.  Lasso recovers every
attack supported on S (for small enough lambda, noise-free) if rho(S) < 1.
Theorem 1 assumes O_Sbar has full column rank; where it does not, rho(S) is
reported as inf and the verdict fails with that support as witness.

rho is invariant under a change of state coordinates, so O_tau is replaced
by the orthonormal factor Q of its QR decomposition: then
O_Sbar^T O_Sbar = I - Q_S^T Q_S, a sum over the items of S that the colex
enumeration engine forms for many supports per numpy call.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from .._exact import exact_stacked_rank
from .._format import sig
from .._linalg import screen_positive_definite, stacked_rank, staircase
from .._validation import as_choice, as_int_option
from ..budget import Budget, bounded_comb, format_count, log10_comb
from ..results import Check, Verdict
from ..system import System
from ..tolerances import BORDERLINE, NONZERO, ZERO, Tolerances
from ._combinatorics import DEFAULT_CHUNK_BYTES, DEFAULT_MEMORY, colex_blocks
from .sparse import DEFAULT_MAX_SETS

__all__ = ["irrepresentable", "irrepresentable_constant", "MODES"]

MODES = ("block", "entrywise")
_SUB = 128  # largest number of supports per dense product
_LISTED = 10_000  # largest support listed in full in a result


def irrepresentable_constant(O: np.ndarray, support: list[int] | np.ndarray) -> float:
    """rho(S) for one support of rows of O, straight from the definition.

    Uses ``numpy.linalg.pinv``; meant for checking and small problems.

    Parameters
    ----------
    O : array_like, shape (m, n)
        Stacked observability matrix (or any sensing matrix).
    support : sequence of int
        Rows of O in the attack support S.

    Returns
    -------
    float
        ``|| O_Sbar^{dagger T} O_S^T ||_inf``; inf when O_Sbar lacks full
        column rank.

    Examples
    --------
    >>> import numpy as np
    >>> round(irrepresentable_constant(2.0 * np.ones((3, 1)), [0]), 12)
    0.5
    """
    O = np.asarray(O, dtype=float)
    mask = np.zeros(O.shape[0], dtype=bool)
    mask[np.asarray(support, dtype=int)] = True
    O_S, O_Sbar = O[mask], O[~mask]
    if O_Sbar.shape[0] < O.shape[1] or np.linalg.matrix_rank(O_Sbar) < O.shape[1]:
        return math.inf
    M = np.linalg.pinv(O_Sbar).T @ O_S.T
    return float(np.abs(M).sum(axis=1).max()) if M.size else 0.0


def irrepresentable(
    system: System,
    support_size: int,
    *,
    horizon: int | None = None,
    mode: str = "block",
    max_sets: int = DEFAULT_MAX_SETS,
    tolerances: Tolerances | None = None,
    progress: Callable[[int, int], None] | None = None,
    budget: Budget | None = None,
) -> Check:
    """Worst irrepresentable constant over all attack supports of a given size.

    Parameters
    ----------
    system : System
    support_size : int
        s sensors (block mode) or h entries of the stacked attack vector
        (entrywise mode).
    horizon : int, optional
        tau, the number of stacked steps (default n).
    mode : {"block", "entrywise"}, default "block"
    max_sets : int, default 50,000,000
        Budget of supports; beyond it the check is inconclusive.
    tolerances : Tolerances, optional
    progress : callable, optional
    budget : Budget, optional
        Memory and work allowed (default ``Budget()``: 2 GiB, 1e12
        operations).  Both are estimated from p, tau, n and the number of
        supports before anything is allocated; beyond them the check is
        inconclusive with the estimate.  Supports are processed in batches
        sized to the memory budget.

    Returns
    -------
    Check
        ``id = "irrepresentable"`` (advisory) with fields ``value`` (worst
        rho, inf when some O_Sbar lacks full column rank), ``worst_support``,
        ``support_size``, ``horizon`` and ``mode``; holds iff value < 1.

    Examples
    --------
    >>> from ssecert import System
    >>> check = irrepresentable(System([[1.0]], [[2.0], [2.0], [2.0]]), 1, horizon=1)
    >>> check.verdict.value, round(check.value, 12), check.fields["worst_support"]
    ('holds', 0.5, [0])
    """
    tol = Tolerances.check(tolerances)
    budget = budget or Budget()
    if not isinstance(system, System):
        raise TypeError(f"system must be a System, got {type(system).__name__}")
    mode = as_choice(mode, "mode", MODES)
    tau = system.n if horizon is None else as_int_option(horizon, "horizon", min_value=1)
    max_sets = as_int_option(max_sets, "max_sets", min_value=1)
    n, p = system.n, system.p
    items = p if mode == "block" else p * tau
    k = as_int_option(support_size, "support_size", min_value=0)
    fields: dict[str, Any] = {"support_size": k, "horizon": tau, "mode": mode}
    title = "Irrepresentable condition (Lasso support recovery)"
    method = "enumeration"
    total = bounded_comb(items, k, max_sets)
    evidence: dict[str, Any] = {
        "method_detail": (
            "every support enumerated; rho from the QR-whitened stacked observability matrix; "
            "worst support recomputed with numpy.linalg.pinv"
        ),
        "definition": "rho(S) = || O_Sbar (O_Sbar^T O_Sbar)^-1 O_S^T ||_inf (largest row sum)",
        "supports": total,
        "budget": budget.to_dict(),
    }
    if total is None:
        evidence["supports_log10"] = log10_comb(items, k)
    tol_out = {"irrepresentable_rtol": tol.irrepresentable_rtol, **tol.to_dict()}

    def describe_support(support: tuple[int, ...]) -> list[Any]:
        if mode == "block":
            return [system.sensors[i] for i in support]
        return [f"{system.sensors[r % p]}@{r // p}" for r in support]

    def make(
        verdict: Verdict,
        value: float,
        support: tuple[int, ...] | None,
        summary: str,
        margin: float | None = None,
        witness: dict | None = None,
    ) -> Check:
        return Check(
            id="irrepresentable",
            title=title,
            verdict=verdict,
            summary=summary,
            value=value,
            margin=margin,
            method=method,
            required=False,
            fields={
                **fields,
                "value": value,
                "worst_support": list(support) if support is not None else None,
                "worst_support_names": (describe_support(support) if support is not None else None),
            },
            evidence=evidence,
            witness=witness,
            tolerances=tol_out,
        )

    if k == 0:
        sc0 = staircase(system.A, system.C, max_steps=min(tau, n), tolerances=tol)
        if sc0.rank < n and not sc0.problem:
            doubt = _exact_doubt(system, range(p * min(tau, n)), min(tau, n), evidence)
            if doubt:
                return make(Verdict.INCONCLUSIVE, math.nan, None, f"O_tau (horizon {tau}) {doubt}")
            return make(
                Verdict.FAILS,
                math.inf,
                (),
                f"O_tau (horizon {tau}) has rank {sc0.rank} < n = {n}: even without "
                f"attack the state is not determined, so rho is inf.",
            )
        return make(
            Verdict.HOLDS,
            0.0,
            (),
            "With no attacked entries there is nothing to misidentify.",
            margin=1.0,
        )
    if k > items:
        every = tuple(range(items)) if items <= _LISTED else None
        return make(
            Verdict.FAILS,
            math.inf,
            every,
            f"The support size {k:,} exceeds the {items:,} available "
            f"{'sensors' if mode == 'block' else 'entries'}: an attack on all of them "
            f"leaves nothing to estimate the state from.",
        )
    if total is None:
        return make(
            Verdict.INCONCLUSIVE,
            math.nan,
            None,
            f"C({items:,}, {k:,}) = {format_count(10 ** min(log10_comb(items, k), 308))} "
            f"supports exceed the budget of {max_sets:,}; raise it with --max-sets "
            f"(max_sets=...).",
        )
    if k == items:
        return make(
            Verdict.FAILS,
            math.inf,
            tuple(range(items)),
            f"With all {items} {'sensors' if mode == 'block' else 'entries'} attacked, "
            f"O_Sbar is empty and lacks full column rank (Theorem 1's assumption), so "
            f"rho is inf.",
            witness={
                "support": list(range(items)),
                "support_names": describe_support(tuple(range(items))),
                "reason": "O_Sbar lacks full column rank",
            },
        )
    h = k * tau if mode == "block" else k
    colex_memory = int(min(DEFAULT_MEMORY, budget.memory // 8))
    nbytes, flops, per_support = _cost(n, p, tau, items, h, total, mode, colex_memory)
    evidence["estimate"] = {"bytes": nbytes, "flops": flops, "bytes_per_support": per_support}
    refusal = budget.refusal(
        f"the irrepresentable enumeration ({format_count(total)} supports of {h:,} rows of the "
        f"{p * tau:,} x {n} matrix O_tau, horizon {tau:,})",
        nbytes=nbytes,
        flops=flops,
    )
    if refusal:
        hint = "; a shorter horizon (--horizon) makes it smaller" if tau > n else ""
        return make(Verdict.INCONCLUSIVE, math.nan, None, f"Not attempted: {refusal}{hint}.")
    batch = int(max(1, min(_SUB, (budget.memory // 4) // per_support)))

    with np.errstate(over="ignore", invalid="ignore"):
        O = system.observability_matrix(tau)  # row t * p + i: sensor i at step t
    if mode == "block":
        rows_of = (
            np.arange(tau, dtype=np.int64)[None, :] * p + np.arange(p, dtype=np.int64)[:, None]
        )
    else:
        rows_of = np.arange(p * tau, dtype=np.int64)[:, None]
    if not np.all(np.isfinite(O)):
        return make(
            Verdict.INCONCLUSIVE,
            math.nan,
            None,
            f"The stacked observability matrix overflows over {tau} steps.",
        )

    sc = staircase(system.A, system.C, max_steps=tau, tolerances=tol)
    evidence["rank_O_tau"] = sc.rank
    if sc.rank < n or sc.problem:
        first = tuple(range(k))
        if sc.problem:
            return make(
                Verdict.INCONCLUSIVE,
                math.nan,
                None,
                f"The rank of O_tau cannot be decided: {sc.problem}.",
            )
        doubt = _exact_doubt(system, range(p * min(tau, n)), min(tau, n), evidence)
        if doubt:
            return make(Verdict.INCONCLUSIVE, math.nan, None, f"O_tau (horizon {tau}) {doubt}")
        return make(
            Verdict.FAILS,
            math.inf,
            first,
            f"O_tau (horizon {tau}) has rank {sc.rank} < n = {n}, so no O_Sbar has full column "
            f"rank as Theorem 1 requires; the first support {', '.join(map(str, describe_support(first)))} "
            f"is a witness.",
            witness={
                "support": list(first),
                "support_names": describe_support(first),
                "reason": "O_Sbar lacks full column rank",
            },
        )

    Q, _ = np.linalg.qr(O)
    U = Q[rows_of]  # (items, r, n)
    G = np.einsum("irn,irm->inm", U, U)
    shift = tol.screen_rtol
    base = np.eye(n)
    worst = -1.0
    worst_support: tuple[int, ...] | None = None
    infinite: tuple[int, ...] | None = None
    n_inf = 0
    borderline = 0
    done = 0
    for block in colex_blocks(G, base, k, memory=colex_memory):
        subsets = block.subsets()
        ok = screen_positive_definite(block.matrices, shift)
        rho = np.full(len(block), np.nan)
        good = np.flatnonzero(ok)
        for start in range(0, good.size, batch):
            sel = good[start : start + batch]
            rho[sel] = _rho_batch(Q, rows_of, block.matrices[sel], subsets[sel])
        bad = np.flatnonzero(~ok)
        if bad.size:
            r_bad, codes = _rho_refine(Q, rows_of, subsets[bad], tol)
            rho[bad] = r_bad
            borderline += int(np.count_nonzero(codes == BORDERLINE))
            inf_rows = bad[codes == ZERO]
            n_inf += inf_rows.size
            for j in inf_rows:
                cand = tuple(int(x) for x in subsets[j])
                if infinite is None or cand < infinite:
                    infinite = cand
        finite = np.flatnonzero(np.isfinite(rho))
        if finite.size:
            top = float(rho[finite].max())
            ties = finite[rho[finite] >= top - 1e-12 * max(1.0, top)]
            cand = min(tuple(int(x) for x in subsets[j]) for j in ties)
            if worst_support is None or top > worst + 1e-12 * max(1.0, worst):
                worst, worst_support = top, cand
            elif top >= worst - 1e-12 * max(1.0, worst):
                worst, worst_support = max(worst, top), min(worst_support, cand)
        done += len(block)
        if progress is not None:
            progress(done, total)

    evidence["supports_without_full_rank"] = n_inf
    evidence["borderline_supports"] = borderline
    if infinite is not None:
        kept = np.setdiff1d(np.arange(p * tau), rows_of[list(infinite)].ravel())
        doubt = _exact_doubt(system, kept, tau, evidence)
        if doubt:
            label = ", ".join(map(str, describe_support(infinite)))
            return make(
                Verdict.INCONCLUSIVE,
                math.nan,
                None,
                f"O_Sbar for the support {label} {doubt}",
            )
        return make(
            Verdict.FAILS,
            math.inf,
            infinite,
            f"For {n_inf} of {total} supports O_Sbar lacks full column rank (Theorem 1's "
            f"assumption); the first is {', '.join(map(str, describe_support(infinite)))}, so rho is inf "
            f"there.",
            witness={
                "support": list(infinite),
                "support_names": describe_support(infinite),
                "reason": "O_Sbar lacks full column rank",
            },
        )
    if borderline:
        return make(
            Verdict.INCONCLUSIVE,
            math.nan,
            None,
            f"{borderline} support(s) have a borderline rank decision for O_Sbar.",
        )
    assert worst_support is not None
    rows = rows_of[list(worst_support)].ravel()
    direct = irrepresentable_constant(O, rows)
    evidence["worst_support_recomputed_with_pinv"] = direct
    rel = abs(direct - worst) / max(1.0, abs(worst))
    evidence["recompute_relative_difference"] = rel
    names = describe_support(worst_support)
    label = ", ".join(map(str, names))
    if not math.isfinite(direct) or rel > 1e-6:
        return make(
            Verdict.INCONCLUSIVE,
            worst,
            worst_support,
            f"The worst constant {worst:.6g} on {label} does not match its direct "
            f"recomputation {direct:.6g}.",
        )
    margin = 1.0 - worst
    band = tol.irrepresentable_rtol
    if worst < 1.0 - band:
        return make(
            Verdict.HOLDS,
            worst,
            worst_support,
            f"The worst irrepresentable constant is {sig(worst)} < 1 (support {label}): "
            f"Lasso identifies every attack on {k} {'sensors' if mode == 'block' else 'entries'}"
            f" for small enough lambda.",
            margin=margin,
        )
    if worst > 1.0 + band:
        return make(
            Verdict.FAILS,
            worst,
            worst_support,
            f"The irrepresentable constant reaches {sig(worst)} >= 1 on support {label}: "
            f"Lasso's support recovery is not guaranteed there.",
            margin=margin,
            witness={"support": list(worst_support), "support_names": names, "value": worst},
        )
    return make(
        Verdict.INCONCLUSIVE,
        worst,
        worst_support,
        f"The worst constant {worst:.12g} is within {band:g} of 1.",
        margin=margin,
    )


def _exact_doubt(system: System, rows: Any, steps: int, evidence: dict[str, Any]) -> str:
    """Why a floating-point rank deficiency of some rows of O_steps is not trusted, or "".

    The rows are taken with the data as exact rationals: full column rank
    there (modulo a prime, a proof) means the deficiency hinged on digits
    below the data's precision.  An exact kernel vector confirms it; beyond
    the exact budgets the floating-point decision stands.
    """
    exact = exact_stacked_rank(system.A, system.C, rows, steps)
    evidence["exact_rank_check"] = exact.to_dict()
    if exact.state != "observable":
        return ""
    return (
        "looks rank deficient in floating point, but with the data taken exactly it has full "
        f"column rank (rank {system.n} modulo a prime): the plant is within the precision of its "
        "data of one where Theorem 1's assumption fails, so rho depends on digits the data do "
        "not have."
    )


def _cost(
    n: int, p: int, tau: int, items: int, h: int, supports: int, mode: str, colex_memory: int
) -> tuple[float, float, float]:
    """Peak bytes, operations and bytes per support of the enumeration, from the shapes.

    Peak: O_tau and its QR factor (4 copies of p tau x n), the per-item
    Gramians, the colex engine's partial sums, one support's dense products
    (2 copies of p tau x h, the rows of O_tau outside and inside it), and the
    direct pinv recomputation of the worst support.  Work: the QR, the Gramians
    and, per support, the p tau x n x h product, its absolute row sums and an
    n x n factorisation; calibrated so that 1e12 is one to three minutes on
    one core.
    """
    M = p * tau
    per_support = 8.0 * (2 * M * h + 3 * h * n + M)
    colex = min(colex_memory + DEFAULT_CHUNK_BYTES, 2 * 8.0 * supports * n * n)
    nbytes = 8.0 * (4 * M * n + M + items * n * n) + colex + per_support + 8.0 * (2 * M * n + M * h)
    # the elementwise passes over the p tau x h product (absolute value, sums, the
    # memory traffic) cost far more than their count: 60 per entry, measured
    flops = (
        4.0 * M * n * n
        + 2.0 * M * n * n
        + supports * (2.0 * M * n * h + 60.0 * M * h + n**3 + 2.0 * n * n * h)
    )
    return nbytes, flops, per_support


def _rho_batch(
    Q: np.ndarray, rows_of: np.ndarray, M: np.ndarray, subsets: np.ndarray
) -> np.ndarray:
    """rho for supports whose Gramian M = Q_Sbar^T Q_Sbar passed screening."""
    N = subsets.shape[0]
    rows = rows_of[subsets].reshape(N, -1)  # (N, h)
    QS = Q[rows]  # (N, h, n)
    X = np.linalg.solve(M, QS.transpose(0, 2, 1))  # (N, n, h)
    h = X.shape[2]
    # one product for the whole batch: (p tau, n) x (n, N h)
    full = Q @ X.transpose(1, 0, 2).reshape(Q.shape[1], N * h)
    np.abs(full, out=full)
    sums = full.reshape(Q.shape[0], N, h).sum(axis=2).T  # (N, p tau)
    np.put_along_axis(sums, rows, 0.0, axis=1)  # keep only rows outside S
    return sums.max(axis=1)


def _rho_refine(
    Q: np.ndarray, rows_of: np.ndarray, subsets: np.ndarray, tol: Tolerances
) -> tuple[np.ndarray, np.ndarray]:
    """Exact rank decision by SVD for supports that failed screening, and rho."""
    N = subsets.shape[0]
    m = Q.shape[0]
    rho = np.empty(N)
    codes = np.empty(N, dtype=np.int8)
    for j in range(N):
        mask = np.ones(m, dtype=bool)
        rows = rows_of[subsets[j]].ravel()
        mask[rows] = False
        Qbar = Q[mask]
        c, _, _ = stacked_rank(Qbar[None], tolerances=tol)
        codes[j] = c[0]
        if c[0] == NONZERO:
            M = np.linalg.pinv(Qbar).T @ Q[rows].T
            rho[j] = np.abs(M).sum(axis=1).max()
        else:
            rho[j] = math.inf if c[0] == ZERO else math.nan
    return rho, codes
