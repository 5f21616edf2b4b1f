"""A model with a network identified for a comparison the way ``posture-id identify``
identifies it: the network's answer refined by the locked least squares (the hybrid),
where the network serves the body; where it does not, the model's own fit
(:func:`~posture_id.fitting.models.fit_model`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from posture_id.errors import PostureIdError
from posture_id.fitting.models import fit_model
from posture_id.frf.locked import LockedOptions
from posture_id.models.protocol import Capability, Model
from posture_id.trials import PreparedTrial

__all__ = ["IdentifiedFit", "fit_as_identified"]


@dataclass(frozen=True)
class IdentifiedFit:
    """The hybrid's fit (:class:`~posture_id.fitting.result.FitResult`) as a
    :class:`~posture_id.models.protocol.ModelFit`: its body COM sway re-simulated on the
    compared trial."""

    result: object
    fitted_com_deg: np.ndarray
    identified_count: int

    @property
    def parameters(self):
        return self.result.parameters

    @property
    def falls(self) -> bool:
        return not bool(np.all(np.isfinite(self.fitted_com_deg)))

    @property
    def residual_sd(self) -> float:
        return self.result.residual_sd

    def comparison_dict(self) -> dict:
        return {"parameters": self.parameters.to_dict(), "residual_sd": self.residual_sd,
                "method": "hybrid"}

    def to_dict(self) -> dict:
        return self.result.to_dict()


#: The least squares' relative tolerance on cost, step and gradient in a comparison's
#: hybrid (the identification's is 1e-10): a comparison reads χ², which it pins to about
#: 1e-4 of itself; on a flat optimum (people-like sway) the parameters move more than
#: that, within their intervals. On a 3-segment people-like recording it stops the exact
#: polish after 6 evaluations instead of 20 (benchmarks/compare_speed.py).
TOLERANCE = 1e-4
#: The hybrid identifiers built, by body (its URDF's digest) and harmonics.
_IDENTIFIERS: dict = {}


def _identifier(body, locked: LockedOptions):
    """The hybrid identifier of ``body`` with the locked fit at ``locked``'s harmonics
    (built once per body), or None where no network serves the body."""
    from posture_id.fitting.options import FitOptions
    from posture_id.identify.core import Identifier
    from posture_id.identify.method import Method
    from posture_id.learning.config import LearningError

    key = (body.sha256, locked)
    if key not in _IDENTIFIERS:
        try:
            _IDENTIFIERS[key] = Identifier(
                body, Method.HYBRID, fit_options=FitOptions(locked=locked, tolerance=TOLERANCE))
        except LearningError:
            _IDENTIFIERS[key] = None
    return _IDENTIFIERS[key]


def fit_as_identified(model: Model, trial: PreparedTrial, body, locked: LockedOptions,
                      options=None, progress=None):
    """``model`` fitted to ``trial`` for a comparison: a model with a network
    (:attr:`~posture_id.models.protocol.Capability.NETWORK`) by the hybrid where its
    network serves the body (and its answer stays up on the trial), every other one, and
    a hybrid answer that falls, by :func:`fit_model`."""
    identifier = (_identifier(body, locked)
                  if Capability.NETWORK in model.capabilities and options is None else None)
    if identifier is None:
        return fit_model(model, trial, body, locked, options, progress)
    try:
        result = identifier.hybrid_fit(identifier.prepare(trial.recording, trial.stimulus),
                                       progress)
    except PostureIdError:
        return fit_model(model, trial, body, locked, options, progress)
    fitted = IdentifiedFit(result, model.com_sway_deg(result.parameters, body, trial),
                           model.identified_count(body))
    if fitted.falls:  # the hybrid ended on a model that falls here: the model's own fit
        return fit_model(model, trial, body, locked, options, progress)
    return fitted
