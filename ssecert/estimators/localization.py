"""Target localization by RSS fingerprinting under sparse sensor attacks.

The thesis (Cilia, Sec. 6.3) and the lecture notes (Migliaccio, Ch. 3)
localize one target in a room split into n cells, from the received signal
strength (RSS) measured by q sensors:

* **training:** the target is placed at the centre of each cell j and each
  sensor i records D_ij, here computed from the log-distance path-loss model
  (thesis (6.2)) RSS(d) = P_t - P_l - 10 alpha log10(d / d0) + xi;
* **runtime:** one snapshot y = D x + a (+ noise), with x in {0, 1}^n the
  one-hot indicator of the target's cell and a in R^q a sparse attack on
  the measurements, is decoded by the elastic net of Algorithm 3 on
  G = [D I_q].

The documents name tracking a moving target as a related problem but
describe no tracking algorithm, so this module is static: one snapshot per
call (batched over snapshots), no ``DynamicObserver``.

Units: positions and distances in metres, P_t in dBm, P_l in dB, RSS and
attacks in dBm (dB for attacks and noise).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..base.validation import as_choice, as_float_option, as_int_option, as_real_matrix, describe
from .shrinkage import elastic_net_shrink

__all__ = [
    "path_loss_rss",
    "RSSDictionary",
    "rss_dictionary",
    "LocalizationScenario",
    "localization_scenario",
    "LocalizationResult",
    "elastic_net_localization",
]


def path_loss_rss(
    d: Any,
    *,
    P_t: float = 25.0,
    P_l: float = 40.2,
    alpha: float = 3.0,
    d0: float = 1.0,
) -> np.ndarray:
    """Noise-free RSS of the log-distance path-loss model (thesis (6.2)), in dBm.

    RSS(d) = P_t - P_l - 10 alpha log10(d / d0) for d >= d0; the model is a
    far-field law, so distances below d0 are evaluated at d0 (the RSS
    saturates at P_t - P_l).

    Parameters
    ----------
    d : array_like
        Transmitter-receiver distances in metres, >= 0.
    P_t : float, default 25.0
        Transmission power in dBm.
    P_l : float, default 40.2
        Average path loss at the reference distance, in dB (40.2 dB is the
        IEEE 802.15.4 value at 1 m and 2.4 GHz; the thesis gives no value).
    alpha : float, default 3.0
        Attenuation (path-loss) exponent, > 0; 2 in free space, 2-4 indoors.
    d0 : float, default 1.0
        Reference distance in metres, > 0.

    Returns
    -------
    ndarray
        RSS in dBm, the shape of ``d``.

    Raises
    ------
    ValueError
        If a distance is negative or not finite, or an option out of range.

    Examples
    --------
    >>> import numpy as np
    >>> np.round(path_loss_rss([0.5, 1.0, 10.0], P_t=25.0, P_l=40.2, alpha=2.0), 9).tolist()
    [-15.2, -15.2, -35.2]
    """
    P_t = as_float_option(P_t, "P_t")
    P_l = as_float_option(P_l, "P_l")
    alpha = as_float_option(alpha, "alpha", min_value=0.0, min_inclusive=False)
    d0 = as_float_option(d0, "d0", min_value=0.0, min_inclusive=False)
    dist = np.asarray(d, dtype=float)
    if not np.all(np.isfinite(dist)) or np.any(dist < 0):
        raise ValueError("d must contain finite distances >= 0 (metres)")
    return P_t - P_l - 10.0 * alpha * np.log10(np.maximum(dist, d0) / d0)


@dataclass(frozen=True)
class RSSDictionary:
    """RSS fingerprints of a grid of cells (the training phase).

    Attributes
    ----------
    D : ndarray, shape (q, n)
        ``D[i, j]``: RSS in dBm at sensor i with the target at the centre of
        cell j.
    cell_centers : ndarray, shape (n, 2)
        Cell centres (x, y) in metres; cell j is row ``j // cols``, column
        ``j % cols`` of the grid, x along columns.
    sensor_positions : ndarray, shape (q, 2)
        Sensor positions in metres.
    grid : tuple of int
        (rows, cols), n = rows * cols.
    cell_size : float
        Side of a square cell in metres.
    P_t, P_l, alpha, d0 : float
        Path-loss parameters (dBm, dB, exponent, metres).
    """

    D: np.ndarray
    cell_centers: np.ndarray
    sensor_positions: np.ndarray
    grid: tuple[int, int]
    cell_size: float
    P_t: float
    P_l: float
    alpha: float
    d0: float

    @property
    def n(self) -> int:
        """Number of cells."""
        return self.D.shape[1]

    @property
    def q(self) -> int:
        """Number of sensors."""
        return self.D.shape[0]


def _grid_positions(q: int, width: float, height: float) -> np.ndarray:
    """q sensors on the most square rows x cols grid with rows * cols = q, centred in cells."""
    rows = max(r for r in range(1, int(np.sqrt(q)) + 1) if q % r == 0)
    cols = q // rows
    if width < height:
        rows, cols = cols, rows
    xs = (np.arange(cols) + 0.5) * width / cols
    ys = (np.arange(rows) + 0.5) * height / rows
    X, Y = np.meshgrid(xs, ys)
    return np.column_stack([X.ravel(), Y.ravel()])


def rss_dictionary(
    *,
    grid: tuple[int, int] = (10, 10),
    cell_size: float = 1.0,
    q: int = 20,
    deployment: str = "random",
    sensor_positions: Any = None,
    P_t: float = 25.0,
    P_l: float = 40.2,
    alpha: float = 3.0,
    d0: float = 1.0,
    seed: int | None = None,
) -> RSSDictionary:
    """Fingerprint dictionary D (q x n) of a rows x cols grid from the path-loss model (6.2).

    Parameters
    ----------
    grid : tuple of int, default (10, 10)
        (rows, cols) of square cells; the thesis's example has n = 100 cells.
    cell_size : float, default 1.0
        Side of a cell in metres (the room is cols * cell_size wide).
    q : int, default 20
        Number of sensors (the thesis's example has 20).
    deployment : {"random", "grid"}, default "random"
        Uniform random positions in the room, or a regular grid of q sensors
        (the two deployments of the lecture notes, Sec. 3.2.1).  Ignored
        when ``sensor_positions`` is given.
    sensor_positions : array_like, shape (q, 2), optional
        Explicit sensor positions in metres.
    P_t : float, default 25.0
        Transmission power in dBm.
    P_l : float, default 40.2
        Average path loss at d0 in dB.
    alpha : float, default 3.0
        Attenuation exponent.
    d0 : float, default 1.0
        Reference distance in metres; closer sensors read RSS(d0).
    seed : int or None, default None
        Seed of ``numpy.random.default_rng`` for random deployment.

    Returns
    -------
    RSSDictionary

    Raises
    ------
    TypeError, ValueError
        On a bad option; messages name the argument.

    Examples
    --------
    >>> dic = rss_dictionary(grid=(2, 2), q=2, sensor_positions=[[0.5, 0.5], [1.5, 1.5]],
    ...                      alpha=2.0)
    >>> dic.D.shape, dic.n, dic.q
    ((2, 4), 4, 2)
    >>> round(float(dic.D[0, 0]), 4), round(float(dic.D[0, 3]), 4)   # -15.2 - 20 log10(sqrt 2)
    (-15.2, -18.2103)
    """
    if not isinstance(grid, (tuple, list)) or len(grid) != 2:
        raise TypeError(f"grid must be a pair (rows, cols), got {describe(grid)}")
    rows = as_int_option(grid[0], "grid[0]", min_value=1)
    cols = as_int_option(grid[1], "grid[1]", min_value=1)
    cell_size = as_float_option(cell_size, "cell_size", min_value=0.0, min_inclusive=False)
    width, height = cols * cell_size, rows * cell_size
    if sensor_positions is not None:
        S = as_real_matrix(
            sensor_positions, "sensor_positions", shape=(None, 2), shape_hint="(x, y) in metres"
        )
        q = S.shape[0]
    else:
        q = as_int_option(q, "q", min_value=1)
        deployment = as_choice(deployment, "deployment", ("random", "grid"))
        if deployment == "random":
            rng = np.random.default_rng(seed)
            S = rng.uniform(0.0, 1.0, (q, 2)) * [width, height]
        else:
            S = _grid_positions(q, width, height)
    r, c = np.divmod(np.arange(rows * cols), cols)
    centers = np.column_stack([(c + 0.5) * cell_size, (r + 0.5) * cell_size])
    dist = np.linalg.norm(S[:, None, :] - centers[None, :, :], axis=-1)
    D = path_loss_rss(dist, P_t=P_t, P_l=P_l, alpha=alpha, d0=d0)
    S = np.array(S, dtype=float)
    for arr in (D, centers, S):
        arr.flags.writeable = False
    return RSSDictionary(
        D, centers, S, (rows, cols), cell_size, float(P_t), float(P_l), float(alpha), float(d0)
    )


@dataclass(frozen=True)
class LocalizationScenario:
    """Runtime snapshots y = D x + a + xi, one per run.

    Attributes
    ----------
    y : ndarray, shape (runs, q)
        Measured RSS in dBm.
    cell : ndarray of int, shape (runs,)
        True cell of the target.
    attack : ndarray, shape (runs, q)
        The attack a (dB), nonzero on the attacked sensors.
    noise : ndarray, shape (runs, q)
        The noise xi (dB).
    """

    y: np.ndarray
    cell: np.ndarray
    attack: np.ndarray
    noise: np.ndarray

    @property
    def attacked(self) -> np.ndarray:
        """Boolean mask of attacked sensors, shape (runs, q)."""
        return self.attack != 0


def localization_scenario(
    dictionary: RSSDictionary,
    *,
    runs: int = 1,
    attacked: int = 0,
    magnitude: tuple[float, float] = (10.0, 20.0),
    xi_std: float = 0.0,
    seed: int | None = None,
) -> LocalizationScenario:
    """Random target cells, attacked sensor sets and attacks on a dictionary.

    Each run draws a cell uniformly, ``attacked`` distinct sensors uniformly,
    and attack values with magnitude uniform in ``magnitude`` (dB) and a
    random sign; xi is Gaussian with standard deviation ``xi_std`` dB.

    Parameters
    ----------
    dictionary : RSSDictionary
    runs : int, default 1
    attacked : int, default 0
        Number of attacked sensors per run, 0 <= attacked <= q.
    magnitude : tuple of float, default (10.0, 20.0)
        Range of |a_i| in dB (the thesis gives none).
    xi_std : float, default 0.0
        Standard deviation of the RSS noise xi in dB.
    seed : int or None, default None
        Seed of ``numpy.random.default_rng``.

    Returns
    -------
    LocalizationScenario

    Examples
    --------
    >>> dic = rss_dictionary(seed=0)
    >>> sc = localization_scenario(dic, runs=3, attacked=2, seed=1)
    >>> sc.y.shape, sc.attacked.sum(axis=1).tolist()
    ((3, 20), [2, 2, 2])
    """
    if not isinstance(dictionary, RSSDictionary):
        raise TypeError(f"dictionary must be an RSSDictionary, got {describe(dictionary)}")
    runs = as_int_option(runs, "runs", min_value=1)
    q, n = dictionary.D.shape
    attacked = as_int_option(attacked, "attacked", min_value=0, max_value=q)
    if not isinstance(magnitude, (tuple, list)) or len(magnitude) != 2:
        raise TypeError(f"magnitude must be a pair (low, high), got {describe(magnitude)}")
    lo = as_float_option(magnitude[0], "magnitude[0]", min_value=0.0, min_inclusive=False)
    hi = as_float_option(magnitude[1], "magnitude[1]", min_value=lo)
    xi_std = as_float_option(xi_std, "xi_std", min_value=0.0)
    rng = np.random.default_rng(seed)
    cell = rng.integers(n, size=runs)
    attack = np.zeros((runs, q))
    for r in range(runs):
        who = rng.choice(q, attacked, replace=False)
        attack[r, who] = rng.choice([-1.0, 1.0], attacked) * rng.uniform(lo, hi, attacked)
    noise = xi_std * rng.standard_normal((runs, q))
    y = dictionary.D[:, cell].T + attack + noise
    return LocalizationScenario(y, cell, attack, noise)


@dataclass(frozen=True)
class LocalizationResult:
    """Output of ``elastic_net_localization``; leading axis runs when y was 2-D.

    Attributes
    ----------
    cell : ndarray of int, shape (...,)
        Estimated cell: the largest entry of x_hat.
    cells : ndarray of int, shape (..., targets)
        The ``targets`` largest entries of x_hat, largest first.
    attacked : ndarray of bool, shape (..., q)
        Estimated attacked sensors: |a_hat_i| > attack_rtol * ||y~||_inf.
    x_hat : ndarray, shape (..., n)
        Cell weights (1 at the target's cell for a perfect estimate).
    a_hat : ndarray, shape (..., q)
        Attack estimate in dB.
    offset : ndarray, shape (...,)
        Estimated common RSS offset c in dB (0 unless ``common_offset``).
    residual : ndarray, shape (...,)
        ||y~ - G~ z~|| / ||y~||: how much of the (preprocessed) snapshot the
        estimate leaves unexplained.
    iterations : ndarray of int, shape (...,)
    converged : ndarray of bool, shape (...,)
        Relative step below ``rtol`` within N iterations (False with rtol = 0).
    identifiable : ndarray of bool, shape (...,)
        2 (targets + |attacked|) <= q, the necessary count for a unique
        sparse explanation (spark(G) <= q + 1); False flags an estimate that
        cannot be trusted whatever the algorithm.
    objective : dict
        Weights of the problem whose minimiser is the fixed point, in the
        preprocessed, normalised variables:
        1/2 ||G~ z - y~||^2 + l1_x ||x||_1 + l1_a ||a||_1
        + (mu_x / 2) ||x||^2 + (mu_a / 2) ||a||^2, with l1 = lambda / t,
        mu = (1/q - 1) / t, t = epsilon * L2; plus ``t``.
    """

    cell: np.ndarray
    cells: np.ndarray
    attacked: np.ndarray
    x_hat: np.ndarray
    a_hat: np.ndarray
    offset: np.ndarray
    residual: np.ndarray
    iterations: np.ndarray
    converged: np.ndarray
    identifiable: np.ndarray
    objective: dict

    def attacked_sensors(self) -> tuple:
        """Indices of the estimated attacked sensors (a tuple per run when batched).

        Examples
        --------
        >>> import numpy as np
        >>> dic = rss_dictionary(seed=0)
        >>> y = dic.D[:, 7] + np.eye(20)[3] * 15.0
        >>> elastic_net_localization(dic.D, y).attacked_sensors()
        (3,)
        """
        if self.attacked.ndim == 1:
            return tuple(int(i) for i in np.flatnonzero(self.attacked))
        return tuple(tuple(int(i) for i in np.flatnonzero(row)) for row in self.attacked)


# the ``method`` of ``elastic_net_localization``: whether its iterations take Nesterov momentum
_ACCELERATE = {"fista": True, "ista": False}


def elastic_net_localization(
    D: Any,
    y: Any,
    *,
    lambda_x: float | None = None,
    lambda_a: float | None = None,
    q_x: float = 1.0,
    q_a: float = 1.0,
    L2: float = 1.0,
    epsilon: float | None = None,
    N: int = 20000,
    method: str = "fista",
    normalize: bool = True,
    common_offset: bool = True,
    rtol: float = 1e-9,
    targets: int = 1,
    attack_rtol: float = 1e-3,
) -> LocalizationResult:
    """Localize a target and find attacked sensors: Algorithm 3 of the thesis (elastic net).

    With G = [D I_q] and z = (x, a), Algorithm 3 iterates from z = 0

        gamma = z - epsilon L2 G^T (G z - y),
        x = q_x S_{lambda_x}(gamma_x),   a = q_a S_{lambda_a}(gamma_a),

    (S the soft threshold), N times.  Its fixed point minimises
    1/2 ||G z - y||^2 + (lambda_x/t) ||x||_1 + (lambda_a/t) ||a||_1
    + (mu_x/2) ||x||^2 + (mu_a/2) ||a||^2 with t = epsilon L2 and
    mu = (1/q - 1)/t (the thesis's objective writes ||.||^2 without the 1/2,
    but its iteration is the gradient step of the 1/2 form).  The cell is the
    largest entry of x, the attacked sensors the nonzero entries of a.

    One snapshot per row of ``y``, no dynamics: the thesis names tracking but
    describes no tracking algorithm, so this is a plain function, not a
    ``DynamicObserver``.

    Three options, on by default, depart from the printed algorithm; the
    thesis-literal call is ``normalize=False, common_offset=False,
    method="ista", N=1000, rtol=0``.  On path-loss dictionaries the
    literal algorithm does not converge in 1000 iterations (every
    fingerprint is close to the constant P_t - P_l, so G is very
    ill-conditioned; benchmarks/exp_localization.py measures it):

    * ``normalize``: run on G with unit-norm columns (z scaled back after),
      a weighted l1 in the original variables that puts cells and attacks on
      an equal footing (the raw columns of D are ~100 times longer than
      those of I_q);
    * ``common_offset``: allow an unpenalised offset c on every sensor,
      y = D x + a + c 1 (e.g. the target's transmit power differing from the
      training one); c is eliminated by projecting y and G onto the
      complement of 1, which also removes the dominant singular value;
    * ``method="fista"``: Nesterov momentum with adaptive restart on the same
      operator (same fixed point), and a stop when the relative step falls
      below ``rtol``.

    Parameters
    ----------
    D : array_like, shape (q, n)
        Fingerprint dictionary (dBm).
    y : array_like, shape (q,) or (runs, q)
        Snapshot(s) of measured RSS (dBm); runs are solved together.
    lambda_x, lambda_a : float or None, default None
        Per-iteration soft-threshold levels; None means 0.05 * epsilon * L2
        (objective weight 0.05, suited to normalised columns).
    q_x, q_a : float, default 1.0
        Elastic-net shrink factors in (0, 1]; the thesis takes (0, 1) and
        1 is the Lasso limit.  Below 1 the ridge part spreads x over
        neighbouring cells, whose fingerprints are almost collinear.
    L2 : float, default 1.0
        Scalar gain (> 0) of the gradient step.
    epsilon : float or None, default None
        Step; None means 0.99 / (L2 ||G~||_2^2) (the iteration converges for
        epsilon L2 ||G~||_2^2 < 2).
    N : int, default 20000
        Maximum number of iterations.
    method : {"fista", "ista"}, default "fista"
    normalize : bool, default True
    common_offset : bool, default True
    rtol : float, default 1e-9
        Stop a run when max |z(k+1) - z(k)| <= rtol * max |z(k+1)| (in the
        normalised variables); 0 runs exactly N iterations.
    targets : int, default 1
        Number of cells reported in ``cells``.
    attack_rtol : float, default 1e-3
        Sensor i is attacked when |a_hat_i| > attack_rtol * ||y~||_inf.

    Returns
    -------
    LocalizationResult

    Raises
    ------
    TypeError
        If an argument has the wrong kind.
    ValueError
        If shapes disagree, an entry is not finite, or an option is out of
        range (including epsilon L2 ||G~||^2 >= 2).

    Examples
    --------
    >>> import numpy as np
    >>> dic = rss_dictionary(seed=0)
    >>> a = np.zeros(20); a[[4, 11]] = [12.0, -15.0]
    >>> res = elastic_net_localization(dic.D, dic.D[:, 42] + a)
    >>> int(res.cell), res.attacked_sensors()
    (42, (4, 11))
    """
    D = as_real_matrix(D, "D")
    q, n = D.shape
    single = np.ndim(y) == 1
    Y = as_real_matrix(
        y,
        "y",
        ndim=1 if single else 2,
        shape=(q,) if single else (None, q),
        shape_hint="the number of sensors, rows of D",
    )
    Y = np.atleast_2d(Y)
    q_x = as_float_option(q_x, "q_x", min_value=0.0, max_value=1.0, min_inclusive=False)
    q_a = as_float_option(q_a, "q_a", min_value=0.0, max_value=1.0, min_inclusive=False)
    L2 = as_float_option(L2, "L2", min_value=0.0, min_inclusive=False)
    N = as_int_option(N, "N", min_value=1)
    accelerate = _ACCELERATE[as_choice(method, "method", tuple(_ACCELERATE))]
    for flag, name in ((normalize, "normalize"), (common_offset, "common_offset")):
        if not isinstance(flag, (bool, np.bool_)):
            raise TypeError(f"{name} must be True or False, got {describe(flag)}")
    rtol = as_float_option(rtol, "rtol", min_value=0.0)
    targets = as_int_option(targets, "targets", min_value=1, max_value=n)
    attack_rtol = as_float_option(attack_rtol, "attack_rtol", min_value=0.0)

    G = np.hstack([D, np.eye(q)])
    Yt = Y
    if common_offset:
        G = G - G.mean(axis=0)
        Yt = Y - Y.mean(axis=1, keepdims=True)
    w = np.linalg.norm(G, axis=0) if normalize else np.ones(n + q)
    if np.any(w <= 0):
        raise ValueError(
            "D has a zero column (after removing the common offset): a cell "
            "with a fingerprint equal to a constant cannot be localized"
        )
    Gt = G / w
    sigma2 = np.linalg.norm(Gt, 2) ** 2
    step: float | np.floating[Any]
    if epsilon is None:
        step = 0.99 / (L2 * sigma2)
    else:
        step = as_float_option(epsilon, "epsilon", min_value=0.0, min_inclusive=False)
        if step * L2 * sigma2 >= 2.0:
            raise ValueError(
                f"epsilon must satisfy epsilon * L2 * ||G||^2 < 2 for convergence; got "
                f"epsilon = {step:.3g}, bound {2.0 / (L2 * sigma2):.3g}"
            )
    t = step * L2
    level_x = (
        0.05 * t
        if lambda_x is None
        else as_float_option(lambda_x, "lambda_x", min_value=0.0, min_inclusive=False)
    )
    level_a = (
        0.05 * t
        if lambda_a is None
        else as_float_option(lambda_a, "lambda_a", min_value=0.0, min_inclusive=False)
    )

    thr = np.concatenate([np.full(n, level_x), np.full(q, level_a)])
    shrink = np.concatenate([np.full(n, q_x), np.full(q, q_a)])
    Z, iterations, converged = _algorithm3(Gt, Yt, t, thr, shrink, N, accelerate, rtol)

    Zs = Z / w
    x_hat, a_hat = Zs[:, :n], Zs[:, n:]
    explained = Z @ Gt.T
    denom = np.maximum(np.linalg.norm(Yt, axis=1), np.finfo(float).tiny)
    residual = np.linalg.norm(Yt - explained, axis=1) / denom
    offset = (Y - x_hat @ D.T - a_hat).mean(axis=1) if common_offset else np.zeros(len(Y))
    cells = np.argsort(-x_hat, axis=1, kind="stable")[:, :targets]
    attacked = np.abs(a_hat) > attack_rtol * np.abs(Yt).max(axis=1, keepdims=True)
    identifiable = 2 * (targets + attacked.sum(axis=1)) <= q
    objective = {
        "t": t,
        "l1_x": level_x / t,
        "l1_a": level_a / t,
        "mu_x": (1.0 / q_x - 1.0) / t,
        "mu_a": (1.0 / q_a - 1.0) / t,
    }
    pick = (lambda arr: arr[0]) if single else (lambda arr: arr)
    return LocalizationResult(
        cell=pick(cells[:, 0]),
        cells=pick(cells),
        attacked=pick(attacked),
        x_hat=pick(x_hat),
        a_hat=pick(a_hat),
        offset=pick(offset),
        residual=pick(residual),
        iterations=pick(iterations),
        converged=pick(converged),
        identifiable=pick(identifiable),
        objective=objective,
    )


def _algorithm3(Gt, Y, t, thr, shrink, N, accelerate, rtol):
    """Algorithm 3 (optionally with FISTA momentum), batched over the rows of Y."""
    runs, size = Y.shape[0], Gt.shape[1]
    GtG = t * (Gt.T @ Gt)
    GtY = t * (Y @ Gt)
    Z = np.zeros((runs, size))
    out = np.zeros((runs, size))
    iterations = np.full(runs, N)
    converged = np.zeros(runs, dtype=bool)
    idx = np.arange(runs)
    V = Z.copy()
    tk = np.ones(runs)
    for it in range(1, N + 1):
        gamma = V - V @ GtG + GtY
        Zn = elastic_net_shrink(gamma, thr, shrink)
        Dz = Zn - Z
        if accelerate:
            tn = 0.5 * (1.0 + np.sqrt(1.0 + 4.0 * tk * tk))
            restart = np.einsum("ij,ij->i", V - Zn, Dz) > 0
            tn[restart] = 1.0
            mom = (tk - 1.0) / tn
            mom[restart] = 0.0
            V = Zn + mom[:, None] * Dz
            tk = tn
        else:
            V = Zn
        Z = Zn
        if rtol > 0:
            done = np.abs(Dz).max(axis=1) <= rtol * np.abs(Zn).max(axis=1)
            if done.any():
                out[idx[done]] = Zn[done]
                iterations[idx[done]] = it
                converged[idx[done]] = True
                keep = ~done
                idx, Z, V, tk, GtY = idx[keep], Z[keep], V[keep], tk[keep], GtY[keep]
                if idx.size == 0:
                    break
    out[idx] = Z
    return out, iterations, converged
