"""Why the CNN's conformal intervals are split by sensor noise: the choice, measured.

Run:  .venv/bin/python benchmarks/interval_methods.py [--model DIR] [--dataset DIR]

The CNN (default: data/models/tip_default) answers every validation and test trial of the
data set (default: data/tip_default) at sensor noise 0° and 0.05°. Three ways to make its
90 % intervals from the validation answers are then checked on the test answers, per
module and parameter:

- ``pooled``: one conformal half-width per module and parameter from the validation
  trials of both noise levels together (plain split conformal);
- ``scaled by noise``: scores |error| / (1 + noise/0.05°), one conformal scale (a
  normalised score with the recording's estimated noise as its difficulty);
- ``split by noise`` (what posture_id does, :mod:`posture_id.uncertainty.conformal`):
  half-widths per noise level, interpolated at the recording's estimated noise.

Writes docs/results/interval_methods.json.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from posture_id.fileio import atomic_write_text
from posture_id.learning.calibration import held_out_predictions
from posture_id.learning.checkpoint import load_model
from posture_id.learning.data.store import Dataset
from posture_id.uncertainty.conformal import ConformalCalibration, Normaliser, conformal_quantile

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"

LEVEL = 0.9
NOISE = (0.0, 0.05)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", type=Path, default=Path("data/models/tip_default"))
    parser.add_argument("--dataset", type=Path, default=Path("data/tip_default"))
    parser.add_argument("--out", type=Path,
                        default=RESULTS / "interval_methods.json")
    args = parser.parse_args()
    model = load_model(args.model)
    data = Dataset.open(args.dataset)
    runs = {(split, noise): held_out_predictions(model, data, split, noise)
            for split in ("validation", "test") for noise in NOISE}

    def error(split, noise):
        r = runs[(split, noise)]
        return np.abs(r.truth[..., :4] - r.estimate[..., :4])

    def difficulty(split, noise):
        return 1.0 + runs[(split, noise)].noise_estimate_deg[:, None, None] / 0.05

    pooled = conformal_quantile(np.concatenate([error("validation", n) for n in NOISE]), LEVEL)
    scaled = conformal_quantile(np.concatenate(
        [error("validation", n) / difficulty("validation", n) for n in NOISE]), LEVEL)
    split = ConformalCalibration.from_scores(
        Normaliser.ABSOLUTE, np.stack([error("validation", n) for n in NOISE]),
        np.array([np.median(runs[("validation", n)].noise_estimate_deg) for n in NOISE]),
        np.array(NOISE))
    results = {"model": str(args.model), "dataset": str(args.dataset), "level": LEVEL,
               "test_trials": len(runs[("test", 0.0)].truth), "methods": {}}
    for name in ("pooled", "scaled by noise", "split by noise"):
        per_noise = {}
        for noise in NOISE:
            err = error("test", noise)
            if name == "pooled":
                half = np.broadcast_to(pooled, err.shape)
            elif name == "scaled by noise":
                half = scaled * difficulty("test", noise)
            else:
                half = np.stack([split.scale(LEVEL, x)
                                 for x in runs[("test", noise)].noise_estimate_deg])
            cov = np.mean(err <= half, axis=0)
            per_noise[f"{noise:g}"] = {"coverage": cov.tolist(), "min": float(cov.min()),
                                       "max": float(cov.max()),
                                       "mean_width": np.mean(2 * half, axis=0).tolist()}
            print(f"{name:>16} at {noise:g}°: 90 % coverage {100 * cov.min():.1f}–"
                  f"{100 * cov.max():.1f} % over the 12 parameters")
        results["methods"][name] = per_noise
    atomic_write_text(args.out, json.dumps(results, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
