"""Dask integration: spread chunks of Monte Carlo runs or grid points over workers.

Work is split into the same chunks whether it runs in-process or on Dask,
and every chunk draws its randomness from (seed, run index), so both paths
give bitwise-identical arrays.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator, Sequence
from typing import Any

__all__ = ["dask_client", "map_ordered"]


@contextlib.contextmanager
def dask_client(address: str | None = None, *, workers: int | None = None) -> Iterator[Any]:
    """A dask.distributed Client: an existing scheduler when ``address`` is given,
    otherwise a LocalCluster of ``workers`` processes closed on exit.

    Raises
    ------
    ImportError
        With the install command, when dask.distributed is missing.
    """
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError as exc:  # pragma: no cover - depends on the extras installed
        raise ImportError(
            "Dask is not installed; install it with: python -m pip install 'ssecert[dist]'"
        ) from exc
    if address:
        client = Client(address)
        try:
            yield client
        finally:
            client.close()
        return
    cluster = LocalCluster(
        n_workers=workers or 2, threads_per_worker=1, processes=True, dashboard_address=None
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
    """[func(item) for item in items], on Dask workers when a client is given."""
    if client is None:
        return [func(item) for item in items]
    futures = client.map(func, list(items), pure=False)
    return client.gather(futures)
