"""Bent bodies at rest and in proportion: the scenarios of tests/test_reference_posture.py,
measured (docs/model.md, "The reference posture of a bent body").

For each lumped preset (TALOS, G1, the example-robot-data human; 3 segments, their
default parameters): the largest |θ| over 30 s without any tilt, the segment angles at the
end of those 30 s, and how far the sway to a 3° PRTS (80 states of 0.25 s, one cycle, no
dead-band) is from six times the sway to a 0.5° one, relative to the latter's peak. Then
with 12 gain sets drawn from docs/model.md §5's prior (seeded; Kp ≠ m·g·h, so the servo must hold
the stance): the largest |θ| over 30 s without any tilt (the stable draws), and the
median stimulus-locked share of the noise-free body COM sway to the 242-state PRTS ×2 at
0.5° (dead-band on; drift-free cycle average, as the universal features read it), with
the TIP and a 3-segment Winter body (1.75 m, 70 kg) beside them.

Run:  .venv/bin/python benchmarks/reference_posture.py
(With ``PYTHONPATH`` pointing at a checkout of an earlier commit, the same script measures
that version: docs/model.md quotes both.)
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

import posture_id
from posture_id.bodies.body import load_body
from posture_id.dec.parameters import default_parameters
from posture_id.dec.prior import sample_parameters
from posture_id.frf.cycles import cycle_average
from posture_id.learning.data.bodies import build_body
from posture_id.learning.data.scope import BodyDraw
from posture_id.simulation import SimulationOptions, prts, simulate
from posture_id.simulation.batch import simulate_batch
from posture_id.simulation.stimulus import tilt_from_array

ROOT = Path(__file__).resolve().parents[1]
PRESETS = ("talos_tip", "g1_tip", "human_tip")


def measure(name: str) -> dict:
    body = load_body(ROOT / "urdf" / f"{name}.urdf")
    params = default_parameters(body)
    still = simulate(body, params, tilt_from_array(np.array([0.0, 30.0]), np.zeros(2)))
    options = SimulationOptions(deadband_rad_s=0.0)

    def sway(amplitude_deg: float) -> np.ndarray:
        stim = prts(amplitude_deg=amplitude_deg, states=80, state_s=0.25, cycles=1)
        return simulate(body, params, stim, options).theta

    small, large = sway(0.5), sway(3.0)
    return {
        "body": name,
        "max_abs_theta_without_tilt_deg": float(np.degrees(np.nanmax(np.abs(still.theta)))),
        "theta_after_30s_deg": np.degrees(still.theta[-1]).round(3).tolist(),
        "nonlinearity_3_vs_0.5_deg": float(np.nanmax(np.abs(large / 6.0 - small))
                                           / np.nanmax(np.abs(small))),
    }


DRAWS = 12


def measure_drawn(name: str, body) -> dict:
    """Gains from the prior: the stance without a tilt, the locked share at 0.5°."""
    params = sample_parameters(body, DRAWS, np.random.default_rng(11))
    still = simulate_batch(body, params, tilt_from_array(np.array([0.0, 30.0]), np.zeros(2)))
    stim = prts(amplitude_deg=0.5, states=242, state_s=0.25, cycles=2)
    swayed = simulate_batch(body, params, stim)
    period = int(round(stim.period_s * SimulationOptions().sample_rate_hz))
    shares, excursions = [], []
    for k in range(DRAWS):
        rest, trial = still.trial(k), swayed.trial(k)
        if not (rest.stable and trial.stable):
            continue
        excursions.append(float(np.degrees(np.abs(rest.theta).max())))
        sway = np.degrees(body.com_angles(trial.theta)[:, 0])
        shares.append(float(cycle_average(sway[:, None], period, 0, 1).locked_share[0]))
    return {"body": name, "stable_draws": len(shares),
            "max_abs_theta_without_tilt_deg": max(excursions) if excursions else None,
            "median_locked_share_at_0.5deg": float(np.median(shares)) if shares else None}


def main() -> None:
    print(f"posture_id from {Path(posture_id.__file__).parent}")
    for name in PRESETS:
        print(json.dumps(measure(name)))
    print(f"gains from the prior ({DRAWS} draws):")
    for name in PRESETS:
        print(json.dumps(measure_drawn(name, load_body(ROOT / "urdf" / f"{name}.urdf"))))
    for name, body in (("tip", load_body()), ("winter 3-seg 1.75 m 70 kg", build_body(
            BodyDraw("winter", 3, 1.75, 70.0, ((1.0, 1.0),) * 3)))):
        print(json.dumps(measure_drawn(name, body)))


if __name__ == "__main__":
    main()
