"""Exchanged columns on recordings cleaner than the network's own error: does putting two
columns the other way round ever explain a *right* recording three times better?

Run:  .venv/bin/python benchmarks/columns_on_clean.py

For the TIP and the 2- and 3-segment Winter bodies (1.75 m, 70 kg), four PRTSs (242
states ×2 at 0.5° and 2°, 80 states ×6 at 1° and 3°), the first two of docs/model.md §5's draws
from seed 100 on that keep their balance, with no sensor noise and with 0.005°: the
bundled network's answer re-simulated, in units of the recording's noise (what
:func:`posture_id.identify.alternatives.better_explanations` compares), as recorded and
with each pair of neighbouring columns exchanged. Prints, per recording, the gain of the
best exchanged reading of the right recording (below 1: worse than as recorded; the check
names columns at ``SWAP_GAIN``, 3) and the gain of putting back the first two columns of
the recording with them exchanged; then the largest gain on right recordings and the
share of the locked body sway the right answers leave: the numbers behind
``MIN_NOISE_SHARE``'s comment (docs/identify.md, "Mistakes").
"""

from __future__ import annotations

import numpy as np

from posture_id.bodies.body import load_body
from posture_id.dec.prior import sample_parameters
from posture_id.identify import Identifier, Method
from posture_id.identify.alternatives import columns_exchanged
from posture_id.learning.data.bodies import build_body
from posture_id.learning.data.scope import BodyDraw
from posture_id.simulation import prts, simulate

STIMULI = ((0.5, 2, 242), (2.0, 2, 242), (1.0, 6, 80), (3.0, 6, 80))


def main() -> None:
    bodies = {"TIP": load_body()}
    for n in (2, 3):
        bodies[f"Winter {n}-seg"] = build_body(BodyDraw("winter", n, 1.75, 70.0,
                                                        ((1.0, 1.0),) * n))
    right_gains, back_gains, shares = [], [], []
    print("| body | PRTS | seed | sensor noise | right: best exchanged gain | exchanged: "
          "putting back gain |\n|---|---|---|---|---|---|")
    for name, body in bodies.items():
        identifier = Identifier(body, Method.CNN)
        for amplitude, cycles, states in STIMULI:
            stimulus = prts(amplitude, cycles, states)
            standing = []
            for seed in range(100, 160):
                truth = sample_parameters(body, 1, np.random.default_rng(seed)).trial(
                    0, body.joint_names)
                sim = simulate(body, truth, stimulus)
                if sim.stable:
                    standing.append((seed, sim))
                if len(standing) == 2:
                    break
            for seed, sim in standing:
                for noise in (0.0, 0.005):
                    recording = sim.to_recording()
                    if noise:
                        recording = recording.with_sensor_noise(noise, seed)
                    trial = identifier.prepare(recording, stimulus)
                    check = identifier._network_check(trial, body)
                    given = check.ratio
                    shares.append(check.relative)
                    best = min(identifier._network_check(columns_exchanged(trial, k), body).ratio
                               for k in range(body.n_segments - 1))
                    swapped = identifier._network_check(columns_exchanged(trial, 0), body).ratio
                    right_gains.append(given / best)
                    back_gains.append(swapped / given)
                    print(f"| {name} | {states}×{cycles}, {amplitude:g}° | {seed} | {noise:g}° "
                          f"| {given / best:.2f} | {swapped / given:.1f} |", flush=True)
    print(f"\n{len(right_gains)} right recordings: the best exchanged reading's gain at most "
          f"{max(right_gains):.2f}; putting back the exchanged columns gains "
          f"{min(back_gains):.1f}–{max(back_gains):.0f}× ({sum(g >= 3 for g in back_gains)} "
          f"of {len(back_gains)} at 3× or more); the right answers leave "
          f"{100 * min(shares):.1f}–{100 * max(shares):.1f} % of the recorded locked body sway "
          "(the network's own error: the noise is a far smaller share)")


if __name__ == "__main__":
    main()
