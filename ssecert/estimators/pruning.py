"""Weighted l1 observer with prior pruning (Zheng and Anubi).

The l1 decoder and its residual detector, the Poisson-binomial
pruning of a support prior (Lemma 3.1, equations (13)-(14)) and the
weighted l1 observer with pruned prior (Definition 5).  The
(eps, alpha)-successful false data injection attack of the paper's
Theorem 2.1 is in ``pruning_attacks``.

Notation.  The paper writes m for the number of measurements per step, k for
the number of attacked ones, T for the window length, H for the stacked
observation matrix and y_T for the stacked measurements.  ssecert writes p
for the number of sensors and s for the number attacked; the functions here
take one matrix ``M`` with one row per measurement:

* the static model ``y = M x + e`` (M = C, p rows), or
* the stacked window model (3), ``M = H = [C; C A; ...; C A^(T-1)]`` with
  ``T * p`` rows; row ``j * p + i`` is sensor ``i`` at step ``j`` of the
  window, oldest step first, as in ``System.observability_matrix``.

Row sets are 0-based index lists: ``support`` is the attack support
(the paper's calligraphic T), ``prior_safe`` the support prior of safe rows
(T-hat complement), ``trusted`` the pruned prior (T-hat complement sub eta).
``probs[i]`` is the paper's p_i, the probability that the prior is right
about row i (epsilon_i ~ Bernoulli(p_i) in the uncertainty model (10)).

Where the paper's formulas disagree with their own definitions this module
follows the definitions; the choices are stated in the function docstrings
(the second form of (13), the detector threshold of Theorem 2.1, the row
order of (3)).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.optimize
import scipy.sparse

from ..base.validation import as_float_option, as_index_list, as_int_option, as_real_matrix

__all__ = [
    "l1_decode",
    "DetectorDecision",
    "detector",
    "poisson_binomial_pmf",
    "reliable_safe_count",
    "PrunedSupportPrior",
    "prune_support_prior",
    "WeightedL1Estimate",
    "weighted_l1_observer",
    "pruned_weighted_l1_observer",
    "pruned_weighted_l1_window_observer",
]

_SCALINGS = ("detector-safe", "paper")


# --------------------------------------------------------------------------
# Decoder and detector (Definitions 1-2)
# --------------------------------------------------------------------------


def _measurements(M: object, y: object) -> tuple[np.ndarray, np.ndarray]:
    M = as_real_matrix(M, "M")
    y = as_real_matrix(y, "y", ndim=1, shape=(M.shape[0],), shape_hint="one entry per row of M")
    return M, y


def _weighted_l1_fit(M: np.ndarray, y: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """argmin_x sum_i w_i |y_i - (M x)_i| as the LP y - M x = u - v, u, v >= 0."""
    p, n = M.shape
    cost = np.concatenate([np.zeros(n), weights, weights])
    eye = scipy.sparse.identity(p, format="csr")
    A_eq = scipy.sparse.hstack([scipy.sparse.csr_matrix(M), eye, -eye], format="csr")
    bounds = [(None, None)] * n + [(0.0, None)] * (2 * p)
    solution = scipy.optimize.linprog(cost, A_eq=A_eq, b_eq=y, bounds=bounds, method="highs")
    if solution.status != 0:
        raise RuntimeError(f"the l1 linear program failed: {solution.message}")
    return np.asarray(solution.x[:n], dtype=np.float64)


def l1_decode(M: np.ndarray, y: np.ndarray, *, weights: np.ndarray | None = None) -> np.ndarray:
    """The l1 decoder: argmin_x sum_i w_i |y_i - (M x)_i|.

    With unit weights this is the decoder D of Definition 1 (eq. (4)); the
    paper writes it as ``V Sigma_1^-1 argmin_z ||y - U_1 z||_1`` with the thin
    SVD ``M = U_1 Sigma_1 V^T``, which is the same minimiser after the change
    of variables ``z = Sigma_1 V^T x``.  With weights it is the weighted l1
    norm ``||y - M x||_(l1, w)`` of (15).  Solved as a linear program by
    HiGHS (``scipy.optimize.linprog(method="highs")``).

    Parameters
    ----------
    M : array_like, shape (p, n)
        Observation matrix, one row per measurement (the paper's H, with
        ``p = T m`` rows for a window of T steps).
    y : array_like, shape (p,)
        Measurements, possibly attacked.
    weights : array_like, shape (p,), optional
        Nonnegative weights w_i, not all zero; default all ones.

    Returns
    -------
    numpy.ndarray, shape (n,)
        A minimiser x_hat.  When the minimiser is not unique (``M`` rank
        deficient, or zero weights on rows that would fix it) the LP returns
        one vertex of the optimal set.

    Raises
    ------
    TypeError
        If an array has non-real entries.
    ValueError
        If shapes disagree, an entry is not finite, a weight is negative or
        every weight is zero.
    RuntimeError
        If the LP solver reports a failure.

    Examples
    --------
    >>> import numpy as np
    >>> M = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, -1.0], [2.0, 1.0]])
    >>> x = np.array([1.0, -2.0])
    >>> y = M @ x
    >>> y[4] += 10.0                     # one attacked measurement
    >>> np.round(l1_decode(M, y), 10).tolist()
    [1.0, -2.0]
    """
    M, y = _measurements(M, y)
    p = M.shape[0]
    if weights is None:
        w = np.ones(p)
    else:
        w = as_real_matrix(weights, "weights", ndim=1, shape=(p,), shape_hint="one per row of M")
        if np.any(w < 0):
            i = int(np.argmin(w))
            raise ValueError(f"weights must be nonnegative, got weights[{i}] = {w[i]}")
        if not np.any(w > 0):
            raise ValueError("weights must have at least one positive entry, got all zeros")
    return _weighted_l1_fit(M, y, w)


@dataclass(frozen=True)
class DetectorDecision:
    """Decision of the residual detector of Definition 2.

    Attributes
    ----------
    alarm : bool
        ``residual > eps``: the detector's positive (attacked) class.
    residual : float
        ``||y - M x_hat||_1``.
    eps : float
        The threshold.
    """

    alarm: bool
    residual: float
    eps: float

    def __bool__(self) -> bool:
        return self.alarm


def detector(M: np.ndarray, y: np.ndarray, x_hat: np.ndarray, eps: float) -> DetectorDecision:
    """Residual detector D_eps of Definition 2 (eq. (5)).

    Fires (returns a decision with ``alarm=True``, the paper's class 1) when
    ``||y - M x_hat||_1 > eps``, where ``x_hat`` is the decoder's estimate
    ``D(y)``.

    Parameters
    ----------
    M : array_like, shape (p, n)
        Observation matrix.
    y : array_like, shape (p,)
        Measurements.
    x_hat : array_like, shape (n,)
        Estimate returned by the decoder on ``y``.
    eps : float
        Threshold, > 0.

    Returns
    -------
    DetectorDecision
        ``alarm``, the residual and the threshold; truthy when it fires.

    Raises
    ------
    TypeError
        If an array has non-real entries or ``eps`` is not a real number.
    ValueError
        If shapes disagree or ``eps <= 0``.

    Examples
    --------
    >>> import numpy as np
    >>> M = np.eye(3)
    >>> decision = detector(M, [1.0, 2.0, 3.5], [1.0, 2.0, 3.0], 0.1)
    >>> decision.alarm, decision.residual
    (True, 0.5)
    """
    M, y = _measurements(M, y)
    x_hat = as_real_matrix(
        x_hat, "x_hat", ndim=1, shape=(M.shape[1],), shape_hint="one entry per column of M"
    )
    eps = as_float_option(eps, "eps", min_value=0.0, min_inclusive=False)
    residual = float(np.sum(np.abs(y - M @ x_hat)))
    return DetectorDecision(alarm=residual > eps, residual=residual, eps=eps)


# --------------------------------------------------------------------------
# Poisson-binomial pruning (Lemma 3.1, eqs. (13)-(14))
# --------------------------------------------------------------------------


def _probabilities(probs: object, name: str = "probs") -> np.ndarray:
    probs = as_real_matrix(probs, name, ndim=1, allow_empty=True)
    bad = np.flatnonzero((probs < 0) | (probs > 1))
    if bad.size:
        i = int(bad[0])
        raise ValueError(f"{name} must lie in [0, 1], got {name}[{i}] = {probs[i]}")
    return probs


def poisson_binomial_pmf(probs: np.ndarray) -> np.ndarray:
    """Exact pmf of a sum of independent Bernoulli(p_i) variables.

    ``pmf[j] = Pr{sum_i eps_i = j}`` for ``j = 0, ..., N``; the paper's
    ``r(k)`` of Lemma 3.1 (eq. (12)) is ``pmf[k - 1]``.  Lemma 3.1 writes the
    pmf as ``prod(p_i)`` times the coefficients of ``prod_i (t - s_i)`` with
    roots ``s_i = -(1 - p_i) / p_i``; that is the generating polynomial
    ``prod_i (1 - p_i + p_i t)``, computed here by multiplying in one factor
    at a time (dynamic programming, O(N^2)), which also allows ``p_i = 0``
    and avoids the overflow of ``(1 - p_i) / p_i`` for small p_i.

    Parameters
    ----------
    probs : array_like, shape (N,)
        Success probabilities in [0, 1]; may be empty.

    Returns
    -------
    numpy.ndarray, shape (N + 1,)
        The pmf; nonnegative, sums to 1 up to rounding.

    Raises
    ------
    TypeError
        If ``probs`` has non-real entries.
    ValueError
        If ``probs`` is not 1-D or an entry is outside [0, 1].

    Examples
    --------
    >>> poisson_binomial_pmf([0.5, 0.5]).tolist()
    [0.25, 0.5, 0.25]
    >>> poisson_binomial_pmf([]).tolist()
    [1.0]
    """
    probs = _probabilities(probs)
    pmf = np.zeros(probs.size + 1)
    pmf[0] = 1.0
    for count, p in enumerate(probs, start=1):
        # New distribution: the previous one without (x (1 - p)) and with (x p, shifted) a success.
        pmf[1 : count + 1] = pmf[1 : count + 1] * (1.0 - p) + pmf[:count] * p
        pmf[0] *= 1.0 - p
    return pmf


def _upper_tail(pmf: np.ndarray) -> np.ndarray:
    """tail[k] = Pr{S >= k}, summed from the top so that small tails keep their accuracy."""
    return np.cumsum(pmf[::-1])[::-1]


def _count_and_tail(probs: np.ndarray, eta: float) -> tuple[int, np.ndarray]:
    """l_eta of (13) and the tail Pr{S >= k}, k = 0, ..., N."""
    tail = _upper_tail(poisson_binomial_pmf(probs))
    # tail is nonincreasing and tail[0] = 1 >= eta, so the set in (13) is {0, ..., l_eta}.
    return int(np.flatnonzero(tail >= eta)[-1]), tail


def _reliability(value: object) -> float:
    return as_float_option(
        value, "reliability", min_value=0.0, max_value=1.0, min_inclusive=False, max_inclusive=False
    )


def reliable_safe_count(probs: np.ndarray, *, reliability: float = 0.9) -> int:
    """l_eta of eq. (13): the most rows of the prior that are right with probability >= eta.

    ``l_eta = max{k : Pr{sum_(i in prior_safe) eps_i >= k} >= eta}``, with
    the ``eps_i`` independent Bernoulli(p_i) (the uncertainty model (10)).
    The paper rewrites the condition as ``sum_(i=1)^(k+1) r(i) <= 1 - eta``;
    with its own indexing ``r(i) = Pr{S = i - 1}`` that sum is
    ``Pr{S <= k}``, i.e. the condition for ``k + 1``, so the second form of
    (13) gives one row fewer than the first.  This function follows the
    first form, the probabilistic definition stated in words.

    Parameters
    ----------
    probs : array_like, shape (N,)
        p_i of the rows of the support prior (only those rows), in [0, 1].
    reliability : float, default 0.9
        eta, in (0, 1).  The paper leaves its value open.

    Returns
    -------
    int
        l_eta, between 0 and N.

    Raises
    ------
    TypeError
        If an argument has the wrong type.
    ValueError
        If a probability is outside [0, 1] or ``reliability`` outside (0, 1).

    Examples
    --------
    >>> reliable_safe_count([0.99, 0.99, 0.99, 0.5], reliability=0.9)
    3
    """
    count, _ = _count_and_tail(_probabilities(probs), _reliability(reliability))
    return count


@dataclass(frozen=True)
class PrunedSupportPrior:
    """A support prior and its pruning, eqs. (13)-(14).

    Attributes
    ----------
    trusted : tuple of int
        The pruned prior (T-hat complement sub eta): the ``count`` rows of
        ``prior_safe`` with the largest p_i, listed by decreasing p_i (ties
        by increasing row index).
    count : int
        l_eta of (13).
    tail_probability : float
        ``Pr{S >= count}`` for S the number of rows of ``prior_safe`` on
        which the prior is right (>= ``reliability``).
    reliability : float
        eta.
    prior_safe : tuple of int
        The support prior of safe rows (T-hat complement), sorted.
    expected_correct : float
        ``E[S] = sum of p_i over prior_safe``.
    """

    trusted: tuple[int, ...]
    count: int
    tail_probability: float
    reliability: float
    prior_safe: tuple[int, ...]
    expected_correct: float


def prune_support_prior(
    prior_safe: Sequence[int], probs: np.ndarray, *, reliability: float = 0.9
) -> PrunedSupportPrior:
    """Prune a support prior (eqs. (13)-(14)).

    Step 1 (13): ``l_eta`` from the Poisson-binomial law of the number of
    rows of ``prior_safe`` on which the prior is right (see
    ``reliable_safe_count``).  Step 2 (14): keep the first ``l_eta`` indices
    of ``argsort_desc(p o q_hat)``; since ``p o q_hat`` vanishes outside the
    prior, these are the ``l_eta`` rows of ``prior_safe`` with the largest
    p_i.  The sort is restricted to ``prior_safe`` explicitly, so rows of the
    prior with ``p_i = 0`` cannot tie with rows outside it.

    Parameters
    ----------
    prior_safe : sequence of int
        Rows the underlying localisation algorithm declares safe (0-based).
    probs : array_like, shape (N,)
        p_i for every row (in [0, 1]); N is the number of rows of the model.
    reliability : float, default 0.9
        eta, in (0, 1).

    Returns
    -------
    PrunedSupportPrior

    Raises
    ------
    TypeError
        If an argument has the wrong type.
    ValueError
        If an index is out of range or repeated, a probability is outside
        [0, 1], or ``reliability`` is outside (0, 1).

    Examples
    --------
    >>> pruned = prune_support_prior([0, 1, 3, 4], [0.99, 0.6, 0.3, 0.98, 0.97], reliability=0.9)
    >>> pruned.count, pruned.trusted
    (3, (0, 3, 4))
    """
    probs = _probabilities(probs)
    prior = as_index_list(prior_safe, "prior_safe", upper=probs.size, what="row")
    eta = _reliability(reliability)
    prior_probs = probs[list(prior)]
    count, tail = _count_and_tail(prior_probs, eta)
    order = np.argsort(-prior_probs, kind="stable")[:count]
    return PrunedSupportPrior(
        trusted=tuple(prior[i] for i in order),
        count=count,
        tail_probability=float(tail[count]),
        reliability=eta,
        prior_safe=tuple(sorted(prior)),
        expected_correct=float(np.sum(prior_probs)),
    )


# --------------------------------------------------------------------------
# Weighted l1 observer (Definition 5)
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class WeightedL1Estimate:
    """Estimate of the weighted l1 observer (15).

    Attributes
    ----------
    x_hat : numpy.ndarray, shape (n,)
        The estimate (for the window model, of the window's first state).
    weights : numpy.ndarray, shape (p,)
        w_i = 1 on ``trusted``, ``omega`` elsewhere.
    trusted : tuple of int
        Rows with unit weight.
    omega : float
        Weight of the other rows.
    residual : numpy.ndarray, shape (p,)
        ``y - M x_hat``, the attack estimate.
    pruning : PrunedSupportPrior or None
        The pruning that chose ``trusted``, when the observer pruned a prior.
    """

    x_hat: np.ndarray
    weights: np.ndarray
    trusted: tuple[int, ...]
    omega: float
    residual: np.ndarray
    pruning: PrunedSupportPrior | None = None


def _omega(value: object) -> float:
    return as_float_option(value, "omega", min_value=0.0, max_value=1.0)


def _weighted_estimate(
    M: np.ndarray,
    y: np.ndarray,
    trusted: tuple[int, ...],
    omega: float,
    pruning: PrunedSupportPrior | None,
) -> WeightedL1Estimate:
    weights = np.full(M.shape[0], omega)
    weights[list(trusted)] = 1.0
    if not np.any(weights > 0):
        raise ValueError("omega must be > 0 when no row is trusted, got omega = 0.0")
    x_hat = _weighted_l1_fit(M, y, weights)
    x_hat.flags.writeable = False
    weights.flags.writeable = False
    residual = y - M @ x_hat
    residual.flags.writeable = False
    return WeightedL1Estimate(x_hat, weights, trusted, omega, residual, pruning)


def weighted_l1_observer(
    M: np.ndarray, y: np.ndarray, trusted: Sequence[int], *, omega: float = 0.05
) -> WeightedL1Estimate:
    """Weighted l1 observer (15) for given trusted rows.

    Minimises ``sum_i w_i |y_i - (M x)_i|`` with ``w_i = 1`` for ``i`` in
    ``trusted`` (the pruned prior T-hat complement sub eta) and
    ``w_i = omega`` for the other rows (T-hat sub eta), as in Definition 5.

    Parameters
    ----------
    M : array_like, shape (p, n)
        Observation matrix (static ``C`` or the stacked window ``H``).
    y : array_like, shape (p,)
        Measurements.
    trusted : sequence of int
        Rows believed safe (0-based).
    omega : float, default 0.05
        Weight of the untrusted rows, in [0, 1].  The paper asks for a value
        "close to zero, but not zero" (Remark 5) and gives none.

    Returns
    -------
    WeightedL1Estimate

    Raises
    ------
    TypeError
        If an argument has the wrong type.
    ValueError
        If shapes disagree, an index is out of range or repeated, ``omega``
        is outside [0, 1], or ``omega = 0`` with no trusted row.

    Examples
    --------
    >>> import numpy as np
    >>> M = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, -1.0], [2.0, 1.0]])
    >>> y = M @ np.array([1.0, -2.0])
    >>> y[2:] += [5.0, -7.0, 3.0]        # three of five rows attacked
    >>> estimate = weighted_l1_observer(M, y, [0, 1])
    >>> np.round(estimate.x_hat, 10).tolist()
    [1.0, -2.0]
    """
    M, y = _measurements(M, y)
    rows = as_index_list(trusted, "trusted", upper=M.shape[0], what="row")
    return _weighted_estimate(M, y, rows, _omega(omega), None)


def pruned_weighted_l1_observer(
    M: np.ndarray,
    y: np.ndarray,
    prior_safe: Sequence[int],
    probs: np.ndarray,
    *,
    reliability: float = 0.9,
    omega: float = 0.05,
) -> WeightedL1Estimate:
    """Weighted l1 observer with pruned prior (Definition 5), static model y = M x + e.

    Prunes the support prior by (13)-(14) (``prune_support_prior``) and
    solves (15) with unit weights on the pruned rows and ``omega`` on the
    others.

    Parameters
    ----------
    M : array_like, shape (p, n)
        Observation matrix (the paper's H; ssecert's C for one step).
    y : array_like, shape (p,)
        Measurements.
    prior_safe : sequence of int
        Support prior: rows declared safe by the localisation algorithm.
    probs : array_like, shape (p,)
        p_i, probability that the prior is right about row i, in [0, 1].
    reliability : float, default 0.9
        eta of (13), in (0, 1).
    omega : float, default 0.05
        Weight of the rows outside the pruned prior, in [0, 1].

    Returns
    -------
    WeightedL1Estimate
        With ``pruning`` set.

    Raises
    ------
    TypeError
        If an argument has the wrong type.
    ValueError
        If shapes disagree or an option is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> M = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, -1.0], [2.0, 1.0]])
    >>> y = M @ np.array([1.0, -2.0])
    >>> y[2:] += [5.0, -7.0, 3.0]
    >>> probs = [0.99, 0.99, 0.6, 0.9, 0.9]
    >>> estimate = pruned_weighted_l1_observer(M, y, [0, 1, 2], probs)
    >>> estimate.trusted, np.round(estimate.x_hat, 10).tolist()
    ((0, 1), [1.0, -2.0])
    """
    M, y = _measurements(M, y)
    probs = _probabilities(probs)
    if probs.size != M.shape[0]:
        raise ValueError(
            f"probs has the wrong number of entries: expected {M.shape[0]} "
            f"(one per row of M), got {probs.size}"
        )
    pruning = prune_support_prior(prior_safe, probs, reliability=reliability)
    return _weighted_estimate(M, y, pruning.trusted, _omega(omega), pruning)


def pruned_weighted_l1_window_observer(
    H: np.ndarray,
    y_window: np.ndarray,
    prior_safe: Sequence[int],
    probs: np.ndarray,
    *,
    sensors: int,
    reliability: float = 0.9,
    omega: float = 0.05,
) -> WeightedL1Estimate:
    """Weighted l1 observer with pruned prior on the stacked window model (3).

    ``y_window = H x + e`` with ``H = [C; C A; ...; C A^(T-1)]`` (T steps,
    ``sensors`` = m rows per step) and ``x`` the state at the first step of
    the window.  The paper stacks ``y_T`` newest first but ``H`` with ``C``
    on top, which pairs the newest measurement with ``C``; here both are
    oldest first (row ``j * m + i`` is sensor ``i`` at step ``j``, as in
    ``System.observability_matrix``).  The prior is per stacked row (the
    paper's q-hat in {0, 1}^(T m)).

    Parameters
    ----------
    H : array_like, shape (T * m, n)
        Stacked observation matrix.
    y_window : array_like, shape (T * m,)
        Stacked measurements, oldest step first.
    prior_safe : sequence of int
        Stacked rows declared safe by the localisation algorithm.
    probs : array_like, shape (T * m,)
        p_i per stacked row, in [0, 1].
    sensors : int
        m, the number of sensors per step; must divide the rows of ``H``.
    reliability : float, default 0.9
        eta of (13), in (0, 1).
    omega : float, default 0.05
        Weight of the rows outside the pruned prior, in [0, 1].

    Returns
    -------
    WeightedL1Estimate
        ``x_hat`` estimates the state at the first step of the window;
        ``trusted`` lists stacked rows (step ``r // m``, sensor ``r % m``).

    Raises
    ------
    TypeError
        If an argument has the wrong type.
    ValueError
        If ``sensors`` does not divide the rows of ``H``, shapes disagree
        or an option is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> from ssecert import System
    >>> plant = System([[0.0, 1.0], [-1.0, 0.0]], [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    >>> H = plant.observability_matrix(2)                 # 2 steps of 3 sensors
    >>> y = H @ np.array([2.0, -1.0])
    >>> y[[1, 2, 4, 5]] += [4.0, -3.0, 6.0, 2.0]          # sensors 1, 2 attacked
    >>> probs = np.array([0.99, 0.7, 0.7, 0.99, 0.7, 0.7])
    >>> estimate = pruned_weighted_l1_window_observer(H, y, [0, 2, 3], probs, sensors=3)
    >>> estimate.trusted, np.round(estimate.x_hat, 10).tolist()
    ((0, 3), [2.0, -1.0])
    """
    H = as_real_matrix(H, "H")
    m = as_int_option(sensors, "sensors", min_value=1)
    if H.shape[0] % m:
        raise ValueError(
            f"H must have a multiple of sensors = {m} rows (T steps of m sensors), "
            f"got {H.shape[0]} rows"
        )
    y_window = as_real_matrix(
        y_window, "y_window", ndim=1, shape=(H.shape[0],), shape_hint="one entry per row of H"
    )
    probs = _probabilities(probs)
    if probs.size != H.shape[0]:
        raise ValueError(
            f"probs has the wrong number of entries: expected {H.shape[0]} "
            f"(one per row of H), got {probs.size}"
        )
    pruning = prune_support_prior(prior_safe, probs, reliability=reliability)
    return _weighted_estimate(H, y_window, pruning.trusted, _omega(omega), pruning)
