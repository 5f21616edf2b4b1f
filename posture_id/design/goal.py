"""What a design ranks protocols by: the parameters that matter, and the lab's limits."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from posture_id.design.noise import DesignError
from posture_id.simulation.protocols import MAX_PLATFORM_DEG

__all__ = ["DesignGoal", "PARAMETERS"]

#: The continuous parameters a design predicts, in the order of its arrays.
PARAMETERS = ("kp", "ki", "kd", "delay_s")


@dataclass(frozen=True)
class DesignGoal:
    """Rank protocols by the geometric mean, over ``parameters`` of every module, of the
    predicted 90 % interval width against the prior's (smaller is better), among the
    protocols within the limits.

    Attributes:
        parameters: any of 'kp', 'ki', 'kd', 'delay_s' (default: all four).
        max_minutes: recording time in all (every recording and repetition), minutes.
        max_peak_to_peak_deg: largest peak-to-peak tilt, degrees.
        max_velocity_deg_s: largest tilt velocity, degrees per second.
    """

    parameters: tuple[str, ...] = PARAMETERS
    max_minutes: float | None = None
    max_peak_to_peak_deg: float | None = None
    max_velocity_deg_s: float | None = None

    def __post_init__(self) -> None:
        unknown = [p for p in self.parameters if p not in PARAMETERS]
        if unknown or not self.parameters:
            raise DesignError(f"goal parameters must be among {PARAMETERS}, got "
                              f"{self.parameters}")
        for name in ("max_minutes", "max_peak_to_peak_deg", "max_velocity_deg_s"):
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and value > 0):
                raise DesignError(f"goal {name} must be > 0, got {value}")
        if (self.max_peak_to_peak_deg or 0) > MAX_PLATFORM_DEG:
            raise DesignError(f"goal max_peak_to_peak_deg {self.max_peak_to_peak_deg:g}° is "
                              f"above the {MAX_PLATFORM_DEG:g}° any protocol may hold: it "
                              "would limit nothing")

    def columns(self) -> list[int]:
        return [PARAMETERS.index(p) for p in self.parameters]

    def score(self, widths: np.ndarray) -> float:
        """Geometric mean of the chosen parameters' widths (N, 4) over every module;
        ∞ when any is unbounded."""
        w = np.asarray(widths)[:, self.columns()]
        if not np.all(np.isfinite(w)):
            return math.inf
        return float(np.exp(np.mean(np.log(np.maximum(w, 1e-300)))))

    def breaks(self, minutes: float, peak_to_peak_deg: float, velocity_deg_s: float
               ) -> list[str]:
        """The limits a protocol breaks, in words (empty: within them)."""
        out = []
        for value, limit, text in (
                (minutes, self.max_minutes, "min"),
                (peak_to_peak_deg, self.max_peak_to_peak_deg, "° p-p"),
                (velocity_deg_s, self.max_velocity_deg_s, "°/s")):
            if limit is not None and value > limit + 1e-9:
                out.append(f"{value:.3g} {text} > {limit:g}")
        return out

    def label(self) -> str:
        names = {"kp": "Kp", "ki": "Ki", "kd": "Kd", "delay_s": "delay"}
        limits = [f"at most {v:g}{unit}" for v, unit in (
            (self.max_minutes, " min"), (self.max_peak_to_peak_deg, "° p-p"),
            (self.max_velocity_deg_s, "°/s")) if v is not None]
        text = "every module's " + ", ".join(names[p] for p in self.parameters)
        return text + (f"; {', '.join(limits)}" if limits else "")

    def to_dict(self) -> dict:
        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}
