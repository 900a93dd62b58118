"""An observer designed against its certificate: the gain synthesised, the scalars searched.

The ``ssecert design`` command's search (``ssecert.design`` in Python; also importable as
``ssecert.synthesize``).  It sits in the layer of ``analyze`` and ``certify`` (it certifies
every candidate as they do), beside the gains it proposes: the gain synthesis itself is
``ssecert.design.synthesis``.

A candidate is a point of a small grid of the scalar parameters, which the
kind declares (``ObserverKind.design_axes`` and ``design_section``; which
kinds are offered, for which objectives, and which is the default, are the
kinds' own declarations too): (shrink, step) for the elastic-net observer,
the step for the D-SSO (shrink 1), nothing for a Luenberger observer.  Its
gain comes out of the synthesis LMI of ``ssecert.design.synthesis`` (or is
a named gain the cell keeps: the D-SSO's ``roa`` grid also tries the deadbeat
gain), and the design built with it is certified exactly as ``ssecert
analyze`` certifies a spec (``observer_stability_check`` and
``iss_gain_check``): only verified numbers count.  The synthesis's own
dissipation certificate is also checked in numpy (``verify_synthesis``); it is
what certifies the decay of the ``rate`` objective.

The grid is searched from its middle outwards: each round certifies the
untried neighbours of the best candidate so far and moves there when one is
better (a pattern search, each round starting from the previous best), then,
while the time budget lasts, the rest of the grid nearest-first.  A candidate
is not started when the time left is less than the candidates so far took on
average; the result reports the time spent and whether the grid was
exhausted.

Objectives: the smallest certified l2 gain from attack to estimation error
at a certified decay (``gain``), the fastest certified decay (``rate``: the
gain synthesised for decay by bisection), or the largest certified region of
attraction (``roa``, for the D-SSO, whose shrink 1 rarely admits a global
certificate: a design certified globally scores an infinite radius).

A certified gain alone rewards doing nothing: on a stable plant the smallest
gain from attack to error belongs to L near 0, an observer that ignores its
sensors while the plant's own decay shrinks the error.  So ``gain`` and
``rate`` first trace the trade-off between the two (``tradeoff_front``: at
the grid's middle, the fastest decay the synthesis certifies, then the
smallest gain at decays between it and almost none, each point's certificate
verified in numpy), and ``gain`` imposes, unless ``min_decay`` is given, the
decay ``choose_decay`` reads off that front: the smallest gain whose certified
contraction per step is at most rho(A)^2 (the error shrinks at least twice as
fast, in logarithm, as the plant's own state: "clearly faster"), else the
knee of the front among the decays faster than the plant's.  A design whose
linear loop A - L S is no faster than the plant (``no_faster``: rho(A - L S)
above rho(A)^1.1 for a stable plant) is then never chosen; with an explicit ``min_decay`` it may be, and it is named
as such.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import TYPE_CHECKING, Any

import numpy as np

from ..observers import get_kind, observer_kinds
from ..observers.base import DESIGN_SHRINKS, DESIGN_STEPS
from ..results import Verdict
from ..system import System
from .outcomes import DecayChoice, DecayCode
from .search_messages import WORSE_RTOL, comparison_summary, decay_text, no_design_text

if TYPE_CHECKING:
    from ..noise import MeasurementNoise

__all__ = [
    "DesignResult",
    "certified_gain",
    "choose_decay",
    "choose_noise_decay",
    "DecayChoice",
    "DecayCode",
    "linear_target",
    "no_faster",
    "tradeoff_front",
    "design_observer",
    "design_kinds",
    "default_kind",
    "objective_refusal",
    "ObjectiveRefusal",
    "verify_synthesis",
    "SHRINKS",
    "STEPS",
]

SHRINKS = DESIGN_SHRINKS
STEPS = DESIGN_STEPS
OBJECTIVES = ("gain", "rate", "roa", "noise")
# why an objective that only some kinds take is refused to the others
ONLY_FOR = {
    "roa": "the other kinds are certified globally or not at all",
    "noise": "the D-SSO's certificates (shrink 1) have no decay, which a sparse observer's "
    "ultimate error bound under noise needs",
}


def default_kind(objective: str) -> str:
    """The kind designed for ``objective`` when none is named: the first registered kind
    whose ``design_default_for`` holds it; ValueError when none does.

    Examples
    --------
    >>> default_kind("gain"), default_kind("roa")
    ('elastic_net', 'dsso')
    """
    for name in observer_kinds():
        if objective in get_kind(name).design_default_for:
            return name
    raise ValueError(f"objective: no observer kind is designed for {objective!r} by default")


def design_kinds() -> tuple[str, ...]:
    """The kinds ``design`` offers (those with ``design_objectives``): the default kind of
    the first objective, then the others by name.

    Examples
    --------
    >>> design_kinds()
    ('elastic_net', 'dsso', 'luenberger')
    """
    names = sorted(name for name in observer_kinds() if get_kind(name).design_objectives)
    first = [default_kind(OBJECTIVES[0])] if names else []
    return (*first, *(name for name in names if name not in first))


@dataclass(frozen=True)
class ObjectiveRefusal:
    """Why a kind is not designed for an objective: the kinds that are (in the words the
    refusal names them with) and why the others are not; ``str()`` is the sentence."""

    objective: str
    kind: str
    takers: tuple[str, ...]
    why: str
    option: str = ""
    given: str = ""

    def __str__(self) -> str:
        takers = " or ".join(self.takers)
        if self.option:
            got = (
                f"--objective {self.objective} is for {takers}, got {self.option} "
                f"{self.given or self.kind}"
            )
        else:
            got = f"objective {self.objective!r} is for {takers}, got kind {self.kind!r}"
        return f"{got}: {self.why}"


def objective_refusal(
    objective: str, kind: str, *, option: str = "", given: str = ""
) -> ObjectiveRefusal | None:
    """Why ``kind`` is not designed for ``objective``, naming the kinds that are (None when
    ``kind`` is one of them); with ``option`` (``--observer``) in the command line's words,
    ``given`` the name the command line was given.

    Examples
    --------
    >>> refusal = objective_refusal("roa", "luenberger")
    >>> refusal.takers
    ('the D-SSO (shrink 1)',)
    >>> str(refusal).split(":")[0]
    "objective 'roa' is for the D-SSO (shrink 1), got kind 'luenberger'"
    >>> objective_refusal("roa", "dsso") is None
    True
    """
    if objective in get_kind(kind).design_objectives:
        return None
    names = []
    for taker in (get_kind(name) for name in design_kinds()):
        if objective in taker.design_objectives:
            words = f"{option} {taker.name}" if option else taker.label or f"the {taker.name}"
            names.append(f"{words} ({taker.design_note})" if taker.design_note else words)
    why = ONLY_FOR.get(objective, f"the other kinds are not designed for {objective!r}")
    return ObjectiveRefusal(objective, kind, tuple(names), why, option=option, given=given)


DEFAULT_KIND = default_kind(OBJECTIVES[0])


@dataclass(frozen=True)
class DesignResult:
    """The synthesised ``[observer]`` section (None when no design was certified), what
    certifies it, and every candidate tried.

    Attributes
    ----------
    observer : dict or None
        The ``[observer]`` section, gain as an explicit matrix.
    gamma : float or None
        Certified l2 gain from attack to estimation error, as ``ssecert analyze`` reports it.
    decay : float or None
        Certified decay per step: the synthesis certificate's alpha, verified.
    objective : str
    candidates : list of dict
        Per candidate: its parameters, the synthesis status, the verdicts and numbers.
    seconds : float
    complete : bool
        False when the time budget ended the search before the grid was exhausted.
    reason : str
        Why no design was certified.
    radius : float or None
        Certified region of attraction (``roa``; inf when observer_stability holds).
    front : list of dict
        The trade-off between certified decay and certified gain (``tradeoff_front``) at
        the grid's middle; empty for ``roa`` or when the synthesis gave no gain.
    plant_radius : float or None
        rho(A), the plant's own contraction per step.
    linear_radius : float or None
        rho(A - L S) of the chosen design's linear loop.
    choice : str
        Why this decay was imposed and, for a design no faster than the plant, that it is
        one.
    noise_bound : float or None
        The chosen design's certified ultimate error bound under the noise the search was
        given (``observer_noise_bound``, as ``ssecert certify`` reports it), with the
        ``noise`` objective; None for the others (the written design's certificate has it).
    """

    observer: dict[str, Any] | None
    gamma: float | None
    decay: float | None
    objective: str
    candidates: list[dict[str, Any]] = field(default_factory=list)
    seconds: float = 0.0
    complete: bool = True
    reason: str = ""
    radius: float | None = None
    front: list[dict[str, Any]] = field(default_factory=list)
    plant_radius: float | None = None
    linear_radius: float | None = None
    choice: str = ""
    noise_bound: float | None = None


def design(
    plant: Any,
    kind: str = DEFAULT_KIND,
    *,
    objective: str = "gain",
    threshold: float = 0.1,
    time_budget: float = 60.0,
    min_decay: float | None = None,
    noise: MeasurementNoise | float | None = None,
) -> DesignResult:
    """Search the best certified design of ``kind`` for a plant (``ssecert.design``).

    ``design_observer`` for any plant ``ssecert.inputs.as_system`` takes.

    Parameters
    ----------
    plant : System, Spec, control.StateSpace, scipy.signal.dlti, str or path
        A plant, a spec (its plant), a discrete-time python-control or SciPy
        system, a spec file or a packaged example's name.
    kind, objective, threshold, time_budget, min_decay, noise
        As for ``design_observer``; a spec's ``[noise]`` is the default noise.

    Returns
    -------
    DesignResult

    Examples
    --------
    >>> import ssecert
    >>> result = ssecert.design("ugv", time_budget=5)
    >>> result.observer["kind"], result.linear_radius < result.plant_radius
    ('elastic_net', True)
    """
    from ..inputs import as_spec, as_system
    from ..spec import Spec

    if isinstance(plant, (str, os.PathLike)):  # a spec file or example: read once
        plant = as_spec(plant)
    if noise is None and isinstance(plant, Spec):
        noise = plant.noise
    return design_observer(
        as_system(plant),
        kind,
        objective=objective,
        threshold=threshold,
        time_budget=time_budget,
        min_decay=min_decay,
        noise=noise,
    )


def design_observer(
    system: System,
    kind: str = DEFAULT_KIND,
    *,
    objective: str = "gain",
    threshold: float = 0.1,
    time_budget: float = 60.0,
    min_decay: float | None = None,
    noise: MeasurementNoise | float | None = None,
) -> DesignResult:
    """Search the best certified design of ``kind`` for ``system``.

    Parameters
    ----------
    system : System
    kind : str, default "elastic_net"
        One of ``design_kinds()``: "elastic_net", "dsso" or "luenberger" of the built-in
        kinds (the SSO is not offered: its gain is fixed by its step, L = step A C^T).
    objective : {"gain", "rate", "roa", "noise"}
        One of the kind's ``design_objectives``: ``roa`` for the D-SSO only; ``noise`` (the
        smallest certified ultimate error bound under ``noise``, with the decay the
        trade-off front's noise axis gives or ``min_decay``) for the elastic-net and
        Luenberger observers.
    threshold : float, default 0.1
        The soft threshold (kept fixed: the certificates of ``gain`` and ``rate`` do not
        depend on it; the region of attraction scales with it).
    time_budget : float, default 60
        Seconds; no candidate is started when fewer seconds remain than the candidates so
        far took on average (``complete`` false when some of the grid was left), and each
        synthesis solve stops at the time left (at least 1 s: the first candidate always
        runs).
    min_decay : float, optional
        Decay alpha imposed by the ``gain`` objective's synthesis (V(xi+) <= (1 - alpha)
        V(xi) without attack).  By default the decay ``choose_decay`` reads off the
        trade-off front (clearly faster than the plant's own); a given alpha is imposed as
        it is, even when the design it gives is no faster than the plant (the result's
        ``choice`` then says so).  The ``noise`` objective imposes it too.
    noise : MeasurementNoise or float, optional
        The measurement noise bound (a float: that bound on every sample of every sensor),
        required by the ``noise`` objective; with it the trade-off front's points also
        carry their certified ultimate error bound under that noise (``noise_bound``).

    Examples
    --------
    >>> from ssecert.examples import load_example
    >>> result = design_observer(load_example("ugv").system, "elastic_net", time_budget=5)
    >>> result.observer["kind"], result.linear_radius < result.plant_radius
    ('elastic_net', True)
    """
    kinds = design_kinds()
    if kind not in kinds:
        raise ValueError(f"kind: expected one of {', '.join(kinds)}, got {kind!r}")
    if objective not in OBJECTIVES:
        raise ValueError(f"objective: expected one of {', '.join(OBJECTIVES)}, got {objective!r}")
    refusal = objective_refusal(objective, kind)
    if refusal is not None:
        raise ValueError(str(refusal))
    noise = _as_noise(noise, system)
    if objective == "noise" and noise is None:
        raise ValueError(
            "objective 'noise' needs the measurement noise bound: noise=ETA (or a spec's "
            "[noise] section, or --noise ETA)"
        )
    start = time.perf_counter()
    rows, cols = get_kind(kind).design_axes(objective)
    plant_radius = _radius(system.A)
    front: list[dict[str, Any]] = []
    alpha = DEFAULT_DECAY if min_decay is None else float(min_decay)
    choice = "" if min_decay is None else f"decay {alpha:.3g} per step imposed (min_decay)"
    # the linear loop is asked to be clearly faster than a stable plant, unless the user
    # imposes a decay of their own
    linear = linear_target(plant_radius) if min_decay is None else None
    if objective in ("gain", "rate", "noise"):
        middle = _template(system, kind, rows[(len(rows) - 1) // 2],
                           cols[(len(cols) - 1) // 2], threshold)  # fmt: skip
        front = tradeoff_front(
            middle, time_limit=FRONT_SHARE * time_budget, linear=linear, noise=noise
        )
        chosen = None
        if objective == "gain" and min_decay is None:
            chosen = choose_decay(front, plant_radius)
        elif objective == "noise" and min_decay is None:
            chosen = choose_noise_decay(front, plant_radius)
        if chosen is not None:
            alpha, choice = chosen.alpha, decay_text(chosen)
    if linear is not None:
        choice += (
            f"; the linear loop is required to contract by {linear:.4g} per step, rho(A)^2 "
            f"(F' P1 F <= {linear:.4g}^2 P1 in the synthesis)"
        )
    evaluate = _evaluator(
        system,
        kind,
        objective,
        threshold,
        lambda: time_budget - (time.perf_counter() - start),
        alpha,
        faster_than=plant_radius if min_decay is None else None,
        linear=linear,
        noise=noise,
    )
    tried: dict[tuple[int, int], dict[str, Any]] = {}
    kept: dict[tuple[int, int], Found] = {}

    def score(cell: tuple[int, int]) -> tuple[float, ...]:
        return kept[cell][0] if cell in kept else (math.inf,)

    def run(cell: tuple[int, int]) -> bool:
        """Certify one cell unless the budget is spent; False when it is."""
        elapsed = time.perf_counter() - start
        if tried and elapsed + elapsed / len(tried) > time_budget:
            return False
        record, found = evaluate(rows[cell[0]], cols[cell[1]])
        record["certified"] = found is not None
        record["seconds_since_start"] = round(time.perf_counter() - start, 3)
        tried[cell] = record
        if found is not None:
            kept[cell] = found
        return True

    complete = _search(rows, cols, tried, run, score)
    seconds = round(time.perf_counter() - start, 3)
    candidates = [tried[c] for c in sorted(tried)]
    if not kept:
        reason = _no_design_reason(kind, candidates, system)
        return DesignResult(
            None, None, None, objective, candidates, seconds, complete, reason,
            front=front, plant_radius=plant_radius, choice=choice,
        )  # fmt: skip
    best = min(kept, key=lambda c: kept[c][0])
    record = tried[best]
    if objective == "gain" and record.get("decay") is None and record["gain"] == "synthesised":
        choice += (
            "; the synthesis's own certificate of that decay did not verify in numpy for "
            "this design (no candidate's did): its stability and l2 gain are certified by the "
            "analysis, its decay is not"
        )
    elif objective == "noise" and record.get("decay") is None and record["gain"] == "synthesised":
        choice += (
            "; the synthesis's own certificate of that decay did not verify in numpy for "
            "this design: its stability, l2 gain and noise bound are certified by the analysis, "
            "its decay is not"
        )
    linear = record.get("linear_radius")
    if linear is not None and no_faster(linear, plant_radius) and system.n:
        choice += (
            f"; its linear loop is no faster than the plant (rho(A - L S) = {linear:.6g} "
            f"against rho(A) = {plant_radius:.6g}): the observer barely uses its sensors"
        )
    return DesignResult(
        kept[best][1],
        record.get("gamma"),
        record.get("decay"),
        objective,
        candidates,
        seconds,
        complete,
        radius=record.get("radius"),
        front=front,
        plant_radius=plant_radius,
        linear_radius=linear,
        choice=choice.lstrip("; "),
        noise_bound=record.get("noise_bound"),
    )


def _as_noise(noise: Any, system: System) -> MeasurementNoise | None:
    """A ``MeasurementNoise`` for ``system``'s sensors: None stays None; a number is that
    bound on every sample of every sensor, a list one bound per sensor (``[noise]``'s
    ``measurement``)."""
    from ..noise import MeasurementNoise

    if noise is None:
        return None
    if isinstance(noise, MeasurementNoise):
        if noise.eta.size != system.p:
            raise ValueError(
                f"noise: expected a bound for each of the plant's {system.p} sensors, got "
                f"{noise.eta.size}"
            )
        if noise.process is not None and noise.process.input.shape[0] != system.n:
            raise ValueError(
                f"noise: its process noise enters {noise.process.input.shape[0]} states, the "
                f"plant has {system.n}"
            )
        return noise
    if isinstance(noise, bool):
        raise ValueError(f"noise: expected a bound >= 0 or one per sensor, got {noise!r}")
    try:
        return MeasurementNoise.read(noise, system.p)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"noise: {exc}") from None


DEFAULT_DECAY = 1e-3  # imposed when the front gives nothing to choose from
FASTER = 1.1  # a loop is faster than a stable plant when its error falls 10% faster (in log)


def no_faster(linear_radius: float, plant_radius: float) -> bool:
    """True when a linear loop with spectral radius ``linear_radius`` is no faster than the
    plant: for a stable plant, rho(A - L S) > rho(A)^1.1 (its error falls less than 10%
    faster, in logarithm, than the plant's own state), except that nothing is slower than a
    plant already faster than 0.05 per step; else rho(A - L S) >= rho(A).

    Examples
    --------
    >>> no_faster(0.9946, 0.9946), no_faster(0.7636, 0.9946), no_faster(0.5, 1.0)
    (True, False, False)
    >>> no_faster(1e-4, 0.0)  # a nilpotent plant: nothing is slower
    False
    """
    if plant_radius <= FAST_PLANT:
        return False
    if _stable(plant_radius):
        return bool(linear_radius > plant_radius**FASTER)
    return bool(linear_radius >= plant_radius)


FAST_PLANT = 0.05  # a plant whose own error falls 20x per step is not asked to be beaten


def linear_target(plant_radius: float) -> float | None:
    """The contraction per step asked of the linear loop A - L S by default: rho(A)^2 for a
    stable plant (its error falls twice as fast, in logarithm, as the plant's own state);
    None (nothing asked) for a plant that is not stable, or already faster than 0.05 per
    step.

    Examples
    --------
    >>> linear_target(0.9), linear_target(1.0), linear_target(0.01)
    (0.81, None, None)
    """
    if _stable(plant_radius) and plant_radius > FAST_PLANT:
        return float(plant_radius**2)
    return None


def _stable(plant_radius: float) -> bool:
    """rho(A) clearly below 1 (a plant whose spectral radius is 1 to 1e-6, as the thesis's
    normalised random plants, is not stable in any useful sense: its own decay takes
    millions of steps)."""
    return bool(0 < plant_radius < 1 - 1e-6)


FRONT_SHARE = 0.3  # of the time budget, at most, for the trade-off front
FRONT_POINTS = 8


def _radius(M: np.ndarray) -> float:
    """The spectral radius of M in floating point (0 for an empty matrix): words and choices
    of the design search, never a verdict."""
    return float(np.abs(np.linalg.eigvals(M)).max()) if M.size else 0.0


def _rate_gain(template: Any, **options: Any) -> tuple[Any, dict[str, Any]]:
    """``synthesize_rate_gain`` and its verification; at the edge of feasibility, where the
    certificate does not verify, the decay further inside (backoff 0.8), which has a margin."""
    from .synthesis import synthesize_rate_gain

    proposal = synthesize_rate_gain(template, **options)
    own = _verified_proposal(template, proposal)
    if proposal.L is not None and not own["verified"]:
        inside = synthesize_rate_gain(template, **{**options, "backoff": 0.8})
        if inside.L is not None:
            proposal, own = inside, _verified_proposal(template, inside)
    return proposal, own


def _template(system: System, kind: str, row: Any, col: Any, threshold: float) -> Any:
    """The design of one grid cell with a zero gain (built by the kind itself: a kind whose
    section has no ``gain`` key, a plugin's, ignores it)."""
    from ..budget import Budget
    from ..tolerances import Tolerances

    observer_kind = get_kind(kind)
    section = observer_kind.design_section(system, row, col, threshold=threshold)
    zero = {**section, "gain": np.zeros((system.n, system.p)).tolist()}
    return observer_kind.build(system, zero, Budget(), Tolerances())


def tradeoff_front(
    template: Any,
    *,
    points: int = FRONT_POINTS,
    time_limit: float | None = None,
    linear: float | None = None,
    noise: MeasurementNoise | None = None,
) -> list[dict[str, Any]]:
    """The trade-off between certified decay and certified l2 gain of ``template``'s kind,
    step and shrink: the smallest gain at almost no decay (alpha = 1e-3), the fastest decay
    the synthesis LMI certifies (bisection on alpha), then the smallest gain at decays
    between (contraction per step sqrt(1 - alpha) evenly spaced), ``points`` in all; with
    ``linear``, every point's linear loop is also required to contract by that much
    (``synthesize_gain``).

    With a ``time_limit`` the solves' time sets how many fit: fewer bisections, fewer
    points, none started past the limit.

    Each point: ``alpha`` (V(k+1) <= (1 - alpha) V(k)), ``contraction`` (sqrt(1 - alpha):
    the error's certified factor per step, in the certificate's norm), ``gamma`` (the l2
    gain from attack to error its certificate proves), ``linear_radius`` (rho(A - L S) of
    its gain), ``verified`` (the synthesis's certificate re-checked in numpy,
    ``verify_synthesis``; alpha and gamma are None when it is not).  With a ``noise``
    (``MeasurementNoise``), also ``noise_bound``: the certified ultimate error bound under
    that noise of the point's design (``_front_noise_bound``: the series certify reports for a
    linear observer, the synthesis certificate's dissipation inequality for a sparse one;
    None where none is proved).  Sorted fastest first; empty when the synthesis gives no
    gain.
    """
    from .synthesis import synthesize_gain

    start = time.perf_counter()

    def left() -> float | None:
        return None if time_limit is None else max(time_limit - (time.perf_counter() - start), 0.5)

    slowest = synthesize_gain(template, alpha=DEFAULT_DECAY, time_limit=left(), linear=linear)
    out = [_front_point(template, slowest, noise)] if slowest.L is not None else []
    solve = time.perf_counter() - start
    room = points + RATE_BISECTIONS_FRONT
    if time_limit is not None:
        room = min(room, int((time_limit - solve) / max(solve, 1e-3)))
    bisections = max(2, min(RATE_BISECTIONS_FRONT, room - 3))
    fastest, _ = _rate_gain(template, time_limit=left(), bisections=bisections, linear=linear)
    if fastest.L is None or fastest.alpha is None:
        return out
    out.append(_front_point(template, fastest, noise))
    solve = (time.perf_counter() - start) / (bisections + 2)  # the solves so far, about
    fast, slow = math.sqrt(1 - float(fastest.alpha)), math.sqrt(1 - DEFAULT_DECAY)
    if fast < slow:
        for c in np.linspace(fast, slow, points)[1:-1]:
            if time_limit is not None and time.perf_counter() - start + solve > time_limit:
                break
            found = synthesize_gain(
                template, alpha=1 - float(c) ** 2, time_limit=left(), linear=linear
            )
            if found.L is not None:
                out.append(_front_point(template, found, noise))
    return sorted(out, key=lambda p: p["contraction"])


RATE_BISECTIONS_FRONT = 6  # alpha of the fastest point to within 2^-6


def _front_point(
    template: Any, proposal: Any, noise: MeasurementNoise | None = None
) -> dict[str, Any]:
    from .synthesis import with_gain

    own = _verified_proposal(template, proposal)
    alpha = float(proposal.alpha)
    design = with_gain(template, proposal.L)
    point = {
        "alpha": own.get("alpha") if own["verified"] else None,
        "contraction": math.sqrt(max(1 - alpha, 0.0)),
        "gamma": own.get("gamma") if own["verified"] else None,
        "linear_radius": _radius(design.error_matrix),
        "verified": bool(own["verified"]),
    }
    if noise is not None:
        point["noise_bound"] = _front_noise_bound(design, proposal, own, noise)
    return point


def _front_noise_bound(
    design: Any, proposal: Any, own: dict[str, Any], noise: MeasurementNoise
) -> float | None:
    """The certified ultimate error bound under ``noise`` of a front point's design: for a
    linear observer the worst-case series ``ssecert certify`` reports
    (``noise_messages.observer_noise_check``); for a sparse one the dissipation inequality of
    the synthesis's own verified certificate (V = xi' P xi, its alpha and gamma:
    ``noise_gain.dissipation_bound``), which certify replaces by iss_gain's certificate of the
    chosen design.  None where none is proved (a certificate not verified, verified only in
    balanced coordinates, without decay, an ill-conditioned P, an error model whose attack
    input is not the measurement vector)."""
    from ..stability.noise_gain import dissipation_bound
    from ..stability.noise_messages import (
        applies_to,
        measurement_rows,
        noise_enters_as_attack,
        observer_noise_check,
        process_certificate,
    )

    if applies_to(design):
        check = observer_noise_check(design, noise)
        return float(check.value) if check.verdict is Verdict.HOLDS else None
    if not own.get("verified") or "state_scaling" in own or not own.get("alpha"):
        return None
    from ..observers.lure import LureModel

    model = LureModel.from_design(design)
    if not noise_enters_as_attack(design, model):
        return None
    per_row = measurement_rows(design, noise)
    if per_row is None:
        return None
    P, alpha, gamma = np.asarray(proposal.P, dtype=float), own["alpha"], own["gamma"]
    if noise.process is not None:
        # the process noise a further input: the inequality verified again with it, at the
        # point's decay, as certify's check does (``process_certificate``)
        process = process_certificate(design, model, noise, float(alpha), per_row)
        if process is None:
            return None
        cert, w_bounds = process
        P, alpha, gamma = np.asarray(cert.P, dtype=float), cert.decay, cert.gamma
        per_row = np.concatenate([per_row, w_bounds])
    found = dissipation_bound(P, float(alpha), float(gamma), per_row, design.system.n)
    return found.bound if math.isfinite(found.bound) else None


def choose_decay(front: list[dict[str, Any]], plant_radius: float) -> DecayChoice:
    """The decay the ``gain`` objective imposes, read off the trade-off front, and the rule
    that chose it (``search_messages.decay_text`` says why).

    The smallest verified gain whose certified contraction is at most rho(A)^2 (the
    error falls at least twice as fast, in logarithm, as the plant's own state); else,
    among the verified points faster than the plant (every point when rho(A) >= 1), the
    knee of the front (the point farthest below the chord from the fastest to the
    slowest, in contraction and log gain); else the fastest verified point.  With fewer
    than two verified points, alpha = 1e-3.

    Examples
    --------
    >>> front = [{"alpha": 0.5, "contraction": 0.71, "gamma": 3.0, "verified": True},
    ...          {"alpha": 0.2, "contraction": 0.89, "gamma": 0.5, "verified": True},
    ...          {"alpha": 0.01, "contraction": 0.995, "gamma": 0.1, "verified": True}]
    >>> choice = choose_decay(front, 0.985)
    >>> choice.alpha, choice.code
    (0.2, <DecayCode.TWICE_AS_FAST: 'twice as fast'>)
    """
    good = [p for p in front if p.get("verified") and p.get("gamma") is not None]
    stable = _stable(plant_radius)
    choice = partial(
        DecayChoice, plant_radius=plant_radius, plant_stable=stable, verified=len(good)
    )
    if len(good) < 2:
        return choice(DEFAULT_DECAY, DecayCode.TOO_FEW_POINTS)
    fastest = min(p["contraction"] for p in good)
    if stable:
        twice = [p for p in good if p["contraction"] <= plant_radius**2]
        if twice:
            pick = min(twice, key=lambda p: p["gamma"])
            return choice(
                float(pick["alpha"]),
                DecayCode.TWICE_AS_FAST,
                contraction=pick["contraction"],
                fastest=fastest,
            )
    faster = [p for p in good if p["contraction"] < plant_radius]
    if faster:
        return choice(
            float((pick := _knee(faster))["alpha"]),
            DecayCode.KNEE if len(faster) >= 3 else DecayCode.FEW_FASTER,
            contraction=pick["contraction"],
            faster=len(faster),
            fastest=fastest,
        )
    pick = min(good, key=lambda p: p["contraction"])
    return choice(
        float(pick["alpha"]),
        DecayCode.FASTEST,
        contraction=pick["contraction"],
        fastest=fastest,
    )


def choose_noise_decay(front: list[dict[str, Any]], plant_radius: float) -> DecayChoice:
    """The decay the ``noise`` objective imposes, read off the trade-off front's noise axis,
    and the rule that chose it.

    The ultimate error bound under noise is not monotone in the decay (a slow decay lets the
    noise pile up, 1 / alpha; a fast one needs a large gain): the verified point with the
    smallest certified bound among those faster than the plant (every point when rho(A) >=
    1, the fastest when none is), alpha = 1e-3 without one.

    Examples
    --------
    >>> front = [{"alpha": 0.5, "contraction": 0.71, "noise_bound": 0.04, "verified": True},
    ...          {"alpha": 0.2, "contraction": 0.89, "noise_bound": 0.01, "verified": True},
    ...          {"alpha": 0.01, "contraction": 0.995, "noise_bound": 0.3, "verified": True}]
    >>> choose_noise_decay(front, 0.985).alpha
    0.2
    """
    good = [p for p in front if p.get("verified") and p.get("noise_bound") is not None]
    stable = _stable(plant_radius)
    choice = partial(
        DecayChoice, plant_radius=plant_radius, plant_stable=stable, verified=len(good)
    )
    if good and max(p["noise_bound"] for p in good) == 0:  # no noise: nothing to minimise
        then = choose_decay(front, plant_radius)
        return choice(then.alpha, DecayCode.NO_NOISE, then=then)
    if not good:
        return choice(DEFAULT_DECAY, DecayCode.NO_NOISE_BOUND)
    faster = [p for p in good if p["contraction"] < plant_radius]
    if faster:
        pick = min(faster, key=lambda p: p["noise_bound"])
        code = DecayCode.SMALLEST_NOISE_BOUND
    else:
        pick = min(good, key=lambda p: p["contraction"])
        code = DecayCode.FASTEST_NOISE_BOUND
    return choice(
        float(pick["alpha"]),
        code,
        contraction=pick["contraction"],
        faster=len(faster),
        fastest=min(p["contraction"] for p in good),
        noise_bound=pick["noise_bound"],
    )


def _knee(points: list[dict[str, Any]]) -> dict[str, Any]:
    """The point farthest below the chord between the front's ends (contraction, log
    gain), each axis scaled to [0, 1]; with fewer than three points the smallest gain."""
    if len(points) < 3:
        return min(points, key=lambda p: p["gamma"])
    x = np.array([p["contraction"] for p in points])
    y = np.log(np.maximum([p["gamma"] for p in points], 1e-300))
    order = np.argsort(x)
    x, y = x[order], y[order]
    xs = (x - x[0]) / max(x[-1] - x[0], 1e-300)
    ys = (y - y.min()) / max(float(y.max() - y.min()), 1e-300)
    chord = ys[0] + (ys[-1] - ys[0]) * xs
    return points[int(order[int(np.argmax(chord - ys))])]


def _search(
    rows: Sequence[Any],
    cols: Sequence[Any],
    tried: dict[tuple[int, int], dict[str, Any]],
    run: Callable[[tuple[int, int]], bool],
    score: Callable[[tuple[int, int]], Any],
) -> bool:
    """Pattern search from the grid's middle, then the rest nearest-first; True when every
    cell was tried."""
    current = ((len(rows) - 1) // 2, (len(cols) - 1) // 2)
    if not run(current):
        return False
    while True:
        around = [
            (current[0] + di, current[1] + dj)
            for di, dj in ((-1, 0), (1, 0), (0, -1), (0, 1))
            if 0 <= current[0] + di < len(rows) and 0 <= current[1] + dj < len(cols)
        ]
        for cell in around:
            if cell not in tried and not run(cell):
                return False
        best = min(tried, key=score)
        if best == current or score(best)[0] == math.inf:
            break
        current = best
    rest = sorted(
        ((i, j) for i in range(len(rows)) for j in range(len(cols)) if (i, j) not in tried),
        key=lambda c: abs(c[0] - current[0]) + abs(c[1] - current[1]),
    )
    return all(run(cell) for cell in rest)


Found = tuple[tuple[float, ...], dict[str, Any]]


def _evaluator(
    system: System,
    kind: str,
    objective: str,
    threshold: float,
    remaining: Callable[[], float],
    min_decay: float,
    faster_than: float | None = None,
    linear: float | None = None,
    noise: MeasurementNoise | None = None,
) -> Callable[[Any, Any], tuple[dict[str, Any], Found | None]]:
    """The function certifying one grid cell: a record with its parameters, verdicts and
    numbers, and, when it is certified, its rank (lower is better: the objective, then a
    tie-break) and its ``[observer]`` section.  With ``faster_than`` (rho(A)), a design
    whose linear loop is no faster than that is rejected.  The ``noise`` objective ranks by
    the ``observer_noise_bound`` check under ``noise`` (as ``ssecert certify`` builds it)."""
    from ..observers import build_observer
    from .synthesis import synthesize_gain, with_gain

    def evaluate(row: Any, col: Any) -> tuple[dict[str, Any], Found | None]:
        params = get_kind(kind).design_section(system, row, col, threshold=threshold)
        record: dict[str, Any] = {k: v for k, v in params.items() if k not in ("kind", "gain")}
        named = params.get("gain")
        if not isinstance(named, list):  # no gain to synthesise: a named one, or the kind's
            try:
                design = build_observer(system, params)
            except ValueError as exc:  # no such gain for this plant
                record["gain"] = named
                record["synthesis"] = f"no {named} gain: {exc}" if named else f"no gain: {exc}"
                return record, None
            record["gain"] = named if named is not None else design.gain.method
            proposal = None
        else:
            template = build_observer(system, params)
            record["gain"] = "synthesised"
            limit = max(remaining(), 1.0)
            if objective == "rate":
                proposal, own = _rate_gain(template, time_limit=limit, linear=linear)
            else:
                proposal = synthesize_gain(
                    template, alpha=min_decay, time_limit=limit, linear=linear
                )
                own = _verified_proposal(template, proposal)
            record["synthesis"] = proposal.status
            if proposal.L is None:
                record["rejected"] = f"the synthesis LMI gave no gain ({proposal.status})"
                return record, None
            record["synthesis_certificate"] = own
            design = with_gain(template, proposal.L)
        record["linear_radius"] = _radius(design.error_matrix)
        if faster_than is not None and no_faster(record["linear_radius"], faster_than):
            record["rejected"] = (
                f"its linear loop is no faster than the plant (rho(A - L S) = "
                f"{record['linear_radius']:.6g} against rho(A) = {faster_than:.6g})"
            )
            return record, None
        stability, iss = certified_gain(design)
        decay = None
        if proposal is not None:
            decay = own.get("alpha") if own["verified"] else None
        record.update(
            stability=stability.verdict.value,
            iss=iss.verdict.value,
            gamma=iss.value if iss.verdict is Verdict.HOLDS else None,
            decay=decay,
        )
        observer = dict(params)
        if proposal is not None:
            observer["gain"] = np.asarray(design.L).tolist()
        if objective == "roa":
            radius = _certified_radius(design, stability)
            record["radius"] = radius
            if radius <= 0:
                record["rejected"] = "no region of attraction certified"
                return record, None
            return record, ((-radius, record["gamma"] or math.inf), observer)
        if stability.verdict is not Verdict.HOLDS:
            record["rejected"] = f"observer_stability {stability.verdict.value}"
            return record, None
        if iss.verdict is not Verdict.HOLDS:
            record["rejected"] = f"iss_gain {iss.verdict.value}"
            return record, None
        if objective == "rate":
            if decay is None:
                record["rejected"] = (
                    "the synthesis's own decay certificate did not verify in numpy "
                    f"({record['synthesis_certificate'].get('problem', '')})"
                )
                return record, None
            return record, ((-decay, float(iss.value)), observer)
        if objective == "noise":
            from ..stability.noise_messages import noise_check

            assert noise is not None  # design_observer requires it for this objective
            bounded = noise_check(design, noise, iss)
            if bounded.verdict is not Verdict.HOLDS:
                record["rejected"] = f"observer_noise_bound {bounded.verdict.value}"
                return record, None
            record["noise_bound"] = float(bounded.value)
            # the bound certify reports first: the synthesis's own decay certificate is not
            # what it rests on (iss_gain's is)
            rank = (float(bounded.value), float(decay is None), float(iss.value))
            return record, (rank, observer)
        # a design whose synthesis certificate verified (its decay is certified) first
        return record, ((float(decay is None), float(iss.value), -(decay or 0.0)), observer)

    return evaluate


def _verified_proposal(template: Any, proposal: Any) -> dict[str, Any]:
    """``verify_synthesis`` on the design with the proposed gain ({} without one)."""
    from .synthesis import with_gain

    if proposal.L is None:
        return {"verified": False}
    return verify_synthesis(with_gain(template, proposal.L), proposal)


def _certified_radius(design: Any, stability: Any) -> float:
    """The certified region of attraction: inf when observer_stability holds, else the
    radius the region_of_attraction check proves (piecewise-quadratic included)."""
    from ..stability.checks import region_of_attraction_check

    if stability.verdict is Verdict.HOLDS:
        return math.inf
    if stability.verdict is Verdict.FAILS:
        return 0.0
    check = region_of_attraction_check(design, piecewise=True)
    return float(check.value or 0.0) if check is not None else 0.0


def _no_design_reason(kind: str, candidates: list[dict[str, Any]], system: System) -> str:
    why = sorted({str(rec.get("rejected", "not certified")) for rec in candidates})
    return no_design_text(kind, len(candidates), why, _undetectable_modes(system))


def _undetectable_modes(system: System) -> list[complex]:
    """Eigenvalues with |lambda| >= 1 that the sensors do not see (PBH test, numerically:
    a reason's words, not a verdict)."""
    A, C = system.A, system.C
    out = []
    for lam in np.linalg.eigvals(A):
        if abs(lam) < 1 - 1e-9:
            continue
        M = np.vstack([A - lam * np.eye(system.n), C])
        s = np.linalg.svd(M, compute_uv=False)
        scale = max(float(np.linalg.norm(A, 2)), float(np.linalg.norm(C, 2)), 1e-300)
        if s[-1] <= 1e-9 * scale:
            out.append(complex(lam) if abs(np.imag(lam)) > 0 else float(np.real(lam)))
    return out


def certified_gain(design: Any) -> tuple[Any, Any]:
    """(observer_stability, iss_gain) of a design, as ``analyze`` checks them."""
    from ..stability.checks import iss_gain_check, observer_stability_check

    stability, cert = observer_stability_check(design)
    return stability, iss_gain_check(design, cert)


def verify_synthesis(design: Any, proposal: Any, *, clear: float = 100.0) -> dict[str, Any]:
    """The synthesis's own dissipation certificate (P, multipliers, alpha, gamma^2) checked in
    numpy on ``design`` (the design built with the proposed gain), as every certificate is:
    ``verified``, the decay ``alpha`` and ``gamma`` it proves, the margin and its bound."""
    from ..observers.lure import LureModel
    from ..stability.lmi_messages import verify_text
    from ..stability.lmi_verification import verify_certificate

    if proposal.P is None or proposal.g is None:
        return {"verified": False, "problem": proposal.status}
    model = LureModel.from_design(design)
    t = proposal.multipliers if proposal.multipliers is not None else np.zeros(0)
    alpha = float(proposal.alpha or 0.0)
    solved_in = None
    if proposal.state_scaling is not None:
        solved_in = (np.asarray(proposal.state_scaling), int(proposal.sensor_exponent))

    def coordinates() -> Iterator[tuple[np.ndarray, int] | None]:
        """The coordinates to try (None: the user's): the user's, then those the synthesis
        solved in; with the sensors in other units, those it solved in first (the slack on
        gamma^2 is absolute: in the user's units it would swamp a small gamma); then the
        model's balancings, computed only when those fail."""
        first: list[tuple[np.ndarray, int] | None] = [None]
        if solved_in is not None:
            first.insert(0 if solved_in[1] else 1, solved_in)
        yield from first
        for s in model.balancings():
            if solved_in is None or not (np.array_equal(s, solved_in[0]) and solved_in[1] == 0):
                yield s, 0

    ok, margin, bound, problem, g = False, math.nan, math.nan, None, math.nan
    out: dict[str, Any] = {}
    for where in coordinates():
        if where is None:
            # a slightly larger gain, so that the margin survives
            g = proposal.g * (1 + 1e-6) + 1e-9
            ok, margin, bound, problem = verify_certificate(
                model, proposal.P, t, kind="iss", alpha=alpha, g=g, clear=clear
            )
            out = {"verified": bool(ok), "margin": margin, "error_bound": bound}
        else:
            # the same inequality by congruence, in balanced state coordinates (and the
            # sensors' units 2^-j: the multipliers and gamma^2 times 2^-2j)
            s, j = where
            scale = np.ones(proposal.P.shape[0])
            scale[: model.N] = s
            P_b = proposal.P * scale[:, None] * scale[None, :]
            t_b = np.ldexp(t, -2 * j)
            g_b = math.ldexp(proposal.g, -2 * j) * (1 + 1e-6) + 1e-9
            if not (
                np.all(np.isfinite(P_b))
                and np.array_equal(P_b / scale[:, None] / scale[None, :], proposal.P)
                and np.array_equal(np.ldexp(t_b, 2 * j), t)
                and math.isfinite(math.ldexp(g_b, 2 * j))
            ):
                continue
            ok, margin, bound, problem = verify_certificate(
                model.scaled(s, sensors=j), P_b, t_b, kind="iss", alpha=alpha, g=g_b,
                clear=clear,
            )  # fmt: skip
            if ok:
                g = math.ldexp(g_b, 2 * j)
                out = {"verified": True, "margin": margin, "error_bound": bound,
                       "state_scaling": s.tolist(),
                       "margin_coordinates": "verified in the balanced coordinates "
                       "xi = diag(state_scaling) xi_b"}  # fmt: skip
                if j:
                    out["sensor_units"] = f"2^{-j}"
                    out["margin_coordinates"] += (
                        f", with the attack and the channels in units 2^{-j}"
                    )
        if ok:
            break
    if ok:
        out.update(alpha=float(proposal.alpha or 0.0), gamma=float(np.sqrt(g)))
    else:
        out["problem"] = verify_text(problem)
    return out


DESIGN_HEADER = (
    "# Observer synthesised by ssecert design ({kind}, objective {objective}) for {source}:\n"
    "# {guarantee}\n"
)


def design_spec_text(spec: Any, result: DesignResult, kind: str) -> str:
    """The spec file of the synthesised design: ``spec`` with the synthesised ``[observer]``
    and the name NAME-design (so that ``ssecert certify`` of it writes NAME-design.html)."""
    from ..spec.write import dumps, spec_document

    if result.observer is None:
        raise ValueError("no design to write: the search certified none")
    document = spec_document(spec, result.observer)
    document["name"] = f"{spec.name}-design"
    return DESIGN_HEADER.format(
        kind=kind,
        objective=result.objective,
        source=spec.source,
        guarantee=_guarantee(result),
    ) + dumps(document)


def _guarantee(result: DesignResult) -> str:
    parts = []
    if result.gamma is not None:
        parts.append(f"certified l2 gain {result.gamma:.6g}")
    if result.decay is not None:
        parts.append(f"certified decay {result.decay:.3g} per step")
    if result.radius is not None:
        parts.append(f"certified region of attraction {result.radius:.4g}")
    text = ", ".join(parts) or "certified"
    if result.decay is not None:  # (a comment line of its own)
        text += (
            "\n# (that decay is the synthesis LMI's certificate's; ssecert certify's circle "
            "criterion,\n# solved for its margin rather than its decay, may report a smaller one)"
        )
    return text


def design_report(
    spec: Any,
    designed: Any,
    *,
    seed: int | None = None,
    runs: int | None = None,
    command: str = "",
    progress: Callable[[str], None] | None = None,
    search: DesignResult | None = None,
) -> Any:
    """``certify`` of the designed spec, with the comparison against the spec's own design
    (when it has one) under the same scenarios and seeds: a ``CertifyResult`` whose
    ``comparison`` holds both designs' verdicts and certified numbers, per scenario the
    final absolute error (mean, q90) and the settling step of the mean error of each, and,
    with the ``search`` that found the design, its trade-off front (``tradeoff``)."""
    from dataclasses import replace

    from ..certify import certify

    say = progress or (lambda message: None)
    result = certify(designed, seed=seed, runs=runs, command=command, progress=progress)
    own = None
    if spec.observer is not None:
        say("certifying and simulating the spec's own design, for the comparison")
        own = certify(spec, seed=seed, runs=runs, region=False)
    comparison = compare_designs(own, result)
    if search is not None and search.front:
        comparison["tradeoff"] = _tradeoff_summary(search, comparison)
    return replace(result, comparison=comparison)


def _tradeoff_summary(search: DesignResult, comparison: dict[str, Any]) -> dict[str, Any]:
    """The front, rho(A), the chosen design's certified point and the spec's design's (its
    linear loop's spectral radius and certified gain: it has no decay certificate)."""
    rows = {d["design"]: d for d in comparison["designs"]}
    chosen = {
        "contraction": None if search.decay is None else math.sqrt(max(1 - search.decay, 0)),
        "gamma": search.gamma,
        "linear_radius": search.linear_radius,
    }
    bound = rows.get("synthesised", {}).get("observer_noise_bound_value")
    if bound is not None:  # with a noise: the design's certified ultimate error
        chosen["noise_bound"] = bound
    out: dict[str, Any] = {
        "front": search.front,
        "plant_radius": search.plant_radius,
        "chosen": chosen,
        "choice": search.choice,
    }
    if "spec" in rows:
        out["spec"] = {
            "linear_radius": rows["spec"].get("linear_radius"),
            "gamma": rows["spec"].get("iss_gain_value"),
        }
        if rows["spec"].get("observer_noise_bound_value") is not None:
            out["spec"]["noise_bound"] = rows["spec"]["observer_noise_bound_value"]
    return out


def compare_designs(own: Any | None, designed: Any) -> dict[str, Any]:
    """Side by side: the spec's own design (a ``CertifyResult`` or None) and the synthesised
    one, their certified numbers and, per scenario both simulated, the simulated error."""
    designs = [_design_row("synthesised", designed)]
    if own is not None:
        designs.insert(0, _design_row("spec", own))
    rows = []
    worse = []
    for name, mine in designed.simulations.items():
        theirs = own.simulations.get(name) if own is not None else None
        row: dict[str, Any] = {"scenario": name, "synthesised": _sim_row(mine)}
        if theirs is not None:
            row["spec"] = _sim_row(theirs)
            row["comparison"] = _versus(row["synthesised"], row["spec"])
            if row["comparison"] == "worse":
                worse.append(name)
        rows.append(row)
    compared = [r for r in rows if r.get("comparison") in ("better", "no worse", "worse")]
    apart = [r["scenario"] for r in rows if "comparison" in r and r not in compared]
    noise = _noise_comparison(designs)
    region = _region_comparison(designs)
    summary = comparison_summary(
        own is not None, len(rows), len(compared), worse, apart, noise, region
    )
    return {
        "designs": designs,
        "scenarios": rows,
        "worse_in": worse,
        "summary": summary,
        "worse_rtol": WORSE_RTOL,
        "metric": "mean absolute error ||x_hat - x|| over the runs and the horizon",
    }


def _noise_comparison(designs: list[dict[str, Any]]) -> tuple[float, float] | None:
    """The certified ultimate errors under the noise (the spec's own design's, the synthesised
    one's) when the spec's own is the smaller, else None."""
    rows = {d["design"]: d for d in designs}
    ours = rows.get("synthesised", {}).get("observer_noise_bound_value")
    theirs = rows.get("spec", {}).get("observer_noise_bound_value")
    if ours is None or theirs is None or not (math.isfinite(theirs) and theirs < ours):
        return None
    return theirs, ours


def _region_comparison(designs: list[dict[str, Any]]) -> tuple[float, float] | None:
    """The certified regions of attraction (the spec's own design's, the synthesised one's:
    inf for a design whose observer_stability holds, which converges from every initial
    error, 0 where none is certified) when the spec's own is the larger, else None."""
    rows = {d["design"]: d for d in designs}

    def radius(row: dict[str, Any]) -> float | None:
        if row.get("observer_stability") == Verdict.HOLDS.value:
            return math.inf
        return row.get("region_of_attraction_value")

    theirs = radius(rows.get("spec", {}))
    if theirs is None:
        return None
    ours = radius(rows.get("synthesised", {})) or 0.0
    return (theirs, ours) if theirs > ours else None


def _design_row(label: str, result: Any) -> dict[str, Any]:
    observer = dict(result.spec.observer or {})
    gain = observer.get("gain")
    cert = result.certificate
    row: dict[str, Any] = {
        "design": label,
        "kind": observer.get("kind"),
        "gain": gain if isinstance(gain, str) else _gain_words(label, gain, cert),
        **{k: observer.get(k) for k in ("step", "threshold", "shrink") if k in observer},
        "linear_radius": _linear_radius(result),
    }
    for check_id in (
        "observer_gain", "observer_stability", "iss_gain", "region_of_attraction",
        "observer_noise_bound",
    ):  # fmt: skip
        check = cert.get(check_id)
        if check is not None:
            row[check_id] = check.verdict.value
            if check.value is not None and check.verdict is Verdict.HOLDS:
                row[f"{check_id}_value"] = check.value
    return row


def _gain_words(label: str, gain: Any, cert: Any) -> str:
    """How the comparison names a gain given as a matrix (or, for a synthesised design of a
    kind whose parameters define its gain, not given: its method)."""
    if label != "synthesised":
        return "matrix"
    if gain is not None:
        return "LMI"
    check = cert.get("observer_gain")
    return str(check.fields.get("gain_method")) if check is not None else "matrix"


def _linear_radius(result: Any) -> float | None:
    """rho(A - L S) of a certified spec's observer (None when it cannot be built)."""
    from ..observers import build_observer

    spec = result.spec
    if getattr(spec, "system", None) is None or not spec.observer:
        return None
    try:
        design = build_observer(spec.system, spec.observer)
        return _radius(design.error_matrix)
    except (ValueError, ArithmeticError, np.linalg.LinAlgError):
        return None


def _sim_row(res: Any) -> dict[str, Any]:
    """One design's simulated error in one scenario: the absolute error ||x_hat - x|| averaged
    over the runs and the horizon (what the comparison reads: it counts the transient and the
    bias alike, so an observer that ignores its sensors on a decaying plant does not win by
    its final step alone), the final one (mean, q90), the settling step of its mean curve,
    and, for information, the final error relative to the initial one and to the state."""
    from ..simulation.metrics import settling_step

    if getattr(res, "absolute_error", None) is None:
        return {"skipped": str(res.get("skipped", "not simulated"))}
    final = res.final()
    with np.errstate(over="ignore", invalid="ignore"):
        mean = np.mean(res.absolute_error, axis=1)
        over_horizon = float(np.mean(mean))
    unresolved = getattr(res, "unresolved_from", None)
    if unresolved is not None:  # the floats' rounding of a huge state: nothing to compare
        return {
            "skipped": f"its errors from step {unresolved:,} are the rounding of the simulated "
            "state (an unstable plant): not compared",
            "unresolved_from_step": unresolved,
        }
    return {
        "mean_error": over_horizon,
        "final_mean": final["absolute_error_mean"],
        "final_q90": final["absolute_error_q90"],
        "final_of_initial": final.get("initial_relative_error_mean"),
        "final_relative": final["relative_error_mean"],
        "settling_step": settling_step(mean),
        "runs": res.runs,
        "steps": res.steps,
        "seed": res.seed,
    }


def _versus(mine: dict[str, Any], theirs: dict[str, Any]) -> str:
    a, b = mine.get("mean_error"), theirs.get("mean_error")
    if a is None or b is None or math.isnan(a) or math.isnan(b):
        return "not compared"
    if not math.isfinite(a):
        return "worse" if math.isfinite(b) else "not compared"
    if a > b * (1 + WORSE_RTOL) + 1e-12:
        return "worse"
    return "better" if a < b * (1 - WORSE_RTOL) else "no worse"
