"""The thesis's comparison of the D-SSO and the elastic-net observer (Sec. 6.1-6.2).

Plant: the packaged random-n15-p30 example (n = 15, p = 30, A and C Gaussian,
A scaled so that its dominant eigenvalue is 1), h = 3 attacked sensors with
magnitudes in [4, 5].  Observers: the D-SSO with deadbeat gain, step 0.7 and
threshold 0.1 (the thesis's values), and the elastic-net observer (Algorithm 2)
with the same deadbeat gain, L2 = I, and step, threshold and shrink chosen by
grid search on the constant-attack scenario with the thesis's cost (6.1)
(alpha = 0.5, our support error standing for its MASE), as the thesis tunes
lambda and L2 by a search.  Scenarios of Sec. 6.2: no attack (attack estimate
started at a random value), constant attack, support changing every 400 steps,
sinusoidal attack.  Reported: final MSE and support error, mean over runs.

    python benchmarks/exp_thesis_observers.py [--runs 50] [--steps 1200]
"""

from __future__ import annotations

import argparse

import numpy as np

from ssecert.examples import load_example
from ssecert.observers import build_observer, observer_from_design
from ssecert.simulation.engine import grid_search, simulate_scenario
from ssecert.simulation.metrics import mse
from ssecert.simulation.scenarios import generate


def no_attack(design, runs: int, steps: int, seed: int) -> tuple[float, float]:
    """No attack, a_hat(0) random (the thesis's set-up): final MSE and support error."""
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
    final_mse = float(np.mean(mse(traj.x_hat[-1], xs[-1])))
    support = float(np.mean(np.any(np.abs(traj.a_hat[-1]) > 1e-9, axis=1)))  # any false alarm
    return final_mse, support


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=50)
    parser.add_argument("--steps", type=int, default=1200)
    args = parser.parse_args()
    spec = load_example("random-n15-p30")
    system = spec.system
    base = {"attack": "constant", "count": 3, "magnitude": (4.0, 5.0), "noise": 0.0, "seed": 0}
    dsso = {"kind": "dsso", "gain": "deadbeat", "step": 0.7, "threshold": 0.1, "shrink": 1.0}
    en = {"kind": "elastic_net", "gain": "deadbeat", "step": 0.3, "threshold": 0.1, "shrink": 0.95}
    grid = grid_search(
        system,
        en,
        {**base, "name": "tuning"},
        {"step": [0.1, 0.3, 0.7], "threshold": [0.05, 0.1, 0.2], "shrink": [0.9, 0.95, 0.99]},
        runs=max(10, args.runs // 5),
        steps=400,
        seed=1,
    )
    en = {**en, **grid.best["params"]}
    print(
        f"elastic-net parameters from the grid search: {grid.best['params']} "
        f"(cost {grid.best['cost']:.3g})"
    )
    scenarios = {
        "constant": base,
        "switching (every 400)": {**base, "attack": "switching", "period": 400},
        "sinusoidal": {**base, "attack": "sinusoidal", "period": 100},
    }
    print(f"n = {system.n}, p = {system.p}, h = 3, {args.runs} runs x {args.steps} steps")
    print(f"{'scenario':<24} {'observer':<12} {'final MSE':>12} {'support error':>14}")
    for label, obs in (("D-SSO", dsso), ("elastic net", en)):
        design = build_observer(system, obs)
        m, sup = no_attack(design, args.runs, args.steps, 7)
        print(f"{'no attack (a_hat(0) rnd)':<24} {label:<12} {m:12.3e} {sup:14.3f}")
    results: dict[str, dict[str, dict]] = {}
    for name, sc in scenarios.items():
        for label, obs in (("D-SSO", dsso), ("elastic net", en)):
            design = build_observer(system, obs)
            res = simulate_scenario(
                design, {**sc, "name": name}, runs=args.runs, steps=args.steps, max_attacked=3
            )
            f = res.final()
            results.setdefault(name, {})[label] = f
            print(f"{name:<24} {label:<12} {f['mse_mean']:12.3e} {f['support_error_mean']:14.3f}")
    print()
    for name, pair in results.items():
        d, e = pair["D-SSO"], pair["elastic net"]
        better_mse = "elastic net" if e["mse_mean"] < d["mse_mean"] else "D-SSO"
        better_sup = "elastic net" if e["support_error_mean"] < d["support_error_mean"] else "D-SSO"
        print(f"{name}: lower MSE: {better_mse}; lower support error: {better_sup}")
    print()
    print(
        "What the thesis shows (Figs. 6.1-6.5, plots only): for the D-SSO the MSE falls to small "
        "values and the MASE settles (Fig. 6.1); in the four scenarios the new (elastic-net) "
        "observer reaches an MSE 'close to zero' and 'consistently identifies' the support, "
        "compared against a grid-searched D-SSO. The 'support error' column is our Jaccard "
        "distance (the thesis does not define MASE precisely), and for 'no attack' it is the "
        "fraction of runs whose attack estimate is not exactly zero at the end. Both observers "
        "converge here too; the thesis's claim that the new observer outperforms the D-SSO is "
        "not borne out uniformly: see the per-scenario comparison above (shrink < 1 biases the "
        "estimate of a persistent attack by the factor shrink). The figures' values cannot be "
        "read from the text, so the comparison with them is qualitative."
    )


if __name__ == "__main__":
    main()
