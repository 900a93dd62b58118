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

Units.  The states are taken in balanced power-of-two units (rho does not
change).  A sensor's units do change rho (its attack column is an identity
column, its l1 penalty weighs the attack in those units), but no rank: every
rank is decided with the rows of C (or of O_Sbar) and the states scaled by
powers of two to unit size, and a support is said to be rank deficient
"within the precision of its data" only with its smallest singular value,
so scaled, stated beside the claim.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from ..base.validation import as_choice, as_float_option, as_int_option
from ..budget import Budget, bounded_comb, format_count, log10_comb
from ..numerics.exact import Observability, exact_stacked_rank
from ..numerics.linalg import balanced_units, staircase
from ..parallel import ChunkError
from ..results import Check
from ..system import System
from ..tolerances import Tolerances
from . import irrepresentable_messages as messages
from ._irrepresentable_scan import (
    ScanPlan,
    StackedRows,
    SupportScan,
    plan_scan,
    rho_error,
    scan_supports,
    sensor_units_condition,
    support_rho,
)
from .outcomes import IrrepresentableCode as Code
from .sparse import DEFAULT_MAX_SETS, DEFAULT_TIME_BUDGET

__all__ = ["irrepresentable", "irrepresentable_constant", "MODES"]

MODES = ("block", "entrywise")
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


@dataclass(frozen=True)
class _Verdicts:
    """What every verdict of one call shows: its fields, evidence, tolerances and sensor names."""

    system: System
    ranks: System  # the same plant with rows and states in unit powers of two: rank decisions
    mode: str
    k: int
    tau: int
    evidence: dict[str, Any]  # filled in as the steps run
    tolerances: dict[str, Any]

    @property
    def noun(self) -> str:
        """What the support counts: sensors (block mode) or entries."""
        return "sensors" if self.mode == "block" else "entries"

    def counted(self, k: int) -> str:
        """The noun for k of them (singular for one)."""
        if k != 1:
            return self.noun
        return "sensor" if self.mode == "block" else "entry"

    def names(self, support: tuple[int, ...]) -> list[Any]:
        """Sensor names of a support (block) or ``name@step`` of its entries (entrywise)."""
        sensors = self.system.sensors
        if self.mode == "block":
            return [sensors[i] for i in support]
        p = self.system.p
        return [f"{sensors[r % p]}@{r // p}" for r in support]

    def label(self, support: tuple[int, ...]) -> str:
        """The support's names, comma separated."""
        return ", ".join(map(str, self.names(support)))

    def rank_witness(self, support: tuple[int, ...]) -> dict[str, Any]:
        """Witness of a support whose O_Sbar lacks full column rank."""
        return {
            "support": list(support),
            "support_names": self.names(support),
            "reason": "O_Sbar lacks full column rank",
        }

    def check(
        self,
        code: Code,
        value: float,
        support: tuple[int, ...] | None,
        facts: dict[str, Any],
        margin: float | None = None,
        witness: dict | None = None,
        extra: dict[str, Any] | None = None,
    ) -> Check:
        """The irrepresentable Check of ``code`` (its verdict; its summary from ``facts``), with
        this worst value and support (and ``extra`` fields)."""
        return Check(
            id="irrepresentable",
            title="Irrepresentable condition (Lasso support recovery)",
            verdict=code.verdict,
            summary=messages.summary(code, facts),
            value=value,
            margin=margin,
            method="enumeration",
            required=False,
            fields={
                "support_size": self.k,
                "horizon": self.tau,
                "mode": self.mode,
                "value": value,
                "worst_support": list(support) if support is not None else None,
                "worst_support_names": self.names(support) if support is not None else None,
                **(extra or {}),
            },
            evidence=self.evidence,
            witness=witness,
            tolerances=self.tolerances,
            code=code,
        )


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
    client: Any | None = None,
    time_budget: float | None = DEFAULT_TIME_BUDGET,
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
    client : dask.distributed.Client, optional
        Split the supports over the client's workers (ranges of colex
        ranks), with the in-process answer; a range that fails twice makes
        the check inconclusive with the reason.
    time_budget : float or None, default 5
        Seconds after which an in-process scan that has already found a
        support with rho clearly above 1 stops: the verdict (fails) is
        decided, and the worst value is then a lower bound
        (``value_is_lower_bound``, with the supports checked).  A holds
        verdict needs every support and is never cut short; None scans all.

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
    system, ranks = _states_balanced(system)
    mode = as_choice(mode, "mode", MODES)
    tau = system.n if horizon is None else as_int_option(horizon, "horizon", min_value=1)
    max_sets = as_int_option(max_sets, "max_sets", min_value=1)
    items = system.p if mode == "block" else system.p * tau
    k = as_int_option(support_size, "support_size", min_value=0)
    total = bounded_comb(items, k, max_sets)
    out = _start(system, ranks, mode, k, tau, items, total, budget, tol)
    decided = _decided_by_size(out, items, total, max_sets, tol)
    if decided is not None:
        return decided
    assert total is not None
    plan = plan_scan(system.n, system.p, tau, items, k, total, mode, budget)
    refused = _over_budget(out, plan, budget, total)
    if refused is not None:
        return refused

    with np.errstate(over="ignore", invalid="ignore"):
        O = system.observability_matrix(tau)  # row t * p + i: sensor i at step t
    rows_of = _rows_of_items(system.p, tau, mode)
    if not np.all(np.isfinite(O)):
        return out.check(Code.OVERFLOW, math.nan, None, {"tau": tau})
    rows = StackedRows.of(O)
    deficient = _rank_deficient(out, rows, tol)
    if deficient is not None:
        return deficient

    deadline = None
    if time_budget is not None and client is None:
        deadline = time.monotonic() + as_float_option(time_budget, "time_budget", min_value=0.0)
    try:
        scan = scan_supports(
            rows, rows_of, k, plan, tol, total, progress, client,
            deadline=deadline, stop_above=1.0 + tol.irrepresentable_rtol,
        )  # fmt: skip
    except ChunkError as exc:
        lo, hi = exc.chunk
        facts = {"first": lo, "last": hi - 1, "cause": exc.cause}
        return out.check(Code.WORKERS_FAILED, math.nan, None, facts)
    return _scan_verdict(out, scan, rows, rows_of, tol, total, time_budget)


def _states_balanced(system: System) -> tuple[System, System]:
    """The plant in balanced power-of-two state units (x = S x_b, exact), and the same plant
    with its sensors' rows and A also scaled by powers of two (``balanced_units``).

    rho(S) depends on O_tau only through its range, which a change of state coordinates
    keeps, so the first gives the same value.  Its sensor rows are the user's: rescaling them
    would weigh the Lasso's l1 penalty differently and change rho.  The second has the same
    ranks (of O_tau and of every O_Sbar) exactly, and decides them: a sensor in units 2^-60,
    or a state in units 2^60 that one sensor alone sees (C = I), has a row far below the
    others' that a rank threshold relative to the whole of C would take for zero."""
    units = balanced_units(system)
    if not units.balanced:
        return system, units.system
    s = units.states
    A = system.A * (s[None, :] / s[:, None])
    balanced = System(A, system.C * s[None, :], sensors=system.sensors, name=system.name)
    return balanced, units.system


def _scan_verdict(
    out: _Verdicts,
    scan: SupportScan,
    rows: StackedRows,
    rows_of: np.ndarray,
    tol: Tolerances,
    total: int,
    time_budget: float | None,
) -> Check:
    """The verdict of a scan (whole or stopped by the time budget), its counts in the evidence."""
    out.evidence["supports_without_full_rank"] = scan.n_inf
    out.evidence["borderline_supports"] = scan.borderline
    if scan.stopped_after is not None:
        out.evidence["stopped_by_time_budget"] = {
            "time_budget_seconds": time_budget,
            "supports_checked": scan.stopped_after,
            "supports": total,
        }
    if scan.infinite is not None:
        return _infinite_verdict(out, scan, rows_of, total, tol)
    if scan.borderline:
        return out.check(Code.BORDERLINE, math.nan, None, {"count": scan.borderline})
    return _worst_verdict(out, scan, rows, rows_of, tol)


def _start(
    system: System,
    ranks: System,
    mode: str,
    k: int,
    tau: int,
    items: int,
    total: int | None,
    budget: Budget,
    tol: Tolerances,
) -> _Verdicts:
    """The call's verdict maker, with the evidence known before any computation."""
    evidence: dict[str, Any] = {
        "method_detail": (
            "every support enumerated, states in balanced power-of-two units; rho from the "
            "QR-whitened stacked observability matrix where the support's whitened Gramian "
            "passes a Cholesky screening with margin 2^-10, else from a Householder QR of "
            "O_Sbar with its rows sorted by size; every rank decided with the rows and columns "
            "scaled by powers of two to unit size; worst support recomputed by that QR"
        ),
        "definition": "rho(S) = || O_Sbar (O_Sbar^T O_Sbar)^-1 O_S^T ||_inf (largest row sum)",
        "supports": total,
        "budget": budget.to_dict(),
    }
    if total is None:
        evidence["supports_log10"] = log10_comb(items, k)
    tol_out = {"irrepresentable_rtol": tol.irrepresentable_rtol, **tol.to_dict()}
    return _Verdicts(system, ranks, mode, k, tau, evidence, tol_out)


def _decided_by_size(
    out: _Verdicts, items: int, total: int | None, max_sets: int, tol: Tolerances
) -> Check | None:
    """The verdict when the support size alone decides it (none, too many, all), or None."""
    k = out.k
    if k == 0:
        return _without_attack(out, tol)
    if k > items:
        every = tuple(range(items)) if items <= _LISTED else None
        facts: dict[str, Any] = {"k": k, "items": items, "noun": out.noun}
        return out.check(Code.SUPPORT_TOO_LARGE, math.inf, every, facts)
    if total is None:
        digits = log10_comb(items, k)
        # exact where it has few digits (a power of ten rounded down read C(20, 3) as 1,139)
        count: float = math.comb(items, k) if digits < 300 else 10 ** min(digits, 308)
        facts = {"items": items, "k": k, "count": count, "max_sets": max_sets}
        return out.check(Code.TOO_MANY_SUPPORTS, math.nan, None, facts)
    if k == items:
        every = tuple(range(items))
        facts = {"items": items, "noun": out.noun}
        return out.check(Code.ALL_ATTACKED, math.inf, every, facts, witness=out.rank_witness(every))
    return None


def _without_attack(out: _Verdicts, tol: Tolerances) -> Check:
    """Support size 0: fails (rho inf) when O_tau is rank deficient, else holds with rho 0."""
    system, tau = out.system, out.tau
    n, steps = system.n, min(out.tau, system.n)
    sc0 = staircase(out.ranks.A, out.ranks.C, max_steps=steps, tolerances=tol)
    if sc0.rank < n and not sc0.problem:
        O = system.observability_matrix(steps)
        doubt = _exact_doubt(system, range(system.p * steps), steps, out.evidence, O, tol)
        if doubt is None:
            facts: dict[str, Any] = {"tau": tau, "rank": sc0.rank, "n": n}
            return out.check(Code.NO_ATTACK_RANK_DEFICIENT, math.inf, (), facts)
        if doubt:
            facts = {"tau": tau, "doubt": messages.doubt(doubt)}
            return out.check(Code.O_TAU_DOUBT, math.nan, None, facts)
    return out.check(Code.NO_ATTACK, 0.0, (), {}, margin=1.0)


def _over_budget(out: _Verdicts, plan: ScanPlan, budget: Budget, total: int) -> Check | None:
    """Record the cost estimate; the inconclusive verdict when it exceeds the budget, or None."""
    n, p, tau = out.system.n, out.system.p, out.tau
    out.evidence["estimate"] = {
        "bytes": plan.nbytes,
        "flops": plan.flops,
        "bytes_per_support": plan.per_support,
    }
    refusal = budget.check(
        f"the irrepresentable enumeration ({format_count(total)} supports of {plan.rows:,} rows "
        f"of the {p * tau:,} x {n} matrix O_tau, horizon {tau:,})",
        nbytes=plan.nbytes,
        flops=plan.flops,
    )
    if refusal is None:
        return None
    facts = {"refusal": refusal, "longer_than_n": tau > n}
    return out.check(Code.OVER_BUDGET, math.nan, None, facts)


def _rows_of_items(p: int, tau: int, mode: str) -> np.ndarray:
    """Rows of O_tau of each item: a sensor's tau rows (block) or one entry (entrywise)."""
    if mode == "block":
        return np.arange(tau, dtype=np.int64)[None, :] * p + np.arange(p, dtype=np.int64)[:, None]
    return np.arange(p * tau, dtype=np.int64)[:, None]


def _rank_deficient(out: _Verdicts, rows: StackedRows, tol: Tolerances) -> Check | None:
    """The verdict when O_tau's rank is below n or undecided (so is every O_Sbar's), or None."""
    system, tau = out.system, out.tau
    n = system.n
    sc = staircase(out.ranks.A, out.ranks.C, max_steps=tau, tolerances=tol)
    out.evidence["rank_O_tau"] = sc.rank
    if sc.rank >= n and not sc.problem:
        return None
    if sc.problem:
        return out.check(Code.RANK_UNDECIDED, math.nan, None, {"problem": sc.problem})
    steps = min(tau, n)
    kept = range(system.p * steps)
    doubt = _exact_doubt(system, kept, steps, out.evidence, rows.O[: system.p * steps], tol)
    if doubt:
        facts: dict[str, Any] = {"tau": tau, "doubt": messages.doubt(doubt)}
        return out.check(Code.O_TAU_DOUBT, math.nan, None, facts)
    if doubt is not None:  # full rank exactly, and clearly so in floating point
        out.evidence["rank_O_tau"] = n
        return None
    first = tuple(range(out.k))
    facts = {"tau": tau, "rank": sc.rank, "n": n, "label": out.label(first)}
    return out.check(
        Code.O_TAU_RANK_DEFICIENT, math.inf, first, facts, witness=out.rank_witness(first)
    )


def _infinite_verdict(
    out: _Verdicts, scan: SupportScan, rows_of: np.ndarray, total: int, tol: Tolerances
) -> Check:
    """Fails on the first support whose O_Sbar is rank deficient, unless the exact data doubt it."""
    infinite = scan.infinite
    assert infinite is not None
    kept = np.setdiff1d(np.arange(out.system.p * out.tau), rows_of[list(infinite)].ravel())
    doubt = _exact_doubt(
        out.system, kept, out.tau, out.evidence, None, tol, smallest=scan.infinite_smallest
    )
    label = out.label(infinite)
    if doubt:
        facts: dict[str, Any] = {"label": label, "doubt": messages.doubt(doubt)}
        return out.check(Code.SUPPORT_DOUBT, math.nan, None, facts)
    checked = total if scan.stopped_after is None else scan.stopped_after
    facts = {"count": scan.n_inf, "checked": checked, "total": total, "label": label}
    return out.check(
        Code.SUPPORT_RANK_DEFICIENT, math.inf, infinite, facts, witness=out.rank_witness(infinite)
    )


def _worst_verdict(
    out: _Verdicts, scan: SupportScan, rows: StackedRows, rows_of: np.ndarray, tol: Tolerances
) -> Check:
    """The worst rho recomputed from the rows of O_tau, then compared with 1 within the
    tolerance band."""
    worst, support = scan.worst, scan.worst_support
    assert support is not None
    inside = rows_of[list(support)].reshape(1, -1)
    direct = float(support_rho(rows, inside, tol)[0][0])
    imprecise = _imprecise(out, scan)
    kappa = sensor_units_condition(rows, inside)
    rel = abs(direct - worst) / max(1.0, abs(worst))
    # the scan's value is within rel of the QR's, whose rounding reaches rho amplified by at
    # most about O_Sbar's condition number (normwise backward stability of Householder QR)
    estimate = rel + float(rho_error(rows.O.shape[0] - inside.shape[1], rows.O.shape[1], kappa))
    out.evidence["worst_support_recomputed"] = direct
    out.evidence["recompute_relative_difference"] = rel
    out.evidence["worst_support_condition"] = kappa
    out.evidence["value_relative_error_estimate"] = estimate
    label = out.label(support)
    if not math.isfinite(direct) or rel > 1e-6:
        facts: dict[str, Any] = {"worst": worst, "label": label, "direct": direct}
        return out.check(Code.RECOMPUTE_MISMATCH, worst, support, facts)
    margin = 1.0 - worst
    band = tol.irrepresentable_rtol
    if abs(margin) > band and estimate * abs(worst) >= abs(margin):
        facts = {"worst": worst, "label": label, "estimate": estimate, "kappa": kappa}
        return out.check(Code.NOT_TOLD_FROM_ONE, worst, support, facts, margin=margin)
    named = {"label": label, "accuracy": (estimate, kappa) if estimate > band else None}
    if worst < 1.0 - band and imprecise is not None:
        return out.check(Code.IMPRECISE_SUPPORTS, worst, support, {**named, "worst": worst,
                         **imprecise}, margin=margin)  # fmt: skip
    if worst < 1.0 - band:
        facts = {**named, "worst": worst, "k": out.k, "counted": out.counted(out.k)}
        return out.check(Code.BELOW_ONE, worst, support, facts, margin=margin)
    if worst > 1.0 + band:
        stopped = scan.stopped_after
        lower = stopped is not None or imprecise is not None
        return out.check(
            Code.ABOVE_ONE,
            worst,
            support,
            {**named, "worst": worst, "stopped": stopped, "imprecise": imprecise},
            margin=margin,
            witness={"support": list(support), "support_names": out.names(support), "value": worst},
            extra={"value_is_lower_bound": True} if lower else None,
        )
    exact = _exact_rho(out.system, out.tau, rows_of[list(support)].ravel())
    if exact is not None:
        out.evidence["worst_support_exact_value"] = str(exact)
    if exact is not None and exact >= 1:
        return out.check(
            Code.EXACTLY_AT_LEAST_ONE,
            worst,
            support,
            {**named, "exact": exact, "imprecise": imprecise},
            margin=margin,
            witness={
                "support": list(support),
                "support_names": out.names(support),
                "value": float(exact),
                "exact_value": str(exact),
            },
            extra={"value_is_lower_bound": True} if imprecise is not None else None,
        )
    facts = {**named, "worst": worst, "band": band, "exact": exact}
    return out.check(Code.WITHIN_BAND, worst, support, facts, margin=margin)


def _imprecise(out: _Verdicts, scan: SupportScan) -> dict[str, Any] | None:
    """Where some support's rho was computed too imprecisely (an ill-conditioned O_Sbar) for
    the worst to be known, the facts (``count``, ``label``, ``value``, ``error``: the one
    whose true value could be largest), also in the evidence; None where none could exceed
    the worst."""
    if not scan.imprecise:
        return None
    out.evidence["imprecise_supports"] = scan.imprecise
    others = [e for e in scan.imprecise_top if e[1] != scan.worst_support]
    if not others or not others[0][0] > scan.worst:
        return None
    _, support, error = others[0]
    out.evidence["imprecise_support"] = {
        "support": list(support),
        "support_names": out.names(support),
        "relative_error_estimate": error,
    }
    return {"count": scan.imprecise, "imprecise_label": out.label(support), "error": error}


def _exact_rho(system: System, tau: int, inside: np.ndarray) -> Fraction | None:
    """rho(S) = || O_Sbar (O_Sbar' O_Sbar)^-1 O_S' ||_inf in rational arithmetic from the
    floats of A and C (the rows ``inside`` of O_tau form S), or None when O_tau is beyond
    ``EXACT_RHO_ENTRIES`` entries or its exact bits, or O_Sbar lacks full column rank."""
    from ..numerics.exact_powers import exact_observability_matrix
    from ..numerics.rational import product, solve

    n = system.n
    if system.p * tau * n > EXACT_RHO_ENTRIES or n == 0:
        return None
    exact = exact_observability_matrix(system.A, system.C, tau, max_total_bits=1e6)
    if exact is None:
        return None
    O = exact.to_fractions()
    chosen = {int(i) for i in inside}
    O_S = [row for i, row in enumerate(O) if i in chosen]
    O_Sbar = [row for i, row in enumerate(O) if i not in chosen]
    gram = product([list(col) for col in zip(*O_Sbar)], O_Sbar)
    columns = []
    for row in O_S:
        x = solve(gram, list(row))
        if x is None:
            return None
        columns.append(x)
    M = product(O_Sbar, [list(r) for r in zip(*columns)]) if columns else []
    return max((sum((abs(v) for v in r), Fraction(0)) for r in M), default=Fraction(0))


#: the largest O_tau (entries) whose worst support is recomputed exactly near 1
EXACT_RHO_ENTRIES = 2_000


def _exact_doubt(
    system: System,
    rows: Any,
    steps: int,
    evidence: dict[str, Any],
    O: np.ndarray | None,
    tol: Tolerances,
    *,
    smallest: float | None = None,
) -> dict[str, Any] | None:
    """Why a floating-point rank deficiency of some rows of O_steps is not trusted.

    The rows are taken with the data as exact rationals: full column rank
    there (modulo a prime, a proof) means the deficiency hinged on digits
    below the data's precision.  An exact kernel vector confirms it; beyond
    the exact budgets the floating-point decision stands.  The claim that the
    rows are within the precision of their data of a rank deficient matrix is
    made only with their smallest singular value, the rows and columns scaled
    by powers of two to unit size, within the rank tolerance band (``smallest``,
    or measured on ``O``'s rows); where it is clearly above, the exact rank
    stands and "" is returned.

    Returns
    -------
    dict or None
        None where the deficiency stands (confirmed exactly or beyond the
        budgets), an empty dict where the rows have full rank (exactly, and
        clearly in floating point), else the facts of the doubt (its words:
        ``irrepresentable_messages.doubt``).
    """
    exact = exact_stacked_rank(system.A, system.C, rows, steps)
    evidence["exact_rank_check"] = exact.to_dict()
    if exact.state is not Observability.OBSERVABLE:
        return None
    if smallest is None:
        assert O is not None
        smallest = _scaled_smallest(O[np.asarray(list(rows), dtype=np.int64)])
    m, n = len(rows), system.n
    if not math.isfinite(smallest):
        return {"n": n, "overflow": True}
    rtol = tol.rtol(m, n)
    band = tol.borderline_factor * rtol
    evidence["exact_rank_check"]["scaled_smallest_singular_value"] = smallest
    if smallest > band:
        return {}
    return {"n": n, "smallest": smallest, "rtol": rtol, "band": band}


def _scaled_smallest(rows: np.ndarray) -> float:
    """sigma_min / sigma_max of a matrix with rows and columns scaled by powers of two to unit
    size (0 when it has fewer rows than columns)."""
    from ..numerics.exact import pow2_row_scaling

    m, n = rows.shape
    if m < n or n == 0:
        return 0.0
    if not np.all(np.isfinite(rows)):
        return math.nan
    scaled = pow2_row_scaling(rows)[:, None] * rows
    scaled = scaled * pow2_row_scaling(scaled.T)[None, :]
    s = np.linalg.svd(scaled, compute_uv=False)
    return float(s[-1] / s[0]) if s[0] > 0 else 0.0
