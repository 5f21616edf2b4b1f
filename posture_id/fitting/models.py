"""Fit any model (:mod:`posture_id.models`) to a recording's locked body sway, the way its
capabilities allow: a closed loop gets the exact frequency-domain fit
(:mod:`posture_id.fitting.frequency`), per-joint modules the locked time-domain least
squares (:mod:`posture_id.fitting.least_squares`). What the comparison and the cohorts
read of either is the :class:`~posture_id.models.protocol.ModelFit` protocol."""

from __future__ import annotations

import time as clock
from dataclasses import dataclass, replace

from posture_id.fitting.frequency import FrequencyFitOptions, IcFitOptions, fit_frequency
from posture_id.fitting.joint_conditions import (
    JointFit,
    fit_conditions,
    options_kind,
    sway_falls,
)
from posture_id.frf.locked import LockedOptions
from posture_id.models.dec import DEC, com_deg
from posture_id.models.ic.model import IC
from posture_id.models.protocol import Capability, FrequencyModel, Model
from posture_id.trials import PreparedTrial

__all__ = ["DecFit", "options_kind", "fit_model", "fit_model_parts", "fit_frequency_parts",
           "fit_ic_parts"]



@dataclass(frozen=True)
class DecFit:
    """A locked DEC fit of one recording (:class:`~posture_id.fitting.result.FitResult`) as
    a :class:`~posture_id.models.protocol.ModelFit`."""

    result: object
    body: object

    @property
    def parameters(self):
        return self.result.parameters

    @property
    def fitted_com_deg(self):
        return com_deg(self.result.fitted, self.body)

    @property
    def identified_count(self) -> int:
        return DEC.identified_count(self.body)

    @property
    def falls(self) -> bool:
        return sway_falls(self.result.fitted)

    @property
    def residual_sd(self):
        return self.result.residual_sd

    def comparison_dict(self) -> dict:
        return {"parameters": self.parameters.to_dict(),
                "residual_sd": self.result.residual_sd}

    def to_dict(self) -> dict:
        return self.result.to_dict()



def fit_model(model: Model, trial: PreparedTrial, body, locked: LockedOptions,
              options=None, progress=None):
    """``model`` fitted to ``trial``'s locked sway at the harmonics ``locked`` names.

    Args:
        options: the model's own fit options (:func:`options_kind`; None: the defaults);
            their harmonics are replaced by ``locked``.
        progress: told the stages of a locked DEC fit.
    Returns:
        a :class:`~posture_id.models.protocol.ModelFit`.
    """
    kind = options_kind(model)
    options = replace(options or kind(), locked=locked)
    if Capability.FREQUENCY_RESPONSE in model.capabilities:
        return fit_frequency(model, trial, body, options)
    from posture_id.fitting.least_squares import fit_recording

    return DecFit(fit_recording(trial, body, None, options, progress=progress), body)


def fit_model_parts(model: Model, trials: list[PreparedTrial], body, locked: LockedOptions,
                    options=None, progress=None) -> JointFit:
    """``model`` fitted to several parts of one subject's protocol at once (options and
    ``locked`` as :func:`fit_model`'s): the joint fit
    (:func:`~posture_id.fitting.joint_conditions.fit_conditions`), DEC with one set of
    parameters for every part, a model with a closed loop with its per-part parameter
    (IC: W) one per part (every part its own condition, the noise from the recorded
    sway; its ``w_by_part``). DEC's ``identified_count`` is its modules' Kp, Ki, Kd,
    delay and class (:meth:`~posture_id.models.dec.DecModel.identified_count`)."""
    started = clock.perf_counter()
    kind = options_kind(model)
    options = replace(options or kind(), locked=locked)
    count = len(trials)
    if Capability.FREQUENCY_RESPONSE in model.capabilities:
        return fit_conditions(model, trials, body,
                              tuple(f"part {k + 1}" for k in range(count)), range(count),
                              (model.per_part,) if count > 1 else (), options,
                              noise_from_residual=False, started=started)
    joint = fit_conditions(model, trials, body, ("every part",), [0] * count, (), options,
                           progress, started=started)
    return replace(joint, identified_count=DEC.identified_count(body))


def fit_frequency_parts(model: FrequencyModel, trials: list[PreparedTrial], body,
                        options: FrequencyFitOptions | None = None):
    """The parameters of ``model`` for every one of ``trials`` (the same subject at
    several amplitudes), shared but for the model's per-part one: the joint fit of
    :func:`~posture_id.fitting.joint_conditions.fit_joint` with every part its own
    condition and the per-part parameter the one per condition, the noise from the
    recorded sway (:func:`~posture_id.fitting.models.fit_model_parts`).

    Returns:
        :class:`~posture_id.fitting.joint_conditions.JointFit`: per part (its condition),
        its parameters; ``w_by_part``.
    """
    options = options or FrequencyFitOptions()
    return fit_model_parts(model, trials, body, options.locked, options)


def fit_ic_parts(trials: list[PreparedTrial], body, options: IcFitOptions | None = None):
    """The IC parameters of every one of ``trials``, shared but for W, one per part."""
    return fit_frequency_parts(IC, trials, body, options or IcFitOptions())
