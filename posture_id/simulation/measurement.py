"""Measurement noise of other shapes than white: coloured sensor noise and drift.

A lab's angles carry more than white noise: markers and inertial sensors add noise whose
power rises towards low frequencies, and the zero of a sensor wanders. A
:class:`MeasurementNoise` adds to every segment angle of a recording, independently per
segment and seeded:

- sensor noise of SD ``sd_deg``, white (``colour_slope`` 0) or coloured: the one-sided PSD
  ∝ (1 + (f/f_0)²)^(−β/2) with β = ``colour_slope`` and f_0 = :data:`COLOUR_CORNER_HZ`
  (flat below it, so that its variance is finite), drawn by shaping white noise in the
  frequency domain over twice the recording and scaled to the SD in expectation;
- drift: an offset (±``offset_deg``, a sign drawn per segment), a straight trend from 0
  to ±``trend_deg`` over the recording, a random walk whose SD reaches
  ``random_walk_deg`` in 60 s, and ``steps`` steps of ±``step_deg`` at uniformly drawn
  times (a sensor re-zeroed; keep them small: a step the size of sway is a mistake the
  verdict looks for, :mod:`posture_id.identify.mistakes`).

The platform tilt is the commanded stimulus and stays clean.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from posture_id.errors import SimulationError
from posture_id.simulation.noise import corner_psd, shaped_noise

__all__ = ["MeasurementNoise", "COLOUR_CORNER_HZ", "MEASUREMENT_STREAM"]

#: Below this the coloured sensor noise's PSD is flat, Hz.
COLOUR_CORNER_HZ = 0.01
#: Second word of the seed sequence of measurement noise: apart from white sensor noise
#: (``default_rng(seed)``) and motor noise of the same seed.
MEASUREMENT_STREAM = 0x4D45415355


@dataclass(frozen=True)
class MeasurementNoise:
    """Sensor noise and drift added to a recording's segment angles (module docstring).

    Attributes:
        sd_deg: sensor noise SD, degrees. colour_slope: β, 0 for white noise (to 3).
        offset_deg, trend_deg, random_walk_deg: drift sizes, degrees (random walk: its
            SD after 60 s). steps: how many steps; step_deg: their size, degrees.
    """

    sd_deg: float = 0.0
    colour_slope: float = 0.0
    offset_deg: float = 0.0
    trend_deg: float = 0.0
    random_walk_deg: float = 0.0
    steps: int = 0
    step_deg: float = 0.0

    def __post_init__(self) -> None:
        for name in ("sd_deg", "offset_deg", "trend_deg", "random_walk_deg", "step_deg"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and 0 <= value <= 10):
                raise SimulationError(f"measurement noise {name} must be in [0, 10]°, got "
                                      f"{value!r}")
        if not (math.isfinite(self.colour_slope) and 0 <= self.colour_slope <= 3):
            raise SimulationError(f"measurement noise colour_slope must be in [0, 3], got "
                                  f"{self.colour_slope!r}")
        if isinstance(self.steps, bool) or not isinstance(self.steps, int) or self.steps < 0:
            raise SimulationError(f"measurement noise steps must be an integer ≥ 0, got "
                                  f"{self.steps!r}")

    def draw(self, time_s: np.ndarray, n_segments: int, seed: int) -> np.ndarray:
        """(S, N) the noise in degrees at the (evenly spaced) times ``time_s``."""
        rng = np.random.default_rng(np.random.SeedSequence([seed, MEASUREMENT_STREAM]))
        t = np.asarray(time_s, dtype=float)
        s = len(t)
        dt = float(t[1] - t[0])
        out = np.zeros((s, n_segments))
        if self.sd_deg > 0:
            out += self.sd_deg * _coloured(rng, s, n_segments, dt, self.colour_slope)
        sign = rng.choice([-1.0, 1.0], size=(3, n_segments))
        out += sign[0] * self.offset_deg
        out += sign[1] * self.trend_deg * (t / t[-1])[:, None]
        if self.random_walk_deg > 0:
            q = self.random_walk_deg**2 / 60.0  # variance per second
            steps = rng.standard_normal((s, n_segments)) * math.sqrt(q * dt)
            steps[0] = 0.0
            out += np.cumsum(steps, axis=0)
        for _ in range(self.steps):
            at = rng.uniform(t[0], t[-1], size=n_segments)
            out += (t[:, None] >= at[None]) * rng.choice([-1.0, 1.0], n_segments) * self.step_deg
        return out

    def apply(self, recording, seed: int):
        """``recording`` (a :class:`~posture_id.recording.Recording`) with this noise added
        to its segment angles, seeded."""
        noise = self.draw(recording.time, len(recording.segments), seed)
        return replace(recording, theta=recording.theta + np.radians(noise))


def _coloured(rng: np.random.Generator, s: int, n: int, dt: float, slope: float
              ) -> np.ndarray:
    """(S, N) unit-variance noise of PSD ∝ (1 + (f/f_0)²)^(−slope/2) (white for 0)."""
    if slope == 0:
        return rng.standard_normal((s, n))
    return shaped_noise(rng, s, n, dt, lambda f: corner_psd(f, COLOUR_CORNER_HZ, slope))
