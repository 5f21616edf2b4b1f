"""Where many independent tasks run: local threads, local processes, or a Dask cluster,
behind one interface.

    >>> with executor_for(scheduler=None, workers=2, processes=True) as run:
    ...     for item, result in run.unordered(task, items):
    ...         ...

Every executor yields ``(item, result)`` as tasks finish, keeps a bounded number in
flight (so that memory stays bounded however many items there are), and releases each
result once yielded. Local processes are spawned (torch and fork do not mix) and run one
thread of math each (threadpoolctl, numba and torch capped), so that the pool fills the
cores without oversubscribing them.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import (
    FIRST_COMPLETED,
    Executor,
    ProcessPoolExecutor,
    ThreadPoolExecutor,
    wait,
)
from typing import Any

from posture_id.errors import PostureIdError

__all__ = ["TaskExecutor", "LocalExecutor", "DaskExecutor", "executor_for",
           "cap_threads_to_one"]


#: What BLAS and OpenMP libraries read when they load.
_THREAD_VARIABLES = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")


def cap_threads_to_one() -> None:
    """This process's math on one thread: numba (its own setting; its environment
    variable only before it loads: numba refuses a change once its threads run), torch
    when it is loaded, the variables that BLAS and OpenMP libraries loaded later read,
    and the pools of those already loaded (threadpoolctl; numpy's among them). The
    initializer of every local worker process (the parent's environment is left alone)."""
    import sys

    import numpy  # noqa: F401  (its BLAS loaded, so that the limit reaches it)
    from threadpoolctl import threadpool_limits

    if "numba" in sys.modules:
        sys.modules["numba"].set_num_threads(1)  # loads its threading layer (OpenMP)
    else:
        os.environ["NUMBA_NUM_THREADS"] = "1"
    if "torch" in sys.modules:
        sys.modules["torch"].set_num_threads(1)
    os.environ.update(dict.fromkeys(_THREAD_VARIABLES, "1"))
    threadpool_limits(limits=1)


class TaskExecutor:
    """The interface: :meth:`unordered` and :meth:`close` (also a context manager)."""

    #: tasks in flight at most
    slots: int

    def _submit(self, fn: Callable, item: Any, args: tuple):  # pragma: no cover
        raise NotImplementedError

    def _next_done(self, in_flight: dict):  # pragma: no cover
        raise NotImplementedError

    def _result(self, future) -> Any:
        return future.result()

    def unordered(self, fn: Callable, items: Iterable, *args) -> Iterator[tuple[Any, Any]]:
        """``fn(item, *args)`` for every item, as ``(item, result)`` in the order they
        finish; at most :attr:`slots` in flight."""
        todo = list(items)[::-1]
        in_flight: dict = {}
        while todo or in_flight:
            while todo and len(in_flight) < self.slots:
                item = todo.pop()
                in_flight[self._submit(fn, item, args)] = item
            future = self._next_done(in_flight)
            item = in_flight.pop(future)
            yield item, self._result(future)

    def close(self) -> None:  # pragma: no cover
        raise NotImplementedError

    def __enter__(self) -> TaskExecutor:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class LocalExecutor(TaskExecutor):
    """Threads (for work that releases the GIL: the compiled simulator, FFTs) or spawned
    one-thread processes (for work that does not: least squares, the CNN)."""

    def __init__(self, workers: int | None = None, processes: bool = False) -> None:
        if workers is not None and workers < 1:
            raise PostureIdError(f"workers must be ≥ 1, got {workers}")
        self.workers = workers or os.cpu_count() or 1
        self.slots = 2 * self.workers
        self.pool: Executor
        if processes:
            self.pool = ProcessPoolExecutor(
                max_workers=self.workers, mp_context=multiprocessing.get_context("spawn"),
                initializer=cap_threads_to_one)
        else:
            self.pool = ThreadPoolExecutor(max_workers=self.workers)

    def _submit(self, fn, item, args):
        return self.pool.submit(fn, item, *args)

    def _next_done(self, in_flight):
        done, _ = wait(in_flight, return_when=FIRST_COMPLETED)
        return next(iter(done))

    def close(self) -> None:
        self.pool.shutdown(wait=True, cancel_futures=True)


#: How long a Dask scheduler is waited for before it is called unreachable, s.
CONNECT_TIMEOUT_S = 30.0


def check_scheduler_address(address: str, timeout_s: float = 5.0) -> None:
    """Refuse, in seconds rather than Dask's half minute of retries, a scheduler address
    that is malformed or where nothing accepts a connection (``tcp://host:port``)."""
    import socket
    from urllib.parse import urlsplit

    parts = urlsplit(address if "://" in address else f"tcp://{address}")
    if parts.scheme not in ("tcp", "tls"):  # inproc://, ucx://, ws://: Dask's own check
        return
    try:
        host, port = parts.hostname, parts.port
    except ValueError:
        host = port = None
    if not host or port is None:
        raise PostureIdError(f"--scheduler {address}: not a Dask scheduler address "
                             "(tcp://host:port)")
    try:
        with socket.create_connection((host, port), timeout=timeout_s):
            pass
    except OSError as exc:
        raise PostureIdError(f"--scheduler {address}: nothing accepts a connection there "
                             f"({exc.strerror or exc}); start the scheduler (dask scheduler) "
                             "or check the address") from None


class DaskExecutor(TaskExecutor):
    """Tasks on a running Dask distributed cluster (``tcp://host:port``); up to two per
    cluster thread in flight, each released once its result is here."""

    def __init__(self, address: str, connect_timeout_s: float = CONNECT_TIMEOUT_S) -> None:
        try:
            from distributed import Client, as_completed
        except ImportError:
            raise PostureIdError("--scheduler needs dask.distributed (pip install "
                                 "'dask[distributed]')") from None
        try:
            self.client = Client(address, timeout=connect_timeout_s)
        except OSError as exc:
            raise PostureIdError(f"cannot reach the Dask scheduler at {address} "
                                 f"({exc})") from None
        self.slots = max(2 * sum(self.client.nthreads().values()), 1)
        self._queue = as_completed()

    def _submit(self, fn, item, args):
        future = self.client.submit(fn, item, *args, pure=False)
        self._queue.add(future)
        return future

    def _next_done(self, in_flight):
        return next(self._queue)

    def _result(self, future):
        result = future.result()
        future.release()
        return result

    def close(self) -> None:
        self.client.close()


def executor_for(scheduler: str | None = None, workers: int | None = None,
                 processes: bool = False) -> TaskExecutor:
    """A Dask executor for a scheduler address, else a local one (threads, or one-thread
    processes with ``processes``)."""
    if scheduler:
        return DaskExecutor(scheduler)
    return LocalExecutor(workers, processes)
