"""The pruning paper's simulations (Sec. IV): Fig. 1, and Fig. 2 with Table I.

Fig. 1 (Sec. IV-A): for m = 20 sensors and n = 10 states, the l1 observer
without prior (Definition 1), the weighted l1 observer with the unpruned
prior and with the pruned prior (Definition 5), on the stacked window model
(3) under the attack (8) of Theorem 2.1; success is a relative state error
below 0.1%.  What the paper leaves open, and the values taken here, are
listed in the experiment's entry (``UNSTATED``).
"""

from __future__ import annotations

import functools
import time
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from ._registry import Result, Settings, experiment, figure

__all__ = ["PruningOptions", "breakdown", "measure"]


@dataclass(frozen=True)
class PruningOptions:
    """The settings of Fig. 1's simulation (those the paper leaves open marked in
    ``UNSTATED``)."""

    runs: int = 200
    window: int = 10
    true_rate: float = 0.6
    reliability: float = 0.9
    omega: float = 0.05
    eps_rel: float = 0.01
    tol: float = 1e-3
    step: int = 1
    prior_model: str = "paper"
    seed: int = 0


M_SENSORS = 20
N_STATES = 10
#: "the resiliency is improved a lot" by pruning, read as: the breakdown moves by at
#: least this much in P_A.
LARGE_GAIN = 0.2
#: "the improvement is limited" with the raw prior, read as: it moves by less than this.
LIMITED_GAIN = 0.1


def random_plant(rng: np.random.Generator, window: int) -> np.ndarray:
    """Stacked window matrix H of a Gaussian (A, C), A scaled to spectral radius 1."""
    A = rng.standard_normal((N_STATES, N_STATES))
    A /= np.max(np.abs(np.linalg.eigvals(A)))
    C = rng.standard_normal((M_SENSORS, N_STATES))
    from ..system import System

    return System(A, C).observability_matrix(window)


def one_run(rng: np.random.Generator, attacked: int, args: PruningOptions) -> dict:
    """Relative errors of the three observers and the pruned prior's quality for one trial."""
    from ..estimators.pruning import (
        l1_decode,
        pruned_weighted_l1_window_observer,
        weighted_l1_observer,
    )
    from ..estimators.pruning_attacks import successful_attack

    H = random_plant(rng, args.window)
    rows = H.shape[0]
    x = rng.standard_normal(N_STATES)
    y = H @ x
    sensors = rng.choice(M_SENSORS, attacked, replace=False)
    support = [step * M_SENSORS + i for step in range(args.window) for i in sensors]
    silent = True
    if support:
        eps = args.eps_rel * float(np.sum(np.abs(y)))
        attack = successful_attack(H, support, eps)
        silent = attack.detector_silent
        y = y + attack.attack

    safe = np.ones(rows, dtype=bool)
    safe[support] = False
    if args.prior_model == "paper":
        probs = np.asarray(rng.uniform(2.0 * args.true_rate - 1.0, 1.0, rows))
        prior_right = rng.random(rows) < probs
    else:
        # The published code's model: p_i >= 0.5 with probability T_r, and the prior is
        # right exactly when p_i > 0.5 (no Bernoulli draw).
        high = rng.random(rows) < args.true_rate
        probs = np.where(high, rng.uniform(0.5, 1.0, rows), rng.uniform(0.0, 0.5, rows))
        prior_right = probs > 0.5
    prior_safe = np.flatnonzero(np.where(prior_right, safe, ~safe)).tolist()

    def error(x_hat: np.ndarray) -> float:
        return float(np.linalg.norm(x_hat - x) / np.linalg.norm(x))

    plain = l1_decode(H, y)
    with_prior = weighted_l1_observer(H, y, prior_safe, omega=args.omega)
    pruned = pruned_weighted_l1_window_observer(
        H, y, prior_safe, probs, sensors=M_SENSORS, reliability=args.reliability, omega=args.omega
    )
    trusted = list(pruned.trusted)
    return {
        "plain": error(plain),
        "prior": error(with_prior.x_hat),
        "pruned": error(pruned.x_hat),
        "ppv_prior": float(np.mean(safe[prior_safe])) if prior_safe else float("nan"),
        "ppv_pruned": float(np.mean(safe[trusted])) if trusted else float("nan"),
        "trusted": len(trusted),
        "all_right": float(np.all(safe[trusted])) if trusted else float("nan"),
        "silent": silent,
    }


def breakdown(table: list[dict], key: str) -> float | None:
    """Attack percentage where the success rate falls below 1/2 for good (linear interpolation).

    0 if it is never 1/2 or more; None if it is still 1/2 or more at the last row.
    """
    rates = [row[key] for row in table]
    above = [i for i, rate in enumerate(rates) if rate >= 0.5]
    if not above:
        return 0.0
    last = above[-1]
    if last == len(rates) - 1:
        return None
    a, b = table[last], table[last + 1]
    fraction = (a[key] - 0.5) / (a[key] - b[key])
    return a["P_A"] + fraction * (b["P_A"] - a["P_A"])


def measure(args: PruningOptions) -> dict[str, Any]:
    """Success rates and prior quality per attack percentage (plain numbers, JSON-ready)."""
    start = time.perf_counter()
    table = []
    for attacked in range(0, M_SENSORS + 1, args.step):
        results = [
            one_run(np.random.default_rng([args.seed, attacked, run]), attacked, args)
            for run in range(args.runs)
        ]

        def mean(key: str, results: list = results) -> float:
            values = [float(r[key]) for r in results if not np.isnan(r[key])]
            return float(np.mean(values)) if values else float("nan")

        row = {
            key: float(np.mean([r[key] < args.tol for r in results]))
            for key in ("plain", "prior", "pruned")
        }
        row.update(
            P_A=attacked / M_SENSORS,
            k=attacked,
            ppv_one=mean("all_right"),
            ppv_prior=mean("ppv_prior"),
            ppv_pruned=mean("ppv_pruned"),
            trusted=mean("trusted"),
            silent=mean("silent"),
        )
        table.append(row)
    return {
        "options": asdict(args),
        "rows": table,
        "seconds": time.perf_counter() - start,
    }


UNSTATED = {
    "plant": "A divided by its spectral radius; a new plant, x ~ N(0, I) and attack support "
    "per run",
    "window": "T = 10 steps (the code published with the paper uses 11), stacked oldest first",
    "attack": "the same sensors over the whole window; eps = 0.01 ||H x||_1 with the "
    "detector-safe scaling of (8)",
    "prior": "p_i ~ Uniform[2 T_r - 1, 1] per stacked row (any law with mean T_r fits), the "
    "prior right with probability p_i (model (10))",
    "pruning": "eta = 0.9, omega = 0.05 on untrusted rows ('close to zero, but not zero')",
    "rows": "P_A every 2 sensors in the quick runs, every sensor otherwise",
}


@experiment(
    "pruning.fig1",
    where="Sec. IV-A, Fig. 1 (m = 20 sensors, n = 10 states, T_r = 0.6)",
    measures="success rate of the l1 observer, the weighted one with the raw prior and with "
    "the pruned prior, against the attack percentage P_A",
)
def fig1(settings: Settings) -> Result:
    runs = settings.count(20, 1000)
    options = PruningOptions(
        runs=runs, step=2 if settings.quick and settings.runs is None else 1, seed=settings.seed
    )
    numbers = measure(options)
    points = {k: breakdown(numbers["rows"], k) for k in ("plain", "prior", "pruned")}
    # never broken down: beyond the last row
    plain, prior, pruned = (2.0 if v is None else v for v in points.values())
    return Result(
        paper={
            "l1 breaks down at P_A <= 1/2": True,
            "the raw prior's gain is limited": True,
            "pruning's gain is large": True,
            "order l1 <= raw prior <= pruned prior": True,
        },
        ours={
            "l1 breaks down at P_A <= 1/2": plain <= 0.5,
            "the raw prior's gain is limited": 0 <= prior - plain < LIMITED_GAIN,
            "pruning's gain is large": pruned - plain >= LARGE_GAIN,
            "order l1 <= raw prior <= pruned prior": plain <= prior <= pruned,
        },
        unstated={**UNSTATED, "runs": f"{runs} per row (the paper: 1000)"},
        table=[{"breakdown": points}, *numbers["rows"]],
        figure=figure(
            "success rate against the attack percentage",
            "attack percentage P_A",
            "success rate",
            {
                label: ([r["P_A"] for r in numbers["rows"]], [r[key] for r in numbers["rows"]])
                for key, label in (
                    ("plain", "l1 observer without prior"),
                    ("prior", "weighted l1 observer with prior"),
                    ("pruned", "weighted l1 observer with prior pruning"),
                )
            },
        ),
        why=f"the breakdown moves from P_A = {plain:.2f} (l1) to {prior:.2f} (raw prior) and "
        f"{pruned:.2f} (pruned): pruning gains {pruned - plain:+.2f}, our rule for 'a lot' is "
        f"{LARGE_GAIN:g}, for 'limited' under {LIMITED_GAIN:g}."
        if not (plain <= 0.5 and 0 <= prior - plain < LIMITED_GAIN and pruned - plain >= LARGE_GAIN)
        else "",
        note="The breakdown is the P_A where a success rate falls below 1/2 for good. The "
        f"paper's words are read as: a limited gain moves it by less than {LIMITED_GAIN:g}, a "
        f"large one by at least {LARGE_GAIN:g}.",
    )


@functools.lru_cache(maxsize=2)
def _table1(seed: int) -> Any:
    from ..estimators.power_grid import ieee14_table1

    return ieee14_table1(seed=seed)


_GRID_UNSTATED = {
    "model": "the packaged ieee14 example: PYPOWER's case14 linearised as the code published for "
    "the set-up does (five machines, rotor angles and speeds, 19 meters: 5 speeds and 14 bus "
    "injections; tools/make_ieee14.py lists its departures from the DC power flow)",
    "attacked meters": "round(0.3 x 19) = 6 per step, drawn with replacement and redrawn every "
    "step from step 160, under the bad-data detector (the code's settings)",
    "observers": "LO with random poles in [0.1, 0.5] (python-control's place: MATLAB's gives "
    "another gain for the same poles); LIO and WLIP over a window of 20 steps from step 30; "
    "prior T_r = 0.5, reliability 0.6 x the bound (17), weight 0.01 on untrusted rows",
    "runs": "one run of 800 steps, no noise, zero initial error (the paper shows one run)",
}


def _keys(table: Any) -> dict[str, float]:
    from ..estimators.power_grid import ANGLES, METHODS

    return {
        f"{metric} {method} {angle}": float(values[i, j])
        for metric, values in (("RMS", table.rms), ("Max. Abs.", table.max_abs))
        for j, method in enumerate(METHODS)
        for i, angle in enumerate(ANGLES)
    }


@experiment(
    "pruning.table1",
    where="Sec. IV-B, Table I (IEEE 14-bus system, 30% of the meters attacked)",
    measures="RMS and maximum absolute error of delta_1..delta_5 for LO, LIO and WLIP",
)
def table1(settings: Settings) -> Result:
    from ..estimators.power_grid import PAPER_TABLE1

    run = _table1(settings.seed)
    return Result(
        paper=_keys(PAPER_TABLE1),
        ours=_keys(run.table),
        unstated=_GRID_UNSTATED,
        table=[{"paper": PAPER_TABLE1.to_dict(), "ours": run.table.to_dict()}],
        why=_table1_why(run.table, PAPER_TABLE1),
        note="WLIP's errors are near zero here because, with the set-up's prior and weight "
        "0.01 on untrusted rows, the pruned prior is always right and the weighted decoder "
        "recovers the state exactly (a heavier weight on untrusted rows gives errors of the "
        "paper's size; which one the paper ran is not stated).",
    )


def table1_gaps(ours: Any, paper: Any) -> dict[str, tuple[float, float]]:
    """Per method, the largest relative gap of its RMS errors and of its largest errors from
    the paper's Table I (0.82: 82% off)."""
    from ..estimators.power_grid import METHODS

    def gap(metric: str, j: int) -> float:
        a, b = getattr(ours, metric)[:, j], getattr(paper, metric)[:, j]
        return float(np.max(np.abs(a - b) / np.abs(b)))

    return {method: (gap("rms", j), gap("max_abs", j)) for j, method in enumerate(METHODS)}


def _table1_why(ours: Any, paper: Any) -> str:
    """Per method and metric (RMS, largest), the largest relative gap of its errors from the
    paper's Table I."""
    gaps = [
        f"{method} within {rms:.0%} (RMS) and {top:.0%} (largest)"
        for method, (rms, top) in table1_gaps(ours, paper).items()
    ]
    largest = float(np.max(ours.max_abs[:, 2]))
    return (
        f"errors: {', '.join(gaps)} of the paper's; WLIP's largest error is "
        f"{largest:.1g} here: with the set-up's prior and weight 0.01 its pruned prior is "
        "always right, so it recovers the angles exactly."
    )


@experiment(
    "pruning.fig2",
    where="Sec. IV-B, Fig. 2 (IEEE 14-bus system, 30% of the meters attacked)",
    measures="the phase angles delta_1..delta_5 estimated by the l1 observer without prior "
    "(LIO) and with pruning (WLIP): whether LIO works with spikes that WLIP removes",
)
def fig2(settings: Settings) -> Result:
    run = _table1(settings.seed)
    lo, lio, wlip = (run.table.max_abs[:, j] for j in range(3))
    return Result(
        paper={
            "LIO works well (its largest error under a tenth of LO's)": True,
            "LIO shows spikes (its largest error over 3 times its RMS)": True,
            "WLIP removes the spikes (its largest error under half of LIO's)": True,
        },
        ours={
            "LIO works well (its largest error under a tenth of LO's)": bool(
                np.all(lio < 0.1 * lo)
            ),
            "LIO shows spikes (its largest error over 3 times its RMS)": bool(
                np.all(lio > 3 * run.table.rms[:, 1])
            ),
            "WLIP removes the spikes (its largest error under half of LIO's)": bool(
                np.all(wlip < 0.5 * lio)
            ),
        },
        unstated=_GRID_UNSTATED,
        table=[{"max_abs": run.table.to_dict()["max_abs"], "rms": run.table.to_dict()["rms"]}],
        figure=figure(
            "absolute error of delta_1 against time",
            "step k",
            "|delta_1 - its estimate|",
            {
                name: (range(run.errors.shape[1]), np.abs(run.errors[j, :, 0]))
                for j, name in enumerate(("LO", "LIO", "WLIP"))
            },
            log=True,
        ),
        note="The figure's words ('works well', 'notable spikes', 'completely eliminates the "
        "spikes') read as rules on each angle's largest and RMS errors, stated in the keys.",
    )
