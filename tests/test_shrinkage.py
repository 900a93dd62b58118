"""Shrinkage operators are the proximal maps they claim to be."""

import numpy as np
import pytest

from ssecert.estimators.shrinkage import elastic_net_shrink, soft_threshold, weighted_soft_threshold


@pytest.mark.parametrize("lam", [0.0, 0.3, 2.0])
def test_soft_threshold_is_the_l1_proximal_map(lam):
    x = np.linspace(-4, 4, 81)
    grid = np.linspace(-6, 6, 120001)
    objective = 0.5 * (grid[None, :] - x[:, None]) ** 2 + lam * np.abs(grid[None, :])
    brute = grid[np.argmin(objective, axis=1)]
    np.testing.assert_allclose(soft_threshold(x, lam), brute, atol=1e-4)


def test_elastic_net_shrink_is_the_elastic_net_proximal_map():
    x = np.linspace(-4, 4, 41)
    q, lam = 0.6, 0.5
    # argmin_z (1/2)||z - x||^2 + lam |z| + (delta/2) z^2 with delta = 1/q - 1 gives q S_lam(x)
    delta = 1 / q - 1
    grid = np.linspace(-6, 6, 120001)
    obj = (
        0.5 * (grid[None] - x[:, None]) ** 2
        + lam * np.abs(grid[None])
        + 0.5 * delta * grid[None] ** 2
    )
    np.testing.assert_allclose(
        elastic_net_shrink(x, lam, q), grid[np.argmin(obj, axis=1)], atol=1e-4
    )


def test_weighted_soft_threshold_broadcasts_per_component():
    x = np.ones((3, 2))
    out = weighted_soft_threshold(x, 0.5, np.array([0.0, 4.0]))
    assert out.shape == (3, 2) and np.all(out[:, 0] == 1.0) and np.all(out[:, 1] == 0.0)


def test_negative_threshold_is_refused():
    with pytest.raises(ValueError, match="threshold"):
        soft_threshold([1.0], -0.1)
