"""Dask integration: spread chunks of Monte Carlo runs or grid points over workers.

Work is split into the same chunks whether it runs in-process or on Dask,
and every chunk draws its randomness from (seed, run index), so both paths
give bitwise-identical arrays.
"""

from __future__ import annotations

import contextlib
import itertools
from collections.abc import Callable, Iterator, Sequence
from typing import Any

__all__ = [
    "ChunkError",
    "DaskUnavailable",
    "dask_client",
    "max_local_workers",
    "map_chunks",
    "map_ordered",
    "map_ranges",
    "rank_ranges",
    "worker_threads",
]


class DaskUnavailable(RuntimeError):
    """Dask cannot run the work: not installed, no scheduler at the address, or no workers."""


CONNECT_SECONDS = 30  # to reach a scheduler, and again for it to have a worker


def max_local_workers() -> int:
    """The most worker processes a local Dask cluster may start: four per core (at least
    eight).  Each is a Python process with numpy (about 100 MB); beyond the cores they only
    wait for one another."""
    import os

    return max(8, 4 * (os.cpu_count() or 1))


# The local cluster's workers start without the glibc trim threshold that Dask's nanny sets
# by default (MALLOC_TRIM_THRESHOLD_=65536, against the fragmentation of long-lived workers):
# with it, the enumeration's per-batch temporaries are returned to the system and faulted in
# again batch after batch, and a range of sets took 1.3-1.4x as long on a worker as
# in-process (benchmarks/bench_distributed.py).  A value set in the environment still wins.
_LOCAL_WORKER_CONFIG = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}


@contextlib.contextmanager
def dask_client(address: str | None = None, *, workers: int | None = None) -> Iterator[Any]:
    """A dask.distributed Client: an existing scheduler when ``address`` is given,
    otherwise a LocalCluster of ``workers`` processes closed on exit.

    Raises
    ------
    DaskUnavailable
        With the install command when dask.distributed is missing; naming
        the address when no scheduler answers there, or when it has no
        worker, within ``CONNECT_SECONDS``.
    """
    try:
        import dask
        from dask.distributed import Client, LocalCluster
    except ImportError as exc:  # pragma: no cover - depends on the extras installed
        raise DaskUnavailable(
            "Dask is not installed; install it with: python -m pip install 'ssecert[dist]'"
        ) from exc
    if address:
        try:
            client = Client(address, timeout=f"{CONNECT_SECONDS}s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise DaskUnavailable(f"no Dask scheduler answers at {address!r}: {exc}") from None
        try:
            try:
                client.wait_for_workers(1, timeout=CONNECT_SECONDS)
            except (OSError, TimeoutError) as exc:
                raise DaskUnavailable(
                    f"the Dask scheduler at {address!r} has no worker after "
                    f"{CONNECT_SECONDS} s ({exc})"
                ) from None
            yield client
        finally:
            client.close()
        return
    if workers is not None and not 1 <= workers <= max_local_workers():
        raise ValueError(
            f"workers must be between 1 and {max_local_workers()} (four per core of this "
            f"machine) for a local cluster, got {workers}; use an address for a larger one"
        )
    with dask.config.set(_LOCAL_WORKER_CONFIG):
        cluster = LocalCluster(
            n_workers=workers or 2, threads_per_worker=1, processes=True, dashboard_address=":0"
        )
    client = Client(cluster)
    try:
        yield client
    finally:
        client.close()
        cluster.close()


def map_ordered(
    func: Callable[..., Any], items: Sequence[Any], client: Any | None = None
) -> list[Any]:
    """[func(item) for item in items], on Dask workers when a client is given (each item
    retried once; ``ChunkError`` when one fails twice)."""
    if client is None:
        return [func(item) for item in items]
    return map_chunks(_apply, func, items, client)


def _apply(func: Callable[..., Any], item: Any) -> Any:
    return func(item)


class ChunkError(RuntimeError):
    """A chunk of work failed on the Dask workers, also when retried.

    Attributes
    ----------
    chunk : object
        The chunk that failed (for an enumeration, its range of ranks).
    """

    def __init__(self, chunk: Any, cause: BaseException, index: int = 0, count: int = 1) -> None:
        super().__init__(
            f"part {index + 1} of {count} of the work failed twice on the Dask workers: {cause!r}"
        )
        self.chunk = chunk
        self.cause = cause


def map_chunks(
    func: Callable[[Any, Any], Any],
    payload: Any,
    chunks: Sequence[Any],
    client: Any | None = None,
    *,
    on_result: Callable[[int, Any], None] | None = None,
    stop: Callable[[Any], bool] | None = None,
) -> list[Any]:
    """[func(payload, chunk) for chunk in chunks], on Dask workers when a client is given.

    ``payload`` (the data every chunk reads) is sent to the workers once;
    results come back in the order of ``chunks`` whatever order they finish
    in, and ``on_result(index, result)`` is called as each arrives (for
    progress).  A chunk that fails on a worker is retried once; if it fails
    again, ``ChunkError`` names it.

    ``stop(result)``, when given, is called on the results in the order of
    ``chunks`` (each once every earlier chunk has arrived); once it returns
    True the later chunks are not run (on Dask, cancelled) and the results up
    to that chunk are returned: the early exit of a search whose answer is
    the first in the chunks' order.
    """
    if client is None:
        out = []
        for index, chunk in enumerate(chunks):
            out.append(func(payload, chunk))
            if on_result is not None:
                on_result(index, out[-1])
            if stop is not None and stop(out[-1]):
                break
        return out
    from dask.distributed import as_completed

    shared = client.scatter(payload, broadcast=True)
    futures = [client.submit(func, shared, chunk, pure=False, retries=1) for chunk in chunks]
    index_of = {future.key: i for i, future in enumerate(futures)}
    results: list[Any] = [None] * len(futures)
    arrived = [False] * len(futures)
    failed: dict[int, BaseException] = {}
    following = 0  # the first chunk not yet offered to ``stop``
    try:
        for future in as_completed(futures):
            i = index_of[future.key]
            error = future.exception()  # None unless the chunk raised
            if error is not None:
                if stop is None:
                    raise ChunkError(chunks[i], error, i, len(chunks))
                # reported only if no earlier chunk ends the search
                failed[i], arrived[i] = error, True
            else:
                results[i], arrived[i] = future.result(), True
                if on_result is not None:
                    on_result(i, results[i])
            while following < len(futures) and arrived[following]:
                if following in failed:
                    raise ChunkError(chunks[following], failed[following], following, len(chunks))
                if stop is not None and stop(results[following]):
                    return results[: following + 1]
                following += 1
    finally:
        for future in futures:
            if not future.done():
                future.cancel()
    return results


def worker_threads(client: Any | None) -> int:
    """Threads the client's workers offer (1 in-process)."""
    if client is None:
        return 1
    return max(1, sum(client.nthreads().values()))


def rank_ranges(total: int, client: Any | None, smallest: int) -> list[tuple[int, int]]:
    """Ranges [lo, hi) covering 0..total: one without a client, else up to four per worker
    thread, none smaller than ``smallest`` (below it a task costs more than it saves), and a
    whole number of rounds of the workers where there are at least as many ranges as threads
    (so that none waits for a last range run alone).  One range when two would be smaller
    than ``smallest``: the work is run in-process."""
    fit = total // max(smallest, 1)
    if client is None or total <= 0 or fit < 2:
        return [(0, total)]
    threads = worker_threads(client)
    pieces = min(4 * threads, fit)
    if pieces >= threads:
        pieces -= pieces % threads
    bounds = [total * i // pieces for i in range(pieces + 1)]  # sizes differ by one at most
    return list(itertools.pairwise(bounds))


def map_ranges(
    func: Callable[[Any, tuple[int, int]], Any],
    payload: Any,
    ranges: Sequence[tuple[int, int]],
    client: Any | None = None,
    progress: Callable[[int, int], None] | None = None,
    stop: Callable[[Any], bool] | None = None,
) -> list[Any]:
    """``map_chunks`` over ranges of ranks, with ``progress(ranks done, ranks in all)`` as
    each range arrives, and its early exit ``stop``."""
    total = sum(hi - lo for lo, hi in ranges)
    done = 0

    def arrived(index: int, result: Any) -> None:
        nonlocal done
        done += ranges[index][1] - ranges[index][0]
        if progress is not None:
            progress(done, total)

    return map_chunks(func, payload, ranges, client, on_result=arrived, stop=stop)
