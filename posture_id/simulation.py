"""Simulate DEC-controlled bodies on a tilting support: one trial or a batch.

    >>> from posture_id import load_body, simulate
    >>> result = simulate(load_body())            # default TIP, defaults, PRTS 1° p-p × 2
    >>> result.theta.shape                        # (6051, 3) segment angles in space, rad

The fast path is the compiled lane kernel of :mod:`posture_id.kernel`, run in blocks on
all cores; :func:`posture_id.reference.simulate_reference` steps the same controller with
Pinocchio's forward dynamics instead, for validation.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np

from posture_id.body import Body
from posture_id.errors import SimulationError
from posture_id.kernel import LANES, buffer_length, kernels
from posture_id.parameters import DecParameters, ParameterArrays
from posture_id.stimulus import TiltProfile, prts

__all__ = [
    "SimulationOptions",
    "SimulationResult",
    "BatchResult",
    "simulate",
    "simulate_batch",
    "MAX_SWAY_LIMIT_DEG",
    "MAX_DELAY_S",
]

#: Largest sway limit accepted: the kernel's polynomial sin/cos are exact up to 45°.
MAX_SWAY_LIMIT_DEG = 45.0
#: Largest lumped delay accepted, s (sizes the delay buffers).
MAX_DELAY_S = 2.0


@dataclass(frozen=True)
class SimulationOptions:
    """How to simulate (MODEL §2 and §5 decisions, all configurable).

    Attributes:
        dt: integration step, s (default 2 ms).
        sample_rate_hz: output rate, Hz (default 50); 1/rate must be a multiple of dt.
        sway_limit_deg: a trial is aborted when any segment leaves ±this angle (default 6°).
        deadband_rad_s: θ, dead-band of the tilt-velocity estimator (default 0.0003 rad/s,
            the paper's text value; its table says 0.03).
        workers: threads for a batch (default: all cores).
    """

    dt: float = 0.002
    sample_rate_hz: float = 50.0
    sway_limit_deg: float = 6.0
    deadband_rad_s: float = 0.0003
    workers: int | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.dt) and 0 < self.dt <= 0.05):
            raise SimulationError(f"dt must be in (0, 0.05] s, got {self.dt}")
        if not (math.isfinite(self.sample_rate_hz) and self.sample_rate_hz > 0):
            raise SimulationError(f"sample_rate_hz must be > 0, got {self.sample_rate_hz}")
        ratio = 1.0 / (self.sample_rate_hz * self.dt)
        if abs(ratio - round(ratio)) > 1e-6 or round(ratio) < 1:
            raise SimulationError(
                f"the sample period 1/{self.sample_rate_hz:g} Hz is not a multiple of dt = "
                f"{self.dt:g} s"
            )
        if not (0 < self.sway_limit_deg <= MAX_SWAY_LIMIT_DEG):
            raise SimulationError(
                f"sway_limit_deg must be in (0, {MAX_SWAY_LIMIT_DEG:g}], got {self.sway_limit_deg}"
            )
        if not (math.isfinite(self.deadband_rad_s) and self.deadband_rad_s >= 0):
            raise SimulationError(f"deadband_rad_s must be ≥ 0, got {self.deadband_rad_s}")
        if self.workers is not None and self.workers < 1:
            raise SimulationError(f"workers must be ≥ 1, got {self.workers}")

    @property
    def sample_every(self) -> int:
        """Integration steps per output sample."""
        return round(1.0 / (self.sample_rate_hz * self.dt))

    def n_steps(self, stimulus: TiltProfile) -> int:
        """Integration steps covering the stimulus (its duration must be a multiple of the
        sample period)."""
        steps = stimulus.duration / self.dt
        n = round(steps)
        if abs(steps - n) > 1e-6 or n % self.sample_every:
            raise SimulationError(
                f"stimulus duration {stimulus.duration:g} s is not a whole number of samples "
                f"at {self.sample_rate_hz:g} Hz"
            )
        return n

    def sampled(self, tilt_grid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Sample times (S,) s and the tilt (S,) rad at them, from the tilt on the step grid."""
        tilt = tilt_grid[:: self.sample_every].copy()
        return np.arange(len(tilt)) * (self.sample_every * self.dt), tilt

    def delay_steps(self, delay_s: np.ndarray) -> np.ndarray:
        """Δ/dt, snapped to the nearest integer when within 1e-9 of it (float noise)."""
        steps = np.asarray(delay_s, dtype=float) / self.dt
        nearest = np.round(steps)
        return np.where(np.abs(steps - nearest) < 1e-9, nearest, steps)


@dataclass(frozen=True)
class SimulationResult:
    """One simulated trial, sampled at ``sample_rate_hz``.

    Attributes:
        time: (S,) s. tilt: (S,) rad, α_FS.
        theta: (S, N) rad, segment angles in space (NaN from an abort on).
        alpha: (S, N) rad, COM-above angles α_i,S (alpha[:, 0] is the body sway α_BS).
        abort_time: s at which a segment left the sway limit, or None.
        segments, joints: URDF names, support upward.
        parameters: the DEC parameters simulated.
        description: the stimulus.
    """

    time: np.ndarray
    tilt: np.ndarray
    theta: np.ndarray
    alpha: np.ndarray
    abort_time: float | None
    segments: tuple[str, ...]
    joints: tuple[str, ...]
    parameters: DecParameters = field(repr=False)
    description: str = ""

    @property
    def stable(self) -> bool:
        """True when the trial stayed within the sway limit to the end."""
        return self.abort_time is None

    def to_csv(self, path) -> None:
        """Write the recording CSV (``time_s,tilt_deg,<segment>_deg,...``, degrees)."""
        from posture_id.recording import Recording

        Recording(self.time, self.tilt, self.theta, self.segments).to_csv(path)

    def plot(self, path=None, title: str | None = None):
        """Tilt and segment sway against time; saved to ``path`` when given."""
        from posture_id.plotting import plot_trial

        return plot_trial(self, path=path, title=title)


@dataclass(frozen=True)
class BatchResult:
    """B simulated trials with the same stimulus.

    Attributes:
        time: (S,) s. tilt: (S,) rad.
        theta, alpha: (B, S, N) rad, NaN from each trial's abort on.
        abort_time: (B,) s, NaN for a trial that stayed within the sway limit.
        segments, joints: URDF names. parameters: the (B, N) parameter arrays.
    """

    time: np.ndarray
    tilt: np.ndarray
    theta: np.ndarray
    alpha: np.ndarray
    abort_time: np.ndarray
    segments: tuple[str, ...]
    joints: tuple[str, ...]
    parameters: ParameterArrays = field(repr=False)
    description: str = ""

    @property
    def stable(self) -> np.ndarray:
        """(B,) bool, True for trials that stayed within the sway limit."""
        return np.isnan(self.abort_time)

    def __len__(self) -> int:
        return self.theta.shape[0]

    def trial(self, b: int) -> SimulationResult:
        """Trial ``b`` as a :class:`SimulationResult`."""
        abort = self.abort_time[b]
        return SimulationResult(
            time=self.time, tilt=self.tilt, theta=self.theta[b], alpha=self.alpha[b],
            abort_time=None if np.isnan(abort) else float(abort), segments=self.segments,
            joints=self.joints, parameters=self.parameters.trial(b, self.joints),
            description=self.description,
        )


def _lane_rows(block: np.ndarray) -> np.ndarray:
    """(count, N) values of a block's trials → (N, LANES), padded with the first trial."""
    if len(block) < LANES:
        block = np.concatenate([block, np.repeat(block[:1], LANES - len(block), axis=0)])
    return block.T


def block_arrays(k, params: ParameterArrays, options: SimulationOptions, first: int,
                 count: int) -> tuple[np.ndarray, np.ndarray]:
    """The flat parameter rows and zeroed delay buffers of one block of the kernel ``k``.

    Delays become Δ/dt steps (snapped to whole steps within 1e-9), with their ceiling and
    the interpolation weight the kernel reads; the buffers are sized for the block's
    longest delay.
    """
    n = params.kp.shape[1]
    pr = k.par_rows
    trials = slice(first, first + count)
    delay = options.delay_steps(params.delay_s[trials])
    delay_ceil = np.ceil(delay)
    rows = {
        pr.kp: params.kp[trials], pr.ki: params.ki[trials], pr.kd: params.kd[trials],
        pr.sign: params.sign[trials], pr.kpas: params.kpas[trials],
        pr.bpas: params.bpas[trials], pr.delay: delay, pr.delay_ceil: delay_ceil,
        pr.delay_frac: delay_ceil - delay,
    }
    par = np.empty((pr.count, LANES))
    for row, values in rows.items():
        par[row : row + n] = _lane_rows(values)
    buf = np.zeros(n * buffer_length(float(delay.max())) * LANES)
    return par.ravel(), buf


def simulate_batch(
    body: Body,
    params: ParameterArrays,
    stimulus: TiltProfile | None = None,
    options: SimulationOptions | None = None,
    progress: Callable[[int], None] | None = None,
) -> BatchResult:
    """Simulate B trials of ``body`` with their own parameters, in parallel.

    Args:
        body: the chain (N segments).
        params: (B, N) parameter arrays.
        stimulus: tilt profile (default: PRTS, 242 states, 2 cycles, 1° p-p).
        options: step, sampling, sway limit, dead-band, threads.
        progress: called with the number of trials of each block as it completes.
    """
    options = options or SimulationOptions()
    stimulus = stimulus or prts()
    n = body.n_segments
    if params.kp.shape[1] != n:
        raise SimulationError(
            f"parameters have {params.kp.shape[1]} modules, body '{body.name}' has {n} joints"
        )
    if np.any(params.delay_s > MAX_DELAY_S):
        raise SimulationError(f"a delay exceeds the supported maximum of {MAX_DELAY_S} s")
    n_steps = options.n_steps(stimulus)
    every = options.sample_every
    n_samples = n_steps // every + 1
    tilt, tilt_vel = stimulus.on_grid(options.dt, n_steps)
    k = kernels(n)
    d = body.coupling
    d_re, d_im = np.ascontiguousarray(d.real), np.ascontiguousarray(d.imag)
    s_re = np.ascontiguousarray(body.gravity_lever.real)
    s_im = np.ascontiguousarray(body.gravity_lever.imag)
    inertia = np.ascontiguousarray(body.inertias)
    n_trials = params.n_trials
    out_theta = np.empty((n_trials, n_samples, n))
    out_alpha = np.empty((n_trials, n_samples, n))
    abort_step = np.empty(n_trials, dtype=np.int64)
    limit = math.radians(options.sway_limit_deg)

    def run_block(first: int) -> int:
        count = min(LANES, n_trials - first)
        par, buf = block_arrays(k, params, options, first, count)
        w = np.zeros(k.rows.count * LANES)
        k.simulate_block(
            w, par, buf, d_re, d_im, inertia, s_re, s_im, body.gravity, tilt,
            tilt_vel, n_steps, options.dt, every, limit, options.deadband_rad_s, out_theta,
            out_alpha, abort_step, first, count,
        )
        if progress is not None:
            progress(count)
        return count

    firsts = range(0, n_trials, LANES)
    workers = min(options.workers or os.cpu_count() or 1, len(firsts))
    if workers <= 1:
        for first in firsts:
            run_block(first)
    else:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            list(pool.map(run_block, firsts))
    abort_time = np.where(abort_step >= 0, abort_step * options.dt, np.nan)
    sample_time, sample_tilt = options.sampled(tilt)
    return BatchResult(
        time=sample_time,
        tilt=sample_tilt,
        theta=out_theta,
        alpha=out_alpha,
        abort_time=abort_time,
        segments=body.segment_names,
        joints=body.joint_names,
        parameters=params,
        description=stimulus.description,
    )


def simulate(
    body: Body,
    params: DecParameters | None = None,
    stimulus: TiltProfile | None = None,
    options: SimulationOptions | None = None,
) -> SimulationResult:
    """Simulate one trial (default parameters and PRTS unless given); see
    :func:`simulate_batch`."""
    params = params or body.default_parameters()
    _check_joints(body, params)
    batch = simulate_batch(body, params.arrays(), stimulus, options)
    return batch.trial(0)


def _check_joints(body: Body, params: DecParameters) -> None:
    if params.joints != body.joint_names:
        raise SimulationError(
            f"parameters are for joints {', '.join(params.joints)}; body '{body.name}' has "
            f"{', '.join(body.joint_names)}"
        )
