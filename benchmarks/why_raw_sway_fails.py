"""The figure and numbers of docs/real_recordings.md: one people-like subject fitted on its
raw sway and on its stimulus-locked sway.

Run:  .venv/bin/python benchmarks/why_raw_sway_fails.py

A TIP subject with the default parameters, 6 cycles of the 80-state PRTS (120 s), motor
noise scaled so that 15 % of its body COM sway's variance is stimulus-locked, 0.05° sensor
noise. Both fits start from the defaults with the classes relaxed. For the locked fit also
its Gauss-Newton standard errors of Kp (normalised) and its χ² at its answer and at the
truth. Writes
docs/results/why_raw_sway_fails.{png,json}.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from posture_id import __version__, load_body
from posture_id.dec.parameters import default_parameters
from posture_id.fileio import atomic_write_text
from posture_id.fitting import FitOptions, fit_recording
from posture_id.frf.locked import LockedOptions, LockedProjection
from posture_id.plotting import plot_locked_sway
from posture_id.simulation import prts, simulate
from posture_id.simulation.subjects import people_like
from posture_id.trials import prepare_trial

OUT = Path(__file__).resolve().parent.parent / "docs" / "results"


def main() -> None:
    body = load_body()
    truth = default_parameters(body)
    stim = prts(states=80, cycles=6)
    subject = people_like(body, truth, stim, locked_share=0.15, seed=3)
    rec = subject.recording
    com = np.degrees(body.com_angles(rec.theta)[:, 0])
    fits, numbers = {}, {"locked_share": subject.locked_share,
                         "motor_noise_deg": subject.motor_noise.sd_deg}
    for label, locked in (("raw-sway least squares", None),
                          ("locked least squares", LockedOptions())):
        fit = fit_recording(prepare_trial(rec, stim), body, options=FitOptions(locked=locked))
        again = simulate(body, fit.parameters, stim)
        fits[label] = np.degrees(again.alpha[:, 0])
        locked_com = np.degrees(subject.locked.alpha[:, 0])
        numbers[label] = {
            "classes_right": fit.classes == tuple(truth[j].controls for j in body.joint_names),
            "kp_error": (fit.parameters.array("kp") / truth.array("kp") - 1).tolist(),
            "e_rel_locked": float(np.linalg.norm(fits[label] - locked_com)
                                  / np.linalg.norm(locked_com)),
            "raw_variance_explained": float(1 - np.var(com - fits[label]) / np.var(com)),
        }
        if locked is not None:
            # how well the data determine the gains, and whether the fit's answer explains
            # the locked sway worse than the truth does (χ² in units of the noise)
            weighted = LockedProjection.for_recording(
                rec.tilt, np.degrees(rec.theta), rec.sample_rate_hz, stim.period_s,
                stim.periodic_from_s, locked)
            at_truth = weighted.apply(np.degrees(subject.locked.theta - rec.theta))
            numbers[label].update(
                kp_standard_error=fit.standard_errors_normalised[:, 0].tolist(),
                chi2_at_fit=2 * fit.cost, chi2_at_truth=float((at_truth**2).sum()),
                residuals=int(at_truth.size))
    projection = LockedProjection.for_recording(rec.tilt, com[:, None], rec.sample_rate_hz,
                                                stim.period_s, options=LockedOptions(
                                                    max_frequency_hz=10.0))
    spectrum = np.abs(projection.all_harmonics(com))
    p = projection.period
    freqs = np.arange(1, p // 2 + 1) * rec.sample_rate_hz / p
    plot_locked_sway(rec.time, com, np.degrees(subject.locked.alpha[:, 0]), fits, freqs,
                     spectrum, projection.excited, projection.noise[:, 0],
                     path=OUT / "why_raw_sway_fails.png",
                     title=f"one subject, {100 * subject.locked_share:.0f} % of its sway "
                           "locked to the stimulus (80-state PRTS × 6)")
    numbers["package_version"] = __version__
    atomic_write_text(OUT / "why_raw_sway_fails.json", json.dumps(numbers, indent=2))
    print(json.dumps(numbers, indent=2))


if __name__ == "__main__":
    main()
