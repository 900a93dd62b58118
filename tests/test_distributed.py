"""Enumeration split into ranges of colex ranks: the same answer in-process and on Dask."""

import contextlib
import itertools
import json
import math

import numpy as np
import pytest

from ssecert import System
from ssecert.analyze import analyze
from ssecert.cli import main
from ssecert.parallel import rank_ranges
from ssecert.report.json import certificate_json
from ssecert.spec import spec_from_dict
from ssecert.structure import _irrepresentable_scan, enumeration, sparse
from ssecert.structure._combinatorics import colex_blocks, colex_rank
from ssecert.structure.enumeration import placement_note
from ssecert.structure.irrepresentable import irrepresentable
from ssecert.structure.outcomes import ProblemCode, SparseCode
from ssecert.structure.sparse import sparse_observability
from ssecert.structure.sparse_messages import placement_text

pytest.importorskip("dask.distributed")


def _two_planted_breaking_sets() -> dict:
    # n = 3, A = I: rows 1, 2, 5..8 lie on the line v, rows 3, 4 in a plane through v,
    # rows 0, 9 in another. Removing {0, 9} or {3, 4} leaves rows in one plane (unobservable);
    # no single removal does. The lexicographically first, (0, 9), is late in colex order
    # (rank 36 of 45) and {3, 4} early (rank 9).
    v = [1.0, 2.0, -1.0]
    rows = {1: v, 2: [2, 4, -2], 5: [-1, -2, 1], 6: [3, 6, -3], 7: [0.5, 1, -0.5], 8: v}
    rows |= {3: [1, 0, 0], 4: [3, 2, -1]}  # plane spanned by v and (1, 0, 0)
    rows |= {0: [0, 0, 1], 9: [1, 2, 0]}  # plane spanned by v and (0, 0, 1)
    C = [rows[i] for i in range(10)]
    return {
        "name": "planted",
        "system": {"A": np.eye(3).tolist(), "C": C},
        "attack": {"max_attacked": 1},
    }


def _holding() -> dict:
    rng = np.random.default_rng(3)
    A = np.array([[0.9, 0.2, 0.0], [0.0, 0.8, 0.3], [0.1, 0.0, 0.7]])
    return {
        "name": "holding",
        "system": {"A": A.tolist(), "C": rng.integers(-3, 4, size=(9, 3)).tolist()},
        "attack": {"max_attacked": 1},
    }


def _answers(cert) -> dict:
    document = json.loads(certificate_json(cert))
    document.pop("meta", None)
    return document


@contextlib.contextmanager
def _in_process_cluster():
    from dask.distributed import Client, LocalCluster

    with (
        LocalCluster(n_workers=1, processes=False, dashboard_address=":0") as cluster,
        Client(cluster) as client,
    ):
        yield client


@pytest.fixture(scope="module")
def client():
    from ssecert.parallel import dask_client

    with dask_client(workers=2) as client:
        yield client


@pytest.fixture
def small_chunks(monkeypatch):
    # split even these small levels into many ranges
    monkeypatch.setattr(enumeration, "MIN_CHUNK_SETS", 1)
    monkeypatch.setattr(enumeration, "_CHUNK_OVER_LEVEL", 0)
    monkeypatch.setattr(enumeration, "MIN_WORKER_SETS", 1)
    monkeypatch.setattr(_irrepresentable_scan, "MIN_CHUNK_SUPPORTS", 1)


def test_colex_ranges_give_the_same_matrices_bit_for_bit():
    rng = np.random.default_rng(0)
    for q, n, k, memory in [(9, 3, 4, 200), (12, 2, 5, 1000), (7, 2, 7, 100), (10, 3, 3, 0)]:
        items, base = rng.standard_normal((q, n, n)), rng.standard_normal((n, n))
        whole = list(colex_blocks(items, base, k, memory=memory, chunk_bytes=64))
        matrices = np.concatenate([b.matrices for b in whole])
        subsets = np.concatenate([b.subsets() for b in whole])
        total = math.comb(q, k)
        assert [colex_rank(tuple(s)) for s in subsets] == list(range(total))
        for _ in range(20):
            cuts = sorted(rng.integers(0, total + 1, size=3).tolist())
            parts = []
            for lo, hi in zip([0, *cuts], [*cuts, total]):
                parts += list(colex_blocks(items, base, k, memory=memory, start=lo, stop=hi))
            assert np.array_equal(np.concatenate([b.matrices for b in parts]), matrices)
            assert np.array_equal(np.concatenate([b.subsets() for b in parts]), subsets)


@pytest.mark.slow
@pytest.mark.parametrize("design", [_two_planted_breaking_sets, _holding])
def test_dask_gives_the_in_process_answer(design, client, small_chunks):
    spec = spec_from_dict(design())
    local = analyze(spec, method="enumeration")
    spread = analyze(spec, method="enumeration", client=client)
    assert _answers(spread) == _answers(local)
    check = spread["sparse_observability"]
    if design is _two_planted_breaking_sets:
        assert check.verdict.value == "fails"
        assert check.fields["breaking_set"] == [0, 9]  # lexicographically first, late in colex
    else:
        assert check.verdict.value == "holds"


@pytest.mark.slow
def test_the_command_line_runs_the_enumeration_on_workers(
    tmp_path, capsys, small_chunks, monkeypatch
):
    path = tmp_path / "planted.json"
    path.write_text(json.dumps(_two_planted_breaking_sets()))
    assert main(["analyze", str(path), "--method", "enumeration", "--json", "-"]) == 1
    local = json.loads(capsys.readouterr().out)
    placed = []

    def placement(outcome):
        placed.append((dict(outcome.on_workers), list(outcome.in_process)))
        return placement_note(outcome)

    monkeypatch.setattr(sparse, "placement_note", placement)
    code = main(["analyze", str(path), "--method", "enumeration", "--workers", "2", "--json", "-"])
    assert code == 1
    spread = json.loads(capsys.readouterr().out)
    # what ran where is said in the notes (small_chunks: the levels of 1 and 2 sensors are
    # split alike)
    [(on_workers, in_process)] = placed
    assert list(on_workers)[:2] == [1, 2] and on_workers[1] == on_workers[2] > 1
    words = placement_text(
        on_workers, in_process, enumeration.MIN_WORKER_SETS, enumeration._CHUNK_OVER_LEVEL
    )
    added = [n for n in spread["meta"]["notes"] if n not in local["meta"]["notes"]]
    assert added == [f"sparse_observability: {words}"]
    local.pop("meta"), spread.pop("meta")
    assert spread == local


class _Threads:
    """A stand-in for a Dask client with the given worker threads."""

    def __init__(self, threads: int) -> None:
        self.threads = threads

    def nthreads(self) -> dict[str, int]:
        return {f"w{i}": 1 for i in range(self.threads)}


@pytest.mark.parametrize(
    ("total", "smallest", "threads", "pieces"),
    [
        (10, 6, 2, 1),  # two ranges would be under the smallest: in-process
        (11, 6, 2, 1),
        (12, 6, 2, 2),
        (100, 10, 2, 8),  # up to four per thread
        (70, 10, 2, 6),  # 7 would leave a last range alone on a worker
        (50, 10, 3, 3),
        (25, 10, 3, 2),  # fewer ranges than threads: as many as fit
        (0, 10, 2, 1),
    ],
)
def test_rank_ranges_are_whole_rounds_of_the_workers(total, smallest, threads, pieces):
    ranges = rank_ranges(total, _Threads(threads), smallest)
    assert len(ranges) == pieces
    assert ranges[0][0] == 0 and ranges[-1][1] == total
    assert all(a[1] == b[0] for a, b in itertools.pairwise(ranges))
    if pieces > 1:
        assert min(hi - lo for lo, hi in ranges) >= smallest
    assert rank_ranges(total, None, smallest) == [(0, total)]


def test_placement_note_says_what_ran_where_only_when_a_level_ran():
    outcome = enumeration._Outcome("enumeration", "exact", on_workers={6: 6})
    outcome.in_process.extend([0, 1, 2, 3, 4, 5])
    # its words: tests/test_problem_messages.py
    assert enumeration.placement_note(outcome) == placement_text(
        {6: 6}, [0, 1, 2, 3, 4, 5], enumeration.MIN_WORKER_SETS, enumeration._CHUNK_OVER_LEVEL
    )
    assert enumeration.MIN_WORKER_SETS == 500_000 and enumeration._CHUNK_OVER_LEVEL == 20
    assert enumeration.placement_note(enumeration._Outcome("enumeration", "exact")) is None


def test_a_range_that_fails_twice_ends_the_enumeration_with_the_reason(
    monkeypatch, small_chunks, sparse_problems
):
    scan = enumeration._scan_range
    calls = {"n": 0}

    def flaky(task, ranks, progress=None):
        calls["n"] += 1
        # the lexicographically first sets of 2 sensors: the last colex ranks of the sensors in
        # reverse order, the first range a level looks at
        if task.k == 2 and ranks[1] == math.comb(task.rest.size, 2):
            raise RuntimeError("worker lost")
        return scan(task, ranks, progress)

    monkeypatch.setattr(enumeration, "_scan_range", flaky)
    system = System(**{k: np.array(v) for k, v in _two_planted_breaking_sets()["system"].items()})
    with _in_process_cluster() as client:  # the patched function reaches the worker
        check = sparse_observability(system, 1, method="enumeration", client=client)
    assert check.verdict.value == "inconclusive"
    assert check.fields["max_removable"] == 1
    assert check.fields["max_removable_is_lower_bound"] is True
    assert check.code is SparseCode.UNDECIDED
    [[problems]] = sparse_problems
    (failed,) = [p for p in problems if p.code is ProblemCode.WORKERS_FAILED]
    assert failed.facts["removed"] == 2 and failed.facts["first"] == 0
    assert failed.facts["cause"] == repr(RuntimeError("worker lost"))
    assert check.evidence["failed_chunk"]["lexicographic_positions"][0] == 0
    assert check.evidence["failed_chunk"]["removed_sensors"] == 2


def test_a_range_that_fails_once_is_retried(monkeypatch, small_chunks, tmp_path):
    scan = enumeration._scan_range

    def once(task, ranks, progress=None):
        # the function travels to the worker pickled: its memory is a file
        mark = tmp_path / f"failed-{task.k}-{ranks[0]}"
        if task.k == 2 and not mark.exists():
            mark.write_text("")
            raise RuntimeError("worker lost")
        return scan(task, ranks, progress)

    system = System(**{k: np.array(v) for k, v in _two_planted_breaking_sets()["system"].items()})
    expected = sparse_observability(system, 1, method="enumeration")
    monkeypatch.setattr(enumeration, "_scan_range", once)
    with _in_process_cluster() as client:  # the patched function reaches the worker
        check = sparse_observability(system, 1, method="enumeration", client=client)
    assert list(tmp_path.glob("failed-2-*"))  # the ranges the level needed failed once
    assert check.fields == expected.fields
    assert check.verdict.value == "fails"


@pytest.mark.parametrize("seed", [0, 1])
def test_the_irrepresentable_scan_on_dask_gives_the_in_process_answer(seed, client, small_chunks):
    rng = np.random.default_rng(seed)
    system = System(rng.standard_normal((3, 3)) / 2, rng.integers(-2, 3, size=(12, 3)))
    local = irrepresentable(system, 2)
    spread = irrepresentable(system, 2, client=client)
    assert (spread.verdict, spread.value, spread.fields) == (
        local.verdict,
        local.value,
        local.fields,
    )
    assert spread.evidence == local.evidence


@pytest.mark.slow
def test_an_unreachable_scheduler_is_a_clear_error(tmp_path, capsys, monkeypatch):
    from ssecert import parallel

    monkeypatch.setattr(parallel, "CONNECT_SECONDS", 1)
    path = tmp_path / "planted.json"
    path.write_text(json.dumps(_two_planted_breaking_sets()))
    assert main(["analyze", str(path), "--scheduler", "tcp://127.0.0.1:9"]) == 2
    err = capsys.readouterr().err
    assert "--scheduler: no Dask scheduler answers at 'tcp://127.0.0.1:9'" in err
    assert "internal error" not in err


def test_a_simulation_chunk_is_retried_once_then_reported(monkeypatch, tmp_path):
    from ssecert.examples import load_example
    from ssecert.observers import build_observer
    from ssecert.parallel import ChunkError
    from ssecert.simulation import engine

    spec = load_example("ugv")
    design = build_observer(spec.system, spec.observer)
    scenario = spec.scenarios[0]
    expected = engine.simulate_scenario(design, scenario, runs=8, steps=20, chunk_runs=2)
    chunk = engine._chunk

    def once(args):
        mark = tmp_path / f"failed-{args[2][0]}"  # the chunk's first run index
        if not mark.exists():
            mark.write_text("")
            raise RuntimeError("worker lost")
        return chunk(args)

    monkeypatch.setattr(engine, "_chunk", once)
    with _in_process_cluster() as client:
        again = engine.simulate_scenario(
            design, scenario, runs=8, steps=20, chunk_runs=2, client=client
        )
    assert len(list(tmp_path.glob("failed-*"))) == 4
    np.testing.assert_array_equal(again.relative_error, expected.relative_error)

    def always(args):
        raise RuntimeError("worker lost")

    monkeypatch.setattr(engine, "_chunk", always)
    with _in_process_cluster() as client, pytest.raises(ChunkError, match="of 4 of the work"):
        engine.simulate_scenario(design, scenario, runs=8, steps=20, chunk_runs=2, client=client)


def test_a_level_ends_at_its_first_breaking_set_in_process_and_on_dask(client, small_chunks):
    # (0, 9) is the 9th set of 2 in lexicographic order: the scan of the 45 sets of 2 stops
    # there, whether in one range per set (in-process) or in ranges on the workers
    system = System(**{k: np.array(v) for k, v in _two_planted_breaking_sets()["system"].items()})
    local = sparse_observability(system, 1, method="enumeration")
    spread = sparse_observability(system, 1, method="enumeration", client=client)
    for check in (local, spread):
        assert check.fields["breaking_set"] == [0, 9]
        assert check.evidence["methods_tried"][0]["sets_checked"] == 1 + 10 + 9
    assert spread.evidence == local.evidence and spread.fields == local.fields


def test_map_chunks_stops_at_the_first_chunk_in_order_that_ends_the_search(client):
    from ssecert.parallel import map_chunks

    chunks = list(range(12))
    for c in (None, client):
        out = map_chunks(_square, None, chunks, c, stop=lambda r: r >= 25)
        assert out == [0, 1, 4, 9, 16, 25]


def _square(payload, x):
    return x * x


def test_a_local_cluster_of_a_billion_workers_is_refused_at_once(tmp_path, capsys):
    # it started processes until memory ran out (13 GB in 35 s)
    from ssecert.cli import main
    from ssecert.parallel import dask_client, max_local_workers

    code = main(["analyze", "ugv", "--workers", "1e9", "--json", str(tmp_path / "x.json")])
    assert code == 2
    err = capsys.readouterr().err
    assert "--workers" in err and f"at most {max_local_workers()}" in err
    assert not (tmp_path / "x.json").exists()
    with (
        pytest.raises(ValueError, match="workers must be between 1 and"),
        dask_client(workers=10**9),
    ):
        pass
