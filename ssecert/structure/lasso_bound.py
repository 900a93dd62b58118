"""Certified worst-case error of the partial Lasso decoder under bounded noise and attack.

The decoder is problem (4) of the Lasso paper over a window of tau steps,

    (x_hat, a_hat) = argmin_{x, a} 1/2 ||Y - O x - a||_2^2 + lam ||a||_1,

with Y = O x + a + w: the attack a nonzero on the rows of at most s sensors, the noise w
bounded on every sensor i (every sample within eta_i, or the window's samples of sensor i
within eta_i in 2-norm; ``ssecert.noise.MeasurementNoise``).

The bound is a primal-dual witness (Wainwright's construction for the Lasso, with a
deterministic noise).  Let S be the rows of s sensors holding the attack and K the others,
G = O_K' O_K (O_K of full column rank), N = G^-1 O_K' = O_K^+, Z_S = G^-1 O_S' and
R = I - O_K N (the residual projector on K's rows).  The decoder restricted to attacks on S
is strictly convex; its solution satisfies

    x_hat - x = N w_K + lam Z_S zeta_S,   zeta_S in [-1, 1]^{|S|} (a subgradient of |a_S|),

and the subgradient it needs on the rows j of K is zeta_j = (R w_K)_j / lam - (O_K Z_S
zeta_S)_j.  So when

    rho_S = ||O_K Z_S||_inf < 1        (the irrepresentable constant, (6) of the paper), and
    lam (1 - rho_S) > delta_S = max over the noise of max_j |(R w_K)_j|,

every |zeta_j| < 1: the restricted solution is the decoder's unique solution, its attack
estimate vanishes outside S, and

    ||x_hat - x||_2 <= beta_S + lam kappa_S,
    beta_S = max over the noise of ||N w_K||_2,  kappa_S = max over zeta of ||Z_S zeta||_2.

Every attack lies within the rows of some set of exactly s sensors, so with rho_S < 1 for
every such S the decoder's error is at most max_S (beta_S + lam kappa_S) for every
lam > lam_min = max_S delta_S / (1 - rho_S).  Without noise lam_min = 0 and the error is
at most lam max_S kappa_S: the bias of the l1 penalty, which vanishes with lam.

Rigour.  Each set's quantities are computed in floating point from the powers C A^k and
made upper bounds for the exact plant (the spec's A and C): sigma_min(O_K) from below (as
for the l0 bound: the Gramian's eigenvalues less their rounding and the powers' a-priori
error), the computed G^-1 [O_S' O_K'] within eps_Z = ||residual|| / sigma_min^2 of the exact
one (the residual evaluated with its rounding and the powers' error added), and every
product's rounding bounded by gamma_k times the norms of its factors.  The printed lam_min
and bound are re-checked in rational arithmetic from the printed numbers of the sets that
decide them.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from fractions import Fraction
from typing import Any

import numpy as np

from ..base.validation import as_float_option
from ..noise import MeasurementNoise
from ..system import System
from ..tolerances import gamma
from ._combinatorics import count_subsets
from .noise import _block_errors, _kept_sets, window_inputs
from .noise import _rounded_up as _next_up

__all__ = ["LassoBoundCode", "LassoErrorBound", "lasso_error_bound", "lasso_worst_case"]

DEFAULT_MAX_SETS = 200_000  # supports of s sensors examined
DEFAULT_MAX_WORK = 3e10  # floating-point operations of the supports' terms (tens of seconds)
_CHUNK_ENTRIES = 2**22  # floats of one chunk's largest array
_SAFE = 1.0 + 2.0**-40  # a relative cushion on every bound, far above its own rounding


def _rounded_up(x: float, exact_zero: bool = False) -> float:
    """An upper bound of what the computed ``x`` approximates: a few units in its last place
    up, so that a value that underflowed to 0 (or into the subnormals) is covered too; 0 only
    where the caller knows the value is exactly 0 (``exact_zero``)."""
    return 0.0 if exact_zero else _next_up(x)


def _times_up(x: np.ndarray | float, exponent: int) -> np.ndarray:
    """x 2^exponent, rounded up where it is subnormal or underflows (exact elsewhere)."""
    with np.errstate(all="ignore"):
        y = np.ldexp(np.asarray(x, dtype=float), exponent)
        tiny = (np.asarray(x) > 0) & (y < 2.0**-1022)
    return np.where(tiny, np.nextafter(y, np.inf), y)


class LassoBoundCode(enum.Enum):
    """How a Lasso decoder error bound came out."""

    #: a finite bound, certified for the exact plant, for every lam above ``lam_min``
    CERTIFIED = "certified"
    #: a support S has rho_S >= 1 (or not proved below 1): the witness does not exist there
    NOT_IRREPRESENTABLE = "not irrepresentable"
    #: the given lam is not above ``lam_min``
    LAMBDA_TOO_SMALL = "lambda too small"
    #: some O_K is not proved of full column rank: the decoder's solution may not be unique
    NO_MARGIN = "no margin"
    #: s >= p: no sensor is left unattacked
    TOO_FEW_SENSORS = "too few sensors"
    #: more supports than the limit, or more work than the limit (``facts``)
    TOO_MANY_SETS = "too many sets"
    #: the data or the bounds leave the floating-point range
    OUT_OF_RANGE = "out of range"
    #: the printed numbers did not survive their rational re-check (please report the plant)
    RECHECK_FAILED = "re-check failed"
    #: the sensors outside some support (``worst_support``) over the window exactly do not
    #: determine the state: an attack there makes two states agree, no decoder is bounded
    WINDOW_TOO_SHORT = "window too short"


@dataclass(frozen=True)
class LassoErrorBound:
    """The worst-case error of the partial Lasso decoder over a window (``lasso_error_bound``).

    Attributes
    ----------
    code : LassoBoundCode
    bound : float
        Certified: ||x_hat - x||_2 <= bound for every attack on at most s sensors, every
        noise within its bounds and the decoder's weight ``lam`` (inf when none is
        certified).
    lam : float
        The weight the bound is for; ``lam_min`` when none was given (the bound then holds
        in the limit lam -> lam_min from above, and ``noise_term + lam kappa`` for every
        larger lam; the decoder itself needs lam > 0, so without noise, lam_min = 0 and the
        bound 0 are that limit, not a weight).
    lam_min : float
        Every lam above it is certified (0 without noise).
    rho : float
        The largest irrepresentable constant over the supports (an upper bound); the
        certificate needs it below 1.
    rho_support : tuple of int
        The sensors of the support with the largest rho.
    lam_support : tuple of int
        The support that decides ``lam_min`` (the largest delta_S / (1 - rho_S)).
    worst_support : tuple of int
        The support with the largest beta_S + lam kappa_S: the attack the bound is worst for.
    noise_term : float
        max_S beta_S: the error the noise alone can cause (the least-squares error on the
        sensors outside S).
    kappa : float
        max_S kappa_S: the bias per unit of lam.
    sigma : float
        The certified lower bound of the smallest sigma_min(O_K) over the supports.
    noise : MeasurementNoise
    horizon, max_attacked : int
    sets : int
        Supports of s sensors examined.
    facts : mapping
        The numbers of the deciding supports (for the re-check and the words).
    sources : MeasurementNoise or None
        The spec's noise with its process noise, when ``noise`` is what it adds up to at
        the sensors (``MeasurementNoise.at_sensors``); None when ``noise`` is the spec's.
    """

    code: LassoBoundCode
    bound: float
    noise: MeasurementNoise
    horizon: int
    max_attacked: int
    lam: float = math.nan
    lam_min: float = math.inf
    rho: float = math.inf
    rho_support: tuple[int, ...] = ()
    lam_support: tuple[int, ...] = ()
    worst_support: tuple[int, ...] = ()
    noise_term: float = math.inf
    kappa: float = math.inf
    sigma: float = 0.0
    sets: int = 0
    facts: dict[str, Any] = field(default_factory=dict)
    sources: MeasurementNoise | None = None

    def at(self, lam: float) -> float:
        """The certified bound for the weight ``lam`` (inf when lam is not above
        ``lam_min``): the largest beta_S + lam kappa_S is at most noise_term + lam kappa."""
        if self.code is not LassoBoundCode.CERTIFIED or not lam > self.lam_min:
            return math.inf
        zero = self.noise_term == 0 and (lam == 0 or self.kappa == 0)
        return _rounded_up((self.noise_term + lam * self.kappa) * _SAFE, exact_zero=zero)


@dataclass(frozen=True)
class _Terms:
    """Upper bounds of each support's numbers, for the exact plant (arrays over supports)."""

    rho: np.ndarray
    delta: np.ndarray
    beta: np.ndarray
    kappa: np.ndarray
    sigma: np.ndarray


def _kept_gramians(
    blocks: np.ndarray, supports: np.ndarray, grams: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The sensors kept by each support (rows of ``supports``) and their Gramians O_K' O_K,
    the sum of every block's less the removed ones (``grams``: each block's, when computed)."""
    count, s = supports.shape
    p = blocks.shape[0]
    kept_mask = np.ones((count, p), dtype=bool)
    np.put_along_axis(kept_mask, supports, False, axis=1)
    kept = np.nonzero(kept_mask)[1].reshape(count, p - s)
    if grams is None:
        grams = np.einsum("itn,itm->inm", blocks, blocks)
    return kept, grams.sum(axis=0) - grams[supports].sum(axis=1)


def inverse_error(
    O_K: np.ndarray, X: np.ndarray, B: np.ndarray, sigma_K: float, e_K: float, e_B: float
) -> float:
    """An upper bound of ||X - X*||_2, X* = (O_K' O_K)^-1 B for the exact plant's O_K (within
    e_K of the one given in Frobenius norm, its B within e_B) and X computed: the residual
    O_K' O_K X - B evaluated with its rounding and the powers' error, over sigma_min^2
    (``sigma_K``, a lower bound for the exact plant)."""
    if not sigma_K > 0:
        return math.inf
    norm_K, norm_X = float(np.linalg.norm(O_K)), float(np.linalg.norm(X))
    residual = (
        float(np.linalg.norm(O_K.T @ (O_K @ X) - B))
        + gamma(O_K.shape[0] + O_K.shape[1] + 2) * (norm_K**2 * norm_X + float(np.linalg.norm(B)))
        + (2 * norm_K * e_K + e_K**2) * norm_X
        + e_B
    ) * _SAFE
    return residual / sigma_K**2 * _SAFE


def _kept_sigma(
    G: np.ndarray,
    frob2: np.ndarray,
    errors: np.ndarray,
    sup: np.ndarray,
    kept: np.ndarray,
    tau: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lower bounds of sigma_min(O_K) of the exact plant for each row of ``kept`` (G the
    computed Gramians: the sum of every block's less the removed ones), and the powers' errors
    e_K, e_S of the kept and removed rows (``errors``: each sensor's, ``frob2``: each block's
    squared Frobenius norm).

    The Gramian's smallest eigenvalue less its rounding (gamma of the sums' lengths times the
    sum of the blocks' norms) and LAPACK's backward error; then e_K off (the exact plant's O_K
    is within e_K of the computed one)."""
    p, n, s = frob2.size, G.shape[-1], sup.shape[1]
    lam_min = np.linalg.eigvalsh(G)[:, 0]
    kept_frob2 = frob2[kept].sum(axis=1)
    e_K = np.sqrt((errors[kept] ** 2).sum(axis=1)) * _SAFE
    e_S = np.sqrt((errors[sup] ** 2).sum(axis=1)) * _SAFE
    g_err = (gamma(tau + p + s + 2) * frob2.sum() + 64 * n * 2.0**-53 * kept_frob2) * _SAFE
    sigma = np.sqrt(np.maximum(lam_min - g_err, 0.0)) - e_K
    return np.maximum(sigma, 0.0) / _SAFE, e_K, e_S


def _support_terms(
    blocks: np.ndarray, errors: np.ndarray, eta: np.ndarray, per_sample: bool, supports: np.ndarray
) -> _Terms:
    """rho_S, delta_S, beta_S and kappa_S of every support (rows of ``supports``: sensor
    indices), each an upper bound for the exact plant; sigma_S a lower bound of sigma_min(O_K)."""
    p, tau, n = blocks.shape
    count, s = supports.shape
    k_rows, s_rows = (p - s) * tau, s * tau
    flat = blocks.reshape(p * tau, n)
    frob2 = np.sum(blocks**2, axis=(1, 2))
    grams = np.einsum("itn,itm->inm", blocks, blocks)
    out = {name: np.empty(count) for name in ("rho", "delta", "beta", "kappa", "sigma")}
    chunk = max(1, _CHUNK_ENTRIES // max(k_rows * p * tau, 1))
    eta_rows = np.repeat(eta, tau)  # each row's bound (per sample), or its sensor's (blocks)
    for start in range(0, count, chunk):
        sup = supports[start : start + chunk]
        c = sup.shape[0]
        kept, G = _kept_gramians(blocks, sup, grams)
        rows_k = (kept[:, :, None] * tau + np.arange(tau)).reshape(c, k_rows)
        rows_s = (sup[:, :, None] * tau + np.arange(tau)).reshape(c, s_rows)
        O_K = flat[rows_k]  # (c, k_rows, n)
        O_S = flat[rows_s]  # (c, s_rows, n)
        sigma, e_K, e_S = _kept_sigma(G, frob2, errors, sup, kept, tau)
        kept_frob2 = frob2[kept].sum(axis=1)
        good = sigma > 0
        # Z = G^-1 [O_S' O_K'] where G is proved positive definite
        G_safe = np.where(good[:, None, None], G, np.eye(n))
        B = np.concatenate([O_S, O_K], axis=1).transpose(0, 2, 1)  # (c, n, s_rows + k_rows)
        with np.errstate(all="ignore"):
            Z = np.linalg.solve(G_safe, B)
            M = O_K @ Z  # (c, k_rows, s_rows + k_rows): [O_K Z_S, O_K N]
            residual = O_K.transpose(0, 2, 1) @ M - B
        norm_OK = np.sqrt(kept_frob2)
        norm_Z = np.linalg.norm(Z, axis=(1, 2))
        norm_ZS = np.linalg.norm(Z[:, :, :s_rows], axis=(1, 2))
        norm_N = np.linalg.norm(Z[:, :, s_rows:], axis=(1, 2))
        # the exact plant's residual: the computed one, its rounding (gamma of the products'
        # lengths times the norms of their factors), and the powers' error
        res = (
            np.linalg.norm(residual, axis=(1, 2))
            + gamma(k_rows + n + 2) * (norm_OK**2 * norm_Z + np.linalg.norm(B, axis=(1, 2)))
            + (2 * norm_OK * e_K + e_K**2) * norm_Z
            + np.sqrt(e_K**2 + e_S**2)
        ) * _SAFE
        with np.errstate(all="ignore"):
            eps_Z = np.where(good, res / np.where(good, sigma, 1.0) ** 2 * _SAFE, np.inf)

        # the error of a product O_K Z (computed) against the exact plant's: rounding, the
        # error of Z and the powers' error, in 2-norm
        err_S, err_K = (
            (gamma(n + 2) * norm_OK * part + norm_OK * eps_Z + e_K * (part + eps_Z)) * _SAFE
            for part in (norm_ZS, norm_N)
        )
        M_S, M_K = M[:, :, :s_rows], M[:, :, s_rows:]
        # sums over a row (<= p tau), over n, over a block's n tau entries, and a root
        up = 1.0 + gamma(p * tau + n * tau + n + 4)
        # rho: the largest row l1 norm of O_K Z_S; an error E moves it by sqrt(|S|) ||E||_2
        rho = (np.abs(M_S).sum(axis=2).max(axis=1, initial=0.0) + math.sqrt(s_rows) * err_S) * up
        R = np.eye(k_rows)[None] - M_K
        eta_k = eta_rows[rows_k]  # (c, k_rows)
        norm_eta = np.sqrt((eta_k**2).sum(axis=1))
        if per_sample:
            delta = (np.abs(R) @ eta_k[:, :, None])[:, :, 0].max(axis=1)
            N = Z[:, :, s_rows:]
            beta_abs = np.sqrt(((np.abs(N) @ eta_k[:, :, None])[:, :, 0] ** 2).sum(axis=1))
            w_norm = norm_eta  # the largest ||w_K||_2
        else:
            per = R.reshape(c, k_rows, p - s, tau)
            delta = (np.sqrt((per**2).sum(axis=3)) @ eta[kept][:, :, None])[:, :, 0].max(axis=1)
            N = Z[:, :, s_rows:].reshape(c, n, p - s, tau)
            block_norms = np.sqrt((N**2).sum(axis=(1, 3)))  # Frobenius >= 2-norm of each block
            beta_abs = (block_norms * eta[kept]).sum(axis=1)
            w_norm = np.sqrt((eta[kept] ** 2).sum(axis=1))
        # an error E of O_K N moves each row's weighted sum by at most ||E||_2 ||eta_K||_2
        delta = (delta + err_K * w_norm) * up
        with np.errstate(all="ignore"):
            beta = np.minimum((beta_abs + eps_Z * w_norm) * up, w_norm / sigma * up)
        kappa_abs = np.sqrt((np.abs(Z[:, :, :s_rows]).sum(axis=2) ** 2).sum(axis=1))
        kappa = (
            np.minimum(kappa_abs + eps_Z * math.sqrt(s_rows), math.sqrt(s_rows) * (norm_ZS + eps_Z))
            * up
        )
        for name, value in (("rho", rho), ("delta", delta), ("beta", beta), ("kappa", kappa)):
            out[name][start : start + c] = np.where(good, value, np.inf)
        out["sigma"][start : start + c] = sigma
    return _Terms(**out)


def _blocks_and_errors(system: System, tau: int) -> tuple[np.ndarray, np.ndarray]:
    """The blocks C_i A^k (shape (p, tau, n)) and upper bounds of each sensor's
    ||fl(O_i) - O_i||_F: from the exact powers (integers; each entry correctly rounded, so
    within u |entry|) where their size allows, else as ``System.sensor_blocks`` forms them,
    with the a-priori bound of their rounding (which grows like |A|^k)."""
    from ..numerics.exact_powers import exact_observability_matrix

    p, n = system.p, system.n
    with np.errstate(all="ignore"):
        exact = exact_observability_matrix(system.A, system.C, tau, max_total_bits=2e7)
    if exact is None:
        return system.sensor_blocks(tau), _block_errors(system, tau)
    scale = 1 << -exact.exponent if exact.exponent < 0 else None
    flat = np.empty(exact.ints.shape)
    try:
        for index, value in np.ndenumerate(exact.ints):
            # int / int is correctly rounded in Python, however large the integers
            flat[index] = int(value) / scale if scale else float(int(value) << exact.exponent)
    except OverflowError:
        return system.sensor_blocks(tau), _block_errors(system, tau)
    blocks = flat.reshape(tau, p, n).transpose(1, 0, 2).copy()
    u = 2.0**-53
    # |fl(x) - x| <= u |x| <= u / (1 - u) |fl(x)| for normal floats, 2^-1075 below them; each
    # sensor's norm taken over its largest entry (no square overflows)
    top = np.max(np.abs(blocks), axis=(1, 2), initial=0.0)
    safe = np.where(top > 0, top, 1.0)
    norms = top * np.sqrt(np.sum((blocks / safe[:, None, None]) ** 2, axis=(1, 2)))
    errors = u / (1 - u) * norms * (1 + 4 * u) + math.sqrt(tau * n) * 2.0**-1074
    return blocks, errors * _SAFE


def _scaled_blocks(system: System, tau: int) -> tuple[np.ndarray, np.ndarray, int] | None:
    """``_blocks_and_errors`` divided by 2^d, d chosen so that the largest entry is in [1, 2)
    (Gramians of a plant whose entries are 1e-155 or 1e150 stay in range; the constants,
    rho and delta, do not change, sigma_min scales by 2^d, N and Z_S by 2^-d); the division's
    rounding (subnormal entries only) is added to the errors.  None when out of range."""
    with np.errstate(all="ignore"):
        blocks, errors = _blocks_and_errors(system, tau)
        top = float(np.max(np.abs(blocks))) if blocks.size else 0.0
        if not (np.all(np.isfinite(blocks)) and np.all(np.isfinite(errors))):
            return None
        d = math.frexp(top)[1] - 1 if top > 0 else 0
        scaled = np.ldexp(blocks, -d)
        errors = np.ldexp(errors, -d) + math.sqrt(blocks[0].size) * 2.0**-1074
        if not (np.all(np.isfinite(scaled)) and np.isfinite(np.sum(scaled**2))):
            return None
    return scaled, errors * _SAFE, d


def _window_deficient(system: System, kept: Sequence[int], tau: int) -> dict[str, bool] | None:
    """Whether the kept sensors over the window exactly fail to determine the state: None
    when they do determine it (or it is not decided), else whether a window of n steps would
    (``longer_horizon_helps``)."""
    from ..numerics.exact import Observability, exact_stacked_rank

    p, n = system.p, system.n

    def deficient(steps: int) -> bool:
        rows = [t * p + i for t in range(steps) for i in kept]
        decision = exact_stacked_rank(system.A, system.C, rows, steps)
        return decision.state is Observability.UNOBSERVABLE

    if not deficient(tau):
        return None
    return {"longer_horizon_helps": tau < n and not deficient(n)}


def lasso_error_bound(
    system: System,
    max_attacked: int,
    noise: MeasurementNoise,
    *,
    horizon: int | None = None,
    lam: float | None = None,
    max_sets: int = DEFAULT_MAX_SETS,
    max_work: float = DEFAULT_MAX_WORK,
) -> LassoErrorBound:
    """The certified worst-case estimation error of the partial Lasso decoder over a window.

    Parameters
    ----------
    system : System
    max_attacked : int
        s, the largest number of attacked sensors.
    noise : MeasurementNoise
        Per-sensor bounds of the measurement noise.
    horizon : int, optional
        tau, the window (default n).
    lam : float, optional
        The decoder's weight; by default the bound is given at ``lam_min`` (the limit from
        above) and ``LassoErrorBound.at`` gives it for any larger weight.
    max_sets : int, default 200,000
        Largest number of supports of s sensors examined.
    max_work : float, default 3e10
        Largest number of floating-point operations for the supports' terms (each support
        costs about 2 (p - s) tau (p tau (n + 2) + (p - s) tau)).

    Returns
    -------
    LassoErrorBound

    Examples
    --------
    Three sensors of one state, one attacked, noise at most 0.1 on each: the irrepresentable
    constant is 1/2 (Example 1 of the paper), lam must exceed 0.1 / (1 - 1/2) = 0.2, and the
    error is at most 0.1 (the two safe sensors' average) plus lam / 2 (the l1 bias).

    >>> import numpy as np
    >>> from ssecert import System
    >>> plant = System(np.eye(1), np.ones((3, 1)))
    >>> found = lasso_error_bound(plant, 1, MeasurementNoise.uniform(0.1, 3), horizon=1)
    >>> round(found.rho, 9), round(found.lam_min, 9), round(found.bound, 9)
    (0.5, 0.2, 0.2)
    >>> round(found.at(1.0), 9)
    0.6
    """
    s, tau = window_inputs(system, max_attacked, noise, horizon)
    if lam is not None:
        lam = as_float_option(lam, "lam", min_value=0.0)
    p = system.p
    base: dict[str, Any] = {"noise": noise, "horizon": tau, "max_attacked": s}
    if s >= p:
        return LassoErrorBound(LassoBoundCode.TOO_FEW_SENSORS, math.inf, **base)
    sets = count_subsets(p, [s])
    n = system.n
    work = 2.0 * sets * (p - s) * tau * (p * tau * (n + 2) + (p - s) * tau)
    if sets > max_sets or work > max_work:
        return LassoErrorBound(
            LassoBoundCode.TOO_MANY_SETS,
            math.inf,
            sets=sets,
            facts={"limit": max_sets, "work": work, "work_limit": max_work},
            **base,
        )
    # the noise's terms are linear in it: computed for the bounds over a power of two c >= the
    # largest (exactly), so that no square under- or overflows, and scaled back by c
    top = float(np.max(noise.eta)) if p else 0.0
    c = MeasurementNoise.scale(top)
    eta = noise.eta / c if top > 0 else np.zeros(p)
    base["sets"] = sets
    ranged = _scaled_blocks(system, tau)
    if ranged is None:
        return LassoErrorBound(LassoBoundCode.OUT_OF_RANGE, math.inf, **base)
    blocks, errors, d = ranged  # the plant's blocks are 2^d times these
    supports = _kept_sets(p, s)
    with np.errstate(all="ignore"):  # a support without a margin gets inf, never a warning
        terms = _support_terms(blocks, errors, eta, noise.per_sample, supports)
    names = lambda j: tuple(int(i) for i in supports[j])  # noqa: E731
    if not np.all(terms.sigma > 0):
        j = int(np.argmin(terms.sigma))
        kept = [i for i in range(p) if i not in set(names(j))]
        short = _window_deficient(system, kept, tau)
        code = LassoBoundCode.NO_MARGIN if short is None else LassoBoundCode.WINDOW_TOO_SHORT
        return LassoErrorBound(code, math.inf, worst_support=names(j), facts=short or {}, **base)
    numbers = (terms.rho, terms.delta, terms.beta, terms.kappa)
    if not all(np.all(~np.isnan(x)) for x in numbers):
        return LassoErrorBound(LassoBoundCode.OUT_OF_RANGE, math.inf, **base)
    worst_rho = int(np.argmax(terms.rho))
    rho = float(terms.rho[worst_rho])
    with np.errstate(all="ignore"):  # a lower bound: rounded down where it is subnormal
        smallest = float(np.ldexp(terms.sigma.min(), d))
    if smallest < 2.0**-1022:
        smallest = float(np.nextafter(smallest, 0.0))

    def common(code: LassoBoundCode, bound: float, **more: Any) -> LassoErrorBound:
        return LassoErrorBound(
            code, bound, rho=rho, rho_support=names(worst_rho), sigma=smallest, **base, **more
        )

    if not rho < 1:
        return common(LassoBoundCode.NOT_IRREPRESENTABLE, math.inf)
    # back to the plant's units: delta by c (the noise's scale), beta by c 2^-d, kappa by 2^-d,
    # each rounded up (a value that underflows is covered by the rounding up)
    e_c = math.frexp(c)[1] - 1  # c = 2^e_c
    silent = top == 0  # no noise: delta and beta are exactly 0
    with np.errstate(all="ignore"):
        need = _times_up(terms.delta / (1.0 - terms.rho) * (1.0 + gamma(4)), e_c)
        beta = _times_up(terms.beta, e_c - d)
        kappas = _times_up(terms.kappa, -d)
    deciding = int(np.argmax(need))
    printed_delta = float(_times_up(terms.delta[deciding], e_c))
    lam_min = max(
        _rounded_up(float(need[deciding]), exact_zero=silent),
        # what the printed numbers give (rounded up where subnormal), so that they re-check
        _rounded_up(
            printed_delta / (1.0 - float(terms.rho[deciding])) * (1.0 + gamma(4)),
            exact_zero=silent,
        ),
    )
    noise_term = _rounded_up(float(beta.max()), exact_zero=silent)
    kappa = _rounded_up(float(kappas.max()), exact_zero=s == 0)
    if not all(math.isfinite(v) for v in (lam_min, noise_term, kappa)):
        return common(LassoBoundCode.OUT_OF_RANGE, math.inf)
    weight = lam_min if lam is None else float(lam)
    with np.errstate(over="ignore"):
        per_support = beta + weight * kappas
    worst = int(np.argmax(per_support))
    zero = silent and (weight == 0 or s == 0)
    found = common(
        LassoBoundCode.CERTIFIED,
        _rounded_up(float(per_support[worst]) * (1.0 + gamma(4)), exact_zero=zero),
        lam=weight,
        lam_min=lam_min,
        lam_support=names(deciding),
        worst_support=names(worst),
        noise_term=noise_term,
        kappa=kappa,
        facts={
            "deciding_rho": float(terms.rho[deciding]),
            "deciding_delta": printed_delta,
            "worst_beta": float(beta[worst]),
            "worst_kappa": float(kappas[worst]),
            "noise_scale": c,
            "data_scale_exponent": d,
        },
    )
    if not math.isfinite(found.bound):
        return replace(found, code=LassoBoundCode.OUT_OF_RANGE, bound=math.inf)
    if lam is not None and not lam > lam_min:
        return replace(found, code=LassoBoundCode.LAMBDA_TOO_SMALL, bound=math.inf)
    if not lasso_bound_rechecks(found):
        return replace(found, code=LassoBoundCode.RECHECK_FAILED)
    return found


def lasso_bound_rechecks(found: LassoErrorBound) -> bool:
    """The printed lam_min and bound re-derived in rational arithmetic from the printed
    numbers of the supports that decide them: lam_min (1 - rho_S) >= delta_S on the support
    deciding lam_min, bound >= beta_S + lam kappa_S on the worst support, and
    noise_term + lam kappa >= the bound's terms."""
    if found.code is not LassoBoundCode.CERTIFIED:
        return False
    f = found.facts
    q = Fraction
    rho, delta = q(f["deciding_rho"]), q(f["deciding_delta"])
    if not (rho < 1 and q(found.lam_min) * (1 - rho) >= delta):
        return False
    beta, kappa = q(f["worst_beta"]), q(f["worst_kappa"])
    lam = q(found.lam)
    if q(found.bound) < beta + lam * kappa:
        return False
    return q(found.noise_term) >= beta and q(found.kappa) >= kappa


def _safe_norm(v: np.ndarray) -> float:
    """||v||_2 without overflow or underflow of the squares."""
    top = float(np.max(np.abs(v))) if v.size else 0.0
    if top == 0 or not math.isfinite(top):
        return top
    return top * float(np.linalg.norm(v / top))


def _construction_error(
    blocks: np.ndarray, errors: np.ndarray, tau: int, best: dict[str, Any], lam_unit: float
) -> float:
    """An upper bound of ||(N* - N) w + lam (Z* - Z) zeta|| and of the rounding of
    N w + lam Z zeta, in the construction's units: N*, Z* the exact plant's, N, Z the computed
    ones, whose error the residual of G [Z N] = [O_S' O_K'] bounds by ||residual|| / sigma^2
    for the exact plant's O (within ``errors`` of the correctly rounded blocks)."""
    p, n = blocks.shape[0], blocks.shape[2]
    O_K, O_S, N, Z = best["O_K"], best["O_S"], best["N"], best["Z"]
    attacked = np.array([sorted({r % p for r in best["rows_s"]})], dtype=np.int64)
    with np.errstate(all="ignore"):
        kept, G = _kept_gramians(blocks, attacked.reshape(1, -1))
        sigma, e_K, e_S = _kept_sigma(
            G, np.sum(blocks**2, axis=(1, 2)), errors, attacked.reshape(1, -1), kept, tau
        )
        ZN = np.concatenate([Z, N], axis=1)
        B = np.concatenate([O_S, O_K]).T
        e_B = math.hypot(float(e_K[0]), float(e_S[0]))
        eps = inverse_error(O_K, ZN, B, float(sigma[0]), float(e_K[0]), e_B)
        norm_ZN = float(np.linalg.norm(ZN))
        reach = _safe_norm(best["w"]) + abs(lam_unit) * math.sqrt(Z.shape[1])
        own = gamma(O_K.shape[0] + Z.shape[1] + n + 4) * norm_ZN * reach
        value = (eps * reach + own) * _SAFE
    return value if math.isfinite(value) else math.inf


def lasso_worst_case(
    system: System, found: LassoErrorBound, lam: float | None = None
) -> dict[str, Any] | None:
    """An attack and a noise within the bounds on which the partial Lasso decoder with weight
    ``lam`` (default ``found.lam``) is off by ``lower``: how tight the certified bound is.

    On a support S where the witness holds, an attack on S large enough (each entry beyond
    its noise, lam and the error's reach on its row) keeps the sign of the attack estimate, so
    zeta_S is the attack's sign and the decoder's error is exactly N w_K + lam Z_S zeta (from
    x = 0).  Its norm is maximised over the signs and the noise's extreme points by
    alternating directions, on the supports that decide the bound (None when ``found`` is not
    certified).  Returns ``lower`` (the error reached, rounded down), the ``support``, the
    ``attack`` and ``noise`` (the stacked window, rows t p + i), ``lam`` and ``error``.
    """
    if found.code is not LassoBoundCode.CERTIFIED:
        return None
    weight = found.lam if lam is None else float(lam)
    if not weight >= found.lam_min:
        return None
    p, n, tau = system.p, system.n, found.horizon
    # in units where O's largest entry and the noise's are about 1 (O = 2^d O', eta = c eta'):
    # N = 2^-d N', Z = 2^-d Z', so the error N w + lam Z zeta is 2^-d c (N' w' + lam / c Z' zeta)
    ranged = _scaled_blocks(system, tau)
    # with process noise, the measurement noise alone: every sensor takes it independently
    realizable = found.noise if found.sources is None else found.sources.measurement_only()
    top_eta = float(np.max(realizable.eta))
    if ranged is None or (top_eta == 0 and weight == 0):
        return {"lower": 0.0, "support": found.worst_support, "lam": weight}
    blocks, errors, d = ranged
    O_unit = blocks.transpose(1, 0, 2).reshape(tau * p, n)  # rows t p + i
    c = MeasurementNoise.scale(top_eta) if top_eta > 0 else 1.0
    eta = realizable.eta / c
    lam_unit = weight / c
    best: dict[str, Any] | None = None
    for support in dict.fromkeys((found.worst_support, found.lam_support, found.rho_support)):
        attacked = set(support)
        rows_s = [t * p + i for t in range(tau) for i in sorted(attacked)]
        rows_k = [t * p + i for t in range(tau) for i in range(p) if i not in attacked]
        O_K, O_S = O_unit[rows_k], O_unit[rows_s]
        with np.errstate(all="ignore"):
            G = O_K.T @ O_K
            try:
                N, Z = np.linalg.solve(G, O_K.T), np.linalg.solve(G, O_S.T)
            except np.linalg.LinAlgError:
                continue
        if not (np.all(np.isfinite(N)) and np.all(np.isfinite(Z))):
            continue
        sensor = np.array([r % p for r in rows_k])
        starts = [np.linalg.svd(M)[0][:, 0] for M in (N, Z) if M.size] + list(np.eye(n))
        for v in starts:
            for _ in range(2 * n + 4):
                sigma = np.where(Z.T @ v >= 0, 1.0, -1.0)
                reach = N.T @ v
                if realizable.per_sample:
                    w = eta[sensor] * np.where(reach >= 0, 1.0, -1.0)
                else:
                    w = np.zeros_like(reach)
                    for i in set(sensor.tolist()):
                        mine = sensor == i
                        size = _safe_norm(reach[mine])
                        share = reach[mine] / size if size > 0 else np.full(tau, tau**-0.5)
                        # a few ulps inside the bound, whatever the division's rounding
                        w[mine] = eta[i] * share * (1 - 2.0**-48)
                with np.errstate(all="ignore"):
                    error = N @ w + lam_unit * (Z @ sigma)
                size = _safe_norm(error)
                if not 0 < size < math.inf:
                    break
                if best is None or size > best["error_norm"]:
                    best = {"error_norm": size, "support": tuple(support), "error": error,
                            "rows_s": rows_s, "rows_k": rows_k, "sigma": sigma, "w": w,
                            "O_K": O_K, "O_S": O_S, "N": N, "Z": Z}  # fmt: skip
                if np.allclose(error / size, v, rtol=0, atol=1e-15):
                    break
                v = error / size
    if best is None:
        return {"lower": 0.0, "support": found.worst_support, "lam": weight}
    exponent = math.frexp(c)[1] - 1 - d
    slack = _construction_error(blocks, errors, tau, best, lam_unit)
    with np.errstate(all="ignore"):
        # a lower bound: the computed error's norm less the error of the computed N and Z
        # against the exact plant's (from their residual) and its own rounding
        certain = max(best["error_norm"] * (1 - 2.0**-40) - slack, 0.0)
        lower = float(np.ldexp(certain, exponent))
        if lower < 2.0**-1022:
            lower = float(np.nextafter(lower, 0.0))
        error = np.ldexp(best["error"], exponent)
        noise = np.zeros(p * tau)
        noise[best["rows_k"]] = best["w"] * c
        # each attacked row beyond its noise (none), lam and the error's reach there
        reach = np.abs(np.ldexp(best["O_S"], d) @ error) + weight
        attack = np.zeros(p * tau)
        attack[best["rows_s"]] = best["sigma"] * (2.0 * reach + 1.0)
    if not all(np.all(np.isfinite(x)) for x in (error, noise, attack)) or not lower < math.inf:
        return {"lower": 0.0, "support": found.worst_support, "lam": weight}
    return {
        "lower": lower,
        "support": best["support"],
        "lam": weight,
        "attack": attack,
        "noise": noise,
        "error": error,
    }
