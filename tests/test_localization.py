"""RSS fingerprinting: the path-loss dictionary and the elastic-net localization.

* the path-loss model (6.2) decays monotonically, 10 alpha dB per decade;
* every sensor's fingerprints decay with the distance to the cell;
* the fixed point of Algorithm 3 is the cvxpy minimiser of the objective the
  result reports (ISTA and FISTA, Lasso and elastic net);
* noise-free snapshots with few attacked sensors are decoded (cell and
  attacked sensors); too many attacks give a flagged answer, not a crash;
* batched snapshots equal single ones; bad inputs name the argument.
"""

import cvxpy as cp
import numpy as np
import pytest

from ssecert.estimators.localization import (
    elastic_net_localization,
    localization_scenario,
    path_loss_rss,
    rss_dictionary,
)


def test_path_loss_decays_monotonically_ten_alpha_db_per_decade():
    d = np.geomspace(1e-3, 1e3, 400)
    for alpha in (2.0, 3.5):
        rss = path_loss_rss(d, P_t=20.0, P_l=40.0, alpha=alpha, d0=1.0)
        far = d > 1.0
        assert np.all(np.diff(rss[far]) < 0)  # strictly decreasing beyond d0
        assert np.all(rss[~far] == rss[~far][0])  # saturated at RSS(d0) inside
        assert rss[~far][0] == pytest.approx(20.0 - 40.0)
        ten = path_loss_rss(10 * d[far], P_t=20.0, P_l=40.0, alpha=alpha, d0=1.0)
        assert np.allclose(rss[far] - ten, 10 * alpha, rtol=0, atol=1e-12)


@pytest.mark.parametrize("deployment", ["random", "grid"])
def test_dictionary_rows_decay_with_distance(deployment):
    dic = rss_dictionary(
        grid=(6, 8), cell_size=0.5, q=12, deployment=deployment, seed=3, alpha=2.5, d0=0.3
    )
    assert dic.D.shape == (12, 48) and dic.n == 48 and dic.q == 12
    width, height = 8 * 0.5, 6 * 0.5
    assert np.all((dic.sensor_positions >= 0) & (dic.sensor_positions <= [width, height]))
    # cell j is row j // cols, column j % cols, centres half a cell in
    assert np.allclose(dic.cell_centers[9], [0.75, 0.75])
    for i in range(12):
        dist = np.linalg.norm(dic.cell_centers - dic.sensor_positions[i], axis=1)
        order = np.argsort(dist)
        rss, dd = dic.D[i, order], dist[order]
        assert np.all(np.diff(rss) <= 0)
        strict = (dd[1:] > dd[:-1] * (1 + 1e-12)) & (dd[:-1] > 0.3)
        assert np.all(np.diff(rss)[strict] < 0)
        assert np.allclose(
            dic.D[i], path_loss_rss(dist, P_t=dic.P_t, P_l=dic.P_l, alpha=2.5, d0=0.3)
        )


def test_dictionary_is_reproducible_from_its_seed():
    a, b, c = (rss_dictionary(seed=s) for s in (1, 1, 2))
    assert np.array_equal(a.D, b.D)
    assert not np.array_equal(a.D, c.D)
    grid = rss_dictionary(deployment="grid", q=20)
    assert len({tuple(p) for p in grid.sensor_positions}) == 20


# -- Algorithm 3 against cvxpy --------------------------------------------------


def preprocessed(D, y):
    """G~, y~, column norms: G = [D I] and y with the common offset removed, unit columns."""
    G = np.hstack([D, np.eye(D.shape[0])])
    G = G - G.mean(axis=0)
    w = np.linalg.norm(G, axis=0)
    return G / w, y - y.mean(), w


@pytest.mark.parametrize(
    "method, q_x, q_a", [("fista", 1.0, 1.0), ("fista", 0.99, 0.95), ("ista", 0.98, 0.98)]
)
def test_fixed_point_is_the_cvxpy_minimiser_of_the_reported_objective(method, q_x, q_a):
    dic = rss_dictionary(grid=(4, 4), q=8, seed=5)
    y = dic.D[:, 6] + 12.0 * np.eye(8)[2]
    res = elastic_net_localization(dic.D, y, method=method, q_x=q_x, q_a=q_a, N=200000, rtol=1e-13)
    assert res.converged
    Gt, yt, w = preprocessed(dic.D, y)
    ob = res.objective
    n = dic.n
    z = cp.Variable(n + 8)
    cost = (
        0.5 * cp.sum_squares(Gt @ z - yt)
        + ob["l1_x"] * cp.norm1(z[:n])
        + ob["l1_a"] * cp.norm1(z[n:])
        + 0.5 * ob["mu_x"] * cp.sum_squares(z[:n])
        + 0.5 * ob["mu_a"] * cp.sum_squares(z[n:])
    )
    cp.Problem(cp.Minimize(cost)).solve(
        solver="CLARABEL", tol_gap_abs=1e-12, tol_gap_rel=1e-12, tol_feas=1e-12
    )
    ours = np.concatenate([res.x_hat, res.a_hat]) * w
    assert np.allclose(ours, z.value, rtol=0, atol=1e-6 * np.abs(z.value).max())


# -- decoding -------------------------------------------------------------------


@pytest.mark.slow
def test_finds_the_cell_and_a_spoofed_sensor_without_noise():
    exact = total = 0
    for seed in range(10):
        dic = rss_dictionary(seed=seed)
        sc = localization_scenario(dic, runs=4, attacked=1, seed=seed)
        y = dic.D[:, sc.cell].T + np.abs(sc.attack)  # the attacker raises one reading
        res = elastic_net_localization(dic.D, y)
        assert np.array_equal(res.cell, sc.cell), seed
        assert np.all(res.attacked[sc.attacked]), seed  # no attacked sensor missed
        exact += int(np.sum(np.all(res.attacked == sc.attacked, axis=1)))
        total += 4
    assert exact >= 0.9 * total


@pytest.mark.slow
def test_few_attacked_sensors_with_random_signs():
    hits = total = 0
    for seed in range(10):
        dic = rss_dictionary(seed=100 + seed)
        for attacked in (1, 2):
            sc = localization_scenario(dic, runs=4, attacked=attacked, seed=seed)
            res = elastic_net_localization(dic.D, sc.y)
            ok = (res.cell == sc.cell) & np.all(res.attacked == sc.attacked, axis=1)
            hits += int(ok.sum())
            total += 4
            assert res.identifiable.all()
    assert hits >= 0.75 * total


def test_unknown_transmit_power_is_absorbed_by_the_common_offset():
    dic = rss_dictionary(seed=4)
    sc = localization_scenario(dic, runs=5, attacked=1, seed=4)
    y = dic.D[:, sc.cell].T + np.abs(sc.attack) - 6.0  # the target transmits 6 dB weaker
    res = elastic_net_localization(dic.D, y)
    assert np.array_equal(res.cell, sc.cell)
    assert np.all(np.abs(res.offset + 6.0) < 0.1)


@pytest.mark.slow
def test_batched_snapshots_equal_single_ones():
    dic = rss_dictionary(seed=8)
    sc = localization_scenario(dic, runs=5, attacked=2, seed=8)
    batch = elastic_net_localization(dic.D, sc.y)
    for r in range(5):
        one = elastic_net_localization(dic.D, sc.y[r])
        assert int(one.cell) == int(batch.cell[r])
        assert np.array_equal(one.attacked, batch.attacked[r])
        assert np.allclose(one.x_hat, batch.x_hat[r], rtol=0, atol=1e-9)
        assert one.iterations == batch.iterations[r]
    assert len(batch.attacked_sensors()) == 5


@pytest.mark.slow
def test_too_many_attacks_give_a_flagged_answer_not_a_crash():
    dic = rss_dictionary(seed=0)
    sc = localization_scenario(dic, runs=6, attacked=15, seed=0)
    res = elastic_net_localization(dic.D, sc.y)
    assert res.cell.shape == (6,) and np.all((res.cell >= 0) & (res.cell < dic.n))
    assert res.attacked.shape == (6, 20) and res.attacked.dtype == bool
    assert np.all(np.isfinite(res.x_hat)) and np.all(np.isfinite(res.a_hat))
    # more than q / 2 - 1 attacked sensors: no sparse explanation is unique
    assert not res.identifiable.any()
    assert np.all(res.attacked.sum(axis=1) > 9)


def test_thesis_literal_settings_run_and_stop_after_N_iterations():
    dic = rss_dictionary(seed=1)
    sc = localization_scenario(dic, runs=3, attacked=5, seed=1)
    res = elastic_net_localization(
        dic.D, sc.y, normalize=False, common_offset=False, method="ista", N=1000, rtol=0
    )
    assert np.all(res.iterations == 1000) and not res.converged.any()
    assert np.all((res.cell >= 0) & (res.cell < dic.n))
    assert np.all(res.offset == 0)


# -- bad inputs -----------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, error, name",
    [
        (dict(q_x=0.0), ValueError, "q_x"),
        (dict(q_a=1.5), ValueError, "q_a"),
        (dict(method="istaa"), ValueError, "method"),
        (dict(epsilon=10.0), ValueError, "epsilon"),
        (dict(normalize="yes"), TypeError, "normalize"),
        (dict(N=0), ValueError, "N"),
        (dict(lambda_x=-1.0), ValueError, "lambda_x"),
        (dict(targets=0), ValueError, "targets"),
        (dict(L2="1"), TypeError, "L2"),
    ],
)
def test_bad_localization_options_name_the_argument(kwargs, error, name):
    dic = rss_dictionary(grid=(3, 3), q=4, seed=0)
    with pytest.raises(error, match=rf"\b{name}\b"):
        elastic_net_localization(dic.D, dic.D[:, 0], **kwargs)


def test_bad_shapes_and_dictionary_options_name_the_argument():
    dic = rss_dictionary(grid=(3, 3), q=4, seed=0)
    with pytest.raises(ValueError, match=r"\by\b"):
        elastic_net_localization(dic.D, np.zeros(5))
    with pytest.raises(ValueError, match=r"\bD\b"):
        elastic_net_localization(np.zeros(4), np.zeros(4))
    with pytest.raises(ValueError, match=r"grid\[0\]"):
        rss_dictionary(grid=(0, 10))
    with pytest.raises(TypeError, match="grid"):
        rss_dictionary(grid=10)
    with pytest.raises(ValueError, match="alpha"):
        rss_dictionary(alpha=0.0)
    with pytest.raises(ValueError, match="d0"):
        path_loss_rss([1.0], d0=-1.0)
    with pytest.raises(ValueError, match=r"\bd\b"):
        path_loss_rss([-1.0])
    with pytest.raises(ValueError, match="sensor_positions"):
        rss_dictionary(sensor_positions=np.zeros((3, 3)))
    with pytest.raises(ValueError, match="deployment"):
        rss_dictionary(deployment="line")
    with pytest.raises(ValueError, match="attacked"):
        localization_scenario(dic, attacked=5)
    with pytest.raises(TypeError, match="dictionary"):
        localization_scenario(dic.D)
