"""Attack scenarios: initial states, attack sequences and measurement noise.

Every run draws its randomness from ``numpy.random.default_rng([seed,
run_index])``, so run r of a scenario is the same whichever batch, chunk or
worker computes it.

Scenario keys (the spec's ``[[scenario]]`` sections, defaults filled in by
``ssecert.spec``): ``attack`` in none | constant | switching | sinusoidal |
random | stealthy; ``sensors`` (0-based) or ``count``; ``magnitude`` (range of
|a_i|, random sign); ``period`` (switching: steps between support changes;
sinusoidal: period in steps); ``noise`` (bound of uniform measurement noise);
``steps``; ``runs``; ``seed``.

x0 has entries of magnitude uniform in [2, 3] with random signs (Lasso paper,
Sec. 5.1).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..structure.attacks import initial_state
from ..system import System

__all__ = ["ScenarioData", "generate", "run_rng", "StealthyReplay"]


@dataclass(frozen=True)
class StealthyReplay:
    """What a stealthy scenario replays: z and the sensors of attack_a."""

    z: np.ndarray
    sensors: tuple[int, ...]


@dataclass(frozen=True)
class ScenarioData:
    """Random inputs of a batch of runs.

    Attributes
    ----------
    runs : ndarray of int
        Run indices.
    x0 : ndarray, shape (runs, n)
    attack : ndarray, shape (steps, runs, p)
    noise : ndarray, shape (steps, runs, p)
    process : ndarray, shape (steps, runs, n), or None
        G w(k), what the process noise adds to the state at each step (None without process
        noise): x(k + 1) = A x(k) + process[k].
    """

    runs: np.ndarray
    x0: np.ndarray
    attack: np.ndarray
    noise: np.ndarray
    process: np.ndarray | None = None


def run_rng(seed: int, run: int) -> np.random.Generator:
    """The generator of run ``run`` of a scenario seeded with ``seed``."""
    return np.random.default_rng([int(seed), int(run)])


def _magnitudes(rng: np.random.Generator, size: int, magnitude: Sequence[float]) -> np.ndarray:
    lo, hi = magnitude
    return _uniform(rng, lo, hi, size) * rng.choice([-1.0, 1.0], size)


def _uniform(rng: np.random.Generator, lo: Any, hi: Any, size: Any) -> np.ndarray:
    """``rng.uniform(lo, hi, size)``, also where hi - lo is beyond the float range (a noise
    bound of 1e308): then drawn in halves of the range, which ``uniform`` can take.  ``lo``
    and ``hi`` may be arrays (one bound per sensor, broadcast along the last axis)."""
    with np.errstate(over="ignore"):
        spread = np.asarray(hi, dtype=float) - np.asarray(lo, dtype=float)
    if np.all(np.isfinite(spread)):
        return rng.uniform(lo, hi, size)
    middle = 0.5 * lo + 0.5 * hi
    return middle + rng.uniform(-0.5, 0.5, size) * 2.0 * (0.5 * hi - 0.5 * lo)


#: below this truncation a truncated Gaussian is drawn as the uniform distribution it tends to
#: (the normal distribution's values at +-t round together where t is tiny)
TRUNCATION_UNIFORM = 1e-3


def _draw(
    rng: np.random.Generator, bound: Any, size: tuple[int, ...], scenario: Mapping[str, Any]
) -> np.ndarray:
    """Noise within +-``bound`` (a number, or one per entry of the last axis): uniform, or with
    ``distribution = "gaussian"`` Gaussian with standard deviation bound / truncation,
    truncated at the bound (by inverting the normal distribution on the uniform draws between
    its values at -truncation and +truncation)."""
    if scenario.get("distribution", "uniform") != "gaussian":
        return _uniform(rng, -bound, bound, size)
    t = float(scenario.get("truncation", 3.0))
    if t < TRUNCATION_UNIFORM:  # the density varies by less than t^2 / 2 < 5e-7: uniform
        return _uniform(rng, -bound, bound, size)
    from scipy import special  # only for Gaussian draws

    edge = float(special.ndtr(-t))
    z = special.ndtri(rng.uniform(edge, 1.0 - edge, size))
    # |z / t| <= 1, so each sample is within its bound (a product by at most 1 rounds within)
    return np.clip(z / t, -1.0, 1.0) * np.asarray(bound, dtype=float)


def _support(rng: np.random.Generator, p: int, scenario: Mapping[str, Any]) -> np.ndarray:
    if scenario.get("sensors") is not None:
        return np.asarray(scenario["sensors"], dtype=np.int64)
    return np.sort(rng.choice(p, int(scenario["count"]), replace=False))


def generate(
    system: System,
    scenario: Mapping[str, Any],
    runs: Sequence[int],
    steps: int,
    *,
    seed: int,
    replay: StealthyReplay | None = None,
) -> ScenarioData:
    """Draw x0, the attack and the noise of the given runs.

    Parameters
    ----------
    system : System
    scenario : mapping
        A validated ``[[scenario]]`` section.
    runs : sequence of int
        Run indices to generate.
    steps : int
    seed : int
    replay : StealthyReplay, optional
        Required for ``attack = "stealthy"``: the direction z and sensors of
        the sparse-observability witness.  The plant starts at x0 and the
        attack P_a C A^k (m z) (m drawn from the magnitude range) makes its
        outputs identical to those of the plant started at x0 + m z.

    Returns
    -------
    ScenarioData

    Raises
    ------
    ValueError
        For a stealthy scenario without a witness to replay.

    Examples
    --------
    >>> from ssecert import System
    >>> sc = {"attack": "constant", "sensors": [1], "magnitude": (4.0, 5.0), "noise": 0.0}
    >>> data = generate(System([[1.0]], [[1.0], [1.0]]), sc, [0, 1], 3, seed=0)
    >>> data.attack.shape, bool((data.attack[:, :, 0] == 0).all())
    ((3, 2, 2), True)
    """
    n, p = system.n, system.p
    kind = scenario["attack"]
    magnitude = scenario.get("magnitude", (4.0, 5.0))
    bounds = np.broadcast_to(np.asarray(scenario.get("noise", 0.0), dtype=float), (p,))
    # one bound for every sensor is drawn as before (the same numbers, run by run)
    noise_bound: Any = float(bounds[0]) if np.all(bounds == bounds[0]) else bounds
    run_ids = np.asarray(list(runs), dtype=np.int64)
    x0 = np.empty((run_ids.size, n))
    attack = np.zeros((steps, run_ids.size, p))
    noise = np.zeros((steps, run_ids.size, p))
    process = None
    if scenario.get("process") is not None:  # drawn after the rest: their draws stay the same
        omega = np.asarray(scenario["process"], dtype=float)
        G = np.asarray(scenario.get("process_input", np.eye(n)), dtype=float)
        process = np.zeros((steps, run_ids.size, n))
    if kind == "stealthy":
        if replay is None:
            raise ValueError(
                "a stealthy scenario needs the sparse-observability witness; the plant is "
                "s-sparse observable, so no stealthy attack exists"
            )
        trace = np.empty((steps, n))  # A^k z
        w = np.asarray(replay.z, dtype=float)
        for k in range(steps):
            trace[k] = w
            w = system.A @ w
        mask = np.zeros(p)
        mask[list(replay.sensors)] = 1.0
        pattern = (trace @ system.C.T) * mask  # P_a C A^k z
    for j, r in enumerate(run_ids):
        rng = run_rng(seed, int(r))
        x0[j] = initial_state(n, rng)
        if kind == "none":
            pass
        elif kind == "constant":
            support = _support(rng, p, scenario)
            attack[:, j, support] = _magnitudes(rng, support.size, magnitude)
        elif kind == "sinusoidal":
            support = _support(rng, p, scenario)
            amp = _magnitudes(rng, support.size, magnitude)
            phase = rng.uniform(0.0, 2 * np.pi, support.size)
            times = np.arange(steps)[:, None]
            attack[:, j, support] = amp * np.sin(2 * np.pi * times / scenario["period"] + phase)
        elif kind == "switching":
            period = int(scenario["period"])
            for start in range(0, steps, period):
                support = _support(rng, p, scenario)
                attack[start : start + period, j, support] = _magnitudes(
                    rng, support.size, magnitude
                )
        elif kind == "random":
            count = int(scenario["count"])
            for k in range(steps):
                support = rng.choice(p, count, replace=False)
                attack[k, j, support] = _magnitudes(rng, count, magnitude)
        elif kind == "stealthy":
            scale = _magnitudes(rng, 1, magnitude)[0]
            attack[:, j, :] = scale * pattern
        else:  # pragma: no cover - the spec validator refuses other kinds
            raise ValueError(f"unknown attack kind {kind!r}")
        if np.any(noise_bound > 0):
            noise[:, j, :] = _draw(rng, noise_bound, (steps, p), scenario)
        if process is not None and np.any(omega > 0):
            process[:, j, :] = _draw(rng, omega, (steps, omega.size), scenario) @ G.T
    return ScenarioData(run_ids, x0, attack, noise, process)
