"""Hypothesis strategies for plants, sparse attacks and observer designs.

Every strategy builds what it promises by construction instead of filtering
random draws, so that ssecert's own analyses decide each draw (``holds``, not
``inconclusive``) and the tests stay fast:

* ``observable_systems(n, p)``: observable plants with a comfortable PBH
  margin;
* ``sparse_observable_systems(n, p, max_removable)``: plants whose
  ``max_removable`` (the largest k such that removing any k sensors keeps
  (A, C) observable) is exactly the given value;
* ``marginally_stable_systems(n, p)``: an eigenvalue exactly at 1 (a state
  that integrates, like the position of a vehicle), the others inside the
  unit disc, observable;
* ``sparse_attacks(p, s, steps)``: attack sequences on one set of at most
  s sensors, the same at every step: the threat model of ssecert's
  certificates (supports that switch over time on request);
* ``observer_designs(system)``: validated designs (``Spec`` with an
  ``[observer]`` section) whose gain can be computed.

Sizes (``n``, ``p``, ``s``, ...) are an int or a hypothesis strategy of
ints.  Continuous data (orthogonal similarities, magnitudes, signs) come
from a ``numpy.random.default_rng`` seeded by a drawn integer; the
structure (sizes, eigenvalues, support sizes) is drawn by hypothesis, so
failing examples shrink towards small plants.

This module needs hypothesis (``pip install "ssecert[testing]"``); the rest
of ``ssecert.testing`` does not.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from hypothesis import reject
from hypothesis import strategies as st
from hypothesis.strategies import SearchStrategy

from ..base.validation import as_float_option, describe
from ..observers import ObserverKind, get_kind, observer_kinds
from ..observers.strategies import POLE_RADIUS as _POLE_RADIUS
from ..observers.strategies import grid_spectrum as _spectrum
from ..spec import OBSERVER_KINDS, Spec, spec_from_dict
from ..system import System

__all__ = [
    "observable_systems",
    "sparse_observable_systems",
    "marginally_stable_systems",
    "sparse_attacks",
    "observer_designs",
    "ATTACK_SHAPES",
    "FIXED_SUPPORT_SHAPES",
]

ATTACK_SHAPES = ("constant", "switching", "sinusoidal")
# the shapes whose attacked set stays the same over the window, as every certificate assumes
FIXED_SUPPORT_SHAPES = ("constant", "sinusoidal")
_SEEDS = st.integers(0, 2**32 - 1)
_MAGNITUDE = (0.5, 2.0)  # nonzero entries of the modal output matrix


# ---------------------------------------------------------------------------
# argument handling


def _size(value: Any, name: str, minimum: int) -> SearchStrategy[int]:
    """An int or a strategy of ints, as a strategy; ints are checked now, draws when drawn."""
    if isinstance(value, SearchStrategy):
        return value.map(lambda drawn: _drawn(drawn, name, minimum))
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise TypeError(
            f"{name} must be an integer or a hypothesis strategy of integers, got {describe(value)}"
        )
    if value < minimum:
        raise ValueError(f"{name} must be >= {minimum}, got {int(value)}")
    return st.just(int(value))


def _drawn(value: Any, name: str, minimum: int) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"the strategy given as {name} must draw integers, drew {describe(value)}")
    if value < minimum:
        raise ValueError(
            f"the strategy given as {name} drew {int(value)}; {name} must be >= {minimum}"
        )
    return int(value)


def _fixed(value: Any) -> int | None:
    """The value of an argument given as an int, None for a strategy."""
    return None if isinstance(value, SearchStrategy) else int(value)


def _choices(value: Any, name: str, allowed: Sequence[str]) -> tuple[str, ...]:
    if isinstance(value, str) or not isinstance(value, Sequence):
        raise TypeError(
            f"{name} must be a sequence of names from {', '.join(allowed)}; got {describe(value)}"
        )
    chosen = tuple(value)
    if not chosen:
        raise ValueError(f"{name} must name at least one of {', '.join(allowed)}; got none")
    for item in chosen:
        if item not in allowed:
            raise ValueError(f"{name} must contain only {', '.join(allowed)}; got {item!r}")
    return tuple(dict.fromkeys(chosen))


# ---------------------------------------------------------------------------
# plants


def _modal_blocks(spectrum: list[tuple[float, float]]) -> tuple[np.ndarray, list[list[int]]]:
    """Block-diagonal real form M and, per eigenvalue, the columns of its block."""
    n = sum(1 if b == 0 else 2 for _, b in spectrum)
    M = np.zeros((n, n))
    columns: list[list[int]] = []
    start = 0
    for a, b in spectrum:
        if b == 0:
            M[start, start] = a
            columns.append([start])
            start += 1
        else:
            M[start : start + 2, start : start + 2] = [[a, -b], [b, a]]
            columns.append([start, start + 1])
            start += 2
    return M, columns


def _modal_outputs(
    rng: np.random.Generator,
    p: int,
    columns: list[list[int]],
    support_sizes: list[int],
    fixed: int | None = None,
    dyadic: bool = False,
) -> np.ndarray:
    """C_modal: the eigenvalue with columns ``cols`` is seen by ``size`` sensors.

    Nonzero entries have magnitudes in [0.5, 2] with random signs; a sensor
    sees a complex pair through both columns of its block.  A sensor left
    seeing nothing is added to a random eigenvalue other than ``fixed`` (whose
    support size must stay as drawn), when there is one.  With ``dyadic`` the
    magnitudes are multiples of 1/64 (exact binary fractions).
    """
    n = sum(len(c) for c in columns)
    supports = [set(rng.choice(p, size, replace=False).tolist()) for size in support_sizes]
    growable = [i for i in range(len(columns)) if i != fixed]
    for sensor in range(p):
        if growable and not any(sensor in support for support in supports):
            supports[growable[int(rng.integers(len(growable)))]].add(sensor)
    Cm = np.zeros((p, n))
    for cols, support in zip(columns, supports):
        rows = sorted(support)
        shape = (len(rows), len(cols))
        magnitudes = rng.uniform(*_MAGNITUDE, shape)
        if dyadic:
            magnitudes = np.round(magnitudes * 64) / 64
        Cm[np.ix_(rows, cols)] = magnitudes * rng.choice([-1.0, 1.0], shape)
    return Cm


def _orthogonal(rng: np.random.Generator, n: int) -> np.ndarray:
    Q, R = np.linalg.qr(rng.standard_normal((n, n)))
    return Q * np.where(np.diag(R) < 0, -1.0, 1.0)


def _exact_similarity(
    rng: np.random.Generator, M: np.ndarray, Cm: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """A = T M T^-1 and C = C_modal T^-1 computed without rounding.

    T is a permutation times elementary operations (row i += c row j,
    c in {+-1/2, +-1}), whose inverses are exact; with binary-fraction data
    every product is exact too, which is checked (A T == T M and C T ==
    C_modal bit for bit).  If a long product would round, fewer operations
    are used; a permutation alone is always exact.
    """
    n = M.shape[0]
    for operations in (2 * n, n, n // 2, 0):
        T, T_inv = np.eye(n), np.eye(n)
        for _ in range(operations if n > 1 else 0):
            i, j = rng.choice(n, 2, replace=False)
            c = float(rng.choice([-1.0, -0.5, 0.5, 1.0]))
            T[:, j] += c * T[:, i]  # T <- T (I + c e_i e_j^T)
            T_inv[i, :] -= c * T_inv[j, :]  # T^-1 <- (I - c e_i e_j^T) T^-1
        perm = rng.permutation(n)
        T, T_inv = T[perm], T_inv[:, perm]
        A, C = T @ M @ T_inv, Cm @ T_inv
        if (
            np.array_equal(T @ T_inv, np.eye(n))
            and np.array_equal(A @ T, T @ M)
            and np.array_equal(C @ T, Cm)
        ):
            return A, C
    raise AssertionError("a permutation similarity cannot round")  # pragma: no cover


@st.composite
def _modal_plant(
    draw: Any,
    n: SearchStrategy[int],
    p: SearchStrategy[int],
    max_removable: SearchStrategy[int] | None,
    name: str,
) -> System:
    n_ = draw(n)
    p_ = draw(p)
    exact = max_removable is not None
    if max_removable is None:
        low = 0
    else:
        low = draw(max_removable)
        if low > p_ - 1:
            reject()  # this p is too small for the requested max_removable
    spectrum = _spectrum(draw, n_, 1.0, dyadic=exact)
    M, columns = _modal_blocks(spectrum)
    sizes = [draw(st.integers(low + 1, p_)) for _ in columns]
    weakest = None
    if exact:
        # the weakest eigenvalue is seen by exactly max_removable + 1 sensors
        weakest = draw(st.integers(0, len(columns) - 1))
        sizes[weakest] = low + 1
    rng = np.random.default_rng(draw(_SEEDS))
    Cm = _modal_outputs(rng, p_, columns, sizes, weakest, dyadic=exact)
    if exact:
        A, C = _exact_similarity(rng, M, Cm)
        return System(A, C, name=name)
    Q = _orthogonal(rng, n_)
    # C v = C_modal e for the eigenvector v = Q e: the sensor pattern survives the similarity
    return System(Q @ M @ Q.T, Cm @ Q.T, name=name)


def observable_systems(
    n: int | SearchStrategy[int], p: int | SearchStrategy[int]
) -> SearchStrategy[System]:
    """Observable plants with a comfortable margin, built so ``observability`` decides them.

    A = Q M Q^T with M block diagonal in real modal form and Q a random
    orthogonal matrix; C = C_modal Q^T.  The eigenvalues are distinct, real
    or in complex conjugate pairs, in the closed unit disc, and any two
    differ by at least 1 / max(6, n).  Every eigenvalue is seen by at least
    one sensor through entries of C_modal of magnitude in [0.5, 2], so the
    PBH test passes at every eigenvalue with a margin far above rounding.

    Parameters
    ----------
    n : int or strategy of int
        Number of states (>= 1).
    p : int or strategy of int
        Number of sensors (>= 1).

    Returns
    -------
    SearchStrategy of System
        Sensors named ``y1``, ..., ``yp``; system name ``"observable"``.

    Raises
    ------
    TypeError
        If a size is neither an int nor a strategy.
    ValueError
        If a size is below 1.

    Examples
    --------
    >>> from hypothesis import given, strategies as st
    >>> from ssecert import observability
    >>> @given(observable_systems(st.integers(1, 4), 2))
    ... def check(system):
    ...     assert observability(system).verdict.value == "holds"
    >>> check()
    """
    return _modal_plant(_size(n, "n", 1), _size(p, "p", 1), None, "observable")


def sparse_observable_systems(
    n: int | SearchStrategy[int],
    p: int | SearchStrategy[int],
    max_removable: int | SearchStrategy[int],
) -> SearchStrategy[System]:
    """Plants whose max_removable is exactly the given value, by construction.

    max_removable is the largest k such that removing any k sensors keeps
    (A, C) observable; a plant tolerates s attacked sensors iff
    2 s <= max_removable.  In modal coordinates A is block diagonal M
    (distinct real eigenvalues and complex pairs in the closed unit disc, on
    a grid of spacing at least 1/8 for n <= 8) and each eigenvalue is seen
    by at least ``max_removable + 1`` sensors, one eigenvalue by exactly
    that many (nonzero entries of C_modal of magnitude in [0.5, 2]).
    Removing those sensors hides its eigenvector, and no smaller set hides
    any, so max_removable = min over eigenvalues of (sensors seeing it) - 1.
    Every sensor sees some eigenvalue, except when A has a single real
    eigenvalue or a single complex pair (it is seen by exactly
    max_removable + 1 sensors; the others see nothing).

    The structure holds exactly in floating point, not only up to
    rounding: eigenvalues and C_modal are binary fractions and A = T M T^-1,
    C = C_modal T^-1 with T a permutation times elementary operations whose
    products are exact (A T == T M and C T == C_modal, checked bit for bit).
    The data thus carries no rounding error that could push a rank decision
    into a tolerance's borderline band; only the analyses' own arithmetic
    rounds.

    Parameters
    ----------
    n : int or strategy of int
        Number of states (>= 1).
    p : int or strategy of int
        Number of sensors (>= 1).
    max_removable : int or strategy of int
        The value to plant, 0 <= max_removable <= p - 1.  When p or
        max_removable is drawn, draws with max_removable > p - 1 are
        rejected (hypothesis reports ``filter_too_much`` if most are).

    Returns
    -------
    SearchStrategy of System
        Sensors named ``y1``, ..., ``yp``; system name ``"sparse-observable"``.

    Raises
    ------
    TypeError
        If an argument is neither an int nor a strategy.
    ValueError
        If n or p is below 1, max_removable is negative, or (both given as
        ints) max_removable > p - 1.

    Examples
    --------
    >>> from hypothesis import given
    >>> from ssecert import sparse_observability
    >>> @given(sparse_observable_systems(3, 4, 2))
    ... def check(system):
    ...     assert sparse_observability(system, 1).fields["max_removable"] == 2
    >>> check()
    """
    n_ = _size(n, "n", 1)
    p_ = _size(p, "p", 1)
    mr = _size(max_removable, "max_removable", 0)
    fixed_p, fixed_mr = _fixed(p), _fixed(max_removable)
    if fixed_p is not None and fixed_mr is not None and fixed_mr > fixed_p - 1:
        raise ValueError(
            f"max_removable must be between 0 and p - 1 = {fixed_p - 1} (removing all {fixed_p} "
            f"sensors always leaves the plant unobservable), got {fixed_mr}"
        )
    return _modal_plant(n_, p_, mr, "sparse-observable")


@st.composite
def _marginal_plant(draw: Any, n: SearchStrategy[int], p: SearchStrategy[int]) -> System:
    n_ = draw(n)
    p_ = draw(p)
    others = [a for a, _ in _spectrum(draw, n_ - 1, _POLE_RADIUS, pairs=False)]
    sizes = [draw(st.integers(1, p_)) for _ in range(n_)]
    rng = np.random.default_rng(draw(_SEEDS))
    U = np.diag([1.0] + others) + np.triu(rng.uniform(-0.5, 0.5, (n_, n_)), 1)
    # C V = C_modal for the eigenvector matrix V: eigenvector i is seen by sizes[i] sensors
    _, V = np.linalg.eig(U)
    Cm = _modal_outputs(rng, p_, [[i] for i in range(n_)], sizes)
    C = Cm @ np.linalg.inv(np.real(V))
    perm = rng.permutation(n_)
    # a permutation similarity is exact: the eigenvalue stays exactly 1, with eigenvector
    # the coordinate axis perm^-1(0)
    return System(U[np.ix_(perm, perm)], C[:, perm], name="marginally-stable")


def marginally_stable_systems(
    n: int | SearchStrategy[int], p: int | SearchStrategy[int]
) -> SearchStrategy[System]:
    """Observable plants with an eigenvalue exactly at 1 and the others inside the unit disc.

    Like the thesis's vehicle, whose position integrates its velocity.  A is
    an upper-triangular U with diagonal (1, lambda_2, ..., lambda_n),
    distinct real lambda_i with |lambda_i| <= 0.9, and strictly upper
    entries in [-0.5, 0.5], followed by a permutation similarity.  Both
    steps are exact in floating point: column j of A, for the state j that
    the permutation moved the 1 to, is the unit vector e_j, so
    (A - I) e_j = 0 exactly.  C = C_modal V^-1 with V the eigenvectors of U
    and every column of C_modal nonzero (magnitudes in [0.5, 2]), so every
    eigenvector is seen by some sensor: the plant is observable.  Every
    sensor sees at least one eigenvector.

    Parameters
    ----------
    n : int or strategy of int
        Number of states (>= 1).
    p : int or strategy of int
        Number of sensors (>= 1).

    Returns
    -------
    SearchStrategy of System
        Sensors named ``y1``, ..., ``yp``; system name ``"marginally-stable"``.

    Raises
    ------
    TypeError
        If a size is neither an int nor a strategy.
    ValueError
        If a size is below 1.

    Examples
    --------
    >>> import numpy as np
    >>> from hypothesis import given
    >>> @given(marginally_stable_systems(3, 2))
    ... def check(system):
    ...     j = int(np.flatnonzero(np.diag(system.A) == 1.0)[0])
    ...     assert np.array_equal(system.A[:, j], np.eye(3)[j])   # A e_j = e_j exactly
    >>> check()
    """
    return _marginal_plant(_size(n, "n", 1), _size(p, "p", 1))


# ---------------------------------------------------------------------------
# attacks


@st.composite
def _attacks(
    draw: Any,
    p: SearchStrategy[int],
    s: SearchStrategy[int],
    steps: SearchStrategy[int],
    kinds: tuple[str, ...],
    magnitude: tuple[float, float],
) -> np.ndarray:
    p_, s_, steps_ = draw(p), draw(s), draw(steps)
    if s_ > p_:
        reject()
    kind = draw(st.sampled_from(kinds))
    attack = np.zeros((steps_, p_))
    if s_ == 0:
        return attack
    size = draw(st.integers(1, s_))
    rng = np.random.default_rng(draw(_SEEDS))

    def support() -> np.ndarray:
        return np.sort(rng.choice(p_, size, replace=False))

    def values(count: int) -> np.ndarray:
        return rng.uniform(*magnitude, count) * rng.choice([-1.0, 1.0], count)

    if kind == "constant":
        cols = support()
        attack[:, cols] = values(size)
    elif kind == "switching":
        period = draw(st.integers(1, steps_))
        previous = None
        for start in range(0, steps_, period):
            cols = support()
            while previous is not None and size < p_ and np.array_equal(cols, previous):
                cols = support()
            attack[start : start + period, cols] = values(size)
            previous = cols
    else:  # sinusoidal
        period = draw(st.integers(2, max(2, steps_)))
        cols = support()
        phase = rng.uniform(0.0, 2 * np.pi, size)
        k = np.arange(steps_)[:, None]
        attack[:, cols] = values(size) * np.sin(2 * np.pi * k / period + phase)
    return attack


def sparse_attacks(
    p: int | SearchStrategy[int],
    s: int | SearchStrategy[int],
    steps: int | SearchStrategy[int],
    *,
    kinds: Sequence[str] = FIXED_SUPPORT_SHAPES,
    magnitude: tuple[float, float] = (0.5, 5.0),
) -> SearchStrategy[np.ndarray]:
    """Attack sequences a(k) on one fixed set of at most s sensors, by default.

    Every certificate of ssecert assumes the threat model of the documents:
    the adversary controls one set of at most s sensors, the same over the
    whole window.  The default ``kinds`` draw only such attacks.  Each draw
    picks one of ``kinds`` and a number of attacked sensors between 1 and s
    (none when s = 0):

    * ``constant``: a fixed support and fixed values;
    * ``sinusoidal``: a fixed support, ``amplitude * sin(2 pi k / period +
      phase)`` with the period drawn in 2..max(2, steps);
    * ``switching`` (only when asked for): a new support (different whenever
      another exists) and new values every ``period`` steps, the period
      drawn in 1..steps.  At most s sensors are attacked at each step, but
      over the window the attacked sensors can number more than s, up to
      p: outside what the certificates cover.  Use it to probe an observer
      beyond its guarantee, not to test a certified property.

    Values and amplitudes have magnitudes in ``magnitude`` with random
    signs, so every entry is finite and bounded by ``magnitude[1]``.

    Parameters
    ----------
    p : int or strategy of int
        Number of sensors (>= 1).
    s : int or strategy of int
        Largest number of attacked sensors (0 <= s <= p): over the whole
        window for the fixed-support kinds, per step for ``switching``.
        When p or s is drawn, draws with s > p are rejected.
    steps : int or strategy of int
        Number of steps (>= 1).
    kinds : sequence of str, default ("constant", "sinusoidal")
        Attack shapes to draw from, among ``ATTACK_SHAPES`` (constant,
        switching, sinusoidal); the default is ``FIXED_SUPPORT_SHAPES``.
    magnitude : (float, float), default (0.5, 5.0)
        Range [low, high] of the magnitudes, 0 <= low <= high.

    Returns
    -------
    SearchStrategy of numpy.ndarray
        Arrays of shape (steps, p); row k is a(k).

    Raises
    ------
    TypeError
        If a size is neither an int nor a strategy, or kinds is not a
        sequence of names.
    ValueError
        If a size is out of range, s > p (both given as ints), kinds is
        empty or names an unknown shape, or magnitude is not a valid range.

    Examples
    --------
    >>> import numpy as np
    >>> from hypothesis import given
    >>> @given(sparse_attacks(5, 2, 30))
    ... def check(a):
    ...     assert a.shape == (30, 5)
    ...     assert np.count_nonzero(np.abs(a).sum(axis=0)) <= 2   # one set over the window
    >>> check()
    >>> @given(sparse_attacks(5, 2, 30, kinds=["switching"]))
    ... def check_switching(a):
    ...     assert (np.count_nonzero(a, axis=1) <= 2).all()   # at most s at each step only
    >>> check_switching()
    """
    p_ = _size(p, "p", 1)
    s_ = _size(s, "s", 0)
    steps_ = _size(steps, "steps", 1)
    fixed_p, fixed_s = _fixed(p), _fixed(s)
    if fixed_p is not None and fixed_s is not None and fixed_s > fixed_p:
        raise ValueError(
            f"s must be between 0 and p = {fixed_p} (the number of sensors), got {fixed_s}"
        )
    chosen = _choices(kinds, "kinds", ATTACK_SHAPES)
    if (
        isinstance(magnitude, (str, bytes))
        or not isinstance(magnitude, Sequence)
        or len(magnitude) != 2
    ):
        raise TypeError(f"magnitude must be a pair (low, high), got {describe(magnitude)}")
    low = as_float_option(magnitude[0], "magnitude[0]", min_value=0.0)
    high = as_float_option(magnitude[1], "magnitude[1]", min_value=0.0)
    if low > high:
        raise ValueError(f"magnitude must be (low, high) with low <= high, got ({low}, {high})")
    return _attacks(p_, s_, steps_, chosen, (low, high))


# ---------------------------------------------------------------------------
# observer designs


@st.composite
def _designs(
    draw: Any,
    system: System | SearchStrategy[System],
    kinds: tuple[str, ...],
    max_attacked: SearchStrategy[int],
    cache: dict[str, Any],
) -> Spec:
    from ..design.gains import GainError
    from ..observers import build_observer

    if isinstance(system, SearchStrategy):
        plant = draw(system)
        if not isinstance(plant, System):
            raise TypeError(
                f"the strategy given as system must draw System objects, drew {describe(plant)}"
            )
        tables = {}  # each kind's strategy is the plant's
    else:
        plant = system
        tables = cache  # one plant: each kind's strategy made once
    s = draw(max_attacked)
    kind = draw(st.sampled_from(kinds))
    if kind not in tables:
        tables[kind] = get_kind(kind).parameter_strategy(plant)
    table: dict[str, Any] = {"kind": kind, **draw(tables[kind])}
    data = {
        "name": f"{kind}-design",
        "system": {"A": plant.A.tolist(), "C": plant.C.tolist(), "sensors": list(plant.sensors)},
        "attack": {"max_attacked": s},
        "observer": table,
        "scenario": [{"name": "nominal", "attack": "none", "steps": 50, "runs": 4, "seed": 0}],
    }
    spec = spec_from_dict(data, source="observer_designs")
    try:
        build_observer(spec.system, table if spec.observer is None else spec.observer)
    except GainError:
        reject()  # a placement missed its poles: rare, and not a valid design
    return spec


def _drawable() -> tuple[str, ...]:
    """The registered kinds that give a parameter strategy."""
    return tuple(
        name
        for name in observer_kinds()
        if type(get_kind(name)).parameter_strategy is not ObserverKind.parameter_strategy
    )


def observer_designs(
    system: System | SearchStrategy[System],
    *,
    kinds: Sequence[str] = OBSERVER_KINDS,
    max_attacked: int | SearchStrategy[int] = 0,
) -> SearchStrategy[Spec]:
    """Valid observer designs for a plant: accepted by the spec validator and buildable.

    Each draw is a ``Spec`` made by ``ssecert.spec_from_dict`` (validated
    exactly as a spec file) with an ``[observer]`` section whose gain
    ``ssecert.design.observer.build_observer`` computes without
    ``GainError``, and one ``[[scenario]]`` named ``"nominal"`` (no attack,
    50 steps, 4 runs, seed 0).  Valid does not mean certified: drawn designs
    may fail ``assert_certified``.  Each kind draws its own keys
    (``ObserverKind.parameter_strategy``); the built-in kinds draw from:

    =============  ==============================================================
    key            drawn from
    =============  ==============================================================
    gain           luenberger, dsso: deadbeat, place, pinv or an explicit matrix;
                   elastic_net: also ogd.  deadbeat and place only for
                   observable plants, pinv only when C has full column rank;
                   the matrix is a placed (or deadbeat) gain, or step A C^T
    poles          n distinct poles (real or conjugate pairs) in |z| <= 0.9
    step           ogd: f / ||C||^2, sso: f / ||O_tau||^2, f in [0.05, 1];
                   dsso, elastic_net: [0.05, 1]
    threshold      [0.01, 0.5]
    shrink         elastic_net: [0.1, 0.95]
    L2             elastic_net, half the draws: diagonal, entries in [0.5, 1]
    window         sso: 1..n
    inner_steps    sso: 1..3
    =============  ==============================================================

    Parameters
    ----------
    system : System or strategy of System
        The plant, or a strategy such as ``observable_systems(3, 2)``.
    kinds : sequence of str, default all five built-in kinds
        Observer kinds to draw from: luenberger, ogd, sso, dsso, elastic_net, or any
        registered kind that gives a ``parameter_strategy``.
    max_attacked : int or strategy of int, default 0
        s, written to the spec's ``[attack]`` section.

    Returns
    -------
    SearchStrategy of Spec
        Named ``"<kind>-design"``.

    Raises
    ------
    TypeError
        If system is neither a System nor a strategy, or an argument has the
        wrong kind.
    ValueError
        If kinds is empty or names an unknown kind, or max_attacked < 0.

    Examples
    --------
    >>> from hypothesis import given
    >>> from ssecert.observers import build_observer
    >>> @given(observer_designs(observable_systems(3, 2), kinds=["dsso", "elastic_net"]))
    ... def check(design):
    ...     assert design.observer["kind"] in ("dsso", "elastic_net")
    ...     assert build_observer(design.system, design.observer).L.shape == (3, 2)
    >>> check()
    """
    if not isinstance(system, (System, SearchStrategy)):
        raise TypeError(
            f"system must be a System or a hypothesis strategy of System objects, "
            f"got {describe(system)}"
        )
    chosen = _choices(kinds, "kinds", _drawable())
    return _designs(system, chosen, _size(max_attacked, "max_attacked", 0), {})
