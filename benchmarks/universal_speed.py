"""How long the universal network takes to identify one recording, features included.

Run:  .venv/bin/python benchmarks/universal_speed.py [--recordings 30]

Simulates ``--recordings`` recordings of the TIP under the 242-state PRTS ×2 (121 s) and
of a 1-segment Winter body under the 80-state PRTS ×12 (240 s), loads the bundled
universal model once per body, then times, per recording, ``UniversalIdentifier.identify``
on a prepared trial (the harmonics, the features, the network, the calibrated intervals
and class probabilities), and the network alone; for 1 and for all torch threads.
Preparing the trial (reading and checking the recording, recognising its stimulus) is
the same for every method and is not included. Writes
docs/results/universal_speed.json.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

from posture_id import __version__, load_body, sample_parameters, simulate_batch
from posture_id.bodies.anthropometry import straight_links, winter_segments
from posture_id.bodies.urdf_writer import write_chain_urdf
from posture_id.fileio import atomic_write_text
from posture_id.learning.universal_identifier import UniversalIdentifier
from posture_id.simulation.stimulus import prts
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
    parser.add_argument("--recordings", type=int, default=30)
    parser.add_argument("--out", type=Path,
                        default=RESULTS / "universal_speed.json")
    args = parser.parse_args()
    tmp = Path(tempfile.mkdtemp())
    winter1 = write_chain_urdf(tmp / "w1.urdf", "winter1",
                               straight_links(winter_segments(1.75, 70.0, 1)))
    cases = {"TIP, PRTS 242 ×2 (121 s)": (load_body(), prts(1.0, 2, 242)),
             "Winter 1-seg, PRTS 80 ×12 (240 s)": (load_body(winter1), prts(1.0, 12, 80))}
    results = {"package_version": __version__, "recordings": args.recordings,
               "cpus": os.cpu_count(), "cases": {}}
    for name, (body, stimulus) in cases.items():
        identifier = UniversalIdentifier.bundled(body)
        params = sample_parameters(body, 2 * args.recordings, np.random.default_rng(5))
        batch = simulate_batch(body, params, stimulus)
        trials = [prepare_trial(batch.trial(b).to_recording(), stimulus)
                  for b in np.flatnonzero(batch.stable)[: args.recordings]]
        identifier.identify(trials[0])  # warm up (first call allocates)
        features = identifier.features(trials[0])
        rows = {}
        for threads in sorted({1, os.cpu_count() or 1}):
            torch.set_num_threads(threads)
            whole = [t for trial in trials
                     for t in timed(lambda x=trial, i=identifier: i.identify(x), 3)]
            network = timed(lambda x=features, i=identifier: i.model.predict(*x), 50)
            rows[str(threads)] = {"identify_ms_median": 1e3 * statistics.median(whole),
                                  "identify_ms_p90": 1e3 * float(np.percentile(whole, 90)),
                                  "network_ms_median": 1e3 * statistics.median(network)}
        results["cases"][name] = rows
        print(name, json.dumps(rows), flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(args.out, json.dumps(results, indent=2) + "\n")


if __name__ == "__main__":
    main()
