"""Predictions of a trained network: from images to normalised targets and classes.

Output per module: [K̃p, K̃i, K̃d, Δ̃] (docs/model.md §3 normalised, p̃ = (p − p0)/p0) and the
class C ∈ {−1, +1}, with the probability that C = +1 (COM in space): a logistic of the
logit for a LOGIT network; for the paper's regression output, 1 or 0 by its sign.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from posture_id.learning.checkpoint import LoadedModel
from posture_id.learning.config import ClassOutput

__all__ = ["Prediction", "predict_images"]


@dataclass(frozen=True)
class Prediction:
    """Predictions for B samples of M modules each.

    Attributes:
        targets: (B, M, 5) normalised [K̃p, K̃i, K̃d, Δ̃, C] with C = ±1; the continuous
            ones clipped at −1 (a parameter is never negative).
        class_probability: (B, M) probability of C = +1.
        standardised: (B, M, 5) the outputs in the training set's standardised units, the
            class column as the standardised value of E[C] (for the paper's RMSE).
        class_logit: (B, M) the network's logit of P(C = +1) (NaN for the paper's
            regression output).
    """

    targets: np.ndarray
    class_probability: np.ndarray
    standardised: np.ndarray
    class_logit: np.ndarray


def predict_images(model: LoadedModel, images: np.ndarray, batch_size: int = 512,
                   standardised_input: bool = False) -> Prediction:
    """Predict from (B, C, 51, 51) images (raw features, or already standardised)."""
    config = model.config
    m = config.modules
    std = model.standardiser
    outputs = []
    with torch.inference_mode():
        for start in range(0, len(images), batch_size):
            chunk = images[start : start + batch_size]
            if not standardised_input:
                chunk = std.images(chunk)
            x = torch.from_numpy(np.ascontiguousarray(chunk, dtype=np.float32))
            outputs.append(model.network(x.contiguous(memory_format=torch.channels_last))
                           .numpy().astype(np.float64))
    out = np.concatenate(outputs).reshape(len(images), m, 5)
    mean = std.target_mean.reshape(m, 5)
    scale = std.target_std.reshape(m, 5)
    raw = out * scale + mean
    if config.class_output is ClassOutput.LOGIT:
        logit = out[..., 4].copy()
        probability = 1.0 / (1.0 + np.exp(-logit))
        expected_c = 2.0 * probability - 1.0
    else:
        logit = np.full(out.shape[:2], np.nan)
        probability = (raw[..., 4] >= 0).astype(float)
        expected_c = raw[..., 4]
    targets = raw.copy()
    targets[..., :4] = np.maximum(targets[..., :4], -1.0)  # p = p0·(1 + p̃) is never negative
    targets[..., 4] = np.where(probability >= 0.5, 1.0, -1.0)
    standardised = out.copy()
    standardised[..., 4] = (expected_c - mean[:, 4]) / scale[:, 4]
    return Prediction(targets, probability, standardised, logit)

