"""Families of the noise people's sway carries, each drawn per subject.

The project's own people-like sway (:mod:`.subjects`) has one shape of noise: first-order
low-pass torque noise of corner 0.2 Hz, independent between joints, white sensor noise.
People's is not all of that shape. Each family here draws, per subject, the motor noise's
shape (:class:`~.noise.MotorShape` and its corner) and the measurement noise
(:class:`~.measurement.MeasurementNoise`), so that an identifier trained on some families
can be checked on the others (``benchmarks/noise_families.py``; docs/real_recordings.md,
"Noise of other shapes"):

- ``low_pass``: the project's own: first order, corner 0.2 Hz; white sensor noise
  0.02–0.05° (as every family but ``drifting``);
- ``two_corners``: corner 0.01–0.3 Hz, slope 1–2 above it, a second corner at 0.5–3 Hz
  and slope 3–5 above that;
- ``shallow``: corner 0.01–0.05 Hz, slope 0.5–1.2 (close to 1/f);
- ``correlated``: first order, corner 0.05–1 Hz, 50–90 % of it shared by the joints;
- ``drifting``: first order, corner 0.05–1 Hz; coloured sensor noise (slope 1–2) of
  0.02–0.05°, an offset up to 1°, a trend up to 0.3°, a random walk up to 0.5° in 60 s
  and up to 2 steps of up to 0.1°;
- ``changing``: first order, corner 0.05–1 Hz, its level ×0.5–2 between the start and
  the end (the change at 30–70 % of the trial).

(Corners drawn log-uniformly, the rest uniformly.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from posture_id.choices import Choice
from posture_id.simulation.measurement import MeasurementNoise
from posture_id.simulation.noise import DEFAULT_CUTOFF_HZ, MotorShape

__all__ = ["NoiseFamily", "NoiseDraw", "draw_noise", "DRIFTING_COLOUR_SLOPE"]

#: The range of the ``drifting`` family's sensor-noise colour (PSD slope, uniform).
DRIFTING_COLOUR_SLOPE = (1.0, 2.0)


class NoiseFamily(Choice):
    """A family of noise processes (module docstring)."""

    LOW_PASS = "low_pass"
    TWO_CORNERS = "two_corners"
    SHALLOW = "shallow"
    CORRELATED = "correlated"
    DRIFTING = "drifting"
    CHANGING = "changing"



@dataclass(frozen=True)
class NoiseDraw:
    """One subject's noise: the torque noise's corner and shape, the white sensor noise's
    SD (degrees) and any other measurement noise."""

    family: NoiseFamily
    cutoff_hz: float
    shape: MotorShape
    sensor_noise_deg: float
    measurement: MeasurementNoise | None

    def to_dict(self) -> dict:
        # the shape's fields: slope, second_cutoff_hz, second_slope, joint_correlation,
        # level_ratio, change_at
        return {"family": self.family.value, "cutoff_hz": self.cutoff_hz, **vars(self.shape),
                "sensor_noise_deg": self.sensor_noise_deg,
                "measurement": None if self.measurement is None else vars(self.measurement)}


def _log_uniform(rng: np.random.Generator, low: float, high: float) -> float:
    return float(np.exp(rng.uniform(np.log(low), np.log(high))))


def draw_noise(family: NoiseFamily, rng: np.random.Generator) -> NoiseDraw:
    """One subject's noise of ``family`` (module docstring's table)."""
    family = NoiseFamily(family)
    sensor = float(rng.uniform(0.02, 0.05))
    corner = _log_uniform(rng, 0.05, 1.0)
    if family is NoiseFamily.LOW_PASS:
        return NoiseDraw(family, DEFAULT_CUTOFF_HZ, MotorShape(), sensor, None)
    if family is NoiseFamily.TWO_CORNERS:
        shape = MotorShape(slope=float(rng.uniform(1, 2)),
                           second_cutoff_hz=_log_uniform(rng, 0.5, 3.0),
                           second_slope=float(rng.uniform(3, 5)))
        return NoiseDraw(family, _log_uniform(rng, 0.01, 0.3), shape, sensor, None)
    if family is NoiseFamily.SHALLOW:
        shape = MotorShape(slope=float(rng.uniform(0.5, 1.2)))
        return NoiseDraw(family, _log_uniform(rng, 0.01, 0.05), shape, sensor, None)
    if family is NoiseFamily.CORRELATED:
        shape = MotorShape(joint_correlation=float(rng.uniform(0.5, 0.9)))
        return NoiseDraw(family, corner, shape, sensor, None)
    if family is NoiseFamily.DRIFTING:
        measurement = MeasurementNoise(
            sd_deg=sensor, colour_slope=float(rng.uniform(*DRIFTING_COLOUR_SLOPE)),
            offset_deg=float(rng.uniform(0, 1)), trend_deg=float(rng.uniform(0, 0.3)),
            random_walk_deg=float(rng.uniform(0, 0.5)), steps=int(rng.integers(0, 3)),
            step_deg=float(rng.uniform(0, 0.1)))
        return NoiseDraw(family, corner, MotorShape(), 0.0, measurement)
    shape = MotorShape(level_ratio=_log_uniform(rng, 0.5, 2.0),
                       change_at=float(rng.uniform(0.3, 0.7)))
    return NoiseDraw(family, corner, shape, sensor, None)
