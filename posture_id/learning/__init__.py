"""Learning: the CNN identifier (networks, training, checkpoints, evaluation, prediction).

The only layer that imports torch (a contract in ``pyproject.toml`` enforces it). It reads
data sets from :mod:`posture_id.learning.data` and sits beside :mod:`posture_id.fitting`, which
it never imports.

Modules: :mod:`.config` (NetworkConfig, TrainingConfig), :mod:`.network`, :mod:`.samples`
(standardised batches from shards), :mod:`.training` (:func:`train`),
:mod:`.checkpoint` (safetensors + JSON), :mod:`.prediction`, :mod:`.evaluation`
(:func:`evaluate`), :mod:`.identifier` (:class:`CnnIdentifier`), :mod:`.bundled`.
"""

from posture_id._lazy import lazy_getattr

__all__ = [
    "NetworkConfig",
    "TrainingConfig",
    "SgdMomentum",
    "AdamWOneCycle",
    "Layout",
    "ClassOutput",
    "LearningError",
    "train",
    "TrainingResult",
    "evaluate",
    "EvaluationReport",
    "load_model",
    "save_model",
    "LoadedModel",
    "CnnIdentifier",
    "CnnIdentification",
]

# Names load on first use: importing the configuration (as the command line does to build
# its parser) must not import torch, which takes a second or more.
_WHERE = {
    "NetworkConfig": "config", "TrainingConfig": "config", "SgdMomentum": "config",
    "AdamWOneCycle": "config", "Layout": "config", "ClassOutput": "config",
    "LearningError": "config", "train": "training", "TrainingResult": "training",
    "evaluate": "evaluation", "EvaluationReport": "evaluation", "load_model": "checkpoint",
    "save_model": "checkpoint", "LoadedModel": "checkpoint", "CnnIdentifier": "identifier",
    "CnnIdentification": "identifier",
}


__getattr__ = lazy_getattr("posture_id.learning",
                           {k: f"posture_id.learning.{v}" for k, v in _WHERE.items()})
