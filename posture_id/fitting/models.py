"""Fit any model (:mod:`posture_id.models`) to a recording's locked body sway, the way its
capabilities allow: a closed loop gets the exact frequency-domain fit
(:mod:`posture_id.fitting.frequency`), per-joint modules the locked time-domain least
squares (:mod:`posture_id.fitting.least_squares`). What the comparison and the cohorts
read of either is the :class:`~posture_id.models.protocol.ModelFit` protocol."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from posture_id.errors import PostureIdError
from posture_id.frf.locked import LockedOptions
from posture_id.models.dec import DEC, com_deg
from posture_id.models.protocol import Capability, Model
from posture_id.trials import PreparedTrial

__all__ = ["DecFit", "fit_model", "fit_model_parts"]


def _falls(theta: np.ndarray) -> bool:
    """Whether a fitted DEC sway (S, N) rad leaves the sway limit (or is not finite)."""
    from posture_id.simulation.options import MAX_SWAY_LIMIT_DEG

    theta = np.asarray(theta, dtype=float)
    return bool(not np.all(np.isfinite(theta))
                or np.max(np.abs(theta)) >= math.radians(MAX_SWAY_LIMIT_DEG) * (1 - 1e-9))


@dataclass(frozen=True)
class DecFit:
    """A locked DEC fit (:class:`~posture_id.fitting.result.FitResult`, or the joint fit of
    several parts) as a :class:`~posture_id.models.protocol.ModelFit`."""

    result: object
    body: object
    parts: int = 1

    @property
    def parameters(self):
        return self.result.parameters

    @property
    def fitted_com_deg(self):
        fitted = self.result.fitted
        if self.parts == 1:
            return com_deg(fitted, self.body)
        return tuple(com_deg(theta, self.body) for theta in fitted)

    @property
    def identified_count(self) -> int:
        return DEC.identified_count(self.body)

    @property
    def falls(self) -> bool:
        fitted = self.result.fitted
        return _falls(fitted) if self.parts == 1 else any(_falls(t) for t in fitted)

    @property
    def residual_sd(self):
        return self.result.residual_sd

    def comparison_dict(self) -> dict:
        out = {"parameters": self.parameters.to_dict()}
        if self.parts == 1:
            out["residual_sd"] = self.result.residual_sd
        return out

    def to_dict(self) -> dict:
        return self.result.to_dict()


def fit_model(model: Model, trial: PreparedTrial, body, locked: LockedOptions,
              options=None, progress=None):
    """``model`` fitted to ``trial``'s locked sway at the harmonics ``locked`` names.

    Args:
        options: the model's own fit options: a
            :class:`~posture_id.fitting.frequency.FrequencyFitOptions` for a model with a
            closed loop, a :class:`~posture_id.fitting.options.FitOptions` for DEC's modules
            (None: the defaults); their harmonics are replaced by ``locked``.
        progress: told the stages of a locked DEC fit.
    Returns:
        a :class:`~posture_id.models.protocol.ModelFit`.
    """
    if Capability.FREQUENCY_RESPONSE in model.capabilities:
        from posture_id.fitting.frequency import FrequencyFitOptions, fit_frequency

        options = replace(options or FrequencyFitOptions(), locked=locked)
        return fit_frequency(model, trial, body, options)
    if Capability.LOCKED_FIT in model.capabilities:
        from posture_id.fitting.least_squares import fit_recording
        from posture_id.fitting.options import FitOptions

        options = replace(options or FitOptions(), locked=locked)
        return DecFit(fit_recording(trial, body, None, options, progress=progress), body)
    raise PostureIdError(f"{model.label}: no way to fit it (it declares neither a closed "
                         "loop nor per-joint modules)")


def fit_model_parts(model: Model, trials: list[PreparedTrial], body, locked: LockedOptions,
                    options=None, progress=None):
    """``model`` fitted to several parts of one subject's protocol at once: DEC with one
    set of parameters for every part, a model with a closed loop with its per-part
    parameter (IC: W) for each."""
    if Capability.FREQUENCY_RESPONSE in model.capabilities:
        from posture_id.fitting.frequency import FrequencyFitOptions, fit_frequency_parts

        options = replace(options or FrequencyFitOptions(), locked=locked)
        return fit_frequency_parts(model, trials, body, options)
    if Capability.LOCKED_FIT in model.capabilities:
        from posture_id.fitting.joint import fit_recordings_jointly
        from posture_id.fitting.options import FitOptions

        options = replace(options or FitOptions(), locked=locked)
        return DecFit(fit_recordings_jointly(trials, body, options, progress), body,
                      len(trials))
    raise PostureIdError(f"{model.label}: no way to fit it (it declares neither a closed "
                         "loop nor per-joint modules)")
