"""The one file format of a trained network, whichever its architecture: a directory with
``model.safetensors`` (the tensors; never a pickle) and ``model.json`` (the sidecar: its
``"format"``, what it was trained on, and ``"weights_sha256"``, the SHA-256 of the
weights), each written atomically, the weights first; read back only when the sidecar is
JSON of the expected format and the weights are the ones it names."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import torch
from safetensors import SafetensorError
from safetensors.torch import load_file, save_file

from posture_id.errors import PostureIdError
from posture_id.fileio import atomic_write, atomic_write_text, file_sha256, json_text

__all__ = ["WEIGHTS", "SIDECAR", "write_model_files", "read_model_files", "load_weights",
           "prefixed", "network_tensors"]

WEIGHTS = "model.safetensors"
SIDECAR = "model.json"


def write_model_files(folder: str | Path, tensors: dict[str, torch.Tensor], sidecar: dict
                      ) -> dict:
    """Write ``tensors`` then ``sidecar`` with the weights' SHA-256 into ``folder``;
    returns the sidecar written."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    atomic_write(folder / WEIGHTS, lambda tmp: save_file(tensors, str(tmp)))
    written = {**sidecar, "weights_sha256": file_sha256(folder / WEIGHTS)}
    atomic_write_text(folder / SIDECAR, json_text(written))
    return written


def read_model_files(folder: str | Path, error: type[PostureIdError],
                     check: Callable[[dict, Path], None]) -> tuple[dict, dict]:
    """(sidecar, tensors) of the model in ``folder``; ``check(sidecar, its path)`` raises
    ``error`` for a sidecar of another format or version. Every refusal is one ``error``
    line naming the file and the problem."""
    folder = Path(folder)
    if not folder.is_dir():
        raise error(f"{folder}: no such model directory")
    sidecar_path, weights_path = folder / SIDECAR, folder / WEIGHTS
    for path in (sidecar_path, weights_path):
        if not path.is_file():
            raise error(f"{path}: missing; a model directory holds {SIDECAR} and {WEIGHTS}")
    try:
        sidecar = json.loads(sidecar_path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise error(f"{sidecar_path}: not valid JSON ({exc})") from None
    if not isinstance(sidecar, dict):
        raise error(f"{sidecar_path}: not a posture_id model's sidecar (not a JSON object)")
    check(sidecar, sidecar_path)
    if file_sha256(weights_path) != sidecar.get("weights_sha256"):
        raise error(f"{weights_path}: corrupt or truncated (SHA-256 differs from {SIDECAR})")
    try:
        tensors = load_file(str(weights_path))
    except (SafetensorError, OSError, ValueError) as exc:
        raise error(f"{weights_path}: not a readable safetensors file ({exc})") from None
    return sidecar, tensors


def load_weights(network: torch.nn.Module, state: dict[str, torch.Tensor], folder: Path,
                 error: type[PostureIdError]) -> None:
    """Load ``state`` (the model in ``folder``'s ``network.*`` tensors, named without the
    prefix) into ``network`` (strict); weights that do not fit its architecture are one
    ``error`` line naming the file."""
    try:
        network.load_state_dict(state, strict=True)
    except RuntimeError as exc:
        first = str(exc).splitlines()[1].strip() if "\n" in str(exc) else str(exc)
        raise error(f"{folder / WEIGHTS}: the weights do not fit the architecture in "
                    f"{SIDECAR} ({first})") from None


def prefixed(tensors: dict[str, torch.Tensor], prefix: str) -> dict[str, torch.Tensor]:
    """The tensors whose names start with ``prefix``, named without it."""
    return {k[len(prefix):]: v for k, v in tensors.items() if k.startswith(prefix)}


def network_tensors(network: torch.nn.Module) -> dict[str, torch.Tensor]:
    """The weights of ``network`` as the files keep them: ``network.*``, on the CPU,
    contiguous."""
    return {f"network.{k}": v.detach().cpu().contiguous() for k, v in network.state_dict().items()}
