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
    register,
    registered,
)

__all__ = ["DEC", "DecModel", "IC", "IcModel", "Capability", "FrequencyModel", "Model",
           "ModelFit", "ModelParameters", "TrustLevel", "model_named", "register",
           "registered"]


def model_named(name: str) -> Model:
    """The model whose ``"model"`` key is ``name``."""
    from posture_id.errors import PostureIdError

    models = {m.name: m for m in registered()}
    if name not in models:
        raise PostureIdError(f"unknown model {name!r} (known: {', '.join(sorted(models))})")
    return models[name]
