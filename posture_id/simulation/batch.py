"""Simulate DEC-controlled bodies on a tilting support: one trial or a batch.

    >>> from posture_id import load_body, simulate
    >>> result = simulate(load_body())            # default TIP, defaults, PRTS 1° p-p × 2
    >>> result.theta.shape                        # (6051, 3) segment angles in space, rad

The fast path is the compiled lane kernel of :mod:`posture_id.simulation.kernel`, run in blocks on
all cores; :func:`posture_id.simulation.reference.simulate_reference` steps the same controller with
Pinocchio's forward dynamics instead, for validation.
"""

from __future__ import annotations

import math
import os
import threading
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from posture_id.bodies.body import Body
from posture_id.dec.parameters import DecParameters, ParameterArrays, default_parameters
from posture_id.errors import SimulationError
from posture_id.progress import Progress, report
from posture_id.simulation.kernel import LANES, buffer_length, kernels
from posture_id.simulation.noise import MotorNoise, motor_noise_torques, per_trial
from posture_id.simulation.options import MAX_DELAY_S, SimulationOptions
from posture_id.simulation.results import BatchResult, SimulationResult
from posture_id.simulation.stimulus import TiltProfile, prts

__all__ = ["simulate", "simulate_batch", "block_arrays", "check_joints"]


def _lane_rows(block: np.ndarray) -> np.ndarray:
    """(count, N) values of a block's trials → (N, LANES), padded with the first trial."""
    if len(block) < LANES:
        block = np.concatenate([block, np.repeat(block[:1], LANES - len(block), axis=0)])
    return block.T


def block_arrays(k, body: Body, params: ParameterArrays, options: SimulationOptions,
                 first: int, count: int) -> tuple[np.ndarray, np.ndarray]:
    """The flat parameter rows and zeroed delay buffers of one block of the kernel ``k``.

    Delays become Δ/dt steps (snapped to whole steps within 1e-9), with their ceiling and
    the interpolation weight the kernel reads; the buffers are sized for the block's
    longest delay. The reference posture θ = 0 (docs/model.md) gives each module its
    reference COM-above angle and the servo command that held it at rest before the trial,
    hold = −τ_hold − Kp·sin α_ref (both 0 for a straight chain).
    """
    n = params.kp.shape[1]
    pr = k.par_rows
    trials = slice(first, first + count)
    delay = options.delay_steps(params.delay_s[trials])
    delay_ceil = np.maximum(np.ceil(delay), 1.0)  # ≥ 1: the kernel reads slot n + 1 − ⌈Δ/dt⌉
    alpha_ref = body.reference_com_angles
    kp = params.kp[trials]
    rows = {
        pr.kp: kp, pr.ki: params.ki[trials], pr.kd: params.kd[trials],
        pr.sign: params.sign[trials], pr.kpas: params.kpas[trials],
        pr.bpas: params.bpas[trials], pr.delay: delay, pr.delay_ceil: delay_ceil,
        pr.delay_frac: delay_ceil - delay,
        pr.alpha_ref: np.broadcast_to(alpha_ref, kp.shape),
        pr.hold: -body.holding_torques - kp * np.sin(alpha_ref),
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
    progress: Progress | None = None,
    workers: int | None = None,
    motor_noise: MotorNoise | Sequence[MotorNoise] | None = None,
) -> BatchResult:
    """Simulate B trials of ``body`` with their own parameters, in parallel.

    Args:
        body: the chain (N segments).
        params: (B, N) parameter arrays.
        stimulus: tilt profile (default: PRTS, 242 states, 2 cycles, 1° p-p).
        options: what is modelled: step, sampling, sway limit, dead-band.
        progress: told the trials finished so far as each block of 32 completes.
        workers: threads running blocks (default: all cores).
        motor_noise: low-pass torque noise at every joint (:mod:`.noise`): one
            :class:`~.noise.MotorNoise` for every trial (trial b seeded by [seed, b]) or
            one per trial (each its own level and seed). Default: none.
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
    if workers is not None and workers < 1:
        raise SimulationError(f"workers must be ≥ 1, got {workers}")
    finished = [0]
    lock = threading.Lock()
    out_theta = np.empty((n_trials, n_samples, n))
    out_alpha = np.empty((n_trials, n_samples, n))
    abort_step = np.empty(n_trials, dtype=np.int64)
    limit = math.radians(options.sway_limit_deg)
    noises = per_trial(motor_noise, n_trials)
    no_motor = np.zeros(n * LANES)

    def run_block(first: int) -> int:
        count = min(LANES, n_trials - first)
        par, buf = block_arrays(k, body, params, options, first, count)
        w = np.zeros(k.rows.count * LANES)
        motor = (no_motor if noises is None else motor_noise_torques(
            noises[first : first + count], n_steps, options.dt, body.mgh, LANES).ravel())
        k.simulate_block(
            w, par, buf, d_re, d_im, inertia, s_re, s_im, body.gravity, tilt,
            tilt_vel, n_steps, options.dt, every, limit, options.deadband_rad_s, out_theta,
            out_alpha, abort_step, first, count, motor, noises is not None,
        )
        with lock:
            finished[0] += count
            done = finished[0]
        report(progress, done, n_trials, "trial")
        return count

    firsts = range(0, n_trials, LANES)
    workers = min(workers or os.cpu_count() or 1, len(firsts))
    if workers <= 1:
        for first in firsts:
            run_block(first)
    else:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            list(pool.map(run_block, firsts))
    abort_time = np.where(abort_step >= 0, abort_step * options.dt, np.nan)
    return BatchResult.on_body(options, tilt, body, params, stimulus.description,
                               theta=out_theta, alpha=out_alpha, abort_time=abort_time)


def simulate(
    body: Body,
    params: DecParameters | None = None,
    stimulus: TiltProfile | None = None,
    options: SimulationOptions | None = None,
    motor_noise: MotorNoise | None = None,
) -> SimulationResult:
    """Simulate one trial (default parameters and PRTS unless given; motor noise seeded
    by its own seed); see :func:`simulate_batch`.

    Args:
        body: the chain (N segments).
        params: every module's DEC parameters, SI units (default: the body's defaults,
            :func:`~posture_id.dec.parameters.default_parameters`).
        stimulus: the platform tilt (default: PRTS, 242 states, 2 cycles, 1° p-p).
        options: what is modelled: step, sampling, sway limit, dead-band (default
            :class:`SimulationOptions`).
        motor_noise: low-pass torque noise at every joint (:class:`~.noise.MotorNoise`),
            or None: none.
    Returns:
        :class:`SimulationResult`: time (S,) s, tilt (S,) rad, segment angles (S, N) rad
        (NaN from an abort on) and COM-above angles (S, N) rad.
    Raises:
        SimulationError: parameters whose modules are not the body's joints (in order).
    """
    params = params or default_parameters(body)
    check_joints(body, params)
    batch = simulate_batch(body, params.arrays(), stimulus, options,
                           motor_noise=None if motor_noise is None else [motor_noise])
    return batch.trial(0)


def check_joints(body: Body, params: DecParameters) -> None:
    """Refuse parameters whose modules are not the body's joints (in order)."""
    if params.joints != body.joint_names:
        raise SimulationError(
            f"parameters are for joints {', '.join(params.joints)}; body '{body.name}' has "
            f"{', '.join(body.joint_names)}"
        )
