"""IC subjects to test on: parameters drawn around the literature's, and people-like
recordings (motor noise leaving a chosen share of the body COM sway locked)."""

from __future__ import annotations

import math

import numpy as np

from posture_id.models.ic.parameters import IcParameters
from posture_id.models.ic.response import IcPlant, is_stable
from posture_id.models.ic.simulation import simulate_ic
from posture_id.recording import Recording
from posture_id.simulation.stimulus import TiltProfile

__all__ = ["draw_ic_parameters", "ic_recording"]

#: The ranges drawn from: gains in units of m·g·h (·s), Δ and τ_f in s.
RANGES = {"kp": (1.3, 2.5), "kd": (0.25, 0.6), "delay_s": (0.08, 0.22), "w": (0.2, 0.9),
          "torque_feedback_gain": (0.0, 0.5), "torque_feedback_time_s": (5.0, 40.0)}


def draw_ic_parameters(rng: np.random.Generator, plant: IcPlant) -> IcParameters:
    """Uniform within :data:`RANGES`, drawn again until the closed loop is stable."""
    while True:
        draw = {k: rng.uniform(*v) for k, v in RANGES.items()}
        draw["kp"] *= plant.mgh
        draw["kd"] *= plant.mgh
        params = IcParameters(**draw)
        if is_stable(params, plant):
            return params


def ic_recording(body, params: IcParameters, stimulus: TiltProfile,
                 locked_share: float | None, seed: int, sensor_noise_deg: float = 0.02,
                 options=None) -> tuple[Recording, float]:
    """An IC recording with white sensor noise; people-like when ``locked_share`` is given:
    the motor-noise level (degrees, returned; 0 without) that leaves that share of the body
    COM sway's variance locked (the model is linear, so the level is exact). ``options``:
    the :class:`~posture_id.simulation.options.SimulationOptions` (its sample rate)."""
    clean = simulate_ic(body, params, stimulus, options)
    if locked_share is None:
        return clean.with_sensor_noise(sensor_noise_deg, seed), 0.0
    unit = simulate_ic(body, params, stimulus, options, motor_sd_deg=0.1, seed=seed)
    com_clean = body.com_angles(clean.theta)[:, 0]
    noise = body.com_angles(unit.theta)[:, 0] - com_clean
    level = 0.1 * math.sqrt(np.var(com_clean) * (1 - locked_share)
                            / (locked_share * np.var(noise)))
    noisy = simulate_ic(body, params, stimulus, options, motor_sd_deg=level, seed=seed)
    return noisy.with_sensor_noise(sensor_noise_deg, seed), level
