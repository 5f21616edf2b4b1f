"""The configuration that determines a data set's content (its identity)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

from posture_id.dec.prior import SIGMA
from posture_id.errors import LearningError
from posture_id.learning.features.spectrograms import FS_HZ
from posture_id.simulation.noise import DEFAULT_CUTOFF_HZ
from posture_id.simulation.options import SimulationOptions
from posture_id.simulation.stimulus import TiltProfile, prts

__all__ = ["DatasetConfig", "DatasetError", "PAPER_SPLIT"]

#: The paper's split of 20 730 modular samples (docs/model.md §5): train / validation / test.
PAPER_SPLIT = (14000 / 20730, 3000 / 20730, 3730 / 20730)


class DatasetError(LearningError):
    """A data-set directory or request is inconsistent."""


@dataclass(frozen=True)
class DatasetConfig:
    """Everything that determines a data set's content (its identity).

    Attributes:
        trials: kept (stable) trials wanted. seed: root seed. shard_size: simulated trials
        per shard. sigma: σ of the parameter perturbation (docs/model.md §5). split: fractions of
        kept trials for train / validation / test (default: the paper's).
        amplitude_deg, cycles, states: the PRTS. simulation: what is modelled (step,
        rate, sway limit, dead-band). body: URDF path (its SHA-256 is checked too).
        sensor_noise_deg: the features of each kept trial are computed from its segment
        angles plus white noise of a standard deviation drawn uniformly from [0, this],
        degrees (0: noise-free, as in the paper), so that a network learns to see through
        sensor noise.
        motor_noise_deg: every simulated trial gets low-pass torque noise at its joints
        (:class:`~posture_id.simulation.noise.MotorNoise`) of a level drawn uniformly from
        [0, this], degrees (0: none); seeded per trial. motor_cutoff_hz: its corner
        frequency.
    """

    trials: int
    body: str
    seed: int = 0
    shard_size: int = 256
    sigma: float = SIGMA
    split: tuple[float, float, float] = PAPER_SPLIT
    amplitude_deg: float = 1.0
    cycles: int = 2
    states: int = 242
    simulation: SimulationOptions = field(default_factory=SimulationOptions)
    sensor_noise_deg: float = 0.0
    motor_noise_deg: float = 0.0
    motor_cutoff_hz: float = DEFAULT_CUTOFF_HZ

    def __post_init__(self) -> None:
        if self.trials < 3:
            raise DatasetError(f"trials must be ≥ 3 (one per split), got {self.trials}")
        if self.simulation.sample_rate_hz != FS_HZ:
            raise DatasetError(
                f"the spectrogram features (docs/model.md §6) are defined at {FS_HZ:g} Hz; the "
                f"simulation samples at {self.simulation.sample_rate_hz:g} Hz"
            )
        if not (math.isfinite(self.sensor_noise_deg) and 0 <= self.sensor_noise_deg <= 1):
            raise DatasetError(f"sensor_noise_deg must be in [0, 1]°, got {self.sensor_noise_deg}")
        if not (math.isfinite(self.motor_noise_deg) and 0 <= self.motor_noise_deg <= 10):
            raise DatasetError(f"motor_noise_deg must be in [0, 10]°, got {self.motor_noise_deg}")
        if not (math.isfinite(self.motor_cutoff_hz) and self.motor_cutoff_hz > 0):
            raise DatasetError(f"motor_cutoff_hz must be > 0, got {self.motor_cutoff_hz}")
        if self.seed < 0:
            raise DatasetError(f"seed must be ≥ 0, got {self.seed}")
        if self.shard_size < 1:
            raise DatasetError(f"shard_size must be ≥ 1, got {self.shard_size}")
        if len(self.split) != 3 or abs(sum(self.split) - 1.0) > 1e-9 or min(self.split) < 0:
            raise DatasetError(f"split must be three fractions summing to 1, got {self.split}")
        object.__setattr__(self, "split", tuple(float(f) for f in self.split))

    def stimulus(self) -> TiltProfile:
        """The PRTS every trial is simulated on: ``amplitude_deg`` p-p, ``cycles``, ``states``."""
        return prts(amplitude_deg=self.amplitude_deg, cycles=self.cycles, states=self.states)

    def identity(self) -> dict:
        """The arguments that must match for a run to resume (the body by path and hash)."""
        data = asdict(self)
        data["split"] = list(self.split)
        data["simulation"] = asdict(self.simulation)
        data["body"] = str(Path(self.body).resolve())
        return data
