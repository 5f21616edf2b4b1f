"""What is modelled: the simulation settings of docs/model.md §2 and §5, defined once.

Every other configuration (data sets, the least-squares fit, the command line's defaults)
embeds or reads :class:`SimulationOptions`; none repeats a value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from posture_id.dec.parameters import MAX_DELAY_S
from posture_id.errors import SimulationError
from posture_id.simulation.stimulus import TiltProfile

__all__ = ["SimulationOptions", "MAX_SWAY_LIMIT_DEG", "MAX_DELAY_S"]

#: Largest sway limit accepted: the kernel's polynomial sin/cos are exact up to 45°.
MAX_SWAY_LIMIT_DEG = 45.0


@dataclass(frozen=True)
class SimulationOptions:
    """How to simulate (docs/model.md §2 and §5 decisions, all configurable).

    Attributes:
        dt: integration step, s (default 2 ms).
        sample_rate_hz: output rate, Hz (default 50); 1/rate must be a multiple of dt.
        sway_limit_deg: a trial is aborted when any segment leaves ±this angle (default 6°).
        deadband_rad_s: θ, dead-band of the tilt-velocity estimator (default 0.0003 rad/s,
            the paper's text value; its table says 0.03).
    """

    dt: float = 0.002
    sample_rate_hz: float = 50.0
    sway_limit_deg: float = 6.0
    deadband_rad_s: float = 0.0003

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

    @property
    def sample_every(self) -> int:
        """Integration steps per output sample."""
        return round(1.0 / (self.sample_rate_hz * self.dt))

    def n_steps(self, stimulus: TiltProfile) -> int:
        """Integration steps covering the stimulus, up to its last sample: a stimulus that
        does not end on the sample grid (a lab's onset or lag) runs to the next sample,
        its tilt held at its last angle (:meth:`TiltProfile.angle`)."""
        samples = math.ceil(stimulus.duration * self.sample_rate_hz - 1e-6)
        return samples * self.sample_every

    def sampled(self, tilt_grid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Sample times (S,) s and the tilt (S,) rad at them, from the tilt on the step grid."""
        tilt = tilt_grid[:: self.sample_every].copy()
        return np.arange(len(tilt)) * (self.sample_every * self.dt), tilt

    def delay_steps(self, delay_s: np.ndarray) -> np.ndarray:
        """Δ/dt, snapped to the nearest integer when within 1e-9 of it (float noise)."""
        steps = np.asarray(delay_s, dtype=float) / self.dt
        nearest = np.round(steps)
        return np.where(np.abs(steps - nearest) < 1e-9, nearest, steps)
