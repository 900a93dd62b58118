"""The experiment of Sec. 5.1 (Fig. 1) of the Lasso paper, with ssecert's static decoders.

Random plants with n = 20 states and p sensors (p = 20, 30, 40, 60, 80 by
default), s = p / 5 attacked sensors: A and C with standard Gaussian
entries, A scaled to spectral radius 1 / 1.01; horizon tau = n, so the
decoders see y = O_tau x(0) + a + eta with O_tau the stacked observability
matrix (20 p rows).  The attacked sensors are drawn uniformly and attacked at
every step with magnitudes in [4, 5] and random signs; x(0) has entries of
magnitude in [2, 3] with random signs.  Noise-free, and with eta uniform in
[-1e-4, 1e-4].

Decoders:

* Lasso: the partial Lasso (problem (4)) with ``--lam``, solved by FISTA
  with adaptive restart in orthonormal coordinates (the same minimiser as
  plain Beck-Teboulle FISTA, about 100 times fewer iterations here;
  ``--plain-fista`` runs the plain one);
* l1: the l1 decoder argmin ||y - O x||_1 (HiGHS);
* l0: the exact l0 decoder over sensor supports (the answer Imhotep-SMT
  gives; an exhaustive search here, so only where sum_{k <= s} C(p, k) is
  at most ``--l0-max-supports``, '-' elsewhere).

Printed: the mean relative state error ||x_hat - x(0)|| / ||x(0)|| and the
mean run time per decoder and p, then a paragraph comparing with Fig. 1.

    python benchmarks/exp_lasso_sec51.py [--runs 20] [--ps 20,30,40,60,80] [--lam 0.01]
"""

from __future__ import annotations

import os

# one BLAS thread unless asked otherwise (small products; steadier timings)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse
import math
import time

import numpy as np

from ssecert import System
from ssecert.estimators.decoders import fista
from ssecert.estimators.support_decoders import l0_decoder, l1_decoder

N_STATES = 20
NOISE_BOUND = 1e-4
METHODS = ("Lasso", "l1", "l0")


def random_run(rng: np.random.Generator, p: int, noise: float):
    """(O_tau, sensor of each row, y, x(0)) for one random plant, attack and noise."""
    n, tau, s = N_STATES, N_STATES, p // 5
    A = rng.standard_normal((n, n))
    A /= 1.01 * np.abs(np.linalg.eigvals(A)).max()
    system = System(A, rng.standard_normal((p, n)))
    O = system.observability_matrix(tau)
    x0 = rng.uniform(2.0, 3.0, n) * rng.choice([-1.0, 1.0], n)
    attacked = rng.choice(p, s, replace=False)
    a = np.zeros((tau, p))
    a[:, attacked] = rng.uniform(4.0, 5.0, (tau, s)) * rng.choice([-1.0, 1.0], (tau, s))
    eta = noise * rng.uniform(-1.0, 1.0, tau * p)
    return O, np.tile(np.arange(p), tau), O @ x0 + a.ravel() + eta, x0


def l0_supports(p: int) -> int:
    return sum(math.comb(p, k) for k in range(p // 5 + 1))


def run_decoders(O, sensors, y, x0, p, args) -> tuple[dict[str, tuple[float, float]], bool]:
    """Relative state error and seconds of each decoder on one run; whether FISTA converged."""
    out = {}
    t0 = time.perf_counter()
    if args.plain_fista:
        sol = fista(O, y, args.lam, iterations=args.iterations)
    else:
        sol = fista(O, y, args.lam, iterations=args.iterations, restart=True, orthonormalize=True)
    out["Lasso"] = (time.perf_counter() - t0, sol.x)
    t0 = time.perf_counter()
    x_l1 = l1_decoder(O, y)
    out["l1"] = (time.perf_counter() - t0, x_l1)
    if l0_supports(p) <= args.l0_max_supports:
        t0 = time.perf_counter()
        sol0 = l0_decoder(O, y, p // 5, sensors_of_row=sensors, max_supports=args.l0_max_supports)
        out["l0"] = (time.perf_counter() - t0, sol0.x)
    norm = np.linalg.norm(x0)
    errors = {k: (float(np.linalg.norm(x - x0) / norm), t) for k, (t, x) in out.items()}
    return errors, bool(sol.converged)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20, help="random runs per p (paper: 50)")
    parser.add_argument("--ps", default="20,30,40,60,80", help="comma-separated sensor counts")
    parser.add_argument("--lam", type=float, default=1e-2, help="Lasso weight lambda")
    parser.add_argument("--iterations", type=int, default=20_000, help="FISTA budget")
    parser.add_argument(
        "--plain-fista",
        action="store_true",
        help="plain Beck-Teboulle FISTA (slower, same minimiser)",
    )
    parser.add_argument(
        "--l0-max-supports",
        type=int,
        default=100_000,
        help="largest l0 search run (p = 30 needs 768,212)",
    )
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    ps = [int(v) for v in args.ps.split(",")]

    # errors[noise][p][method] = list of (error, seconds)
    results: dict[str, dict[int, dict[str, list[tuple[float, float]]]]] = {}
    unconverged = 0
    started = time.perf_counter()
    for label, noise in (("noise-free", 0.0), (f"noise {NOISE_BOUND:g}", NOISE_BOUND)):
        results[label] = {}
        for p in ps:
            # the same plants and attacks with and without noise
            rng = np.random.default_rng([args.seed, p])
            per = {m: [] for m in METHODS}
            for _ in range(args.runs):
                O, sensors, y, x0 = random_run(rng, p, noise)
                errors, converged = run_decoders(O, sensors, y, x0, p, args)
                unconverged += not converged
                for method, (err, seconds) in errors.items():
                    per[method].append((err, seconds))
            results[label][p] = per
    total = time.perf_counter() - started

    variant = "plain FISTA" if args.plain_fista else "FISTA, restart, orthonormal coordinates"
    print(
        f"Sec. 5.1 experiment: n = {N_STATES}, tau = n, s = p/5, {args.runs} runs per p, "
        f"Lasso lambda = {args.lam:g} ({variant}; {unconverged} runs hit the "
        f"{args.iterations} iteration budget); {total:.0f} s in all"
    )
    print("mean relative state error ||x_hat - x|| / ||x||  and  mean run time [ms]")
    for label, by_p in results.items():
        print(f"\n{label}")
        head = f"{'p':>4} {'s':>3}" + "".join(f" | {m + ' err':>10} {'ms':>8}" for m in METHODS)
        print(head)
        print("-" * len(head))
        for p, per in by_p.items():
            line = f"{p:4d} {p // 5:3d}"
            for method in METHODS:
                if per[method]:
                    errs, secs = zip(*per[method])
                    line += f" | {np.mean(errs):10.2e} {np.mean(secs) * 1e3:8.2f}"
                else:
                    line += f" | {'-':>10} {'-':>8}"
            print(line)
    print()
    print(verdict(results))


def mean_error(results, label, p, method) -> float:
    runs = results[label][p][method]
    return float(np.mean([e for e, _ in runs])) if runs else math.nan


def verdict(results) -> str:
    """What Fig. 1 shows, and whether the numbers above agree."""
    free, noisy = list(results)
    ps = list(results[free])
    lasso_free = [mean_error(results, free, p, "Lasso") for p in ps]
    lasso_noisy = [mean_error(results, noisy, p, "Lasso") for p in ps]
    l0_ps = [p for p in ps if results[free][p]["l0"]]
    l0_free = [mean_error(results, free, p, "l0") for p in l0_ps]
    l0_noisy = [mean_error(results, noisy, p, "l0") for p in l0_ps]
    l1_free = [mean_error(results, free, p, "l1") for p in ps]
    l1_noisy = [mean_error(results, noisy, p, "l1") for p in ps]
    lasso_robust = all(b <= 1.5 * a + 1e-6 for a, b in zip(lasso_free, lasso_noisy))
    l0_exact = bool(l0_free) and max(l0_free) < 1e-9
    l0_degrades = bool(l0_noisy) and min(l0_noisy) > 10 * max(lasso_noisy)
    lines = [
        "Fig. 1 of the paper (n = 20, s = p/5, 50 runs): Lasso solved by FISTA is more accurate "
        "and faster than ETPG; Imhotep-SMT (the l0 decoder) gives the exact state quickly when "
        "there is no noise, but its accuracy suffers under noise of bound 1e-4, while Lasso and "
        "ETPG degrade only slightly.",
        " Here (ETPG is not implemented, so Lasso vs ETPG cannot be checked): ",
    ]
    lines.append(
        f"Lasso's mean error ranges {min(lasso_free):.1e}-{max(lasso_free):.1e} noise-free and "
        f"{min(lasso_noisy):.1e}-{max(lasso_noisy):.1e} with noise, "
        + (
            "so it is robust to small noise, as in the paper"
            if lasso_robust
            else "so, unlike the paper, noise degrades it noticeably"
        )
        + "; its error is the lambda bias of the partial Lasso (it scales with lambda). "
    )
    if l0_ps:
        lines.append(
            f"The l0 decoder is exact noise-free (mean error {max(l0_free):.1e} at p = "
            f"{', '.join(map(str, l0_ps))}) "
            + ("as in the paper" if l0_exact else "- unlike the paper, not exact")
            + f"; with noise its mean error is {max(l0_noisy):.1e}, "
            + (
                "worse than Lasso, as in the paper."
                if l0_degrades
                else "no worse than Lasso: this disagrees with the paper's Imhotep-SMT. Our l0 "
                "decoder falls back to the support of s sensors with the least residual when no "
                "support explains y exactly, which is robust; Imhotep-SMT's sensitivity "
                "presumably comes from how it accepts a support by a residual tolerance (not "
                "checked here), not from the l0 formulation itself."
            )
            + " Its exhaustive search is tractable only for the smallest p (Imhotep-SMT prunes "
            "with a SAT solver), so its times are not comparable beyond that. "
        )
    lines.append(
        f"The l1 decoder (not in Fig. 1) has mean error {min(l1_free):.1e}-{max(l1_free):.1e} "
        f"noise-free and {min(l1_noisy):.1e}-{max(l1_noisy):.1e} with noise: with a "
        "time-invariant attack on s = p/5 sensors and tau = n it recovers x, and it has no "
        "lambda bias."
    )
    text = "".join(lines)
    # wrap to 100 columns
    words, out, line = text.split(), [], ""
    for word in words:
        if len(line) + len(word) + 1 > 100:
            out.append(line)
            line = word
        else:
            line = f"{line} {word}" if line else word
    out.append(line)
    return "\n".join(out)


if __name__ == "__main__":
    main()
