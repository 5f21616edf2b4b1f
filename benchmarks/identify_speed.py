"""How long the CNN takes to identify one recording, features included.

Run:  .venv/bin/python benchmarks/identify_speed.py [--model DIR] [--recordings 50]

Simulates ``--recordings`` 121 s TIP recordings (docs/model.md §5 random parameters, stable
ones), loads the model once (default: the bundled TIP model), then times, per recording,
``CnnIdentifier.identify``: the checks of the recording and its stimulus, the STFT
features, the network, the parameters and, for a calibrated model, the intervals (the
sensor-noise estimate and the conformal half-widths). Reports the median and 90th
percentile per recording, with the time of the features and of the network alone, and
the same identifier with its calibration switched off, timed in turn with it, for the
cost of the intervals as a ratio; for 1 and for all torch threads. Writes
docs/results/identify_speed.json.
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import statistics
import time
from pathlib import Path

import numpy as np
import torch

from posture_id import __version__, load_body, sample_parameters, simulate_batch
from posture_id.fileio import atomic_write_text
from posture_id.learning.features.spectrograms import FS_HZ, modular_images, stft
from posture_id.learning.identifier import CnnIdentifier
from posture_id.learning.prediction import predict_images
from posture_id.trials import prepare_trial

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"


def timed(fn, repeats: int) -> list[float]:
    out = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        out.append(time.perf_counter() - start)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", type=Path, help="model directory (default: bundled)")
    parser.add_argument("--recordings", type=int, default=50)
    parser.add_argument("--out", type=Path,
                        default=RESULTS / "identify_speed.json")
    args = parser.parse_args()
    body = load_body()
    identifier = CnnIdentifier.resolve(args.model, body)
    params = sample_parameters(body, 2 * args.recordings, np.random.default_rng(5))
    batch = simulate_batch(body, params)
    recordings = [batch.trial(b).to_recording() for b in np.flatnonzero(batch.stable)]
    recordings = recordings[: args.recordings]
    identifier.identify(prepare_trial(recordings[0]))  # warm up (first call allocates)
    plain = copy.copy(identifier)
    plain.calibration = None  # the same network, without intervals
    results = {"package_version": __version__, "model": str(identifier.model.path),
               "recordings": len(recordings), "cpus": os.cpu_count(), "threads": {}}
    for threads in sorted({1, os.cpu_count() or 1}):
        torch.set_num_threads(threads)
        whole, without = [], []
        for r in recordings:  # in turn, so that both see the same machine state
            whole += timed(lambda r=r: identifier.identify(prepare_trial(r)), 3)
            without += timed(lambda r=r: plain.identify(prepare_trial(r)), 3)
        rec = recordings[0]
        theta = rec.theta[: identifier.n_samples]
        tilt = rec.tilt[: identifier.n_samples]
        features = timed(lambda t=tilt, th=theta: modular_images(stft(t), stft(th.T)[None]), 50)
        images = identifier.features(prepare_trial(rec))
        network = timed(lambda x=images: predict_images(identifier.model, x), 50)
        row = {"identify_ms_median": 1e3 * statistics.median(whole),
               "identify_ms_p90": 1e3 * float(np.percentile(whole, 90)),
               "features_ms_median": 1e3 * statistics.median(features),
               "network_ms_median": 1e3 * statistics.median(network),
               "calibrated": identifier.calibration is not None,
               "identify_without_intervals_ms_median": 1e3 * statistics.median(without),
               "intervals_time_ratio": statistics.median(whole) / statistics.median(without)}
        results["threads"][str(threads)] = row
        print(f"{threads} thread(s): identify {row['identify_ms_median']:.2f} ms median "
              f"({row['identify_ms_p90']:.2f} ms 90th percentile) per {len(rec.time)}-sample "
              f"recording at {FS_HZ:g} Hz; of which STFT features "
              f"{row['features_ms_median']:.2f} ms, network {row['network_ms_median']:.2f} ms; "
              f"without the intervals {row['identify_without_intervals_ms_median']:.2f} ms "
              f"(with them {row['intervals_time_ratio']:.2f}× that)")
    atomic_write_text(args.out, json.dumps(results, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
