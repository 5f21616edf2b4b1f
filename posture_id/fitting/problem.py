"""The compiled fit problem for one (body, recording length, model): hold it, reuse it.

A :class:`FitProblem` owns the compiled CasADi simulation of a recording and its exact
directional derivatives, and a thread pool that evaluates Jacobian columns. It is safe to
use from several threads at once (two fits side by side share it). :meth:`FitProblem.get`
keeps a few in a process-wide cache keyed only on what the compiled code depends on
(:class:`ProblemKey`): changing an iteration limit or a seed does not rebuild it, and
dropping one from the cache never stops a fit that still holds it.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from posture_id.bodies.body import Body
from posture_id.dec.parameters import DecParameters, default_parameters
from posture_id.fitting import symbolic
from posture_id.fitting.build import Backend, compile_functions
from posture_id.fitting.options import Compilation, FitOptions
from posture_id.fitting.symbolic import (
    SymbolicModel,
    buffer_sizes,
    delay_weights,
    rollout_function,
    rollout_steps,
    step_function,
)
from posture_id.fitting.unknowns import PER_MODULE

__all__ = ["ProblemKey", "FitProblem"]

_BASE_FIELDS = ("kp", "ki", "kd", "delay_s", "kpas", "bpas")


@dataclass(frozen=True)
class ProblemKey:
    """Everything the compiled functions depend on, and nothing else.

    Attributes:
        body: the body (its constants enter the generated code).
        n_samples: samples of the recording. sample_every: steps per sample.
        dt: s. deadband_rad_s: θ. smooth_deadband_rad_s: softplus width.
        delay_upper: the upper bound of Δ̃ (sizes the delay buffers).
        threads: Jacobian threads (columns per evaluation). compilation: C or VM.
    """

    body: Body
    n_samples: int
    sample_every: int
    dt: float
    deadband_rad_s: float
    smooth_deadband_rad_s: float
    delay_upper: float
    threads: int
    compilation: Compilation

    @classmethod
    def of(cls, body: Body, n_samples: int, options: FitOptions) -> ProblemKey:
        sim = options.simulation
        return cls(body, n_samples, sim.sample_every, sim.dt, sim.deadband_rad_s,
                   options.smooth_deadband_rad_s, options.delay_bounds[1], options.threads,
                   options.compilation)


class FitProblem:
    """Compiled simulation and Jacobian of one body and recording length.

    Attributes:
        key: what it was built for. n: modules. n_steps_u: steps of the rollout input.
        defaults: the body's default parameters (the normalisation of the unknowns).
        backend: how the functions run (:class:`~posture_id.fitting.build.Backend`).
    """

    _cache: OrderedDict = OrderedDict()
    _cache_lock = threading.Lock()
    #: Problems kept in the process-wide cache (each holds compiled code and threads).
    CACHE_SIZE = 4

    def __init__(self, key: ProblemKey, notify=None) -> None:
        body = key.body
        n = body.n_segments
        self.key = key
        self.n = n
        self.n_steps_u = rollout_steps(key.n_samples, key.sample_every)
        self.defaults: DecParameters = default_parameters(body)
        base = {f: self.defaults.array(f) for f in _BASE_FIELDS}
        delay0 = base["delay_s"] / key.dt
        sizes = buffer_sizes(delay0 * (1 + key.delay_upper))
        model = SymbolicModel(body, tuple(sizes), key.dt, key.deadband_rad_s,
                              smooth=key.smooth_deadband_rad_s)
        unknowns = PER_MODULE * n
        self.width = -(-unknowns // key.threads)  # Jacobian columns per thread

        def build() -> list[ca.Function]:
            rollout = rollout_function(model, key.n_samples, key.sample_every)
            q = ca.MX.sym("q", unknowns)
            u = ca.MX.sym("u", 3, self.n_steps_u)
            delay = delay0 * (1 + q[3 * n : 4 * n])
            p = ca.vertcat(base["kp"] * (1 + q[0:n]), base["ki"] * (1 + q[n : 2 * n]),
                           base["kd"] * (1 + q[2 * n : 3 * n]), delay, q[4 * n : 5 * n],
                           base["kpas"] * (1 + q[5 * n : 6 * n]),
                           base["bpas"] * (1 + q[6 * n : 7 * n]))
            theta = rollout(u, p, delay_weights(delay, sizes))
            seeds = ca.MX.sym("V", unknowns, self.width)
            sim = ca.Function("dec_sim", [q, u], [theta])
            # vec() of the (N, S) samples is sample-major: row s·N + j, as numpy ravels (S, N)
            dirs = ca.Function("dec_dirs", [q, u, seeds],
                               [ca.jtimes(ca.vec(theta), q, seeds)])
            return [sim, dirs]

        # everything the compiled functions depend on: the step (its generated C holds the
        # body's constants), sizes, defaults, and this module's and the model's code
        step_c = ca.CodeGenerator("step.c")
        step_c.add(step_function(model))
        code_key = "|".join([
            step_c.dump(), repr((key.n_samples, key.sample_every, sizes, self.width)),
            repr({k: v.tolist() for k, v in base.items()}),
            Path(__file__).read_text(), Path(symbolic.__file__).read_text(),
        ]).encode()
        (self.sim, self.dirs), self.backend = compile_functions(
            f"dec_fit_n{n}_{key.n_samples}", code_key, build, notify=notify,
            mode=key.compilation)
        self.backend: Backend
        self._pool = ThreadPoolExecutor(max_workers=key.threads,
                                        thread_name_prefix="posture_id-fit")

    @classmethod
    def get(cls, body: Body, n_samples: int, options: FitOptions, notify=None) -> FitProblem:
        """The problem for (body, n_samples, options), from the process-wide cache when an
        equal one was built before (thread-safe; at most one build per key at a time)."""
        key = ProblemKey.of(body, n_samples, options)
        with cls._cache_lock:
            if key in cls._cache:
                cls._cache.move_to_end(key)
                return cls._cache[key]
            problem = cls(key, notify)
            cls._cache[key] = problem
            while len(cls._cache) > cls.CACHE_SIZE:
                cls._cache.popitem(last=False)  # a fit still holding it keeps it alive
            return problem

    def simulate(self, q: np.ndarray, u: np.ndarray) -> np.ndarray:
        """(S, N) rad segment angles for unknowns q (7N,) and rollout input u."""
        return np.array(self.sim(q, u)).T

    def jacobian(self, q: np.ndarray, u: np.ndarray, columns: list[int]) -> np.ndarray:
        """(S·N, len(columns)) ∂θ/∂q (rad), columns evaluated in parallel chunks."""
        chunks = [columns[i : i + self.width] for i in range(0, len(columns), self.width)]

        def run(chunk):
            seeds = np.zeros((PER_MODULE * self.n, self.width))
            seeds[chunk, range(len(chunk))] = 1.0
            return np.array(self.dirs(q, u, seeds))[:, : len(chunk)]

        return np.hstack(list(self._pool.map(run, chunks)))
