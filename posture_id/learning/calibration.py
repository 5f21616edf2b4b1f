"""A CNN's calibration: conformal intervals and temperature-scaled class probabilities.

Made on a data set's validation split (never trained on) by :func:`calibrate_cnn`, at
several sensor-noise levels (white noise added to the stored noise-free sway, seeded per
shard and level), and kept beside the weights as ``calibration.json``:

- the continuous outputs' conformal half-widths per module and parameter
  (:class:`~posture_id.uncertainty.conformal.ConformalCalibration`, scores |p̃ − p̂̃|);
- the temperature T_m of each module's class logits (:func:`~posture_id.uncertainty.
  coverage.fit_temperature`), so that P(C_m = +1) = sigmoid(logit_m / T_m).

The file names the weights it was made for (their SHA-256) and is ignored, with a notice,
beside other weights.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from posture_id.datasets.store import Dataset
from posture_id.fileio import atomic_write_text, json_text
from posture_id.learning.checkpoint import LoadedModel
from posture_id.learning.config import ClassOutput, Layout, LearningError
from posture_id.learning.inputs import sway_features
from posture_id.learning.prediction import predict_images
from posture_id.learning.samples import stimulus_of
from posture_id.progress import Progress, report
from posture_id.uncertainty.conformal import ConformalCalibration, Normaliser
from posture_id.uncertainty.coverage import fit_temperature
from posture_id.uncertainty.noise import sensor_noise_deg

__all__ = ["CALIBRATION", "CnnCalibration", "HeldOutPredictions", "calibrate_cnn",
           "held_out_predictions", "noise_levels_of"]

CALIBRATION = "calibration.json"
#: Second word of the seed of the sensor noise added to held-out sway.
_NOISE_STREAM = 0xCA1B


@dataclass(frozen=True)
class HeldOutPredictions:
    """The CNN on T trials of a split at one sensor-noise level.

    Attributes:
        noise_deg: the white noise SD added, °. estimate, truth: (T, N, 5) normalised
        [K̃p, K̃i, K̃d, Δ̃, C]. logit: (T, N) class logits. noise_estimate_deg: (T,).
    """

    noise_deg: float
    estimate: np.ndarray
    truth: np.ndarray
    logit: np.ndarray
    noise_estimate_deg: np.ndarray


def held_out_predictions(model: LoadedModel, data: Dataset, split: str, noise_deg: float,
                         progress: Progress | None = None) -> HeldOutPredictions:
    """The CNN's answers on every trial of ``split`` with white sensor noise of
    ``noise_deg``° added to the stored noise-free sway (seeded by shard and level)."""
    layout = model.config.layout
    locals_ = data.split_local(split)
    profile = stimulus_of(data.manifest["stimulus"])
    rate = float(data.manifest["options"]["sample_rate_hz"])
    estimate, truth, logit, noise = [], [], [], []
    shards = [k for k, local in enumerate(locals_) if len(local)]
    for done, k in enumerate(shards):
        report(progress, done, len(shards), f"{split} split at {noise_deg:g}°")
        arrays = data.load_shard(k, keys=("theta", "targets"))
        local = locals_[k]
        theta = arrays["theta"][local].astype(np.float64)
        rng = np.random.default_rng(np.random.SeedSequence(
            [k, int(round(1e6 * noise_deg)), _NOISE_STREAM]))
        theta += np.radians(noise_deg) * rng.standard_normal(theta.shape)
        tilt = profile.angle(np.arange(theta.shape[1]) / rate)
        features = sway_features(layout, profile, tilt, theta)
        n = theta.shape[2]
        if layout is Layout.MODULAR:
            features = features.reshape(-1, *features.shape[2:])
        prediction = predict_images(model, features)
        estimate.append(prediction.targets.reshape(len(local), n, 5))
        logit.append(prediction.class_logit.reshape(len(local), n))
        truth.append(np.asarray(arrays["targets"][local], dtype=np.float64))
        noise.append(sensor_noise_deg(theta))
    report(progress, len(shards), len(shards), f"{split} split at {noise_deg:g}°")
    return HeldOutPredictions(float(noise_deg), np.concatenate(estimate), np.concatenate(truth),
                              np.concatenate(logit), np.concatenate(noise))


def noise_levels_of(data: Dataset, count: int = 5) -> tuple[float, ...]:
    """``count`` evenly spaced sensor-noise levels from 0 to the data set's training noise
    (just 0 for a set made without it)."""
    top = float(data.manifest["config"].get("sensor_noise_deg", 0.0) or 0.0)
    if top == 0:
        return (0.0,)
    return tuple(float(x) for x in np.round(np.linspace(0.0, top, count), 6))


@dataclass(frozen=True)
class CnnCalibration:
    """See the module doc. ``temperature``: (N,) per module, or None for the paper's
    regression class output (its 0/1 class probability cannot be calibrated).
    ``least_squares``: the scales of the Gauss-Newton standard errors of least squares
    refining this model's answers (:mod:`posture_id.identify.calibration`), or None when
    not measured."""

    weights_sha256: str
    intervals: ConformalCalibration
    temperature: tuple[float, ...] | None
    dataset: str
    least_squares: ConformalCalibration | None = None

    def class_probability(self, logit: np.ndarray) -> np.ndarray:
        """Calibrated P(C = +1) from (..., N) logits."""
        t = np.asarray(self.temperature if self.temperature is not None else 1.0)
        return 1.0 / (1.0 + np.exp(-np.asarray(logit) / t))

    def to_dict(self) -> dict:
        return {"format": "posture_id-calibration", "format_version": 1,
                "weights_sha256": self.weights_sha256, "dataset": self.dataset,
                "temperature": self.temperature, "intervals": self.intervals.to_dict(),
                "least_squares": (None if self.least_squares is None
                                  else self.least_squares.to_dict())}

    def save(self, model_dir: str | Path) -> Path:
        return atomic_write_text(Path(model_dir) / CALIBRATION, json_text(self.to_dict()))

    @classmethod
    def load(cls, model_dir: str | Path) -> CnnCalibration | None:
        """The calibration in ``model_dir``, or None when there is none."""
        path = Path(model_dir) / CALIBRATION
        if not path.exists():
            return None
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
            if data.get("format") != "posture_id-calibration":
                raise ValueError("not a posture_id calibration file")
            return cls(str(data["weights_sha256"]),
                       ConformalCalibration.from_dict(data["intervals"], str(path)),
                       None if data["temperature"] is None else
                       tuple(float(t) for t in data["temperature"]),
                       str(data.get("dataset", "")),
                       None if data.get("least_squares") is None else
                       ConformalCalibration.from_dict(data["least_squares"], str(path)))
        except (OSError, ValueError, KeyError, TypeError) as error:
            raise LearningError(f"{path}: unreadable calibration ({error}); make it again "
                                "with posture-id calibration") from None


def calibrate_cnn(model: LoadedModel, data: Dataset, noise_levels: tuple[float, ...],
                  progress: Progress | None = None) -> CnnCalibration:
    """Calibrate ``model`` on the validation split of ``data`` (see the module doc)."""
    if not noise_levels:
        raise LearningError("calibration needs at least one sensor-noise level")
    runs = [held_out_predictions(model, data, "validation", level, progress)
            for level in noise_levels]
    scores = np.stack([np.abs(r.truth[..., :4] - r.estimate[..., :4]) for r in runs])
    intervals = ConformalCalibration.from_scores(
        Normaliser.ABSOLUTE, scores,
        np.array([np.median(r.noise_estimate_deg) for r in runs]), np.array(noise_levels))
    temperature = None
    if model.config.class_output is ClassOutput.LOGIT:
        logits = np.concatenate([r.logit for r in runs])
        outcomes = np.concatenate([r.truth[..., 4] > 0 for r in runs])
        temperature = tuple(fit_temperature(logits[:, m], outcomes[:, m])
                            for m in range(logits.shape[1]))
    return CnnCalibration(str(model.sidecar.get("weights_sha256")), intervals, temperature,
                          str(data.path))
