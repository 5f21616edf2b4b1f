"""Fit any model (:mod:`posture_id.models`) to a recording's locked body sway, the way its
capabilities allow: a closed loop gets the exact frequency-domain fit
(:mod:`posture_id.fitting.frequency`), per-joint modules the locked time-domain least
squares (:mod:`posture_id.fitting.least_squares`). What the comparison and the cohorts
read of either is the :class:`~posture_id.models.protocol.ModelFit` protocol."""

from __future__ import annotations

import math
import time as clock
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from posture_id.errors import PostureIdError
from posture_id.frf.locked import LockedOptions
from posture_id.models.dec import DEC, com_deg
from posture_id.models.protocol import Capability, Model
from posture_id.trials import PreparedTrial

if TYPE_CHECKING:
    from posture_id.fitting.joint_conditions import JointFit

__all__ = ["DecFit", "options_kind", "fit_model", "fit_model_parts"]


def _falls(theta: np.ndarray) -> bool:
    """Whether a fitted DEC sway (S, N) rad leaves the sway limit (or is not finite)."""
    from posture_id.simulation.options import MAX_SWAY_LIMIT_DEG

    theta = np.asarray(theta, dtype=float)
    return bool(not np.all(np.isfinite(theta))
                or np.max(np.abs(theta)) >= math.radians(MAX_SWAY_LIMIT_DEG) * (1 - 1e-9))


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
        return _falls(self.result.fitted)

    @property
    def residual_sd(self):
        return self.result.residual_sd

    def comparison_dict(self) -> dict:
        return {"parameters": self.parameters.to_dict(),
                "residual_sd": self.result.residual_sd}

    def to_dict(self) -> dict:
        return self.result.to_dict()


def options_kind(model: Model) -> type:
    """The class of ``model``'s fit options: a
    :class:`~posture_id.fitting.frequency.FrequencyFitOptions` for a model with a closed
    loop, a :class:`~posture_id.fitting.options.FitOptions` for DEC's modules.

    Raises:
        PostureIdError: a model with neither (no way to fit it).
    """
    if Capability.FREQUENCY_RESPONSE in model.capabilities:
        from posture_id.fitting.frequency import FrequencyFitOptions

        return FrequencyFitOptions
    if Capability.LOCKED_FIT in model.capabilities:
        from posture_id.fitting.options import FitOptions

        return FitOptions
    raise PostureIdError(f"{model.label}: no way to fit it (it declares neither a closed "
                         "loop nor per-joint modules)")


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
        from posture_id.fitting.frequency import fit_frequency

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
    from posture_id.fitting.joint_conditions import fit_conditions

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
