"""The enumeration's screening: LAPACK's decisions, bit for bit, with less of LAPACK.

The screening of the sensor sets' Gramians decides each set as LAPACK's
Cholesky factorization (``numpy.linalg.cholesky``) does and ranks the sets
closest to breaking by LAPACK's smallest pivot; a bound shared by the sets
with the same largest sensor and a single-precision factorization with the
batch last decide most sets without it.  The reference here is the plain
algorithm: LAPACK on every block of ``colex_blocks``.
"""

import itertools
import math

import numpy as np
import pytest

from ssecert import System
from ssecert.numerics.linalg import (
    balanced_units,
    cholesky_or_nan,
    screen_positive_definite,
    sensor_subspaces,
    single_screen,
)
from ssecert.structure._combinatorics import (
    ColexScreen,
    _clip,
    _proxies,
    cholesky_screen,
    colex_blocks,
    colex_unrank,
)
from ssecert.structure._level_scan import (
    _CRITICAL,
    _batches,
    _Level,
    _LevelTask,
    _refine,
    _scan_range,
    _screen_margin,
)
from ssecert.tolerances import BORDERLINE, ZERO, Tolerances


def _lapack(mats: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """numpy.linalg.cholesky one matrix at a time: success and smallest diagonal entry."""
    ok = np.zeros(mats.shape[0], dtype=bool)
    smallest = np.full(mats.shape[0], np.nan)
    for i, m in enumerate(mats):
        try:
            L = np.linalg.cholesky(m)
        except np.linalg.LinAlgError:
            continue
        ok[i] = np.isfinite(L[-1, -1]) and np.isfinite(L[0, 0])
        smallest[i] = np.diagonal(L).min()
    return ok, smallest


def _hard_matrices(rng: np.random.Generator, n: int, count: int) -> np.ndarray:
    """Symmetric matrices around the edge of positive definiteness: smallest eigenvalues from
    -1e-4 to 1e2 (many within rounding of 0), condition numbers up to 1e14, scales 1e-3 to
    1e3, and Kahan-like ones (ill-conditioned with moderate pivots)."""
    Q = np.linalg.qr(rng.standard_normal((count, n, n)))[0]
    lam = 10.0 ** rng.uniform(-12, 2, (count, n))
    lam[::3, 0] = rng.uniform(-1e-4, 1e-4, lam[::3, 0].shape)
    lam[1::3, 0] = rng.choice([0.0, 1e-16, -1e-16, 1e-13], lam[1::3, 0].shape)
    A = (Q * lam[:, None, :]) @ Q.transpose(0, 2, 1)
    c = rng.uniform(0.3, 0.9, count // 4)
    s = np.sqrt(1 - c**2)
    R = np.zeros((count // 4, n, n))
    for i in range(n):
        R[:, i, i] = s**i
        R[:, i, i + 1 :] = -(c * s**i)[:, None]
    A[: count // 4] = R.transpose(0, 2, 1) @ R
    A = (A + A.transpose(0, 2, 1)) / 2
    return A * 10.0 ** rng.uniform(-3, 3, (count, 1, 1))


@pytest.mark.parametrize("n", [1, 2, 5, 12, 20])
def test_screens_decide_as_lapack(n):
    rng = np.random.default_rng(n)
    A = _hard_matrices(rng, n, 400)
    ok, smallest = _lapack(A)
    assert 0 < ok.sum() < ok.size  # both kinds, so that the test means something
    assert np.array_equal(screen_positive_definite(A, 0.0), ok)
    decided, proxy = cholesky_screen(A, 1e-12, True)
    assert np.array_equal(decided, ok)
    assert np.array_equal(proxy, np.where(ok, smallest**2 + 1e-12, -np.inf))
    assert np.array_equal(cholesky_screen(A, 1e-12, False)[0], ok)
    L = cholesky_or_nan(A)
    assert np.array_equal(np.isfinite(L[:, -1, -1]), ok)
    assert np.array_equal(
        L[ok].min(axis=(1, 2)), np.array([np.linalg.cholesky(a).min() for a in A[ok]])
    )
    # the single-precision screening is sound: what it passes LAPACK factors, with a smallest
    # pivot at least its own
    passed, low = single_screen(A)
    assert np.all(ok[passed]) and np.all(low[passed].astype(float) <= smallest[passed])


def test_screen_positive_definite_takes_a_shift_per_matrix():
    rng = np.random.default_rng(1)
    A = _hard_matrices(rng, 4, 200)
    shift = rng.uniform(-1e-3, 1e-3, 200)
    ok, _ = _lapack(A - shift[:, None, None] * np.eye(4))
    assert np.array_equal(screen_positive_definite(A, shift), ok)


@pytest.mark.parametrize("q, n, k, memory", [(9, 3, 4, 200), (12, 2, 5, 1000), (7, 2, 7, 100)])
def test_colex_screen_numbers_the_sets_of_colex_blocks(q, n, k, memory):
    rng = np.random.default_rng(q)
    items, base = rng.standard_normal((q, n, n)), rng.standard_normal((n, n))
    total = math.comb(q, k)
    for lo, hi in [(0, total), (total // 3, total - total // 5)]:
        blocks = list(
            colex_blocks(items, base, k, memory=memory, chunk_bytes=64, start=lo, stop=hi)
        )
        source = ColexScreen(items, base, k, 0.0, memory=memory, chunk_bytes=64, start=lo, stop=hi)
        ranks = np.arange(lo, hi)
        assert np.array_equal(source.subsets(ranks), [colex_unrank(r, k) for r in range(lo, hi)])
        matrices = np.concatenate([b.matrices for b in blocks])
        assert np.array_equal(source.matrices(ranks), matrices)  # bit for bit
        begins, ends = source.spans(ranks)
        spans = [(b.offset, b.offset + len(b)) for b in blocks for _ in range(len(b))]
        assert [(int(a), int(b)) for a, b in zip(begins, ends)] == spans


def _plants() -> list[System]:
    """Plants whose levels hold sets of every kind: far from breaking, breaking, within
    rounding of the screening's shift, tied proxies (repeated sensors)."""
    rng = np.random.default_rng(3)
    out = []
    for n, p, sees in [(6, 14, 0.4), (8, 16, 0.5), (10, 18, 0.5)]:
        C = rng.integers(-3, 4, (p, n)) * (rng.random((p, n)) < sees)
        out.append(System(np.diag(np.arange(1.0, n + 1) / (n + 1)), C.astype(float)))
    n, p = 6, 14
    rows = rng.standard_normal((p, n)) * (rng.random((p, n)) < 0.35)
    for eps in (1e-7, 1e-9, 0.0):  # pairs of sensors that nearly coincide
        C = rows.copy()
        C[p // 2 :] = rows[: p - p // 2] + eps * rng.standard_normal((p - p // 2, n))
        out.append(System(np.diag(np.linspace(0.2, 0.9, n)), C))
    C = np.zeros((12, 5))  # sensors of one coordinate each, some weak
    for i in range(12):
        C[i, i % 5] = 1.0 if i < 5 else 3e-7
    out.append(System(0.5 * np.eye(5) + 0.1 * np.diag(np.ones(4), 1), C))
    return out


def _reference(task: _LevelTask, ranks: tuple[int, int]) -> _Level:
    """The level's findings by the plain algorithm: LAPACK on every block of colex_blocks."""
    rest, full, q = task.rest, task.full, task.rest.size
    total = math.comb(q, task.k)
    level, candidates = _Level(), []
    for block in colex_blocks(task.proj, task.shifted, task.k, start=ranks[0], stop=ranks[1]):
        ok, proxy = _proxies(cholesky_or_nan(block.matrices), task.shift)
        if task.critical:
            for j, removed in enumerate(block.subsets()):
                kept = tuple(sorted(int(i) for i in rest if i not in set(rest[removed].tolist())))
                candidates.append((float(proxy[j]), total - 1 - block.offset - j, kept))
            candidates = sorted(candidates)[:_CRITICAL]
        bad = np.flatnonzero(~ok)
        if bad.size:
            subsets = block.subsets(bad)
            codes, _, nulls = _refine(task.P, task.ranks, subsets, q, task.tol, task.errors)
            for j, row, code, z in zip(bad, subsets, codes, nulls):
                removed = tuple(sorted(full.tolist() + rest[row].tolist()))
                if code == ZERO:
                    level.failures[removed] = z
                elif code == BORDERLINE:
                    level.borderline_at.append(total - 1 - block.offset - int(j))
        level.checked += len(block)
    level.critical = candidates
    return level


def _plant_task(plant: int, k: int, critical: bool) -> _LevelTask:
    """The level of k removed sensors of one of ``_plants`` (its sensors in reverse order)."""
    tol = Tolerances()
    system = balanced_units(_plants()[plant]).system
    sub = sensor_subspaces(system.A, system.C, tolerances=tol)
    rest = np.flatnonzero(sub.ranks < system.n)[::-1]
    P = sub.bases[rest]
    proj = np.einsum("qkn,qkm->qnm", P, P)
    q, n = rest.size, system.n
    shift = max(tol.screen_rtol * q, 10.0 * float(np.sum(sub.errors[rest])) ** 2)
    return _LevelTask(
        P, sub.ranks[rest], proj, proj.sum(axis=0) - shift * np.eye(n), shift, k,
        rest, np.zeros(0, dtype=np.int64), tol, critical, sub.errors[rest],
    )  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize("plant", range(7))
def test_level_scan_finds_what_lapack_on_every_block_finds(plant):
    tol = Tolerances()
    system = balanced_units(_plants()[plant]).system
    sub = sensor_subspaces(system.A, system.C, tolerances=tol)
    rest = np.flatnonzero(sub.ranks < system.n)[::-1]
    P = sub.bases[rest]
    proj = np.einsum("qkn,qkm->qnm", P, P)
    q, n = rest.size, system.n
    shift = max(tol.screen_rtol * q, 10.0 * float(np.sum(sub.errors[rest])) ** 2)
    rng = np.random.default_rng(plant)
    for k in range(q + 1):
        total = math.comb(q, k)
        if total > 20000:
            break
        cuts = sorted({0, total, *rng.integers(0, total + 1, 2).tolist()})
        for critical in (True, False):
            task = _LevelTask(
                P, sub.ranks[rest], proj, proj.sum(axis=0) - shift * np.eye(n), shift, k,
                rest, np.zeros(0, dtype=np.int64), tol, critical, sub.errors[rest],
            )  # fmt: skip
            for lo, hi in itertools.pairwise(cuts):
                got, want = _scan_range(task, (lo, hi)), _reference(task, (lo, hi))
                assert got.checked == want.checked == hi - lo
                assert got.failures.keys() == want.failures.keys()
                for key, z in want.failures.items():
                    assert np.array_equal(got.failures[key], z)
                assert got.borderline_at == sorted(want.borderline_at)
                assert got.critical == want.critical


@pytest.mark.parametrize("plant", [0, 1, 5])
def test_the_verdict_level_ranks_the_closest_sets_as_lapack(plant, monkeypatch):
    """The verdict's level (the closest sets ranked, in many batches, so that the bounds meet
    a finite threshold) finds LAPACK's closest sets and failures, on plants far from breaking
    and on one with repeated sensors (tied proxies)."""
    from ssecert.structure import _combinatorics, _level_scan

    # many batches: finite thresholds; tier 2 factors a few sets at a time
    monkeypatch.setattr(_level_scan, "_FIRST_RANKED_SETS", 256)
    monkeypatch.setattr(_level_scan, "_RANKED_BATCH_SETS", 512)
    monkeypatch.setattr(_combinatorics, "TIER2_SETS", 96)
    q = _plant_task(plant, 0, True).rest.size
    k = max(j for j in range(q) if math.comb(q, j) <= 12000 and j <= q // 2)
    task = _plant_task(plant, k, True)
    total = math.comb(q, k)
    got, want = _scan_range(task, (0, total)), _reference(task, (0, total))
    assert got.failures.keys() == want.failures.keys()
    assert got.critical == want.critical and len(got.critical) == _CRITICAL


def test_the_shared_bound_is_below_the_smallest_eigenvalue():
    """Tier 1's bound (the sets sharing their largest sensor) never exceeds the smallest
    eigenvalue of a set's Gramian less LAPACK's error, and decides most sets of a plant far
    from breaking."""
    tol = Tolerances()
    rng = np.random.default_rng(0)
    n, p = 8, 16
    C = rng.integers(-3, 4, (p, n)) * (rng.random((p, n)) < 0.5)
    system = balanced_units(System(np.diag(np.arange(1.0, n + 1) / 9), C.astype(float))).system
    sub = sensor_subspaces(system.A, system.C, tolerances=tol)
    P = sub.bases
    proj = np.einsum("qkn,qkm->qnm", P, P)
    shifted = proj.sum(axis=0) - 1e-12 * np.eye(n)
    k = 4
    total = math.comb(p, k)
    task = _LevelTask(
        P, sub.ranks, proj, shifted, 1e-12, k, np.arange(p), np.zeros(0, dtype=np.int64), tol,
        False, sub.errors,
    )  # fmt: skip
    source = ColexScreen(proj, shifted, k, _screen_margin(task), factors=P)
    bound = source.lower_bounds(source._pieces(0, total), total)
    exact = np.linalg.eigvalsh(source.matrices(np.arange(total)))[:, 0]
    assert np.all(bound <= exact)
    assert np.mean(bound > 0) > 0.5
    # at a shift (the ranking's threshold): still below, and more sets proved above it
    gains = []
    for mu in np.quantile(exact, [0.01, 0.1, 0.3, 0.6]):
        shifted_bound = source.lower_bounds(source._pieces(0, total), total, float(mu))
        assert np.all(shifted_bound <= exact)
        gains.append(np.mean(shifted_bound > mu) - np.mean(bound > mu))
    assert min(gains) >= 0 and max(gains) > 0.1


def test_tier_two_fills_the_selected_rows_as_the_whole_batch():
    """The matrices tier 2 gathers for the sets tier 1 leaves open are those of the whole
    batch, bit for bit, across the tops of the single-precision level."""
    rng = np.random.default_rng(3)
    q, n, k = 12, 4, 4
    F = rng.standard_normal((q, 2, n))
    items = np.einsum("qrn,qrm->qnm", F, F)
    source = ColexScreen(items, items.sum(axis=0), k, 1e-3, single_memory=4 * n * n * 40)
    assert 0 < source.m32 < k
    start, stop = 17, math.comb(q, k) - 5
    N = stop - start
    pieces = source._pieces(start, stop)
    whole = np.empty((n, n, N), dtype=np.float32)
    source.fill(pieces, whole)
    rows = np.flatnonzero(rng.random(N) < 0.3)
    assert np.array_equal(source.fill_rows(pieces, rows, start), whole[:, :, rows])
    for a, b in [(0, N), (5, 40), (N - 9, N)]:
        part = np.empty((n, n, b - a), dtype=np.float32)
        source.fill(_clip(pieces, a, b), part)
        assert np.array_equal(part, whole[:, :, a:b])


@pytest.mark.parametrize("k", [1, 3, 5])
def test_matrices_formed_one_by_one_are_those_of_the_levels(k):
    """A few sets' matrices are formed one by one, without the levels of partial sums (the
    refinement levels ask for a few hundred sets of millions): bit for bit the matrices the
    levels give, in float64 (LAPACK's decisions) and in single precision (tier 2)."""
    rng = np.random.default_rng(k)
    q, n = 14, 5
    F = rng.standard_normal((q, 2, n)) * np.exp(rng.uniform(-6, 6, (q, 1, 1)))
    items = np.einsum("qrn,qrm->qnm", F, F)
    total = math.comb(q, k)
    ranks = np.sort(rng.choice(total, size=min(total, 9), replace=False))
    one_by_one = ColexScreen(items, items.sum(axis=0), k, 1e-3, memory=8 * n * n * 40,
                             single_memory=4 * n * n * 40)  # fmt: skip
    levels = ColexScreen(items, items.sum(axis=0), k, 1e-3, memory=8 * n * n * 40,
                         single_memory=4 * n * n * 40)  # fmt: skip
    levels._formed = {"float64": total, "float32": total}  # as if many had been asked
    assert np.array_equal(one_by_one.matrices(ranks), levels.matrices(ranks))
    assert one_by_one._sums is None and levels._sums is not None
    start = int(ranks[0])
    pieces = levels._pieces(start, total)
    rows = ranks - start
    assert np.array_equal(
        one_by_one.fill_rows(pieces, rows, start), levels.fill_rows(pieces, rows, start)
    )
    assert one_by_one._sums32 is None and levels._sums32 is not None


@pytest.mark.parametrize("lo, hi, size, first", [(0, 10, 3, None), (4, 50, 8, 3), (5, 6, 4, 2)])
def test_the_batches_cover_the_range_from_the_last_down(lo, hi, size, first):
    batches = _batches(lo, hi, size, first)
    assert [r for a, b in reversed(batches) for r in range(a, b)] == list(range(lo, hi))
    assert all(b - a <= size for a, b in batches[1:])
    assert batches[0][1] - batches[0][0] <= (size if first is None else first)
