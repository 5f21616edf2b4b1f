"""One executor interface for local threads, one-thread processes and Dask."""

from __future__ import annotations

import pytest

from posture_id.errors import PostureIdError
from posture_id.executors import LocalExecutor


def _square(x: int, offset: int = 0) -> int:
    return x * x + offset


def _threads(_: int) -> tuple[int, int]:
    """(BLAS/OpenMP threads, numba threads) inside a worker."""
    import numba
    from threadpoolctl import threadpool_info

    pools = [p["num_threads"] for p in threadpool_info()]
    return max(pools, default=1), numba.get_num_threads()


@pytest.mark.parametrize("processes", [False, True])
def test_every_item_comes_back_once_with_its_result(processes):
    with LocalExecutor(2, processes=processes) as run:
        out = dict(run.unordered(_square, range(25), 3))
    assert out == {x: x * x + 3 for x in range(25)}


def test_worker_processes_do_their_math_on_one_thread():
    with LocalExecutor(2, processes=True) as run:
        seen = {result for _, result in run.unordered(_threads, range(4))}
    assert seen == {(1, 1)}


def test_bad_requests_are_refused_in_words():
    with pytest.raises(PostureIdError, match="workers must be ≥ 1"):
        LocalExecutor(0)


def test_an_unreachable_scheduler_is_refused_in_words():
    """(It waits for the connection's time-out, 30 s by default, 2 s here.)"""
    from posture_id.executors import DaskExecutor

    with pytest.raises(PostureIdError, match="cannot reach the Dask scheduler"):
        DaskExecutor("tcp://127.0.0.1:9", connect_timeout_s=2.0)
