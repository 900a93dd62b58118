"""The thesis's simulations (Ch. 6): Figs. 6.1-6.7.

Figs. 6.2-6.5 (Sec. 6.2): the D-SSO against the elastic-net observer on the
packaged random-n15-p30 plant (n = 15, p = 30, A and C Gaussian, A scaled
so that its dominant eigenvalue is 1), h = 3 attacked sensors with
magnitudes in [4, 5], both observers with the deadbeat gain.  Tuning, as
the thesis did it (Sec. 6.2.2): both observers grid-searched with the cost
(6.1), alpha MSE + (1 - alpha) MASE; the thesis gives neither grid, so both
are tuned the same way: a grid search on the constant-attack scenario (its
own seed, 400 steps), alpha = 0.5 and our support error standing for the
MASE, over the same step and threshold values (the elastic net also over
shrink): ``FULL_GRID``, or ``QUICK_GRID`` in the quick runs.  The D-SSO at
the values the thesis set by hand in Sec. 6.1 (nu = 0.7, lambda = 0.1) is
simulated too, as "D-SSO (6.1)".
"""

from __future__ import annotations

import functools
import math
import time
from typing import Any

import numpy as np

from ._registry import Result, Settings, experiment, figure

__all__ = ["FULL_GRID", "QUICK_GRID", "measure", "no_attack", "tune"]


ATTACKED = 3
ALPHA = 0.5
#: The D-SSO's values of the thesis's Sec. 6.1, set "empirically" there.
THESIS_DSSO = {"step": 0.7, "threshold": 0.1}
QUICK_GRID = {
    "step": [0.1, 0.3, 0.7],
    "threshold": [0.05, 0.1, 0.2],
    "shrink": [0.9, 0.95, 0.99],
}
FULL_GRID = {
    "step": [0.1, 0.2, 0.3, 0.5, 0.7, 0.9, 1.0, 1.2],
    "threshold": [0.01, 0.02, 0.05, 0.1, 0.2, 0.5],
    "shrink": [0.9, 0.95, 0.98, 0.99, 0.995],
}
TUNING_STEPS, TUNING_SEED = 400, 1
#: The thesis's words for the new observer (Sec. 6.2.7), read as rules on the numbers.
CLOSE_TO_ZERO = 1e-6  # final MSE at most this fraction of the initial MSE
SUPPORT_IDENTIFIED = 0.05  # final mean support error at most this
MSE_ATOL = 1e-20  # MSEs below this are zero in floating point: a tie
SUPPORT_ATOL = 0.01
OBSERVERS = ("D-SSO", "elastic net", "D-SSO (6.1)")
BASE: dict[str, Any] = {
    "attack": "constant",
    "count": ATTACKED,
    "magnitude": (4.0, 5.0),
    "noise": 0.0,
    "seed": 0,
}
SCENARIOS: dict[str, dict[str, Any]] = {
    "constant": BASE,
    "switching (every 400)": {**BASE, "attack": "switching", "period": 400},
    "sinusoidal": {**BASE, "attack": "sinusoidal", "period": 100},
}
NO_ATTACK = "no attack (a_hat(0) rnd)"


def no_attack(design: Any, runs: int, steps: int, seed: int) -> tuple[float, float, float]:
    """No attack, a_hat(0) random (the thesis's set-up): initial and final MSE, support error.

    The support error is the fraction of runs whose attack estimate is not exactly zero
    at the end (any false alarm).
    """
    from ..observers import observer_from_design
    from ..simulation.metrics import mse
    from ..simulation.scenarios import generate

    system = design.system
    data = generate(system, {"attack": "none", "noise": 0.0}, range(runs), steps, seed=seed)
    x, ys, xs = data.x0.copy(), [], []
    for _ in range(steps):
        ys.append(x @ system.C.T)
        xs.append(x)
        x = x @ system.A.T
    xs.append(x)
    obs = observer_from_design(design)
    state = obs.initial_state(runs)
    rng = np.random.default_rng(seed)
    state["a_hat"] = rng.uniform(-5, 5, state["a_hat"].shape) * (
        rng.random(state["a_hat"].shape) < 0.1
    )
    traj = obs.run(np.array(ys), state)
    initial = float(np.mean(mse(traj.x_hat[0], xs[0])))
    final = float(np.mean(mse(traj.x_hat[-1], xs[-1])))
    a_hat = traj.a_hat
    assert a_hat is not None  # a sparse observer estimates the attack
    support = float(np.mean(np.any(np.abs(a_hat[-1]) > 1e-9, axis=1)))
    return initial, final, support


def tune(
    system: Any, observer: dict[str, Any], grid: dict[str, list[float]], runs: int, seed: int = 0
) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """Grid search of one observer with cost (6.1); the best finite-cost point and all costs."""
    from ..simulation.engine import grid_search

    result = grid_search(
        system,
        observer,
        {**BASE, "name": "tuning"},
        grid,
        runs=runs,
        steps=TUNING_STEPS,
        seed=TUNING_SEED + seed,
        alpha=ALPHA,
    )
    finite = [pt for pt in result.points if math.isfinite(pt["cost"])]
    best = min(finite, key=lambda pt: pt["cost"]) if finite else result.best
    return best, result.points


def measure(runs: int, steps: int, grid: dict[str, list[float]], seed: int = 0) -> dict[str, Any]:
    """Tune both observers, simulate the four scenarios (plain numbers, JSON-ready); ``seed``
    shifts every seed (the tuning's, the scenarios' and the no-attack runs')."""
    from ..examples import load_example
    from ..observers import build_observer
    from ..simulation.engine import simulate_scenario

    system = load_example("random-n15-p30").system
    tuning_runs = max(10, runs // 5)
    dsso = {"kind": "dsso", "gain": "deadbeat", "shrink": 1.0, **THESIS_DSSO}
    en = {"kind": "elastic_net", "gain": "deadbeat", "step": 0.3, "threshold": 0.1}
    dsso_grid = {key: grid[key] for key in ("step", "threshold")}
    tuned: dict[str, Any] = {}
    observers: dict[str, dict[str, Any]] = {}
    for label, base, g in (
        ("D-SSO", dsso, dsso_grid),
        ("elastic net", {**en, "shrink": 0.95}, grid),
    ):
        best, points = tune(system, base, g, tuning_runs, seed)
        thesis = next(
            (
                pt["cost"]
                for pt in points
                if all(pt["params"].get(k) == v for k, v in THESIS_DSSO.items())
            ),
            None,
        )
        tuned[label] = {
            "grid": g,
            "points": len(points),
            "diverged": sum(not math.isfinite(pt["cost"]) for pt in points),
            "best": best["params"],
            "cost": best["cost"],
            "sharing_best_cost": sum(
                math.isclose(pt["cost"], best["cost"], rel_tol=1e-9) for pt in points
            ),
            "cost_at_thesis_values": thesis if label == "D-SSO" else None,
        }
        observers[label] = {**base, **best["params"]}
    observers["D-SSO (6.1)"] = dsso
    results = []
    for label, obs in observers.items():
        design = build_observer(system, obs)
        initial, final, support = no_attack(design, runs, steps, 7 + seed)
        results.append(
            {"scenario": NO_ATTACK, "observer": label, "mse_initial": initial}
            | {"mse": final, "support_error": support}
        )
    for name, sc in SCENARIOS.items():
        for label, obs in observers.items():
            design = build_observer(system, obs)
            res = simulate_scenario(
                design,
                {**sc, "name": name, "seed": sc["seed"] + seed},
                runs=runs,
                steps=steps,
                max_attacked=ATTACKED,
            )
            last = res.final()
            results.append(
                {
                    "scenario": name,
                    "observer": label,
                    "mse_initial": float(np.mean(res.mse[0])),
                    "mse": _number(last["mse_mean"]),
                    "support_error": _number(last["support_error_mean"]),
                    # the mean MSE every SERIES_EVERY steps (the figures' curves)
                    "mse_series": np.mean(res.mse[::SERIES_EVERY], axis=1).tolist(),
                }
            )
    return {
        "n": system.n,
        "p": system.p,
        "h": ATTACKED,
        "runs": runs,
        "steps": steps,
        "tuning": {
            "runs": tuning_runs,
            "steps": TUNING_STEPS,
            "seed": TUNING_SEED + seed,
            "alpha": ALPHA,
        },
        "tuned": tuned,
        "results": results,
    }


STEPS = 1200
SERIES_EVERY = 10


def _number(value: float | None) -> float:
    return math.nan if value is None else float(value)


UNSTATED = {
    "grids": "the same values for both observers: step, threshold (and shrink for the elastic "
    "net); the quick runs use a 3 x 3 (x 3) grid, the others an 8 x 6 (x 5) one",
    "tuning": f"the constant-attack scenario, {TUNING_STEPS} steps, alpha = {ALPHA}, our support "
    "error (Jaccard distance) standing for the MASE",
    "steps": f"{STEPS}",
    "sinusoidal attack": "period 100",
    "no attack": "a_hat(0) with 10% of its entries uniform in [-5, 5]",
}


@functools.lru_cache(maxsize=4)
def _measured(runs: int, quick: bool, seed: int) -> dict[str, Any]:
    return measure(runs, STEPS, QUICK_GRID if quick else FULL_GRID, seed)


def _scenario(settings: Settings, scenario: str) -> Result:
    runs = settings.count(10, 50)
    numbers = _measured(runs, settings.quick and settings.runs is None, settings.seed)
    rows = {r["observer"]: r for r in numbers["results"] if r["scenario"] == scenario}
    en = rows["elastic net"]
    return Result(
        paper={
            "the elastic net's state error converges close to zero": True,
            "the elastic net identifies the attack support": True,
        },
        ours={
            "the elastic net's state error converges close to zero": en["mse"]
            <= CLOSE_TO_ZERO * en["mse_initial"],
            "the elastic net identifies the attack support": en["support_error"]
            <= SUPPORT_IDENTIFIED,
        },
        unstated={**UNSTATED, "runs": f"{runs} (the thesis: 50)"},
        table=[
            {"tuned": numbers["tuned"]},
            *({k: v for k, v in r.items() if k != "mse_series"} for r in rows.values()),
        ],
        figure=figure(
            f"MSE of the state estimate against time ({scenario})",
            "step k",
            "mean MSE over runs",
            {
                name: (range(0, SERIES_EVERY * len(r["mse_series"]), SERIES_EVERY), r["mse_series"])
                for name, r in rows.items()
            },
            log=True,
        )
        if all("mse_series" in r for r in rows.values())
        else None,
        note="The thesis's words (Sec. 6.2.7) read as rules: 'close to zero', a final MSE at "
        f"most {CLOSE_TO_ZERO:g} of the initial one; 'identified', a final support error at "
        f"most {SUPPORT_IDENTIFIED:g}. The thesis does not say in words which observer is "
        "better; the table gives both." + _shrink_words(numbers["tuned"]["elastic net"]["best"]),
        why=_scenario_why(rows, numbers["tuned"]["elastic net"]["best"]),
    )


def _scenario_why(
    rows: dict[str, dict[str, Any]], tuned: dict[str, Any], dsso: str = "the tuned D-SSO"
) -> str:
    """Why the elastic net misses the thesis's words here, from the numbers."""
    en, other = rows["elastic net"], rows["D-SSO"]
    if en["mse"] <= CLOSE_TO_ZERO * en["mse_initial"] and en["support_error"] <= SUPPORT_IDENTIFIED:
        return ""
    words = (
        f"the elastic net ends at MSE {en['mse']:.2g} (from {en['mse_initial']:.2g}) and support "
        f"error {en['support_error']:.2g}; {dsso} at {other['mse']:.2g} and "
        f"{other['support_error']:.2g}."
    )
    return words + _shrink_words(tuned)


def _shrink_words(tuned: dict[str, Any]) -> str:
    """Why the tuned elastic net (its parameters ``tuned``) keeps an error under a persistent
    attack, when it does."""
    shrink = tuned.get("shrink", 1.0)
    if shrink >= 1:
        return ""
    return (
        f" The tuned elastic net's shrink q = {shrink:g} < 1 scales a persistent attack's "
        "estimate by q, which biases its state estimate while the attack lasts."
    )


@experiment(
    "thesis.fig6_1",
    where="Sec. 6.1, Fig. 6.1 (D-SSO, nu = 0.7, lambda = 0.1, marginally stable plant, "
    "constant attack, 50 runs)",
    measures="MASE and MSE of the D-SSO against time, and whether its hand-set pair suits "
    "some runs and not others",
)
def fig6_1(settings: Settings) -> Result:
    from ..examples import load_example
    from ..observers import build_observer
    from ..simulation.engine import simulate_scenario

    runs = settings.count(10, 50)
    system = load_example("random-n15-p30").system
    design = build_observer(system, {"kind": "dsso", "gain": "deadbeat", **THESIS_DSSO})
    scenario = {**BASE, "name": "constant", "seed": BASE["seed"] + settings.seed}
    res = simulate_scenario(design, scenario, runs=runs, steps=STEPS, max_attacked=ATTACKED)
    converged = res.mse[-1] <= CLOSE_TO_ZERO * res.mse[0]
    last = res.final()
    return Result(
        paper={
            "the pair suits some runs": True,
            "the pair does not suit every run": True,
        },
        ours={
            "the pair suits some runs": bool(np.any(converged)),
            "the pair does not suit every run": not bool(np.all(converged)),
        },
        unstated={
            "plant": "the packaged random-n15-p30 (A scaled so that its dominant eigenvalue is 1)",
            "attack": f"constant on {ATTACKED} sensors, magnitudes in [4, 5]",
            "steps": f"{STEPS}",
            "runs": f"{runs} (the thesis: 50)",
        },
        table=[
            {
                "runs whose MSE converges close to zero": int(np.sum(converged)),
                "runs": runs,
                "final MSE (mean)": _number(last["mse_mean"]),
                "final support error (mean)": _number(last["support_error_mean"]),
            }
        ],
        note="The thesis's Sec. 6.1.4: 'for some system scenarios the chosen parameter pair "
        "works quite well; however, there are cases in which the parameter pair is not "
        f"suitable'. 'Works', read as: the run's final MSE at most {CLOSE_TO_ZERO:g} of its "
        "initial one.",
        why=""
        if 0 < int(np.sum(converged)) < runs
        else f"{int(np.sum(converged))} of {runs} runs reach a final MSE within "
        f"{CLOSE_TO_ZERO:g} of their initial one (mean final MSE "
        f"{_number(last['mse_mean']):.2g}): by that rule the pair suits "
        + ("every run" if bool(np.all(converged)) else "none")
        + " here.",
    )


for _n, _scenario_name, _case in (
    (2, NO_ATTACK, "no attack (the attack estimate started at a random value)"),
    (3, "constant", "a constant attack"),
    (4, "switching (every 400)", "an attack whose support changes every 400 steps"),
    (5, "sinusoidal", "a sinusoidal attack"),
):
    experiment(
        f"thesis.fig6_{_n}",
        where=f"Sec. 6.2, Fig. 6.{_n} ({_case})",
        measures=f"MASE and MSE of the D-SSO and the elastic-net observer under {_case}",
    )(functools.partial(_scenario, scenario=_scenario_name))


#: Sec. 6.3's decoders: A, Algorithm 3 as printed (raw G, ISTA, N = 1000, q_x = q_a = 0.999);
#: B, the same on G with unit-norm columns; C, ssecert's default (unit columns, unknown common
#: offset, FISTA to convergence, q = 1); D, C with q_x = q_a = 0.999
#: Success rates within this many percentage points are a tie (sampling noise).
RATE_ATOL = 5.0
RATE_TIE = f"within {RATE_ATOL:g} percentage points"
#: Fig. 6.6 shows a success; it is "typical" of a decoder that succeeds in at least this %.
TYPICAL = 50.0
DECODERS = {
    "A": dict(
        normalize=False, common_offset=False, method="ista", N=1000, rtol=0.0, q_x=0.999, q_a=0.999
    ),
    "B": dict(
        normalize=True, common_offset=False, method="ista", N=1000, rtol=0.0, q_x=0.999, q_a=0.999
    ),
    "C": dict(),
    "D": dict(q_x=0.999, q_a=0.999),
}


def evaluate(
    attacked: int,
    *,
    runs: int,
    dictionaries: int,
    xi_std: float,
    seed: int,
    sign: float | None = None,
) -> dict[str, dict[str, Any]]:
    """Success counts of every decoder of Sec. 6.3's set-up for ``attacked`` attacked sensors
    (``sign``: the attacks' sign forced, else random), over ``runs`` runs on ``dictionaries``
    random deployments."""
    from ..estimators.localization import (
        elastic_net_localization,
        localization_scenario,
        rss_dictionary,
    )

    per = [runs // dictionaries + (i < runs % dictionaries) for i in range(dictionaries)]
    stats: dict[str, dict[str, Any]] = {
        name: {"cell": 0, "set": 0, "both": 0, "dist": [], "conv": 0, "sec": 0.0, "its": []}
        for name in (*DECODERS, "kNN")
    }
    for i, count in enumerate(per):
        if count == 0:
            continue
        dic = rss_dictionary(seed=seed + i)
        sc = localization_scenario(
            dic, runs=count, attacked=attacked, xi_std=xi_std, seed=10_000 + seed + i
        )
        y = sc.y if sign is None else dic.D[:, sc.cell].T + sign * np.abs(sc.attack) + sc.noise
        for name, options in DECODERS.items():
            t0 = time.perf_counter()
            res = elastic_net_localization(dic.D, y, **options)  # type: ignore[arg-type]
            st = stats[name]
            st["sec"] += time.perf_counter() - t0
            cell_ok = res.cell == sc.cell
            set_ok = np.all(res.attacked == sc.attacked, axis=1)
            st["cell"] += int(cell_ok.sum())
            st["set"] += int(set_ok.sum())
            st["both"] += int((cell_ok & set_ok).sum())
            st["conv"] += int(res.converged.sum())
            st["its"].extend(int(i) for i in np.atleast_1d(res.iterations))
            st["dist"].extend(
                np.linalg.norm(dic.cell_centers[res.cell] - dic.cell_centers[sc.cell], axis=1)
            )
        knn = np.argmin(((dic.D.T[None, :, :] - y[:, None, :]) ** 2).sum(axis=2), axis=1)
        stats["kNN"]["cell"] += int((knn == sc.cell).sum())
        stats["kNN"]["dist"].extend(
            np.linalg.norm(dic.cell_centers[knn] - dic.cell_centers[sc.cell], axis=1)
        )
    return stats


@experiment(
    "thesis.fig6_6",
    where="Sec. 6.3, Fig. 6.6 (RSS localization, 100 cells, 20 sensors, 5 attacked)",
    measures="whether Algorithm 3 finds the target's cell and the 5 attacked sensors, over "
    "many random deployments",
)
def fig6_6(settings: Settings) -> Result:
    runs = settings.count(20, 100)
    dictionaries = min(runs, 4 if settings.quick and settings.runs is None else 10)
    stats = evaluate(5, runs=runs, dictionaries=dictionaries, xi_std=0.0, seed=settings.seed)
    rate = {name: 100 * v["both"] / runs for name, v in stats.items() if name != "kNN"}
    cells = {name: 100 * v["cell"] / runs for name, v in stats.items()}
    return Result(
        paper={"Algorithm 3 finds the cell and the 5 attacked sensors": True},
        ours={"Algorithm 3 finds the cell and the 5 attacked sensors": rate["A"] >= TYPICAL},
        unstated={
            "path loss": "P_t = 25 dBm, P_l = 40.2 dB, alpha = 3, d0 = 1 m",
            "sensors": "uniform in the 10 m x 10 m room, a new deployment for each group of runs",
            "attacks": "magnitudes uniform in [10, 20] dB with random signs; no noise",
            "Algorithm 3": "q_x = q_a = 0.999 (the thesis needs q in (0, 1)), lambda = 0.05 "
            "epsilon L2, epsilon = 0.99 / ||G||^2, N = 1000",
            "runs": f"{runs} on {dictionaries} deployments (the thesis shows one snapshot)",
        },
        table=[
            {
                "decoder": name,
                "cell and attacked set right (%)": rate.get(name),
                "cell right (%)": cells[name],
            }
            for name in stats
        ],
        note="The thesis shows one successful snapshot and gives none of the set-up's "
        f"numbers; its outcome is read as typical of Algorithm 3 when at least {TYPICAL:g}% of "
        "the runs find both the cell and the attacked set. Decoder C is ssecert's default "
        "(unit columns, an unknown common offset, FISTA to convergence), B and D variants, kNN "
        "the thesis's fingerprint baseline (cell only).",
        why=""
        if rate["A"] >= TYPICAL
        else f"Algorithm 3 as printed finds both in {rate['A']:.0f}% of the runs (its raw "
        f"dictionary is badly conditioned), ssecert's decoder C in {rate['C']:.0f}%.",
    )


def ugv_comparison(runs: int, quick: bool, seed: int) -> dict[str, Any]:
    """Sec. 6.4 on the packaged ugv example: the D-SSO of its spec (the thesis's Sec. 6.1
    values) and the elastic-net observer tuned on the spec's constant attack on sensor 2
    (velocity-a) with cost (6.1), both simulated on that scenario: initial and final MSE and
    final support error."""
    from ..examples import load_example
    from ..observers import build_observer
    from ..simulation.engine import grid_search, simulate_scenario

    spec = load_example("ugv")
    scenario = next(sc for sc in spec.scenarios if sc["name"] == "constant-velocity-a")
    scenario = {**scenario, "seed": scenario["seed"] + seed}
    grid = QUICK_GRID if quick else FULL_GRID
    en = {"kind": "elastic_net", "gain": "deadbeat", "step": 0.3, "threshold": 0.1, "shrink": 0.95}
    found = grid_search(
        spec.system,
        en,
        {**scenario, "name": "tuning", "seed": TUNING_SEED + seed},
        grid,
        runs=max(10, runs // 5),
        steps=TUNING_STEPS,
        alpha=ALPHA,
        max_attacked=spec.max_attacked,
    )
    finite = [pt for pt in found.points if math.isfinite(pt["cost"])]
    best = min(finite, key=lambda pt: pt["cost"])["params"] if finite else found.best["params"]
    rows, sweep = {}, []
    for label, section in (("D-SSO", dict(spec.observer or {})), ("elastic net", {**en, **best})):
        design = build_observer(spec.system, section)
        res = simulate_scenario(
            design, scenario, runs=runs, steps=STEPS, max_attacked=spec.max_attacked
        )
        last = res.final()
        rows[label] = {
            "mse_initial": float(np.mean(res.mse[0])),
            "mse": _number(last["mse_mean"]),
            "support_error": _number(last["support_error_mean"]),
        }
        # the attack's magnitude, which the thesis does not give, swept
        for magnitude in UGV_MAGNITUDES:
            other = simulate_scenario(
                design,
                {**scenario, "magnitude": magnitude},
                runs=runs,
                steps=STEPS,
                max_attacked=spec.max_attacked,
            ).final()
            sweep.append(
                {
                    "observer": label,
                    "magnitude": list(magnitude),
                    "mse": _number(other["mse_mean"]),
                    "support_error": _number(other["support_error_mean"]),
                }
            )
    return {"tuned": best, "rows": rows, "sweep": sweep}


#: the UGV attack's magnitudes swept beside the example's [4, 5]
UGV_MAGNITUDES = ((0.5, 1.0), (1.0, 2.0), (8.0, 10.0))


@experiment(
    "thesis.fig6_7",
    where="Sec. 6.4, Fig. 6.7 (the UGV, a constant attack on the second sensor)",
    measures="MASE and MSE of the D-SSO and the elastic-net observer on the UGV",
)
def fig6_7(settings: Settings) -> Result:
    runs = settings.count(10, 50)
    quick = settings.quick and settings.runs is None
    out = ugv_comparison(runs, quick, settings.seed)
    en = out["rows"]["elastic net"]
    return Result(
        paper={
            "the elastic net's support error is zero": True,
            "the elastic net's state error converges close to zero": True,
        },
        ours={
            "the elastic net's support error is zero": en["support_error"] == 0,
            "the elastic net's state error converges close to zero": en["mse"]
            <= CLOSE_TO_ZERO * en["mse_initial"],
        },
        unstated={
            "attack": "the ugv example's constant-velocity-a scenario: sensor 2 (velocity-a), "
            "magnitudes in [4, 5], 300 steps (the thesis gives no magnitude; [0.5, 1], [1, 2] "
            "and [8, 10] are swept in the table)",
            "elastic net": f"tuned like Figs. 6.2-6.5 on that scenario: {_params_words(out)}",
            "D-SSO": "the example's spec: deadbeat gain, nu = 0.7, lambda = 0.1 (Sec. 6.1)",
            "runs": f"{runs} (the thesis: 50)",
        },
        table=[
            {"tuned": out["tuned"]},
            *({"observer": k, **v} for k, v in out["rows"].items()),
            *out["sweep"],
        ],
        note=f"'Close to zero' read as a final MSE at most {CLOSE_TO_ZERO:g} of the initial "
        "one, as for Figs. 6.2-6.5. The UGV is not 2-sparse observable (an attack on the "
        "position sensor cannot be told from another position), but an attack on a velocity "
        "sensor can be: the position sensor and the dynamics expose it."
        + _shrink_words(out["tuned"]),
        why=_scenario_why(
            {"elastic net": en, "D-SSO": out["rows"]["D-SSO"]}, out["tuned"], "the example's D-SSO"
        ),
    )


def _params_words(out: dict[str, Any]) -> str:
    return ", ".join(f"{k} {v:g}" for k, v in out["tuned"].items())
