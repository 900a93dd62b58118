"""Numerical building blocks: eigenvalue groups, staircase, subspaces, colex engine."""

import itertools
import math

import numpy as np
import pytest
from scipy.linalg import block_diag

from ssecert.numerics.linalg import (
    eigen_clusters,
    screen_positive_definite,
    sensor_subspaces,
    stacked_rank,
    staircase,
)
from ssecert.structure._combinatorics import colex_blocks, colex_rank, colex_unrank


def jordan(lam, m):
    return lam * np.eye(m) + np.diag(np.ones(m - 1), 1)


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("orthogonal", [True, False])
def test_jordan_structure_is_recovered(seed, orthogonal):
    rng = np.random.default_rng(seed)
    B = block_diag(jordan(0.7, 3), jordan(-0.5, 2), [[0.3, 0.8], [-0.8, 0.3]], [[0.7]])
    n = B.shape[0]
    T = np.linalg.qr(rng.standard_normal((n, n)))[0] if orthogonal else rng.standard_normal((n, n))
    A = T @ B @ np.linalg.inv(T)
    eig = eigen_clusters(A)
    assert eig.ok, eig.problems
    found = sorted(
        (round(c.center.real, 5), round(abs(c.center.imag), 5), c.algebraic, c.geometric)
        for c in eig.clusters
    )
    assert found == [(-0.5, 0.0, 2, 1), (0.3, 0.8, 1, 1), (0.7, 0.0, 4, 2)]
    for c in eig.clusters:
        residual = np.linalg.norm(A @ c.basis - c.center * c.basis) / np.linalg.norm(A, 2)
        assert residual < 1e-9
        assert np.allclose(c.basis.conj().T @ c.basis, np.eye(c.geometric), atol=1e-10)


def test_identity_is_one_group_with_full_eigenspace():
    eig = eigen_clusters(np.eye(6))
    assert len(eig.clusters) == 1
    assert eig.clusters[0].geometric == 6 and eig.clusters[0].is_real


def test_exact_jordan_block():
    eig = eigen_clusters(np.array([[1.0, 1.0], [0.0, 1.0]]))
    (c,) = eig.clusters
    assert c.algebraic == 2 and c.geometric == 1
    assert np.allclose(np.abs(c.basis[:, 0]), [1.0, 0.0])


def test_unresolvable_eigenvalues_are_reported_not_guessed():
    # two distinct eigenvalues 1e-13 apart with orthogonal eigenvectors: grouped they
    # leave A - mu I with two borderline singular values; neither answer is trusted
    eig = eigen_clusters(np.diag([0.5, 0.5 + 1e-13, 2.0]))
    assert not eig.ok
    assert any("0.5" in p for p in eig.problems)


def test_eigenvalues_equal_to_rounding_form_a_jordan_group():
    # coupling 1 and a gap of 1e-14: a Jordan block to working precision
    A = np.diag([0.5, 0.5 + 1e-14, 2.0])
    A[0, 1] = 1.0
    eig = eigen_clusters(A)
    assert eig.ok
    group = next(c for c in eig.clusters if abs(c.center - 0.5) < 1e-9)
    assert group.algebraic == 2 and group.geometric == 1


def test_complex_pairs_are_kept_once():
    A = block_diag([[0.0, -2.0], [2.0, 0.0]], [[1.0]])
    eig = eigen_clusters(A)
    assert len(eig.clusters) == 2
    pair = [c for c in eig.clusters if c.conjugate_pair]
    assert len(pair) == 1 and pair[0].center.imag > 0


def test_staircase_is_reliable_where_the_rank_of_o_n_is_not():
    A = np.diag(np.linspace(0.1, 0.95, 20))
    C = np.ones((1, 20))
    O = np.vstack([C @ np.linalg.matrix_power(A, k) for k in range(20)])
    assert np.linalg.matrix_rank(O) < 20  # the unreliable test
    sc = staircase(A, C)
    assert sc.rank == 20 and sc.index == 20 and not sc.problem
    assert np.allclose(sc.basis @ sc.basis.T, np.eye(20), atol=1e-10)


@pytest.mark.parametrize("seed", range(20))
def test_staircase_index_matches_rank_of_o_k_on_well_conditioned_plants(seed):
    rng = np.random.default_rng(seed)
    n, p = int(rng.integers(2, 7)), int(rng.integers(1, 4))
    A = np.linalg.qr(rng.standard_normal((n, n)))[0]  # orthogonal: O_k well conditioned
    C = rng.standard_normal((p, n))
    sc = staircase(A, C)
    ranks = [
        np.linalg.matrix_rank(np.vstack([C @ np.linalg.matrix_power(A, j) for j in range(k)]))
        for k in range(1, n + 1)
    ]
    assert sc.rank == ranks[-1]
    assert sc.index == next(k for k, r in enumerate(ranks, start=1) if r == sc.rank)
    assert list(np.cumsum(sc.block_sizes)) == sorted(set(ranks))[: len(sc.block_sizes)]


def test_staircase_finds_unobservable_direction():
    A = block_diag(jordan(0.5, 2), [[0.9]])
    C = np.array([[1.0, 0.0, 0.0]])
    sc = staircase(A, C)
    assert sc.rank == 2
    z = sc.unobservable_direction()
    assert np.allclose(np.abs(z), [0.0, 0.0, 1.0], atol=1e-12)


def test_staircase_rejects_unknown_error_model():
    with pytest.raises(ValueError, match="error_model"):
        staircase(np.eye(2), np.eye(2), error_model="fast")


def test_sensor_subspaces_match_individual_staircases():
    rng = np.random.default_rng(5)
    A = block_diag(jordan(0.3, 2), [[0.8]], [[-0.4]])
    C = rng.standard_normal((5, 4))
    C[1, [0, 1]] = 0.0  # sensor 1 does not see the Jordan block
    C[2] = 0.0  # a dead sensor
    sub = sensor_subspaces(A, C)
    for i in range(5):
        assert sub.ranks[i] == staircase(A, C[[i]]).rank
    assert sub.ranks[2] == 0 and sub.ranks[1] == 2
    P = sub.projectors()
    for i in range(5):
        assert np.allclose(P[i] @ P[i], P[i], atol=1e-10)
        assert np.trace(P[i]) == pytest.approx(sub.ranks[i])


def test_screen_positive_definite_is_per_matrix():
    mats = np.stack([np.eye(3), np.diag([1.0, -1.0, 1.0]), np.diag([1.0, 1.0, 0.0]), 2 * np.eye(3)])
    assert screen_positive_definite(mats, 0.0).tolist() == [True, False, False, True]
    assert screen_positive_definite(mats, 1.5).tolist() == [False, False, False, True]


def test_stacked_rank_decisions():
    full = np.eye(3)[None]
    deficient = np.array([[[1.0, 0, 0], [0, 1.0, 0], [1.0, 1.0, 0]]])
    tiny = np.diag([1.0, 1.0, 1e-14])[None]
    codes, rel, null = stacked_rank(np.concatenate([full, deficient, tiny]))
    assert codes.tolist() == [2, 0, 1]
    assert np.allclose(np.abs(null[1]), [0, 0, 1])


@pytest.mark.parametrize("q, n", [(7, 2), (9, 3)])
@pytest.mark.parametrize("memory", [1, 300, 10**9])
def test_colex_blocks_cover_every_subset_once(q, n, memory):
    rng = np.random.default_rng(q)
    items = rng.standard_normal((q, n, n))
    base = rng.standard_normal((n, n))
    for k in range(q + 1):
        seen = set()
        for block in colex_blocks(items, base, k, memory=memory, chunk_bytes=256):
            for r, (subset, M) in enumerate(zip(block.subsets(), block.matrices)):
                key = tuple(int(i) for i in subset)
                assert key not in seen
                seen.add(key)
                assert colex_rank(key) == block.offset + r
                assert colex_unrank(block.offset + r, k) == key
                np.testing.assert_allclose(M, base - items[list(key)].sum(axis=0), atol=1e-12)
        assert len(seen) == math.comb(q, k)
        assert seen == set(itertools.combinations(range(q), k))
