"""The accelerator path of the enumeration: the same code on numpy (and on array-api-strict,
the standard only) gives the CPU's answers, bit for bit; an unusable device is refused."""

import json
import math

import numpy as np
import pytest

from ssecert import System
from ssecert.cli import main
from ssecert.numerics.linalg import cholesky_batch_last, single_passed
from ssecert.structure import device as accelerator
from ssecert.structure._combinatorics import ColexScreen
from ssecert.structure.device import (
    DeviceKernel,
    DeviceUnavailable,
    cholesky_diagonal,
    resolve_device,
)
from ssecert.structure.sparse import sparse_observability


def _namespaces():
    """numpy (as ``device="numpy"`` runs the kernel) and, where installed (the test extra),
    array-api-strict: the standard and nothing else."""
    out = [pytest.param(accelerator._namespace("numpy")[0], id="numpy")]
    try:
        import array_api_strict
    except ImportError:  # pragma: no cover - in the test extra
        return out
    return [*out, pytest.param(array_api_strict, id="array-api-strict")]


def _cuda_kernel():
    """The kernel on a CUDA device where this machine has one (the tests marked ``cuda`` run
    there only: CI has none, a GPU machine checks the accelerator's own arithmetic)."""
    try:
        return accelerator.device_kernel("cuda")
    except DeviceUnavailable:
        return None


cuda = pytest.mark.skipif(_cuda_kernel() is None, reason="no CUDA device")


def _batch(rng, n, N):
    """Batch-last float32 matrices: positive definite, indefinite and nearly singular."""
    G = rng.standard_normal((N, n, n + 2)).astype(np.float32)
    A = G @ G.transpose(0, 2, 1)
    A[: N // 3] -= 3.0 * np.eye(n, dtype=np.float32)  # many indefinite
    A[N // 3 : N // 3 + 5, :, 0] = 0.0  # singular: a zero row and column
    A[N // 3 : N // 3 + 5, 0, :] = 0.0
    return np.ascontiguousarray(A.transpose(1, 2, 0))


def _against_the_cpu(ours, work):
    """(which of ``ours`` passed, which the CPU tier's factorization of ``work`` passed, its
    pivots)."""
    cpu = np.empty((work.shape[0], work.shape[2]), dtype=np.float32)
    cholesky_batch_last(work.copy(), cpu)
    passed, _ = single_passed(cpu)
    with np.errstate(invalid="ignore"):
        ours_passed = (ours.min(axis=0) > 0) & np.isfinite(ours.sum(axis=0))
    return ours_passed, passed, cpu


@pytest.mark.parametrize("xp", _namespaces())
def test_the_array_api_factorization_decides_as_the_cpu_one(xp):
    rng = np.random.default_rng(0)
    for n in (1, 2, 5, 10):
        work = _batch(rng, n, 300)
        with np.errstate(all="ignore"):
            ours = accelerator._to_numpy(cholesky_diagonal(xp, xp.asarray(work)))
        ours_passed, passed, cpu = _against_the_cpu(ours, work)
        # far from the edge, both decide alike and agree to single-precision rounding
        assert np.array_equal(ours_passed, passed)
        assert np.allclose(ours[:, passed], cpu[:, passed], rtol=1e-4, atol=1e-6)
        assert 0 < passed.sum() < passed.size


@cuda
def test_the_gpu_factorization_decides_as_the_cpu_one():
    kernel = _cuda_kernel()
    rng = np.random.default_rng(4)
    for n in (1, 2, 5, 10, 20):
        work = _batch(rng, n, 3000)
        ours = accelerator._to_numpy(cholesky_diagonal(kernel.xp, kernel._put(work)))
        ours_passed, passed, cpu = _against_the_cpu(ours, work)
        assert np.array_equal(ours_passed, passed)
        # the squared pivots agree to the rounding of a factorization (n u times the matrix's
        # scale, taken generously): a small pivot's square root magnifies its rounding
        gap = np.abs(ours[:, passed].astype(float) ** 2 - cpu[:, passed].astype(float) ** 2)
        assert gap.max() <= 1e-4 * n * np.abs(work).max()


def test_numpy_and_the_standard_alone_factor_bit_for_bit_alike():
    strict = pytest.importorskip("array_api_strict")
    work = _batch(np.random.default_rng(1), 7, 200)
    with np.errstate(all="ignore"):
        a = accelerator._to_numpy(cholesky_diagonal(np, work))
        b = accelerator._to_numpy(cholesky_diagonal(strict, strict.asarray(work)))
    assert np.array_equal(a, b, equal_nan=True)


def _screens(kernel, k=4, q=14, n=4, critical=True):
    """The same level screened on the CPU and through ``kernel``: (ok, proxies) of each."""
    rng = np.random.default_rng(3)
    factors = np.zeros((q, n, n))
    factors[:, 0, :] = rng.standard_normal((q, n))  # one row per sensor, ...
    factors[: q - 4, 0, 2:] = 0.0  # ... all but 4 in one plane: removing 3 of the 4 breaks
    items = np.einsum("qrn,qrm->qnm", factors, factors)
    shift = 1e-9
    base = items.sum(axis=0) - shift * np.eye(n)
    margin = 1e-5
    total = math.comb(q, k)
    out = []
    for device in (None, kernel):
        source = ColexScreen(
            items, base, k, margin, factors=factors, device=device, single_memory=4096
        )
        work = np.empty((n, n, total), dtype=np.float32)
        diagonal = np.empty((n, total), dtype=np.float32)
        oks, proxies = [], []
        for first, last in source.batches(97):  # many pieces and batches
            screen = source.screen(first, last, shift, np.inf if critical else None, work, diagonal)
            ok = np.ones(last - first, dtype=bool)
            ok[screen.failed()] = False
            oks.append(ok)
            if critical:
                proxies.append(screen.proxies(np.arange(last - first), shift))
        out.append((np.concatenate(oks), np.concatenate(proxies) if critical else None))
    return out


@pytest.mark.parametrize("xp", _namespaces())
def test_a_level_screened_through_the_kernel_is_decided_as_on_the_cpu(xp):
    kernel = DeviceKernel(xp, None, name="test")
    (cpu_ok, cpu_proxy), (dev_ok, dev_proxy) = _screens(kernel)
    assert np.array_equal(dev_ok, cpu_ok)
    assert np.array_equal(dev_proxy, cpu_proxy)  # LAPACK's, bit for bit
    assert 0 < cpu_ok.sum() < cpu_ok.size  # both kinds of sets
    (cpu_ok, _), (dev_ok, _) = _screens(kernel, critical=False)
    assert np.array_equal(dev_ok, cpu_ok)


@cuda
def test_a_level_screened_on_the_gpu_is_decided_as_on_the_cpu():
    (cpu_ok, cpu_proxy), (dev_ok, dev_proxy) = _screens(_cuda_kernel())
    assert np.array_equal(dev_ok, cpu_ok)
    assert np.array_equal(dev_proxy, cpu_proxy)
    assert 0 < cpu_ok.sum() < cpu_ok.size


def _answer(check):
    evidence = dict(check.evidence)
    evidence.pop("cost_estimate", None)  # measured times
    return json.dumps(
        [check.verdict.value, check.fields, evidence, check.witness], sort_keys=True, default=str
    )


@pytest.fixture
def small_device_batches(monkeypatch):
    monkeypatch.setattr(accelerator, "DEVICE_MIN_SETS", 0)
    monkeypatch.setattr(accelerator, "DEVICE_BATCH_SETS", 1000)


def _planted(p=12, seed=0):
    """A = I (n = 4), sensors 0 to p - 4 in one plane: removing the 3 others and any one of
    them leaves a plane, a planted breaking set of 4."""
    C = np.random.default_rng(seed).standard_normal((p, 4))
    C[: p - 3, 2:] = 0.0
    return System(np.eye(4), C)


@pytest.mark.parametrize(
    ("system", "s"),
    [
        (_planted(), 2),  # fails: a planted set
        (System(np.eye(4), np.random.default_rng(1).standard_normal((16, 4))), 2),  # holds
        (System(np.eye(3), np.random.default_rng(2).standard_normal((12, 3))), 3),
    ],
)
@pytest.mark.parametrize("device", ["numpy", pytest.param("cuda", marks=cuda)])
def test_a_device_gives_the_cpu_answer_bit_for_bit(system, s, device, small_device_batches):
    cpu = sparse_observability(system, s, method="enumeration", time_budget=None)
    dev = sparse_observability(system, s, method="enumeration", time_budget=None, device=device)
    assert _answer(dev) == _answer(cpu)


def test_the_device_names_are_checked():
    assert resolve_device(None) is None and resolve_device("cpu") is None
    assert resolve_device("numpy") == "numpy"
    with pytest.raises(ValueError, match="device must be one of cpu, cuda, numpy"):
        resolve_device("gpu")


def test_cuda_without_a_gpu_library_is_refused_with_what_to_install(monkeypatch):
    import builtins

    real = builtins.__import__

    def no_gpu(name, *args, **kwargs):
        if name in ("torch", "cupy") or name.startswith(("torch.", "cupy.")):
            raise ImportError(name)
        return real(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_gpu)
    accelerator.device_kernel.cache_clear()
    with pytest.raises(DeviceUnavailable, match="PyTorch is not installed; CuPy is not"):
        resolve_device("cuda")


def test_the_command_line_refuses_an_unusable_device_before_any_work(monkeypatch, capsys):
    def unusable(name):
        raise DeviceUnavailable("no CUDA device to screen on: PyTorch sees no CUDA device")

    monkeypatch.setattr(accelerator, "device_kernel", unusable)
    assert main(["analyze", "notes-example-2", "--device", "cuda"]) == 2
    err = capsys.readouterr().err
    assert "ssecert: error: --device cuda: no CUDA device to screen on" in err


@pytest.mark.slow
def test_no_level_is_taken_for_another_when_the_device_copies(monkeypatch, small_device_batches):
    # a GPU keeps its own copy of each range's level: one plant after another, each range must
    # factor its own (an unobservable plant stays unobservable after any other)
    monkeypatch.setattr(
        DeviceKernel,
        "_put",
        lambda self, a: self.xp.asarray(np.array(a, copy=True), device=self.device),
    )
    monkeypatch.setattr(accelerator, "DEVICE_BATCH_SETS", 7)
    unseen = System(np.eye(2), [[1.0, 0.0], [2.0, 0.0], [3.0, 0.0]])  # no sensor sees x2
    cpu = _answer(sparse_observability(unseen, 0, method="enumeration", time_budget=None))
    for trial in range(12):
        rng = np.random.default_rng(trial)
        n, p = int(rng.integers(3, 7)), int(rng.integers(8, 14))
        C = rng.standard_normal((p, n))
        C[: p // 2, -1] = 0.0
        other = System(np.eye(n), C)
        expected = sparse_observability(other, 2, method="enumeration", time_budget=None)
        got = sparse_observability(other, 2, method="enumeration", time_budget=None, device="numpy")
        assert _answer(got) == _answer(expected), trial
        again = sparse_observability(
            unseen, 0, method="enumeration", time_budget=None, device="numpy"
        )
        assert _answer(again) == cpu, trial


@pytest.mark.parametrize(
    ("q", "k", "single_memory", "n"),
    [(14, 4, 4096, 3), (12, 5, 2000, 3), (9, 3, 1 << 20, 3), (25, 24, 16, 1), (14, 12, 16, 2)],
)
def test_the_pieces_as_arrays_are_those_of_the_walk_through_the_tops(q, k, single_memory, n):
    # the device takes a batch's pieces as arrays: the same rows, level rows and tops' sums,
    # bit for bit, as the walk the CPU tier takes, for ranges in either order (tops of many
    # items too: one addition at a time, in both)
    rng = np.random.default_rng(5)
    factors = rng.standard_normal((q, 1, n))
    items = np.einsum("qrn,qrm->qnm", factors, factors)
    total = math.comb(q, k)
    source = ColexScreen(items, items.sum(axis=0), k, 1e-6, single_memory=single_memory)
    ranges = [(a, min(a + 37, total)) for a in range(0, total, 37)]
    for start, stop in [*ranges, *reversed(ranges), (0, total), (5, total - 3)]:
        pieces = source._pieces(start, stop)
        rows, offsets, totals = source.piece_arrays(start, stop)
        assert rows.tolist() == [row for row, *_ in pieces]
        assert (rows + offsets).tolist() == [first for _, first, _, _ in pieces]
        tops = [source._top_total(top) for *_, top in pieces]
        if tops[0] is None:
            assert totals is None
        else:
            assert np.array_equal(totals.view(np.uint32), np.stack(tops, axis=2).view(np.uint32))


def test_a_range_of_segments_has_the_blocks_of_each_segment_alone():
    # an accelerator screens a few of the CPU's ranges at once: each rank's block (which sets
    # are refined together) must be the one its own range gives it
    rng = np.random.default_rng(6)
    q, k, n = 13, 4, 3
    factors = rng.standard_normal((q, 1, n))
    items = np.einsum("qrn,qrm->qnm", factors, factors)
    total = math.comb(q, k)
    for segment in (7, 64, 100):
        for start in (0, 2 * segment):
            joined = ColexScreen(
                items, items.sum(axis=0), k, 1e-6, start=start, segment=segment, chunk_bytes=1
            )
            ranks = np.arange(start, total)
            begins, ends = joined.spans(ranks)
            for rank, begin, end in zip(ranks.tolist(), begins, ends):
                lo = start + (rank - start) // segment * segment
                alone = ColexScreen(
                    items, items.sum(axis=0), k, 1e-6, start=lo, stop=lo + segment, chunk_bytes=1
                )
                b, e = alone.spans(np.array([rank]))
                assert (begin, end) == (b[0], e[0]), (segment, rank)


@pytest.mark.parametrize("device", ["numpy", pytest.param("cuda", marks=cuda)])
def test_a_level_in_many_ranges_gets_the_cpu_answer_on_a_device(monkeypatch, device):
    # the CPU's ranges of a level small enough to be many (each refined in its own blocks),
    # joined on the device: a plant with a planted breaking set (its sensors scaled apart),
    # read in both orders, and one that holds
    from ssecert.structure import enumeration

    monkeypatch.setattr(enumeration, "MIN_CHUNK_SETS", 23)
    monkeypatch.setattr(enumeration, "_CHUNK_OVER_LEVEL", 0)
    monkeypatch.setattr(accelerator, "DEVICE_MIN_SETS", 0)
    monkeypatch.setattr(accelerator, "DEVICE_BATCH_SETS", 100)
    rng = np.random.default_rng(7)
    C = rng.standard_normal((14, 4))
    C[:9, 3] = 0.0  # 9 sensors blind to x4: removing the other 5 breaks
    C[9:, :] *= rng.uniform(0.5, 2.0, (5, 1))
    for system, s in ((System(np.eye(4), C), 3), (System(np.eye(4), C[::-1].copy()), 2)):
        cpu = sparse_observability(system, s, method="enumeration", time_budget=None)
        dev = sparse_observability(system, s, method="enumeration", time_budget=None, device=device)
        assert _answer(dev) == _answer(cpu)
    holds = System(np.eye(3), rng.standard_normal((13, 3)))
    cpu = sparse_observability(holds, 3, method="enumeration", time_budget=None)
    dev = sparse_observability(holds, 3, method="enumeration", time_budget=None, device=device)
    assert _answer(dev) == _answer(cpu)
