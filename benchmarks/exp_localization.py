"""The localization example of the thesis (Cilia, Sec. 6.3, Fig. 6.6), over many runs.

Set-up of Sec. 6.3: a grid of n = 100 cells (10 x 10 cells of 1 m) and
q = 20 sensors, some of them attacked; one target, one RSS snapshot
y = D x + a (+ xi), decoded by the elastic net of Algorithm 3 on G = [D I].
The thesis gives no path-loss parameters, sensor positions, attack values,
algorithm parameters or success rates; we take P_t = 25 dBm,
P_l = 40.2 dB, alpha = 3, d0 = 1 m, sensors uniform in the room, attacks
of magnitude uniform in [10, 20] dB with random signs, noise-free unless
``--xi-std`` is given.  Each of ``--dictionaries`` random deployments serves
runs / dictionaries runs.

Decoders (cell% / attacked-set%, the latter counting only exact sets):

* A, Algorithm 3 as printed: raw G, ISTA, N = 1000, q_x = q_a = 0.999
  (the thesis needs q in (0, 1) and gives no value; A and B fail alike
  with q = 1 or 0.99);
* B, the same on G with unit-norm columns;
* C, ssecert's default: unit columns, unknown common offset, FISTA until
  the relative step is below 1e-9 (N <= 20000), q = 1 (Lasso);
* D, C with q_x = q_a = 0.999 (a proper elastic net);
* k-NN, the thesis's baseline argmin_j ||D_j - y|| (cell only, no attack model).

Thresholds lambda = 0.05 epsilon L2 everywhere (objective weight 0.05),
epsilon = 0.99 / ||G||^2, L2 = 1.  A second table follows Algorithm 3's own
iteration (ISTA, with C's preprocessing) on a few snapshots: its distance to
the minimiser after N iterations.

    python benchmarks/exp_localization.py [--runs 100] [--dictionaries 10] [--xi-std 0]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse
import textwrap
import time

import numpy as np

from ssecert.estimators.localization import (
    elastic_net_localization,
    localization_scenario,
    rss_dictionary,
)

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


def evaluate(attacked, *, runs, dictionaries, xi_std, seed, sign=None):
    """Success counts of every decoder for `attacked` attacked sensors."""
    per = [runs // dictionaries + (i < runs % dictionaries) for i in range(dictionaries)]
    stats = {
        name: {"cell": 0, "set": 0, "both": 0, "dist": [], "conv": 0, "sec": 0.0}
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
            res = elastic_net_localization(dic.D, y, **options)
            st = stats[name]
            st["sec"] += time.perf_counter() - t0
            cell_ok = res.cell == sc.cell
            set_ok = np.all(res.attacked == sc.attacked, axis=1)
            st["cell"] += int(cell_ok.sum())
            st["set"] += int(set_ok.sum())
            st["both"] += int((cell_ok & set_ok).sum())
            st["conv"] += int(res.converged.sum())
            st["dist"].extend(
                np.linalg.norm(dic.cell_centers[res.cell] - dic.cell_centers[sc.cell], axis=1)
            )
        knn = np.argmin(((dic.D.T[None, :, :] - y[:, None, :]) ** 2).sum(axis=2), axis=1)
        stats["kNN"]["cell"] += int((knn == sc.cell).sum())
        stats["kNN"]["dist"].extend(
            np.linalg.norm(dic.cell_centers[knn] - dic.cell_centers[sc.cell], axis=1)
        )
    return stats


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100, help="snapshots per row (100)")
    parser.add_argument(
        "--dictionaries", type=int, default=10, help="random sensor deployments (10)"
    )
    parser.add_argument(
        "--attacked", default="0,1,2,3,5,8", help="numbers of attacked sensors (0,1,2,3,5,8)"
    )
    parser.add_argument("--xi-std", type=float, default=0.0, help="RSS noise std in dB (0)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    if not 1 <= args.dictionaries <= args.runs:
        parser.error("--dictionaries must be between 1 and --runs")
    counts = [int(v) for v in args.attacked.split(",")]

    print(
        f"Localization, 10 x 10 cells of 1 m, q = 20 sensors (uniform), {args.runs} runs "
        f"on {args.dictionaries} deployments per row, xi std {args.xi_std} dB"
    )
    print("entries: cell found % / attacked set exactly found %   (k-NN: cell % only)")
    head = (
        f"{'attacked':>8}  {'A printed':>11} {'B unit cols':>11} {'C default':>11} "
        f"{'D q=0.999':>11} {'k-NN':>6}   {'C both':>6} {'C err m':>7} {'C conv':>6}"
    )
    print(head)
    print("-" * len(head))
    table = {}
    t0 = time.perf_counter()
    for s in counts:
        st = evaluate(
            s, runs=args.runs, dictionaries=args.dictionaries, xi_std=args.xi_std, seed=args.seed
        )
        table[s] = st
        R = args.runs
        cells = "".join(
            f" {100 * st[k]['cell'] / R:>5.0f}/{100 * st[k]['set'] / R:<5.0f}" for k in DECODERS
        )
        print(
            f"{s:>8} {cells} {100 * st['kNN']['cell'] / R:>6.0f}   "
            f"{100 * st['C']['both'] / R:>6.0f} {np.mean(st['C']['dist']):>7.2f} "
            f"{100 * st['C']['conv'] / R:>5.0f}%"
        )
    print(
        f"(C both: cell and attacked set right; C err m: mean distance between estimated and "
        f"true cell centres; C conv: runs converged; {time.perf_counter() - t0:.1f} s)"
    )
    print()
    sign_rows = {}
    sign_counts = [s for s in (1, 5) if s in counts] or counts[:1]
    print("decoder C by attack sign (attacker raises or lowers the readings)")
    print(f"{'attacked':>8} {'raised: both %':>15} {'lowered: both %':>16}")
    for s in sign_counts:
        up = evaluate(
            s,
            runs=args.runs,
            dictionaries=args.dictionaries,
            xi_std=args.xi_std,
            seed=args.seed,
            sign=1.0,
        )["C"]["both"]
        down = evaluate(
            s,
            runs=args.runs,
            dictionaries=args.dictionaries,
            xi_std=args.xi_std,
            seed=args.seed,
            sign=-1.0,
        )["C"]["both"]
        sign_rows[s] = (100 * up / args.runs, 100 * down / args.runs)
        print(f"{s:>8} {sign_rows[s][0]:>15.0f} {sign_rows[s][1]:>16.0f}")
    print()
    conv = ista_convergence(seed=args.seed)
    print(
        "Algorithm 3's iteration (ISTA, unit columns, common offset) on 10 snapshots with 5 "
        "attacked sensors: distance to the minimiser (FISTA, checked against cvxpy in the tests)"
    )
    print(f"{'N':>8} {'max |z - z*| / |z*|':>20} {'same cell':>10} {'same attacked set':>18}")
    for N, dist, cell, att in conv:
        print(f"{N:>8} {dist:>20.2e} {cell:>9.0%} {att:>18.0%}")
    print()
    print(paragraph(table, sign_rows, args.runs, conv))


def ista_convergence(*, seed, Ns=(1000, 10_000, 100_000)):
    """Relative distance of N ISTA iterations to the converged solution, 10 snapshots."""
    dic = rss_dictionary(seed=seed)
    sc = localization_scenario(dic, runs=10, attacked=5, seed=seed + 1)
    ref = elastic_net_localization(dic.D, sc.y, rtol=1e-12, N=100_000)
    zref = np.hstack([ref.x_hat, ref.a_hat])
    rows = []
    for N in Ns:
        res = elastic_net_localization(dic.D, sc.y, method="ista", N=N, rtol=0.0)
        z = np.hstack([res.x_hat, res.a_hat])
        dist = np.max(np.abs(z - zref).max(axis=1) / np.abs(zref).max(axis=1))
        rows.append(
            (
                N,
                dist,
                np.mean(res.cell == ref.cell),
                np.mean(np.all(res.attacked == ref.attacked, axis=1)),
            )
        )
    return rows


def paragraph(table, sign_rows, runs, conv) -> str:
    pct = lambda s, k, f: 100 * table[s][k][f] / runs  # noqa: E731
    five = 5 if 5 in table else max(table)
    small = [s for s in table if 1 <= s <= 2]
    text = [
        "What the thesis reports: one example (Fig. 6.6) with 100 cells and 20 sensors, five of "
        "them attacked, where Algorithm 3 (N = 1000 iterations) finds both the target's cell and "
        "the attacked sensors. It gives no success rate, no path-loss or algorithm parameters "
        "(lambda, q, L2, epsilon), and loads D and y from a file. ",
        f"Over {runs} random instances with {five} attacked sensors, the printed algorithm "
        f"(A) finds the cell in {pct(five, 'A', 'cell'):.0f}% and the exact attacked set in "
        f"{pct(five, 'A', 'set'):.0f}%: on a path-loss dictionary every fingerprint is close to "
        "the constant P_t - P_l, G = [D I] is very ill-conditioned, and 1000 gradient steps "
        "leave the estimate far from the minimiser (unit columns, B, do not cure it: "
        f"{pct(five, 'B', 'cell'):.0f}% / {pct(five, 'B', 'set'):.0f}%). ",
        f"With an unknown common offset and FISTA run to convergence (C), the cell is found in "
        f"{pct(five, 'C', 'cell'):.0f}% and the attacked set in {pct(five, 'C', 'set'):.0f}% of "
        f"the runs with {five} attacked sensors, ",
    ]
    if small:
        text.append(
            "and in "
            + ", ".join(
                f"{pct(s, 'C', 'cell'):.0f}% / {pct(s, 'C', 'set'):.0f}% with {s}" for s in small
            )
            + ". "
        )
    else:
        text.append(". ")
    lo, hi = min(pct(s, "C", "conv") for s in table), max(pct(s, "C", "conv") for s in table)
    text.append(
        f"C converges in {f'{lo:.0f}' if lo == hi else f'{lo:.0f}-{hi:.0f}'}% of the runs, "
        "so its failures are "
        "failures of the l1 relaxation itself (tests/test_localization.py checks the fixed point "
        "against cvxpy): neighbouring cells have almost collinear fingerprints (log-distance "
        "fields are harmonic away from the sensors), so a mixture of cells plus small attacks "
        "on many sensors can cost less than the true one-hot cell plus the real attack. "
    )
    if sign_rows:
        s0 = min(sign_rows)
        text.append(
            f"Attacks that lower the readings are the hard ones (with {s0} attacked "
            f"sensor{'s' if s0 > 1 else ''}: "
            f"{sign_rows[s0][0]:.0f}% right when the attacker raises them, "
            f"{sign_rows[s0][1]:.0f}% when it lowers them), plausibly because a lowered reading "
            "looks like a target farther away, which mixtures of other cells can explain. "
        )
    last = conv[-1]
    text.append(
        f"Algorithm 3's plain iteration converges to the same minimiser (ISTA is guaranteed to), "
        f"but slowly: after "
        f"{last[0]:,} iterations its distance to it is still {last[1]:.1e} (relative), with the "
        f"same cell in {last[2]:.0%} and the same attacked set in {last[3]:.0%} of the "
        "snapshots; FISTA with restart needs a few thousand. "
    )
    text.append(
        f"A proper elastic net (D, q = 0.999) is worse ({pct(five, 'D', 'cell'):.0f}% / "
        f"{pct(five, 'D', 'set'):.0f}% with {five}): its ridge part spreads x over the "
        "collinear neighbouring cells. "
        f"Plain k-NN, which has no attack model, finds the cell in "
        f"{pct(five, 'kNN', 'cell'):.0f}% with {five} attacked sensors and "
        f"{pct(min(table), 'kNN', 'cell'):.0f}% with {min(table)}. "
        f"So the thesis's Fig. 6.6 is reproducible as an instance (decoder C gets the cell and "
        f"the {five} attacked sensors right in {pct(five, 'C', 'both'):.0f}% of the runs), not as "
        "the behaviour of Algorithm 3 with N = 1000 on a path-loss dictionary; "
        "whether the thesis's file held a better-conditioned D cannot be told from the text."
    )
    return textwrap.fill("".join(text), width=100)


if __name__ == "__main__":
    main()
