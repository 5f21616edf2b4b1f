"""Where shards are made: local threads (the kernel and the FFTs release the GIL) or a
Dask distributed cluster (:mod:`posture_id.executors`).

:func:`shard_runner` gives a callable that takes shard indices and yields ``(k, arrays)``
as shards complete, at most two per thread in flight, so memory stays bounded.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

from posture_id.bodies.body import Body
from posture_id.errors import PostureIdError
from posture_id.executors import TaskExecutor, executor_for
from posture_id.learning.data.trial_config import DatasetConfig, DatasetError
from posture_id.learning.data.trial_shards import make_shard, make_shard_remote

__all__ = ["shard_runner"]


def _local_shard(k: int, config: DatasetConfig, body: Body) -> dict:
    return make_shard(config, k, body)


def _remote_shard(k: int, config: DatasetConfig, urdf_text: str) -> dict:
    return make_shard_remote(config, k, urdf_text)


def shard_runner(config: DatasetConfig, body: Body, workers: int | None = None,
                 scheduler: str | None = None
                 ) -> tuple[Callable[[list[int]], Iterator[tuple[int, dict]]], TaskExecutor]:
    """(a runner of shard indices, its executor to close): local threads, or tasks on the
    Dask cluster at ``scheduler`` that carry the body's URDF text (the workers need not
    see the file)."""
    try:
        executor = executor_for(scheduler, workers)
    except PostureIdError as exc:
        raise DatasetError(str(exc)) from None
    if scheduler:
        urdf_text = Path(config.body).read_text()
        return (lambda ks: executor.unordered(_remote_shard, ks, config, urdf_text)), executor
    return (lambda ks: executor.unordered(_local_shard, ks, config, body)), executor
