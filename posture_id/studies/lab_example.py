"""The shipped lab-like example recording: a file as a lab writes it.

    python -m posture_id.studies.lab_example posture_id/studies/examples   # = make examples

A simulated subject (a 1-segment Winter body of 1.75 m and 70 kg: the lab records the body
COM only) with people-like sway (motor noise and 0.02° sensor noise), on the 80-state
PRTS × 3, 1° peak to peak, started 36.48 states into its cycle after a 1.97 s lead-in and a
40 ms platform lag, the platform level again for 1.7 s after the last cycle; sampled at
100 Hz and written with the lab's own column names, ``time,platform,COM_x`` (seconds,
degrees). Writes ``lab_subject.csv``, ``lab_subject.urdf`` and ``lab_subject.truth.json``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from posture_id.bodies.anthropometry import straight_links, winter_segments
from posture_id.bodies.body import load_body
from posture_id.bodies.urdf_writer import write_chain_urdf
from posture_id.dec.parameters import default_parameters
from posture_id.fileio import atomic_write_text
from posture_id.simulation.batch import simulate
from posture_id.simulation.noise import MotorNoise
from posture_id.simulation.stimulus import prts

__all__ = ["LAB_STIMULUS", "make_lab_example"]

#: The stimulus as the example lab ran it.
LAB_STIMULUS = {"amplitude_deg": 1.0, "cycles": 3, "states": 80, "onset_s": 1.97,
                "start_state": 36.48, "lag_s": 0.04}
RATE_HZ, TAIL_S, SENSOR_NOISE_DEG = 100.0, 1.7, 0.02


def make_lab_example(folder: str | Path) -> list[Path]:
    """Write the example's three files into ``folder`` (atomically); their paths."""
    folder = Path(folder)
    urdf = write_chain_urdf(folder / "lab_subject.urdf", "lab_subject",
                            straight_links(winter_segments(1.75, 70.0, 1)))
    body = load_body(urdf)
    joint = body.joint_names[0]
    truth = default_parameters(body)
    truth = truth.replace(joint, kp=1.15 * truth[joint].kp, kd=0.9 * truth[joint].kd)
    stimulus = prts(**LAB_STIMULUS)
    stimulus = stimulus.spanning(stimulus.duration + TAIL_S)
    sway = simulate(body, truth, stimulus, motor_noise=MotorNoise(0.1, seed=21))
    t = np.arange(int(round(sway.time[-1] * RATE_HZ)) + 1) / RATE_HZ
    com = np.interp(t, sway.time, sway.theta[:, 0])
    com += np.radians(SENSOR_NOISE_DEG) * np.random.default_rng(22).standard_normal(len(t))
    tilt = stimulus.angle(t)
    rows = "".join(f"{a:.4f},{np.degrees(b):.8f},{np.degrees(c):.8f}\n"
                   for a, b, c in zip(t, tilt, com, strict=True))
    csv = atomic_write_text(folder / "lab_subject.csv", "time,platform,COM_x\n" + rows)
    truth.to_json(folder / "lab_subject.truth.json")
    return [csv, Path(urdf), folder / "lab_subject.truth.json"]


if __name__ == "__main__":
    for path in make_lab_example(sys.argv[1] if len(sys.argv) > 1 else "."):
        print(f"wrote {path}")
