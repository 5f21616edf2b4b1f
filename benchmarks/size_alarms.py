"""Right bodies called another person's: the size check's false alarms on clean sway.

Run:  .venv/bin/python benchmarks/size_alarms.py [--recordings 40] [--unconfirmed]
                                                 [--model DIR]

Clean recordings of Winter bodies of 1–3 segments (1.5–1.95 m, 50–95 kg), docs/model.md §5's
draws, the 242-state PRTS ×2 or the 80-state PRTS ×6 at 0.5–3° peak to peak, 0.005,
0.01 or 0.02° of white sensor noise, each identified by the default command on its *own*
body (``Identifier(body).identify``). Prints each recording's verdict and the mistakes
named, then how many right bodies were called another person's ("is the URDF this
subject's?"). ``--unconfirmed``: the size check without least squares' confirmation
(``Identifier._fits_within_noise`` taken as False: the network's readings alone, as
before stop 53). Draws are seeded (2024): the same recordings every run.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from posture_id.dec.prior import sample_parameters
from posture_id.identify.core import Identifier
from posture_id.learning.data.bodies import build_body
from posture_id.learning.data.scope import BodyDraw
from posture_id.simulation import prts, simulate

SEED = 2024


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--recordings", type=int, default=40, help="draws (those that "
                        "fall are skipped)")
    parser.add_argument("--unconfirmed", action="store_true")
    parser.add_argument("--model", type=Path, help="universal model (default: bundled)")
    args = parser.parse_args()
    if args.unconfirmed:
        Identifier._fits_within_noise = lambda self, *args: False
    rng = np.random.default_rng(SEED)
    alarms = made = 0
    for k in range(args.recordings):
        segments = int(rng.integers(1, 4))
        height, mass = float(rng.uniform(1.5, 1.95)), float(rng.uniform(50, 95))
        body = build_body(BodyDraw("winter", segments, height, mass, ((1.0, 1.0),) * segments))
        truth = sample_parameters(body, 1, rng).trial(0, body.joint_names)
        amplitude = float(np.exp(rng.uniform(np.log(0.5), np.log(3))))
        stimulus = prts(amplitude, 2, 242) if rng.random() < 0.5 else prts(amplitude, 6, 80)
        noise_deg = float(rng.choice([0.005, 0.01, 0.02]))
        sim = simulate(body, truth, stimulus)
        if not sim.stable:
            continue
        recording = sim.to_recording().with_sensor_noise(noise_deg, k)
        result = Identifier(body, model=args.model).identify(recording, stimulus)
        named = [m for m in result.verdict.mistakes if "is the URDF this subject's?" in m]
        made += 1
        alarms += bool(named)
        print(f"{k:3d} {segments}-seg {height:.2f} m {noise_deg:g}° {stimulus.description}: "
              f"{result.verdict.level} ({result.method.value}, "
              f"{result.verdict.noise.ratio:.1f}× the noise)"
              + (f"; {named[0].split(':')[0]}" if named else ""), flush=True)
    print(f"right bodies called another person's: {alarms} of {made}")


if __name__ == "__main__":
    main()
