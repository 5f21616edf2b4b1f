"""Trained models on disk: safetensors weights and a JSON sidecar; nothing is unpickled.

A model directory holds ``model.safetensors`` (the network's weights and the
standardisation statistics) and ``model.json``::

    format, format_version, package_version
    architecture      the NetworkConfig
    features          the feature definition (posture_id.learning.features.spectrograms)
    standardisation   target means and standard deviations (images: in the weights file)
    targets           names, units and how the class is read
    body, stimulus, simulation   from the training set's manifest (body SHA-256 included)
    dataset           path and SHA-256 of its manifest
    training          the TrainingConfig, epochs run, best epoch, losses
    weights_sha256    of model.safetensors

Loading checks every part and refuses, in one line, a directory that is missing a file,
a corrupt or truncated weights file, a newer format, another feature definition, or an
architecture this code does not build.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import torch

from posture_id._version import __version__
from posture_id.fileio import jsonable
from posture_id.learning.config import (
    MODEL_FORMAT,
    ClassOutput,
    Layout,
    LearningError,
    NetworkConfig,
)
from posture_id.learning.model_files import (
    WEIGHTS,
    load_weights,
    network_tensors,
    prefixed,
    read_model_files,
    write_model_files,
)
from posture_id.learning.network import IdentifierNetwork
from posture_id.learning.samples import Standardiser

__all__ = ["FORMAT", "FORMAT_VERSION", "LoadedModel", "save_model", "load_model",
           "network_config_from_dict", "TARGETS"]

FORMAT = MODEL_FORMAT
FORMAT_VERSION = 1
#: The five outputs of a module.
TARGETS = [
    {"name": "kp", "unit": "normalised: (Kp - Kp_default) / Kp_default"},
    {"name": "ki", "unit": "normalised: (Ki - Ki_default) / Ki_default"},
    {"name": "kd", "unit": "normalised: (Kd - Kd_default) / Kd_default"},
    {"name": "delay_s", "unit": "normalised: (delay - delay_default) / delay_default"},
    {"name": "class", "unit": "C: +1 controls the COM in space, -1 the joint angle; read by "
                              "the sign (a logit when class_output is 'logit')"},
]


def network_config_from_dict(data: dict) -> NetworkConfig:
    """The inverse of ``jsonable(NetworkConfig)``; errors become :class:`LearningError`."""
    try:
        return NetworkConfig(
            layout=Layout(data["layout"]), in_channels=int(data["in_channels"]),
            modules=int(data["modules"]), widths=tuple(data["widths"]),
            head=tuple(data["head"]), class_output=ClassOutput(data["class_output"]),
            image_size=int(data["image_size"]),
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise LearningError(f"architecture is not one this code builds ({exc})") from None


@dataclass(frozen=True)
class LoadedModel:
    """A model ready to predict.

    Attributes:
        path: its directory. network: in eval mode. config: its architecture.
        standardiser: the training statistics. sidecar: the parsed model.json.
    """

    path: Path
    network: IdentifierNetwork
    config: NetworkConfig
    standardiser: Standardiser
    sidecar: dict


def save_model(folder: str | Path, network: IdentifierNetwork, standardiser: Standardiser,
               sidecar: dict) -> Path:
    """Write ``model.safetensors`` then ``model.json`` (both atomically) into ``folder``.

    ``sidecar`` holds what only the caller knows (body, stimulus, data set, training); the
    format, version, architecture, features and targets are added here.
    """
    tensors = network_tensors(network)
    tensors.update({k: v.float() if v.dtype == torch.float64 else v
                    for k, v in standardiser.to_tensors().items()})
    write_model_files(folder, tensors, {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "package_version": __version__,
        "architecture": jsonable(network.config),
        "features": network.config.feature_definition,
        "targets": TARGETS,
        "standardisation": {"target_mean": standardiser.target_mean.tolist(),
                            "target_std": standardiser.target_std.tolist(),
                            "images": "tensors standardiser.image_mean/_std in the weights"},
        **sidecar,
    })
    return Path(folder)


def _check_sidecar(sidecar: dict, path: Path) -> None:
    """Refuse a sidecar of the universal model, of another format or a newer version, or
    of features this code does not compute."""
    if sidecar.get("format") == "posture_id-universal-model":
        raise LearningError(f"{path.parent}: the universal model, not a per-body model: "
                            "`posture-id network universal table` scores it, `posture-id "
                            "network cnn evaluate SPECIALIST SET --universal` sets it beside a "
                            "specialist")
    if sidecar.get("format") != FORMAT:
        raise LearningError(f"{path}: not a posture_id model (format is not '{FORMAT}')")
    version = sidecar.get("format_version")
    if not isinstance(version, int) or version > FORMAT_VERSION:
        raise LearningError(f"{path}: model format version {version!r} is newer than "
                            f"this posture_id reads ({FORMAT_VERSION}); upgrade posture_id")
    config = network_config_from_dict(sidecar.get("architecture") or {})
    if sidecar.get("features") != config.feature_definition:
        raise LearningError(f"{path}: the model was trained on another feature "
                            "definition than this code computes; retrain it")


def load_model(folder: str | Path) -> LoadedModel:
    """Load and check a model directory (see the module doc); never unpickles."""
    folder = Path(folder)
    sidecar, tensors = read_model_files(folder, LearningError, _check_sidecar)
    config = network_config_from_dict(sidecar.get("architecture") or {})
    network = IdentifierNetwork(config)
    load_weights(network, prefixed(tensors, "network."), folder, LearningError)
    try:
        standardiser = Standardiser.from_tensors(tensors)
    except KeyError as exc:
        raise LearningError(f"{folder / WEIGHTS}: standardisation tensor {exc} is missing"
                            ) from None
    network.eval()
    network.to(memory_format=torch.channels_last)
    return LoadedModel(folder, network, config, standardiser, sidecar)
