"""Every holds verdict re-verifies from its JSON evidence, with code independent of ssecert.

The checks below read only the JSON document (what a user or a reviewer has) and
decide in exact rational arithmetic (Python fractions), sharing nothing with the
package's numerics.  Also: methods that answer the same question agree with the
field's libraries where both apply (our deadbeat gain and control.place).
"""

from __future__ import annotations

import itertools
import json
from fractions import Fraction

import control
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from planted import exact_rank as _rank

from ssecert import System, analyze, spec_from_dict
from ssecert.design.gains import deadbeat_gain, verify_deadbeat
from ssecert.examples import load_example


def _q(M):
    return [[Fraction(float(x)) for x in row] for row in np.atleast_2d(np.asarray(M, float))]


def _mul(X, Y):
    return [
        [sum(X[i][k] * Y[k][j] for k in range(len(Y))) for j in range(len(Y[0]))]
        for i in range(len(X))
    ]


def _obsv_rank(A, C, steps):
    rows, block = [], C
    for _ in range(steps):
        rows.extend(block)
        block = _mul(block, A)
    return _rank(rows) if rows else 0


def _positive_definite(S):
    """Sylvester: every leading principal minor > 0 (Gaussian elimination on fractions)."""
    M = [list(r) for r in S]
    n = len(M)
    for k in range(n):
        if M[k][k] <= 0:
            return False
        for r in range(k + 1, n):
            f = M[r][k] / M[k][k]
            M[r] = [a - f * b for a, b in zip(M[r], M[k])]
    return True


def _reverify(document, A, C):
    """Re-verify every holds verdict of a JSON certificate; returns the ids verified."""
    checks = document["checks"]
    n, p = len(A), len(C)
    done = []
    obs = checks["observability"]
    if obs["verdict"] == "holds":
        k = obs["observability_index"]
        assert _obsv_rank(A, C, k) == n and (k == 1 or _obsv_rank(A, C, k - 1) < n)
        done.append("observability")
    sparse = checks["sparse_observability"]
    if sparse["verdict"] == "holds":
        mr, s = sparse["max_removable"], sparse["max_attacked"]
        assert 2 * s <= mr
        for size in range(mr + 1):
            for removed in itertools.combinations(range(p), size):
                kept = [C[i] for i in range(p) if i not in removed]
                assert _obsv_rank(A, kept, n) == n, removed
        if sparse["breaking_set"] is not None:
            kept = [C[i] for i in range(p) if i not in sparse["breaking_set"]]
            assert not kept or _obsv_rank(A, kept, n) < n
            assert len(sparse["breaking_set"]) == mr + 1
        done.append("sparse_observability")
    gain = checks.get("observer_gain")
    if gain is not None and gain["verdict"] == "holds":
        L = _q(gain["L"])
        F = [[a - b for a, b in zip(ra, rb)] for ra, rb in zip(A, _mul(L, C))]
        if gain["gain_method"] == "deadbeat":
            m = gain["evidence"]["details"]["upper_bound_power"]
            P = F
            for _ in range(m - 1):
                P = _mul(P, F)
            norm = max(sum(abs(x) for x in row) for row in P)
            assert norm < 1  # rho(F)^m <= ||F^m||_inf < 1
        elif gain["evidence"].get("certificate") == "lyapunov":
            P = _q(gain["evidence"]["P"])
            decrease = [
                [a - b for a, b in zip(ra, rb)]
                for ra, rb in zip(P, _mul(_mul(list(map(list, zip(*F))), P), F))
            ]
            assert _positive_definite(P) and _positive_definite(decrease)
        done.append("observer_gain")
    return done


@pytest.mark.parametrize("gain", ["deadbeat", "place", "matrix"])
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(1, 4),
    extra=st.integers(0, 2),
    s=st.integers(0, 1),
)
@settings(max_examples=max(5, settings.default.max_examples // 4))
def test_holds_verdicts_reverify_from_json_in_exact_arithmetic(gain, seed, n, extra, s):
    rng = np.random.default_rng(seed)
    p = n + extra + 1
    A = np.round(rng.standard_normal((n, n)), 3)
    C = np.round(rng.standard_normal((p, n)), 3)
    if rng.random() < 0.3:  # structural zeros make breaking sets
        C[rng.integers(p), rng.integers(n)] = 0.0
        C[:, rng.integers(n)] *= rng.random() < 0.5
    observer: dict = {"kind": "luenberger", "gain": gain}
    if gain == "place":
        observer["poles"] = list(np.round(np.linspace(-0.5, 0.5, n), 3))
    if gain == "matrix":
        observer["gain"] = (0.3 * rng.standard_normal((n, p))).tolist()
    spec = spec_from_dict(
        {
            "name": "r",
            "system": {"A": A.tolist(), "C": C.tolist()},
            "attack": {"max_attacked": s},
            "observer": observer,
        }
    )
    try:
        cert = analyze(spec)
    except Exception as exc:  # GainError is bad input for the CLI, not a verdict
        from ssecert.design.gains import GainError

        if isinstance(exc, GainError):
            return
        raise
    document = json.loads(json.dumps(cert.to_dict()))
    _reverify(document, _q(A), _q(C))


@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 5), extra=st.integers(0, 3))
def test_deadbeat_agrees_with_control_place_where_both_apply(seed, n, extra):
    """With rank(C) = n, control.place can put every pole at 0; both gains are then
    deadbeat, verified on their printed floats, and ours has the minimal index, 1."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    C = rng.standard_normal((n + extra, n))
    ours = deadbeat_gain(System(A, C))
    L_place = np.asarray(control.place(A.T, C.T, np.zeros(n))).T
    theirs = verify_deadbeat(A, L_place, C)
    assert ours.verified and ours.details["nilpotency_index"] == 1
    assert theirs.verified and theirs.index >= ours.details["nilpotency_index"]


@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 6))
def test_deadbeat_goes_where_control_place_cannot(seed, n):
    """With fewer sensors than states, place refuses n poles at 0; ours reaches the
    observability index, which no gain can beat."""
    rng = np.random.default_rng(seed)
    p = int(rng.integers(1, n))
    A, C = rng.standard_normal((n, n)), rng.standard_normal((p, n))
    with pytest.raises(ValueError, match="repeated"):
        control.place(A.T, C.T, np.zeros(n))
    gain = deadbeat_gain(System(A, C))
    if gain.verified:
        assert gain.details["nilpotency_index"] == gain.details["observability_index"]
        assert gain.details["spectral_radius_upper_bound"] < 1


def _zames_falb_lmi(model, P, m0, a, b):
    """The Zames-Falb LMI of the module docstring rebuilt in fractions from the JSON alone.

    z = (xi, u(k-1..k-K), v(k-1..k-K), u(k)); zeta+ = (A xi + B u, u, u(k-1..k-K+1), v,
    v(k-1..k-K+1)) with v = q Cw xi - u; M = G' P G - diag(P, 0) + multiplier terms.
    """
    A, B, Cw = _q(model["A"]), _q(model["B"]), _q(model["Cw"])
    q = Fraction(float(model["q"]))
    N, m, K = len(A), len(B[0]), len(a)
    D = N + 2 * m * K
    Z = D + m
    zero = Fraction(0)

    def row(entries):
        r = [zero] * Z
        for j, x in entries:
            r[j] += x
        return r

    u_now = [row([(D + i, Fraction(1))]) for i in range(m)]
    u_old = [[row([(N + m * j + i, Fraction(1))]) for i in range(m)] for j in range(K)]
    v_old = [[row([(N + m * (K + j) + i, Fraction(1))]) for i in range(m)] for j in range(K)]
    v_now = [row([(c, q * Cw[i][c]) for c in range(N)] + [(D + i, Fraction(-1))]) for i in range(m)]
    xi_next = [
        row([(c, A[r][c]) for c in range(N)] + [(D + i, B[r][i]) for i in range(m)])
        for r in range(N)
    ]
    G = xi_next + u_now + [x for j in range(K - 1) for x in u_old[j]]
    G += v_now + [x for j in range(K - 1) for x in v_old[j]]
    Pq = _q(P)
    GT = list(map(list, zip(*G)))
    M = _mul(_mul(GT, Pq), G)
    for r in range(D):
        for c in range(D):
            M[r][c] -= Pq[r][c]

    def add_sym(x, y, coef):
        for r in range(Z):
            for c in range(Z):
                M[r][c] += coef * (x[r] * y[c] + y[r] * x[c]) / 2

    for i in range(m):
        add_sym(v_now[i], u_now[i], Fraction(float(m0[i])))
        for j in range(K):
            add_sym(v_now[i], u_old[j][i], -Fraction(float(a[j][i])))
            add_sym(v_old[j][i], u_now[i], -Fraction(float(b[j][i])))
    return M


def test_a_zames_falb_certificate_reverifies_from_json_in_exact_arithmetic():
    # the README's example: the circle criterion finds nothing, a multiplier of order 2 certifies
    spec = spec_from_dict(
        {
            "name": "zf",
            "system": {
                "A": [[-0.4, -0.9], [1.1, -0.4]],
                "C": [[0.9, -0.2], [0.7, 0.5], [0.8, 0.7]],
            },
            "attack": {"max_attacked": 1},
            "observer": {"kind": "elastic_net", "gain": "deadbeat", "step": 1.0,
                         "threshold": 0.1, "shrink": 0.8},
        }
    )  # fmt: skip
    document = json.loads(json.dumps(analyze(spec).to_dict()))
    check = document["checks"]["observer_stability"]
    assert check["verdict"] == "holds" and check["method"].startswith("Zames-Falb")
    ev = check["evidence"]
    m0, a, b = ev["multipliers_m0"], ev["u_delays"], ev["v_delays"]
    for i in range(len(m0)):  # m0_i >= sum_j |a_ji| + |b_ji|, exactly
        total = sum(abs(Fraction(float(row[i]))) for row in a + b)
        assert Fraction(float(m0[i])) >= total
    assert _positive_definite(_q(ev["P"]))
    M = _zames_falb_lmi(ev["model"], ev["P"], m0, a, b)
    assert _positive_definite([[-x for x in r] for r in M])


def _lasso_terms_exact(O, S, eta_rows):
    """rho_S, delta_S, beta_S^2 and kappa_S^2 of one support in exact arithmetic: rows S of the
    stacked O attacked, the others K; the noise within eta_rows (per sample) on K."""
    rows = range(len(O))
    K = [r for r in rows if r not in S]
    OK, OS = [O[r] for r in K], [O[r] for r in S]
    n = len(O[0])
    G = _mul(list(map(list, zip(*OK))), OK)
    # G^-1 by Gauss-Jordan in fractions
    aug = [G[i][:] + [Fraction(int(i == j)) for j in range(n)] for i in range(n)]
    for c in range(n):
        pivot = next(r for r in range(c, n) if aug[r][c] != 0)
        aug[c], aug[pivot] = aug[pivot], aug[c]
        aug[c] = [x / aug[c][c] for x in aug[c]]
        for r in range(n):
            if r != c and aug[r][c] != 0:
                aug[r] = [x - aug[r][c] * y for x, y in zip(aug[r], aug[c])]
    Ginv = [row[n:] for row in aug]
    N = _mul(Ginv, list(map(list, zip(*OK))))  # n x |K|
    Z = _mul(Ginv, list(map(list, zip(*OS)))) if OS else [[] for _ in range(n)]
    M = _mul(OK, Z) if OS else [[] for _ in K]
    rho = max((sum(abs(x) for x in row) for row in M), default=Fraction(0))
    P = _mul(OK, N)
    R = [[Fraction(int(i == j)) - P[i][j] for j in range(len(K))] for i in range(len(K))]
    eta_K = [eta_rows[r] for r in K]
    delta = max(sum(abs(x) * e for x, e in zip(row, eta_K)) for row in R)
    beta2 = max(
        sum(
            sum(N[i][j] * sg * e for j, (sg, e) in enumerate(zip(signs, eta_K))) ** 2
            for i in range(n)
        )
        for signs in itertools.product((-1, 1), repeat=len(K))
    )
    kappa2 = max(
        (
            sum(sum(Z[i][j] * sg for j, sg in enumerate(signs)) ** 2 for i in range(n))
            for signs in itertools.product((-1, 1), repeat=len(S))
        ),
        default=Fraction(0),
    )
    return rho, delta, beta2, kappa2


def _decoder_bound_from_json(check_id):
    """A decoder bound's JSON on a five-sensor, two-state plant (s = 1, one step, noise per
    sensor), the stacked observability matrix of the spec's data in fractions, p, tau and the
    printed noise bounds as fractions."""
    spec = spec_from_dict(
        {
            "name": "decoder-reverify",
            "system": {"A": [[1, 1], [0, 1]], "C": [[1, 0], [0, 1], [1, 0], [0, 1], [1, 1]]},
            "attack": {"max_attacked": 1, "horizon": 1},
            "noise": {"measurement": [0.01, 0.02, 0.01, 0.03, 0.01]},
        }
    )
    doc = json.loads(json.dumps(analyze(spec).to_dict()))
    check = doc["checks"][check_id]
    assert check["verdict"] == "holds"
    A, C = _q(spec.system.A), _q(spec.system.C)  # the spec's data, as its file holds them
    p, tau = len(C), check["horizon"]
    O, block = [], C
    for _ in range(tau):
        O.extend(block)
        block = _mul(block, A)
    return check, O, p, tau, [Fraction(x) for x in check["noise"]["measurement"]]


def test_the_lasso_bound_reverifies_from_json_in_exact_arithmetic():
    """From the JSON alone: every support's irrepresentable constant is at most the printed one
    and below 1, lambda_min clears every support's delta / (1 - rho), and the printed bound is at
    least beta_S + lambda_min kappa_S on every support (the noise's worst signs and the
    subgradients' enumerated exactly)."""
    check, O, p, tau, eta = _decoder_bound_from_json("lasso_error_bound")
    eta_rows = [eta[r % p] for r in range(len(O))]
    lam = Fraction(check["lambda_min"])
    bound = Fraction(check["bound"])
    for support in itertools.combinations(range(p), 1):
        S = [t * p + i for t in range(tau) for i in support]
        rho, delta, beta2, kappa2 = _lasso_terms_exact(O, S, eta_rows)
        assert rho <= Fraction(check["irrepresentable_constant"]) and rho < 1
        assert lam * (1 - rho) >= delta
        # bound >= sqrt(beta2) + lam sqrt(kappa2), squared twice: with X = bound^2 + beta2 -
        # lam^2 kappa2, bound >= sqrt(beta2), X >= 0 and X^2 >= 4 bound^2 beta2
        X = bound**2 + beta2 - lam**2 * kappa2
        assert bound**2 >= beta2 and X >= 0 and 4 * bound**2 * beta2 <= X**2
    assert Fraction(check["lower_bound"]) <= bound


def _l1_ratio_exact(OK, OS):
    """max ||O_S e||_1 / ||O_K e||_1 over e != 0 in the plane, exactly: both norms are linear
    on each cone between the lines o^T e = 0 of the rows o of O_K and O_S, so the ratio's
    maximum is on one of those lines (a direction perpendicular to a row)."""
    best = Fraction(0)
    for o in OK + OS:
        if o[0] == 0 and o[1] == 0:
            continue
        d = (-o[1], o[0])
        below = sum(abs(r[0] * d[0] + r[1] * d[1]) for r in OK)
        assert below > 0  # O_K has full column rank: no direction it does not see
        best = max(best, sum(abs(r[0] * d[0] + r[1] * d[1]) for r in OS) / below)
    return best


def test_the_l1_bound_reverifies_from_json_in_exact_arithmetic():
    """From the JSON alone, on a two-state plant: every set's null-space constant (its exact
    maximum over the plane) is at most the printed one and below 1, and the printed bound is
    at least 2 ||w_K||_1 ||O_K^+||_(1->2) / (1 - theta_S) on every set of s sensors, the
    pseudo-inverse's columns formed exactly."""
    check, O, p, tau, eta = _decoder_bound_from_json("l1_error_bound")
    bound, theta = Fraction(check["bound"]), Fraction(check["null_space_constant"])
    assert theta < 1
    tightest = Fraction(0)
    for support in itertools.combinations(range(p), 1):
        S = [t * p + i for t in range(tau) for i in support]
        K = [r for r in range(len(O)) if r not in S]
        OK, OS = [O[r] for r in K], [O[r] for r in S]
        theta_S = _l1_ratio_exact(OK, OS)
        assert theta_S <= theta
        # ||O_K^+||_(1->2)^2: the largest squared column norm of (O_K' O_K)^-1 O_K'
        (a, b), (c, d) = _mul(list(map(list, zip(*OK))), OK)
        inverse = [
            [d / (a * d - b * c), -b / (a * d - b * c)],
            [-c / (a * d - b * c), a / (a * d - b * c)],
        ]
        pinv = _mul(inverse, list(map(list, zip(*OK))))
        reach2 = max(pinv[0][j] ** 2 + pinv[1][j] ** 2 for j in range(len(K)))
        noise = sum(eta[r % p] for r in K)  # ||w_K||_1 at most, per sample
        # bound (1 - theta_S) >= 2 noise reach, squared (both sides nonnegative)
        assert (bound * (1 - theta_S)) ** 2 >= 4 * noise**2 * reach2
        tightest = max(tightest, 4 * noise**2 * reach2 / (1 - theta_S) ** 2)
    # the printed bound is the largest of them, up to its certified error terms
    assert bound**2 <= tightest * (1 + Fraction(1, 10**9))


def _pwq_region_reverifies(model, cert):
    """The piecewise-quadratic region certificate (``ssecert.stability.piecewise``) checked
    again in fractions from the JSON alone: in z = (xi / threshold, 1), every region's
    function, every LMI with its multiplier, and every Farkas certificate of a transition or
    an initial region left out; returns the number of LMIs checked."""
    A, B, Cw = _q(model["A"]), _q(model["B"]), _q(model["Cw"])
    q, N, m, n = Fraction(float(model["q"])), len(A), len(B[0]), int(model["n_e"])
    zero, one = Fraction(0), Fraction(1)
    patterns = cert["patterns"]
    P = [_q(F) for F in cert["functions"]]
    alpha, r, R = (Fraction(float(cert[k])) for k in ("alpha", "radius", "ball"))
    level = R * R

    def G(k):
        rows = []
        for i, si in enumerate(patterns[k]):
            if si == 0:
                rows += [[-c for c in Cw[i]] + [one], [*Cw[i], one]]
            else:
                rows.append([si * c for c in Cw[i]] + [-one])
        return rows

    def T(k):
        s = patterns[k]
        rows = [
            [A[a][b] + q * sum((B[a][i] * Cw[i][b] for i in range(m) if s[i]), zero)
             for b in range(N)] + [-q * sum((B[a][i] * s[i] for i in range(m)), zero)]
            for a in range(N)
        ]  # fmt: skip
        return rows + [[zero] * N + [one]]

    def tr(X):
        return [list(r) for r in zip(*X)]

    def diag(values):
        return [[v if i == j else zero for j in range(len(values))] for i, v in enumerate(values)]

    def comb(*terms):
        out = [[zero] * len(terms[0][1][0]) for _ in terms[0][1]]
        for c, X in terms:
            out = [[o + c * x for o, x in zip(ro, rx)] for ro, rx in zip(out, X)]
        return out

    last = [[zero] * N + [one]]
    Z = [[one if (i == j < n) or (i == N and j == n) else zero for j in range(n + 1)]
         for i in range(N + 1)]  # fmt: skip
    Iq, E1 = diag([one] * N + [zero]), diag([zero] * N + [one])
    In, e1 = diag([one] * n + [zero]), diag([zero] * n + [one])
    # the mirrored regions' functions are the representatives' conjugated by J = diag(-I, 1)
    J = diag([-one] * N + [one])
    for k, s in enumerate(patterns):
        mirror = patterns.index([-v for v in s])
        assert P[k] == _mul(_mul(J, P[mirror]), J)
    # the dead zone's decrease: A' P0 A - P0 + alpha I < 0
    dead = patterns.index([0] * m)
    P0 = [row[:N] for row in P[dead][:N]]
    assert all(v == 0 for v in P[dead][N]) and all(row[N] == 0 for row in P[dead])
    D = comb((one, _mul(_mul(tr(A), P0), A)), (-one, P0), (alpha, diag([one] * N)))
    assert _positive_definite([[-x for x in row] for row in D])
    seen = set()
    for item in cert["lmis"]:
        k, j, kind = item["region"], item["to"], item["kind"]
        w, s = [Fraction(float(x)) for x in item["multiplier_last_row"]], Fraction(item["scalar"])
        assert min(w) >= 0 and s >= 0
        if kind == "outer":
            H = G(k) + last
        elif kind == "inner":
            H = _mul(G(k) + last, Z)
        else:
            H = G(k) + _mul(G(j), T(k)) + last
        W = [[w[b] if a == len(w) - 1 else (w[a] if b == len(w) - 1 else zero)
              for b in range(len(w))] for a in range(len(w))]  # fmt: skip
        HWH = _mul(_mul(tr(H), W), H)
        if kind == "outer":  # P_k - c E1 - s (Iq - c E1) - H'WH > 0
            M = comb((one, P[k]), (-level, E1), (-s, comb((one, Iq), (-level, E1))), (-one, HWH))
        elif kind == "inner":  # c e1 - Z' P_k Z - s (r^2 e1 - In) - H'WH > 0
            M = comb((level, e1), (-one, _mul(_mul(tr(Z), P[k]), Z)),
                     (-s, comb((r * r, e1), (-one, In))), (-one, HWH))  # fmt: skip
        else:  # T' P_j T - P_k + alpha Iq + H'WH + s (c E1 - Iq) < 0
            Tk = T(k)
            M = comb((-one, _mul(_mul(tr(Tk), P[j]), Tk)), (one, P[k]), (-alpha, Iq),
                     (-one, HWH), (-s, comb((level, E1), (-one, Iq))))  # fmt: skip
        assert _positive_definite(M), (kind, k, j)
        seen.add((kind, k, j))
    for item in cert["empty_transitions"] + cert["empty_initial"]:
        k = item["region"]
        y = [Fraction(float(x)) for x in item["farkas"]]
        if "to" in item:
            H, key = G(k) + _mul(G(item["to"]), T(k)), ("decrease", k, item["to"])
        else:
            H, key = _mul(G(k) + last, Z)[:-1], ("inner", k, k)
        assert min(y) >= 0
        combo = _mul([y], H)[0]
        assert combo[-1] + Fraction(float(item["box"])) * sum(abs(v) for v in combo[:-1]) < 0
        assert Fraction(float(item["box"])) >= (R if "to" in item else r)
        seen.add(key)
    # every representative region: its outer and inner LMIs, and every transition from it
    for k, s in enumerate(patterns):
        if patterns.index([-v for v in s]) < k:
            continue
        assert ("outer", k, k) in seen and ("inner", k, k) in seen
        for j in range(len(patterns)):
            assert k == j == dead or ("decrease", k, j) in seen, (k, j)
    return len(cert["lmis"])


@pytest.mark.slow
def test_the_piecewise_region_of_attraction_reverifies_from_json_in_exact_arithmetic():
    # the UGV's D-SSO (shrink 1, an eigenvalue at 1): no quadratic function certifies it;
    # the piecewise-quadratic one proves convergence from every initial error of norm <= 10
    document = json.loads(json.dumps(analyze(load_example("ugv")).to_dict()))
    region = document["checks"]["region_of_attraction"]
    assert region["verdict"] == "holds" and region["value"] == pytest.approx(10.0)
    model = document["checks"]["observer_stability"]["evidence"]["model"]
    cert = region["evidence"]["certificate"]
    assert Fraction(cert["radius"]) * Fraction(model["threshold"]) >= Fraction(region["value"])
    assert _pwq_region_reverifies(model, cert) > 300
    # a multiplier taken away, or a function changed, is caught
    broken = json.loads(json.dumps(cert))
    broken["lmis"][-1]["multiplier_last_row"] = [0.0] * len(
        broken["lmis"][-1]["multiplier_last_row"]
    )
    with pytest.raises(AssertionError):
        _pwq_region_reverifies(model, broken)
