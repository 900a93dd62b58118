"""Certified ultimate error bound of a linear observer under bounded measurement noise.

A linear observer x_hat+ = A x_hat + L (y - C x_hat) with y = C x + n and no
attack has the error e = x_hat - x following e+ = F e + L n, F = A - L C.
With every sample of sensor i within eta_i, each component of the error is
eventually at most

    b = sum_{j >= 0} |F^j L| eta       (|.| entrywise),

and no smaller bound holds: the noise n(k - j) = eta * sign((F^j L)_i.) drives
component i to the partial sums of that series.  So b is the exact
worst-case ultimate error, componentwise; ||b||_2 bounds the 2-norm.

Rigour.  The powers F^j L are computed in midpoint-radius interval
arithmetic (Rump's product bound, with each rounding taken up) from
intervals that contain the exact F and L of the spec's data (their
floats plus the a-priori rounding of their formation).  The series is cut
after J terms once its tail, bounded by the norms of m consecutive powers
over 1 - q (q >= ||F^m||_inf < 1, from the same intervals), is a small part
of the sum; an interval that has grown too wide to show a power below 1
leaves the bound inconclusive.  The lower bound is the partial sum's lower
end, for component i the worst.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any, NamedTuple

import numpy as np

from ..noise import MeasurementNoise
from ..tolerances import gamma, rows_norm_up, times_up
from ..tolerances import gamma as gamma_rounding
from ..tolerances import interval_product as _product
from ..tolerances import up_by as _up

__all__ = [
    "balanced_noise_bound",
    "tighter_noise_bound",
    "DecayScan",
    "decay_scan",
    "decaying_certificate",
    "DissipationBound",
    "NoiseGain",
    "NoiseGainCode",
    "dissipation_bound",
    "linear_noise_bound",
    "LocalBound",
    "local_noise_bound",
    "SplitBound",
    "split_bound",
]

MAX_TERMS = 20_000
CONTRACTION_LIMIT = 4096  # powers of F tried for one proved below 1 in norm
TAIL_SHARE = 1e-6  # the series stops once its tail bound is this part of the sum


class NoiseGainCode(enum.Enum):
    """How a noise bound of a linear observer came out."""

    #: a finite ultimate bound, certified for the exact F and L
    CERTIFIED = "certified"
    #: no power of F up to the limit is proved below 1 in norm
    NOT_CONTRACTIVE = "not contractive"
    #: the matrices leave the floating-point range, or their rounding is unknown
    OUT_OF_RANGE = "out of range"


@dataclass(frozen=True)
class NoiseGain:
    """The worst-case ultimate error of a linear observer under bounded noise.

    Attributes
    ----------
    code : NoiseGainCode
    componentwise : ndarray, shape (n,)
        Certified: eventually |e_i(k)| <= componentwise[i] for every noise within its
        bounds (inf where none is certified).
    reached : ndarray, shape (n,)
        Some noise within the bounds drives |e_i| at least this far (the partial sums' lower
        ends): the worst case lies between.
    bound_2, bound_inf : float
        ||componentwise||_2 and its largest entry.
    lower : float
        The largest entry of ``reached``: the worst case of ||e||_inf and of ||e||_2 is at
        least this.
    terms : int
        Terms of the series summed (J).
    power, contraction : int, float
        m and q >= ||F^m||_inf (< 1) of the tail bound.
    tail : float
        The bound of the series' tail added to every component.
    facts : mapping
        Numbers the words need.
    """

    code: NoiseGainCode
    componentwise: np.ndarray
    reached: np.ndarray
    bound_2: float = math.inf
    bound_inf: float = math.inf
    lower: float = 0.0
    terms: int = 0
    power: int = 0
    contraction: float = math.inf
    tail: float = math.inf
    facts: dict[str, Any] = field(default_factory=dict)


def linear_noise_bound(
    F: np.ndarray,
    L: np.ndarray,
    eta: np.ndarray,
    *,
    rounding_F: float = 0.0,
    rounding_L: float = 0.0,
    max_terms: int = MAX_TERMS,
) -> NoiseGain:
    """The certified worst-case ultimate error of e+ = F e + L n with |n_i| <= eta_i.

    Parameters
    ----------
    F : ndarray, shape (n, n)
        The error matrix A - L C as computed.
    L : ndarray, shape (n, p)
    eta : ndarray, shape (p,)
        Each sensor's bound on every sample of its noise.
    rounding_F, rounding_L : float
        Upper bounds of the 2-norm distance of ``F`` and ``L`` from the exact matrices of the
        spec's data (each bounds every entry's distance too).
    max_terms : int
        Largest number of terms summed.

    Returns
    -------
    NoiseGain

    Examples
    --------
    A scalar error e+ = 0.5 e + n, |n| <= 1: eventually |e| <= 2, reached.

    >>> found = linear_noise_bound(np.array([[0.5]]), np.array([[1.0]]), np.array([1.0]))
    >>> round(found.bound_inf, 5), round(found.lower, 5)
    (2.0, 2.0)
    """
    eta = np.asarray(eta, dtype=float)
    # linear in the noise: computed for the bounds over a power of two c >= the largest (exact)
    # so that nothing under- or overflows, and scaled back by c
    top = float(np.max(eta)) if eta.size and np.all(np.isfinite(eta)) else 0.0
    c = MeasurementNoise.scale(top)
    found = _unit_noise_bound(
        F, L, eta / c, rounding_F=rounding_F, rounding_L=rounding_L, max_terms=max_terms
    )
    if found.code is not NoiseGainCode.CERTIFIED:
        return found
    if not np.any(eta):  # no noise, a contraction: every term is exactly 0 (not its rounding)
        zeros = np.zeros_like(found.componentwise)
        return replace(
            found, componentwise=zeros, reached=zeros, bound_2=0.0, bound_inf=0.0, lower=0.0,
            tail=0.0,
        )  # fmt: skip
    if c == 1.0:
        return _in_range(found)
    with np.errstate(over="ignore"):
        up = np.vectorize(lambda x: times_up(float(x), c))
        componentwise = up(found.componentwise) if found.componentwise.size else found.componentwise
        scaled = replace(
            found,
            componentwise=componentwise,
            reached=found.reached * c,
            bound_2=times_up(found.bound_2, c),
            bound_inf=times_up(found.bound_inf, c),
            lower=found.lower * c,
            tail=times_up(found.tail, c),
        )
    return _in_range(scaled)


def balanced_noise_bound(
    F: np.ndarray,
    L: np.ndarray,
    eta: np.ndarray,
    exact_F: Any,
    *,
    rounding_L: float = 0.0,
    max_terms: int = MAX_TERMS,
) -> BalancedNoise | None:
    """``linear_noise_bound`` in balanced state coordinates e = diag(s) e_b (s powers of two
    from LAPACK's balancing of F, exact), written back: |e_i| <= s_i |e_b,i| (the bound and
    the worst case reached, componentwise, exactly; the contraction and the tail are the
    balanced coordinates'); with s and the roundings of F and L the series used there.
    None where F's states need no balancing or L does not scale exactly.  A stable F whose
    states are in units 1e150 apart has powers whose infinity norm no float bound proves
    below 1 in those units.

    ``exact_F`` (an ``ExactMatrix``) gives F's exact value, whose rounding in the balanced
    coordinates is measured on it; ``rounding_L`` bounds ||L - exact||_2, so ||S^-1 (L -
    exact)||_2 <= rounding_L / min(s)."""
    from ..numerics.linalg import state_balancing

    F = np.asarray(F, dtype=float)
    L = np.asarray(L, dtype=float)
    s = state_balancing(F, np.zeros((0, F.shape[0])))
    if s is None:
        return None
    k = np.round(np.log2(s)).astype(np.int64)
    with np.errstate(all="ignore"):
        F_b = F * (s[None, :] / s[:, None])
        L_b = L / s[:, None]
        if not (
            np.all(np.isfinite(F_b))
            and np.array_equal(F_b * (s[:, None] / s[None, :]), F)
            and np.array_equal(L_b * s[:, None], L)
        ):
            return None  # (not exactly representable in the balanced coordinates)

    rounding_F = exact_F.similar(k, "F in balanced state coordinates").rounding(F_b)
    rounding = times_up(rounding_L, float(1.0 / s.min())) if rounding_L else 0.0
    found = linear_noise_bound(
        F_b, L_b, eta, rounding_F=rounding_F, rounding_L=rounding, max_terms=max_terms
    )
    if found.code is not NoiseGainCode.CERTIFIED:
        return BalancedNoise(found, s, rounding_F, rounding)
    with np.errstate(over="ignore"):
        up = np.vectorize(lambda x, c: times_up(float(x), float(c)), otypes=[float])
        componentwise = up(found.componentwise, s) if s.size else found.componentwise
        reached = found.reached * s  # (a lower bound: rounding down keeps it one)
    back = replace(
        found,
        componentwise=componentwise,
        reached=reached,
        bound_2=_norm_up(componentwise) if np.all(np.isfinite(componentwise)) else math.inf,
        bound_inf=float(np.max(componentwise)) if componentwise.size else 0.0,
        lower=float(np.max(reached)) if reached.size else 0.0,
    )
    return BalancedNoise(_in_range(back), s, rounding_F, rounding)


class BalancedNoise(NamedTuple):
    """``balanced_noise_bound``'s bound, written back, and what its series used: the states'
    units s (e = diag(s) e_b) and the roundings of F and L in those coordinates."""

    found: NoiseGain
    scaling: np.ndarray
    rounding_F: float
    rounding_L: float


def tighter_noise_bound(own: NoiseGain, other: NoiseGain) -> NoiseGain:
    """Two certified bounds of the same error (``own`` in the spec's coordinates, ``other``
    written back from balanced ones), componentwise the smaller bound and the larger worst
    case reached; the series' terms, contraction and tail are ``own``'s."""
    with np.errstate(over="ignore"):
        componentwise = np.minimum(own.componentwise, other.componentwise)
        reached = np.maximum(own.reached, other.reached)
    return replace(
        own,
        componentwise=componentwise,
        reached=reached,
        bound_2=min(own.bound_2, other.bound_2, _norm_up(componentwise)),
        bound_inf=float(np.max(componentwise)) if componentwise.size else 0.0,
        lower=float(np.max(reached)) if reached.size else 0.0,
    )


def _in_range(found: NoiseGain) -> NoiseGain:
    """``found``, or out of range where its bounds overflow (a 2-norm or an entry at inf)."""
    if math.isfinite(found.bound_2) and bool(np.all(np.isfinite(found.componentwise))):
        return found
    n = found.componentwise.size
    return NoiseGain(NoiseGainCode.OUT_OF_RANGE, np.full(n, math.inf), np.zeros(n))


def _norm_up(x: np.ndarray) -> float:
    """An upper bound of ||x||_2 (x >= 0) that neither under- nor overflows where its largest
    entry does not (``rows_norm_up``)."""
    return float(rows_norm_up(np.reshape(x, (1, -1)))[0]) if x.size else 0.0


def _unit_noise_bound(
    F: np.ndarray,
    L: np.ndarray,
    eta: np.ndarray,
    *,
    rounding_F: float = 0.0,
    rounding_L: float = 0.0,
    max_terms: int = MAX_TERMS,
) -> NoiseGain:
    """``linear_noise_bound`` for bounds of at most 1."""
    F = np.asarray(F, dtype=float)
    L = np.asarray(L, dtype=float)
    eta = np.asarray(eta, dtype=float)
    n, p = L.shape
    nothing = np.full(n, math.inf)
    finite = all(np.all(np.isfinite(x)) for x in (F, L, eta, np.array([rounding_F, rounding_L])))
    if not finite:
        return NoiseGain(NoiseGainCode.OUT_OF_RANGE, nothing, np.zeros(n))
    RF = np.full_like(F, _up(rounding_F, 1))
    RL = np.full_like(L, _up(rounding_L, 1))
    with np.errstate(over="ignore", invalid="ignore"):
        found = _contraction(F, RF, max_terms)
        if isinstance(found, int):
            return NoiseGain(
                NoiseGainCode.NOT_CONTRACTIVE, nothing, np.zeros(n), facts={"max_terms": found}
            )
        powers, (G, RG), q = found
        m = len(powers)
        # Q_r = F^r L for r < m, side by side: every block of m terms is G^t [Q_0 ... Q_(m-1)]
        blocks = [_product(M, R, L, RL) for M, R in powers]
        QM = np.concatenate([b[0] for b in blocks], axis=1)
        QR = np.concatenate([b[1] for b in blocks], axis=1)
        weights = np.tile(eta, m)
        upper, lower = np.zeros(n), np.zeros(n)
        # sum_{t >= B} G^t Q n <= sum_t ||G^t|| * max_r ||Q_r n||, each term at most q^t
        per_block = float(sum(np.max(_up((np.abs(b[0]) + b[1]) @ eta, p + 2)) for b in blocks))
        M, R = np.eye(n), np.zeros((n, n))  # G^t, exactly G^0
        tail, terms = math.inf, 0
        for _ in range(max(max_terms // m, 1)):
            mid, rad = _product(M, R, QM, QR)
            upper += _up((np.abs(mid) + rad) @ weights, m * p + 2)
            lower += np.maximum(np.abs(mid) - rad, 0.0) @ weights
            terms += m
            M, R = _product(M, R, G, RG)
            norm = float(np.max(_up(np.sum(np.abs(M) + R, axis=1), n)))
            if not math.isfinite(norm):
                break
            tail = _up(norm / (1.0 - q) * per_block, 4)
            if tail <= TAIL_SHARE * float(np.max(upper)) or tail == 0.0:
                break
    if not math.isfinite(tail):
        return NoiseGain(
            NoiseGainCode.NOT_CONTRACTIVE,
            nothing,
            np.zeros(n),
            terms=terms,
            facts={"max_terms": max_terms},
        )
    bound = _up(upper + tail, 2 * terms + 4)
    reached = lower * (1 - gamma(terms * (n + p + 2) + 4))
    return NoiseGain(
        NoiseGainCode.CERTIFIED,
        bound,
        reached,
        bound_2=_norm_up(bound),
        bound_inf=float(np.max(bound)) if n else 0.0,
        lower=float(np.max(reached)) if n else 0.0,
        terms=terms,
        power=m,
        contraction=q,
        tail=float(tail),
    )


def _contraction(
    F: np.ndarray, RF: np.ndarray, limit: int
) -> tuple[list[tuple[np.ndarray, np.ndarray]], tuple[np.ndarray, np.ndarray], float] | int:
    """The intervals of F^0 .. F^(m-1), of G = F^m, and q >= ||F^m||_inf with q < 1: the first
    power whose bound is at most 1/2, else the one whose bound's m-th root is the smallest below
    1; when no power up to ``limit`` is proved below 1 before the intervals grow wide, the number
    of powers examined."""
    n = F.shape[0]
    M, R = np.eye(n), np.zeros((n, n))
    powers = [(M, R)]
    best: tuple[float, int] | None = None
    for r in range(1, min(limit, CONTRACTION_LIMIT) + 1):
        M, R = _product(M, R, F, RF)
        norm = float(np.max(_up(np.sum(np.abs(M) + R, axis=1), n)))
        if not math.isfinite(norm) or norm > 1e100:  # the intervals prove nothing more
            break
        if norm < 1.0 and (best is None or norm ** (1.0 / r) < best[0]):
            best = (norm ** (1.0 / r), r)
        if norm <= 0.5:
            return powers, (M, R), norm
        powers.append((M, R))
    if best is None:
        return len(powers)
    m = best[1]
    q = (
        float(np.max(_up(np.sum(np.abs(powers[m][0]) + powers[m][1], axis=1), n)))
        if m < len(powers)
        else math.inf
    )
    if not q < 1.0:
        return len(powers)
    return powers[:m], powers[m], q


class DissipationBound(NamedTuple):
    """The ultimate error bound a dissipation inequality with decay gives under noise
    (``dissipation_bound``)."""

    bound: float  # inf when none is certified
    noise_norm: float  # N, a bound of |n(k)| on every sample
    top: float  # lambda_max((P^-1)_ee), taken up by its rounding
    condition: float  # of P
    ill_conditioned: bool  # P too ill-conditioned to invert with a known error


def dissipation_bound(
    P: np.ndarray, alpha: float, gamma: float, per_row: np.ndarray, n: int
) -> DissipationBound:
    """limsup |e| <= sqrt(gamma^2 N^2 / alpha * lambda_max((P^-1)_ee)) for a verified
    V+ - V <= -alpha V - |e|^2 + gamma^2 |n|^2 (V = xi' P xi, e the first ``n`` entries of
    xi) and noise within ``per_row`` on each entry of n: computed for the noise over a power
    of two and scaled back, every rounding taken up (the inverse and its eigenvalue to a
    relative 1e-8 of a P with condition number up to 1e8; beyond, none)."""
    rows = per_row.size
    # linear in the noise: N over a power of two c >= the largest bound, scaled back at the end
    top_eta = float(np.max(per_row)) if rows else 0.0
    c = MeasurementNoise.scale(top_eta)
    N2 = float(np.sum((per_row / c) ** 2)) * (1 + 4 * rows * 2.0**-53)
    cond = float(np.linalg.cond(P))
    if not math.isfinite(cond) or cond > 1e8:
        return DissipationBound(math.inf, math.sqrt(N2) * c, math.nan, cond, True)
    inverse = np.linalg.inv(0.5 * (P + P.T))
    block = inverse[:n, :n]
    top = float(np.max(np.linalg.eigvalsh(0.5 * (block + block.T))))
    top *= 1 + 1e-8 * max(cond, 1.0)
    unit = math.sqrt(gamma**2 * N2 / alpha * top) * (1 + 1e-12)
    return DissipationBound(unit * c, math.sqrt(N2) * c, top, cond, False)


# the decays a sparse observer's ultimate bound is tried at: iss_gain's, then 4 times it, and so
# on below 1, while each is verified and the bound falls, then twice and half the best
# (``decay_scan``)
SCAN_SOLVES = 8
SCAN_FACTOR = 2.0
SCAN_START = 1e-2  # below it (4 times over), the scan starts here rather than at iss_gain's decay
# the scan's LMIs are solved only for error models whose one dissipation LMI is estimated
# below this many operations (``lmi_solver.lmi_cost``, block-diagonal P; measured 0.45 s for
# 3.2e10 on this machine, an SSO of 2 states and 5 sensors over a window of 3)
SCAN_OPERATIONS = 4e10
# P's structures tried at each decay: a full cross block between the error and the attack
# estimate first where its LMI is estimated below ``SCAN_CROSS_OPERATIONS`` (a window SSO's
# bound 0.81 against 1.64 with P block-diagonal; 0.44 s a solve there, 2.2 s at 1.7e10), then
# block-diagonal where that is not verified
SCAN_STRUCTURES = ("cross", "block-diagonal")
SCAN_CROSS_OPERATIONS = 5e9


class DecayScan(NamedTuple):
    """The smallest ultimate bound over the decays tried (``decay_scan``)."""

    found: DissipationBound
    alpha: float
    gamma: float
    P: np.ndarray
    multipliers: np.ndarray  # the sector multipliers T of the verified inequality
    tried: list[dict[str, float]]  # each decay tried: alpha and its bound (inf: none verified)


def decaying_certificate(
    model: Any, alpha: float, structures: tuple[str, ...] = ("auto",)
) -> Any | None:
    """``lmi.iss_certificate`` of ``model`` at decay ``alpha``, the structures of P tried in
    turn until one is verified; None where none holds with a positive decay, P and gamma (the
    solver's own failures included)."""
    from ..results import Verdict
    from .lmi import iss_certificate

    cert = None
    for structure in structures:
        try:
            cert = iss_certificate(model, alpha=alpha, structure=structure)
        except (ValueError, np.linalg.LinAlgError):  # the solver's own failures
            cert = None
        if cert is not None and cert.verdict is Verdict.HOLDS:
            break
    if (
        cert is None
        or cert.verdict is not Verdict.HOLDS
        or cert.P is None
        or cert.gamma is None
        or cert.decay is None
        or not cert.decay > 0
    ):
        return None
    return cert


def decay_scan(
    model: Any,
    alpha: float,
    per_row: np.ndarray,
    n: int,
    *,
    solves: int = SCAN_SOLVES,
    bound_of: Callable[[np.ndarray, float, float], DissipationBound] | None = None,
    tried: list[dict[str, float]] | None = None,
) -> DecayScan | None:
    """The smallest ultimate bound under noise within ``per_row`` (``dissipation_bound``) of
    the inequality V+ - V <= -a V + g |n|^2 with decay a = ``alpha``, 4 ``alpha``, 16
    ``alpha`` ... below 1 while each is verified and its bound is smaller (from ``alpha``
    below ``SCAN_START`` / 4: ``SCAN_START``, 4 times it ... and, where ``SCAN_START`` is the
    best, a quarter of it ... down to ``alpha``; from ``alpha`` where ``SCAN_START`` does not
    verify), then twice and half the best, at most ``solves`` in all, each solved and verified as iss_gain's
    certificate is (``lmi.iss_certificate`` of the error model without its output, so that
    the LMI weighs only V's ellipsoid, which the bound rests on; ``SCAN_STRUCTURES``).  None
    where none is verified, or where the model's LMI is too large for several solves
    (``SCAN_OPERATIONS``).

    iss_gain's own certificate, with the output's -|e|^2 and at its one decay, weighs the
    l2 gain from attack to error: the bound it gives under noise is often several times
    this one (on the 2-state test plant's window SSO, 0.245 against 0.065).

    ``bound_of(P, alpha, gamma)`` gives each verified inequality's bound instead of
    ``dissipation_bound`` (``split_bound``'s, the process noise split off).  ``tried``, a
    list, receives each decay tried and its bound (inf: not verified), also when none is."""
    from .lmi_solver import lmi_cost

    quiet = replace(model, Ce=np.zeros_like(model.Ce))
    if lmi_cost(quiet, "iss", "block-diagonal")[1] > SCAN_OPERATIONS:
        return None
    structures = tuple(
        st
        for st in SCAN_STRUCTURES
        if st != "cross" or lmi_cost(quiet, "iss", "cross")[1] <= SCAN_CROSS_OPERATIONS
    )
    tried = [] if tried is None else tried

    def attempt(a: float) -> DecayScan | None:
        """The verified inequality at decay a and its bound (recorded in ``tried``)."""
        cert = decaying_certificate(quiet, a, structures)
        if cert is None:
            tried.append({"alpha": a, "bound": math.inf})
            return None
        P = np.asarray(cert.P, dtype=float)
        decay, gain = float(cert.decay), float(cert.gamma)
        found = (
            dissipation_bound(P, decay, gain, per_row, n)
            if bound_of is None
            else bound_of(P, decay, gain)
        )
        tried.append({"alpha": a, "bound": found.bound})
        if found.ill_conditioned or not math.isfinite(found.bound):
            return None
        t = np.zeros(0) if cert.multipliers is None else np.asarray(cert.multipliers, dtype=float)
        return DecayScan(found, float(cert.decay), float(cert.gamma), P, t, tried)

    def climb(a: float, factor: float, best: DecayScan | None) -> DecayScan | None:
        """Coarse steps of ``factor`` from decay a while each verifies and the bound falls."""
        while len(tried) < solves - 2 and 0 < a < 1 and a >= alpha:
            found = attempt(a)
            if found is None or (best is not None and not found.found.bound < best.found.bound):
                break
            best, a = found, a * factor
        return best

    # coarse steps of SCAN_FACTOR^2 up from iss_gain's decay while the bound falls, then the
    # decays halfway (in logarithm) on either side of the best; from a decay far below
    # SCAN_START (whose bound, 1 / alpha, is far from the best) the climb starts at
    # SCAN_START instead, up and then down to iss_gain's decay, and from iss_gain's decay
    # where SCAN_START does not verify
    best: DecayScan | None = None
    if 0 < alpha < SCAN_START / SCAN_FACTOR**2:
        best = climb(SCAN_START, SCAN_FACTOR**2, None)
        if best is not None and best.alpha == SCAN_START:
            best = climb(SCAN_START / SCAN_FACTOR**2, SCAN_FACTOR**-2, best)
    if best is None:
        best = climb(float(alpha), SCAN_FACTOR**2, None)
    if best is not None:
        for a in (best.alpha * SCAN_FACTOR, best.alpha / SCAN_FACTOR):
            if len(tried) < solves and alpha <= a < 1 and all(d["alpha"] != a for d in tried):
                found = attempt(a)
                if found is not None and found.found.bound < best.found.bound:
                    best = found
    return None if best is None else best._replace(tried=tried)


class LocalBound(NamedTuple):
    """An ultimate error bound under noise that holds in the dead zone's invariant set
    (``local_noise_bound``): from every initial error within ``radius`` (the attack estimate
    0), the error eventually stays within ``bound``."""

    bound: float  # inf when none is certified
    radius: float  # ||e(0)|| within which it holds (0 when none)
    rho: float  # sqrt(V) contracts by at most this per step without noise
    reach: float  # one sample of noise moves sqrt(V) by at most this
    inner: float  # r_min = reach / (1 - rho): sqrt(V)'s ultimate level
    outer: float  # r_max: sqrt(V) up to which the dead zone holds with the noise
    into_dead_zone: float  # the largest reach of the noise into a channel's input
    top: float  # lambda_max((P^-1)_ee), taken up
    top_ee: float  # lambda_max(P_ee), taken up
    condition: float  # of P
    problem: str  # why none is certified ("" when one is)


def local_noise_bound(model: Any, P: np.ndarray, per_row: np.ndarray, n: int) -> LocalBound:
    """The ultimate error bound under noise of an observer certified only near zero error, in
    the dead zone of its nonlinearity, where it is linear: with V = xi' P xi decreasing along
    xi+ = A xi (verified as the region's Lyapunov function is, ``verified_decrease``) and the
    noise a entering as xi+ = A xi + B phi(w) + E a, w = Cw xi + Dw a (``model``), each entry
    of a within ``per_row``.

    In the set sqrt(V) <= r every channel's input satisfies |w_i| <= r sqrt(Cw_i P^-1 Cw_i') +
    sum_j |Dw_ij| per_row_j; while that is at most the threshold, phi(w) = 0 and sqrt(V(xi+))
    <= rho sqrt(V(xi)) + max ||E a||_P (rho^2 <= 1 - lambda_min(P - A' P A) / lambda_max(P)).
    So with r_min = max ||E a||_P / (1 - rho) below the largest such r, r_max, the set sqrt(V)
    <= r_max is invariant, sqrt(V) falls to r_min, and the error eventually satisfies |e| <=
    r_min sqrt(lambda_max((P^-1)_ee)), from every initial error with e(0)' P_ee e(0) <=
    r_max^2, the attack estimate 0.  The model's rounding (``model.rounding``, the floats of
    [A B E; Cw Dw] against the spec's data) is taken into each term, and every product up by
    its rounding; P's inverse to a relative 1e-8 of a P with condition number up to 1e8.
    ``LocalNoise(model, P, n)`` computes what depends on P once, for several noises."""
    return LocalNoise(model, P, n).bound(per_row)


class LocalNoise:
    """``local_noise_bound`` for one model and P: what depends on them (V's decrease and
    contraction, P's inverse, each channel's reach per unit of sqrt(V), E's columns in V's
    norm) computed once; ``bound(per_row)`` for each noise."""

    def __init__(self, model: Any, P: np.ndarray, n: int) -> None:
        from .lyapunov import verified_decrease

        self.model, self.n = model, n
        self.problem, self.known = "", {}
        P = 0.5 * (np.asarray(P, dtype=float) + np.asarray(P, dtype=float).T)
        N = P.shape[0]
        self.eps = eps = float(model.rounding)
        if model.m == 0 or not float(model.threshold) > 0:
            self.problem = "the observer has no dead zone"
            return
        verified = verified_decrease(model.A, P, rounding=eps)
        if verified is None:
            self.problem = "V = xi' P xi is not verified to decrease in the dead zone"
            return
        cond = float(np.linalg.cond(P))
        self.known = {"condition": cond}
        if not math.isfinite(cond) or cond > 1e8:
            self.problem = f"P is too ill-conditioned (condition number {cond:.3g}) to invert"
            return
        dec_min, error = verified
        eigs = np.linalg.eigvalsh(P)
        normP, top_P = float(np.linalg.norm(P, 2)), float(eigs[-1]) * (1 + 64 * N * 2.0**-53)
        low_P = float(eigs[0]) * (1 - 1e-8 * cond)
        rho2 = 1.0 - (dec_min - error) * normP / top_P * (1 - gamma(4))
        self.rho = rho = math.sqrt(max(rho2, 0.0)) * (1 + gamma(4))
        if not rho < 1.0:
            self.problem = "V's decrease leaves no contraction"
            return
        self.known["rho"] = rho
        inverse = np.linalg.inv(P)
        inverse = 0.5 * (inverse + inverse.T)
        slack = 1 + 1e-8 * max(cond, 1.0)
        E, Cw = np.asarray(model.E, float), np.asarray(model.Cw, float)
        self.Dw = np.asarray(model.Dw, float)
        with np.errstate(over="ignore", invalid="ignore"):
            # each column of E in V's norm, and sqrt(lambda_max(E' P E)) (the noise's 2-norm
            # bound's), each quadratic form up by its rounding (gamma(2 N) |x|' |P| |x|)
            absP = np.abs(P)
            forms = np.einsum("ij,jk,ki->i", E.T, P, E) + gamma(2 * N + 2) * np.einsum(
                "ij,jk,ki->i", np.abs(E).T, absP, np.abs(E)
            )
            self.columns = np.sqrt(np.maximum(forms, 0.0)) * (1 + gamma(2))
            gram = E.T @ P @ E
            gram_error = gamma(2 * N + 2) * float(np.linalg.norm(np.abs(E).T @ absP @ np.abs(E), 2))
            top_gram = float(np.linalg.eigvalsh(0.5 * (gram + gram.T))[-1]) if gram.size else 0.0
            top_gram += gram_error + 64 * max(gram.shape[0], 1) * 2.0**-53 * abs(top_gram)
            self.root_gram = math.sqrt(max(top_gram, 0.0))
            self.sqrt_top_P = math.sqrt(top_P)
            # the state's reach into each channel through P^-1 (its rounding in slack), Cw's
            # rounding eps ||xi|| with ||xi|| <= sqrt(V / lambda_min(P))
            spread = (
                np.einsum("ij,jk,ik->i", Cw, inverse, Cw) * slack
                + gamma(2 * N + 2)
                * np.einsum("ij,jk,ik->i", np.abs(Cw), np.abs(inverse), np.abs(Cw))
            ) * slack
            self.per_state = np.sqrt(np.maximum(spread, 0.0)) * (1 + gamma(2)) + eps / math.sqrt(
                low_P
            )
        block = inverse[:n, :n]
        self.top = float(np.max(np.linalg.eigvalsh(0.5 * (block + block.T)))) * slack
        self.top_ee = float(np.max(np.linalg.eigvalsh(P[:n, :n]))) * (1 + 64 * n * 2.0**-53)

    def bound(self, per_row: np.ndarray) -> LocalBound:
        """The bound and its region for a noise with each entry of a within ``per_row``."""
        known = dict(self.known)

        def none(problem: str) -> LocalBound:
            numbers = {k: known.get(k, math.nan) for k in LocalBound._fields[2:-1]}
            return LocalBound(math.inf, 0.0, **numbers, problem=problem)

        if self.problem:
            return none(self.problem)
        eps, rho, threshold = self.eps, self.rho, float(self.model.threshold)
        bounds = np.asarray(per_row, dtype=float)
        with np.errstate(over="ignore", invalid="ignore"):
            noise_2 = float(rows_norm_up(bounds[None, :])[0]) if bounds.size else 0.0
            # max ||E a||_P over the box: each column's P-norm times its bound, summed, and
            # sqrt(lambda_max(E' P E)) ||a||_2; the smaller, with E's rounding (||dE|| ||a||_2)
            by_columns = float(_up(np.sum(self.columns * bounds), bounds.size))
            by_norm = self.root_gram * noise_2 * (1 + gamma(4))
            reach = (min(by_columns, by_norm) + self.sqrt_top_P * eps * noise_2) * (1 + gamma(4))
            # the noise's reach into each channel's input, Dw's rounding eps ||a||_2
            into = _up(np.abs(self.Dw) @ bounds, bounds.size) + eps * noise_2
        finite = math.isfinite(reach) and np.all(np.isfinite(into))
        if not (finite and np.all(np.isfinite(self.per_state))):
            return none("the noise's reach leaves the floating-point range")
        room = threshold - np.max(into) * (1 + gamma(2)) if into.size else threshold
        known.update(reach=reach, into_dead_zone=float(np.max(into, initial=0.0)))
        if not room > 0:
            return none("the noise alone can leave the dead zone")
        # (a channel the state does not reach is bounded by the noise alone: no level)
        per_state = self.per_state
        with np.errstate(over="ignore"):
            levels = np.where(per_state > 0, room / np.where(per_state > 0, per_state, 1.0), np.inf)
        outer = float(np.min(levels)) * (1 - gamma(4))
        inner = reach / (1.0 - rho) * (1 + gamma(4))
        known.update(outer=outer, inner=inner)
        if not inner < outer:
            return none("the noise drives V beyond the dead zone's invariant set")
        bound = inner * math.sqrt(self.top) * (1 + gamma(4))
        radius = outer / math.sqrt(self.top_ee) * (1 - gamma(4))
        return LocalBound(bound, radius, rho, reach, inner, outer, known["into_dead_zone"],
                          self.top, self.top_ee, known["condition"], "")  # fmt: skip


def _process_reach(Pee: np.ndarray, G: np.ndarray, omega: np.ndarray) -> float:
    """W >= max ||G w||_Pee over |w_j| <= omega_j: sum_j omega_j ||G_j||_Pee, each column
    first brought to entries near 1 by a power of two (so that neither G_j' Pee G_j nor its
    product with omega_j under- or overflows where W does not: G of 1e-200 and omega of
    1e197 is the same G w as G of 1 and omega of 1e-3), each quadratic form up by its rounding
    (gamma(2 n) |g|' |Pee| |g|) and the entries a scaling drops below the subnormal range added
    back at their largest."""
    n = Pee.shape[0]
    absP = np.abs(Pee)
    total = 0.0
    for j in range(G.shape[1]):
        column, bound = G[:, j], float(omega[j])
        top = float(np.max(np.abs(column))) if column.size else 0.0
        if top == 0.0 or bound == 0.0:
            continue
        if not (math.isfinite(top) and math.isfinite(bound)):
            return math.inf
        k = -math.frexp(top)[1]  # g = column 2^k has its largest entry in [0.5, 1)
        g = np.ldexp(column, k)
        form = float(g @ Pee @ g) + gamma(2 * n + 2) * float(np.abs(g) @ absP @ np.abs(g))
        # the entries 2^k took into the subnormal range lost at most 2^-1074 each
        form += 2.0**-1070 * n * float(absP.max()) * 4 if k < 0 else 0.0
        norm = math.sqrt(max(form, 0.0)) * (1 + gamma(2))
        mantissa, exponent = math.frexp(bound)
        with np.errstate(over="ignore", under="ignore"):
            reach = float(np.ldexp(norm * mantissa, exponent - k))
        if 0.0 <= reach < 2.0**-1022:  # rounded in the subnormal range (or to 0): take it up
            reach = float(np.nextafter(reach, np.inf))
        total = float(_up(total + reach, 1))
    return total


class SplitBound(NamedTuple):
    """The ultimate error bound with the process noise split off a measurement-noise
    inequality (``split_bound``)."""

    bound: float  # inf when none is certified
    noise_norm: float  # N, a bound of |n(k)| on every sample
    process_reach: float  # W >= max ||G w||_{P_ee} over the process noise's box
    split: float  # the epsilon of the split used
    top: float  # lambda_max((P^-1)_ee), taken up
    condition: float  # of P


def split_as_dissipation(split: SplitBound) -> DissipationBound:
    """A ``split_bound`` as the bound of a dissipation inequality (``decay_scan``'s)."""
    return DissipationBound(split.bound, split.noise_norm, split.top, split.condition,
                            not math.isfinite(split.top))  # fmt: skip


def split_bound(
    P: np.ndarray,
    alpha: float,
    gamma: float,
    per_row: np.ndarray,
    G: np.ndarray,
    omega: np.ndarray,
    n: int,
    *,
    points: int = 400,
) -> SplitBound:
    """limsup |e| under measurement noise within ``per_row`` and process noise w within
    ``omega`` (x+ = A x + G w) from a verified V+ - V <= -alpha V + gamma^2 |n|^2 without
    process noise (V = xi' P xi, e the first ``n`` entries of xi).

    The process noise adds d = (-G w, 0) to the next error state, outside the nonlinearity's
    argument, so for every eps > 0, V(xi+ + d) <= (1 + eps) V(xi+) + (1 + 1/eps) ||d||_P^2
    <= (1 + eps)(1 - alpha) V + (1 + eps) gamma^2 N^2 + (1 + 1/eps) W^2, and with (1 + eps)(1 -
    alpha) < 1, limsup V <= ((1 + eps) gamma^2 N^2 + (1 + 1/eps) W^2) / (1 - (1 + eps)(1 -
    alpha)); |e|^2 <= V lambda_max((P^-1)_ee).  Every eps gives a bound: the smallest over
    ``points`` of them (log-spaced in (0, alpha / (1 - alpha))) is taken, each up by its
    rounding.  W = sum_j omega_j ||G_j||_{P_ee}, the quadratic forms up by their rounding.
    It needs no further LMI, so it holds wherever the measurement-noise inequality does,
    whatever the process noise's size (often looser than an inequality with w as an input)."""
    base = dissipation_bound(P, alpha, gamma, per_row, n)
    nan = math.nan
    if base.ill_conditioned or not math.isfinite(base.bound) or not alpha > 0:
        return SplitBound(math.inf, base.noise_norm, nan, nan, base.top, base.condition)
    W = _process_reach(0.5 * (P[:n, :n] + P[:n, :n].T), np.asarray(G, float), omega)
    # in units of c, a power of two near the larger of gamma N and W (linear in both: the
    # bound scales back by c), the smaller's square taken up where it underflows
    reach_n = gamma * base.noise_norm * (1 + gamma_rounding(2))
    largest = max(reach_n, W)
    if not math.isfinite(largest):
        return SplitBound(math.inf, base.noise_norm, W, nan, base.top, base.condition)
    if largest == 0.0:
        return SplitBound(0.0, base.noise_norm, W, nan, base.top, base.condition)
    c = math.ldexp(1.0, math.frexp(largest)[1])
    tiny = 2.0**-1022
    a = (reach_n / c) ** 2 * (1 + gamma_rounding(4)) + (tiny if reach_n > 0 else 0.0)
    b = (W / c) ** 2 * (1 + gamma_rounding(4)) + (tiny if W > 0 else 0.0)
    beta = max(1.0 - alpha, 0.0)
    if beta == 0.0:  # V+ <= (1 + eps) a + (1 + 1/eps) b for every V: the best eps sqrt(b / a)
        eps = math.sqrt(b / a) if a > 0 and b > 0 else 1.0
        grid = np.array([eps])
    else:
        grid = (alpha / beta) * np.logspace(-6, math.log10(1 - 1e-6), points)
    u = 2.0**-53
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        numerator = ((1 + grid) * a + (1 + 1 / grid) * b) * (1 + 8 * u)
        room = (1 - (1 + grid) * beta) - 8 * u
        values = np.where(room > 0, numerator / room * (1 + 2 * u), np.inf)
    best = int(np.argmin(values))
    V = float(values[best])
    bound = math.inf
    if math.isfinite(V):
        with np.errstate(over="ignore", under="ignore"):
            bound = float(math.sqrt(V * base.top) * (1 + gamma_rounding(4)) * np.float64(c))
        if 0.0 <= bound < 2.0**-1022:  # rounded in the subnormal range: taken up
            bound = float(np.nextafter(bound, np.inf))
    return SplitBound(bound, base.noise_norm, W, float(grid[best]), base.top, base.condition)
