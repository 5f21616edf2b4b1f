"""The universal model on a specialist's own test set (``posture-id network cnn evaluate
--universal``): the same trials, the same standardised units, so the two can be read side
by side."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from posture_id.bodies.body import load_body
from posture_id.learning.data.store import Dataset, with_sensor_noise
from posture_id.learning.evaluation import relative_errors
from posture_id.learning.features.harmonics import harmonic_layout, sway_harmonics
from posture_id.learning.features.module_frfs import body_descriptors, com_weights
from posture_id.learning.universal_model import UniversalModel
from posture_id.learning.universal_samples import inputs_and_noise

__all__ = ["universal_on_dataset", "NOISE_STREAM"]

#: Second word of the seed of the sensor noise added to the stored sway.
NOISE_STREAM = 0x554E56


def universal_on_dataset(universal_dir: str | Path, dataset_dir: str | Path,
                         per_module: bool = True) -> dict:
    """Fit RMSE (per-sample reading, the data set's standardised units: per module when
    ``per_module``, else per trial), class accuracy and median |relative error| of each
    parameter of the universal model on the test split; each trial's sway gets white
    sensor noise of the SD its specialist features had (a new draw)."""
    model = UniversalModel.load(universal_dir)
    data = Dataset.open(dataset_dir)
    body = load_body(data.manifest["body"]["urdf"])
    stats = data.stats()
    std = np.asarray(stats["targets_std"], dtype=float)[:4]
    stimulus, rate = data.stimulus, data.rate_hz
    desc, com = body_descriptors(body), com_weights(body)
    local = data.split_local("test")
    errors, rel, right = [], [], []
    layout = None
    for k, idx in enumerate(local):
        if not len(idx):
            continue
        arrays = data.load_shard(k)
        theta = with_sensor_noise(arrays["theta"][idx].astype(np.float64),
                                  arrays["sensor_noise_deg"][idx],
                                  np.random.SeedSequence([k, NOISE_STREAM]))
        if layout is None:
            layout = harmonic_layout(data.tilt(theta.shape[1]), rate, stimulus.period_s,
                                     stimulus.periodic_from_s)
        y = sway_harmonics(layout, np.moveaxis(theta, 0, 1))  # (K, T, N)
        pred = model.predict(*inputs_and_noise(layout, y, desc, com))
        truth = arrays["targets"][idx].reshape(-1, 5).astype(float)
        errors.append(((pred.mean - truth[:, :4]) / std).reshape(len(idx), -1, 4))
        rel.append(relative_errors(pred.mean, truth[:, :4]))
        right.append((pred.logit > 0) == (truth[:, 4] > 0))
    err = np.concatenate(errors)  # (T, N, 4)
    squares = (err**2).sum(axis=2)
    per_sample = squares.ravel() if per_module else squares.sum(axis=1)
    rel = np.concatenate(rel)
    return {"model": str(universal_dir), "dataset": str(dataset_dir),
            "test_trials": int(len(err)),
            "fit_rmse_per_sample": float(np.sqrt(np.mean(per_sample))),
            "reading": "per module" if per_module else "per trial",
            "class_accuracy": float(np.mean(np.concatenate(right))),
            "median_error_pct": {n: float(100 * np.median(rel[:, i]))
                                 for i, n in enumerate(("kp", "ki", "kd", "delay_s"))}}

