"""Parameters of the independent-channel (IC) model (docs/model.md §8), JSON in and out.

The keys of a parameter file: ``kp`` (N·m/rad), ``kd`` (N·m·s/rad), ``ki`` (N·m/(rad·s)),
``delay_s`` (s), ``w`` (the proprioceptive weight, 0–1), ``torque_feedback_gain`` (G, 0–0.9),
``torque_feedback_time_s`` (τ_f, s), ``kpas`` (N·m/rad), ``bpas`` (N·m·s/rad), and
``"model": "ic"`` beside them.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path

from posture_id.errors import ParameterError
from posture_id.fileio import JsonFile, read_json

__all__ = ["IcParameters", "MODEL_NAME", "default_ic_parameters"]

#: The ``"model"`` value of an IC parameter file.
MODEL_NAME = "ic"


@dataclass(frozen=True)
class IcParameters(JsonFile):
    """The IC model of one body (SI units; docs/model.md §8).

    Attributes:
        kp: N·m/rad, proportional gain on the sensory error. kd: N·m·s/rad, derivative gain.
        ki: N·m/(rad·s), integral gain (0 unless asked for). delay_s: s, the lumped delay.
        w: proprioceptive weight: the share of the platform's tilt taken as vertical.
        torque_feedback_gain: G, the positive torque feedback's gain (of m·g·h).
        torque_feedback_time_s: τ_f, its low-pass time constant, s.
        kpas: N·m/rad, passive stiffness. bpas: N·m·s/rad, passive damping (0 unless asked).
    """

    kp: float
    kd: float
    delay_s: float
    w: float
    torque_feedback_gain: float = 0.0
    torque_feedback_time_s: float = 20.0
    ki: float = 0.0
    kpas: float = 0.0
    bpas: float = 0.0

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, bool) or not isinstance(value, int | float) \
                    or not math.isfinite(value):
                raise ParameterError(f"IC {f.name} must be a finite number, got {value!r}")
            object.__setattr__(self, f.name, float(value))
        for name in ("kp", "kd", "ki", "kpas", "bpas", "torque_feedback_gain"):
            if getattr(self, name) < 0:
                raise ParameterError(f"IC {name} must be ≥ 0, got {getattr(self, name)}")
        if not 0 <= self.delay_s <= 2.0:
            raise ParameterError(f"IC delay_s must be within 0–2 s (it is in seconds), got "
                                 f"{self.delay_s}")
        if not 0 <= self.w <= 1:
            raise ParameterError(f"IC w (the proprioceptive weight) must be within 0–1, got "
                                 f"{self.w}")
        if self.torque_feedback_gain >= 1:
            raise ParameterError("IC torque_feedback_gain must be < 1 (a positive feedback "
                                 f"of the whole m·g·h never settles), got "
                                 f"{self.torque_feedback_gain}")
        if self.torque_feedback_time_s <= 0:
            raise ParameterError(f"IC torque_feedback_time_s must be > 0, got "
                                 f"{self.torque_feedback_time_s}")

    def replace(self, **changes: float) -> IcParameters:
        """A copy with the given fields changed (SI units), validated like a new one."""
        return replace(self, **changes)

    def to_dict(self) -> dict:
        """The parameter-file format: ``{"model": "ic", "kp": ..., ...}`` (SI units)."""
        return {"model": MODEL_NAME, **asdict(self)}

    @classmethod
    def from_dict(cls, data: object, name: str = "IC parameters") -> IcParameters:
        """Validate a mapping; a missing optional field takes its default.

        Raises:
            ParameterError: naming ``name``, the field and the problem.
        """
        if not isinstance(data, dict):
            raise ParameterError(f"{name}: expected a JSON object with \"model\": \"ic\"")
        if data.get("model") != MODEL_NAME:
            raise ParameterError(f"{name}: \"model\" must be \"ic\" for an IC parameter file, "
                                 f"got {data.get('model')!r} (a DEC file is keyed by joint)")
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known - {"model"})
        if unknown:
            raise ParameterError(f"{name}: unknown field(s) {unknown} (fields: "
                                 f"{sorted(known)})")
        missing = [k for k in ("kp", "kd", "delay_s", "w") if k not in data]
        if missing:
            raise ParameterError(f"{name}: missing field(s) {missing}")
        try:
            return cls(**{k: v for k, v in data.items() if k != "model"})
        except ParameterError as exc:
            raise ParameterError(f"{name}: {exc}") from None

    @classmethod
    def from_json(cls, path: str | Path) -> IcParameters:
        """Read and validate an IC parameter file."""
        data = read_json(path, "an IC parameter file", ParameterError)
        return cls.from_dict(data, str(path))

    def summary(self) -> str:
        """One line: Kp, Kd, Δ, W, G and τ_f (with Ki and the passive terms when set)."""
        return (f"IC  Kp {self.kp:.1f} N·m/rad  Kd {self.kd:.1f} N·m·s/rad  Δ "
                f"{self.delay_s:.3f} s  W {self.w:.3f}  G {self.torque_feedback_gain:.3f}  "
                f"τ_f {self.torque_feedback_time_s:.1f} s"
                + (f"  Ki {self.ki:.2f}" if self.ki else "")
                + (f"  Kpas {self.kpas:.1f} Bpas {self.bpas:.1f}" if self.kpas or self.bpas
                   else ""))


def default_ic_parameters(mgh: float) -> IcParameters:
    """Typical values of the literature for a body of ``mgh`` (N·m/rad): Kp 1.5·m·g·h,
    Kd 0.35·m·g·h·s, Δ 0.15 s, W 0.6, G 0.3 with τ_f 20 s."""
    return IcParameters(kp=1.5 * mgh, kd=0.35 * mgh, delay_s=0.15, w=0.6,
                        torque_feedback_gain=0.3, torque_feedback_time_s=20.0)
