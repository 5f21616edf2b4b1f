"""The IC model in the time domain (docs/model.md §8): re-simulation and recordings to test on.

The linear pendulum J·θ̈ = m·g·h·θ − τ (+ motor-noise torque), started at rest, stepped
with the DEC simulator's 2 ms semi-implicit Euler (docs/model.md §2): velocity first, then angle,
the torque-feedback low-pass and the integral with it. The delayed servo term
[Kp·ε + Kd·ε̇ + Ki·∫ε](t − Δ) is read from a buffer of its past values, interpolated
linearly between steps. The recording it makes has every segment at the COM angle (the
joints locked upright), so any body's recording format reads it, and its body COM sway is
θ.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from posture_id.bodies.body import Body
from posture_id.models.ic.parameters import IcParameters
from posture_id.models.ic.response import IcPlant
from posture_id.recording import Recording
from posture_id.simulation.options import SimulationOptions
from posture_id.simulation.stimulus import TiltProfile, prts

__all__ = ["simulate_ic", "ic_sway"]


def _step_loop(theta_tilt: np.ndarray, tilt_velocity: np.ndarray, motor: np.ndarray,
               p: tuple, dt: float, every: int, delay_steps: float) -> np.ndarray:
    """θ (rad) every ``every`` steps; see the module doc. ``p``: (J, mgh, Kp, Kd, Ki, W,
    G/mgh, τ_f, Kpas, Bpas)."""
    inertia, mgh, kp, kd, ki, w, g, tau_f, kpas, bpas = p
    n = len(theta_tilt) - 1
    lag = int(math.floor(delay_steps))
    frac = delay_steps - lag
    servo = np.zeros(n + 1)
    out = np.zeros(n // every + 1)
    theta = velocity = z = integral = 0.0
    for k in range(n + 1):
        a, a_dot = theta_tilt[k], tilt_velocity[k]
        # the delayed servo torque, linear between the buffer's steps (0 before t = 0)
        i0 = k - lag
        older = servo[i0 - 1] if i0 - 1 >= 0 else 0.0
        newer = servo[i0] if i0 >= 0 and i0 < k else 0.0
        delayed = (1.0 - frac) * newer + frac * older if lag > 0 or frac > 0 else 0.0
        torque = kpas * (theta - a) + bpas * (velocity - a_dot) + delayed + motor[k]
        z_dot = (torque - z) / tau_f
        error = theta - w * a + g * z
        error_dot = velocity - w * a_dot + g * z_dot
        servo[k] = kp * error + kd * error_dot + ki * integral
        if lag == 0 and frac == 0.0:  # no delay: the servo acts at once
            torque += servo[k]
        if k % every == 0:
            out[k // every] = theta
        velocity += dt * (mgh * theta - torque) / inertia
        theta += dt * velocity
        z += dt * z_dot
        integral += dt * error
    return out


def ic_sway(params: IcParameters, plant: IcPlant, stimulus: TiltProfile,
            options: SimulationOptions | None = None,
            motor_torque: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(time (S,) s, θ (S,) rad) of the IC model on ``stimulus``, sampled at
    ``options.sample_rate_hz``; ``motor_torque``: (n_steps + 1,) N·m on the step grid."""
    options = options or SimulationOptions()
    n_steps = options.n_steps(stimulus)
    tilt, tilt_velocity = stimulus.on_grid(options.dt, n_steps)
    motor = np.zeros(n_steps + 1) if motor_torque is None else np.asarray(motor_torque, float)
    p = (plant.inertia, plant.mgh, params.kp, params.kd, params.ki, params.w,
         params.torque_feedback_gain / plant.mgh, params.torque_feedback_time_s,
         params.kpas, params.bpas)
    loop = _compiled_loop()
    theta = loop(np.ascontiguousarray(tilt), np.ascontiguousarray(tilt_velocity),
                 np.ascontiguousarray(motor), p, options.dt, options.sample_every,
                 params.delay_s / options.dt)
    time = np.arange(len(theta)) / options.sample_rate_hz
    return time, theta


def simulate_ic(body: Body, params: IcParameters, stimulus: TiltProfile | None = None,
                options: SimulationOptions | None = None, motor_sd_deg: float = 0.0,
                motor_cutoff_hz: float = 0.2, seed: int = 0) -> Recording:
    """A recording of ``body`` balanced by the IC model: every segment at the COM angle.

    Args:
        body: the body simulated, turning as one about the ankle (:class:`IcPlant`).
        params: the IC model's parameters (:class:`IcParameters`, SI units).
        stimulus: the platform tilt (default: :func:`~posture_id.simulation.stimulus.prts`'s
            defaults, 2 cycles of the 242-state PRTS at 1°).
        options: step, output rate and sway limit (default :class:`SimulationOptions`).
        motor_sd_deg: motor noise σ (degrees), the torque m·g·h·σ·η with η the project's
            low-pass unit noise (:class:`~posture_id.simulation.noise.MotorNoise`); 0: none.
        motor_cutoff_hz: the motor noise's low-pass corner frequency, Hz.
        seed: seeds the motor noise.
    Returns:
        A :class:`Recording` at ``options.sample_rate_hz``: time (S,) s, tilt (S,) rad and
        the segment angles (S, N) rad, NaN from where the sway leaves the sway limit.
    """
    from posture_id.simulation.noise import MotorNoise

    options = options or SimulationOptions()
    stimulus = stimulus or prts()
    plant = IcPlant.of(body)
    motor = None
    if motor_sd_deg > 0:
        noise = MotorNoise(motor_sd_deg, motor_cutoff_hz, seed)
        eta = noise.unit_noise(options.n_steps(stimulus) + 1, 1, options.dt)[:, 0]
        motor = plant.mgh * math.radians(motor_sd_deg) * eta
    time, theta = ic_sway(params, plant, stimulus, options, motor)
    reference = body.reference_com_angles[0]
    tilt = stimulus.angle(time)
    angles = np.repeat((theta - reference)[:, None], body.n_segments, axis=1)
    if not np.all(np.isfinite(theta)) or np.max(np.abs(theta)) > math.radians(
            options.sway_limit_deg):
        beyond = np.flatnonzero(~(np.abs(theta) <= math.radians(options.sway_limit_deg)))
        angles[beyond[0]:] = np.nan
    return Recording(time, tilt, angles, body.segment_names, name="IC simulation")


@functools.cache
def _compiled_loop():
    """:func:`_step_loop` compiled by numba (cached on disk), or as it is without numba."""
    try:
        import numba
    except ImportError:  # pragma: no cover - numba is a dependency
        return _step_loop
    return numba.njit(cache=True)(_step_loop)
