"""Certified worst-case error of the l1 decoder under bounded noise and attack.

The decoder (``ssecert.estimators.l1_decoder``; the l1 decoder of the pruning paper) is
x_hat = argmin_x ||Y - O x||_1 over a window of tau steps, with Y = O x + a + w: the attack
a on the rows of at most s sensors, the noise w bounded on every sensor (every sample within
eta_i, or the window's samples of sensor i within eta_i in 2-norm).

The bound.  Let S be the rows of s sensors holding the attack, K the others and e = x_hat - x.
The decoder's optimality, ||a_S + w_S - O_S e||_1 + ||w_K - O_K e||_1 <= ||a_S + w_S||_1 +
||w_K||_1, and the triangle inequality give

    ||O_K e||_1 - ||O_S e||_1 <= 2 ||w_K||_1.

With theta_S = max_e ||O_S e||_1 / ||O_K e||_1 (the null-space constant of S: below 1 exactly
when the decoder recovers x from every attack on S without noise),

    ||e||_2 <= nu_K ||O_K e||_1 <= 2 W_K nu_K / (1 - theta_S),

nu_K = ||O_K^+||_{1->2} the largest 2-norm of a column of the pseudo-inverse (e = O_K^+ O_K e;
at most 1 / sigma_min(O_K), and smaller by up to the square root of K's rows),

W_K the largest ||w_K||_1 (tau sum eta_i per sample, sqrt(tau) sum eta_i for window 2-norm
bounds).  Every attack lies within the rows of some set of exactly s sensors, so the decoder's
error is at most the largest of these over the sets.

theta_S is a maximum over the sign patterns sigma of the attacked rows of the linear program
max sigma' O_S e subject to ||O_K e||_1 <= 1, whose dual is min ||z||_inf subject to
O_K' z = O_S' sigma: any z that satisfies the equality bounds it (sigma' O_S e = z' O_K e <=
||z||_inf ||O_K e||_1).  Each dual is solved by HiGHS and its z made exactly feasible for the
exact plant by a correction of 2-norm at most ||residual||_2 / sigma_min(O_K) (the residual
evaluated with its rounding and the powers' error), so each theta_S used is an upper bound.
There are 2^(s tau - 1) patterns per set (sigma and -sigma give the same value): the number of
programs is limited.
"""

from __future__ import annotations

import enum
import itertools
import math
from dataclasses import dataclass, field, replace
from fractions import Fraction
from typing import Any

import numpy as np

from ..noise import MeasurementNoise
from ..system import System
from ..tolerances import gamma
from ._combinatorics import count_subsets
from .lasso_bound import (
    _SAFE,
    _kept_gramians,
    _kept_sigma,
    _rounded_up,
    _scaled_blocks,
    _times_up,
    _window_deficient,
    inverse_error,
)
from .noise import _kept_sets, window_inputs

__all__ = [
    "L1BoundCode",
    "L1ErrorBound",
    "l1_bound_rechecks",
    "l1_error_bound",
    "l1_worst_case",
    "with_lower_bound",
]

DEFAULT_MAX_PROGRAMS = 4096  # linear programs (sets times sign patterns)


class L1BoundCode(enum.Enum):
    """How an l1 decoder error bound came out."""

    #: a finite bound, certified for the exact plant
    CERTIFIED = "certified"
    #: a set S has theta_S >= 1 (or not proved below 1): an attack on S may move the decoder
    #: without noise, and the bound does not exist there
    NOT_NULL_SPACE = "null-space constant not below 1"
    #: some O_K is not proved of full column rank
    NO_MARGIN = "no margin"
    #: s >= p: no sensor is left unattacked
    TOO_FEW_SENSORS = "too few sensors"
    #: more linear programs than the limit
    TOO_MANY_PROGRAMS = "too many programs"
    #: a linear program was not solved, or the numbers leave the floating-point range
    NOT_SOLVED = "not solved"
    #: the printed numbers did not survive their rational re-check (please report the plant)
    RECHECK_FAILED = "re-check failed"
    #: the sensors outside some set (``worst_support``) over the window exactly do not
    #: determine the state: an attack there makes two states agree, no decoder is bounded
    WINDOW_TOO_SHORT = "window too short"


@dataclass(frozen=True)
class L1ErrorBound:
    """The worst-case error of the l1 decoder over a window (``l1_error_bound``).

    Attributes
    ----------
    code : L1BoundCode
    bound : float
        Certified: ||x_hat - x||_2 <= bound for every attack on at most s sensors and every
        noise within its bounds (inf when none is certified).
    theta : float
        The largest null-space constant over the sets of s sensors (an upper bound); the
        certificate needs it below 1.  Not certified, that of the first set found whose
        constant is not proved below 1 (the others are not examined).
    theta_support : tuple of int
        The sensors of the set with the largest theta.
    worst_support : tuple of int
        The set of s sensors whose bound is the largest.
    sigma : float
        The certified lower bound of sigma_min(O_K) there.
    reach : float
        The certified upper bound of nu_K = ||O_K^+||_{1->2} there (the largest 2-norm of a
        column of O_K^+).
    noise_l1 : float
        The largest ||w_K||_1 there.
    noise : MeasurementNoise
    horizon, max_attacked : int
    sets, programs : int
        Sets of s sensors, and linear programs solved.
    facts : mapping
        The numbers of the worst set (for the re-check and the words).
    sources : MeasurementNoise or None
        The spec's noise with its process noise, when ``noise`` is what it adds up to at
        the sensors (``MeasurementNoise.at_sensors``); None when ``noise`` is the spec's.
    """

    code: L1BoundCode
    bound: float
    noise: MeasurementNoise
    horizon: int
    max_attacked: int
    theta: float = math.inf
    theta_support: tuple[int, ...] = ()
    worst_support: tuple[int, ...] = ()
    sigma: float = 0.0
    reach: float = math.inf
    noise_l1: float = math.inf
    sets: int = 0
    programs: int = 0
    facts: dict[str, Any] = field(default_factory=dict)
    sources: MeasurementNoise | None = None
    lower: float = 0.0
    lower_kept: tuple[int, ...] = ()

    @property
    def realizable(self) -> MeasurementNoise:
        """The noise the lower bound's construction keeps within: ``noise``, or with process
        noise (``sources``) its measurement noise alone."""
        return self.noise if self.sources is None else self.sources.measurement_only()


# sets of s sensors whose kept sensors are tried for the lower bound, beyond the worst set's
# and the largest null-space constant's: every one up to this many sets
_LOWER_SETS = 256


def with_lower_bound(system: System, found: L1ErrorBound) -> L1ErrorBound:
    """``found`` with the error the l1 decoder makes on a window built for it (``lower``,
    ``lower_kept``): for kept sensors K (p - s of them) and v the smallest right singular
    vector of O_K, the data Y = O (x + c v) are those of the state x with the noise c O_K v on
    K (c the largest scale within the realizable noise's bounds, less the rounding of O_K v)
    and the attack c O_S v on the s others; they are explained exactly by x + c v, which the
    l1 decoder returns (the only state with zero residual, O of full column rank), so its
    error there is c ||v||.  The largest over the kept sensors of the worst set, of the
    largest null-space constant and, up to ``_LOWER_SETS`` sets, of every set; 0 when the
    bound is not certified or no scale is positive (no noise)."""
    if found.code is not L1BoundCode.CERTIFIED or found.max_attacked >= system.p:
        return found
    from .noise import _block_errors

    p, tau, s = system.p, found.horizon, found.max_attacked
    supports = [found.worst_support, found.theta_support]
    if count_subsets(p, [s]) <= _LOWER_SETS:
        supports += [tuple(int(i) for i in row) for row in _kept_sets(p, s)]
    with np.errstate(all="ignore"):
        blocks = system.sensor_blocks(tau)  # (p, tau, n)
        errors = _block_errors(system, tau)
    if not (np.all(np.isfinite(blocks)) and np.all(np.isfinite(errors))):
        return found
    eta = found.realizable.eta
    kept = np.array(
        [[i for i in range(p) if i not in support] for support in dict.fromkeys(supports)]
    )  # (sets, p - s): every kept set at once
    O_K = blocks[kept]  # (sets, p - s, tau, n)
    v = _weakest(O_K)
    with np.errstate(all="ignore"):
        Ov = np.abs(np.einsum("skti,si->skt", O_K, v))
        size = np.max(Ov, axis=2) if found.realizable.per_sample else np.linalg.norm(Ov, axis=2)
        # the exact O_K v is within ||fl(O_i) - O_i||_F ||v||_2 of it on sensor i's rows
        norms = np.linalg.norm(v, axis=1)
        size = (size + errors[kept] * norms[:, None]) * (1 + 4 * 2.0**-53 * (tau + 4))
        scales = np.where(size > 0, eta[kept] / size, np.inf)
        lower = np.min(scales, axis=1) * (1 - 2.0**-40) * norms * (1 - 2.0**-40)
    # (a subnormal result is rounded absolutely, beyond what the factors take off: none)
    lower = np.where(np.isfinite(lower) & (lower >= 2.0**-1021), lower, 0.0)
    j = int(np.argmax(lower))  # the first of the largest
    if not lower[j] > 0:
        return replace(found, lower=0.0, lower_kept=())
    return replace(found, lower=float(lower[j]), lower_kept=tuple(int(i) for i in kept[j]))


def _weakest(O_K: np.ndarray) -> np.ndarray:
    """The smallest right singular vector of each stacked O_K (sets, |K|, tau, n)."""
    _, _, vh = np.linalg.svd(O_K.reshape(O_K.shape[0], -1, O_K.shape[-1]))
    return vh[:, -1, :]


def l1_worst_case(system: System, found: L1ErrorBound) -> dict[str, Any] | None:
    """The window ``with_lower_bound`` builds on ``found.lower_kept``: the state x = 0, the
    noise (within the realizable bounds on the kept sensors, 0 elsewhere), the attack (on the
    others), the data Y (p, tau) and the state x + c v that explains it exactly, whose error
    is ``found.lower``; None without one."""
    if not found.lower_kept:
        return None
    tau, kept = found.horizon, list(found.lower_kept)
    blocks = system.sensor_blocks(tau)
    v = _weakest(blocks[kept][None])[0]
    lower_c = found.lower / float(np.linalg.norm(v)) / (1 - 2.0**-40)
    data = lower_c * (blocks @ v)  # (p, tau): O (c v)
    attacked = [i for i in range(system.p) if i not in found.lower_kept]
    noise = np.zeros_like(data)
    noise[kept] = data[kept]
    attack = np.zeros_like(data)
    attack[attacked] = data[attacked]
    return {
        "x": np.zeros(system.n),
        "x_explaining": lower_c * v,
        "noise": noise,
        "attack": attack,
        "attacked": attacked,
        "data": data,
        "lower": found.lower,
    }


def _reach_upper(O_K: np.ndarray, sigma_K: float, e_K: float) -> float:
    """An upper bound of ||O_K^+||_{1->2} (the largest column 2-norm of the pseudo-inverse)
    for the exact plant: N = G^-1 O_K' computed, its error at most ||residual|| / sigma_min^2
    (the residual G N - O_K' evaluated with its rounding and the powers' error)."""
    n = O_K.shape[1]
    N = np.linalg.solve(O_K.T @ O_K, O_K.T)
    columns = float(np.sqrt((N**2).sum(axis=0)).max()) * (1.0 + gamma(n + 2))
    return (columns + inverse_error(O_K, N, O_K.T, sigma_K, e_K, e_K)) * _SAFE


def _theta_upper(
    O_K: np.ndarray, O_S: np.ndarray, sigma_K: float, e_K: float, e_S: float
) -> float | None:
    """An upper bound of theta_S for the exact plant (None when a program is not solved)."""
    from scipy.optimize import linprog

    k, n = O_K.shape
    m = O_S.shape[0]
    if m == 0:
        return 0.0
    # min t subject to -t <= z_j <= t, O_K' z = O_S' sigma: variables (z, t)
    cost = np.concatenate([np.zeros(k), [1.0]])
    bound_rows = np.block(
        [[np.eye(k), -np.ones((k, 1))], [-np.eye(k), -np.ones((k, 1))]]
    )  # fmt: skip
    A_eq = np.hstack([O_K.T, np.zeros((n, 1))])
    norm_K, norm_S = float(np.linalg.norm(O_K)), float(np.linalg.norm(O_S))
    worst = 0.0
    for tail in itertools.product((1.0, -1.0), repeat=m - 1):
        signs = np.array((1.0, *tail))
        target = O_S.T @ signs
        result = linprog(
            cost,
            A_ub=bound_rows,
            b_ub=np.zeros(2 * k),
            A_eq=A_eq,
            b_eq=target,
            bounds=[(None, None)] * (k + 1),
            method="highs",
        )
        if result.status != 0 or result.x is None:
            return None
        z = np.asarray(result.x[:k])
        norm_z = float(np.linalg.norm(z))
        # the exact plant's residual O_S' sigma - O_K' z: computed, its rounding, the powers'
        # error; the correction that zeroes it has 2-norm <= ||residual|| / sigma_min(O_K)
        residual = (
            float(np.linalg.norm(target - O_K.T @ z))
            + gamma(k + m + 2) * (norm_S * math.sqrt(m) + norm_K * norm_z)
            + e_S * math.sqrt(m)
            + e_K * norm_z
        ) * _SAFE
        value = (float(np.max(np.abs(z))) + residual / sigma_K) * _SAFE
        worst = max(worst, value)
    return worst


def l1_error_bound(
    system: System,
    max_attacked: int,
    noise: MeasurementNoise,
    *,
    horizon: int | None = None,
    max_programs: int = DEFAULT_MAX_PROGRAMS,
) -> L1ErrorBound:
    """The certified worst-case estimation error of the l1 decoder over a window.

    Parameters
    ----------
    system : System
    max_attacked : int
        s, the largest number of attacked sensors.
    noise : MeasurementNoise
        Per-sensor bounds of the measurement noise.
    horizon : int, optional
        tau, the window (default n).
    max_programs : int, default 4096
        Largest number of linear programs: C(p, s) sets times 2^(s tau - 1) sign patterns.

    Returns
    -------
    L1ErrorBound

    Examples
    --------
    Three sensors of one state, one attacked, noise at most 0.1 on each: theta = 1/2 (the
    attacked sensor against the two others) and ||O_K^+||_(1->2) = 1/2, so the error is at most
    2 (0.2) (1/2) / (1 - 1/2).

    >>> import numpy as np
    >>> from ssecert import System
    >>> plant = System(np.eye(1), np.ones((3, 1)))
    >>> found = l1_error_bound(plant, 1, MeasurementNoise.uniform(0.1, 3), horizon=1)
    >>> round(found.theta, 9), round(found.bound, 6)
    (0.5, 0.4)
    """
    s, tau = window_inputs(system, max_attacked, noise, horizon)
    p = system.p
    base: dict[str, Any] = {"noise": noise, "horizon": tau, "max_attacked": s}
    if s >= p:
        return L1ErrorBound(L1BoundCode.TOO_FEW_SENSORS, math.inf, **base)
    sets = count_subsets(p, [s])
    programs = sets * (2 ** (s * tau - 1) if s else 0)
    base["sets"] = sets
    if programs > max_programs:
        return L1ErrorBound(
            L1BoundCode.TOO_MANY_PROGRAMS,
            math.inf,
            programs=programs,
            facts={"limit": max_programs},
            **base,
        )
    ranged = _scaled_blocks(system, tau)
    if ranged is None:
        return L1ErrorBound(L1BoundCode.NOT_SOLVED, math.inf, **base)
    blocks, errors, d = ranged  # the plant's blocks are 2^d times these: theta does not change
    supports = _kept_sets(p, s)
    kept, G = _kept_gramians(blocks, supports)
    frob2 = np.sum(blocks**2, axis=(1, 2))
    sigma, e_K, e_S = _kept_sigma(G, frob2, errors, supports, kept, tau)
    names = lambda j: tuple(int(i) for i in supports[j])  # noqa: E731
    if not np.all(sigma > 0):
        j = int(np.argmin(sigma))
        short = _window_deficient(system, [int(i) for i in kept[j]], tau)
        code = L1BoundCode.NO_MARGIN if short is None else L1BoundCode.WINDOW_TOO_SHORT
        return L1ErrorBound(code, math.inf, worst_support=names(j), facts=short or {}, **base)
    # each set's largest ||w_K||_1, for the noise over a power of two c (exactly)
    top = float(np.max(noise.eta)) if p else 0.0
    c = MeasurementNoise.scale(top)
    eta = noise.eta / c if top > 0 else np.zeros(p)
    per_sensor = eta * (tau if noise.per_sample else math.sqrt(tau))
    noise_l1 = per_sensor[kept].sum(axis=1) * (1.0 + gamma(p + 2))
    thetas, reaches = np.empty(sets), np.empty(sets)
    flat = blocks.reshape(p * tau, -1)
    for j in range(sets):
        rows_k = [i * tau + t for i in kept[j] for t in range(tau)]
        rows_s = [i * tau + t for i in supports[j] for t in range(tau)]
        with np.errstate(all="ignore"):
            value = _theta_upper(flat[rows_k], flat[rows_s], float(sigma[j]), e_K[j], e_S[j])
            reaches[j] = min(
                _reach_upper(flat[rows_k], float(sigma[j]), e_K[j]), 1.0 / float(sigma[j])
            )
        if value is None:
            return L1ErrorBound(L1BoundCode.NOT_SOLVED, math.inf, programs=programs, **base)
        thetas[j] = value
        if not value < 1:  # refused: no bound, whatever the other sets give
            thetas[j + 1 :] = -math.inf
            break
    j_theta = int(np.argmax(thetas))
    common: dict[str, Any] = {
        "theta": float(thetas[j_theta]),
        "theta_support": names(j_theta),
        "programs": programs,
    }
    if not thetas[j_theta] < 1:
        return L1ErrorBound(L1BoundCode.NOT_NULL_SPACE, math.inf, **common, **base)
    e_c = math.frexp(c)[1] - 1  # c = 2^e_c
    with np.errstate(all="ignore"):
        bounds = 2.0 * noise_l1 * reaches / (1.0 - thetas) * (1.0 + gamma(6))
        worst = int(np.argmax(bounds))
        # back to the plant's units (bound by c 2^-d, sigma by 2^d, rounded down where
        # subnormal: a lower bound), rounded up where it could underflow
        bound = _rounded_up(float(_times_up(bounds[worst], e_c - d)), exact_zero=top == 0)
        sigma_worst = float(np.ldexp(sigma[worst], d))
        if sigma_worst < 2.0**-1022:
            sigma_worst = float(np.nextafter(sigma_worst, 0.0))
        reach_worst = float(_times_up(reaches[worst], -d))
        noise_worst = float(_times_up(noise_l1[worst], e_c))
        # at least what the printed numbers give (they are rounded up where subnormal)
        printed = 2.0 * noise_worst * reach_worst / (1.0 - thetas[worst]) * (1.0 + gamma(6))
        bound = max(bound, _rounded_up(float(printed), exact_zero=top == 0))
    if not all(math.isfinite(v) for v in (bound, sigma_worst, reach_worst, noise_worst)):
        return L1ErrorBound(L1BoundCode.NOT_SOLVED, math.inf, **common, **base)
    found = L1ErrorBound(
        L1BoundCode.CERTIFIED,
        bound,
        worst_support=names(worst),
        sigma=sigma_worst,
        reach=reach_worst,
        noise_l1=noise_worst,
        facts={"worst_theta": float(thetas[worst]), "noise_scale": c},
        **common,
        **base,
    )
    if not l1_bound_rechecks(found):
        return replace(found, code=L1BoundCode.RECHECK_FAILED)
    return found


def l1_bound_rechecks(found: L1ErrorBound) -> bool:
    """The printed bound re-derived in rational arithmetic from the printed numbers of the
    worst set: bound >= 2 noise_l1 reach / (1 - theta_S), theta_S < 1."""
    if found.code is not L1BoundCode.CERTIFIED:
        return False
    theta = Fraction(found.facts["worst_theta"])
    if not (theta < 1 and found.sigma > 0):
        return False
    need = 2 * Fraction(found.noise_l1) * Fraction(found.reach) / (1 - theta)
    return Fraction(found.bound) >= need
