"""The models that ship inside the package (made by ``make models``, docs/learning.md).

Each is a model directory under ``posture_id/learning/models/``. A body gets the model
trained on its own URDF (same SHA-256); failing that, one trained on a body with as many
segments, with a notice (the gains are normalised by the body's m·g·h, so a modular
model carries over between similar bodies, but it was not validated there).
"""

from __future__ import annotations

import json
from pathlib import Path

from posture_id.errors import LearningError
from posture_id.learning.config import MODEL_FORMAT

__all__ = ["MODELS_DIR", "bundled_models", "bundled_model_dir"]

MODELS_DIR = Path(__file__).resolve().parent / "models"


def bundled_models() -> dict[Path, dict]:
    """Model directory → its ``model.json``, for every bundled per-body model."""
    out = {}
    for sidecar in sorted(MODELS_DIR.glob("*/model.json")):
        try:
            data = json.loads(sidecar.read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError):
            continue  # load_model gives the precise error if this one is asked for
        if data.get("format") == MODEL_FORMAT:  # the universal model's folder is beside them
            out[sidecar.parent] = data
    return out


def bundled_model_dir(body) -> tuple[Path, tuple[str, ...]]:
    """(model directory, notices) of the bundled model for ``body``."""
    models = bundled_models()
    for folder, sidecar in models.items():
        if sidecar.get("body", {}).get("sha256") == body.sha256:
            return folder, ()
    for folder, sidecar in models.items():
        trained = sidecar.get("body", {})
        if trained.get("n_segments") == body.n_segments:
            return folder, (f"no bundled model was trained on body '{body.name}'; using the "
                            f"one trained on '{trained.get('name')}' ({folder.name})",)
    raise LearningError(
        f"no bundled model for a {body.n_segments}-segment body ('{body.name}'); train one "
        "(posture-id network cnn data generate --body URDF, then posture-id network cnn "
        "train) and pass --network")
