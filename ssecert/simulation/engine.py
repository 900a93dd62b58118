"""Monte Carlo simulation of an observer design under an attack scenario.

Runs are simulated together, vectorised across runs (arrays of shape
runs x n), in chunks of ``CHUNK_RUNS`` runs; the same chunks are computed
in-process or on Dask workers, so both give bitwise-identical results.

Before anything is allocated, the memory of the per-step results (three
steps x runs series) and of one chunk's trajectories, and the work of the
whole scenario, are estimated from the shapes (``scenario_cost``).  Chunks
get fewer runs when a chunk of ``CHUNK_RUNS`` would not fit the memory
budget; a scenario that does not fit even with one run per chunk, or whose
work exceeds the budget, is refused with the estimate
(``ResourceLimitError``).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..budget import Budget, ResourceLimitError, stage
from ..context import OBSERVER, AnalysisContext, shared, sparse_key
from ..observers import ObserverDesign, build_observer, observer_from_design
from ..parallel import map_ordered
from ..results import Verdict
from ..system import System
from .metrics import (
    absolute_error,
    detection_delay,
    initial_relative_error,
    mse,
    quantile,
    relative_error,
    summarize,
    support_error,
)
from .scenarios import StealthyReplay, generate

__all__ = [
    "ScenarioResult",
    "simulate_scenario",
    "simulate_spec",
    "GridResult",
    "grid_search",
    "CHUNK_RUNS",
    "stealthy_replay",
    "scenario_cost",
]

CHUNK_RUNS = 64
# operations charged for one pass of a Python-level loop (about 10 us), so that
# the work estimate also bounds loops over steps, chunks and random supports
_LOOP_COST = 1e5


def scenario_cost(
    design: ObserverDesign, scenario: Mapping[str, Any], runs: int, steps: int, chunk_runs: int
) -> tuple[float, float, float]:
    """Estimated bytes of the results, bytes per run of one chunk, and operations.

    Parameters
    ----------
    design : ObserverDesign
    scenario : mapping
    runs, steps, chunk_runs : int

    Returns
    -------
    result_bytes : float
        The relative error, MSE and support error series (steps + 1 x runs
        each), twice (the chunks and their concatenation).
    chunk_bytes_per_run : float
        Trajectories of one run in a chunk: plant states and outputs, attack
        and noise, the observer's stacked estimates and the metrics'
        temporaries, plus the observer's matrices shared by the chunk.
    flops : float
        Matrix products of the plant and the observer over runs x steps, plus
        the Python-level loops (per step and chunk, and per step and run for
        random and switching supports).
    """
    n, p = design.system.n, design.system.p
    m = design.sensing.shape[0] if design.sparse else 0
    rs = float(runs) * float(steps + 1)
    result_bytes = 2 * 3 * 8.0 * rs
    per_run = 8.0 * (steps + 1) * (8 * p + 6 * n + 3 * (n + m))
    fixed = 8.0 * (4 * (n + m) ** 2 + 2 * m * n)
    # an SSO runs its inner ISTA steps in a Python loop inside each step (1 for other kinds)
    inner = float(max(int(design.inner_steps), 1))
    step_flops = design.observer_kind.simulation_flops(design) * inner
    flops = rs * (step_flops + 2.0 * n * (n + p) + 20.0 * (n + p + m))
    chunks = -(-int(runs) // max(int(chunk_runs), 1))
    flops += float(steps) * chunks * inner * _LOOP_COST + float(runs) * _LOOP_COST
    kind = scenario.get("attack")
    if kind == "random":
        flops += rs * _LOOP_COST
    elif kind == "switching":
        flops += float(runs) * (steps / max(int(scenario.get("period", 1)), 1) + 1) * _LOOP_COST
    return result_bytes, per_run + fixed / max(int(chunk_runs), 1), flops


def _plan(
    design: ObserverDesign,
    scenario: Mapping[str, Any],
    runs: int,
    steps: int,
    chunk_runs: int,
    budget: Budget,
) -> int:
    """Runs per chunk within the memory budget; raises ResourceLimitError with the estimate."""
    inner = (
        f" x {design.inner_steps:,} inner steps (observer.inner_steps)"
        if design.inner_steps > 1
        else ""
    )
    what = (
        f"scenario {scenario.get('name', 'scenario')!r} ({runs:,} runs x {steps:,} steps"
        f"{inner} of the {design.kind} observer)"
    )
    result_bytes, per_run, flops = scenario_cost(design, scenario, runs, steps, chunk_runs)
    chunk = max(1, min(int(chunk_runs), runs))
    room = budget.memory - result_bytes
    if room < per_run * chunk:
        chunk = int(max(1, room // per_run)) if room > 0 else 1
    result_bytes, per_run, flops = scenario_cost(design, scenario, runs, steps, chunk)
    budget.require(what, nbytes=result_bytes + per_run * chunk, flops=flops)
    return chunk


@dataclass(frozen=True)
class ScenarioResult:
    """Per-run, per-step metrics of one scenario.

    Attributes
    ----------
    name, attack, observer : str
    runs, steps, seed : int
    relative_error, mse : ndarray, shape (steps + 1, runs)
        ||x_hat - x|| / max(||x||, 1e-9 ||x0||) and the mean squared error.
    support_error : ndarray or None, shape (steps + 1, runs)
        For observers that estimate the attack.
    detection_delay : ndarray or None, shape (runs,)
    seconds : float
    absolute_error : ndarray, shape (steps + 1, runs)
        ||x_hat - x||.
    initial_relative_error : ndarray, shape (steps + 1, runs)
        ||x_hat(k) - x(k)|| / ||x_hat(0) - x(0)||: the part of the initial error left.
    certified_bound : mapping or None
        Beside a certified error bound (``with_certified_bound``): the bound, the largest
        error observed once the initial error has had time to fade, and whether it is within.
    unresolved_from : int or None
        The first step from which the errors are the floats' rounding of a huge simulated
        state rather than the observer's (an unstable plant), with a note; None where every
        step is resolved.

    ``ssecert.simulation.metrics`` defines each; the relative error grows without bound
    when the state decays and the error does not, so designs are compared on the
    absolute error (same seeds, same plant trajectories).
    """

    name: str
    attack: str
    observer: str
    runs: int
    steps: int
    seed: int
    relative_error: np.ndarray
    mse: np.ndarray
    support_error: np.ndarray | None
    detection_delay: np.ndarray | None
    seconds: float = 0.0
    notes: tuple[str, ...] = field(default=())
    absolute_error: np.ndarray | None = None
    initial_relative_error: np.ndarray | None = None
    certified_bound: dict[str, Any] | None = None
    # the first step whose errors are the floats' rounding of a huge state (``_unresolved_from``)
    unresolved_from: int | None = None

    def final(self) -> dict[str, float | None]:
        """Aggregates at the last step."""
        rel = self.relative_error[-1]
        with np.errstate(over="ignore", invalid="ignore"):  # diverged runs: inf or NaN
            out: dict[str, float | None] = {}
            for key in ("absolute_error", "initial_relative_error"):
                series = getattr(self, key)
                if series is not None:
                    out[f"{key}_mean"] = float(np.mean(series[-1]))
                    out[f"{key}_q90"] = float(quantile(series[-1], 0.9))
            out |= {
                "relative_error_mean": float(np.mean(rel)),
                "relative_error_q90": float(quantile(rel, 0.9)),
                "mse_mean": float(np.mean(self.mse[-1])),
                "support_error_mean": (
                    None if self.support_error is None else float(np.mean(self.support_error[-1]))
                ),
            }
        if self.detection_delay is not None:
            delays = self.detection_delay[np.isfinite(self.detection_delay)]
            out["detection_delay_median"] = float(np.median(delays)) if delays.size else None
            out["detected_fraction"] = float(delays.size / self.runs)
        return out

    def to_dict(self) -> dict[str, Any]:
        """The JSON object of ``ssecert simulate`` for this scenario."""
        series: dict[str, Any] = {
            key: summarize(getattr(self, key))
            for key in ("absolute_error", "initial_relative_error")
            if getattr(self, key) is not None
        }
        series |= {"relative_error": summarize(self.relative_error), "mse": summarize(self.mse)}
        if self.support_error is not None:
            series["support_error"] = summarize(self.support_error)
        return {
            "observer": self.observer,
            "attack": self.attack,
            "runs": self.runs,
            "steps": self.steps,
            "seed": self.seed,
            "final": self.final(),
            "series": series,
            "seconds": self.seconds,
            "notes": list(self.notes),
            **({"certified_bound": self.certified_bound} if self.certified_bound else {}),
            **(
                {"unresolved_from_step": self.unresolved_from}
                if self.unresolved_from is not None
                else {}
            ),
        }

    def with_certified_bound(
        self, bound: float, fading: Callable[[int, int], float], check: str
    ) -> ScenarioResult:
        """This result beside a certified ultimate bound of ||x_hat - x||_2 (the check
        ``check``'s): the largest error over every run in the last quarter of the steps, and an
        allowance for what is left of the initial error there (``fading(k0, steps)``, the
        largest factor over those steps, times max ||e(0)||, from the certificate): the observed
        error must be within the bound plus that allowance.  ``within`` is None where the
        excess is below the rounding of the simulated state itself (2^-40 max ||x||: an
        unstable plant's state of 1e15 makes x_hat - x uncertain by about 1e3 in floats)."""
        if self.absolute_error is None:
            return self
        start = self.steps - self.steps // 4
        observed = float(np.max(self.absolute_error[start:]))
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            # the initial error's part may grow again after ``start`` (a non-normal F): its
            # largest factor over the steps compared
            factor = fading(start, self.steps)
            left = float(factor * np.max(self.absolute_error[0]))
            # ||x|| (at least) from the relative error, where it is defined
            sizes = self.absolute_error[start:] / self.relative_error[start:]
        sizes = sizes[np.isfinite(sizes)]
        rounding = float(np.max(sizes)) * 2.0**-40 if sizes.size else 0.0
        within: bool | None = bool(observed <= bound + left)
        if not within and observed <= bound + left + rounding:
            within = None  # the simulation cannot resolve the bound
        out = {
            "check": check,
            "bound": bound,
            "observed_max": observed,
            "from_step": start,
            "initial_error_left": left,
            "within": within,
        }
        if within is None:
            out["state_rounding"] = rounding
        return replace(self, certified_bound=out)


def stealthy_replay(
    system: System, max_attacked: int, *, context: AnalysisContext | None = None
) -> StealthyReplay | None:
    """The witness of a failing sparse-observability check, or None when it holds.

    With a ``context``, the check the run already made (the certificate's own
    witness) is replayed instead of a new one.
    """
    from ..structure.sparse import sparse_observability

    check = shared(
        context, sparse_key(max_attacked), lambda: sparse_observability(system, max_attacked)
    )
    if check.verdict is not Verdict.FAILS or check.witness is None:
        return None
    w = check.witness
    return StealthyReplay(np.asarray(w["z"], dtype=float), tuple(w["sensors_a"]))


def _chunk(args: tuple) -> dict[str, np.ndarray]:
    """Simulate one chunk of runs (top level, so Dask can pickle it)."""
    # an unstable plant or a diverging observer overflows: the metrics then say so (inf)
    with np.errstate(over="ignore", invalid="ignore"):
        return _simulate_chunk(*args)


def _simulate_chunk(
    design: ObserverDesign,
    scenario: Mapping[str, Any],
    runs: list[int],
    steps: int,
    seed: int,
    replay: StealthyReplay | None,
) -> dict[str, np.ndarray]:
    system = design.system
    data = generate(system, scenario, runs, steps, seed=seed, replay=replay)
    A_T, C_T = system.A.T, system.C.T
    x = data.x0.copy()
    xs = np.empty((steps + 1,) + x.shape)
    ys = np.empty((steps,) + (x.shape[0], system.p))
    xs[0] = x
    for k in range(steps):
        ys[k] = x @ C_T + data.attack[k] + data.noise[k]
        x = x @ A_T
        if data.process is not None:
            x = x + data.process[k]
        xs[k + 1] = x
    observer = observer_from_design(design)
    traj = observer.run(ys)
    d = traj.delay
    # estimate at time k refers to x(k - d); compare where defined
    x_ref = xs if d == 0 else np.concatenate([np.repeat(xs[:1], d, axis=0), xs[:-d]], axis=0)
    error = absolute_error(traj.x_hat, x_ref)
    out = {
        # the largest finite ||x|| and error of the chunk's runs at each step, (steps + 1, 1)
        "state_norm": _largest_finite(np.sqrt(np.einsum("...i,...i->...", x_ref, x_ref))),
        "largest_error": _largest_finite(error),
        "absolute_error": error,
        "initial_relative_error": initial_relative_error(error, data.x0),
        "relative_error": relative_error(traj.x_hat, x_ref, data.x0[None]),
        "mse": mse(traj.x_hat, x_ref),
    }
    if traj.a_hat is not None and traj.a_hat.shape[-1] == system.p:
        # a_hat(k + 1) is the estimate built from y(k): compare it with a(k)
        truth = np.concatenate([np.zeros_like(data.attack[:1]), data.attack], axis=0)
        out["support_error"] = support_error(traj.a_hat, truth)
        out["detection_delay"] = detection_delay(traj.a_hat[1:], data.attack)
    return out


# per step, the largest of a chunk's runs (``_simulate_chunk``)
_TOPS = ("state_norm", "largest_error")


def _largest_finite(values: np.ndarray) -> np.ndarray:
    """The largest finite entry of each row (0 where none), shape (rows, 1)."""
    return np.max(values, axis=-1, keepdims=True, initial=0.0, where=np.isfinite(values))


def simulate_scenario(
    design: ObserverDesign,
    scenario: Mapping[str, Any],
    *,
    runs: int | None = None,
    steps: int | None = None,
    seed: int | None = None,
    max_attacked: int | None = None,
    client: Any | None = None,
    chunk_runs: int = CHUNK_RUNS,
    budget: Budget | None = None,
    context: AnalysisContext | None = None,
) -> ScenarioResult:
    """Simulate a design under a scenario for many runs at once.

    Parameters
    ----------
    design : ObserverDesign
    scenario : mapping
        A validated ``[[scenario]]`` section.
    runs, steps, seed : int, optional
        Override the scenario's values.
    max_attacked : int, optional
        s, needed to compute the stealthy attack of a ``stealthy`` scenario.
    client : dask.distributed.Client, optional
        Spread the chunks of runs over its workers (bitwise-identical
        results to the in-process path).
    chunk_runs : int, default 64
        Runs per chunk (fewer when a chunk would not fit the memory budget).
    budget : Budget, optional
        Memory and work allowed (default ``Budget()``: 2 GiB, 1e12
        operations), estimated by ``scenario_cost`` before anything is
        allocated.
    context : AnalysisContext, optional
        The run's shared results: a stealthy scenario replays the
        sparse-observability witness kept there.

    Returns
    -------
    ScenarioResult

    Raises
    ------
    ResourceLimitError
        (a ``ValueError``) when the scenario does not fit the budget; the
        message gives the estimate.
    ValueError
        For a stealthy scenario on a plant that has no stealthy attack.

    Examples
    --------
    >>> from ssecert.examples import load_example
    >>> from ssecert.observers import build_observer
    >>> spec = load_example("ugv")
    >>> design = build_observer(spec.system, spec.observer)
    >>> res = simulate_scenario(design, spec.scenarios[0], runs=4, steps=50)
    >>> res.relative_error.shape, res.support_error.shape
    ((51, 4), (51, 4))
    """
    start = time.perf_counter()
    runs = int(scenario.get("runs", 50) if runs is None else runs)
    steps = int(scenario.get("steps", 300) if steps is None else steps)
    seed = int(scenario.get("seed", 0) if seed is None else seed)
    chunk_runs = _plan(design, scenario, runs, steps, chunk_runs, budget or Budget())
    replay = None
    if scenario["attack"] == "stealthy":
        replay = stealthy_replay(design.system, int(max_attacked or 0), context=context)
    chunks = [
        (design, dict(scenario), list(range(r0, min(r0 + chunk_runs, runs))), steps, seed, replay)
        for r0 in range(0, runs, chunk_runs)
    ]
    parts = map_ordered(_chunk, chunks, client)
    # (the per-step largest ||x|| and error first, their chunks' arrays freed before the merge)
    tops = [np.max(np.hstack([p.pop(key) for p in parts]), axis=1) for key in _TOPS]
    merged = {key: np.concatenate([p[key] for p in parts], axis=-1) for key in parts[0]}
    notes = []
    bad = ~np.isfinite(merged["relative_error"])  # (steps + 1, runs)
    overflowed = int(np.count_nonzero(bad.any(axis=0)))
    if overflowed:
        first = int(np.argmax(bad.any(axis=1)))
        # a run that overflowed has an unbounded error from then on, not an undefined one
        gone = np.maximum.accumulate(bad, axis=0)
        for key in ("absolute_error", "initial_relative_error", "relative_error", "mse"):
            merged[key] = np.where(gone, np.inf, merged[key])
        notes.append(
            f"the plant state or its estimate overflows in floating point in {overflowed} of "
            f"{runs} runs, the first at step {first:,}: their errors are reported as inf from "
            f"then on"
        )
    unresolved = _unresolved_from(tops[0], tops[1], notes)
    return ScenarioResult(
        name=str(scenario.get("name", "scenario")),
        attack=scenario["attack"],
        observer=design.kind,
        runs=runs,
        steps=steps,
        seed=seed,
        relative_error=merged["relative_error"],
        mse=merged["mse"],
        support_error=merged.get("support_error"),
        detection_delay=merged.get("detection_delay"),
        seconds=time.perf_counter() - start,
        notes=tuple(notes),
        absolute_error=merged["absolute_error"],
        initial_relative_error=merged["initial_relative_error"],
        unresolved_from=unresolved,
    )


# the simulated state's rounding taken as 2^-40 ||x||: x_hat and x each carry a relative
# rounding of a few thousand eps after the steps of a simulation
STATE_ROUNDING = 2.0**-40


def _unresolved_from(state_norm: np.ndarray, error: np.ndarray, notes: list[str]) -> int | None:
    """The first step from which the error metrics are the floats' rounding rather than the
    observer's, or None (``state_norm``, ``error``: the largest finite ||x|| and ||x_hat -
    x|| of the runs at each step, shape (steps + 1,)): where the simulated state is so large (an unstable plant) that
    x_hat - x, a difference of two numbers near it, is known only to about 2^-40 ||x||, and
    that is within a factor 1,000 of both the largest error at that step and the largest
    initial error (an error converging to 0 on a stable plant stays resolved: it is below the
    state's rounding, but so is nothing it is compared with).  A note says so."""
    from ..base.format import readable

    with np.errstate(over="ignore", invalid="ignore"):
        rounding, largest = state_norm * STATE_ROUNDING, error
        lost = (rounding > 0) & (rounding >= 1e-3 * largest) & (rounding >= 1e-3 * largest[0])
    if not lost.any():
        return None
    first = int(np.argmax(lost))
    top = float(rounding[first:].max())
    notes.append(
        f"from step {first:,} the simulated state reaches {readable(top / STATE_ROUNDING)}, "
        f"so x_hat - x is known only to about {readable(top)} "
        f"(2^-40 ||x||), within a factor 1,000 of the errors reported: from there on they are "
        "the rounding of the floats, not the observer's error (the plant is unstable; fewer "
        "steps keep the state within the floats' resolution)"
    )
    return first


@dataclass(frozen=True)
class GridResult:
    """Grid search over observer hyperparameters.

    ``points`` lists, per grid point, the parameters and the final metrics;
    ``best`` is the point with the smallest cost
    alpha * MSE + (1 - alpha) * support error (thesis (6.1), with our
    support error for its MASE).
    """

    points: list[dict[str, Any]]
    best: dict[str, Any]
    alpha: float

    def to_dict(self) -> dict[str, Any]:
        return {"points": self.points, "best": self.best, "alpha": self.alpha}


def _grid_point(args: tuple) -> dict[str, Any]:
    system, observer, params, scenario, runs, steps, seed, s, budget = args
    design = build_observer(system, {**observer, **params}, budget=budget)
    res = simulate_scenario(
        design, scenario, runs=runs, steps=steps, seed=seed, max_attacked=s, budget=budget
    )
    return res.final()


def grid_search(
    system: System,
    observer: Mapping[str, Any],
    scenario: Mapping[str, Any],
    grid: Mapping[str, Sequence[Any]],
    *,
    runs: int | None = None,
    steps: int | None = None,
    seed: int | None = None,
    alpha: float = 0.5,
    max_attacked: int | None = None,
    client: Any | None = None,
    budget: Budget | None = None,
) -> GridResult:
    """Evaluate an observer over a grid of hyperparameters under a scenario.

    Parameters
    ----------
    system : System
    observer : mapping
        A validated ``[observer]`` section; grid values override its keys.
    scenario : mapping
    grid : mapping of str to sequence
        E.g. ``{"step": [0.1, 0.3], "threshold": [0.05, 0.1]}``.
    runs, steps, seed : int, optional
    alpha : float, default 0.5
        Weight of the MSE in the cost alpha MSE + (1 - alpha) support error.
    max_attacked : int, optional
    client : dask.distributed.Client, optional
        Evaluate grid points on its workers.
    budget : Budget, optional
        Bounds each grid point's simulation (see ``simulate_scenario``).

    Returns
    -------
    GridResult
    """
    import itertools

    keys = list(grid)
    combos = [dict(zip(keys, values)) for values in itertools.product(*(grid[k] for k in keys))]
    tasks = [
        (system, dict(observer), c, dict(scenario), runs, steps, seed, max_attacked, budget)
        for c in combos
    ]
    finals = map_ordered(_grid_point, tasks, client)
    points = []
    for params, final in zip(combos, finals):
        support = final.get("support_error_mean")
        cost = alpha * final["mse_mean"] + (1 - alpha) * (support if support is not None else 0.0)
        points.append({"params": params, **final, "cost": cost})
    best = min(points, key=lambda pt: pt["cost"])
    return GridResult(points, best, alpha)


def simulate_spec(
    spec: Any,
    *,
    seed: int | None = None,
    runs: int | None = None,
    steps: int | None = None,
    client: Any | None = None,
    budget: Budget | None = None,
    context: AnalysisContext | None = None,
) -> dict[str, Any]:
    """Simulate every ``[[scenario]]`` of a spec with its ``[observer]``.

    Parameters
    ----------
    spec : Spec
    seed : int, optional
        Replaces every scenario's seed.
    runs, steps : int, optional
        Override every scenario's values.
    client : dask.distributed.Client, optional
    budget : Budget, optional
        Memory and work allowed per scenario (default ``Budget()``: 2 GiB,
        1e12 operations).
    context : AnalysisContext, optional
        Shared results of the run (the observer, the stealthy witness); one
        is made when none is given, so that the scenarios share them.

    Returns
    -------
    dict
        ``{"scenarios": {NAME: ScenarioResult or {"skipped": reason}}}``.

    Raises
    ------
    ValueError
        If the spec has no observer or no scenario.
    ResourceLimitError
        Before anything is simulated, if a scenario does not fit the budget
        (the message names the scenario's keys and gives the estimate), or
        if the observer's matrices do not.
    """
    if spec.observer is None:
        raise ValueError(f"{spec.source}: the spec has no [observer] section to simulate")
    if not spec.scenarios:
        raise ValueError(f"{spec.source}: the spec has no [[scenario]] section")
    budget = budget or Budget()
    context = context if context is not None else AnalysisContext()
    try:
        design = context.once(
            OBSERVER, lambda: build_observer(spec.system, spec.observer, budget=budget)
        )
    except ResourceLimitError as exc:
        raise ResourceLimitError(f"{spec.source}: {exc}") from None
    for index, scenario in enumerate(spec.scenarios):
        count = int(scenario.get("runs", 50) if runs is None else runs)
        length = int(scenario.get("steps", 300) if steps is None else steps)
        try:
            _plan(design, scenario, count, length, CHUNK_RUNS, budget)
        except ResourceLimitError as exc:
            names = [
                f"--{key}" if override is not None else f"scenario[{index}].{key}"
                for key, override in (("runs", runs), ("steps", steps))
            ]
            if design.inner_steps > 1:
                names.insert(0, "observer.inner_steps")
            keys = ", ".join(names[:-1]) + f" and {names[-1]}"
            raise ResourceLimitError(f"{spec.source}: {exc}; lower {keys}") from None
    out: dict[str, Any] = {}
    for scenario in spec.scenarios:
        try:
            with stage(f"scenario {scenario['name']}"):
                out[scenario["name"]] = simulate_scenario(
                    design,
                    scenario,
                    runs=runs,
                    steps=steps,
                    seed=seed,
                    max_attacked=spec.max_attacked,
                    client=client,
                    budget=budget,
                    context=context,
                )
        except ResourceLimitError:
            raise
        except ValueError as exc:  # a stealthy scenario on a sparse-observable plant
            out[scenario["name"]] = {"skipped": str(exc)}
    return {"scenarios": out}
