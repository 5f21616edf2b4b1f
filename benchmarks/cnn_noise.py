"""How the CNN's class calls hold up under sensor noise.

Run:  .venv/bin/python benchmarks/cnn_noise.py [--model DIR] [--trials 40]

Simulates ``--trials`` 121 s TIP recordings (docs/model.md §5 parameters from
``default_rng(5)``; the stable ones are used), adds white noise of 0, 0.01° and 0.05° to
the segment angles (``Recording.with_sensor_noise``), and counts the recordings whose
three classes the CNN calls right, and the modules. Writes
docs/results/cnn_noise.json.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from posture_id import __version__, load_body, sample_parameters, simulate_batch
from posture_id.fileio import atomic_write_text
from posture_id.learning.identifier import CnnIdentifier
from posture_id.trials import prepare_trial

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", type=Path, help="model directory (default: bundled)")
    parser.add_argument("--trials", type=int, default=40)
    parser.add_argument("--out", type=Path,
                        default=RESULTS / "cnn_noise.json")
    args = parser.parse_args()
    body = load_body()
    identifier = CnnIdentifier.resolve(args.model, body)
    params = sample_parameters(body, args.trials, np.random.default_rng(5))
    batch = simulate_batch(body, params)
    results = {}
    for noise in (0.0, 0.01, 0.05):
        trials, modules = [], []
        for b in np.flatnonzero(batch.stable):
            truth = params.trial(b, body.joint_names)
            recording = batch.trial(b).to_recording()
            if noise:
                recording = recording.with_sensor_noise(noise, int(b))
            got = identifier.identify(prepare_trial(recording)).classes
            right = [g == truth[j].controls for g, j in zip(got, body.joint_names, strict=True)]
            trials.append(all(right))
            modules += right
        results[f"{noise:g}"] = {"recordings": len(trials),
                                 "all_classes_right": float(np.mean(trials)),
                                 "modules_right": float(np.mean(modules))}
        print(f"sensor noise {noise:g}°: all three classes right in "
              f"{100 * np.mean(trials):.0f} % of {len(trials)} recordings, "
              f"{100 * np.mean(modules):.1f} % of modules")
    atomic_write_text(args.out, json.dumps({"package_version": __version__,
                                            "model": str(identifier.model.path),
                                            "results": results}, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
