"""People-like recordings: a subject whose sway is only partly locked to the stimulus.

In a posture lab most of a person's sway on a tilting floor is not the response to the
tilt: spontaneous sway, drift. :func:`people_like` simulates a subject whose body COM sway
(α_BS) has a chosen stimulus-locked share: the motor noise (:mod:`.noise`) is scaled so
that

    share = var(α_BS without motor noise) / var(α_BS with it),

measured on the trial itself (the body is nearly linear at these angles, so the noise's
contribution scales with its level: one calibration run with a unit level gives the
level, and the realised share is reported), then white sensor noise is added.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from posture_id.bodies.body import Body
from posture_id.dec.parameters import DecParameters, ParameterArrays
from posture_id.errors import SimulationError
from posture_id.recording import Recording
from posture_id.simulation.batch import simulate, simulate_batch
from posture_id.simulation.measurement import MeasurementNoise
from posture_id.simulation.noise import DEFAULT_CUTOFF_HZ, DEFAULT_SHAPE, MotorNoise, MotorShape
from posture_id.simulation.options import SimulationOptions
from posture_id.simulation.results import BatchResult, SimulationResult
from posture_id.simulation.stimulus import TiltProfile

__all__ = ["PeopleLike", "people_like", "MotorLevels", "motor_levels_for_share",
           "UNIT_LEVEL_PER_DEG", "per_trial_values"]

#: The motor-noise level of a batched calibration run, per degree of peak-to-peak tilt.
UNIT_LEVEL_PER_DEG = 0.05


@dataclass(frozen=True)
class PeopleLike:
    """A simulated subject.

    Attributes:
        recording: what a lab would record (motor and sensor noise).
        locked: the same subject without any noise: the stimulus-locked response.
        motor_noise: the motor noise used. locked_share: the realised share of the body
        COM sway's variance that is the locked response.
    """

    recording: Recording
    locked: SimulationResult
    motor_noise: MotorNoise
    locked_share: float


def people_like(body: Body, params: DecParameters, stimulus: TiltProfile,
                locked_share: float, seed: int, sensor_noise_deg: float = 0.05,
                cutoff_hz: float = DEFAULT_CUTOFF_HZ,
                options: SimulationOptions | None = None,
                shape: MotorShape = DEFAULT_SHAPE,
                measurement: MeasurementNoise | None = None) -> PeopleLike:
    """Simulate a subject whose body COM sway is ``locked_share`` stimulus-locked.

    ``shape``: the motor noise's spectrum, joint correlation and time course
    (:class:`~posture_id.simulation.noise.MotorShape`; default the first-order low-pass of
    corner ``cutoff_hz``). ``measurement``: coloured sensor noise and drift added after the
    white ``sensor_noise_deg`` (:class:`~posture_id.simulation.measurement.MeasurementNoise`).

    Raises:
        SimulationError: the subject falls (without noise or with it), or the share is not
            in (0, 1).
    """
    if not 0 < locked_share < 1:
        raise SimulationError(f"locked_share must be in (0, 1), got {locked_share}")
    locked = simulate(body, params, stimulus, options)
    unit = simulate(body, params, stimulus, options, MotorNoise(1.0, cutoff_hz, seed, shape))
    if not (locked.stable and unit.stable):
        # a unit level may tip the body over: calibrate at a tenth of it
        unit = simulate(body, params, stimulus, options,
                        MotorNoise(0.1, cutoff_hz, seed, shape))
        scale = 0.1
    else:
        scale = 1.0
    if not (locked.stable and unit.stable):
        raise SimulationError("the subject falls")
    response = np.var(locked.alpha[:, 0])
    per_level = np.var(unit.alpha[:, 0] - locked.alpha[:, 0]) / scale**2
    level = math.sqrt(response * (1 - locked_share) / locked_share / per_level)
    motor = MotorNoise(float(level), cutoff_hz, seed, shape)
    noisy = simulate(body, params, stimulus, options, motor)
    if not noisy.stable:
        raise SimulationError("the subject falls with its motor noise")
    realised = float(response / np.var(noisy.alpha[:, 0]))
    recording = noisy.to_recording()
    if sensor_noise_deg > 0:
        recording = recording.with_sensor_noise(sensor_noise_deg, seed)
    if measurement is not None:
        recording = measurement.apply(recording, seed)
    return PeopleLike(recording, locked, motor, realised)


@dataclass(frozen=True)
class MotorLevels:
    """Motor-noise levels that leave chosen shares of B trials' body COM sway locked.

    Attributes:
        level: (B,) σ, degrees (NaN where none was found: the trial fell or needs > 10°).
        usable: (B,) bool, a level was found. clean: the trials without motor noise.
        response: (B,) variance of the clean body COM sway, rad².
    """

    level: np.ndarray
    usable: np.ndarray
    clean: BatchResult
    response: np.ndarray


def motor_levels_for_share(body: Body, params: ParameterArrays, stimulus: TiltProfile,
                           share: np.ndarray, seeds: np.ndarray, unit_level: float,
                           cutoff_hz: float | Sequence[float] = DEFAULT_CUTOFF_HZ,
                           options: SimulationOptions | None = None,
                           shapes: Sequence[MotorShape] | None = None) -> MotorLevels:
    """The batched form of :func:`people_like`'s calibration: B trials simulated without
    motor noise and with ``unit_level`` (trial b seeded by ``seeds[b]``), and the level
    that leaves ``share[b]`` of trial b's body COM sway locked (the body is nearly linear:
    the noise's variance scales with the level squared). ``cutoff_hz`` and ``shapes``:
    the noise's corner and :class:`~posture_id.simulation.noise.MotorShape`, one for all
    trials or one per trial (default: the first-order low-pass)."""
    clean = simulate_batch(body, params, stimulus, options, workers=1)
    unit = simulate_batch(body, params, stimulus, options, workers=1, motor_noise=[
        MotorNoise(unit_level, c, int(s), m)
        for s, c, m in zip(seeds, per_trial_values(cutoff_hz, len(seeds)),
                           per_trial_values(shapes or DEFAULT_SHAPE, len(seeds)),
                           strict=True)])
    with np.errstate(invalid="ignore", divide="ignore"):
        response = np.var(clean.alpha[:, :, 0], axis=1)
        per_level = np.var(unit.alpha[:, :, 0] - clean.alpha[:, :, 0], axis=1) / unit_level**2
        level = np.sqrt(response * (1 - share) / share / per_level)
    usable = clean.stable & unit.stable & np.isfinite(level) & (level <= 10)
    return MotorLevels(np.where(usable, level, np.nan), usable, clean, response)


def per_trial_values(value, n: int) -> list:
    """``value`` for each of ``n`` trials: a sequence of n as it is, anything else n times."""
    if isinstance(value, list | tuple | np.ndarray):
        if len(value) != n:
            raise SimulationError(f"{len(value)} values given for {n} trials")
        return [v.item() if isinstance(v, np.generic) else v for v in value]
    return [value] * n
