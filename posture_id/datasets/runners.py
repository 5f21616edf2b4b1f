"""Where shards are made: local threads or a Dask distributed cluster.

A runner is called with shard indices and yields ``(k, arrays)`` as shards complete; it
keeps at most two shards per thread in flight, so memory stays bounded.
"""

from __future__ import annotations

import os
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from pathlib import Path

from posture_id.bodies.body import Body
from posture_id.datasets.config import DatasetConfig, DatasetError
from posture_id.datasets.shards import make_shard, make_shard_remote

__all__ = ["LocalRunner", "DaskRunner"]


class LocalRunner:
    """Make shards in local threads (the kernel and the FFTs release the GIL).

    At most two shards per worker are in flight, and a shard's arrays are dropped as soon
    as they are written, so memory stays bounded whatever the size of the set.
    """

    def __init__(self, workers: int | None, config: DatasetConfig, body: Body) -> None:
        if workers is not None and workers < 1:
            raise DatasetError(f"workers must be ≥ 1, got {workers}")
        self.workers = workers or os.cpu_count() or 1
        self.pool = ThreadPoolExecutor(max_workers=self.workers)
        self.config = config
        self.body = body

    def __call__(self, ks: list[int]):
        todo = list(reversed(ks))
        in_flight: dict = {}
        while todo or in_flight:
            while todo and len(in_flight) < 2 * self.workers:
                k = todo.pop()
                in_flight[self.pool.submit(make_shard, self.config, k, self.body)] = k
            done, _ = wait(in_flight, return_when=FIRST_COMPLETED)
            for fut in done:
                k = in_flight.pop(fut)
                yield k, fut.result()

    def close(self) -> None:
        self.pool.shutdown(wait=True, cancel_futures=True)


class DaskRunner:
    """Make shards as tasks on a Dask distributed cluster; results are written here.

    Up to two shards per cluster thread are in flight; each is released once written.
    """

    def __init__(self, address: str, config: DatasetConfig) -> None:
        self.urdf_text = Path(config.body).read_text()
        try:
            from distributed import Client
        except ImportError:
            raise DatasetError("--scheduler needs dask.distributed (pip install "
                               "'dask[distributed]')") from None
        try:
            self.client = Client(address, timeout=30)
        except OSError as exc:
            raise DatasetError(f"cannot reach the Dask scheduler at {address} ({exc})") from None
        self.config = config

    def __call__(self, ks: list[int]):
        from distributed import as_completed

        slots = max(2 * sum(self.client.nthreads().values()), 1)
        todo = list(reversed(ks))
        in_flight: dict = {}
        queue = as_completed()
        while todo or in_flight:
            while todo and len(in_flight) < slots:
                k = todo.pop()
                fut = self.client.submit(make_shard_remote, self.config, k, self.urdf_text,
                                         pure=False)
                in_flight[fut] = k
                queue.add(fut)
            fut = next(queue)
            k = in_flight.pop(fut)
            arrays = fut.result()
            fut.release()
            yield k, arrays

    def close(self) -> None:
        self.client.close()
