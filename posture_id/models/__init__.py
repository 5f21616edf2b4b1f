"""The posture-control models behind one protocol (:mod:`posture_id.models.protocol`): DEC
(:data:`DEC`) and the independent-channel model (:data:`IC`); a new model implements the
protocol and registers itself (:func:`register`)."""

from posture_id.models.dec import DEC, DecModel
from posture_id.models.ic import IC, IcModel
from posture_id.models.protocol import (
    Capability,
    FrequencyModel,
    Model,
    ModelFit,
    ModelParameters,
    TrustLevel,
    model_named,
    register,
    registered_models,
)

__all__ = ["DEC", "DecModel", "IC", "IcModel", "Capability", "FrequencyModel", "Model",
           "ModelFit", "ModelParameters", "TrustLevel", "model_named", "register",
           "registered_models"]
