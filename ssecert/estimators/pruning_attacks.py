"""The (eps, alpha)-successful false data injection attack (Zheng and Anubi, Theorem 2.1).

The attack the paper constructs against the l1 decoder with residual
detector of ``pruning``, and its independent verification.  Notation as in
``pruning``: ``M`` has one row per measurement (C, or the stacked window
matrix H), ``support`` is the attacked rows (0-based).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..base.validation import as_choice, as_float_option, as_index_list, as_real_matrix
from ..tolerances import default_rtol
from .pruning import _SCALINGS, _weighted_l1_fit, detector, l1_decode

__all__ = [
    "FalseDataInjectionAttack",
    "successful_attack",
    "AttackVerification",
    "verify_successful_attack",
]


# --------------------------------------------------------------------------
# (eps, alpha)-successful attacks (Definition 3, Theorem 2.1)
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class FalseDataInjectionAttack:
    """The attack (8) of Theorem 2.1 and what it achieves.

    Attributes
    ----------
    attack : numpy.ndarray, shape (p,)
        e with ``e_T = U_(1,T) z_e = M_T delta`` and ``e_(T^c) = 0``.
    support : tuple of int
        T, the attacked rows (sorted).
    eps : float
        Detector threshold.
    state_shift : numpy.ndarray, shape (n,)
        ``delta = V Sigma_1^-1 z_e``: the attacked rows read ``M_T (x + delta)``.
    z : numpy.ndarray, shape (n,)
        z_e, the variable of program (7).
    bounded : bool
        Whether program (7) is bounded (the safe rows ``M_(T^c)`` have full
        column rank).  When it is not, ``state_shift`` lies in their null
        space and the attack is exactly undetectable.
    safe_residual : float
        ``||U_(1,T^c) z_e||_1 = ||M_(T^c) delta||_1``; the decoder's residual
        on the attacked measurements is at most this.
    alpha : float
        The deviation the attack achieves: ``||D(M x + e) - x||_2``, the same
        for every x because the l1 decoder commutes with shifts by ``M x``
        (when its minimiser is unique); measured by decoding ``e`` alone.
    decoder_residual : float
        ``||e - M D(e)||_1``, the detector statistic under attack.
    detector_silent : bool
        ``decoder_residual <= eps``.
    alpha_guaranteed : float
        A lower bound on alpha that needs no decoding:
        ``||delta|| - 2 ||M_(T^c) delta||_1 / sigma_min(M)`` (no guarantee
        when <= 0).
    alpha_theorem : float
        Theorem 2.1's printed value
        ``eps / (sigma sigma_bar) * (1 - sigma_bar sqrt(p - |T|))``; see
        ``successful_attack`` for why it is not a valid bound.
    theorem_condition : bool
        Theorem 2.1's hypothesis ``sigma_bar sqrt(p - |T|) < 1``.
    sigma_bar : float
        Largest singular value of ``U_(1,T^c)``.
    sigma_min : float
        Smallest singular value of ``M``.
    scaling : str
        How the optimal direction of (7) was scaled.
    margin : float
        Relative slack kept below ``eps`` by the detector-safe scaling.
    """

    attack: np.ndarray
    support: tuple[int, ...]
    eps: float
    state_shift: np.ndarray
    z: np.ndarray
    bounded: bool
    safe_residual: float
    alpha: float
    decoder_residual: float
    detector_silent: bool
    alpha_guaranteed: float
    alpha_theorem: float
    theorem_condition: bool
    sigma_bar: float
    sigma_min: float
    scaling: str
    margin: float


def _read_only(array: np.ndarray) -> np.ndarray:
    array = np.ascontiguousarray(array, dtype=np.float64)
    array.flags.writeable = False
    return array


def successful_attack(
    M: np.ndarray,
    support: Sequence[int],
    eps: float,
    *,
    scaling: str = "detector-safe",
    margin: float = 1e-3,
    max_shift: float = 1e3,
    rank_rtol: float | None = None,
) -> FalseDataInjectionAttack:
    """The (eps, alpha)-successful attack of Theorem 2.1, eqs. (7)-(8).

    Program (7) maximises ``||Sigma_1^-1 z||_2`` subject to
    ``||U_(1,T^c) z||_2 <= budget``.  It maximises a convex function, so it
    is not a convex program (no cvxpy or LP formulation); it is solved
    exactly instead.  With ``delta = V Sigma_1^-1 z`` (so that
    ``U_1 z = M delta``) it reads: maximise ``||delta||_2`` subject to
    ``||M_(T^c) delta||_2 <= budget``, whose solution is ``delta`` along the
    right singular vector of the safe rows ``M_(T^c)`` for their smallest
    singular value.  The program is homogeneous, so this direction does not
    depend on the budget; ``scaling`` sets the size:

    * ``"detector-safe"`` (default): ``||M_(T^c) delta||_1 = (1 - margin) eps``.
      The decoder's residual is at most ``||M_(T^c) delta||_1`` (its value at
      ``x + delta``), so the detector of Definition 2 cannot fire.
    * ``"paper"``: ``||M_(T^c) delta||_2 = eps``, the budget printed in (7).
      The proof of Theorem 2.1 then bounds the l1 residual by
      ``sqrt(p - |T|) sigma_bar eps``, but the correct bound is
      ``sqrt(p - |T|) eps`` (the constraint already bounds
      ``||U_(1,T^c) z_e||_2`` by eps); generically the residual exceeds eps
      and the detector fires.

    In both cases ``||delta||`` is capped at ``max_shift``; when (7) is
    unbounded (fewer than n safe rows, or rank-deficient safe rows) the
    shift is a null vector of ``M_(T^c)`` of length ``max_shift``.

    Theorem 2.1's alpha is reported as printed but is not a valid bound: its
    proof drops a factor 2 (``||z_perp||_1 <= ||U_(1,T^c) z_e||_1`` does not
    follow from ``f(z_perp) <= f(0)``; the triangle inequality gives
    ``||U_1 z_perp||_1 <= 2 ||U_(1,T^c) z_e||_1``) and uses the l2 budget of
    (7) as if it bounded the l1 residual.  ``alpha_guaranteed`` is the
    corrected bound; ``alpha`` is what the decoder actually does.

    Parameters
    ----------
    M : array_like, shape (p, n)
        Observation matrix with full column rank (the paper's H).
    support : sequence of int
        T, the attacked rows (0-based, at least one).
    eps : float
        Detector threshold, > 0.
    scaling : {"detector-safe", "paper"}, default "detector-safe"
        Size of the attack, see above.
    margin : float, default 1e-3
        Relative slack below eps for the detector-safe scaling, in [0, 1),
        so that the LP solver's tolerance cannot push the residual over eps.
    max_shift : float, default 1e3
        Largest state shift ``||delta||_2``, > 0.
    rank_rtol : float, optional
        Singular values of ``M`` and ``M_(T^c)`` at most
        ``rank_rtol * ||M||_2`` count as zero; default ``max(p, n) * eps``
        (machine epsilon).

    Returns
    -------
    FalseDataInjectionAttack

    Raises
    ------
    TypeError
        If an argument has the wrong type.
    ValueError
        If ``M`` lacks full column rank, ``support`` is empty, out of range
        or repeated, or an option is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> M = np.random.default_rng(0).standard_normal((12, 3))
    >>> attack = successful_attack(M, range(7), 0.1)
    >>> bool(attack.detector_silent), bool(attack.alpha > 0.01)
    (True, True)
    >>> bool(np.all(attack.attack[7:] == 0.0))
    True
    """
    M = as_real_matrix(M, "M")
    p, n = M.shape
    attacked = as_index_list(support, "support", upper=p, what="row")
    if not attacked:
        raise ValueError("support must name at least one attacked row, got an empty list")
    eps = as_float_option(eps, "eps", min_value=0.0, min_inclusive=False)
    scaling = as_choice(scaling, "scaling", _SCALINGS)
    margin = as_float_option(margin, "margin", min_value=0.0, max_value=1.0, max_inclusive=False)
    max_shift = as_float_option(max_shift, "max_shift", min_value=0.0, min_inclusive=False)
    rtol = (
        default_rtol(p, n)
        if rank_rtol is None
        else as_float_option(rank_rtol, "rank_rtol", min_value=0.0)
    )

    U, sigma, Vt = np.linalg.svd(M, full_matrices=False)
    if n > p or sigma[-1] <= rtol * sigma[0]:
        raise ValueError(
            f"M must have full column rank {n}; its smallest singular value is "
            f"{sigma[-1]:.3e} against {sigma[0]:.3e} for the largest"
        )
    support_set = sorted(attacked)
    safe = np.setdiff1d(np.arange(p), support_set)
    M_safe = M[safe]
    U1_safe = U[safe]
    sigma_bar = float(np.linalg.norm(U1_safe, 2)) if safe.size else 0.0

    if safe.size:
        _, s_safe, Vt_safe = np.linalg.svd(M_safe, full_matrices=True)
    else:
        s_safe, Vt_safe = np.zeros(0), Vt
    bounded = safe.size >= n and s_safe[n - 1] > rtol * sigma[0]
    direction = Vt_safe[-1]  # unit; a null vector of M_safe when unbounded
    if bounded:
        image = M_safe @ direction
        size = (
            (1.0 - margin) * eps / float(np.sum(np.abs(image)))
            if scaling == "detector-safe"
            else eps / float(np.linalg.norm(image))
        )
        size = min(size, max_shift)
    else:
        size = max_shift
    shift = size * direction
    attack = np.zeros(p)
    attack[support_set] = M[support_set] @ shift
    safe_residual = float(np.sum(np.abs(M_safe @ shift))) if safe.size else 0.0

    x_hat = _weighted_l1_fit(M, attack, np.ones(p))
    alpha = float(np.linalg.norm(x_hat))
    decoder_residual = float(np.sum(np.abs(attack - M @ x_hat)))
    sigma_min = float(sigma[-1])
    alpha_guaranteed = float(np.linalg.norm(shift)) - 2.0 * safe_residual / sigma_min
    if sigma_bar > 0:
        alpha_theorem = eps / (sigma_min * sigma_bar) * (1.0 - sigma_bar * math.sqrt(safe.size))
    else:
        alpha_theorem = math.inf
    return FalseDataInjectionAttack(
        attack=_read_only(attack),
        support=tuple(support_set),
        eps=eps,
        state_shift=_read_only(shift),
        z=_read_only(sigma * (Vt @ shift)),
        bounded=bool(bounded),
        safe_residual=safe_residual,
        alpha=alpha,
        decoder_residual=decoder_residual,
        detector_silent=decoder_residual <= eps,
        alpha_guaranteed=alpha_guaranteed,
        alpha_theorem=float(alpha_theorem),
        theorem_condition=bool(sigma_bar * math.sqrt(safe.size) < 1.0),
        sigma_bar=sigma_bar,
        sigma_min=sigma_min,
        scaling=scaling,
        margin=margin,
    )


@dataclass(frozen=True)
class AttackVerification:
    """Check of Definition 3 by decoding attacked measurements.

    Attributes
    ----------
    successful : bool
        ``deviation >= alpha - atol`` and the detector stays silent.
    deviation : float
        ``||x_true - D(M x_true + attack)||_2``.
    residual : float
        ``||y - M D(y)||_1``, the detector statistic.
    alarm : bool
        ``residual > eps``.
    alpha : float
        The deviation claimed.
    eps : float
        Detector threshold.
    atol : float
        Absolute slack allowed on the deviation:
        ``rtol * (||x_true|| + ||x_hat||)``.
    x_hat : numpy.ndarray, shape (n,)
        The decoder's estimate.
    """

    successful: bool
    deviation: float
    residual: float
    alarm: bool
    alpha: float
    eps: float
    atol: float
    x_hat: np.ndarray


def verify_successful_attack(
    M: np.ndarray,
    x_true: np.ndarray,
    attack: np.ndarray,
    eps: float,
    alpha: float,
    *,
    rtol: float = 1e-6,
) -> AttackVerification:
    """Check that an attack is (eps, alpha)-successful (Definition 3, eq. (6)).

    Runs the l1 decoder (Definition 1) on ``y = M x_true + attack`` and the
    detector (Definition 2) on its estimate; uses nothing from the attack's
    construction.

    Parameters
    ----------
    M : array_like, shape (p, n)
        Observation matrix.
    x_true : array_like, shape (n,)
        True state x*.
    attack : array_like, shape (p,)
        Attack e added to the true measurements.
    eps : float
        Detector threshold, > 0.
    alpha : float
        Claimed deviation, >= 0.
    rtol : float, default 1e-6
        Relative slack on the deviation, scaled by
        ``||x_true|| + ||x_hat||`` (the LP solver's accuracy is relative).

    Returns
    -------
    AttackVerification

    Raises
    ------
    TypeError
        If an argument has the wrong type.
    ValueError
        If shapes disagree or an option is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> M = np.random.default_rng(0).standard_normal((12, 3))
    >>> attack = successful_attack(M, range(7), 0.1)
    >>> check = verify_successful_attack(M, [1.0, 2.0, 3.0], attack.attack, 0.1, attack.alpha)
    >>> bool(check.successful), bool(check.alarm)
    (True, False)
    """
    M = as_real_matrix(M, "M")
    p, n = M.shape
    x_true = as_real_matrix(
        x_true, "x_true", ndim=1, shape=(n,), shape_hint="one entry per column of M"
    )
    attack = as_real_matrix(
        attack, "attack", ndim=1, shape=(p,), shape_hint="one entry per row of M"
    )
    eps = as_float_option(eps, "eps", min_value=0.0, min_inclusive=False)
    alpha = as_float_option(alpha, "alpha", min_value=0.0)
    rtol = as_float_option(rtol, "rtol", min_value=0.0)
    y = M @ x_true + attack
    x_hat = l1_decode(M, y)
    decision = detector(M, y, x_hat, eps)
    deviation = float(np.linalg.norm(x_hat - x_true))
    atol = rtol * float(np.linalg.norm(x_true) + np.linalg.norm(x_hat))
    x_hat.flags.writeable = False
    return AttackVerification(
        successful=bool(deviation >= alpha - atol and not decision.alarm),
        deviation=deviation,
        residual=decision.residual,
        alarm=decision.alarm,
        alpha=alpha,
        eps=eps,
        atol=atol,
        x_hat=x_hat,
    )
