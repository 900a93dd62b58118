"""Certified worst-case error of the l0 decoder under bounded measurement noise.

Over a window of tau steps the stacked measurements are Y = O x + E + N:
O = O_tau, E nonzero on the rows of at most s attacked sensors (anything
there), N the noise, bounded on every sensor i either entrywise
(``norm = "inf"``: |N_i(k)| <= eta_i at every step) or as a block
(``norm = "2"``: ||N_i||_2 <= eta_i over the window).  The l0 decoder
(``ssecert.estimators.l0_decoder``, what Imhotep-SMT returns) picks the
support T_hat of s sensors and the state x_hat whose residual on the other
sensors is smallest.

The bound.  Let T be the attacked sensors and K = (T u T_hat)^c: at least
p - 2s sensors, none attacked in either explanation.  Then

    ||O_K (x_hat - x)|| <= ||(Y - O x_hat)_K|| + ||N_K||
                        <= ||(Y - O x)_{T^c}|| + ||N_K|| = ||N_{T^c}|| + ||N_K||,

the middle step by the decoder's optimality (its residual is at most the
true state's on T^c).  T^c is K and at most s other sensors, so with
sigma_K = sigma_min(O_K) and, for each K of exactly p - 2s sensors (a
larger K only raises sigma_min),

    bound(K) = (sqrt(n_K^2 + m_K^2) + n_K) / sigma_K,

n_K the largest ||N_K|| (sqrt(tau) ||eta_K||_2 entrywise, ||eta_K||_2 for
blocks) and m_K that of the s noisiest sensors outside K, every error
x_hat - x has ||x_hat - x||_2 <= max_K bound(K).  The set K that attains
the maximum is the set to harden: the bound is also reported with its
sensors' noise halved.

The lower bound.  For the worst K, with v its smallest right singular
vector and c the largest scale with c |O_i v| / 2 within sensor i's bound
for every i in K, the data of x (attack on s of the 2s sensors outside K,
noise c O_K v / 2 on K) equal those of x + c v (attack on the other s,
noise -c O_K v / 2): no decoder can tell them apart, so none guarantees an
error below c / 2 (``worst_case_pair`` builds them).

Rigour.  The Gramians O_K' O_K are formed and their smallest eigenvalues
computed in floating point; every sigma_K used is a lower bound of the
exact plant's (the spec's A and C): LAPACK's backward error, the rounding
of the Gramian and of the powers C A^k (an a-priori bound) are taken off.
The sets with the largest bounds are then decided by an SVD of O_K, with
its own error taken off.  The reported bound is rounded up and re-checked
in rational arithmetic from the printed numbers.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from fractions import Fraction
from typing import Any

import numpy as np

from ..base.validation import as_int_option
from ..noise import MeasurementNoise
from ..system import System
from ..tolerances import gamma, times_up
from ._combinatorics import count_subsets

__all__ = [
    "BoundCode",
    "DecoderErrorBound",
    "decoder_error_bound",
    "with_sources",
    "worst_case_pair",
]

DEFAULT_MAX_SETS = 5_000_000  # sets of p - 2s sensors screened
_REFINED = 64  # sets decided by an SVD, the largest bounds first
DIRECT_SETS = 20_000  # up to this many sets every one is evaluated; beyond, they are screened
_SAMPLE = 256  # sets sampled for the screening's first bound
_FAILURES = 20_000  # sets the screening may leave to evaluate
_SCREENINGS = 6
# sets tried for the lower bound: those with the largest bounds, those with the smallest sigma
_PAIRS = 8
#: the scales of the worst set's noise in ``DecoderErrorBound.curve``
HARDENING = (0.0, 0.25, 0.5, 0.75, 1.0)
_U = 2.0**-53

# (sensors, scale) -> the noise bounds with those sensors' measurement noise times the scale
Soften = Callable[[list[int], float], np.ndarray]


class BoundCode(enum.Enum):
    """How a decoder error bound came out."""

    #: a finite bound, certified for the exact plant
    CERTIFIED = "certified"
    #: every set of p - 2s sensors has full rank only within rounding: no finite bound proved
    NO_MARGIN = "no margin"
    #: 2s >= p: no set of sensors is left unattacked in both explanations
    TOO_FEW_SENSORS = "too few sensors"
    #: more sets of p - 2s sensors than the limit
    TOO_MANY_SETS = "too many sets"
    #: the data or the bounds leave the floating-point range
    OUT_OF_RANGE = "out of range"
    #: the printed bound did not survive its rational re-check (please report the plant)
    RECHECK_FAILED = "re-check failed"
    #: a set of at most 2s sensors breaks observability (sparse_observability's breaking set,
    #: in ``facts``): two states explain the same data even without noise, no bound exists
    NOT_SPARSE_OBSERVABLE = "not 2s-sparse observable"
    #: the kept sensors ``worst_kept`` over the window do not determine the state, exactly
    #: (``facts["rank"]`` < n): the window is too short or the sensors too few, no bound exists
    WINDOW_TOO_SHORT = "window too short"


@dataclass(frozen=True)
class DecoderErrorBound:
    """The worst-case error of the l0 decoder over a window under bounded noise and at most s
    attacked sensors (``decoder_error_bound``).

    Attributes
    ----------
    code : BoundCode
    bound : float
        Certified: ||x_hat - x||_2 <= bound for every attack on at most s sensors and every
        noise within its bounds (inf when none is certified).
    lower : float
        No decoder guarantees an error below this (``worst_case_pair`` on ``lower_kept``);
        0 when not built.
    lower_kept : tuple of int
        The p - 2s sensors of that construction.
    worst_kept : tuple of int
        The p - 2s sensors K whose bound(K) is the largest: the set to harden.
    sigma : float
        The certified lower bound of sigma_min(O_K) for that set.
    smallest_sigma : float
        The certified lower bound of min over every K of sigma_min(O_K).
    smallest_kept : tuple of int
        The set with the smallest sigma_min among those evaluated (beyond
        ``DIRECT_SETS`` sets, the others are screened: their sigma_min is at least
        ``smallest_sigma``).
    hardened : float
        The bound with the noise of ``worst_kept``'s sensors halved.
    curve : tuple of (float, float)
        (f, the bound with the noise of ``worst_kept``'s sensors times f) for f in
        ``HARDENING``: what hardening that set gives.
    noise : MeasurementNoise
        The per-sensor bounds the bound is certified for: the spec's noise, or with process
        noise what it adds up to at the sensors over the window (``sources``).
    horizon, max_attacked : int
    sets : int
        Sets of p - 2s sensors.
    evaluated : int
        Sets whose sigma_min was computed (every one up to ``DIRECT_SETS``; beyond, those the
        Cholesky screening left, and a sample).
    refined : int
        Sets decided by an SVD.
    facts : mapping
        Numbers the words need (a limit, the data's largest entry).
    sources : MeasurementNoise or None
        The spec's noise with its process noise, when ``noise`` is what it adds up to at
        the sensors (``MeasurementNoise.at_sensors``); None when ``noise`` is the spec's.
    """

    code: BoundCode
    bound: float
    lower: float
    noise: MeasurementNoise
    horizon: int
    max_attacked: int
    worst_kept: tuple[int, ...] = ()
    sigma: float = 0.0
    smallest_sigma: float = 0.0
    smallest_kept: tuple[int, ...] = ()
    hardened: float = math.inf
    curve: tuple[tuple[float, float], ...] = ()
    sets: int = 0
    evaluated: int = 0
    refined: int = 0
    lower_kept: tuple[int, ...] = ()
    facts: dict[str, Any] = field(default_factory=dict)
    sources: MeasurementNoise | None = None

    @property
    def realizable(self) -> MeasurementNoise:
        """The noise the lower bound's construction keeps within: ``noise``, or with process
        noise (``sources``) its measurement noise alone (the process noise's reach at the
        sensors is not a noise every sensor can take independently)."""
        return self.noise if self.sources is None else self.sources.measurement_only()


def _block_errors(system: System, horizon: int) -> np.ndarray:
    """(p,) upper bounds of ||fl(O_i) - O_i||_F: the rounding of the rows C_i A^k as
    ``System.sensor_blocks`` forms them (k products by A, each with the error of an inner
    product of length n: |fl(c A^k) - c A^k| <= ((1 + gamma_n)^k - 1) |c| |A|^k)."""
    n = system.n
    absA, row = np.abs(system.A), np.abs(system.C)
    out = np.zeros(system.p)
    growth = 1.0 + gamma(n + 2)
    for k in range(horizon):
        if k:
            row = row @ absA
            factor = growth**k - 1.0
            out += (factor * (1 + 1e-6)) ** 2 * np.sum(row**2, axis=1)
    return np.sqrt(out) * (1 + 1e-6)


def _kept_sets(p: int, removed: int) -> np.ndarray:
    """Every set of ``removed`` sensors, in lexicographic order, shape (C(p, removed), removed)."""
    import itertools

    sets = list(itertools.combinations(range(p), removed))
    return np.array(sets, dtype=np.int64).reshape(len(sets), removed)


def _sigma_lower_from_gramians(
    blocks: np.ndarray, removed: np.ndarray, chunk: int = 4096
) -> tuple[np.ndarray, np.ndarray]:
    """Lower bounds of sigma_min(fl(O_K)) for K the complement of each row of ``removed``, from
    the smallest eigenvalue of the Gramian (the sum of the kept blocks' Gramians), with the
    Gramian's rounding and LAPACK's backward error taken off; and the computed values."""
    p, tau, n = blocks.shape
    grams = np.einsum("ikn,ikm->inm", blocks, blocks)
    total = grams.sum(axis=0)
    frob = np.sum(blocks**2, axis=(1, 2))  # ||O_i||_F^2
    low = np.empty(removed.shape[0])
    value = np.empty(removed.shape[0])
    for start in range(0, removed.shape[0], chunk):
        rows = removed[start : start + chunk]
        G = total - grams[rows].sum(axis=1)
        lam = np.linalg.eigvalsh(G)[:, 0]
        kept_frob = frob.sum() - frob[rows].sum(axis=1)
        # forming each Gramian block (tau-term sums) and the sum of all minus the removed ones
        # (p + 2s terms) rounds by at most gamma(tau + p + 2 + 2s) times the sum of the terms'
        # absolute values, whose norm is at most the sum of ||O_i||_F^2 over every sensor;
        # LAPACK's eigenvalues are those of a matrix within 64 n u ||G|| of the one given
        error = (gamma(tau + p + rows.shape[1] + 2) * frob.sum() + 64 * n * _U * kept_frob) * (
            1 + 1e-6
        )
        value[start : start + chunk] = np.sqrt(np.maximum(lam, 0.0))
        low[start : start + chunk] = np.sqrt(np.maximum(lam - error, 0.0))
    return low, value


def _sigma_lower_svd(blocks: np.ndarray, kept: Sequence[int] | np.ndarray) -> float:
    """A lower bound of sigma_min(fl(O_K)) from its SVD (backward stable: within
    gamma(c max(m, n)) ||O_K||_2 of the exact singular values)."""
    O_K = blocks[list(kept)].reshape(-1, blocks.shape[2])
    sv = np.linalg.svd(O_K, compute_uv=False)
    if sv.size < blocks.shape[2]:
        return 0.0
    error = 64 * max(O_K.shape) * _U * float(sv[0]) * (1 + 1e-6)
    return max(float(sv[-1]) - error, 0.0)


def _noise_terms(block: np.ndarray, removed: np.ndarray, s: int) -> tuple[np.ndarray, np.ndarray]:
    """(n_K, m_K) of every K (the complement of each row of ``removed``), each rounded up: the
    largest ||N_K||, and the largest ||N|| of s sensors outside K (the s noisiest of the
    removed ones)."""
    p = block.size
    sq = block**2
    mask = np.ones((removed.shape[0], p), dtype=bool)
    np.put_along_axis(mask, removed, False, axis=1)
    up = 1.0 + gamma(p + 4)  # the squares, their sum and the square root, rounded
    n_K = np.sqrt(np.where(mask, sq, 0.0).sum(axis=1) * up) * up
    outside = np.sort(sq[removed], axis=1)[:, ::-1][:, :s]
    m_K = np.sqrt(outside.sum(axis=1) * up) * up
    return n_K, m_K


def _bound_of(n_K: Any, m_K: Any, sigma: Any) -> Any:
    """bound(K), rounded up (each of its few operations by a unit in the last place)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        value = (np.sqrt(n_K**2 + m_K**2) + n_K) / sigma * (1.0 + gamma(8))
    return np.where(np.asarray(sigma) > 0, value, np.inf)


def _evaluate(
    blocks: np.ndarray, errors: np.ndarray, block: np.ndarray, removed: np.ndarray, s: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]:
    """(sigma, bound, n_K, m_K, sets refined) of the sets K left by each row of ``removed``:
    sigma a lower bound of sigma_min of the exact plant's O_K, from the Gramians, the largest
    bounds decided again by an SVD (sharper where the Gramian squares the condition number)
    until the best refined one is above every set left."""
    p = blocks.shape[0]
    low, _ = _sigma_lower_from_gramians(blocks, removed)
    # the exact plant's O_K is within ||errors_K|| of the computed one
    err_K = np.sqrt(np.maximum((errors**2).sum() - (errors[removed] ** 2).sum(axis=1), 0.0))
    sigma = np.maximum(low - err_K, 0.0)
    n_K, m_K = _noise_terms(block, removed, s)
    bounds = _bound_of(n_K, m_K, sigma)
    order = np.argsort(-bounds, kind="stable")
    refined = 0
    for j in order[:_REFINED]:
        kept = np.setdiff1d(np.arange(p), removed[j])
        better = max(_sigma_lower_svd(blocks, kept) - float(err_K[j]), 0.0)
        refined += 1
        if better > sigma[j]:
            sigma[j] = better
            bounds[j] = _bound_of(n_K[j], m_K[j], better)
        rest = order[refined:]
        if rest.size == 0 or bounds[rest].max() <= bounds[order[:refined]].max():
            break
    return sigma, bounds, n_K, m_K, refined


def _screened_candidates(
    blocks: np.ndarray, errors: np.ndarray, block: np.ndarray, s: int
) -> tuple[np.ndarray, float]:
    """The removed sets (rows, sorted) whose bound may be the largest, with a sample whose
    largest bound B every other set is proved not to exceed.

    A sample of sets gives B; every set's Gramian minus t^2 I is then screened by the
    enumeration's Cholesky kernel (``ColexScreen``: LAPACK's decisions), t chosen so that a
    set that passes has sigma_min of the exact plant's O_K at least num / B, num >= every
    set's noise term: its bound is at most B.  The sets that fail are returned with the
    sample; when too many fail, B is raised to the largest bound among them and the screening
    repeated.  Returns the candidates and t' (every other set has sigma_min >= t'), 0 when
    every set is a candidate."""
    p, tau, n = blocks.shape
    k = 2 * s
    rng = np.random.default_rng(0)
    sample = np.sort(
        np.array([rng.choice(p, k, replace=False) for _ in range(_SAMPLE)], dtype=np.int64),
        axis=1,
    )
    sample = np.unique(sample, axis=0)
    _, bounds, _, _, _ = _evaluate(blocks, errors, block, sample, s)
    sq = np.sort(block**2)[::-1]
    up = 1.0 + gamma(p + 8)
    num = (math.sqrt(sq[: p - s].sum() * up) + math.sqrt(sq[: p - k].sum() * up)) * up
    highest = float(np.max(bounds))
    for _ in range(_SCREENINGS):
        if not math.isfinite(highest) or highest <= 0:
            break
        floor = num / highest
        failed = _screen_failures(blocks, errors, k, floor, _FAILURES)
        if failed.shape[0] < _FAILURES:
            return np.unique(np.concatenate([sample, failed]), axis=0), floor
        # too many below: the largest bound among those found, or a quarter more
        _, more, _, _, _ = _evaluate(blocks, errors, block, failed, s)
        highest = max(highest * 1.25, float(np.max(more)))
    # the screening did not narrow the sets down: every set is a candidate
    return _kept_sets(p, k), 0.0


def _screen_failures(
    blocks: np.ndarray, errors: np.ndarray, k: int, target: float, limit: int
) -> np.ndarray:
    """The sets of k removed sensors (rows) whose kept sensors' O_K the screening cannot prove
    to have sigma_min >= ``target`` for the exact plant: LAPACK's Cholesky factorization of
    the Gramian minus t^2 I fails, t^2 = (target + the O's rounding)^2 + every rounding of the
    Gramians, of their sums and LAPACK's backward error.  At most ``limit`` rows (the first
    ones found) when more fail."""
    from ..numerics.linalg import single_precision_margin
    from ._combinatorics import ColexScreen

    p, tau, n = blocks.shape
    grams = np.einsum("ikn,ikm->inm", blocks, blocks)
    total = grams.sum(axis=0)
    frob_items = float(np.linalg.norm(grams, axis=(1, 2)).sum())
    trace = float(np.abs(np.trace(total)))
    squares = float(np.sum(blocks**2))
    rounding = (
        gamma(k + 4) * (float(np.linalg.norm(total)) + frob_items)  # the sums of Gramians
        + gamma(tau + 2) * squares  # each Gramian from its blocks
        + 100 * gamma(4 * n + 4) * (trace + n * (target + 1.0) ** 2)  # LAPACK's backward error
    )
    err_O = float(np.sqrt(np.sum(errors**2)))
    shift = ((target + err_O) ** 2 + 2.0 * rounding) * (1 + 1e-9)
    base = total - shift * np.eye(n)
    margin = float(
        single_precision_margin(
            n,
            1.01 * (np.abs(np.diagonal(base)).sum() + n * shift),
            1.01 * (float(np.linalg.norm(base)) + frob_items),
            terms=k,
        )
    )
    source = ColexScreen(grams, base, k, margin)
    size = 4096
    work = np.empty((n, n, size), dtype=np.float32)
    diagonal = np.empty((n, size), dtype=np.float32)
    found: list[np.ndarray] = []
    count = 0
    for first, last in source.batches(size):
        screen = source.screen(first, last, shift, None, work, diagonal)
        bad = first + screen.failed()
        if bad.size:
            found.append(source.subsets(bad))
            count += bad.size
            if count >= limit:
                break
    if not found:
        return np.zeros((0, k), dtype=np.int64)
    return np.concatenate(found)[:limit]


def _times_down(x: float, c: float) -> float:
    """x times the power of two c, rounded down where the product is subnormal (a lower
    bound stays one)."""
    y = x * c
    return float(np.nextafter(y, 0.0)) if 0 < y < 2.0**-1022 else y


def window_inputs(
    system: System, max_attacked: Any, noise: MeasurementNoise, horizon: Any
) -> tuple[int, int]:
    """s and tau of a decoder bound, checked (tau defaults to n), and the noise's bounds
    checked against the plant's sensors."""
    s = as_int_option(max_attacked, "max_attacked", min_value=0)
    tau = system.n if horizon is None else as_int_option(horizon, "horizon", min_value=1)
    if noise.eta.shape != (system.p,):
        raise ValueError(f"noise: {noise.eta.size} bounds for {system.p} sensors")
    return s, tau


def decoder_error_bound(
    system: System,
    max_attacked: int,
    noise: MeasurementNoise,
    *,
    horizon: int | None = None,
    max_sets: int = DEFAULT_MAX_SETS,
    sources: MeasurementNoise | None = None,
) -> DecoderErrorBound:
    """The certified worst-case estimation error of the l0 decoder over a window.

    Parameters
    ----------
    system : System
    max_attacked : int
        s, the largest number of attacked sensors.
    noise : MeasurementNoise
        Per-sensor bounds of the measurement noise.
    horizon : int, optional
        tau, the window (default n).
    max_sets : int, default 200,000
        Largest number of sets of p - 2s sensors examined.
    sources : MeasurementNoise, optional
        The measurement and process noise whose bounds at the sensors ``noise`` is
        (``MeasurementNoise.at_sensors`` over the window): the hardening curve then scales
        the measurement noise of the set to harden and keeps the process noise's reach
        (hardening a sensor does not quiet the plant).

    Returns
    -------
    DecoderErrorBound

    Examples
    --------
    Three sensors of one state, one attacked, noise at most 0.1 on each: the
    bound (sqrt(2) + 1) 0.1 and no decoder guarantees better than 0.1.

    >>> import numpy as np
    >>> from ssecert import System
    >>> plant = System(np.eye(1), np.ones((3, 1)))
    >>> found = decoder_error_bound(plant, 1, MeasurementNoise.uniform(0.1, 3), horizon=1)
    >>> round(found.bound, 6), round(found.lower, 6), found.worst_kept
    (0.241421, 0.1, (0,))
    """
    soften = (
        None
        if sources is None
        else _softened(system, sources, window_inputs(system, max_attacked, noise, horizon)[1])
    )
    found = _bound_in_units(system, max_attacked, noise, horizon, max_sets, soften)
    if found.code is BoundCode.OUT_OF_RANGE:
        # the data in other units: every sensor's rows and noise bounds divided by the power of
        # two that brings C's largest entry into [1, 2) (the same decoding problem, so the
        # same errors; its Gramians in range where the spec's would overflow or underflow)
        units = _sensor_units(system, noise)
        if units is not None:
            again = _bound_in_units(
                units[0], max_attacked, units[1], horizon, max_sets, soften, units[2]
            )
            if again.code is BoundCode.CERTIFIED:  # (else the spec's data's own reason)
                back = _in_spec_units(system, again, noise, units[2])
                if back is not None:
                    return back
    return found


def _softened(system: System, sources: MeasurementNoise, tau: int) -> Soften:
    """The per-sample bounds at the sensors (``MeasurementNoise.at_sensors``) with the
    measurement noise of the given sensors times a scale, the process noise as it is."""

    def seen(sensors: list[int], scale: float) -> np.ndarray:
        eta = sources.eta.copy()
        eta[sensors] *= scale
        out = replace(sources, eta=eta).at_sensors(system.A, system.C, tau)
        return np.full(eta.size, np.inf) if out is None else out.eta

    return seen


def _sensor_units(
    system: System, noise: MeasurementNoise
) -> tuple[System, MeasurementNoise, int] | None:
    """(the plant with C / 2^d, the noise bounds / 2^d, d), d the exponent that brings C's
    largest entry into [1, 2); None when d = 0 or a division is not exact (subnormal)."""
    top = float(np.max(np.abs(system.C))) if system.C.size else 0.0
    d = math.frexp(top)[1] - 1 if top > 0 and math.isfinite(top) else 0
    with np.errstate(all="ignore"):  # (an overflow or underflow: not exact, None)
        C, eta = np.ldexp(system.C, -d), np.ldexp(noise.eta, -d)
        exact = np.array_equal(np.ldexp(C, d), system.C) and np.array_equal(
            np.ldexp(eta, d), noise.eta
        )
    if d == 0 or not exact:
        return None
    return replace(system, C=C), MeasurementNoise(eta, noise.norm), d


def _in_spec_units(
    system: System, found: DecoderErrorBound, noise: MeasurementNoise, d: int
) -> DecoderErrorBound | None:
    """A certified ``found`` for the plant in units 2^-d (``_sensor_units``) in the spec's:
    the errors are the same, the singular values 2^d times, the noise the spec's; re-checked
    there.  None when a singular value leaves the float range in the spec's units."""
    with np.errstate(all="ignore"):
        sigma = float(np.ldexp(found.sigma, d))
        smallest = float(np.ldexp(found.smallest_sigma, d))
    if not (math.isfinite(sigma) and math.isfinite(smallest)):
        return None
    back = replace(
        found,
        noise=noise,
        sigma=sigma,
        smallest_sigma=smallest,
        facts={**found.facts, "sensor_scale": math.ldexp(1.0, d)},
    )
    exact = sigma_rechecks(system, back)
    back = replace(back, facts={**back.facts, "sigma_rechecked_exactly": exact})
    if not bound_rechecks(back) or exact is False:
        return replace(back, code=BoundCode.RECHECK_FAILED)
    return back


def _bound_in_units(
    system: System,
    max_attacked: int,
    noise: MeasurementNoise,
    horizon: int | None,
    max_sets: int,
    soften: Soften | None = None,
    exponent: int = 0,
) -> DecoderErrorBound:
    """``decoder_error_bound`` on the data in the units given (C and the noise 2^exponent
    times smaller than the spec's, which ``soften`` gives its bounds in)."""
    s, tau = window_inputs(system, max_attacked, noise, horizon)
    p = system.p
    # the bound is linear in the noise: computed for the bounds over a power of two c >= the
    # largest (exactly), so that no square under- or overflows, and scaled back by c
    top = float(np.max(noise.eta)) if p else 0.0
    c = MeasurementNoise.scale(top)
    unit = MeasurementNoise(noise.eta / c if top > 0 else np.ones(p), noise.norm)
    unit_soften: Soften | None = None
    if soften is not None and top > 0:

        def unit_soften(sensors: list[int], scale: float) -> np.ndarray:
            eta = np.ldexp(soften(sensors, scale), -exponent) / c
            return MeasurementNoise(eta, noise.norm).block_bounds(tau)

    found = _bound_of_unit_noise(system, s, unit, tau, max_sets, unit_soften)
    found = replace(found, noise=noise, facts={**found.facts, "noise_scale": c})
    if found.code is not BoundCode.CERTIFIED:
        return found
    if top == 0:  # no noise: the margins were checked with unit bounds, the error is 0
        return replace(
            found, bound=0.0, lower=0.0, hardened=0.0, curve=tuple((f, 0.0) for f, _ in found.curve)
        )
    with np.errstate(over="ignore"):
        scaled = replace(
            found,
            bound=times_up(found.bound, c),
            lower=_times_down(found.lower, c),
            hardened=times_up(found.hardened, c),
            curve=tuple((f, times_up(b, c)) for f, b in found.curve),
        )
    if not math.isfinite(scaled.bound):
        return replace(scaled, code=BoundCode.OUT_OF_RANGE, bound=math.inf)
    if not bound_rechecks(scaled):
        return replace(scaled, code=BoundCode.RECHECK_FAILED)
    return scaled


def _bound_of_unit_noise(
    system: System,
    s: int,
    noise: MeasurementNoise,
    tau: int,
    max_sets: int,
    soften: Soften | None = None,
) -> DecoderErrorBound:
    """``decoder_error_bound`` for bounds of at most 1 (``soften``: the block bounds with
    some sensors' measurement noise scaled, in the same units)."""
    p = system.p
    base: dict[str, Any] = {"noise": noise, "horizon": tau, "max_attacked": s}
    removed_size = 2 * s
    if removed_size >= p:
        return DecoderErrorBound(BoundCode.TOO_FEW_SENSORS, math.inf, 0.0, **base)
    sets = count_subsets(p, [removed_size])
    if sets > max_sets:
        return DecoderErrorBound(
            BoundCode.TOO_MANY_SETS, math.inf, 0.0, sets=sets, facts={"limit": max_sets}, **base
        )
    with np.errstate(all="ignore"):
        blocks = system.sensor_blocks(tau)
        finite = bool(np.all(np.isfinite(blocks))) and bool(np.isfinite(np.sum(blocks**2)))
    if not finite or not np.isfinite(np.sum(noise.block_bounds(tau) ** 2)):
        return DecoderErrorBound(BoundCode.OUT_OF_RANGE, math.inf, 0.0, sets=sets, **base)
    errors = _block_errors(system, tau)
    block = noise.block_bounds(tau)
    floor = 0.0  # sigma_min of every set not evaluated is at least this
    if sets <= DIRECT_SETS:
        removed = _kept_sets(p, removed_size)
    else:
        removed, floor = _screened_candidates(blocks, errors, block, s)
    sigma, bounds, n_K, m_K, refined = _evaluate(blocks, errors, block, removed, s)
    screened = removed.shape[0] < sets
    # the sets not evaluated: bound(K) <= (the largest noise term) / floor, below the largest
    # evaluated bound by the screening's construction; kept as a guard all the same
    sq = np.sort(block**2)[::-1]
    up = 1.0 + gamma(p + 8)
    num_hi = (math.sqrt(sq[: p - s].sum() * up) + math.sqrt(sq[: p - removed_size].sum() * up)) * up
    guard = _rounded_up(num_hi / floor) if screened and floor > 0 else 0.0
    # ties go to the lexicographically first kept set (the last removed set of the order)
    last = bounds.size - 1
    worst = last - int(np.argmax(bounds[::-1]))
    weakest = last - int(np.argmin(sigma[::-1]))
    kept_of = lambda j: tuple(int(i) for i in np.setdiff1d(np.arange(p), removed[j]))  # noqa: E731
    if not np.isfinite(bounds[worst]):
        from ..numerics.exact import Observability, exact_stacked_rank

        kept = kept_of(worst)
        rows = [t * p + i for t in range(tau) for i in kept]
        decision = exact_stacked_rank(system.A, system.C, rows, tau)
        deficient = decision.state is Observability.UNOBSERVABLE
        return DecoderErrorBound(
            BoundCode.WINDOW_TOO_SHORT if deficient else BoundCode.NO_MARGIN,
            math.inf,
            0.0,
            worst_kept=kept,
            smallest_kept=kept_of(weakest),
            sets=sets,
            refined=refined,
            facts={"rank": decision.rank_mod_p} if deficient else {},
            **base,
        )
    bound = max(_rounded_up(float(bounds[worst])), guard)

    def softer(scale: float) -> np.ndarray:
        sensors = list(kept_of(worst))
        if soften is not None:
            return soften(sensors, scale)
        out = block.copy()
        out[sensors] *= scale
        return out

    hardened = _bound_with(softer(0.5), removed, s, sigma, floor, up)
    smallest = float(sigma[weakest]) if not screened else min(float(sigma[weakest]), floor)
    curve = tuple(
        (scale, _bound_with(softer(scale), removed, s, sigma, floor, up)) for scale in HARDENING
    )
    found = DecoderErrorBound(
        BoundCode.CERTIFIED,
        bound,
        0.0,
        worst_kept=kept_of(worst),
        sigma=float(sigma[worst]),
        smallest_sigma=smallest,
        smallest_kept=kept_of(weakest),
        hardened=hardened,
        curve=curve,
        sets=sets,
        evaluated=int(removed.shape[0]),
        refined=refined,
        **base,
    )
    exact = sigma_rechecks(system, found)
    found = replace(found, facts={**found.facts, "sigma_rechecked_exactly": exact})
    if not bound_rechecks(found) or exact is False:
        return replace(found, code=BoundCode.RECHECK_FAILED)
    # the lower bound: the best pair over the sets with the largest bounds and the smallest
    # singular values
    candidates = dict.fromkeys(
        [int(j) for j in np.argsort(-bounds, kind="stable")[:_PAIRS]]
        + [int(j) for j in np.argsort(sigma, kind="stable")[:_PAIRS]]
    )
    best = 0.0
    best_kept: tuple[int, ...] = ()
    for j in candidates:
        pair = worst_case_pair(system, replace(found, lower_kept=kept_of(j)))
        if pair is not None and pair["lower"] > best:
            best, best_kept = float(pair["lower"]), kept_of(j)
    return replace(found, lower=best, lower_kept=best_kept)


def with_sources(
    system: System, found: DecoderErrorBound, sources: MeasurementNoise
) -> DecoderErrorBound:
    """``found``, certified for the noise ``sources`` adds up to at the sensors
    (``MeasurementNoise.at_sensors``), with its sources, and its lower bound rebuilt within
    their measurement noise alone (``worst_case_pair`` on the sets of the bound's own lower
    bound, of the largest bound and of the smallest singular value): the process noise's
    reach is not a noise each sensor can take on its own."""
    candidates = dict.fromkeys((found.lower_kept, found.worst_kept, found.smallest_kept))
    found = replace(found, sources=sources, lower=0.0, lower_kept=())
    if found.code is not BoundCode.CERTIFIED:
        return found
    best: float = 0.0
    best_kept: tuple[int, ...] = ()
    for kept in candidates:
        pair = worst_case_pair(system, replace(found, lower_kept=kept)) if kept else None
        if pair is not None and pair["lower"] > best:
            best, best_kept = float(pair["lower"]), kept
    return replace(found, lower=best, lower_kept=best_kept)


def _bound_with(
    softer: np.ndarray,
    removed: np.ndarray,
    s: int,
    sigma: np.ndarray,
    floor: float,
    up: float,
) -> float:
    """The certified bound for the block bounds ``softer`` (some sensors' noise scaled): the
    largest over the evaluated sets, and over the others (sigma_min >= ``floor``, 0 when
    there are none) the largest noise term over ``floor``."""
    n_h, m_h = _noise_terms(softer, removed, s)
    value = _rounded_up(float(np.max(_bound_of(n_h, m_h, sigma))))
    if floor > 0:
        p = softer.size
        sq = np.sort(softer**2)[::-1]
        num = (math.sqrt(sq[: p - s].sum() * up) + math.sqrt(sq[: p - 2 * s].sum() * up)) * up
        value = max(value, _rounded_up(num / floor))
    return value


def _rounded_up(x: float) -> float:
    """x a few units in the last place up (the bound's own rounding)."""
    return float(np.nextafter(np.nextafter(x * (1 + 4 * _U), np.inf), np.inf))


def _sqrt_upper(q: Fraction) -> Fraction:
    """A rational r >= sqrt(q): sqrt(a / b) = sqrt(a b) / b <= (isqrt(a b) + 1) / b, with
    the numerator and denominator shifted by an even power of two for 60 digits to spare."""
    if q <= 0:
        return Fraction(0)
    a, b = q.numerator, q.denominator
    shift = max(0, 200 - (a * b).bit_length() // 2)  # digits to spare, whatever q's size
    return Fraction(math.isqrt(a * b * 4**shift) + 1, b * 2**shift)


def bound_rechecks(found: DecoderErrorBound) -> bool:
    """Whether the printed bound, times the printed sigma, is at least sqrt(n_K^2 + m_K^2) +
    n_K in rational arithmetic (n_K and m_K recomputed exactly from the printed bounds)."""
    block = [Fraction(float(b)) for b in found.noise.eta]
    tau = found.horizon
    kept = set(found.worst_kept)
    weight = Fraction(tau) if found.noise.norm == "inf" else Fraction(1)
    nK2 = weight * sum((block[i] ** 2 for i in kept), Fraction(0))
    outside = sorted((block[i] ** 2 for i in range(len(block)) if i not in kept), reverse=True)
    mK2 = weight * sum(outside[: found.max_attacked], Fraction(0))
    need = _sqrt_upper(nK2 + mK2) + _sqrt_upper(nK2)
    return Fraction(found.bound) * Fraction(found.sigma) >= need


EXACT_SIGMA_LIMIT = 12  # largest n and horizon whose printed sigma is re-checked exactly


def sigma_rechecks(system: System, found: DecoderErrorBound) -> bool | None:
    """Whether the printed sigma of ``found.worst_kept`` is a lower bound of sigma_min(O_K) of
    the exact plant (the floats of A and C as rationals): O_K' O_K - sigma^2 I positive
    semidefinite, decided in rational arithmetic (positive definite with sigma taken a hair
    down); None beyond ``EXACT_SIGMA_LIMIT`` states or steps (not run)."""
    from ..numerics.rational import fractions, is_positive_definite, product

    n, tau = system.n, found.horizon
    if n > EXACT_SIGMA_LIMIT or tau > EXACT_SIGMA_LIMIT or not found.worst_kept:
        return None
    A = fractions(system.A)
    rows = []
    for i in found.worst_kept:
        row = fractions(system.C[i : i + 1])
        for _ in range(tau):
            rows.append(row[0])
            row = product(row, A)
    gram = product([list(col) for col in zip(*rows)], rows)
    sigma2 = Fraction(found.sigma) ** 2 * (1 - Fraction(1, 2**40))
    shifted = [
        [g - (sigma2 if r == c else 0) for c, g in enumerate(line)] for r, line in enumerate(gram)
    ]
    return is_positive_definite(shifted)


def worst_case_pair(system: System, found: DecoderErrorBound) -> dict[str, Any] | None:
    """Two explanations of the same window's data that no decoder can tell apart, on the set
    K = ``found.lower_kept`` (see the module's docstring): states x = 0 and x' = c v, the attack
    of each (on s sensors outside K each), the noise of each (within its bounds) and the data;
    ``lower`` = c / 2.  None when the set has no positive scale (noise 0 on it)."""
    tau, s = found.horizon, found.max_attacked
    kept = list(found.lower_kept)
    if not kept:
        return None
    blocks = system.sensor_blocks(tau)
    O_K = blocks[kept]  # (|K|, tau, n)
    _, _, vh = np.linalg.svd(O_K.reshape(-1, system.n))
    v = vh[-1]
    Ov = O_K @ v  # (|K|, tau)
    realizable = found.realizable
    size = np.max(np.abs(Ov), axis=1) if realizable.per_sample else np.linalg.norm(Ov, axis=1)
    eta = realizable.eta[kept]
    with np.errstate(divide="ignore", invalid="ignore"):
        scales = np.where(size > 0, 2.0 * eta / size, np.inf)
    c = float(np.min(scales)) * (1 - 1e-12)
    if not np.isfinite(c) or c <= 0:
        return None
    outside = [i for i in range(system.p) if i not in set(kept)]
    attacked, other = outside[:s], outside[s : 2 * s]
    Y = np.zeros((system.p, tau))
    Y[kept] = 0.5 * c * Ov  # x = 0 with noise c O_K v / 2; x' = c v with noise -c O_K v / 2
    x_other = c * v
    Y[attacked] = blocks[attacked] @ x_other  # x's attack makes these read x'
    # on ``other`` the data are x = 0's, noiseless: x' explains them by its attack
    return {
        "lower": 0.5 * c,
        "direction": v,
        "scale": c,
        "x": np.zeros(system.n),
        "x_other": x_other,
        "attacked": attacked,
        "attacked_other": other,
        "measurements": Y,  # (p, tau): sensor i at step k
    }
