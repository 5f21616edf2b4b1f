"""Worker processes for identifying many recordings: one per core, each on one thread
(:class:`~posture_id.executors.LocalExecutor`), each building its
:class:`~posture_id.identify.Identifier` once."""

from __future__ import annotations

import functools

from posture_id.bodies.body import load_body
from posture_id.fitting.options import FitOptions
from posture_id.identify import Identifier, Method
from posture_id.identify.networks import Network, network_for

__all__ = ["worker_identifier"]


@functools.cache
def _cnn(urdf: str, model: str | None) -> Network:
    return network_for(model, load_body(urdf))


@functools.cache
def worker_identifier(urdf: str, method: str, model: str | None = None) -> Identifier:
    """The identifier of a worker process for a body (URDF path), a method and a model
    (None: the bundled one), built on its first task and kept for the rest (the pool's
    processes live for the whole run); its least squares runs on one thread, since the
    workers fill the cores. The identifiers of one body share one loaded network."""
    method = Method(method)
    cnn = None if method is Method.FIT else _cnn(urdf, model)
    body = load_body(urdf) if cnn is None else cnn.body
    return Identifier(body, method, cnn, FitOptions(threads=1))
