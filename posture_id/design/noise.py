"""The noise a design assumes: white sensor noise, and motor noise given as the share of
the body COM sway it leaves locked (people-like) or as its level; and the noise-driven
sway's spectrum at a protocol's harmonics, simulated for each drawn subject."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from posture_id.bodies.body import Body
from posture_id.dec.parameters import ParameterArrays
from posture_id.errors import PostureIdError
from posture_id.simulation.batch import simulate_batch
from posture_id.simulation.noise import DEFAULT_CUTOFF_HZ, MotorNoise
from posture_id.simulation.options import SimulationOptions
from posture_id.simulation.protocols import SingleProtocol
from posture_id.simulation.subjects import UNIT_LEVEL_PER_DEG, motor_levels_for_share

__all__ = ["SwayNoise", "NoiseSpectra", "noise_spectra", "DesignError"]



class DesignError(PostureIdError):
    """A design's input is inconsistent."""


@dataclass(frozen=True)
class SwayNoise:
    """The noise of the recordings a design plans for.

    Attributes:
        sensor_noise_deg: SD of white noise on every recorded angle, degrees.
        locked_share: motor noise that leaves this share of each subject's body COM sway
            stimulus-locked (people: 0.15–0.4), or None.
        motor_sd_deg: or motor noise of this level (:class:`~posture_id.simulation.noise.
            MotorNoise`'s σ, degrees), or None. At most one of the two.
        cutoff_hz: the motor noise's corner frequency.
    """

    sensor_noise_deg: float = 0.05
    locked_share: float | None = None
    motor_sd_deg: float | None = None
    cutoff_hz: float = DEFAULT_CUTOFF_HZ

    def __post_init__(self) -> None:
        if not (math.isfinite(self.sensor_noise_deg) and self.sensor_noise_deg >= 0):
            raise DesignError(f"sensor_noise_deg must be ≥ 0°, got {self.sensor_noise_deg}")
        if self.locked_share is not None and self.motor_sd_deg is not None:
            raise DesignError("give the motor noise as locked_share or motor_sd_deg, not both")
        if self.locked_share is not None and not 0 < self.locked_share < 1:
            raise DesignError(f"locked_share must be in (0, 1), got {self.locked_share}")
        if self.motor_sd_deg is not None and not 0 <= self.motor_sd_deg <= 10:
            raise DesignError(f"motor_sd_deg must be in [0, 10]°, got {self.motor_sd_deg}")
        if self.sensor_noise_deg == 0 and not self.motor:
            raise DesignError("a design needs some noise: sensor_noise_deg > 0 or motor noise")

    @property
    def motor(self) -> bool:
        return self.locked_share is not None or bool(self.motor_sd_deg)

    def label(self) -> str:
        parts = [f"sensor {self.sensor_noise_deg:g}°"]
        if self.locked_share is not None:
            parts.append(f"motor noise leaving {100 * self.locked_share:.0f} % locked")
        elif self.motor_sd_deg:
            parts.append(f"motor noise {self.motor_sd_deg:g}°")
        return ", ".join(parts)

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class NoiseSpectra:
    """Per drawn subject, the noise of one cycle's harmonics (DFT ÷ P) of the segment
    angles, degrees².

    Attributes:
        covariance: (B, P/2, N, N) complex E[X Xᴴ] at harmonics 1..P/2 (sensor and motor).
        stable: (B,) the subject stayed up (with and without motor noise).
        motor_sd_deg: (B,) the motor-noise level used (0 without).
    """

    covariance: np.ndarray
    stable: np.ndarray
    motor_sd_deg: np.ndarray


def noise_spectra(body: Body, params: ParameterArrays, protocol: SingleProtocol,
                  noise: SwayNoise, seed: int, cycles: int = 8, smooth: int = 3,
                  options: SimulationOptions | None = None) -> NoiseSpectra:
    """Each subject's noise spectrum at the harmonics of ``protocol``'s period.

    Motor noise: the subjects are simulated over ``cycles`` + 1 cycles of the protocol
    with and without it (the level found as :func:`~posture_id.simulation.subjects.
    motor_levels_for_share` does, on the protocol's own recording length), and the
    difference (the noise-driven sway, its interaction with the dead-band included)
    after the first cycle gives the cross-spectra, averaged over the cycles and over
    ±``smooth`` neighbouring harmonics. Sensor noise adds σ²/P on the diagonal.
    """
    options = options or SimulationOptions()
    b, n = params.kp.shape
    rate = options.sample_rate_hz
    period = int(round(protocol.period_s * rate))
    half = period // 2
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0x4E4F4953]))
    seeds = rng.integers(0, 2**62, b)
    cov = np.zeros((b, half, n, n), complex)
    stable = np.ones(b, bool)
    levels = np.zeros(b)
    if noise.motor:
        if noise.locked_share is not None:
            found = motor_levels_for_share(
                body, params, protocol.profile(), np.full(b, noise.locked_share), seeds,
                UNIT_LEVEL_PER_DEG * protocol.peak_to_peak_deg, noise.cutoff_hz, options)
            levels = np.nan_to_num(found.level)
            stable &= found.usable
        else:
            levels = np.full(b, float(noise.motor_sd_deg))
        long = protocol.with_cycles(cycles + 1).profile()
        clean = simulate_batch(body, params, long, options, workers=1)
        noisy = simulate_batch(body, params, long, options, workers=1, motor_noise=[
            MotorNoise(float(v), noise.cutoff_hz, int(s)) for v, s in zip(levels, seeds,
                                                                        strict=True)])
        stable &= clean.stable & noisy.stable
        x = np.degrees(np.nan_to_num(noisy.theta - clean.theta))[:, period:(cycles + 1) * period]
        x = x.reshape(b, cycles, period, n)
        spec = np.fft.rfft(x, axis=2)[:, :, 1:half + 1] / period  # (B, C, P/2, N)
        raw = np.einsum("bckm,bckl->bkml", spec, spec.conj()) / cycles
        kernel = np.ones(2 * smooth + 1)
        counts = np.convolve(np.ones(half), kernel, mode="same")
        cov = np.apply_along_axis(lambda v: np.convolve(v, kernel, mode="same"), 1,
                                  raw) / counts[None, :, None, None]
    cov = cov + (noise.sensor_noise_deg**2 / period) * np.eye(n)[None, None]
    return NoiseSpectra(cov, stable, levels)
