"""Write ssecert/examples/ieee14.toml: the IEEE 14-bus system of the pruning paper's Sec. IV-B.

The pruning paper (Zheng and Anubi, "Attack-resilient weighted l1 observer with prior
pruning", Sec. IV-B) runs its Table I on "IEEE Bus 14 system with a similar setup in
[15]" (Anubi, Konstantinou, Wong and Vedula, CCTA 2020) and gives no model.  The code of
that set-up is public in github.com/ZYblend/Resilient_Observers_Comparison (run_model.m
and bus14_PSCAD.m; header "Jan. 2020 (initial version) Olugbenga Moses Anubi, Carlos A.
Wong, Satish Vedula; Jan. 2021 Yu Zheng"), which cites the pruning paper.  This script
builds the same linear model from PYPOWER's case14 (the IEEE common data format case, the
same bus, branch and generator data as the code's bus14_PSCAD.m) and the generator
constants of bus14_PSCAD.m, which case14 does not carry:

* five classical machines at buses 1, 2, 3, 6, 8 (the generator buses of case14), each an
  internal voltage angle delta_i behind its transient reactance X_d, inertia constant H
  and damping D (X_d = 0.2995, 0.185, 0.185, 0.232, 0.232; H = 5.148, 6.54, 6.54, 5.06,
  5.06; D = 2), 60 Hz, flat voltage magnitudes, lossless lines;
* states x = [delta_1..delta_5, omega_1..omega_5] (angle and speed deviations), the swing
  equations M d(omega)/dt = -K delta - D omega with M = 2 H / (2 pi 60) and K the
  network reduced to the internal nodes (Kron reduction), discretised with
  A = expm(A_c T_s), T_s = 0.01 s;
* sensors: the five rotor speeds and the net power injected at the 14 buses (the DC
  power-flow model P = B theta of the bus angles theta, themselves a linear function of
  delta); no line flows.  Sensor order follows the code: generator buses first
  (1, 2, 3, 6, 8), then 4, 5, 7, 9, ..., 14.

The loads and the generators' mechanical power enter the code's model as known inputs;
ssecert's plants have none, and with the inputs known the estimation errors of the
observers of Table I do not depend on them.

The code's linearisation departs from the DC power-flow physics in three ways, and this
script keeps all three, because they are the model the paper simulated (the matrices
agree with those saved in the code's workspace, result/result_with_oracle/
Resulting_data.mat, to 1e-15 relative):

1. the network Laplacian of the Kron reduction is weighted by the line reactances x, not
   by the susceptances 1/x (``graph(fbus, tbus, branch.x)``);
2. the injection map uses 1/x, but in the original branch order while the incidence
   matrix lists the branches in MATLAB's ``graph`` order (sorted by end buses after the
   generator-first relabelling), so most susceptances sit on the wrong lines;
3. the Kron reduction has the wrong sign, ``K = Y_gg + Y_gg S Y_gg`` instead of
   ``Y_gg - Y_gg S Y_gg``, so K is positive definite instead of a Laplacian.

The third is what makes the rotor angles observable: in the consistent model
(``consistent_model``: PYPOWER's ``makeBdc`` susceptances, tap ratios included, and the
Kron reduction with its right sign) K has a zero eigenvalue, A an eigenvalue 1 and the
common angle of the five machines is unobservable from speeds and injections, so
delta_1..delta_5 of Table I could not be estimated at all.

    python tools/make_ieee14.py          # needs pypower (pip install ssecert[dev])
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.linalg

#: Generator constants of the code's bus14_PSCAD.m, in the order of case14's generators.
TRANSIENT_REACTANCE = (0.2995, 0.185, 0.185, 0.232, 0.232)
INERTIA = (5.148, 6.54, 6.54, 5.06, 5.06)
DAMPING = (2.0, 2.0, 2.0, 2.0, 2.0)
FREQUENCY = 60.0
SAMPLE_TIME = 0.01
#: Table I attacks 30 % of the 19 meters; the code draws round(fraction * meters) of them.
MAX_ATTACKED = 6
#: The code's receding horizon T = 2 n.
HORIZON = 20

OUT = Path(__file__).resolve().parents[1] / "ssecert" / "examples" / "ieee14.toml"


def case14() -> dict:
    """PYPOWER's IEEE 14-bus case."""
    from pypower.case14 import case14 as load

    return load()


def _generator_first(case: dict) -> tuple[np.ndarray, np.ndarray]:
    """The code's relabelling: buses sorted by type, descending and stable (slack, PV, PQ).

    Returns the original 0-based bus index of each new label and the new label of each bus.
    """
    order = np.argsort(-case["bus"][:, 1], kind="stable")
    label = np.empty(order.size, dtype=int)
    label[order] = np.arange(order.size)
    gen_buses = case["gen"][:, 0].astype(int) - 1
    if not np.array_equal(label[gen_buses], np.arange(gen_buses.size)):
        raise ValueError("the generator buses are not the first labels after the relabelling")
    return order, label


def _swing_matrices(K: np.ndarray, C_angles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Continuous swing equations in x = [delta; omega] and the sensors [omega; P]."""
    ng = K.shape[0]
    M = np.diag(2.0 * np.asarray(INERTIA) / (2.0 * np.pi * FREQUENCY))
    D = np.diag(DAMPING)
    A_c = np.block(
        [
            [np.zeros((ng, ng)), np.eye(ng)],
            [-np.linalg.solve(M, K), -np.linalg.solve(M, D)],
        ]
    )
    C = np.vstack(
        [
            np.hstack([np.zeros((ng, ng)), np.eye(ng)]),
            np.hstack([C_angles, np.zeros((C_angles.shape[0], ng))]),
        ]
    )
    return A_c, C


def published_model(case: dict | None = None) -> dict:
    """The linear model of the code's run_model.m, from case14's data.

    Returns a dict with ``A`` (discrete, 10 x 10), ``C`` (19 x 10), ``A_c`` (continuous),
    ``K`` (the reduced network), ``sensors`` (names) and ``buses`` (original bus number of
    each new label).
    """
    case = case14() if case is None else case
    bus, branch, gen = case["bus"], case["branch"], case["gen"]
    nb, ng = bus.shape[0], gen.shape[0]
    order, label = _generator_first(case)
    f = label[branch[:, 0].astype(int) - 1]
    t = label[branch[:, 1].astype(int) - 1]
    x = branch[:, 3]
    # MATLAB's graph(s, t, w): undirected edges stored with the smaller end first, sorted
    lo, hi = np.minimum(f, t), np.maximum(f, t)
    graph_order = np.lexsort((hi, lo))
    incidence = np.zeros((nb, x.size))
    incidence[lo[graph_order], np.arange(x.size)] = -1.0
    incidence[hi[graph_order], np.arange(x.size)] = 1.0
    adjacency = np.zeros((nb, nb))
    adjacency[f, t] = x  # departure 1: weighted by x
    adjacency[t, f] = x
    laplacian = np.diag(adjacency.sum(axis=0)) - adjacency
    # departure 2: 1/x in branch order against the incidence in graph order
    J = -incidence @ np.diag(1.0 / x) @ incidence.T
    Y_gg = np.diag(1.0 / np.asarray(TRANSIENT_REACTANCE))
    Y_gl = np.hstack([Y_gg, np.zeros((ng, nb - ng))])
    Y_ll = -scipy.linalg.block_diag(Y_gg, np.zeros((nb - ng, nb - ng))) - laplacian
    angles = np.linalg.solve(Y_ll, Y_gl.T)  # theta = -angles @ delta
    K = Y_gg - Y_gl @ angles  # departure 3: Y_gg + Y_gg S Y_gg
    A_c, C = _swing_matrices(K, -J @ angles)
    return {
        "A": scipy.linalg.expm(A_c * SAMPLE_TIME),
        "C": C,
        "A_c": A_c,
        "K": K,
        "sensors": _sensor_names(order, ng),
        "buses": order + 1,
    }


def consistent_model(case: dict | None = None) -> dict:
    """The same machines on PYPOWER's DC model (``makeBdc``), Kron-reduced with the right sign.

    For comparison only: its common rotor angle is unobservable.  Same keys as
    ``published_model``, plus ``Bbus`` and ``Bf`` (injections and line flows in terms of
    the bus angles, generator-first labels) and ``angles`` (S, with theta = S delta).
    """
    from pypower.ext2int import ext2int
    from pypower.makeBdc import makeBdc

    case = case14() if case is None else case
    internal = ext2int(case)
    Bbus, Bf, _, _ = makeBdc(internal["baseMVA"], internal["bus"], internal["branch"])
    order, _ = _generator_first(case)
    Bbus = Bbus.toarray()[np.ix_(order, order)]
    Bf = Bf.toarray()[:, order]
    ng, nb = case["gen"].shape[0], case["bus"].shape[0]
    Y_gg = np.diag(1.0 / np.asarray(TRANSIENT_REACTANCE))
    Y = Bbus + scipy.linalg.block_diag(Y_gg, np.zeros((nb - ng, nb - ng)))
    S = np.linalg.solve(Y, np.vstack([Y_gg, np.zeros((nb - ng, ng))]))  # theta = S delta
    K = Y_gg - Y_gg @ S[:ng]
    # Bbus S = Y S - diag(Y_gg, 0) S = [Y_gg (I - S_g); 0]: a load bus injects nothing the
    # angles move (its load is an input), so its rows are zero, not rounding noise
    injections = np.vstack([Y_gg @ (np.eye(ng) - S[:ng]), np.zeros((nb - ng, ng))])
    A_c, C = _swing_matrices(K, injections)
    return {
        "A": scipy.linalg.expm(A_c * SAMPLE_TIME),
        "C": C,
        "A_c": A_c,
        "K": K,
        "Bbus": Bbus,
        "Bf": Bf,
        "angles": S,
        "sensors": _sensor_names(order, ng),
        "buses": order + 1,
    }


def _sensor_names(order: np.ndarray, ng: int) -> list[str]:
    buses = order + 1
    return [f"omega-bus{b}" for b in buses[:ng]] + [f"P-bus{b}" for b in buses]


def _rows(M: np.ndarray) -> str:
    lines = ("  [" + ", ".join(repr(float(v)) for v in row) + "]" for row in M)
    return "[\n" + ",\n".join(lines) + ",\n]"


def render(model: dict) -> str:
    """The example spec's text."""
    names = [f'"{name}"' for name in model["sensors"]]
    sensors = ",\n".join("  " + ", ".join(names[i : i + 5]) for i in range(0, len(names), 5))
    return f"""# IEEE 14-bus system of the pruning paper (Zheng and Anubi, Sec. IV-B, Table I), as
# linearised by the code of its set-up (github.com/ZYblend/Resilient_Observers_Comparison,
# run_model.m): five classical machines at buses 1, 2, 3, 6, 8 on PYPOWER's case14 network,
# x = [delta_1..delta_5, omega_1..omega_5] (rotor angle and speed deviations), T_s = 0.01 s.
# Sensors: the five rotor speeds and the DC net injections at the 14 buses.  The code's
# linearisation departs from the DC power-flow physics (see tools/make_ieee14.py, which
# generates this file); without its third departure the common rotor angle would be
# unobservable.  max_attacked = 6: Table I attacks 30 % of the 19 meters; horizon = 20: the
# code's window T = 2 n.
name = "ieee14"

[attack]
max_attacked = {MAX_ATTACKED}
horizon = {HORIZON}

[system]
sensors = [
{sensors},
]
A = {_rows(model["A"])}
C = {_rows(model["C"])}
"""


def main() -> None:
    model = published_model()
    OUT.write_text(render(model))
    consistent = consistent_model()
    rank = np.linalg.matrix_rank(
        np.vstack([model["C"] @ np.linalg.matrix_power(model["A"], k) for k in range(10)])
    )
    print(f"wrote {OUT}")
    print(f"eigenvalue moduli of A: {np.sort(np.abs(np.linalg.eigvals(model['A'])))[::-1]}")
    print(f"observability rank: {rank} of 10")
    print(
        "consistent model (makeBdc, right Kron sign): smallest eigenvalue of K "
        f"{np.linalg.eigvalsh((consistent['K'] + consistent['K'].T) / 2)[0]:.2e}, "
        f"largest |eig(A)| {np.abs(np.linalg.eigvals(consistent['A'])).max():.15f}"
    )


if __name__ == "__main__":
    main()
