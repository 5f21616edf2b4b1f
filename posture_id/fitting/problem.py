"""The compiled fit problem for one (body, recording length, model): hold it, reuse it.

Two levels:

- a :class:`CompiledModel` owns the compiled CasADi simulation of a recording length for
  N-segment bodies and its exact directional derivatives, and a thread pool that evaluates
  Jacobian columns. The body's constants and the normalisation of the unknowns (the body's
  default gains) are inputs of the compiled code, so every body with N segments shares
  it: a cohort of subjects with their own anthropometric bodies compiles once.
- a :class:`FitProblem` is one body on that model: its constants and defaults, filled in.

The compiled model is built for a **length bucket**, not for the recording's exact length:
the recording's samples rounded up to a whole number of :data:`BUCKET_SAMPLES` (10 s at
50 Hz). The simulation is causal, so its first S samples do not depend on what follows;
the problem returns those S and the Jacobian's rows for them, and a lab's trials that
differ in length by a few seconds (121.3 s, 119.8 s, ...) share one compile instead of
paying a minute of compiler each.

Both are safe to use from several threads at once (two fits side by side share them).
:meth:`FitProblem.get` and :meth:`CompiledModel.get` keep a few in process-wide caches
keyed only on what they depend on (:class:`ProblemKey`, :class:`ModelKey`): changing an
iteration limit or a seed does not rebuild them, and dropping one from a cache never stops
a fit that still holds it.
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
    body_constants,
    buffer_sizes,
    delay_weights,
    n_body_constants,
    rollout_function,
    rollout_steps,
    step_function,
)
from posture_id.fitting.unknowns import PER_MODULE

__all__ = ["ProblemKey", "ModelKey", "CompiledModel", "FitProblem"]

#: Recording lengths share a compiled model within buckets of this many samples.
BUCKET_SAMPLES = 500


def bucket_samples(n_samples: int) -> int:
    """The compiled model's length for a recording of ``n_samples``: rounded up to a
    whole number of :data:`BUCKET_SAMPLES`."""
    return -(-int(n_samples) // BUCKET_SAMPLES) * BUCKET_SAMPLES


#: Default values that scale the unknowns (q = value / default − 1); Δ is fixed per model.
_SCALED_FIELDS = ("kp", "ki", "kd", "kpas", "bpas")


@dataclass(frozen=True)
class ModelKey:
    """Everything the compiled code depends on, and nothing else (no body constants).

    Attributes:
        n_segments: N. n_samples: samples of the recording. sample_every: steps per sample.
        dt: s. deadband_rad_s: θ. smooth_deadband_rad_s: softplus width.
        delay_upper: the upper bound of Δ̃ (sizes the delay buffers).
        default_delay_steps: (N,) the default delays Δ/dt that Δ̃ scales (the paper's per
            column, the same for every body).
        threads: Jacobian threads (columns per evaluation). compilation: C or VM.
    """

    n_segments: int
    n_samples: int
    sample_every: int
    dt: float
    deadband_rad_s: float
    smooth_deadband_rad_s: float
    delay_upper: float
    default_delay_steps: tuple[float, ...]
    threads: int
    compilation: Compilation


@dataclass(frozen=True)
class ProblemKey:
    """What one body's problem depends on: the body and its compiled model's key.

    Attributes:
        body: the body (its constants are inputs of the compiled model).
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

    def model_key(self, default_delay_steps: np.ndarray) -> ModelKey:
        """The key of the compiled model this body's problem runs on (its length the
        recording's bucket, :func:`bucket_samples`)."""
        return ModelKey(self.body.n_segments, bucket_samples(self.n_samples),
                        self.sample_every, self.dt,
                        self.deadband_rad_s, self.smooth_deadband_rad_s, self.delay_upper,
                        tuple(float(d) for d in default_delay_steps), self.threads,
                        self.compilation)


class _ProcessCache:
    """A small process-wide least-recently-used cache of built objects (thread-safe; at
    most one build per key at a time). Dropping an entry never stops a user that still
    holds it."""

    def __init__(self, size: int) -> None:
        self.size = size
        self._items: OrderedDict = OrderedDict()
        self._lock = threading.Lock()

    def get(self, key, build):
        """The object for ``key``: cached, or ``build()`` and cached."""
        with self._lock:
            if key in self._items:
                self._items.move_to_end(key)
                return self._items[key]
            value = self._items[key] = build()
            while len(self._items) > self.size:
                self._items.popitem(last=False)
            return value


class CompiledModel:
    """Compiled simulation and Jacobian of one recording length for N-segment bodies.

    The functions take the unknowns q (7N,), the rollout input u (3, n_steps_u) and the
    context c = [body constants (:func:`~.symbolic.body_constants`), the default Kp, Ki,
    Kd, Kpas, Bpas (5N)] that q scales.

    Attributes:
        key: what it was built for. n: modules. n_steps_u: steps of the rollout input.
        width: Jacobian columns per thread.
        backend: how the functions run (:class:`~posture_id.fitting.build.Backend`).
    """

    #: Models kept in the process-wide cache (each holds compiled code and threads).
    _cache = _ProcessCache(4)

    def __init__(self, key: ModelKey, notify=None) -> None:
        n = key.n_segments
        self.key = key
        self.n = n
        self.n_steps_u = rollout_steps(key.n_samples, key.sample_every)
        delay0 = np.array(key.default_delay_steps)
        sizes = buffer_sizes(delay0 * (1 + key.delay_upper))
        model = SymbolicModel(n, tuple(sizes), key.dt, key.deadband_rad_s,
                              smooth=key.smooth_deadband_rad_s)
        unknowns = PER_MODULE * n
        n_body = n_body_constants(n)
        self.width = -(-unknowns // key.threads)  # Jacobian columns per thread

        def build() -> list[ca.Function]:
            rollout = rollout_function(model, key.n_samples, key.sample_every)
            q = ca.MX.sym("q", unknowns)
            u = ca.MX.sym("u", 3, self.n_steps_u)
            c = ca.MX.sym("c", n_body + 5 * n)
            base = {f: c[n_body + i * n : n_body + (i + 1) * n]
                    for i, f in enumerate(_SCALED_FIELDS)}
            delay = delay0 * (1 + q[3 * n : 4 * n])
            p = ca.vertcat(base["kp"] * (1 + q[0:n]), base["ki"] * (1 + q[n : 2 * n]),
                           base["kd"] * (1 + q[2 * n : 3 * n]), delay, q[4 * n : 5 * n],
                           base["kpas"] * (1 + q[5 * n : 6 * n]),
                           base["bpas"] * (1 + q[6 * n : 7 * n]))
            theta = rollout(u, p, delay_weights(delay, sizes), c[:n_body])
            seeds = ca.MX.sym("V", unknowns, self.width)
            sim = ca.Function("dec_sim", [q, u, c], [theta])
            # vec() of the (N, S) samples is sample-major: row s·N + j, as numpy ravels (S, N)
            dirs = ca.Function("dec_dirs", [q, u, c, seeds],
                               [ca.jtimes(ca.vec(theta), q, seeds)])
            return [sim, dirs]

        # everything the compiled functions depend on: the step's generated C, the sizes,
        # the default delays, and this module's and the model's code
        step_c = ca.CodeGenerator("step.c")
        step_c.add(step_function(model))
        code_key = "|".join([
            step_c.dump(), repr((key.n_samples, key.sample_every, sizes, self.width,
                                 key.default_delay_steps)),
            Path(__file__).read_text(), Path(symbolic.__file__).read_text(),
        ]).encode()
        (self.sim, self.dirs), self.backend = compile_functions(
            f"dec_fit_n{n}_{key.n_samples}", code_key, build, notify=notify,
            mode=key.compilation)
        self.backend: Backend
        self.pool = ThreadPoolExecutor(max_workers=key.threads,
                                       thread_name_prefix="posture_id-fit")

    @classmethod
    def get(cls, key: ModelKey, notify=None) -> CompiledModel:
        """The model for ``key``, from the process-wide cache when an equal one was built
        before (thread-safe; at most one build per key at a time)."""
        return cls._cache.get(key, lambda: cls(key, notify))


class FitProblem:
    """One body's compiled simulation and Jacobian for one recording length.

    Attributes:
        key: what it was built for. n: modules. n_steps_u: steps of the rollout input.
        defaults: the body's default parameters (the normalisation of the unknowns).
        model: the :class:`CompiledModel` it runs on (shared by every N-segment body).
        backend: how the functions run (:class:`~posture_id.fitting.build.Backend`).
    """

    #: Problems kept in the process-wide cache (small: the compiled code is shared).
    _cache = _ProcessCache(16)

    def __init__(self, key: ProblemKey, notify=None) -> None:
        body = key.body
        self.key = key
        self.n = body.n_segments
        self.defaults: DecParameters = default_parameters(body)
        delay0 = self.defaults.array("delay_s") / key.dt
        self.model = CompiledModel.get(key.model_key(delay0), notify)
        self.n_samples = key.n_samples  # the recording's; the model's may be longer
        self.n_steps_u = self.model.n_steps_u
        self.backend: Backend = self.model.backend
        self.context = np.concatenate([body_constants(body)]
                                      + [self.defaults.array(f) for f in _SCALED_FIELDS])

    @classmethod
    def get(cls, body: Body, n_samples: int, options: FitOptions, notify=None) -> FitProblem:
        """The problem for (body, n_samples, options), from the process-wide cache when an
        equal one was made before; its compiled model is shared by every body with as
        many segments (thread-safe)."""
        key = ProblemKey.of(body, n_samples, options)
        return cls._cache.get(key, lambda: cls(key, notify))

    def simulate(self, q: np.ndarray, u: np.ndarray) -> np.ndarray:
        """(S, N) rad segment angles for unknowns q (7N,) and rollout input u (S: the
        recording's samples)."""
        return np.array(self.model.sim(q, u, self.context)).T[: self.n_samples]

    def jacobian(self, q: np.ndarray, u: np.ndarray, columns: list[int]) -> np.ndarray:
        """(S·N, len(columns)) ∂θ/∂q (rad), columns evaluated in parallel chunks."""
        width = self.model.width
        chunks = [columns[i : i + width] for i in range(0, len(columns), width)]

        def run(chunk):
            seeds = np.zeros((PER_MODULE * self.n, width))
            seeds[chunk, range(len(chunk))] = 1.0
            return np.array(self.model.dirs(q, u, self.context, seeds))[:, : len(chunk)]

        rows = self.n_samples * self.n  # sample-major: the recording's samples come first
        return np.hstack(list(self.model.pool.map(run, chunks)))[:rows]
