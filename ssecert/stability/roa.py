"""A certified region of attraction of a sparse observer: the invariant part of its dead zone.

Near the origin the soft threshold is exactly zero: while every entry of
w = Cw xi is at most the threshold in magnitude, the error state of the
Lur'e model (``ssecert.observers.lure``) follows the linear map
xi+ = A xi.  When A is Schur with a verified Lyapunov matrix P
(A' P A - P < 0, ``lyapunov_certificate``), every sublevel set
{xi' P xi <= c} is invariant under that map, and the largest one inside the
dead zone, c* = min_i threshold^2 / (Cw_i P^-1 Cw_i'), is invariant under the
observer itself: from any initial state in it the error converges to zero.
An observer starts with a_hat(0) = 0, so the region is reported as the
radius r of initial estimation errors: ||e(0)|| <= r puts xi(0) in the set.
P is the Lyapunov matrix with Q = I, or, when it certifies a larger radius,
one proposed by an LMI that maximises the radius (cvxpy with Clarabel; the
solver's answer is only a candidate, re-verified in numpy).  Each radius is
checked by simulating initial errors on its sphere before it is reported.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import replace
from fractions import Fraction
from typing import Any

import numpy as np

from ..budget import Budget, stage
from ..numerics.rational import fractions, is_positive_definite, product, solve
from ..observers.lure import ExactLure, LureModel
from ..results import Verdict
from .lyapunov import LyapunovMethod, lyapunov_certificate, verified_decrease
from .outcomes import Region, RegionCode
from .piecewise import piecewise_region

__all__ = ["dead_zone_region", "region_of_attraction"]

SAFETY = 1.0 - 1e-9  # the level used, a hair inside the dead zone's largest invariant set
SAMPLES = 64  # initial errors on the sphere of the radius, simulated
STEPS = 200
LMI_LIMIT = 40  # largest error state whose P is also chosen by an LMI (a second or two)
EXACT_LIMIT = 20  # largest error state whose region is re-checked in exact arithmetic


def region_cost(model: LureModel) -> tuple[float, float]:
    """Bytes and operations of the dead zone's region: a dense Lyapunov solve of the N-state
    model (Bartels-Stewart: a dozen N x N work arrays, about 30 N^3 operations) and the replay
    of ``SAMPLES`` initial errors for ``STEPS`` steps."""
    N, m = model.N, model.m
    nbytes = 8.0 * (12 * N * N + (STEPS + 1) * SAMPLES * N)
    return nbytes, 30.0 * N**3 + 2.0 * STEPS * SAMPLES * (N * N + 2 * N * m)


def region_of_attraction(
    model: LureModel,
    *,
    seed: int = 0,
    piecewise: bool = False,
    widen: bool = True,
    budget: Budget | None = None,
) -> Region:
    """The certified radius of initial estimation errors (a_hat(0) = 0) from which the observer
    converges without attack, with how it was found; radius 0 with the reason's code when none
    is (``RegionCode.DEAD_ZONE_UNSTABLE`` when the dead zone's linear dynamics are proved
    unstable: no region exists, and the region_of_attraction check fails).

    With ``piecewise``, a piecewise-quadratic Lyapunov function over the soft threshold's
    regions (``ssecert.stability.piecewise``, up to 3 channels) is also searched, and the
    larger verified radius is kept (the evidence's ``dead_zone_radius`` then records the
    other).  Without
    ``widen`` only the Lyapunov matrix with Q = I is tried (no LMI: the design-space map).

    When the states' units differ widely, the region is searched again in balanced
    coordinates xi = diag(s) xi_b (``LureModel.balancing``, exact): a radius r_b there holds
    for ||e(0)|| <= r_b min(s_e) in the model's own units, kept where larger than the one
    certified in those units (``state_scaling``, ``balanced_radius``, ``unbalanced_radius``;
    the other numbers then are in the balanced coordinates).

    Radius 0, not attempted, when the dead zone's Lyapunov solve and replay (``region_cost``)
    do not fit ``budget`` (default ``Budget()``).
    """
    nbytes, flops = region_cost(model)
    refusal = (budget or Budget()).check(
        f"the dead zone's Lyapunov function of the {model.N:,}-state error dynamics",
        nbytes=nbytes,
        flops=flops,
    )
    if refusal is not None:
        return Region.none(RegionCode.NOT_ATTEMPTED, refusal=refusal)
    found = _region_in_units(model, seed, piecewise, widen)
    if found.code is RegionCode.DEAD_ZONE_UNSTABLE or math.isinf(found.radius):
        return found
    # where the states' units are far apart, also in balanced coordinates: the larger region
    # (the model's own units can hide a piecewise function that balanced ones find)
    for s in model.balancings():
        inner = _region_in_units(model.scaled(s), seed, piecewise, widen)
        if inner.radius > 0:
            break
    else:
        return found
    low = float(np.min(s[: model.n_e]))
    if not inner.radius * low > found.radius:
        return found
    evidence = {**inner.evidence, "state_scaling": s, "balanced_radius": inner.radius}
    if "certificate" in evidence:  # (a piecewise one: its LMIs are the balanced model's)
        certificate = dict(evidence["certificate"])
        certificate["coordinates"] += (
            "; xi is in the balanced coordinates xi = diag(state_scaling)^-1 xi_model (the "
            "model's states divided by state_scaling, exactly: powers of two)"
        )
        evidence["certificate"] = certificate
    if "dead_zone_radius" in evidence:
        evidence["dead_zone_radius"] = float(evidence["dead_zone_radius"]) * low
    if found.radius > 0:
        evidence["unbalanced_radius"] = found.radius
    return replace(inner, radius=inner.radius * low, evidence=evidence)


def _region_in_units(model: LureModel, seed: int, piecewise: bool, widen: bool) -> Region:
    """``region_of_attraction`` in the model's own coordinates."""
    with stage("the dead zone's invariant set"):
        found = _dead_zone_region(model, seed, widen)
    if not piecewise or model.m == 0:
        return found
    wider = piecewise_region(model, seed=seed, floor=found.radius)
    if wider.radius > found.radius:
        return replace(wider, evidence={**wider.evidence, "dead_zone_radius": found.radius})
    return replace(found, evidence={**found.evidence, "piecewise": wider})


def dead_zone_region(model: LureModel, seed: int = 0) -> tuple[Region, np.ndarray | None]:
    """The region the dead zone's Lyapunov function certifies in the model's own units (its
    ``P`` and ``level`` in the evidence), the radius 0 with the reason's code when none;
    ``region_of_attraction`` without the piecewise search and the balancing.  Beside it, the
    verified solution P of the discrete Lyapunov equation with Q = I that the region tried
    first (None where there is none), whichever P the region kept."""
    return _dead_zone(model, seed)


def _dead_zone_region(model: LureModel, seed: int, widen: bool = True) -> Region:
    """The radius of the largest invariant sublevel set of the dead zone's Lyapunov function."""
    return _dead_zone(model, seed, widen)[0]


def _dead_zone(model: LureModel, seed: int, widen: bool = True) -> tuple[Region, np.ndarray | None]:
    """``_dead_zone_region`` and the verified Lyapunov solution with Q = I it started from."""
    if model.m == 0 or model.threshold <= 0:
        return Region.none(RegionCode.NO_DEAD_ZONE), None
    n_e = model.n_e
    if n_e < model.N and not np.any(model.A[n_e:]):
        # xi+ = A xi with A = [[F, -L], [0, 0]]: its eigenvalues are F's and 0, so F decides
        # (the exact powers of F alone reach a decision the whole A's may not)
        local = lyapunov_certificate(model.A[:n_e, :n_e], exact=model.exact_A(error_block=True))
        if local.verdict is Verdict.FAILS:
            return Region.none(
                RegionCode.DEAD_ZONE_UNSTABLE, error_block=True, lyapunov=local.reason
            ), None
    lyap = lyapunov_certificate(model.A, exact=model.exact_A())
    if (
        lyap.verdict is not Verdict.HOLDS
        or lyap.P is None
        or lyap.method is not LyapunovMethod.LYAPUNOV
    ):
        code = (
            RegionCode.DEAD_ZONE_UNSTABLE
            if lyap.verdict is Verdict.FAILS
            else RegionCode.NO_VERIFIED_LYAPUNOV
        )
        return Region.none(code, lyapunov=lyap.reason), None
    found = _region(model, 0.5 * (lyap.P + lyap.P.T), lyap.margin, lyap.error_bound, seed)
    found = _with(found, P_from="discrete Lyapunov equation with Q = I")
    candidate = _lmi_matrix(model) if widen and model.N <= LMI_LIMIT and found.radius > 0 else None
    if candidate is None:
        return found, lyap.P
    wider, solver = candidate
    verified = verified_decrease(model.A, wider, rounding=model.rounding)
    if verified is not None:
        other = _region(model, wider, verified[0], verified[1], seed)
        if other.radius > found.radius:
            by = "Clarabel" if solver == "CLARABEL" else f"{solver} through cvxpy"
            return _with(
                other,
                P_from=f"LMI maximising the radius ({by}), verified in numpy",
                radius_with_Q_identity=found.radius,
            ), lyap.P
    return found, lyap.P


def _with(region: Region, **evidence: Any) -> Region:
    """``region`` with more evidence, after its own."""
    return replace(region, evidence={**region.evidence, **evidence})


def _region(
    model: LureModel, P: np.ndarray, margin: float | None, bound: float, seed: int
) -> Region:
    """The radius that the verified Lyapunov matrix ``P`` of the dead zone certifies."""
    Pinv_Cw = np.linalg.solve(P, model.Cw.T)  # columns P^-1 Cw_i'
    spread = np.einsum("ij,ji->i", model.Cw, Pinv_Cw)  # Cw_i P^-1 Cw_i'
    # beyond the exact matrices' budget the region rests on the floats: each row's reach
    # ||P^-1/2 Cw_i'|| then takes the model's rounding eps, at most eps / sqrt(lambda_min(P))
    exact_model = model.exact() if model.N <= EXACT_LIMIT else None
    unchecked = model.N <= EXACT_LIMIT and exact_model is None
    if unchecked:
        spread = _rounded_spread(model, P, spread)
    # a row that is zero never leaves the dead zone: it bounds no level
    with np.errstate(over="ignore"):
        room = np.float64(model.threshold) ** 2 / np.where(spread > 0, spread, 1.0)
    room = np.where(spread > 0, room, np.inf)
    level = SAFETY * float(np.min(room))
    if not math.isfinite(level):
        return Region.none(
            RegionCode.LEVEL_OUT_OF_RANGE,
            threshold=model.threshold,
            unreached=bool(np.all(spread == 0)),
        )
    n_e = model.n_e
    top = float(np.linalg.eigvalsh(P[:n_e, :n_e])[-1])
    # a hair inside, so that the ball lies strictly in the level set on the printed numbers
    radius = math.sqrt(level / top) * (1 - 1e-12) if math.isfinite(level) and top > 0 else 0.0
    if radius <= 0:
        return Region.none(RegionCode.NO_INVARIANT_SET)
    exact = None if exact_model is None else _exact_recheck(exact_model, model, P, level, radius)
    if exact is not None and not all(exact.values()):
        refuted = [k for k, ok in exact.items() if not ok]
        return Region.none(
            RegionCode.EXACT_RECHECK_FAILED, {"exact_recheck": exact}, refuted=refuted
        )
    replay = _replay(model, radius, P, level, seed)
    if not replay["confirmed"]:
        return Region.none(RegionCode.REPLAY_LEFT_SET, {"replay": replay})
    evidence = {
        "level": level,
        "P": P,
        "lyapunov_margin": margin,
        "lyapunov_error_bound": bound,
        "binding_row": int(np.argmin(room)),
        "exact_recheck": exact
        if exact is not None
        else "not run: the model's exact matrices are beyond their budget; verified in "
        f"floating point, each row's reach up by the model's rounding {model.rounding:.3g}"
        if unchecked
        else f"not run: error states above {EXACT_LIMIT} are verified in floating point only",
        "method": "largest invariant sublevel set of the dead zone's Lyapunov function",
        "replay": replay,
    }
    return Region(radius, RegionCode.CERTIFIED, evidence=evidence)


def _lmi_matrix(model: LureModel) -> tuple[np.ndarray, str] | None:
    """A candidate P with a larger certified radius: Y = P^-1 with A Y A' - Y <= -eps I, the dead
    zone's rows Cw_i Y Cw_i' <= threshold^2 and Y >= t E E' (E the estimation-error coordinates),
    t maximised; P and the solver's name, or None when the solver fails.  Nothing here is
    trusted: the caller verifies."""
    from ._conic import LMIProblem

    N, n_e = model.N, model.n_e
    E = np.zeros((N, n_e))
    E[:n_e] = np.eye(n_e)
    scale = model.threshold**2
    lp = LMIProblem()
    Y, t = lp.block(N), lp.scalar()
    eye = np.eye(N)
    zero = np.zeros((N, N))
    lp.lmi(zero, [(Y, eye, 1.0), (Y, model.A.T, -1.0)], delta=1e-6 * scale)
    lp.lmi(zero, [(Y, eye, 1.0)], [(t, E @ E.T, -1.0)])
    lp.lmi(zero, [(Y, eye, 1.0)], delta=1e-9 * scale)
    for row in model.Cw:
        lp.lmi(np.array([[scale]]), [(Y, row.reshape(N, 1), -1.0)])
    lp.maximize(t)
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            # an inaccurate solution is only a candidate like any other: it is verified
            warnings.simplefilter("ignore")
            x, info = lp.solve()
    except (ArithmeticError, ValueError):
        return None
    if x is None:
        return None
    Yv = lp.matrix(x, Y)
    try:
        np.linalg.cholesky(Yv)
    except np.linalg.LinAlgError:
        return None
    P = np.linalg.inv(Yv)
    return 0.5 * (P + P.T), info["solver"]


def _rounded_spread(model: LureModel, P: np.ndarray, spread: np.ndarray) -> np.ndarray:
    """Upper bounds of Cx_i P^-1 Cx_i' for the exact rows Cx_i of the model's threshold inputs,
    within ``model.rounding`` of its floats Cw_i (``spread`` their computed Cw_i P^-1 Cw_i'):
    ||P^-1/2 Cx_i'|| <= ||P^-1/2 Cw_i'|| + eps / sqrt(lambda_min(P)), the computed values up by
    a relative 64 N u cond(P) and lambda_min down by as much (inf where P is not positive
    definite in floating point or too ill-conditioned for that)."""
    N = P.shape[0]
    eigs = np.linalg.eigvalsh(0.5 * (P + P.T))
    slack = 64 * N * 2.0**-53 * (float(eigs[-1]) / float(eigs[0]) if eigs[0] > 0 else math.inf)
    if not slack < 1e-3:
        return np.full(spread.shape, np.inf)
    low = float(eigs[0]) * (1 - slack)
    reach = np.sqrt(np.maximum(spread, 0.0) * (1 + slack)) + model.rounding / math.sqrt(low)
    return (reach * (1 + 1e-12)) ** 2


def _exact_recheck(
    exact: ExactLure, model: LureModel, P: np.ndarray, level: float, radius: float
) -> dict[str, bool]:
    """The three facts the region rests on, decided exactly on the printed floats P, level and
    radius and the model's ``exact`` matrices (from the spec's data): V decreases (P - A' P A
    > 0, and P > 0), the level set lies in the dead zone (level Cw_i P^-1 Cw_i' <= threshold^2
    for every i), and the ball of initial errors lies in the level set (level I - radius^2 P_ee
    > 0, a_hat(0) = 0)."""
    Pq, Aq, Cw = fractions(P), exact.fractions("A"), exact.fractions("Cw")
    n_e = model.n_e
    decrease = [[p - v for p, v in zip(rp, rv)] for rp, rv in zip(Pq, product(
        [list(col) for col in zip(*Aq)], product(Pq, Aq)))]  # fmt: skip
    lam2, c, r2 = Fraction(model.threshold) ** 2, Fraction(level), Fraction(radius) ** 2
    inside = True
    for row in Cw:
        x = solve(Pq, row)  # P^-1 Cw_i'
        if x is None or c * sum((a * b for a, b in zip(row, x)), Fraction(0)) > lam2:
            inside = False
            break
    ball = [[(c if i == k else 0) - r2 * Pq[i][k] for k in range(n_e)] for i in range(n_e)]
    return {
        "lyapunov_decrease": is_positive_definite(Pq) and is_positive_definite(decrease),
        "level_set_in_dead_zone": inside,
        "ball_in_level_set": is_positive_definite(ball),
    }


def _replay(model: LureModel, radius: float, P: np.ndarray, level: float, seed: int) -> dict:
    """Simulate initial errors of norm ``radius`` (a_hat(0) = 0, no attack): the certificate
    says they never leave the level set and V = xi' P xi decreases along them."""
    rng = np.random.default_rng(seed)
    e0 = rng.standard_normal((SAMPLES, model.n_e))
    e0 *= radius / np.linalg.norm(e0, axis=1, keepdims=True)
    xi0 = np.concatenate([e0, np.zeros((SAMPLES, model.N - model.n_e))], axis=1)
    path = model.simulate(xi0, STEPS)  # (steps + 1, samples, N)
    V = np.einsum("ksi,ij,ksj->ks", path, P, path)
    highest = float(V.max() / level)
    decreasing = bool(np.all(np.diff(V, axis=0) <= 1e-9 * level))
    return {
        "samples": SAMPLES,
        "steps": STEPS,
        "highest_level_reached": highest,
        "decreasing": decreasing,
        "final_over_initial": float(V[-1].max() / max(V[0].max(), np.finfo(float).tiny)),
        "confirmed": decreasing and highest <= 1.0 + 1e-6,
    }
