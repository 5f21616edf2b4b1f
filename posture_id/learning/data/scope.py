"""What the universal identifier is trained on, and how one training trial is drawn.

A shard of the training set is one body and one stimulus (drawn together), and many DEC
parameter sets (docs/model.md §5's prior) simulated with motor noise that leaves a drawn share of
the body's sway stimulus-locked. The scope is also what a recording is checked against:
a body, stimulus or noise outside it gets a notice.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from posture_id.errors import LearningError
from posture_id.simulation.noise_families import NoiseFamily
from posture_id.simulation.protocols import MAX_PLATFORM_DEG
from posture_id.simulation.stimulus import LAB_STATE_RANGE_S, TiltProfile, prts

__all__ = ["UniversalScope", "BodyDraw", "StimulusDraw", "draw_body", "draw_stimulus",
           "ScopeError"]


class ScopeError(LearningError):
    """A scope is inconsistent."""


@dataclass(frozen=True)
class UniversalScope:
    """The bodies, stimuli and noise a universal identifier is trained on.

    Attributes:
        heights_m, masses_kg: ranges of Winter bodies (uniform).
        segments: segment counts of Winter bodies (equally likely).
        proportion_jitter: each Winter segment's mass and length scaled by a factor drawn
            uniformly within ±this (people are not all Winter's average).
        tip_share: share of shards on the default triple inverted pendulum.
        preset_share: share of shards on lumped humanoids (:data:`presets`, 2 or 3
            segments).
        preset_jitter: each lumped humanoid segment's mass and length scaled by a factor
            drawn uniformly within ±this (0: the robots as lumped; above, robot-like
            bodies around them, as a robot engineer's own humanoid would be).
        states: PRTS lengths (equally likely). state_s: range of a state's duration, s.
        amplitude_deg: range of peak-to-peak tilt, degrees (log-uniform).
        duration_s: range of the recording's length, s (at least one whole cycle).
        sensor_noise_deg: range of white sensor noise SD, degrees (uniform, per trial,
            drawn afresh every epoch).
        clean_share: share of trials without motor noise.
        locked_share: range of the stimulus-locked share of the body COM sway of the
            other trials (uniform).
        drift_deg: range of slow drift, degrees: the SD a random walk of the lean reaches
            in 60 s (uniform, per trial and epoch).
        cutoff_hz: the motor noise's corner, Hz (without ``noise_families``).
        noise_families: () (default): every trial's motor noise is the first-order
            low-pass of ``cutoff_hz``. Names of
            :class:`~posture_id.simulation.noise_families.NoiseFamily`: each trial with
            motor noise draws one of them (equally likely) and from it its torque noise's
            corner and shape (its measurement noise is not stored: the sensor noise and
            the drift are drawn at training time).
    """

    heights_m: tuple[float, float] = (1.45, 2.05)
    masses_kg: tuple[float, float] = (40.0, 120.0)
    segments: tuple[int, ...] = (1, 2, 3)
    proportion_jitter: float = 0.15
    tip_share: float = 0.1
    preset_share: float = 0.15
    preset_jitter: float = 0.0
    presets: tuple[str, ...] = ("talos", "g1", "human")
    states: tuple[int, ...] = (242, 80)
    state_s: tuple[float, float] = LAB_STATE_RANGE_S
    amplitude_deg: tuple[float, float] = (0.5, 4.0)
    duration_s: tuple[float, float] = (40.0, 250.0)
    sensor_noise_deg: tuple[float, float] = (0.0, 0.1)
    clean_share: float = 0.25
    locked_share: tuple[float, float] = (0.1, 1.0)
    drift_deg: tuple[float, float] = (0.0, 0.5)
    cutoff_hz: float = 0.2
    noise_families: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        for name in ("heights_m", "masses_kg", "state_s", "amplitude_deg", "duration_s",
                     "sensor_noise_deg", "locked_share", "drift_deg"):
            lo, hi = getattr(self, name)
            if not (math.isfinite(lo) and math.isfinite(hi) and 0 <= lo <= hi):
                raise ScopeError(f"scope {name} must be a range 0 ≤ low ≤ high, got {(lo, hi)}")
            object.__setattr__(self, name, (float(lo), float(hi)))
        if self.amplitude_deg[1] > MAX_PLATFORM_DEG or self.amplitude_deg[0] <= 0:
            raise ScopeError(f"scope amplitude_deg must lie within (0, {MAX_PLATFORM_DEG:g}]° "
                             f"peak to peak (what a posture platform tilts), got "
                             f"{self.amplitude_deg}")
        if not set(self.segments) <= {1, 2, 3} or not self.segments:
            raise ScopeError(f"scope segments must be among 1, 2, 3, got {self.segments}")
        if not set(self.states) <= {80, 242} or not self.states:
            raise ScopeError(f"scope states must be among 80, 242, got {self.states}")
        if not (self.tip_share >= 0 and self.preset_share >= 0
                and self.tip_share + self.preset_share <= 1):
            raise ScopeError(f"scope tip_share and preset_share must be ≥ 0 with a sum "
                             f"within [0, 1], got {self.tip_share} and {self.preset_share}")
        for name in ("proportion_jitter", "preset_jitter"):
            if not 0 <= getattr(self, name) < 1:
                raise ScopeError(f"scope {name} must be within [0, 1), got "
                                 f"{getattr(self, name)}")
        if not 0 < self.locked_share[0] <= self.locked_share[1] <= 1:
            raise ScopeError(f"scope locked_share must be a range within (0, 1], got "
                             f"{self.locked_share}")
        if not 0 <= self.clean_share <= 1:
            raise ScopeError(f"scope clean_share must be within [0, 1], got {self.clean_share}")
        known = [f.value for f in NoiseFamily]
        unknown = [f for f in self.noise_families if f not in known]
        if unknown or len(set(self.noise_families)) != len(self.noise_families):
            raise ScopeError(f"scope noise_families must be distinct names among "
                             f"{', '.join(known)}; got {', '.join(self.noise_families)}")
        object.__setattr__(self, "noise_families", tuple(self.noise_families))

    def to_dict(self) -> dict:
        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}

    @classmethod
    def from_dict(cls, data: dict) -> UniversalScope:
        return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in data.items()})


@dataclass(frozen=True)
class BodyDraw:
    """A drawn body: ``kind`` 'winter', 'tip' or a preset's name; for Winter bodies the
    height, mass, segments and the per-segment (mass, length) factors; for a preset its
    segments and (mass, length) factors (none: the robot as lumped)."""

    kind: str
    segments: int
    height_m: float = math.nan
    mass_kg: float = math.nan
    factors: tuple[tuple[float, float], ...] = field(default=())

    def label(self) -> str:
        if self.kind == "winter":
            return f"Winter {self.segments}-seg {self.height_m:.2f} m {self.mass_kg:.0f} kg"
        if self.kind == "tip":
            return "TIP (default)"
        return f"{self.kind} {self.segments}-seg (lumped{', jittered' if self.factors else ''})"


@dataclass(frozen=True)
class StimulusDraw:
    """A drawn PRTS: states, s per state, peak-to-peak degrees, whole cycles."""

    states: int
    state_s: float
    amplitude_deg: float
    cycles: int

    def profile(self) -> TiltProfile:
        return prts(self.amplitude_deg, self.cycles, self.states, self.state_s)

    @property
    def duration_s(self) -> float:
        return self.states * self.state_s * self.cycles


def _factors(rng: np.random.Generator, n: int, jitter: float) -> tuple[tuple[float, float], ...]:
    """(n,) per-segment (mass, length) factors, uniform within 1 ± jitter."""
    return tuple((float(a), float(b)) for a, b in rng.uniform(1 - jitter, 1 + jitter, (n, 2)))


def draw_body(scope: UniversalScope, rng: np.random.Generator) -> BodyDraw:
    """One body of the scope: the TIP, a lumped humanoid or a jittered Winter body."""
    u = rng.random()
    if u < scope.tip_share:
        return BodyDraw("tip", 3)
    if u < scope.tip_share + scope.preset_share and scope.presets:
        name, n = str(rng.choice(scope.presets)), int(rng.choice([2, 3]))
        # no draw without jitter: the sets made before it existed stay as they were
        factors = _factors(rng, n, scope.preset_jitter) if scope.preset_jitter else ()
        return BodyDraw(name, n, factors=factors)
    n = int(rng.choice(scope.segments))
    factors = _factors(rng, n, scope.proportion_jitter)
    return BodyDraw("winter", n, float(rng.uniform(*scope.heights_m)),
                    float(rng.uniform(*scope.masses_kg)), factors)


def draw_stimulus(scope: UniversalScope, rng: np.random.Generator) -> StimulusDraw:
    """One PRTS of the scope: whole cycles that fill a drawn duration (at least one)."""
    states = int(rng.choice(scope.states))
    # a cycle of a whole number of samples at 50 Hz (the locked analysis needs it)
    state_s = round(float(rng.uniform(*scope.state_s)) * states * 50) / (states * 50)
    lo, hi = np.log(scope.amplitude_deg)
    amplitude = float(np.exp(rng.uniform(lo, hi)))
    duration = float(rng.uniform(*scope.duration_s))
    cycles = max(1, int(duration // (states * state_s)))
    return StimulusDraw(states, state_s, round(amplitude, 4), cycles)
