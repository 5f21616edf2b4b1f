"""Motor noise: low-pass filtered torque noise at every joint (van der Kooij & Peterka 2011).

People sway even on a still floor, and most of their sway on a moving one is not locked to
the stimulus. Motor noise reproduces that: at joint i a torque

    n_i(t) = m·g·h_i · σ · η_i(t),

added to the DEC torque, with m·g·h_i the gravity stiffness of the segments above joint i
(N·m/rad), σ the noise level in radians (given in degrees: the SD of n_i is the gravity
torque of a lean of σ), and η_i independent unit-variance noises, each white noise through
a first-order low-pass of corner frequency f_c (an Ornstein-Uhlenbeck process of time
constant T = 1/(2π f_c)). On the step grid (dt) it is the exact discretisation

    η[k + 1] = a·η[k] + √(1 − a²)·ξ[k],   a = exp(−dt/T),   ξ ~ N(0, 1),

started from its stationary distribution, so its variance is 1 at every step and its
one-sided power spectral density is 2·dt·(1 − a²) / |1 − a·e^{−2πi f dt}|² (1/Hz), which
tends to the continuous 4T / (1 + (2π f T)²) well below the Nyquist frequency.

**[decision]** the corner frequency defaults to 0.2 Hz: spontaneous sway carries most of
its power below it, and it puts much of the noise below the fundamental of the 80-state
PRTS (0.05 Hz) as well as across the stimulated band, as in recordings of people.

Every trial draws its own noise from its own seed, so a trial's sway does not depend on
the batch it is simulated in.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from posture_id.errors import SimulationError

__all__ = ["MotorNoise", "DEFAULT_CUTOFF_HZ", "motor_noise_torques", "per_trial"]

#: Unit-noise draws kept (a batch's trials: 64 per universal shard).
UNIT_NOISE_KEPT = 128

#: Second word of a trial's own seed sequence: motor noise never shares a stream with
#: ``default_rng(seed)`` (the sensor noise of the same seed).
MOTOR_STREAM = 0x4D4F544F52

#: Corner frequency of the low-pass, Hz **[decision]** (module docstring).
DEFAULT_CUTOFF_HZ = 0.2


@dataclass(frozen=True)
class MotorNoise:
    """Low-pass filtered torque noise at every joint.

    Attributes:
        sd_deg: σ, degrees: the noise torque's SD at joint i is m·g·h_i·σ (σ in radians).
        cutoff_hz: corner frequency f_c of the first-order low-pass, Hz.
        seed: seeds the noise: a trial given its own MotorNoise draws from the seed
            sequence [seed, MOTOR_STREAM] (apart from any other stream of the same seed,
            such as sensor noise); a batch given one MotorNoise gives trial b [seed, b].
    """

    sd_deg: float
    cutoff_hz: float = DEFAULT_CUTOFF_HZ
    seed: int = 0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.sd_deg) and 0 <= self.sd_deg <= 10):
            raise SimulationError(f"motor noise sd_deg must be in [0, 10]°, got {self.sd_deg}")
        if not (math.isfinite(self.cutoff_hz) and self.cutoff_hz > 0):
            raise SimulationError(f"motor noise cutoff_hz must be > 0, got {self.cutoff_hz}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int | np.integer) \
                or self.seed < 0:
            raise SimulationError(f"motor noise seed must be an integer ≥ 0, got {self.seed!r}")

    @property
    def time_constant_s(self) -> float:
        """T = 1/(2π f_c), s."""
        return 1.0 / (2.0 * math.pi * self.cutoff_hz)

    def pole(self, dt: float) -> float:
        """a = exp(−dt/T) of the discretised low-pass."""
        return math.exp(-dt / self.time_constant_s)

    def unit_psd(self, frequency_hz: np.ndarray, dt: float) -> np.ndarray:
        """One-sided PSD (1/Hz) of the unit-variance noise η on the step grid dt."""
        a = self.pole(dt)
        z = np.exp(-2j * np.pi * np.asarray(frequency_hz, dtype=float) * dt)
        return 2.0 * dt * (1.0 - a * a) / np.abs(1.0 - a * z) ** 2

    def unit_noise(self, n_steps: int, n_joints: int, dt: float,
                   seed: np.random.SeedSequence | int | None = None) -> np.ndarray:
        """(n_steps, n_joints) unit-variance low-pass noise η on the step grid."""
        seed = np.random.SeedSequence([self.seed, MOTOR_STREAM]) if seed is None else seed
        rng = np.random.default_rng(seed)
        a = self.pole(dt)
        start = rng.standard_normal(n_joints)  # the stationary distribution
        white = rng.standard_normal((n_steps, n_joints))
        from scipy.signal import lfilter  # 1.2 s of import: only where motor noise is drawn

        eta, _ = lfilter([math.sqrt(1.0 - a * a)], [1.0, -a], white, axis=0,
                         zi=(a * start)[None, :])
        return eta


def per_trial(noise: MotorNoise | Sequence[MotorNoise] | None,
              n_trials: int) -> list[tuple[MotorNoise, np.random.SeedSequence]] | None:
    """The (noise, seed) of every trial of a batch: one MotorNoise for all (trial b seeded
    by [seed, b]) or one per trial (each by its own seed); None when there is none."""
    if noise is None:
        return None
    if isinstance(noise, MotorNoise):
        return [(noise, np.random.SeedSequence([noise.seed, b])) for b in range(n_trials)]
    noise = list(noise)
    if len(noise) != n_trials:
        raise SimulationError(f"{len(noise)} motor noises given for {n_trials} trials")
    if not all(isinstance(m, MotorNoise) for m in noise):
        raise SimulationError("motor noise must be MotorNoise objects")
    return [(m, np.random.SeedSequence([m.seed, MOTOR_STREAM])) for m in noise]


def motor_noise_torques(trials: list[tuple[MotorNoise, np.random.SeedSequence]],
                        n_steps: int, dt: float, mgh: np.ndarray, lanes: int) -> np.ndarray:
    """Noise torques of one block of trials in the kernel's layout: (n_steps, N, lanes)
    N·m, lanes past the block's trials zero.

    Args:
        trials: (noise, seed) of each of the block's trials (≤ lanes).
        n_steps: steps of the trial (the torque of step k acts from k·dt to (k+1)·dt).
        mgh: (N,) m·g·h of each joint, N·m/rad.
    """
    n = len(mgh)
    out = np.zeros((n_steps, n, lanes))
    for lane, (noise, seed) in enumerate(trials):
        if noise.sd_deg == 0:
            continue
        scale = np.asarray(mgh, dtype=float) * math.radians(noise.sd_deg)
        entropy = seed.entropy if isinstance(seed.entropy, int) else tuple(
            int(e) for e in seed.entropy)
        out[:, :, lane] = _unit_noise(noise.cutoff_hz, entropy, tuple(seed.spawn_key),
                                      seed.pool_size, n_steps, n, dt) * scale
    return out


@lru_cache(maxsize=UNIT_NOISE_KEPT)
def _unit_noise(cutoff_hz: float, entropy: int | tuple, spawn_key: tuple, pool_size: int,
                n_steps: int, n_joints: int, dt: float) -> np.ndarray:
    """:meth:`MotorNoise.unit_noise` of one seed, kept: a trial simulated at several
    levels of the same noise (:func:`~.subjects.motor_levels_for_share` and the level it
    finds) draws it once. Read-only."""
    seed = np.random.SeedSequence(entropy if isinstance(entropy, int) else list(entropy),
                                  spawn_key=spawn_key, pool_size=pool_size)
    eta = MotorNoise(1.0, cutoff_hz).unit_noise(n_steps, n_joints, dt, seed)
    eta.flags.writeable = False
    return eta
