"""Does a model explain a recording as well as the recording's own noise allows?

A model that is right leaves a residual that is the recording's noise; a wrong class, a
fit stuck in a local minimum or a parameter pinned at a bound leaves more. The noise is
estimated from the recording itself, in the way that suits its stimulus:

- **locked** (a periodic stimulus, at least one whole cycle): the residual's
  stimulus-locked harmonics (recorded minus model, the drift-free cycle average at the
  stimulated frequencies) divided by the noise level at each, estimated from the
  neighbouring harmonics the stimulus leaves empty (:class:`~posture_id.frf.locked.
  LockedProjection`). Sway of the subject's own, drift and sensor noise are all "noise"
  here, so a people-like recording whose sway is mostly not locked to the stimulus is
  judged as fairly as a clean one. A right model leaves an RMS of about 1 (the residual
  is χ² with 2K·N degrees of freedom); below 1 when the noise estimate includes response
  the model reproduces (the dead-band's even harmonics of a clean recording).
- **raw** (any other stimulus): the residual's SD against the white sensor noise
  estimated from the recording's third differences
  (:func:`~posture_id.uncertainty.noise.sensor_noise_deg`). Sway of the subject's own is
  not told apart here, so a people-like recording without a periodic stimulus is judged
  strictly.

:data:`NOISE_RATIO_LIMIT` is where "as well as the noise allows" ends (docs/identify.md,
measured on the benchmarks).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from posture_id.errors import PostureIdError
from posture_id.frf.locked import LockedOptions, LockedProjection
from posture_id.trials import PreparedTrial
from posture_id.uncertainty.noise import sensor_noise_deg

__all__ = ["NoiseCheck", "noise_check", "NOISE_RATIO_LIMIT"]

#: The residual's RMS in units of the recording's noise up to which a model is said to
#: explain the recording as well as its noise allows.
NOISE_RATIO_LIMIT = 1.5
#: A noise estimate below this (degrees) is raised to it: quantisation and rounding of a
#: recording's file leave at least this much.
_NOISE_FLOOR_DEG = 1e-4


@dataclass(frozen=True)
class NoiseCheck:
    """The residual of a model against the noise estimated from the recording.

    Attributes:
        ratio: the residual's RMS in units of the recording's noise (inf for a model that
            falls). basis: "locked" or "raw" (module docstring). noise_deg: for "raw", the
            estimated sensor noise SD (degrees); for "locked", the median noise level of
            the compared harmonics (degrees, DFT ÷ P). limit: :data:`NOISE_RATIO_LIMIT`.
    """

    ratio: float
    basis: str
    noise_deg: float
    limit: float = NOISE_RATIO_LIMIT

    @property
    def consistent(self) -> bool:
        """The residual is no larger than the recording's noise allows."""
        return self.ratio <= self.limit

    def sentence(self) -> str:
        what = ("stimulus-locked residual" if self.basis == "locked" else "residual")
        verdict = ("consistent with the recording's noise" if self.consistent
                   else "larger than the recording's noise allows")
        return (f"{what} {self.ratio:.2f}× the recording's own noise "
                f"({verdict}; the limit is {self.limit:g}×)")

    def to_dict(self) -> dict:
        return {"ratio": self.ratio if math.isfinite(self.ratio) else None,
                "basis": self.basis, "noise_deg": self.noise_deg, "limit": self.limit,
                "consistent": self.consistent}


def noise_check(trial: PreparedTrial, model_theta: np.ndarray,
                limit: float = NOISE_RATIO_LIMIT) -> NoiseCheck:
    """Judge a model's sway ``model_theta`` (S, N) rad against ``trial``'s recording (the
    trial the model was fitted on: with a fitted offset, the shifted one)."""
    recorded = trial.recording.theta
    model_theta = np.asarray(model_theta, dtype=float)[: len(recorded)]
    residual = np.degrees(recorded - model_theta)
    projection = _locked_projection(trial)
    if projection is not None:
        noise = float(np.median(projection.noise))
        if not np.all(np.isfinite(residual)):
            return NoiseCheck(math.inf, "locked", noise, limit)
        weighted = projection.apply(residual)
        return NoiseCheck(float(np.sqrt(np.mean(weighted**2))), "locked", noise, limit)
    noise = max(float(sensor_noise_deg(recorded)), _NOISE_FLOOR_DEG)
    if not np.all(np.isfinite(residual)):
        return NoiseCheck(math.inf, "raw", noise, limit)
    return NoiseCheck(float(np.sqrt(np.mean(residual**2))) / noise, "raw", noise, limit)


def _locked_projection(trial: PreparedTrial) -> LockedProjection | None:
    """The noise-weighted locked projection of a trial with a periodic stimulus and a
    whole cycle, else None."""
    if trial.stimulus.period_s is None:
        return None
    try:
        return LockedProjection.for_trial(trial, LockedOptions(weighted=True))
    except PostureIdError:  # less than a cycle, a period off the grid, no empty harmonic
        return None
