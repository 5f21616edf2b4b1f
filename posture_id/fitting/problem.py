"""The compiled fit problem for one body and recording: hold it, reuse it.

Two levels:

- a :class:`CompiledModel` owns the compiled CasADi simulation of one **block** of
  :data:`~posture_id.fitting.symbolic.BLOCK_SAMPLES` samples for N-segment bodies and its
  exact directional derivatives (with respect to the block's initial state and the
  unknowns), and a thread pool that evaluates Jacobian columns. A recording of any length
  is simulated block after block, each block starting from the state the last one ended
  in, and its Jacobian carried through the blocks the same way (forward mode): the
  recording's length is not in the compiled code, so one compile serves every length. The
  body's constants and the normalisation of the unknowns (the body's default gains) are
  inputs too, so every body with N segments shares it: a cohort of subjects with their
  own anthropometric bodies and trials of any length compiles once.
- a :class:`FitProblem` is one body and recording length on that model: its constants
  and defaults, filled in.

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
from dataclasses import dataclass, replace
from pathlib import Path

import casadi as ca
import numpy as np

from posture_id.bodies.body import Body
from posture_id.dec.parameters import DecParameters, default_parameters
from posture_id.fitting import symbolic
from posture_id.fitting.build import Backend, compile_functions
from posture_id.fitting.options import Compilation, FitOptions
from posture_id.fitting.symbolic import (
    BLOCK_SAMPLES,
    SymbolicModel,
    block_function,
    body_constants,
    buffer_sizes,
    delay_weights,
    n_body_constants,
    step_function,
)
from posture_id.fitting.unknowns import PER_MODULE

__all__ = ["ProblemKey", "ModelKey", "CompiledModel", "FitProblem"]

#: Default values that scale the unknowns (q = value / default − 1); Δ is fixed per model.
_SCALED_FIELDS = ("kp", "ki", "kd", "kpas", "bpas")


@dataclass(frozen=True)
class ModelKey:
    """Everything the compiled code depends on, and nothing else (no body constants).

    Attributes:
        n_segments: N. sample_every: steps per sample.
        dt: s. deadband_rad_s: θ. smooth_deadband_rad_s: softplus width.
        delay_upper: the upper bound of Δ̃ (sizes the delay buffers).
        default_delay_steps: (N,) the default delays Δ/dt that Δ̃ scales (the paper's per
            column, the same for every body).
        threads: Jacobian threads (columns per evaluation). compilation: C or VM.
    """

    n_segments: int
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
    """What one body's problem depends on: the body, the recording's length and its
    compiled model's key.

    Attributes:
        body: the body (its constants are inputs of the compiled model).
        n_samples: samples of the recording.
        compiled: the :class:`ModelKey` of its compiled model but for the default delays,
            which are the body's (``default_delay_steps`` empty; :meth:`model_key`).
    """

    body: Body
    n_samples: int
    compiled: ModelKey

    @classmethod
    def of(cls, body: Body, n_samples: int, options: FitOptions) -> ProblemKey:
        sim = options.simulation
        return cls(body, n_samples, ModelKey(
            body.n_segments, sim.sample_every, sim.dt, sim.deadband_rad_s,
            options.smooth_deadband_rad_s, options.delay_bounds[1], (), options.threads,
            options.compilation))

    def model_key(self, default_delay_steps: np.ndarray) -> ModelKey:
        """The key of the compiled model this body's problem runs on (any length)."""
        return replace(self.compiled,
                       default_delay_steps=tuple(float(d) for d in default_delay_steps))


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
    """Compiled simulation and directional derivatives of one block of samples for
    N-segment bodies, and the loops that run a recording of any length on them.

    The block functions take z = [initial state; unknowns q (7N,)], the block's rollout
    input (3, BLOCK_SAMPLES·sample_every) and the context c = [body constants
    (:func:`~.symbolic.body_constants`), the default Kp, Ki, Kd, Kpas, Bpas (5N)] that q
    scales; the simulation returns the block's end state and its samples, the derivative
    function both of them in ``width`` directions of z.

    Attributes:
        key: what it was built for. n: modules. n_state: the simulation's state size.
        block_steps: rollout steps per block. width: Jacobian columns per thread.
        backend: how the functions run (:class:`~posture_id.fitting.build.Backend`).
    """

    #: Models kept in the process-wide cache (each holds compiled code and threads).
    _cache = _ProcessCache(4)

    def __init__(self, key: ModelKey, notify=None) -> None:
        n = key.n_segments
        self.key = key
        self.n = n
        delay0 = np.array(key.default_delay_steps)
        sizes = buffer_sizes(delay0 * (1 + key.delay_upper))
        model = SymbolicModel(n, tuple(sizes), key.dt, key.deadband_rad_s,
                              smooth=key.smooth_deadband_rad_s)
        self.n_state = model.n_state
        self.block_steps = BLOCK_SAMPLES * key.sample_every
        unknowns = PER_MODULE * n
        n_body = n_body_constants(n)
        self.width = -(-unknowns // key.threads)  # Jacobian columns per thread

        def build() -> list[ca.Function]:
            block = block_function(model, key.sample_every)
            z = ca.MX.sym("z", self.n_state + unknowns)
            x0, q = z[: self.n_state], z[self.n_state :]
            u = ca.MX.sym("u", 3, self.block_steps)
            c = ca.MX.sym("c", n_body + 5 * n)
            base = {f: c[n_body + i * n : n_body + (i + 1) * n]
                    for i, f in enumerate(_SCALED_FIELDS)}
            delay = delay0 * (1 + q[3 * n : 4 * n])
            p = ca.vertcat(base["kp"] * (1 + q[0:n]), base["ki"] * (1 + q[n : 2 * n]),
                           base["kd"] * (1 + q[2 * n : 3 * n]), delay, q[4 * n : 5 * n],
                           base["kpas"] * (1 + q[5 * n : 6 * n]),
                           base["bpas"] * (1 + q[6 * n : 7 * n]))
            x_end, theta = block(x0, u, p, delay_weights(delay, sizes), c[:n_body])
            # vec() of the (N, B) samples is sample-major: row s·N + j, as numpy ravels (B, N)
            out = ca.vertcat(x_end, ca.vec(theta))
            sim = ca.Function("dec_block", [z, u, c], [out])
            forward = sim.forward(self.width)
            zs, us, cs = (ca.MX.sym("z", z.sparsity()), ca.MX.sym("u", u.sparsity()),
                          ca.MX.sym("c", c.sparsity()))
            seeds = ca.MX.sym("Z", self.n_state + unknowns, self.width)
            tangent = forward(zs, us, cs, sim(zs, us, cs), seeds,
                              ca.MX(3, self.block_steps * self.width),
                              ca.MX(c.shape[0], self.width))
            dirs = ca.Function("dec_block_dirs", [zs, us, cs, seeds], [tangent])
            return [sim, dirs]

        # everything the compiled functions depend on: the step's generated C, the sizes,
        # the default delays, and this module's and the model's code
        step_c = ca.CodeGenerator("step.c")
        step_c.add(step_function(model))
        code_key = "|".join([
            step_c.dump(), repr((key.sample_every, sizes, self.width,
                                 key.default_delay_steps)),
            Path(__file__).read_text(), Path(symbolic.__file__).read_text(),
        ]).encode()
        (self.sim, self.dirs), self.backend = compile_functions(
            f"dec_fit_n{n}", code_key, build, notify=notify, mode=key.compilation)
        self.backend: Backend
        self.pool = ThreadPoolExecutor(max_workers=key.threads,
                                       thread_name_prefix="posture_id-fit")

    @classmethod
    def get(cls, key: ModelKey, notify=None) -> CompiledModel:
        """The model for ``key``, from the process-wide cache when an equal one was built
        before (thread-safe; at most one build per key at a time)."""
        return cls._cache.get(key, lambda: cls(key, notify))

    def rollout(self, q: np.ndarray, u: np.ndarray, c: np.ndarray
                ) -> tuple[np.ndarray, list[np.ndarray]]:
        """The samples (S_u, N) rad of the whole rollout input u (3, blocks·block_steps)
        from rest, the first one the initial 0, and each block's initial state."""
        n, blocks = self.n, u.shape[1] // self.block_steps
        state = np.zeros(self.n_state)
        starts, samples = [], [np.zeros((1, n))]
        for k in range(blocks):
            starts.append(state)
            out = np.array(self.sim(np.concatenate([state, q]),
                                    u[:, k * self.block_steps : (k + 1) * self.block_steps],
                                    c)).ravel()
            state = out[: self.n_state]
            samples.append(out[self.n_state :].reshape(BLOCK_SAMPLES, n))
        return np.vstack(samples), starts

    def directions(self, q: np.ndarray, u: np.ndarray, c: np.ndarray, starts,
                   columns: list[int]) -> np.ndarray:
        """(N·(S_u + 1), len(columns)) ∂θ/∂q for the unknowns ``columns`` (at most
        ``width``), carried through the blocks from their initial states ``starts``;
        sample-major rows, the first sample's zero."""
        n_z = self.n_state + PER_MODULE * self.n
        seeds = np.zeros((n_z, self.width))
        seeds[self.n_state + np.asarray(columns), range(len(columns))] = 1.0
        rows = [np.zeros((self.n, self.width))]
        for k, state in enumerate(starts):
            out = np.array(self.dirs(np.concatenate([state, q]),
                                     u[:, k * self.block_steps : (k + 1) * self.block_steps],
                                     c, seeds))
            seeds[: self.n_state] = out[: self.n_state]
            rows.append(out[self.n_state :])
        return np.vstack(rows)[:, : len(columns)]


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
        delay0 = self.defaults.array("delay_s") / key.compiled.dt
        self.model = CompiledModel.get(key.model_key(delay0), notify)
        self.n_samples = key.n_samples
        blocks = -(-(key.n_samples - 1) // BLOCK_SAMPLES)  # whole blocks: u padded past
        self.n_steps_u = max(blocks, 1) * self.model.block_steps  # the end, dropped after
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
        return self.model.rollout(np.asarray(q, dtype=float), np.asarray(u, dtype=float),
                                  self.context)[0][: self.n_samples]

    def jacobian(self, q: np.ndarray, u: np.ndarray, columns: list[int]) -> np.ndarray:
        """(S·N, len(columns)) ∂θ/∂q (rad), columns evaluated in parallel chunks."""
        q, u = np.asarray(q, dtype=float), np.asarray(u, dtype=float)
        _, starts = self.model.rollout(q, u, self.context)
        width = self.model.width
        chunks = [columns[i : i + width] for i in range(0, len(columns), width)]

        def run(chunk):
            return self.model.directions(q, u, self.context, starts, chunk)

        rows = self.n_samples * self.n  # sample-major: the recording's samples come first
        return np.hstack(list(self.model.pool.map(run, chunks)))[:rows]
