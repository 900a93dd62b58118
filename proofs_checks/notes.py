"""Claims of 002, Migliaccio's lecture notes: correctability (Proposition 1), Examples 0-3 and
q >= 2h + n (Ch. 2), ISTA (Sec. 2.5), the online-gradient observer (Sec. 4.2) and the
constant-attack proposition (Sec. 4.3).

The notes write x(k+1) = A x(k), y(k) = C x(k) + a(k) with q sensors (one scalar output each),
n states, at most h attacked sensors and a window of T steps: ssecert's p, s and tau (window) are
the notes' q, h and T, and the notes' tau is a step size (ssecert's ``step``).  Their observers
x_hat(k+1) = A x_hat(k) - L [y_hat(k) - y(k)] have ssecert's sign convention, error matrix A - L C.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from fractions import Fraction

import numpy as np
import sympy as sp

from ._core import Finding, claim

__all__: list[str] = []

Matrix = list[list[Fraction]]


# ---------------------------------------------------------------- exact linear algebra
def _exact(rows: Sequence[Sequence[int | Fraction]]) -> Matrix:
    return [[Fraction(v) for v in row] for row in rows]


def _identity(n: int) -> Matrix:
    return [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]


def _mul(X: Matrix, Y: Matrix) -> Matrix:
    return [[sum((x * y for x, y in zip(row, col)), Fraction(0)) for col in zip(*Y)] for row in X]


def _rref(M: Matrix) -> tuple[Matrix, list[int], Fraction]:
    """Reduced row echelon form over the rationals (exact), its pivot columns, and the
    determinant when M is square."""
    rows, det = [list(r) for r in M], Fraction(1)
    pivots: list[int] = []
    for j in range(len(rows[0]) if rows else 0):
        r = len(pivots)
        p = next((i for i in range(r, len(rows)) if rows[i][j] != 0), None)
        if p is None:
            det = Fraction(0)
            continue
        if p != r:
            rows[r], rows[p], det = rows[p], rows[r], -det
        det *= rows[r][j]
        rows[r] = [v / rows[r][j] for v in rows[r]]
        for i in range(len(rows)):
            if i != r and rows[i][j]:
                rows[i] = [a - rows[i][j] * b for a, b in zip(rows[i], rows[r])]
        pivots.append(j)
    return rows, pivots, det


def _rank(M: Matrix) -> int:
    return len(_rref(M)[1])


def _kernel_vector(M: Matrix) -> list[Fraction]:
    """A nonzero solution of M v = 0 (M without full column rank)."""
    rows, pivots, _ = _rref(M)
    free = next(j for j in range(len(M[0])) if j not in pivots)
    v = [Fraction(int(j == free)) for j in range(len(M[0]))]
    for i, j in enumerate(pivots):
        v[j] = -rows[i][free]
    return v


def _min_support(C: Matrix) -> tuple[int, tuple[int, ...]]:
    """min over z != 0 of ||C z||_0, i.e. q minus the largest set of rows of rank < n, and that
    set, by exhaustive search over the row subsets."""
    q, n = len(C), len(C[0])
    for size in range(q, -1, -1):
        for rows in itertools.combinations(range(q), size):
            if size < n or _rank([C[i] for i in rows]) < n:
                return q - size, rows
    raise AssertionError("unreachable: the empty set of rows has rank 0 < n")


# ---------------------------------------------------------------- Proposition 1
_ROWS2 = np.array([(0, 0), (1, 0), (0, 1), (1, 1), (1, -1)])
_PLANTS2 = {
    "identity": [[1, 0], [0, 1]],
    "jordan_at_1": [[1, 1], [0, 1]],
    "rotation_90": [[0, -1], [1, 0]],
    "swap": [[0, 1], [1, 0]],
    "nilpotent": [[0, 1], [0, 0]],
    "projection": [[1, 0], [0, 0]],
    "reflection": [[1, 0], [0, -1]],
    "zero": [[0, 0], [0, 0]],
}


def _correctable(O: np.ndarray, q: int, h: int, moving: bool) -> tuple[np.ndarray, np.ndarray]:
    """Definition 1 on the notes' stacked form y = O_T x(0) + a, for a stack of O_T: two
    explanations with x' != x'' exist iff O_T z = a'' - a' for some z != 0, i.e. iff [O_T, E_W]
    loses rank for a union W of two attack supports (the same 2h sensors at every k, or any 2h
    sensors at each k if `moving`).  Returns the verdicts and the singular values computed."""
    N, qT, n = O.shape
    T, w = qT // q, min(2 * h, q)
    sets = list(itertools.combinations(range(q), w))
    choices = list(itertools.product(sets, repeat=T)) if moving else [(s,) * T for s in sets]
    E = np.zeros((len(choices), qT, T * w))
    for c, choice in enumerate(choices):
        for k, W in enumerate(choice):
            E[c, [k * q + i for i in W], [k * w + j for j in range(w)]] = 1.0
    O_, E_ = np.broadcast_to(O[:, None], (N, len(E), qT, n)), np.broadcast_to(E, (N, *E.shape))
    s = np.linalg.svd(np.concatenate([O_.astype(float), E_], axis=3), compute_uv=False)
    return np.all((s > 1e-9).sum(axis=2) == n + T * w, axis=1), s


def _support_counts(O: np.ndarray, T: int, q: int) -> tuple[np.ndarray, ...]:
    """For n = 2 and integer O_T, the exact minimum over z != 0 of three readings of ||O_T z||_0:
    nonzero entries, sensors with a nonzero output, and max over k of ||C A^k z||_0.  A z
    orthogonal to no nonzero row has the fewest zeros; any other z is parallel to the normal of a
    nonzero row, so these candidates decide the minimum."""
    N = O.shape[0]
    normals = np.stack([O[:, :, 1], -O[:, :, 0]], axis=1)
    Z = np.concatenate([normals, np.tile([[[1], [10]]], (N, 1, 1))], axis=2)
    P = (O @ Z) != 0
    if not np.array_equal(P[:, :, -1], np.any(O != 0, axis=2)):
        raise AssertionError("the generic direction (1, 10) is orthogonal to a nonzero row")
    P, valid = P.reshape(N, T, q, -1), np.any(Z != 0, axis=1)
    return tuple(
        np.where(valid, c, 10**6).min(axis=1)
        for c in (P.sum(axis=(1, 2)), P.any(axis=1).sum(axis=1), P.sum(axis=2).max(axis=1))
    )


def _prop1_exhaustive() -> dict[str, float]:
    keys = ("systems", "literal_wrong", "literal_wrong_T1", "literal_only_if_wrong", "sensor_wrong")
    count = dict.fromkeys((*keys, "per_step_wrong", "sensor_reading_wrong_for_moving_attacks"), 0)
    zero_sv, nonzero_sv = 0.0, np.inf
    plants = np.array(list(_PLANTS2.values()))
    for q, T in itertools.product(range(1, 5), (1, 2, 3)):
        Cs = np.array(
            [_ROWS2[list(r)] for r in itertools.combinations_with_replacement(range(5), q)]
        )
        powers = np.array([[np.linalg.matrix_power(A, k) for k in range(T)] for A in plants])
        O = np.einsum("cqi,atij->catqj", Cs, powers).reshape(-1, T * q, 2)
        entries, sensors, per_step = _support_counts(O, T, q)
        for h in (0, 1):
            fixed, s = _correctable(O, q, h, moving=False)
            svs = [s]
            if T <= 2:  # attacks that move between sensors: (q choose 2h)^T supports
                moving, s2 = _correctable(O, q, h, moving=True)
                svs.append(s2)
                count["per_step_wrong"] += int(np.sum((per_step > 2 * h) != moving))
                wrong_moving = int(np.sum((sensors > 2 * h) != moving))
                count["sensor_reading_wrong_for_moving_attacks"] += wrong_moving
            for v in svs:
                zero_sv = max(zero_sv, float(v[v <= 1e-9].max(initial=0.0)))
                nonzero_sv = min(nonzero_sv, float(v[v > 1e-9].min(initial=np.inf)))
            wrong = int(np.sum((entries > 2 * h) != fixed))
            count["systems"] += len(O)
            count["literal_wrong"] += wrong
            count["literal_wrong_T1"] += wrong if T == 1 else 0
            count["literal_only_if_wrong"] += int(np.sum(fixed & (entries <= 2 * h)))
            count["sensor_wrong"] += int(np.sum((sensors > 2 * h) != fixed))
    return {**count, "largest_zero_singular_value": zero_sv, "smallest_nonzero_sv": nonzero_sv}


@claim(
    "notes.prop1",
    where="002 Sec. 2.2-2.3, Definition 1 and Proposition 1 (Proof 1)",
    statement="h errors are correctable after T steps (Definition 1: any x(0) can be recovered from "
    "y(0), ..., y(T-1) under ||a(k)||_0 <= h for each k) if and only if ||O_T z||_0 > 2h for all "
    "z in R^n (z != 0), O_T = [C; CA; ...; CA^(T-1)].",
    recorded="conditional",
)
def prop1() -> Finding:
    # the counterexamples, exactly: y(k) - C x(k) for the two explanations, one attack each
    C1, y1 = np.array([[1], [1]]), np.array([1, 0])
    A2, C2 = np.array([[0, 1], [1, 0]]), np.array([[1, 0], [1, 0], [0, 1], [0, 1]])
    y2, x2 = [np.array([1, 0, 0, 0]), np.array([0, 0, 1, 0])], np.array([1, 0])
    attacks = [y1 - C1 @ [1], y1 - C1 @ [0], y2[0] - C2 @ x2, y2[1] - C2 @ A2 @ x2, *y2]
    ex = _prop1_exhaustive()
    ok = ex["sensor_wrong"] == ex["per_step_wrong"] == ex["literal_wrong_T1"] == 0
    ok = ok and ex["literal_only_if_wrong"] == 0
    if not ([np.count_nonzero(a) for a in attacks] == [1] * 6 and ok and ex["literal_wrong"]):
        raise AssertionError(f"the check of Proposition 1 did not come out as expected: {ex}")
    return Finding(
        "conditional",
        "Read literally, ||O_T z||_0 counts nonzero entries of O_T z in R^{qT}, while Definition 1 "
        "allows h of the q sensors to be attacked at each k; then the 'if' direction fails for "
        "T >= 2. With n = 1, q = 2, A = 1, C = (1; 1), h = 1, T = 2, ||O_2 z||_0 = 4 > 2h for every "
        "z != 0, yet y(0) = y(1) = (1, 0) comes from x' = 1 with sensor 2 attacked (a' = (0, -1)) "
        "and from x'' = 0 with sensor 1 attacked (a'' = (1, 0)): x(0) cannot be recovered. The "
        "'only if' direction holds (correctability forces more than 2h nonzero entries), and "
        "z = 0 must be excluded (||O_T 0||_0 = 0). Keeping Definition 1 as written (any h "
        "sensors at each k), the criterion that holds is per step: every z != 0 has some k < T "
        "with ||C A^k z||_0 > 2h (two explanations differ by a z whose C A^k z = a''(k) - a'(k) "
        "is 2h-sparse at every k, and conversely such a z splits into two attacks). If instead "
        "the attacked sensors are the same at every k, the statement holds, and Proof 1 carries "
        "over word for word, when ||O_T z||_0 counts the sensors i whose outputs C_i A^k z "
        "(k < T) are not all zero (ssecert's reading: s attacked sensors are correctable iff "
        "2s <= max_removable); that sensor count is not enough for attacks that move (evidence: "
        "A swapping two states, four sensors). In the static case T = 1 that the notes prove, "
        f"all readings agree. Over {ex['systems']} small systems decided exhaustively, both "
        "corrected forms agree with Definition 1 everywhere (the per-step one checked for "
        f"T <= 2) and the literal one is wrong in {ex['literal_wrong']}, none with T = 1.",
        {
            "method": "exhaustive",
            "family": "n = 2; C: every multiset of 1-4 rows from (0,0), (1,0), (0,1), (1,1), "
            f"(1,-1) (125); A: {', '.join(_PLANTS2)}; T = 1, 2, 3; h = 0, 1",
            "readings": {
                "literal": "nonzero entries of O_T z in R^{qT}, attacks of h sensors at each k",
                "sensor": "sensors i with (C_i A^k z)_{k<T} != 0, the same h sensors at every k",
                "per_step": "max over k < T of ||C A^k z||_0, any h sensors at each k (T <= 2)",
            },
            "how": "Definition 1 from the rank of [O_T, E_W] over every union W of two attack "
            "supports (numpy SVD, threshold 1e-9); each reading's minimum over z != 0 exactly, in "
            "integers, over the normals of the rows of O_T and one generic direction",
            **ex,
            "moving_attack_counterexample": {
                "A": [[0, 1], [1, 0]],
                "C": [[1, 0], [1, 0], [0, 1], [0, 1]],
                "h": 1,
                "T": 2,
                "shows": "every z != 0 is seen by all 4 > 2h sensors, but y(0) = (1, 0, 0, 0), "
                "y(1) = (0, 0, 1, 0) comes from x(0) = 0 (sensor 1, then sensor 3 attacked) and "
                "from x(0) = (1, 0) (sensor 2, then sensor 4 attacked)",
            },
        },
        counterexample={
            "n": 1,
            "q": 2,
            "h": 1,
            "T": 2,
            "A": [[1]],
            "C": [[1], [1]],
            "O_T": [[1], [1], [1], [1]],
            "y": [[1, 0], [1, 0]],
            "x'": [1],
            "a'": [[0, -1], [0, -1]],
            "x''": [0],
            "a''": [[1, 0], [1, 0]],
            "shows": "||O_T z||_0 = 4 > 2h = 2 for every z != 0, yet y(k) = C x' + a'(k) = "
            "C x'' + a''(k) = (1, 0) for k = 0, 1 with ||a'(k)||_0 = ||a''(k)||_0 = 1 = h: x(0) is "
            "either 1 or 0, so h = 1 error is not correctable (2 sensors see z, and 2 = 2h)",
        },
        condition="z != 0 and, keeping Definition 1 as written (any h sensors attacked at each "
        "k), the norm taken per step: every z != 0 has some k < T with ||C A^k z||_0 > 2h; or, "
        "if the at most h attacked sensors are the same for k = 0, ..., T-1, ||O_T z||_0 counting "
        "the sensors i whose output sequence (C_i z, C_i A z, ..., C_i A^(T-1) z) is nonzero "
        "(for T = 1, the static case of Proof 1, every reading agrees)",
    )


# ---------------------------------------------------------------- Examples 0-3
_EXAMPLES = {  # Example: (C, the notes' verdict for h = 1, the notes' witness z or None)
    0: ([[1, 0, 0], [0, 1, 0], [0, 0, 1]], False, None),
    1: ([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0], [0, 1, 0]], False, [0, 0, 1]),
    2: ([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1], [1, -1, 1]], False, [1, 0, -1]),
    3: ([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1], [1, 2, -1]], True, None),
}


def _ssecert_max_removable() -> dict[str, int]:
    """What ssecert's sparse-observability check finds on its packaged copies of the examples."""
    from ssecert.examples import load_example
    from ssecert.structure.sparse import sparse_observability

    return {
        f"example_{i}": int(
            sparse_observability(load_example(f"notes-example-{i}").system, 1).value
        )
        for i in _EXAMPLES
    }


@claim(
    "notes.examples0_3",
    where="002 Sec. 2.3.1, Examples 0-3",
    statement="Static case (A = I), n = 3, h = 1: Example 0 (C = I_3), Example 1 (rows e1, e2, e3, "
    "e1, e2; z = (0, 0, alpha)) and Example 2 (rows e1, e2, e3, (1, 1, 1), (1, -1, 1); "
    "C5 = C4 - 2 C2, z = (alpha, 0, -alpha) gives a 2-sparse Cz) do not correct h = 1 error; "
    "Example 3 (rows e1, e2, e3, (1, 1, 1), (1, 2, -1); all triples of rows linearly independent) "
    "corrects h = 1 error.",
    recorded="holds",
)
def examples0_3() -> Finding:
    found: dict[str, dict[str, object]] = {}
    least: dict[str, int] = {}
    for i, (rows, verdict, witness) in _EXAMPLES.items():
        least[f"example_{i}"], deficient = _min_support(_exact(rows))
        entry: dict[str, object] = {
            "min_support_of_Cz": least[f"example_{i}"],
            "largest_rank_deficient_rows": [r + 1 for r in deficient],
            "corrects_h_1": least[f"example_{i}"] > 2,
            "notes_say": verdict,
        }
        if witness is not None:
            Cz = [int(row[0]) for row in _mul(_exact(rows), _exact([[w] for w in witness]))]
            entry.update(notes_witness_Cz=Cz, witness_valid=0 < np.count_nonzero(Cz) <= 2)
        if (least[f"example_{i}"] > 2) != verdict or entry.get("witness_valid") is False:
            raise AssertionError(f"Example {i} disagrees with the notes: {entry}")
        found[f"example_{i}"] = entry
    C2, C3 = _EXAMPLES[2][0], _EXAMPLES[3][0]
    relation = [a - 2 * b for a, b in zip(C2[3], C2[1])] == C2[4]
    triples = {
        str([r + 1 for r in t]): int(_rref(_exact([C3[r] for r in t]))[2])
        for t in itertools.combinations(range(5), 3)
    }
    ssecert = _ssecert_max_removable()
    agrees = all(v == least[k] - 1 for k, v in ssecert.items())
    if not (relation and 0 not in triples.values() and agrees):
        raise AssertionError("C5 = C4 - 2 C2, the triples of Example 3 or ssecert disagree")
    return Finding(
        "holds",
        "All four verdicts are right, and so are the witnesses. By Proposition 1 (static case, "
        "T = 1, where it holds as stated), C corrects h = 1 error iff ||Cz||_0 > 2 for all z != 0, "
        "and min ||Cz||_0 is q minus the largest set of rows of rank < 3. Example 0: 1 (z = e1). "
        "Example 1: 1, from rows 1, 2, 4, 5 (the notes' z = (0, 0, 1) gives Cz = e3). Example 2: 2, "
        "from rows 2, 4, 5 (C5 = C4 - 2 C2 holds, and z = (1, 0, -1) gives Cz = (1, 0, -1, 0, 0)). "
        "Example 3: 3, since all ten triples of rows have nonzero determinant, so it corrects "
        "h = 1 error with q = 5 = 2h + n sensors. ssecert's packaged copies (notes-example-0..3) "
        "give max_removable = 0, 0, 1, 2, i.e. min ||Cz||_0 - 1, in agreement.",
        {
            "method": "exhaustive",
            "how": "every subset of rows of each C, ranks in exact rational arithmetic",
            **found,
            "example_2_relation_C5_eq_C4_minus_2C2": relation,
            "example_3_triple_determinants": triples,
            "ssecert_max_removable": ssecert,
        },
    )


# ---------------------------------------------------------------- q >= 2h + n
def _sensor_ranks(A: Matrix, C: Matrix, T: int) -> list[int]:
    """Exact rank of each sensor's own T-step observability matrix (C_i; C_i A; ...)."""
    powers = [_identity(len(A))]
    for _ in range(T - 1):
        powers.append(_mul(powers[-1], A))
    return [_rank([_mul([row], P)[0] for P in powers]) for row in C]


def _min_support_n2(q: int) -> tuple[int, int]:
    """Every C in {-1, 0, 1}^(q x 2) of rank 2: (how many, largest min_z ||Cz||_0 - (q - 1)).

    Exact in integers: a z != 0 orthogonal to no nonzero row (here (1, 10)) leaves no zero
    entry but the zero rows, any other z is parallel to the normal (c2, -c1) of a row."""
    C = np.array(list(itertools.product((-1, 0, 1), repeat=2 * q))).reshape(-1, q, 2)
    full = C[:, :, 0, None] * C[:, None, :, 1] - C[:, :, 1, None] * C[:, None, :, 0]
    C = C[np.any(full != 0, axis=(1, 2))]  # rank 2: two rows with a nonzero determinant
    Z = np.concatenate(
        [np.stack([C[:, :, 1], -C[:, :, 0]], 1), np.tile([[[1], [10]]], (len(C), 1, 1))], 2
    )
    counts = np.where(np.any(Z != 0, axis=1), np.count_nonzero(C @ Z, axis=1), q + 1)
    return len(C), int((counts.min(axis=1) - (q - 1)).max())


def _vandermonde_static() -> list[dict[str, int]]:
    """min ||Cz||_0 for Vandermonde rows (1, t, ..., t^(n-1)), q = 2h + n and one row fewer."""
    static = []
    for n, h in ((1, 1), (2, 1), (3, 1), (2, 2), (3, 2)):
        below, at = (
            _min_support(_exact([[t**j for j in range(n)] for t in range(2 * h + n + d)]))[0]
            for d in (-1, 0)
        )
        static.append({"n": n, "h": h, "min_support_q_2h_n_minus_1": below, "at_q_2h_n": at})
    return static


@claim(
    "notes.q_ge_2h_plus_n",
    where="002 Sec. 2.3.2 (within Sec. 2.3, the static case)",
    statement="Static case (Sec. 2.3: A = I, y = C x + a): for C in R^{q,n} with rank(C) = n and "
    "q > n, correcting h errors needs q >= 2h + n (any n - 1 rows have a nontrivial kernel, so "
    "2h < q - (n - 1)); e.g. h = 1, n = 3 needs at least q = 5 sensors.",
    recorded="holds",
)
def q_ge_2h_plus_n() -> Finding:
    static = _vandermonde_static()
    tight = all(s["min_support_q_2h_n_minus_1"] == 2 * s["h"] < s["at_q_2h_n"] for s in static)
    exhaustive = {f"q={q}": _min_support_n2(q) for q in (3, 4)}
    # the remark: three identical sensors on a rotation by 90 degrees; and n = 3, q = 3 < 5
    # identical sensors on a cyclic shift
    A, C = _exact([[0, -1], [1, 0]]), _exact([[1, 0], [1, 0], [1, 0]])
    per_sensor, CA = _sensor_ranks(A, C, 2), _mul(C, A)
    same = all(r == C[0] for r in C) and all(r == CA[0] for r in CA)  # C A^k z = (c_k z)(1, 1, 1)
    shift = _exact([[0, 1, 0], [0, 0, 1], [1, 0, 0]])
    larger = _sensor_ranks(shift, _exact([[1, 0, 0]] * 3), 3)
    if not (tight and all(w <= 0 for _, w in exhaustive.values())):
        raise AssertionError("the static bound q >= 2h + n did not come out as expected")
    if not (per_sensor == [2, 2, 2] and same and larger == [3, 3, 3]):
        raise AssertionError("the dynamic remark did not come out as expected")
    return Finding(
        "holds",
        "In the static case of Sec. 2.3, where the notes state it, it holds: any n - 1 rows of C "
        "are n - 1 homogeneous equations in n unknowns, so some z != 0 makes them vanish; as "
        "rank C = n, Cz != 0 and ||Cz||_0 <= q - n + 1. Proposition 1 (static case, where it "
        "holds as stated: notes.prop1) needs ||Cz||_0 > 2h for every z != 0, hence "
        "q - n + 1 > 2h, i.e. q >= 2h + n, and h = 1, n = 3 need q >= 5. The bound is attained "
        "(Vandermonde rows give min ||Cz||_0 = 2h + 1 with q = 2h + n sensors, 2h with one "
        "fewer), and every C in {-1, 0, 1}^(q x 2) of rank 2, q = 3, 4, has min ||Cz||_0 <= "
        "q - 1 (exhaustive). The printed 'or equivalently h <= q - n' is wrong "
        "(notes.h_le_q_minus_n), but q >= 2h + n follows from 2h < q - (n - 1) directly. "
        "Remark: the bound is the static case's. For a dynamic plant observed over T >= 2 "
        "steps it is not necessary (only q >= 2h + 1 is): a sensor's outputs (C_i; C_i A; ...) "
        "can see the whole state, e.g. n = 2, h = 1 and q = 3 < 2h + n identical sensors "
        "measuring x1 of a rotation by 90 degrees correct one attacked sensor, fixed or moving, "
        "after T = 2 steps by a majority vote at each k (evidence).",
        {
            "method": "symbolic+exhaustive",
            "argument": "n - 1 homogeneous equations in n unknowns have a solution z != 0, and Cz is "
            "zero on those n - 1 rows: min over z != 0 of ||Cz||_0 <= q - n + 1",
            "static_vandermonde": static,
            "exhaustive_n2_entries_-1_0_1": {
                k: {"rank_2_matrices": m, "max_of_min_support_minus_(q-n+1)": w}
                for k, (m, w) in exhaustive.items()
            },
            "how": "exact rational ranks of every row subset, and integer counts for n = 2",
            "remark_dynamic_plant": {
                "n": 2,
                "q": 3,
                "h": 1,
                "T": 2,
                "A": [[0, -1], [1, 0]],
                "C": [[1, 0], [1, 0], [1, 0]],
                "O_T": [[1, 0], [1, 0], [1, 0], [0, -1], [0, -1], [0, -1]],
                "sensor_ranks_T2": per_sensor,
                "cyclic_shift_n3_q3_sensor_ranks_T3": larger,
                "shows": "q = 3 < 2h + n = 4, yet C z = z1 (1, 1, 1) and C A z = -z2 (1, 1, 1): "
                "every z != 0 has ||C A^k z||_0 = 3 > 2h for k = 0 or k = 1, so each sensor "
                "alone observes x(0) and one attacked sensor (fixed or moving) is corrected "
                "after T = 2 steps; outside Sec. 2.3's static setting",
            },
        },
    )


@claim(
    "notes.h_le_q_minus_n",
    where="002 Sec. 2.3.2",
    statement="For integers q > n >= 1 and h >= 0: '2h < q - (n - 1), or equivalently h <= q - n'.",
    recorded="fails",
)
def h_le_q_minus_n() -> Finding:
    triples = wrong = fixed_wrong = 0
    for q in range(2, 41):
        for n, h in itertools.product(range(1, q), range(q + 1)):
            strict = 2 * h < q - (n - 1)
            triples += 1
            wrong += int(strict != (h <= q - n))
            fixed_wrong += int(strict != (2 * h <= q - n))
    vandermonde = _exact([[t**j for j in range(3)] for t in range(4)])  # q = 4, n = 3
    least, rows = _min_support(vandermonde)
    Cz = [row[0] for row in _mul(vandermonde, _exact([[0], [1], [-1]]))]
    if not (wrong and fixed_wrong == 0 and least == 2 and Cz == [0, 0, -2, -6]):
        raise AssertionError("the check of 'equivalently h <= q - n' did not come out")
    return Finding(
        "fails",
        "The printed step is well-formed and false, so it fails: for integers 2h < q - (n - 1) "
        "means 2h <= q - n, not h <= q - n. With q = 4, n = 3, h = 1, h <= q - n holds (1 <= 1) "
        "but 2h < q - n + 1 does not (2 < 2 is false); and indeed no 4 x 3 C of rank 3 corrects "
        "one error: any two rows share a kernel vector, so min ||Cz||_0 <= 2 = 2h (Vandermonde "
        "rows (1, t, t^2), t = 0..3: exactly 2). It looks like a misprint for 2h <= q - n, "
        f"which is equivalent to 2h < q - (n - 1) (all {triples} integer triples with "
        "q <= 40 checked) and gives the notes' q >= 2h + n; the conclusion is unaffected "
        f"(notes.q_ge_2h_plus_n). 'h <= q - n' disagrees with 2h < q - (n - 1) on {wrong} of "
        "those triples.",
        {
            "method": "exhaustive",
            "triples": triples,
            "range": "q = 2..40, n = 1..q-1, h = 0..q",
            "disagreements_with_h_le_q_minus_n": wrong,
            "disagreements_with_2h_le_q_minus_n": fixed_wrong,
            "vandermonde_q4_n3_min_support": least,
            "vandermonde_largest_rank_deficient_rows": [r + 1 for r in rows],
        },
        counterexample={
            "q": 4,
            "n": 3,
            "h": 1,
            "C": [[1, 0, 0], [1, 1, 1], [1, 2, 4], [1, 3, 9]],
            "shows": "h <= q - n reads 1 <= 1 (true), 2h < q - (n - 1) reads 2 < 2 (false): the "
            "two are not equivalent. The second is the one that matters: rows 1 and 2 of this C "
            "(rank 3) vanish on z = (0, 1, -1), and Cz = (0, 0, -2, -6) has 2 = 2h nonzero "
            "entries, so h = 1 error is not correctable with q = 4 < 2h + n = 5 sensors.",
        },
    )


# ---------------------------------------------------------------- ISTA
def _surrogate_identity() -> bool:
    """(2.3)-(2.8): the smooth part of R(x, b) is (1/(2 tau)) ||x - q||^2 plus a term free of x,
    q = b + tau A^T (y - A b); checked with sympy for a symbolic 3 x 2 matrix A."""
    tau = sp.symbols("tau", positive=True)
    A, y = sp.Matrix(3, 2, sp.symbols("a1:7", real=True)), sp.Matrix(sp.symbols("y1:4", real=True))
    x, b = sp.Matrix(sp.symbols("x1:3", real=True)), sp.Matrix(sp.symbols("b1:3", real=True))

    def sq(v: sp.Matrix) -> sp.Expr:
        return (v.T * v)[0]

    smooth = sq(A * x - y) / 2 + sq(x - b) / (2 * tau) - sq(A * (x - b)) / 2
    rest = smooth - sq(x - b - tau * A.T * (y - A * b)) / (2 * tau)
    return all(sp.simplify(sp.diff(rest, xi)) == 0 for xi in x)


def _ista_matrices(rng: np.random.Generator, m: int, n: int, per: int) -> np.ndarray:
    """`per` matrices of each family: gaussian, rank one, two equal columns, a zero row and
    column, 2 x orthonormal (all singular values equal)."""
    G = rng.standard_normal((5, per, m, n))
    G[1] = rng.standard_normal((per, m, 1)) @ rng.standard_normal((per, 1, n))
    G[2, :, :, 1] = G[2, :, :, 0]
    G[3, :, 0, :], G[3, :, :, -1] = 0.0, 0.0
    G[4] = 2 * np.linalg.qr(rng.standard_normal((per, max(m, n), max(m, n))))[0][:, :m, :n]
    return G.reshape(5 * per, m, n)


def _ista_batch(
    rng: np.random.Generator, A: np.ndarray, theta: tuple[float, float], K: int
) -> dict[str, float]:
    """Run ISTA (2.11) with tau = theta / ||A||^2 on a stack of A at once; test every step's
    descent and, at k = 100, 1000, 3000, the convergence bound."""
    B, m, n = A.shape
    y = 2 * rng.standard_normal((B, m))
    AtA, Aty = np.swapaxes(A, 1, 2) @ A, np.einsum("bij,bi->bj", A, y)
    L = np.linalg.norm(A, 2, axis=(1, 2)) ** 2
    tau = np.asarray(rng.uniform(theta[0], theta[1], size=B))
    if theta[1] <= 1:
        tau[::4] = 1 - 1e-6  # just below 1 / ||A||^2
    tau /= L
    lam = np.abs(Aty).max(axis=1) * 10 ** rng.uniform(-1.5, 0.3, B)  # some with x* = 0
    x = x0 = np.where(rng.random((B, 1)) < 0.5, 0.0, rng.standard_normal((B, n)))

    def F(v: np.ndarray) -> np.ndarray:
        r = np.einsum("bij,bj->bi", A, v) - y
        return 0.5 * np.sum(r * r, axis=1) + lam * np.abs(v).sum(axis=1)

    def gap(v: np.ndarray) -> np.ndarray:  # F(v) - D(nu) >= F(v) - F*, nu feasible for the dual
        r = y - np.einsum("bij,bj->bi", A, v)
        nu = r * np.minimum(1.0, lam / np.abs(np.einsum("bij,bi->bj", A, r)).max(axis=1))[:, None]
        return F(v) - (np.sum(nu * y, axis=1) - 0.5 * np.sum(nu * nu, axis=1))

    Fk, worst_descent, worst_rate = F(x), np.inf, 0.0
    for k in range(1, K + 1):
        v = x + tau[:, None] * (Aty - np.einsum("bij,bj->bi", AtA, x))
        xn = np.sign(v) * np.maximum(np.abs(v) - (tau * lam)[:, None], 0.0)
        Fn = F(xn)
        # Theorem (1) with its margin: F(x_k) - F(x_k+1) >= (1/tau - ||A||^2/2) ||dx||^2
        margin = Fk - Fn - (1 / tau - L / 2) * np.sum((xn - x) ** 2, axis=1)
        worst_descent = min(worst_descent, float(np.min(margin / (1 + np.abs(Fk)))))
        x, Fk = xn, Fn
        if k in (100, 1000, 3000) and theta[1] <= 1:
            # Theorem (2): F(x_k) - F* <= ||x0 - x*||^2 / (2 tau k), and ||x0 - x*|| <= R with
            # ||x*||_1 <= F* / lambda <= F(x_k) / lambda
            R = np.linalg.norm(x0, axis=1) + Fk / lam
            worst_rate = max(worst_rate, float(np.max(gap(x) * 2 * tau * k / R**2)))
    final = gap(x) / (1 + Fk)
    return {
        "instances": B,
        "worst_descent_margin": worst_descent,
        "worst_gap_over_rate_bound": worst_rate,
        "max_relative_gap_at_K": float(final.max()),
        "median_relative_gap_at_K": float(np.median(final)),
    }


@claim(
    "notes.ista_descent",
    where="002 Sec. 2.5.1, (2.2)-(2.11) and Theorems (1)-(2)",
    statement="For the LASSO functional F(x) = 1/2 ||Ax - y||_2^2 + lambda ||x||_1 and "
    "tau < 1/||A||_2^2, ISTA x(k+1) = S_{tau lambda}[x(k) + tau A^T (y - A x(k))] (2.11) is a "
    "descent algorithm, F(x(k+1)) <= F(x(k)) (Theorem (1)), and converges to the minimum of LASSO "
    "(Theorem (2)).",
    recorded="holds",
)
def ista_descent() -> Finding:
    identity = _surrogate_identity()
    rng = np.random.default_rng(2025)
    runs = {
        f"{m}x{n}": _ista_batch(rng, _ista_matrices(rng, m, n, 30), (0.2, 1.0), 3000)
        for m, n in ((6, 4), (3, 6))
    }
    beyond = _ista_batch(rng, _ista_matrices(rng, 6, 4, 10), (1.0, 1.95), 300)
    descent = min(r["worst_descent_margin"] for r in [*runs.values(), beyond])
    rate = max(r["worst_gap_over_rate_bound"] for r in runs.values())
    if not (identity and descent > -1e-12 and rate <= 1.0):
        raise AssertionError(f"ISTA failed its check: identity {identity}, {runs}, {beyond}")
    del beyond["worst_gap_over_rate_bound"]
    return Finding(
        "holds",
        "Both theorems hold for tau < 1/||A||^2. Each ISTA step minimises the surrogate "
        "R(., x(k)), which is (1/(2 tau)) ||x - q||^2 + lambda ||x||_1 plus a constant (checked "
        "with sympy), so F(x(k)) = R(x(k), x(k)) >= R(x(k+1), x(k)) >= F(x(k+1)); the sharper "
        "F(x(k)) - F(x(k+1)) >= (1/tau - ||A||^2/2) ||x(k+1) - x(k)||^2 held at every step of every "
        "instance. The convergence bound F(x(k)) - F* <= ||x(0) - x*||^2 / (2 tau k) held at "
        "k = 100, 1000, 3000 (F - F* bounded above by a duality gap), including rank-one and "
        "repeated-column A, whose minimiser need not be unique; there the gap shrinks only like "
        "1/k. Two slips in the derivation, neither affecting the theorems: (1/(2 tau)) ||x - b||^2 "
        "- (1/2) ||Ax - Ab||^2 is >= (not =) (1/2)(1/tau - ||A||^2) ||x - b||^2, so it is "
        "non-negative for all x, b iff tau <= 1/||A||^2 (not only for '<'); and (2.5) should read "
        "-(1/2)||Ax||^2 - (1/2)||Ab||^2 + b^T A^T A x. Theorem (1) even holds for tau up to "
        "2/||A||^2 (tested too): the notes' condition is sufficient, not necessary.",
        {
            "method": "symbolic+randomised",
            "symbolic": "sympy: d/dx [smooth part of R(x, b) - ||x - q||^2 / (2 tau)] = 0 for a "
            "symbolic 3 x 2 A, q = b + tau A^T (y - A b)",
            "distribution": "A: gaussian, rank one, two equal columns, a zero row and column, or 2x "
            "orthonormal (equal singular values), 6x4 and 3x6; y ~ N(0, 4 I); tau = theta / "
            "||A||^2 with theta ~ U(0.2, 1) and a quarter at 1 - 1e-6; lambda = ||A^T y||_inf "
            "10^U(-1.5, 0.3); x(0) = 0 or N(0, I); 3000 iterations; seed 2025",
            "descent_test": "F(x_k) - F(x_k+1) - (1/tau - ||A||^2/2) ||x_k+1 - x_k||^2 >= 0, "
            "relative to 1 + |F(x_k)|, every step",
            "rate_test": "duality gap at k / (R^2 / (2 tau k)), R = ||x0|| + F(x_k) / lambda >= "
            "||x0 - x*|| (must be <= 1)",
            "worst_descent_margin": descent,
            "worst_gap_over_rate_bound": rate,
            "runs": runs,
            "beyond_the_statement": {"theta": "U(1, 1.95)", "iterations": 300, **beyond},
        },
    )


# ---------------------------------------------------------------- online gradient descent
def _ogd_error(A: Matrix, C: Matrix, tau: Fraction) -> tuple[Matrix, Matrix]:
    """I - tau C^T C and A - L_g C = A - tau A C^T C (4.13)-(4.14), exactly."""
    CtC = _mul([list(col) for col in zip(*C)], C)
    M = [[e - tau * g for e, g in zip(er, gr)] for er, gr in zip(_identity(len(A)), CtC)]
    L_g = [[tau * v for v in row] for row in _mul(A, [list(col) for col in zip(*C)])]
    return M, [[a - lc for a, lc in zip(ar, lr)] for ar, lr in zip(A, _mul(L_g, C))]


def _eigenvalues_2x2(M: Matrix) -> tuple[Fraction, Fraction]:
    """(trace, determinant): the eigenvalues solve s^2 - trace s + det = 0."""
    return M[0][0] + M[1][1], M[0][0] * M[1][1] - M[0][1] * M[1][0]


def _ogd_random(rng: np.random.Generator, N: int) -> dict[str, float]:
    """rho(A (I - tau C^T C)) for ||A||_2 <= 1 (orthogonal or normal A), C of full column rank and
    0 < tau < 1/||C||^2; and how often a non-normal marginally stable A breaks it."""
    out = dict(instances=N, max_norm_I_minus_tau_CtC=0.0, max_spectral_radius=0.0)
    out.update(max_rho_minus_norm=-np.inf, min_norm_rank_deficient_C=1.0, non_normal_unstable=0)
    for i in range(N):
        n = int(rng.integers(2, 6))
        Q = np.linalg.qr(rng.standard_normal((n, n)))[0]
        D = np.diag(np.r_[1.0, rng.uniform(-1, 1, n - 1)])
        if n >= 3:  # a pair of complex eigenvalues of modulus U(0.5, 1)
            t, r = rng.uniform(0, np.pi), rng.uniform(0.5, 1)
            D[1:3, 1:3] = r * np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
        A = Q @ D @ Q.T if i % 2 else Q  # normal, or orthogonal
        C = rng.standard_normal((n + int(rng.integers(0, 3)), n)) @ np.diag(
            10 ** rng.uniform(-1, 1, n)
        )
        tau = (1 - 1e-6 if i % 5 == 0 else rng.uniform(0.01, 1)) / np.linalg.norm(C, 2) ** 2
        M = np.eye(n) - tau * C.T @ C
        norm, rho = float(np.linalg.norm(M, 2)), float(np.abs(np.linalg.eigvals(A @ M)).max())
        out["max_norm_I_minus_tau_CtC"] = max(out["max_norm_I_minus_tau_CtC"], norm)
        out["max_spectral_radius"] = max(out["max_spectral_radius"], rho)
        out["max_rho_minus_norm"] = max(out["max_rho_minus_norm"], rho - norm)  # rho <= ||M||
        C[:, -1] = C[:, 0]  # rank deficient: ||I - tau C^T C|| = 1
        Md = np.eye(n) - tau / 4 * C.T @ C
        out["min_norm_rank_deficient_C"] = min(
            out["min_norm_rank_deficient_C"], float(np.linalg.norm(Md, 2))
        )
        P = rng.standard_normal((n, n)) + 3 * np.eye(n)  # non-normal, marginally stable
        An = P @ np.diag(np.r_[1.0, rng.uniform(-1, 1, n - 1)]) @ np.linalg.inv(P)
        out["non_normal_unstable"] += int(np.abs(np.linalg.eigvals(An @ M)).max() > 1 + 1e-9)
    return out


@claim(
    "notes.ogd_stability",
    where="002 Sec. 4.2, (4.13)-(4.14) and the two cases after them",
    statement="For the OGD observer (4.13), L_g = tau A C^T and A - L_g C = A (I - tau C^T C); with "
    "tau < 1/||C||_2^2, ||I - tau C^T C|| <= 1, and if ||I - tau C^T C|| < 1 and A is marginally "
    "stable, then A - L_g C is asymptotically stable.",
    recorded="conditional",
)
def ogd_stability() -> Finding:
    from ssecert import System
    from ssecert.design.gains import ogd_gain

    # exact: tau = 1/8 < 1/||C||^2 = 1/4 (C diagonal), A has eigenvalues 1 and 0
    A = _exact([[3, -2], [3, -2]])
    shrink, err = _ogd_error(A, _exact([[1, 0], [0, 2]]), Fraction(1, 8))
    exact = shrink == _exact([[Fraction(7, 8), 0], [0, Fraction(1, 2)]]) and err == _mul(A, shrink)
    exact = (
        exact and _eigenvalues_2x2(A) == (1, 0) and _eigenvalues_2x2(err) == (Fraction(13, 8), 0)
    )
    gain = ogd_gain(System(np.array([[3.0, -2.0], [3.0, -2.0]]), np.diag([1.0, 2.0])), 0.125)
    ssecert_rho = float(np.abs(np.linalg.eigvals(gain.error_matrix)).max())
    # the notes' other case, ||I - tau C^T C|| = 1: C = (1, 0), tau = 1/2, A = [[-2, 3], [-2, 3]]
    shrink1, err1 = _ogd_error(_exact([[-2, 3], [-2, 3]]), _exact([[1, 0]]), Fraction(1, 2))
    exact = exact and shrink1 == _exact([[Fraction(1, 2), 0], [0, 1]])
    stats = _ogd_random(np.random.default_rng(42), 400)
    ok = stats["max_spectral_radius"] < 1 and stats["max_rho_minus_norm"] < 1e-12
    if not (exact and _eigenvalues_2x2(err1) == (2, 0) and abs(ssecert_rho - 1.625) < 1e-12 and ok):
        raise AssertionError(f"the OGD check did not come out as expected: {stats}")
    return Finding(
        "conditional",
        "A - L_g C = A (I - tau C^T C) (4.14) is right, and for 0 < tau < 1/||C||^2 the "
        "eigenvalues 1 - tau sigma_i^2 of I - tau C^T C lie in (0, 1], so ||I - tau C^T C|| <= 1, "
        "with < 1 exactly when C has full column rank (the premise of the second case). But a "
        "marginally stable A can have ||A|| > 1, and then the product can have spectral radius "
        "above 1: in the counterexample A (eigenvalues 1 and 0, a projection, A^2 = A) is "
        "marginally stable, ||I - tau C^T C|| = 7/8 < 1, tau = 1/8 < 1/||C||^2 = 1/4, yet "
        "A - L_g C has eigenvalue 13/8, so the OGD observer diverges. The bound "
        "rho(A M) <= ||A|| ||M|| < 1 does give the conclusion when ||A||_2 <= 1, e.g. A orthogonal "
        "or normal with eigenvalues in the closed unit disc: in 400 such random instances the "
        "spectral radius never exceeded ||I - tau C^T C|| < 1 (it comes close to 1 only when "
        "tau sigma_min(C)^2 is small), while the same C and tau made "
        f"{stats['non_normal_unstable']} of 400 non-normal marginally stable A unstable. "
        "The first case (||I - tau C^T C|| = 1 gives marginal stability) fails the same way "
        "(evidence). ssecert's ogd_gain(step = 1/8) gives the same error matrix.",
        {
            "method": "certificate+randomised",
            "certificate": "exact rationals: tr(A) = 1, det(A) = 0; I - tau C^T C = diag(7/8, 1/2); "
            "A - L_g C = [[21/8, -1], [21/8, -1]], tr = 13/8, det = 0",
            "margin": "rho(A - L_g C) - 1 = 5/8",
            "ssecert_ogd_gain_spectral_radius": ssecert_rho,
            "distribution": "n ~ U{2..5}; A = Q (orthogonal, half) or Q D Q^T (normal, D with 1, "
            "U(-1, 1) and for n >= 3 a rotation block of radius U(0.5, 1)); q = n..n+2; C gaussian "
            "times diag(10^U(-1, 1)); tau = theta / ||C||^2, theta ~ U(0.01, 1), a fifth at "
            "1 - 1e-6; non-normal A = P diag(1, U(-1, 1)) P^-1, P gaussian + 3 I; seed 42",
            **stats,
            "first_case_counterexample": {
                "A": [[-2, 3], [-2, 3]],
                "C": [[1, 0]],
                "tau": 0.5,
                "shows": "tau = 1/2 < 1/||C||^2 = 1, ||I - tau C^T C|| = ||diag(1/2, 1)|| = 1 and A "
                "marginally stable (eigenvalues 1, 0), yet A - L_g C = [[-1, 3], [-1, 3]] has "
                "eigenvalue 2: not marginally stable",
            },
        },
        counterexample={
            "A": [[3, -2], [3, -2]],
            "C": [[1, 0], [0, 2]],
            "tau": 0.125,
            "L_g": [[0.375, -0.5], [0.375, -0.5]],
            "I - tau C^T C": [[0.875, 0], [0, 0.5]],
            "A - L_g C": [[2.625, -1], [2.625, -1]],
            "shows": "A has eigenvalues 1 and 0 (marginally stable), ||C||^2 = 4 so tau = 1/8 < 1/4, "
            "||I - tau C^T C|| = 7/8 < 1, yet A - L_g C = A (I - tau C^T C) has trace 13/8 and "
            "determinant 0: eigenvalue 13/8 > 1, not asymptotically stable",
        },
        condition="||A||_2 <= 1 (e.g. A orthogonal, or normal with its eigenvalues in the closed "
        "unit disc), besides C of full column rank (which is what makes ||I - tau C^T C|| < 1)",
    )


# ---------------------------------------------------------------- constant attack
def _augmented_O(A: Matrix, C: Matrix, T: int) -> Matrix:
    """O'_T of (4.18): block rows (C A^k, I_q), k = 0, ..., T-1."""
    rows, P = [], _identity(len(A))
    for _ in range(T):
        rows += [c + e for c, e in zip(_mul(C, P), _identity(len(C)))]
        P = _mul(P, A)
    return rows


def _with_eigenvalue_1(rng: np.random.Generator, n: int, shape: str) -> Matrix:
    """A = P J P^-1, J upper triangular with a simple 1, a repeated 1 or a Jordan block at 1 and
    other diagonal entries p/r (p in -3..3, r in 1..3), P a random invertible integer matrix."""
    J = [[Fraction(0)] * n for _ in range(n)]
    for i in range(n):
        J[i][i] = Fraction(int(rng.integers(-3, 4)), int(rng.integers(1, 4)))
    J[0][0] = Fraction(1)
    if shape != "simple":
        J[1][1], J[0][1] = Fraction(1), Fraction(int(shape == "jordan"))
    P = _exact(rng.integers(-2, 3, size=(n, n)).tolist())
    while _rank(P) < n:
        P = _exact(rng.integers(-2, 3, size=(n, n)).tolist())
    P_inv = [r[n:] for r in _rref([p + e for p, e in zip(P, _identity(n))])[0]]
    return _mul(_mul(P, J), P_inv)


@claim(
    "notes.constant_attack",
    where="002 Sec. 4.3, (4.17)-(4.24) and the Proposition",
    statement="For x(k+1) = A x(k), y(k) = C x(k) + a with a constant attack a in R^q, i.e. "
    "(y(0); ...; y(T-1)) = O'_T (x(0); a) with O'_T = [C I; CA I; ...; CA^(T-1) I] (4.17)-(4.18): "
    "if A has an eigenvalue equal to 1, the dynamic CPS with constant attack is not observable.",
    recorded="holds",
)
def constant_attack() -> Finding:
    # symbolic: in a basis whose first vector is the eigenvector v (A e1 = e1), every block row
    # of O'_T (v; -C v) is C A^k v - C v = 0
    A = sp.Matrix(3, 3, lambda i, j: int(i == 0) if j == 0 else sp.Symbol(f"a{i}{j}"))
    C, v = sp.Matrix(2, 3, lambda i, j: sp.Symbol(f"c{i}{j}")), sp.Matrix([1, 0, 0])
    symbolic = all(sp.expand(C * A**k * v - C * v) == sp.zeros(2, 1) for k in range(5))
    rng = np.random.default_rng(7)
    deficiency, in_kernel, instances = [], True, 0
    for shape in ("simple", "repeated", "jordan"):
        for _ in range(6):
            n, q = int(rng.integers(2, 5)), int(rng.integers(1, 4))
            A_ = _with_eigenvalue_1(rng, n, shape)
            C_ = rng.integers(-2, 3, size=(q, n))
            C_[0] *= int(rng.random() > 0.3)  # a zero row 30% of the time
            Cx = _exact(C_.tolist())
            u = _kernel_vector([[A_[i][j] - int(i == j) for j in range(n)] for i in range(n)])
            z = [[c] for c in u] + [[-r[0]] for r in _mul(Cx, [[c] for c in u])]  # (v; -C v)
            for T in (1, n, n + 2):
                O = _augmented_O(A_, Cx, T)
                deficiency.append(n + q - _rank(O))
                in_kernel &= all(r[0] == 0 for r in _mul(O, z))
            instances += 1
    if not (symbolic and in_kernel and min(deficiency) >= 1):
        raise AssertionError("the constant-attack check did not come out as expected")
    return Finding(
        "holds",
        "If A v = v with v != 0, then (x(0); a) = (v; -C v) gives y(k) = C A^k v - C v = 0 for "
        "every k, the same outputs as x(0) = 0, a = 0: O'_T has a kernel vector with nonzero "
        "x-part for every T, so x(0) cannot be recovered (sympy verifies the block rows for a "
        "symbolic A and C). Exact rational checks on random A with a simple, repeated or "
        "defective (Jordan) eigenvalue 1, C with zero rows, T = 1, n, n + 2, found (v; -C v) in "
        "the kernel every time. (By the PBH test the converse also holds for observable (A, C): "
        "without an eigenvalue 1 the augmented pair is observable.) Slips in the derivation, none "
        "affecting the proposition: (4.17) writes O_n for O_T, and in (4.24) the second block row "
        "should be (C(A - I), 0), not (C(A - I), I).",
        {
            "method": "symbolic+randomised",
            "symbolic": "sympy: C A^k e1 - C e1 = 0 for k = 0, ..., 4, A with first column e1 "
            "and its other entries symbols, C a symbolic 2 x 3 matrix",
            "distribution": "A = P J P^-1, J upper triangular with a simple 1, a repeated 1 or a "
            "Jordan block at 1 and other rationals p/r, p in -3..3, r in 1..3; P integer in -2..2 "
            "(invertible); C integer in -2..2 with a zero first row 30% of the time; n in 2..4, q in "
            "1..3; seed 7",
            "instances": instances,
            "min_rank_deficiency_of_O_prime_T": min(deficiency),
            "how": "exact rational arithmetic (fractions)",
        },
    )
