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

**Other shapes** (:class:`MotorShape`): people's own sway is not all first-order low-pass
noise, and a network that learnt one shape must be checked on others. A shape other than
the default gives each unit noise the one-sided PSD

    S(f) ∝ (1 + (f/f_c)²)^(−s/2) · (1 + (f/f_2)²)^(−(s_2 − s)/2)

(flat below the corner f_c = ``cutoff_hz``, falling with log-log slope −s above it, and
−s_2 above a second corner f_2 when there is one), drawn by shaping white noise in the
frequency domain over twice the trial (so the trial's start and end are not tied) and
scaled to unit variance in expectation. ``joint_correlation`` ρ makes the joints' noises
share a part: η_i = √ρ·c + √(1 − ρ)·e_i, c and e_i independent of the same shape.
``level_ratio`` r lets the level change within the trial: η is multiplied by
1 + (r − 1)/(1 + exp(−(t − t_c)/2 s)), t_c at ``change_at`` of the trial. The default
shape (s = 2, no second corner, ρ = 0, r = 1) is the Ornstein-Uhlenbeck process above,
drawn exactly as before.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from posture_id.errors import SimulationError

__all__ = ["MotorNoise", "MotorShape", "DEFAULT_SHAPE", "DEFAULT_CUTOFF_HZ", "motor_noise_torques",
           "per_trial", "shaped_noise", "corner_psd"]

#: Unit-noise draws kept (a batch's trials: 64 per universal shard).
UNIT_NOISE_KEPT = 128

#: Second word of a trial's own seed sequence: motor noise never shares a stream with
#: ``default_rng(seed)`` (the sensor noise of the same seed).
MOTOR_STREAM = 0x4D4F544F52

#: Corner frequency of the low-pass, Hz **[decision]** (module docstring).
DEFAULT_CUTOFF_HZ = 0.2


@dataclass(frozen=True)
class MotorShape:
    """The spectrum, the joints' correlation and the time course of motor noise (module
    docstring); the default is the first-order low-pass.

    Attributes:
        slope: s, the PSD's log-log slope above the corner, negated (2: first order).
        second_cutoff_hz: f_2, a second corner above the first (Hz), or None.
        second_slope: s_2, the slope above the second corner, negated.
        joint_correlation: ρ in [0, 1), the share of each joint's noise variance that
            every joint shares.
        level_ratio: r > 0, the noise's SD at the end of the trial over its SD at the start.
        change_at: where the level changes, as a share of the trial (0–1).
    """

    slope: float = 2.0
    second_cutoff_hz: float | None = None
    second_slope: float = 4.0
    joint_correlation: float = 0.0
    level_ratio: float = 1.0
    change_at: float = 0.5

    def __post_init__(self) -> None:
        for name, low, high in (("slope", 0.0, 6.0), ("second_slope", 0.0, 8.0),
                                ("joint_correlation", 0.0, 0.999), ("change_at", 0.0, 1.0),
                                ("level_ratio", 0.05, 20.0)):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value)
                    and low <= value <= high):
                raise SimulationError(f"motor noise {name} must be in [{low:g}, {high:g}], "
                                      f"got {value!r}")
        if self.second_cutoff_hz is not None and not (
                math.isfinite(self.second_cutoff_hz) and self.second_cutoff_hz > 0):
            raise SimulationError(f"motor noise second_cutoff_hz must be > 0 Hz, got "
                                  f"{self.second_cutoff_hz}")

    @property
    def ornstein_uhlenbeck(self) -> bool:
        """The default shape: the exact first-order discretisation applies."""
        return self == MotorShape()

    def psd(self, frequency_hz: np.ndarray, cutoff_hz: float) -> np.ndarray:
        """The unnormalised one-sided PSD S(f) of the module docstring."""
        out = corner_psd(frequency_hz, cutoff_hz, self.slope)
        if self.second_cutoff_hz is not None:
            out = out * corner_psd(frequency_hz, self.second_cutoff_hz,
                                   self.second_slope - self.slope)
        return out

    def level(self, t_s: np.ndarray, duration_s: float) -> np.ndarray:
        """The factor on the noise at times ``t_s`` (1 at the start, r at the end)."""
        if self.level_ratio == 1.0:
            return np.ones_like(np.asarray(t_s, dtype=float))
        centre = self.change_at * duration_s
        x = np.clip((np.asarray(t_s, dtype=float) - centre) / 2.0, -50, 50)
        return 1 + (self.level_ratio - 1) / (1 + np.exp(-x))


#: The first-order low-pass (:class:`MotorShape`'s defaults).
DEFAULT_SHAPE = MotorShape()


@dataclass(frozen=True)
class MotorNoise:
    """Low-pass filtered torque noise at every joint.

    Attributes:
        sd_deg: σ, degrees: the noise torque's SD at joint i is m·g·h_i·σ (σ in radians).
        cutoff_hz: corner frequency f_c of the first-order low-pass, Hz.
        seed: seeds the noise: a trial given its own MotorNoise draws from the seed
            sequence [seed, MOTOR_STREAM] (apart from any other stream of the same seed,
            such as sensor noise); a batch given one MotorNoise gives trial b [seed, b].
        shape: :class:`MotorShape` (default: the first-order low-pass).
    """

    sd_deg: float
    cutoff_hz: float = DEFAULT_CUTOFF_HZ
    seed: int = 0
    shape: MotorShape = DEFAULT_SHAPE

    def __post_init__(self) -> None:
        if not (math.isfinite(self.sd_deg) and 0 <= self.sd_deg <= 10):
            raise SimulationError(f"motor noise sd_deg must be in [0, 10]°, got {self.sd_deg}")
        if not (math.isfinite(self.cutoff_hz) and self.cutoff_hz > 0):
            raise SimulationError(f"motor noise cutoff_hz must be > 0, got {self.cutoff_hz}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int | np.integer) \
                or self.seed < 0:
            raise SimulationError(f"motor noise seed must be an integer ≥ 0, got {self.seed!r}")
        if not isinstance(self.shape, MotorShape):
            raise SimulationError(f"motor noise shape must be a MotorShape, got {self.shape!r}")

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
        """(n_steps, n_joints) unit-variance noise η on the step grid (of this shape)."""
        seed = np.random.SeedSequence([self.seed, MOTOR_STREAM]) if seed is None else seed
        rng = np.random.default_rng(seed)
        if not self.shape.ornstein_uhlenbeck:
            return self._shaped_noise(rng, n_steps, n_joints, dt)
        a = self.pole(dt)
        start = rng.standard_normal(n_joints)  # the stationary distribution
        white = rng.standard_normal((n_steps, n_joints))
        from scipy.signal import lfilter  # 1.2 s of import: only where motor noise is drawn

        eta, _ = lfilter([math.sqrt(1.0 - a * a)], [1.0, -a], white, axis=0,
                         zi=(a * start)[None, :])
        return eta

    def _shaped_noise(self, rng: np.random.Generator, n_steps: int, n_joints: int,
                      dt: float) -> np.ndarray:
        """η of a :class:`MotorShape` other than the default (module docstring)."""
        shape = self.shape
        columns = n_joints + (1 if shape.joint_correlation > 0 else 0)
        eta = shaped_noise(rng, n_steps, columns, dt,
                           lambda f: shape.psd(f, self.cutoff_hz))
        if shape.joint_correlation > 0:
            rho = shape.joint_correlation
            eta = math.sqrt(rho) * eta[:, -1:] + math.sqrt(1 - rho) * eta[:, :n_joints]
        t = np.arange(n_steps) * dt
        return eta * shape.level(t, n_steps * dt)[:, None]


def corner_psd(frequency_hz: np.ndarray, corner_hz: float, slope: float) -> np.ndarray:
    """(1 + (f/f_c)²)^(−slope/2): flat below the corner, log-log slope −``slope`` above it
    (the unnormalised PSD of every shaped noise here and of coloured sensor noise)."""
    f = np.asarray(frequency_hz, dtype=float)
    return (1 + (f / corner_hz) ** 2) ** (-slope / 2)


def shaped_noise(rng: np.random.Generator, n_samples: int, columns: int, dt: float,
                 psd: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """(n_samples, columns) independent Gaussian noises of one-sided PSD ∝ ``psd(f)`` (f in
    Hz), unit variance in expectation: white noise shaped in the frequency domain over
    twice the length (so that the start and the end are not tied), then cut."""
    m = 2 * n_samples
    frequency = np.fft.rfftfreq(m, dt)
    amplitude = np.sqrt(np.asarray(psd(frequency), dtype=float))
    amplitude[0] = 0.0  # no offset
    # white noise's DFT has E|X_k|² = m; the inverse DFT of X·A has variance
    # Σ_k w_k A_k² / m² · m with w_k = 2 for 0 < k < m/2 and 1 at 0 and m/2
    weights = np.full(len(frequency), 2.0)
    weights[0] = 1.0
    weights[-1] = 1.0 if m % 2 == 0 else 2.0
    variance = float(np.sum(weights * amplitude**2)) / m
    white = rng.standard_normal((m, columns))
    return np.fft.irfft(np.fft.rfft(white, axis=0) * amplitude[:, None], n=m,
                        axis=0)[:n_samples] / math.sqrt(variance)


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
                                      seed.pool_size, n_steps, n, dt, noise.shape) * scale
    return out


@lru_cache(maxsize=UNIT_NOISE_KEPT)
def _unit_noise(cutoff_hz: float, entropy: int | tuple, spawn_key: tuple, pool_size: int,
                n_steps: int, n_joints: int, dt: float,
                shape: MotorShape = DEFAULT_SHAPE) -> np.ndarray:
    """:meth:`MotorNoise.unit_noise` of one seed, kept: a trial simulated at several
    levels of the same noise (:func:`~.subjects.motor_levels_for_share` and the level it
    finds) draws it once. Read-only."""
    seed = np.random.SeedSequence(entropy if isinstance(entropy, int) else list(entropy),
                                  spawn_key=spawn_key, pool_size=pool_size)
    eta = MotorNoise(1.0, cutoff_hz, shape=shape).unit_noise(n_steps, n_joints, dt, seed)
    eta.flags.writeable = False
    return eta
