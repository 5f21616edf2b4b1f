"""Which of a model's networks answers a recording, by the noise the recording shows.

The universal network trained under the project's low-pass motor noise alone (the base)
and its fine-tune over the noise families (the noise stage) are each best on their own
sway: the base on sway whose noise is a sensor's (white) or nearly none, the stage on
sway whose noise is shaped by the body (motor noise of any shape, drift: docs/universal.md,
"The noise stage"). A :class:`NoiseGate` lets one model hold both and weigh them by what
the recording itself shows, the two numbers the calibration's regimes are made of
(:func:`~.features.module_frfs.noise_ratio`: the share of the locked harmonics that is noise;
:func:`~.features.module_frfs.noise_colour`: white about 0, shaped by the body above
:data:`~.calibration.COLOUR_EDGE`):

    w = ramp(colour; colour_from, colour_to) · ramp(log10 ratio; log10 ratio_from, log10 ratio_to)

the share of the coloured-noise members in the answer (0: the white-noise members alone,
1: the coloured ones alone; between, a mixture of the two answers). Both ramps: a
recording whose "noise" is a sway's own dead band (a ratio below ``ratio_from``, however
coloured) is clean sway, and white noise of any level is a sensor's. The edges:
docs/universal.md, "One model, two networks, chosen by the noise".
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from posture_id.errors import LearningError

__all__ = ["NoiseGate"]


def _ramp(x: np.ndarray, low: float, high: float) -> np.ndarray:
    return np.clip((x - low) / (high - low), 0.0, 1.0)


@dataclass(frozen=True)
class NoiseGate:
    """The first ``white_members`` members of a model answer white or nearly no noise, the
    others noise shaped by the body (module docstring).

    Attributes:
        white_members: how many of the model's members (first) answer white noise.
        colour_from, colour_to: the colour ramp (log10 power ratio, dimensionless).
        ratio_from, ratio_to: the noise-ratio ramp (share of the locked harmonics).
    """

    white_members: int
    colour_from: float = 0.3
    colour_to: float = 0.8
    ratio_from: float = 0.003
    ratio_to: float = 0.02

    def __post_init__(self) -> None:
        if not (isinstance(self.white_members, int) and self.white_members >= 1):
            raise LearningError(f"white_members must be an integer ≥ 1, got {self.white_members!r}")
        if not self.colour_from < self.colour_to:
            raise LearningError(f"the colour ramp must rise: {self.colour_from} to "
                             f"{self.colour_to}")
        if not 0 < self.ratio_from < self.ratio_to:
            raise LearningError(f"the noise-ratio ramp must rise from above 0: "
                             f"{self.ratio_from} to {self.ratio_to}")

    def coloured_share(self, noise_ratio: np.ndarray, noise_colour: np.ndarray) -> np.ndarray:
        """(M,) the coloured-noise members' share of each answer, in [0, 1], from each
        sample's noise ratio and colour (M,)."""
        ratio = np.log10(np.maximum(np.asarray(noise_ratio, dtype=float), 1e-12))
        colour = np.asarray(noise_colour, dtype=float)
        return (_ramp(colour, self.colour_from, self.colour_to)
                * _ramp(ratio, np.log10(self.ratio_from), np.log10(self.ratio_to)))

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> NoiseGate:
        return cls(int(data["white_members"]), float(data["colour_from"]),
                   float(data["colour_to"]), float(data["ratio_from"]),
                   float(data["ratio_to"]))
