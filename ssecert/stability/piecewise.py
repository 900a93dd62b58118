"""A larger certified region of attraction: a piecewise-quadratic Lyapunov function.

The soft threshold splits the error state of the Lur'e model
(``ssecert.observers.lure``) into 3^m polyhedral regions, one per pattern
s in {-1, 0, 1}^m (channel i in the dead zone, |w_i| <= threshold, or
active with the sign s_i); on each the dynamics are affine,

    xi+ = A_s xi + b_s,   A_s = A + q B diag(|s|) Cw,   b_s = -q threshold B s.

With z = (xi, 1), each region carries its own quadratic function
V_s(xi) = z' P_s z (the dead zone's has no affine part, so V(0) = 0), and
with a ball of radius R and a level c = R^2 the LMIs (S-procedure
multipliers W >= 0 entrywise on the products of the regions' inequalities)
ask:

1. decrease: for every pair of regions (s, t) that one step can join inside
   the ball, V_t(xi+) <= V_s(xi) - alpha |xi|^2 (the dead zone to itself:
   A' P_0 A - P_0 <= -alpha I);
2. the level set stays in the ball: V_s(xi) > c on region s outside the ball;
3. the initial errors are in it: V_s(xi) <= c on region s for xi = (e, 0)
   with |e| <= r.

As matrices (the evidence's ``certificate``, in z = (xi / threshold, 1); G_s the rows
of region s's inequalities G_s z >= 0: (-c_i, 1) and (c_i, 1) for a channel in the dead
zone, (s_i c_i, -1) for an active one, c_i the rows of Cw; T_s = [[A_s, b_s], [0, 1]]
at threshold 1; W >= 0 zero but for its last row and column; Iq = diag(I, 0), E1 =
diag(0, 1); Z (e, 1) = (xi, 1) for xi = (e, 0), In and e1 alike for (e, 1)):

1. decrease, H = [G_s; G_t T_s; (0, 1)]: T_s' P_t T_s - P_s + alpha Iq + H' W H
   + sigma (c E1 - Iq) < 0;
2. outer, H = [G_s; (0, 1)]: P_s - c E1 - sigma (Iq - c E1) - H' W H > 0;
3. inner, H = [G_s; (0, 1)] Z: c e1 - Z' P_s Z - sigma (r^2 e1 - In) - H' W H > 0;

sigma >= 0 the ball's scalar; a transition or initial region left out has y >= 0 with
y' [G_s; G_t T_s] (or y' G_s Z) = (h, h_0), h_0 + box ||h||_1 < 0.

Then S = {|xi| < R : V_s(xi) <= c for a region s of xi} is invariant (by 1,
V_t(xi+) <= c, so by 2 xi+ is back in the ball) and V decreases along every
trajectory in it by alpha |xi|^2 while staying bounded below on the ball, so
the error converges to zero from every initial error with |e(0)| <= r and
a_hat(0) = 0.  The function may jump across region boundaries: every
region containing a point is covered, so the argument does not need it
continuous.  Pairs of regions that no step joins inside the ball's bounding
box are left out with a Farkas certificate of emptiness, checked in exact
arithmetic.

The problem is posed in units of the threshold (the dynamics scale with it),
solved with Clarabel (or the solver ``--solver`` names, through cvxpy:
``ssecert.stability._conic``), and nothing of the solver is trusted: every
LMI is recomputed in numpy from the returned matrices with the multipliers
clipped to be nonnegative, and must beat a rounding-error bound by the
factor ``clear``.  The model is symmetric (the soft threshold is odd), so the
functions of s and -s are tied, P_(-s) = J P_s J with J = diag(-I, 1), and
each LMI of a pair (-s, -t) is the one of (s, t) conjugated by J (sign
changes, exact in floating point): one of each is verified.

This certifies what a quadratic function cannot when shrink = 1 and the
plant has an eigenvalue at 1: there the observer's error falls only by a
constant amount per step far from the origin, and on a bounded ball the
S-procedure can still make every LMI strict.
"""

from __future__ import annotations

import copy
import itertools
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from fractions import Fraction
from functools import partial
from typing import Any, NamedTuple

import numpy as np

from ..budget import stage
from ..numerics.rational import fractions, product
from ..observers.lure import LureModel
from ..tolerances import EPS
from .outcomes import Region, RegionCode

__all__ = ["piecewise_region", "MAX_CHANNELS", "MAX_STATES"]

MAX_CHANNELS = 3  # 27 regions and at most 729 transitions (one LMI each)
MAX_STATES = 12
ALPHA = 1e-4  # decrease imposed, alpha |xi|^2, xi in thresholds
DELTA = 1e-7  # strictness imposed on every LMI
OUTER = 2.0  # the ball's radius R over the radius r of initial errors
LADDER = (3.0, 10.0, 30.0, 100.0, 300.0, 1000.0)  # radii r searched, in thresholds
MAX_ITER = 30  # interior-point iterations (a certificate that verifies takes 10 to 20)
SAMPLES = 64
STEPS = 5000
MAX_STEPS = 100_000  # the replay's longest run, in chunks of STEPS


class _Regions:
    """The soft threshold's regions of one model, in units of the threshold."""

    def __init__(self, model: LureModel) -> None:
        N, m, q = model.N, model.m, model.q
        self.signs = np.array(list(itertools.product((-1.0, 0.0, 1.0), repeat=m)))
        self.zero = (3**m - 1) // 2
        self.index = {tuple(s): k for k, s in enumerate(self.signs)}
        self.G: list[np.ndarray] = []
        self.T: list[np.ndarray] = []
        self._exact_model: LureModel | None = None
        self._exact_fractions: tuple[list[list[Fraction]], ...] | None = None
        self._exact_cache: dict[str, dict[int, list[list[Fraction]]]] = {"G": {}, "T": {}}
        for s in self.signs:
            rows = []
            for i, si in enumerate(s):
                c = model.Cw[i]
                if si == 0:
                    rows += [np.r_[-c, 1.0], np.r_[c, 1.0]]
                else:
                    rows.append(np.r_[si * c, -1.0])
            self.G.append(np.array(rows))
            T = np.zeros((N + 1, N + 1))
            T[:N, :N] = model.A + q * model.B @ np.diag(np.abs(s)) @ model.Cw
            T[:N, N] = -q * model.B @ s
            T[N, N] = 1.0
            self.T.append(T)

    def _exact_G(self, model: LureModel, k: int) -> list[list[Fraction]] | None:
        """The rows of G_k (threshold 1) from the model's exact Cw, or None beyond its budget."""
        data = self._exact_data(model)
        if data is None:
            return None
        if k not in self._exact_cache["G"]:
            Cw, rows = data[2], []
            for i, si in enumerate(self.signs[k]):
                if si == 0:
                    rows += [[-v for v in Cw[i]] + [Fraction(1)], [*Cw[i], Fraction(1)]]
                else:
                    rows.append([int(si) * v for v in Cw[i]] + [Fraction(-1)])
            self._exact_cache["G"][k] = rows
        return self._exact_cache["G"][k]

    def _exact_T(self, model: LureModel, k: int) -> list[list[Fraction]] | None:
        """T_k (threshold 1) from the model's exact A, B and Cw, or None beyond their budget."""
        data = self._exact_data(model)
        if data is None:
            return None
        if k not in self._exact_cache["T"]:
            A, B, Cw = data
            q, N, s = Fraction(model.q), model.N, self.signs[k]
            on = [i for i in range(model.m) if s[i] != 0]
            T = [[A[a][b] + q * sum((B[a][i] * Cw[i][b] for i in on), Fraction(0))
                  for b in range(N)] + [-q * sum((B[a][i] * int(s[i]) for i in on), Fraction(0))]
                 for a in range(N)]  # fmt: skip
            T.append([Fraction(0)] * N + [Fraction(1)])
            self._exact_cache["T"][k] = T
        return self._exact_cache["T"][k]

    def exact_combination(
        self, model: LureModel, k: int, j: int, y: list[Fraction]
    ) -> list[Fraction] | None:
        """y' [G_k; G_j T_k] (thresholds 1) exactly, from the model's exact matrices (the
        spec's data), as y_1' G_k + (y_2' G_j) T_k; None when those are beyond their budget."""
        Gk, Gj, T = self._exact_G(model, k), self._exact_G(model, j), self._exact_T(model, k)
        if Gk is None or Gj is None or T is None:
            return None
        head, tail = [y[: len(Gk)]], [y[len(Gk) :]]
        return [
            a + b
            for a, b in zip(product(head, Gk)[0], product(product(tail, Gj), T)[0], strict=True)
        ]

    def exact_inner_combination(
        self, model: LureModel, k: int, y: list[Fraction]
    ) -> list[Fraction] | None:
        """y' G_k Z exactly (Z: the initial states (e, a_hat = 0), ``_inner_map``), or None."""
        Gk = self._exact_G(model, k)
        if Gk is None:
            return None
        n, N = model.n_e, model.N
        return product([y], [row[:n] + [row[N]] for row in Gk])[0]

    def _exact_data(self, model: LureModel) -> tuple[list[list[Fraction]], ...] | None:
        """The model's exact A, B and Cw as fractions (converted once per model), or None."""
        if self._exact_model is not model:
            exact = model.exact()
            self._exact_model = model
            self._exact_cache = {"G": {}, "T": {}}
            self._exact_fractions = (
                None if exact is None else tuple(exact.fractions(k) for k in ("A", "B", "Cw"))
            )
        return self._exact_fractions

    def mirror(self, k: int) -> int:
        return self.index[tuple(-self.signs[k])]

    def representatives(self) -> list[int]:
        """One region of each pair (s, -s); the dead zone is its own."""
        return [k for k in range(len(self.signs)) if k <= self.mirror(k)]


def piecewise_region(
    model: LureModel, *, seed: int = 0, floor: float = 0.0, clear: float = 100.0
) -> Region:
    """The largest radius of initial errors (a_hat(0) = 0) from which a verified
    piecewise-quadratic Lyapunov function proves convergence without attack.

    Searches the radii of ``LADDER`` (in thresholds) by bisection: a radius
    that verifies sends the search up, one that does not (the LMIs grow
    harder as the ball grows) sends it down; radii not above ``floor`` (the
    radius already certified otherwise) are not tried.  Returns radius 0 with
    the reason's code when none verifies or the model is out of reach.
    """
    from ..solvers import solver_name

    key = _key(model, seed, floor, clear) + solver_name().encode()  # solvers find differently
    if key in _CACHE:
        return copy.deepcopy(_CACHE[key])
    found = _search(model, seed, floor, clear)
    if len(_CACHE) >= 32:
        _CACHE.pop(next(iter(_CACHE)))
    _CACHE[key] = found
    return copy.deepcopy(found)


_CACHE: dict[bytes, Region] = {}  # the search is a pure function of these

# y -> y' H in exact arithmetic (None beyond the exact data's budget)
Combination = Callable[[list[Fraction]], list[Fraction] | None]


def _key(model: LureModel, *numbers: float) -> bytes:
    parts = [model.A, model.B, model.Cw, np.array([model.q, model.threshold, *numbers])]
    return b"|".join(
        np.ascontiguousarray(p, dtype=float).tobytes() + bytes(str(p.shape), "ascii") for p in parts
    )


def _search(model: LureModel, seed: int, floor: float, clear: float) -> Region:
    """``piecewise_region`` without its cache."""
    if model.m == 0 or model.threshold <= 0:
        return Region.none(RegionCode.NO_DEAD_ZONE, piecewise=True)
    if model.m > MAX_CHANNELS or model.N > MAX_STATES:
        return Region.none(RegionCode.NOT_ATTEMPTED, channels=model.m, states=model.N)
    lam = model.threshold
    with np.errstate(over="ignore"):
        if not np.isfinite((np.float64(OUTER * LADDER[-1]) * lam) ** 2 * (model.N + 1)):
            return Region.none(RegionCode.BALL_OUT_OF_RANGE)
    ladder = [r for r in LADDER if r * lam > floor]
    if not ladder:
        return Region.none(RegionCode.WITHIN_FLOOR, floor=floor)
    regions = _Regions(model)
    with np.errstate(all="ignore"):
        finite = all(np.all(np.isfinite(T)) for T in regions.T) and all(
            np.all(np.isfinite(G @ T)) for G in regions.G for T in regions.T
        )
    if not finite:
        return Region.none(RegionCode.MAPS_OUT_OF_RANGE)
    unit = replace(model, threshold=1.0)  # the same dynamics, in units of the threshold
    # emptiness in the largest box holds in every smaller one
    empty_pairs = _empty_pairs(regions, unit, OUTER * ladder[-1])
    inner = regions.representatives()
    inner_found = _empty_in_boxes(
        [
            (
                regions.G[k] @ _inner_map(model),
                ladder[-1],
                partial(regions.exact_inner_combination, unit, k),
            )
            for k in inner
        ]
    )
    empty_inner = {k: y for k, y in zip(inner, inner_found, strict=True) if y is not None}
    attempts: list[dict[str, Any]] = []
    best: _Attempt | None = None
    lo, hi = -1, len(ladder)  # ladder[lo] verified, ladder[hi] did not
    while hi - lo > 1:
        mid = (lo + hi) // 2
        with stage(f"piecewise-quadratic LMIs, radius {ladder[mid] * lam:.4g}"):
            found = _attempt(model, regions, ladder[mid], OUTER * ladder[mid], clear,
                             empty_pairs, empty_inner)  # fmt: skip
        attempts.append({"radius": ladder[mid] * lam, **found.record})
        if found.ok:
            best, lo = found, mid
        else:
            hi = mid
    if best is None:
        return Region.none(RegionCode.NO_PIECEWISE_FUNCTION, {"attempts": attempts})
    r = ladder[lo]
    replay = _replay(model, r * lam, OUTER * r * lam, seed)
    if not replay["confirmed"]:
        return Region.none(
            RegionCode.PIECEWISE_REPLAY_FAILED, {"attempts": attempts, "replay": replay}
        )
    evidence = {
        "ball": OUTER * r * lam,
        "method": "piecewise-quadratic Lyapunov function over the soft threshold's "
        f"{3**model.m} regions (S-procedure LMIs, {_solved_by(best)}), verified in numpy",
        "transitions": best.transitions,
        "transitions_empty": best.empty,
        "margin": best.margin,
        "error_bound": best.bound,
        "attempts": attempts,
        "replay": replay,
        "certificate": _certificate(
            regions, best, r, empty_pairs, empty_inner, OUTER * ladder[-1], ladder[-1]
        ),
    }
    return Region(r * lam * (1 - 1e-12), RegionCode.PIECEWISE_CERTIFIED, evidence=evidence)


def _certificate(
    regions: _Regions,
    best: _Attempt,
    r: float,
    empty_pairs: Mapping[tuple[int, int], list[Fraction]],
    empty_inner: Mapping[int, list[Fraction]],
    box: float,
    inner_box: float,
) -> dict[str, Any]:
    """The verified certificate, everything needed to check it again (the module docstring's
    inequalities, in units of the threshold): the functions P_s of every region, and for
    every region s of a pair (s, -s) listed first (``representatives``; the other's are the
    same conjugated by J = diag(-I, 1)) each LMI's multiplier and ball scalar, and the Farkas
    certificates of the transitions and initial regions left out as empty."""

    def floats(y: list[Fraction]) -> list[float]:
        return [float(v) for v in y]  # (dyadic: the floats the LP returned, exactly)

    return {
        "coordinates": "z = (xi / threshold, 1): the LMIs are posed in units of the threshold",
        "alpha": ALPHA,
        "radius": r,
        "ball": OUTER * r,
        "patterns": regions.signs.astype(int),
        "functions": best.functions,
        "lmis": [
            {
                "kind": item.kind,
                "region": item.region,
                "to": item.to,
                # W is zero but for its last row and column (``_multiplier_mask``)
                "multiplier_last_row": np.asarray(item.multiplier)[-1],
                "scalar": float(item.scalar),
            }
            for item in best.lmis
        ],
        "empty_transitions": [
            {"region": k, "to": j, "farkas": floats(y), "box": box}
            for (k, j), y in sorted(empty_pairs.items())
        ],
        "empty_initial": [
            {"region": k, "farkas": floats(y), "box": inner_box}
            for k, y in sorted(empty_inner.items())
        ],
    }


def _solved_by(attempt: _Attempt) -> str:
    """The solver of a verified attempt, as the method names it."""
    name = attempt.record["solver"]
    return "Clarabel" if name == "CLARABEL" else f"{name} through cvxpy"


class _RegionLMI(NamedTuple):
    """One S-procedure LMI of a piecewise certificate, as solved (or as posed: then the
    multiplier and scalar are the solver's variable handles)."""

    kind: str  # "outer" (the level set in the ball), "inner" (the initial ball), "decrease"
    region: int  # k: the region the state is in
    to: int  # j: the region it moves to ("decrease"; k otherwise)
    H: np.ndarray  # the rows of the region constraints the multiplier weighs
    multiplier: Any  # W >= 0 entrywise (a block handle while posed)
    scalar: Any  # the ball's S-procedure scalar (a handle while posed)


@dataclass(frozen=True)
class _Attempt:
    """What one radius's LMIs gave: ``ok`` when they were solved and verified; ``record`` is
    the attempt's evidence row (status, margin, error bound, seconds, the problem)."""

    ok: bool
    record: dict[str, Any]
    transitions: int = 0
    empty: int = 0  # transitions and initial regions proved empty, without an LMI
    margin: float = math.nan
    bound: float = math.nan
    functions: list[np.ndarray] = field(default_factory=list)  # the verified P_s
    lmis: list[_RegionLMI] = field(default_factory=list)


def _attempt(
    model: LureModel,
    regions: _Regions,
    r: float,
    R: float,
    clear: float,
    empty_pairs: Mapping[tuple[int, int], list[Fraction]],
    empty_inner: Mapping[int, list[Fraction]],
) -> _Attempt:
    """Pose, solve and verify the LMIs for initial errors of radius r inside the ball R
    (both in thresholds)."""
    from ._conic import LMIProblem

    start = time.perf_counter()
    N, n = model.N, model.n_e
    K = len(regions.signs)
    one = np.r_[np.zeros(N), 1.0]
    Iq = np.diag(np.r_[np.ones(N), 0.0])
    E1 = np.diag(np.r_[np.zeros(N), 1.0])
    Z = _inner_map(model)
    In = np.diag(np.r_[np.ones(n), 0.0])
    e1 = np.diag(np.r_[np.zeros(n), 1.0])
    J = np.diag(np.r_[-np.ones(N), 1.0])
    E = np.eye(N, N + 1)
    level = R**2

    lp = LMIProblem()
    P0 = lp.block(N)
    reps = regions.representatives()
    handle = {k: lp.block(N + 1) for k in reps if k != regions.zero}

    def V(k: int, F: np.ndarray, sign: float) -> tuple[int, np.ndarray, float]:
        """The term sign F' P_k F, through the variable that holds P_k."""
        if k == regions.zero:
            return P0, E @ F, sign
        if k in handle:
            return handle[k], F, sign
        return handle[regions.mirror(k)], J @ F, sign

    lp.lmi(-ALPHA * np.eye(N), [(P0, np.eye(N), 1.0), (P0, model.A, -1.0)], delta=DELTA)
    lmis: list[_RegionLMI] = []
    empty = 0
    for k in reps:
        G = np.vstack([regions.G[k], one])
        U, kap = lp.block(len(G), nonneg=True, mask=_multiplier_mask(len(G))), lp.scalar()
        lp.lmi(
            -level * E1,
            [V(k, np.eye(N + 1), 1.0), (U, G, -1.0)],
            [(kap, Iq - level * E1, -1.0)],
            delta=DELTA,
        )
        lmis.append(_RegionLMI("outer", k, k, G, U, kap))
        GZ = G @ Z
        if k not in empty_inner:
            U2, kap2 = lp.block(len(G), nonneg=True, mask=_multiplier_mask(len(G))), lp.scalar()
            lp.lmi(
                level * e1,
                [V(k, Z, -1.0), (U2, GZ, -1.0)],
                [(kap2, r**2 * e1 - In, -1.0)],
                delta=DELTA,
            )
            lmis.append(_RegionLMI("inner", k, k, GZ, U2, kap2))
        else:
            empty += 1
        T = regions.T[k]
        for j in range(K):
            if k == regions.zero and j == regions.zero:
                continue
            if (k, j) in empty_pairs:
                empty += 1
                continue
            H = np.vstack([regions.G[k], regions.G[j] @ T, one])
            W, nu = lp.block(len(H), nonneg=True, mask=_multiplier_mask(len(H))), lp.scalar()
            lp.lmi(
                -ALPHA * Iq,
                [V(j, T, -1.0), V(k, np.eye(N + 1), 1.0), (W, H, -1.0)],
                [(nu, level * E1 - Iq, -1.0)],
                delta=DELTA,
            )
            lmis.append(_RegionLMI("decrease", k, j, H, W, nu))
    x, info = lp.solve(max_iter=MAX_ITER)
    record: dict[str, Any] = {
        "transitions": sum(1 for item in lmis if item.kind == "decrease"),
        "solver": info["solver"],
        "status": info["status"],
    }
    if x is None:
        record["seconds"] = round(time.perf_counter() - start, 3)
        return _Attempt(False, record)
    values: list[np.ndarray] = []
    for k in range(K):
        if k == regions.zero:
            values.append(E.T @ lp.matrix(x, P0) @ E)
        elif k in handle:
            values.append(lp.matrix(x, handle[k]))
        else:
            values.append(J @ lp.matrix(x, handle[regions.mirror(k)]) @ J)
    solved = [
        item._replace(
            multiplier=np.maximum(lp.matrix(x, item.multiplier), 0.0),
            scalar=max(lp.value(x, item.scalar), 0.0),
        )
        for item in lmis
    ]
    margin, bound, problem_text = _verify(model, regions, values, solved, r, R, clear)
    record.update(
        margin=margin,
        error_bound=bound,
        verified=not problem_text,
        seconds=round(time.perf_counter() - start, 3),
    )
    if problem_text:
        record["problem"] = problem_text
        return _Attempt(False, record)
    return _Attempt(True, record, record["transitions"], empty, margin, bound, values, solved)


def _multiplier_mask(size: int) -> np.ndarray:
    """The S-procedure's multipliers: each inequality g_i(xi) >= 0 times the constant 1 (the
    last row of H); products of two inequalities certified no more on the examples tried and
    cost three times the variables."""
    mask = np.zeros((size, size), bool)
    mask[-1, :] = mask[:, -1] = True
    return mask


def _inner_map(model: LureModel) -> np.ndarray:
    """Z with (xi, 1) = Z (e, 1) for the initial states (e, a_hat = 0)."""
    N, n = model.N, model.n_e
    Z = np.zeros((N + 1, n + 1))
    Z[:n, :n] = np.eye(n)
    Z[N, n] = 1.0
    return Z


def _sym(M: np.ndarray) -> np.ndarray:
    return 0.5 * (M + M.T)


def _verify(
    model: LureModel,
    regions: _Regions,
    P: list[np.ndarray],
    lmis: list[_RegionLMI],
    r: float,
    R: float,
    clear: float,
) -> tuple[float, float, str]:
    """Recompute every LMI from the solver's matrices (multipliers clipped to >= 0):
    (smallest margin, largest error bound, the first problem or '')."""
    N, n = model.N, model.n_e
    level = R**2
    Iq = np.eye(N + 1)
    Iq[N, N] = 0.0
    E1 = np.zeros((N + 1, N + 1))
    E1[N, N] = 1.0
    if not all(np.all(np.isfinite(p)) for p in P):
        return math.nan, 0.0, "the solver returned non-finite matrices"
    P0 = P[regions.zero][:N, :N]
    dead = model.A.T @ P0 @ model.A - P0 + ALPHA * np.eye(N)
    worst = -float(np.linalg.eigvalsh(_sym(dead))[-1])
    top = max(float(np.abs(model.A).max()), 1.0)
    d = model.rounding  # the model's floats against the spec's exact data
    bound = 10 * N * EPS * (top**2 + 1) * float(np.abs(P0).max()) * N + _perturbation(
        model.A, P0, d
    )
    where = "the dead zone's decrease"
    if worst <= clear * bound:
        return worst, bound, f"{where}: margin {worst:.2e} not above {clear:g} x {bound:.2e}"
    for kind, k, j, H, W, s in lmis:
        if kind == "outer":
            M = P[k] - level * E1 - s * (Iq - level * E1) - H.T @ W @ H
            sign, terms = -1.0, [P[k], level * E1, s * (level + 1) * np.eye(N + 1)]
        elif kind == "inner":
            Z = np.zeros((N + 1, n + 1))
            Z[:n, :n] = np.eye(n)
            Z[N, n] = 1.0
            In = np.eye(n + 1)
            In[n, n] = 0.0
            e1 = np.zeros((n + 1, n + 1))
            e1[n, n] = 1.0
            M = level * e1 - Z.T @ P[k] @ Z - s * (r**2 * e1 - In) - H.T @ W @ H
            sign, terms = -1.0, [P[k], level * E1, s * (r**2 + 1) * np.eye(N + 1)]
        else:
            T = regions.T[k]
            M = T.T @ P[j] @ T - P[k] + ALPHA * Iq + H.T @ W @ H + s * (level * E1 - Iq)
            sign = 1.0
            terms = [np.abs(T).T @ np.abs(P[j]) @ np.abs(T), P[k], s * (level + 1) * np.eye(N + 1)]
        terms.append(np.abs(H).T @ W @ np.abs(H))
        size = M.shape[0] + H.shape[0]
        err = 10 * size * EPS * sum(float(np.abs(t).sum()) for t in terms)
        # G and T are formed from Cw and A + q B D Cw: each is within (1 + q ||B||) d of exact
        dT = (1.0 + model.q * float(np.linalg.norm(model.B, 2))) * d
        err += _perturbation(H, W, dT)
        if kind == "decrease":
            err += _perturbation(regions.T[k], P[j], dT)
        eig = np.linalg.eigvalsh(_sym(M))
        margin = float(-eig[-1]) if sign > 0 else float(eig[0])
        if margin < worst:
            worst, where = (
                margin,
                f"{kind} {regions.signs[k].astype(int).tolist()}"
                + (f" -> {regions.signs[j].astype(int).tolist()}" if kind == "decrease" else ""),
            )
        bound = max(bound, err)
        if margin <= clear * err:
            return worst, bound, f"{where}: margin {margin:.2e} not above {clear:g} x {err:.2e}"
    return worst, bound, ""


def _perturbation(X: np.ndarray, P: np.ndarray, d: float) -> float:
    """A bound on ||X'PX - Y'PY||_2 over every Y with ||Y - X||_2 <= d."""
    if d == 0:
        return 0.0
    return (2 * float(np.linalg.norm(X, 2)) + d) * d * float(np.linalg.norm(P, 2)) * (1 + 1e-12)


def _empty_in_box(
    H: np.ndarray, box: float, exact: Combination | None = None
) -> list[Fraction] | None:
    """A Farkas certificate that {x : H (x, 1) >= 0, |x_i| <= box} is empty, checked exactly:
    y >= 0 with y' h + box ||H_x' y||_1 < 0.  ``exact(y)`` gives y' H in exact arithmetic
    (from the spec's data) when the floats of H were rounded (products of matrices); None
    from it proves nothing.  None when the set is not proved empty."""
    return _empty_in_boxes([(H, box, exact)])[0]


def _empty_in_boxes(
    problems: Sequence[tuple[np.ndarray, float, Combination | None]],
) -> list[list[Fraction] | None]:
    """``_empty_in_box`` of each (H, box, exact), from one linear program: each set's
    problem (minimise y' h + box sum(u) with -u <= H_x' y <= u, y >= 0, sum(y) = 1) is a
    block of its own, so the sum of their objectives is least where each is, and each
    block's y is checked exactly on its own.  One program's tolerances serve every block,
    so a badly scaled block may come back less accurate, or fail the whole program: where
    the program fails, and for each block whose objective is negative (by more than
    ``_ZERO`` of its data) but whose y does not pass the exact check, the block's program
    is solved alone, as one per set would be."""
    if not problems:
        return []
    blocks = [_farkas_program(H, box) for H, box, _ in problems]
    solved = _solve_programs(blocks)
    out: list[list[Fraction] | None] = []
    for (H, box, exact), block, x in zip(problems, blocks, solved, strict=True):
        found, negative = _farkas_of(H, box, exact, block, x)
        if found is None and (x is None or negative):
            alone = _solve_programs([block])[0]
            found = _farkas_of(H, box, exact, block, alone)[0] if alone is not None else None
        out.append(found)
    return out


# a block whose objective is below 0 but whose y fails the exact check is solved alone; one
# whose objective is within this of 0, relative to its largest entry of H times (1 + box), is
# not (the sets that are not empty sit at 0, within about 1e-17 of it)
_ZERO = 1e-14


class _Program(NamedTuple):
    """One block of ``_empty_in_boxes``'s linear program."""

    cost: np.ndarray
    upper: np.ndarray  # A_ub (its b_ub is 0)
    equal: np.ndarray  # the row of sum(y) = 1


def _farkas_program(H: np.ndarray, box: float) -> _Program:
    rows, cols = H.shape
    Hx, h = H[:, :-1], H[:, -1]
    return _Program(
        np.r_[h, box * np.ones(cols - 1)],
        np.block([[Hx.T, -np.eye(cols - 1)], [-Hx.T, -np.eye(cols - 1)]]),
        np.r_[np.ones(rows), np.zeros(cols - 1)][None],
    )


def _solve_programs(blocks: list[_Program]) -> list[np.ndarray | None]:
    """Each block's solution from one HiGHS program (None for every block where it fails)."""
    from scipy import sparse
    from scipy.optimize import linprog

    res = linprog(
        np.concatenate([b.cost for b in blocks]),
        A_ub=sparse.block_diag([b.upper for b in blocks], format="csr"),
        b_ub=np.zeros(sum(b.upper.shape[0] for b in blocks)),
        A_eq=sparse.block_diag([b.equal for b in blocks], format="csr"),
        b_eq=np.ones(len(blocks)),
        bounds=(0, None),
        method="highs",
    )
    if res.status != 0:
        return [None] * len(blocks)
    edges = np.cumsum([0, *(b.cost.size for b in blocks)])
    return [res.x[lo:hi] for lo, hi in itertools.pairwise(edges)]


def _farkas_of(
    H: np.ndarray, box: float, exact: Combination | None, block: _Program, x: np.ndarray | None
) -> tuple[list[Fraction] | None, bool]:
    """(the certificate in the block's solution x, or None; whether its objective is below 0
    by more than ``_ZERO`` of its data)."""
    if x is None:
        return None, False
    value = float(block.cost @ x)
    if value >= 0:
        return None, False
    negative = value < -_ZERO * float(np.abs(H).max(initial=0.0)) * (1.0 + box)
    return _farkas(H, box, x[: H.shape[0]], exact), negative


def _farkas(
    H: np.ndarray, box: float, y_float: np.ndarray, exact: Combination | None
) -> list[Fraction] | None:
    """y (the LP's, clipped to be nonnegative) when it proves {x : H (x, 1) >= 0, |x_i| <=
    box} empty in exact arithmetic, else None."""
    y = [Fraction(max(float(v), 0.0)) for v in y_float]
    if exact is None:
        combo: list[Fraction] | None = product([y], fractions(H))[0]
    else:
        combo = exact(y)
    if combo is None:
        return None
    spread = sum((abs(v) for v in combo[:-1]), Fraction(0))
    return y if combo[-1] + Fraction(box) * spread < 0 else None


def _empty_pairs(
    regions: _Regions, model: LureModel, box: float
) -> dict[tuple[int, int], list[Fraction]]:
    """The transitions (k, j) that no step makes inside the box, for representatives k, each
    with its Farkas certificate, checked.  Transitions seen on sampled states need no LP (a
    transition kept that is in fact empty only costs an LMI)."""
    seen = _sampled_pairs(model, regions, box)
    pairs = [
        (k, j)
        for k in regions.representatives()
        for j in range(len(regions.signs))
        if not (k == regions.zero and j == regions.zero) and (k, j) not in seen
    ]
    problems = [
        (
            np.vstack([regions.G[k], regions.G[j] @ regions.T[k]]),
            box,
            partial(regions.exact_combination, model, k, j),
        )
        for k, j in pairs
    ]
    found = _empty_in_boxes(problems)
    return {pair: y for pair, y in zip(pairs, found, strict=True) if y is not None}


def _sampled_pairs(
    model: LureModel, regions: _Regions, box: float, per_region: int = 2000
) -> set[tuple[int, int]]:
    """(region, next region) seen on random states of every region (threshold 1): w = Cw xi
    drawn in the region's intervals (active entries log-spread up to the box), plus a random
    component in the null space of Cw."""
    rng = np.random.default_rng(0)
    m, N = model.m, model.N
    pinv = np.linalg.pinv(model.Cw)
    null = np.eye(N) - pinv @ model.Cw
    out: set[tuple[int, int]] = set()
    weights = 3 ** np.arange(m - 1, -1, -1)
    for k, s in enumerate(regions.signs):
        size = np.exp(rng.uniform(0.0, np.log(box), (per_region, m)))
        w = np.where(s == 0, rng.uniform(-1.0, 1.0, (per_region, m)), s * size)
        z = rng.standard_normal((per_region, N)) * np.exp(
            rng.uniform(np.log(1e-2), np.log(box), (per_region, 1))
        )
        # (states near the floats' limits overflow: those samples are dropped, not counted)
        with np.errstate(over="ignore", invalid="ignore"):
            xi = w @ pinv.T + z @ null.T
            nxt = xi @ model.A.T + model.phi(xi @ model.Cw.T) @ model.B.T
            seen = np.all(np.isfinite(xi), axis=1) & np.all(np.isfinite(nxt @ model.Cw.T), axis=1)
            inside = seen & (_codes(xi @ model.Cw.T, weights) == k)
            for j in np.unique(_codes(nxt @ model.Cw.T, weights)[inside]).tolist():
                out.add((k, j))
    return out


def _codes(w: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """The index of the region of each row of w (threshold 1)."""
    return np.where(w > 1.0, 2, np.where(w < -1.0, 0, 1)) @ weights


def _replay(model: LureModel, radius: float, ball: float, seed: int) -> dict[str, Any]:
    """Simulate initial errors of norm ``radius`` (a_hat(0) = 0, no attack): the certificate
    says they stay in the ball and converge to zero."""
    rng = np.random.default_rng(seed)
    e0 = rng.standard_normal((SAMPLES, model.n_e))
    e0 *= radius / np.linalg.norm(e0, axis=1, keepdims=True)
    xi0 = np.concatenate([e0, np.zeros((SAMPLES, model.N - model.n_e))], axis=1)
    target = 1e-6 * max(radius, 1.0)
    highest, steps, xi = 0.0, 0, xi0
    while True:  # a slow design converges late: go on, chunk by chunk, while it stays inside
        path = model.simulate(xi, STEPS)[1:]
        norms = np.linalg.norm(path, axis=2)  # (steps, samples)
        highest, steps, xi = max(highest, float(norms.max())), steps + STEPS, path[-1]
        final = float(norms[-1].max())
        if highest > ball or final <= target or steps >= MAX_STEPS:
            break
    return {
        "samples": SAMPLES,
        "steps": steps,
        "largest_norm_reached": highest,
        "final_largest_norm": final,
        "confirmed": highest <= ball and final <= target,
    }
