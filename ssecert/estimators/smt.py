"""An exact decoder in the manner of Imhotep-SMT (Shoukry et al., 2017).

Y. Shoukry, P. Nuzzo, A. Puggelli, A. L. Sangiovanni-Vincentelli, S. A.
Seshia and P. Tabuada, "Secure state estimation for cyber-physical systems
under sensor attacks: a satisfiability modulo theory approach", IEEE Trans.
Autom. Control 62(10):4917-4932, 2017; its public tool nesl/Imhotep-smt
(``ImhotepSMT/ImhotepSMT.m``), the baseline of the Lasso paper's Figs. 1-2.

A SAT solver proposes attack supports: one Boolean b_i per sensor, at most s
true.  A theory solver fits x by least squares to the sensors the proposal
calls clean and refutes the proposal when the fit's residual exceeds a
tolerance, adding a conflict clause (at least one sensor of a conflicting
set is attacked) that the SAT solver must respect from then on.  The first
proposal that passes is the answer; when the clauses leave no proposal, no
support of at most s sensors explains y within the tolerance.

Needs the optional z3-solver package (``pip install 'ssecert[smt]'``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..base.validation import as_float_option, as_int_option, as_real_matrix, describe
from .decoders import _as_flag, _as_measurements, _as_sensing_matrix
from .support_decoders import _as_sensor_map

__all__ = ["SMTSolution", "smt_decoder"]

DEFAULT_ATOL = 1e-5  # Imhotep-SMT's ``tolerance``
DEFAULT_RTOL = 1e-9
DEFAULT_MAX_THEORY_CALLS = 100_000
STATUSES = ("sat", "unsat", "budget")


def _import_z3() -> Any:
    try:
        import z3
    except ImportError as error:  # pragma: no cover - exercised where z3 is missing
        raise ImportError(
            "smt_decoder needs the z3-solver package, an optional dependency of ssecert: "
            "pip install 'ssecert[smt]' (or pip install z3-solver)"
        ) from error
    return z3


@dataclass(frozen=True)
class SMTSolution:
    """Result of ``smt_decoder``.

    Attributes
    ----------
    x : ndarray, shape (n,)
        Least-squares state estimate from the sensors outside ``support``
        (minimum-norm when they do not determine x); NaN when no support was
        found.
    support : tuple of int or None
        Sensors declared attacked, sorted; None when no support was found.
    a : ndarray, shape (m,)
        Attack estimate ``y - M x`` on the rows of ``support``, zero
        elsewhere; NaN when no support was found.
    status : str
        "sat": ``support`` passed the check; "unsat": the conflict clauses
        exclude every support of at most s sensors (no s-sparse attack
        explains y within the tolerance: more than s sensors attacked, or
        noise above it); "budget": ``max_theory_calls`` proposals were
        refuted first.
    residual : float
        The check's slack of ``support``: the sum over the kept sensors i of
        ||y_i - M_i x|| (inf when none was found).
    threshold : float
        What the slack was compared with: atol + rtol ||y|| plus the noise
        bounds of the kept sensors.
    unique : bool
        Whether the kept rows have full column rank (x determined).
    theory_calls : int
        Supports proposed by the SAT solver and checked.
    conflicts : tuple of tuple of int
        The learnt clauses, each a set of sensors not all clean.
    atol : float
        Absolute residual tolerance used.
    rtol : float
        Relative residual tolerance used.
    noise_bound : ndarray, shape (q,)
        Bound on each sensor's noise norm used.
    """

    x: np.ndarray
    support: tuple[int, ...] | None
    a: np.ndarray
    status: str
    residual: float
    threshold: float
    unique: bool
    theory_calls: int
    conflicts: tuple[tuple[int, ...], ...]
    atol: float
    rtol: float
    noise_bound: np.ndarray


def _as_noise_bound(value: Any, q: int) -> np.ndarray:
    if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
        value, (bool, np.bool_)
    ):
        bound = as_float_option(value, "noise_bound", min_value=0.0)
        return np.full(q, bound)
    if value is None or isinstance(value, (str, bytes, bool, np.bool_)):
        raise TypeError(
            f"noise_bound must be a number or one number per sensor, got {describe(value)}"
        )
    bounds = np.array(
        as_real_matrix(value, "noise_bound", ndim=1, shape=(q,), shape_hint="the number of sensors")
    )
    if np.any(bounds < 0):
        raise ValueError(f"noise_bound must be >= 0, got {float(bounds.min())}")
    return bounds


def smt_decoder(
    M: Any,
    y: Any,
    s: int,
    *,
    sensors_of_row: Sequence[int] | np.ndarray | None = None,
    noise_bound: float | Sequence[float] | np.ndarray = 0.0,
    atol: float = DEFAULT_ATOL,
    rtol: float = DEFAULT_RTOL,
    smallest: bool = False,
    max_theory_calls: int = DEFAULT_MAX_THEORY_CALLS,
) -> SMTSolution:
    """Secure state estimation by SAT-proposed supports and least-squares checks (Imhotep-SMT).

    Algorithm 1 of Shoukry et al. (2017) as its public tool implements it
    (nesl/Imhotep-smt, ``ImhotepSMT.m``, methods ``solve`` and
    ``writeConstriantsToSAT``), with z3 in place of SAT4J:

    1. the SAT solver proposes b with sum b_i <= s and every learnt clause
       satisfied (unsat: stop, no support is left);
    2. x = argmin ||y_K - M_K x|| over the kept sensors K = {i : b_i false};
       the slack of sensor i is ||y_i - M_i x||; the proposal passes when
       sum_K slack_i <= atol + rtol ||y|| + sum_K noise_bound_i;
    3. otherwise a conflict: the kept sensor of largest slack is joined,
       one at a time, by the kept sensors outside the s of largest slack,
       taken by increasing dim ker M_i (then by slack), until the joined
       set's least-squares residual exceeds atol + rtol ||y|| plus its
       noise bounds; the clause "at least one of them is attacked" is
       learnt (the whole of K when no prefix conflicts).

    Every clause is implied by the check (a set of clean sensors, each with
    noise within its bound, fits within the sum of its bounds), so with
    bounds that hold and data that an attack on at most s sensors explains,
    the attacked support is never excluded; with 2s-sparse observability
    and an exact fit, a passing support gives the true x (Lemma III.1).
    The tool's "agreeable" clauses (asserting the p - 2s sensors of least
    slack clean, Algorithm 5, sound under 3s-sparse observability only) are
    left out.  Under noise beyond ``noise_bound`` the check refutes the true
    support as well and the answer is "unsat" or a wrong support: the
    tolerance decides, as in the original (the Lasso paper's Figs. 1-2).
    The tool's check also leaves the largest-slack sensor's bound out of a
    conflict's threshold; here every sensor of the set counts.

    Parameters
    ----------
    M : array_like, shape (m, n)
        Sensing matrix (C, or the stacked O_tau).
    y : array_like, shape (m,)
        Measurements.
    s : int
        Largest number of attacked sensors, 0 <= s < number of sensors.
    sensors_of_row : sequence of int, optional
        Sensor (0-based) owning each row of ``M``; default, each row is its
        own sensor.  For O_tau with p sensors: ``numpy.tile(numpy.arange(p), tau)``.
    noise_bound : float or array_like of shape (q,), default 0
        Bound Psi_i on the 2-norm of sensor i's noise over its rows (the
        tool's ``noiseBound``); a number applies to every sensor.
    atol : float, default 1e-5
        Absolute tolerance of the checks (the tool's ``tolerance``).
    rtol : float, default 1e-9
        Tolerance relative to ||y|| added to ``atol``, for rounding errors
        of large data.
    smallest : bool, default False
        Raise the bound on sum b_i from 0 to s, so that the support found
        is a smallest one (the l0 decoder's answer up to ties); False
        proposes any support of at most s sensors, as the tool does.
    max_theory_calls : int, default 100000
        Largest number of proposals to check.

    Returns
    -------
    SMTSolution

    Raises
    ------
    ImportError
        If z3-solver is not installed.
    TypeError
        If an argument has the wrong kind.
    ValueError
        If ``y``, ``sensors_of_row`` or ``noise_bound`` does not match
        ``M``, ``s`` is out of range, a tolerance is negative or
        ``max_theory_calls < 1``.

    Examples
    --------
    >>> C = [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, -1.0], [2.0, 1.0]]
    >>> y = [1.0, 2.0, 3.0, 9.0, 4.0]            # x = (1, 2), sensor 3 attacked
    >>> sol = smt_decoder(C, y, 1)
    >>> sol.status, sol.support, sol.x.round(9).tolist()
    ('sat', (3,), [1.0, 2.0])
    >>> smt_decoder(C, [1.0, 2.0, 3.0, 9.0, 7.0], 1).status   # two sensors attacked
    'unsat'
    """
    z3 = _import_z3()
    M = _as_sensing_matrix(M)
    m, n = M.shape
    y = np.array(_as_measurements(y, m, batched=False))
    sensors, q = _as_sensor_map(sensors_of_row, m)
    s = as_int_option(s, "s", min_value=0, max_value=q - 1)
    bounds = _as_noise_bound(noise_bound, q)
    atol = as_float_option(atol, "atol", min_value=0.0)
    rtol = as_float_option(rtol, "rtol", min_value=0.0)
    smallest = _as_flag(smallest, "smallest")
    max_theory_calls = as_int_option(max_theory_calls, "max_theory_calls", min_value=1)

    rows_of = [np.flatnonzero(sensors == i) for i in range(q)]
    null_dim = np.array([n - np.linalg.matrix_rank(M[rows]) for rows in rows_of])
    base = atol + rtol * float(np.linalg.norm(y))

    def fit(kept: Sequence[int]) -> tuple[np.ndarray, np.ndarray, int]:
        rows = np.concatenate([rows_of[i] for i in kept])
        x, _, rank, _ = np.linalg.lstsq(M[rows], y[rows], rcond=None)
        return x, rows, int(rank)

    # a context of its own: z3's shared one keeps state between calls, and the proposals with it
    ctx = z3.Context()
    b = [z3.Bool(f"b{i}", ctx) for i in range(q)]
    solver = z3.Solver(ctx=ctx)
    solver.add(z3.AtMost(*b, s))
    # "at most k attacked" for k < s, switched on by an assumption, so learnt clauses stay
    levels = [z3.Bool(f"at_most_{k}", ctx) for k in range(s)]
    for k, level in enumerate(levels):
        solver.add(z3.Implies(level, z3.AtMost(*b, k)))
    ladder = list(range(s + 1)) if smallest else [s]
    conflicts: list[tuple[int, ...]] = []
    calls = 0
    over_budget = False
    for k in ladder:
        assumptions = [levels[k]] if k < s else []
        while True:
            if solver.check(*assumptions) != z3.sat:
                break  # no support of at most k sensors is left
            if calls >= max_theory_calls:
                over_budget = True
                break
            calls += 1
            model = solver.model()
            attacked = [i for i in range(q) if z3.is_true(model.eval(b[i], model_completion=True))]
            kept = [i for i in range(q) if i not in attacked]
            x, rows, rank = fit(kept)
            slack = np.array([np.linalg.norm(y[rows_of[i]] - M[rows_of[i]] @ x) for i in kept])
            threshold = base + float(bounds[kept].sum())
            if slack.sum() <= threshold:
                a = np.zeros(m)
                on = np.isin(sensors, attacked)
                a[on] = y[on] - M[on] @ x
                return SMTSolution(
                    x, tuple(attacked), a, "sat", float(slack.sum()), threshold, rank == n,
                    calls, tuple(conflicts), atol, rtol, bounds,
                )  # fmt: skip
            conflict = _conflict(kept, slack, s, null_dim, bounds, base, fit, M, y)
            conflicts.append(conflict)
            solver.add(z3.Or(*[b[i] for i in conflict]))
        if over_budget:
            break
    nan = np.full(n, np.nan)
    status = "budget" if over_budget else "unsat"
    return SMTSolution(
        nan, None, np.full(m, np.nan), status, np.inf, base, False, calls, tuple(conflicts),
        atol, rtol, bounds,
    )  # fmt: skip


def _conflict(
    kept: list[int],
    slack: np.ndarray,
    s: int,
    null_dim: np.ndarray,
    bounds: np.ndarray,
    base: float,
    fit: Any,
    M: np.ndarray,
    y: np.ndarray,
) -> tuple[int, ...]:
    """A set of kept sensors that cannot all be clean (the tool's linear search).

    The sensor of largest slack is joined, one at a time, by the kept
    sensors outside the max(s, 1) of largest slack, ordered by increasing
    dim ker M_i (stable, so by slack among equals), until their joint fit
    fails; the whole kept set when none does.
    """
    order = [kept[j] for j in np.argsort(slack, kind="stable")]
    worst = order[-1]
    low = order[: len(order) - max(s, 1)]
    low = [low[j] for j in np.argsort(null_dim[low], kind="stable")]
    chosen = [worst]
    for sensor in low:
        chosen.append(sensor)
        x, rows, _ = fit(chosen)
        if np.linalg.norm(y[rows] - M[rows] @ x) > base + float(bounds[chosen].sum()):
            return tuple(sorted(chosen))
    return tuple(sorted(kept))
