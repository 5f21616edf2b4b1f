"""One subject, several trials: the IC joint fit (``posture_id.fitting.joint_conditions``)
on simulated subjects tested in two conditions with three sinusoid trials each.

Run:  .venv/bin/python benchmarks/joint_fit.py [--subjects 24] [--out docs/results/joint_fit]

Each subject: a 1-segment Winter body (1.75 m, 70 kg), IC parameters drawn by
:func:`~posture_id.models.ic.subjects.draw_ic_parameters` (Kp, Kd, Δ and the torque
feedback G, τ_f shared), and a proprioceptive weight W per condition: "eyes open" W drawn
within 0.3–0.5, "eyes closed" that plus 0.2–0.4 (vision gone, proprioception weighs
more). Per condition three trials, each one sinusoid (``SumOfSinesProtocol`` of one
frequency) of 2° peak to peak: 0.1, 0.2 and 0.4 Hz, 40 s each (4, 8 and 16 cycles). The
stimulus is given to ``prepare_trial``; the joint fit identifies the IC model's six
parameters with W per condition (seven numbers from twelve: two per trial).

Sway, made as :func:`~posture_id.models.ic.subjects.ic_recording` makes it (motor noise
through the subject's own loop, then white sensor noise):

- ``clean``: 0.02° sensor noise, no motor noise (the clean recordings of
  ``benchmarks/ic_recovery.py``);
- ``people-like``: the subject's own spontaneous sway, the motor noise that leaves
  15–40 % of its COM sway locked on the project's people-like PRTS trial (80 states, 1°
  peak to peak, three cycles; ``ic_recording``'s level), the same level on every trial,
  and 0.05° sensor noise. A sinusoid concentrates its sway at one frequency, so the locked
  share of a sinusoid trial is higher than the PRTS trial's (the report gives it).

A subject whose sway makes them fall on any trial is drawn again (as ``ic_recovery``
does). Reported per sway: the median and 90th percentile |error| of the shared Kp, Kd, Δ
(relative) and of W (absolute, both conditions), the share of 90 % intervals that hold the
truth per parameter and over all seven, the verdicts and the longest fit.
``--calibrate`` fits subjects of another seed and prints the quantiles of
|error| / standard error per parameter (what a calibrated interval multiplies the
standard error by), so that the report's own subjects test any calibration made from
them. Writes ``report.md`` and ``rows.json``.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SEED = 6060
CALIBRATION_SEED = 7070
BODY = ROOT / "urdf" / "winter_1.75m_70kg_1seg.urdf"
FREQUENCIES_HZ = (0.1, 0.2, 0.4)
TRIAL_S = 40.0
AMPLITUDE_DEG = 1.0  # each sine's amplitude: 2° peak to peak
CONDITIONS = ("eyes open", "eyes closed")
SHARED = ("kp", "kd", "delay_s", "torque_feedback_gain", "torque_feedback_time_s")
JUDGED = ("kp", "kd", "delay_s")
SWAYS = ("clean", "people-like")
LEVELS = (0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 0.99)
#: The simulation's step, s: the IC simulator's 2 ms semi-implicit Euler is first order,
#: its steady state off H(jω) by up to 2 % (docs/ic.md); clean sway would measure that
#: bias, not the fit. A quarter of it leaves a quarter of the bias.
STEP_S = 0.0005


def subject(body, seed: int, k: int, sway: str):
    """(truth, {condition: W}, trials, labels, motor level, PRTS locked share, each
    trial's locked share) of subject ``k``: drawn again until no trial falls (the module
    doc)."""
    from posture_id.models.ic import IcPlant
    from posture_id.models.ic.simulation import simulate_ic
    from posture_id.models.ic.subjects import draw_ic_parameters, ic_recording
    from posture_id.simulation.options import SimulationOptions
    from posture_id.simulation.protocols import SumOfSinesProtocol
    from posture_id.simulation.stimulus import prts
    from posture_id.trials import prepare_trial

    plant = IcPlant.of(body)
    fine = SimulationOptions(dt=STEP_S)
    rng = np.random.default_rng([seed, k])
    while True:
        truth = draw_ic_parameters(rng, plant)
        open_w = float(rng.uniform(0.3, 0.5))
        weights = {CONDITIONS[0]: open_w, CONDITIONS[1]: open_w + float(rng.uniform(0.2, 0.4))}
        level, share = 0.0, None
        if sway == "people-like":
            share = float(rng.uniform(0.15, 0.4))
            _, level = ic_recording(body, truth.replace(w=weights[CONDITIONS[0]]),
                                    prts(1.0, 3, 80), share, int(rng.integers(1 << 30)))
        trials, labels, shares = [], [], []
        for condition, w in weights.items():
            for f in FREQUENCIES_HZ:
                profile = SumOfSinesProtocol(frequencies_hz=(f,), amplitudes_deg=(AMPLITUDE_DEG,),
                                             cycles=int(round(TRIAL_S * f))).profile()
                noise_seed = int(rng.integers(1 << 30))
                recording = simulate_ic(body, truth.replace(w=w), profile, fine,
                                        motor_sd_deg=level, seed=noise_seed)
                recording = recording.with_sensor_noise(0.05 if level else 0.02, noise_seed)
                if not np.all(np.isfinite(recording.theta)):
                    break
                clean = simulate_ic(body, truth.replace(w=w), profile, fine)
                shares.append(float(np.var(body.com_angles(clean.theta)[:, 0])
                                    / np.var(body.com_angles(recording.theta)[:, 0])))
                recording = replace(recording, name=f"{condition} {f:g} Hz")
                trials.append(prepare_trial(recording, stimulus=profile, rate_hz=50.0))
                labels.append(condition)
        if len(trials) == len(CONDITIONS) * len(FREQUENCIES_HZ):
            return truth, weights, trials, labels, level, share, shares


def run(subjects: int, seed: int, sways=SWAYS) -> list[dict]:
    import scipy.optimize  # noqa: F401 - loaded before the first fit is timed

    from posture_id import load_body
    from posture_id.fitting.joint_conditions import fit_joint
    from posture_id.models.ic import IC

    body = load_body(BODY)
    plant = IC.plant(body)
    ranges = {n: (lo * IC.scale(n, plant), hi * IC.scale(n, plant))
              for n, (lo, hi) in IC.search_bounds.items()}
    rows = []
    for sway in sways:
        for k in range(subjects):
            truth, weights, trials, labels, level, share, shares = subject(body, seed, k, sway)
            started = time.perf_counter()
            fit = fit_joint(IC, trials, body, labels, ("w",))
            seconds = time.perf_counter() - started
            row = {"sway": sway, "k": k, "seconds": seconds, "level": fit.trust_level.value,
                   "chi2": fit.chi2, "dof": fit.dof, "motor_deg": level,
                   "prts_locked_share": share, "on_bound": list(fit.on_bound)}
            row["sine_locked_share"] = float(np.median(shares))
            for name in SHARED:
                _score(row, name, getattr(truth, name), fit.shared[name],
                       fit.intervals["shared"][name], fit.standard_errors["shared"][name],
                       ranges[name], relative=True)
            for c, condition in enumerate(CONDITIONS):
                _score(row, f"w{c}", weights[condition], fit.per_condition[condition]["w"],
                       fit.intervals["per_condition"][condition]["w"],
                       fit.standard_errors["per_condition"][condition]["w"], ranges["w"],
                       relative=False)
            rows.append(row)
            print(f"[{sway} {k + 1}/{subjects}] Kp {100 * row['kp_error']:.1f} %, Kd "
                  f"{100 * row['kd_error']:.1f} %, Δ {100 * row['delay_s_error']:.1f} %, W "
                  f"{row['w0_error']:.3f} / {row['w1_error']:.3f}, {fit.trust_level.value} "
                  f"({seconds:.1f} s)", file=sys.stderr, flush=True)
    return rows


def _score(row: dict, key: str, true: float, got: float, interval, se: float, search,
           relative: bool) -> None:
    """The error (relative or absolute), whether the interval holds the truth, whether it
    is the whole search range (the trials leave the parameter undetermined) and, where it
    is not, |error| / standard error (what the calibration takes quantiles of)."""
    low, high = interval
    row[f"{key}_error"] = abs(got - true) / abs(true) if relative and true else abs(got - true)
    row[f"{key}_inside"] = bool(low <= true <= high)
    undetermined = (low, high) == tuple(search)
    row[f"{key}_undetermined"] = undetermined
    row[f"{key}_z"] = None if undetermined or not se > 0 else abs(got - true) / se


WORDS = {"kp": "Kp", "kd": "Kd", "delay_s": "Δ", "torque_feedback_gain": "G",
         "torque_feedback_time_s": "τ_f", "w0": "W open", "w1": "W closed"}


def report(rows: list[dict], command: str) -> str:
    from posture_id.fitting.joint_conditions import joint_calibration

    keys = (*SHARED, "w0", "w1")
    made = joint_calibration().get("ic", {})
    subjects = len({r["k"] for r in rows})
    lines = ["# One subject, several trials: the IC joint fit", "",
             f"Made by `{command}` ({subjects} subjects per sway; the module doc of "
             "`benchmarks/joint_fit.py` says how). Two conditions (eyes open, eyes closed: "
             "W per condition, Kp, Kd, Δ, G and τ_f shared), three sinusoid trials each "
             f"(0.1, 0.2, 0.4 Hz, 2° peak to peak, {TRIAL_S:g} s); 7 parameters from 12 "
             "numbers.", "",
             "Intervals: the Gauss-Newton standard error of the joint weighted residual "
             "(scaled by χ²/(1.2·dof) where that exceeds 1: 1.2 is what the estimated noise "
             "levels make χ²/dof on average) times the joint fit's calibrated "
             "multiplier (`posture_id/fitting/joint_calibration.json`, "
             f"made by `{made.get('made_by', '?')}` on subjects of seed "
             f"{made.get('seed', '?')}, not these); a parameter whose standard error is 0 "
             "(a direction the trials leave undetermined) gets its whole search range.", "",
             "| sway | subjects | median |error| Kp, Kd, Δ | W (open, closed) | 90th "
             "percentile Kp, Kd, Δ | W | verdicts good / imprecise / doubtful | longest fit "
             "|", "|---|---|---|---|---|---|---|---|"]
    for sway in SWAYS:
        mine = [r for r in rows if r["sway"] == sway]
        if not mine:
            continue
        med = ", ".join(f"{100 * np.median([r[f'{p}_error'] for r in mine]):.1f} %"
                        for p in JUDGED)
        w = ", ".join(f"{np.median([r[f'w{c}_error'] for r in mine]):.3f}" for c in (0, 1))
        p90 = ", ".join(f"{100 * np.percentile([r[f'{p}_error'] for r in mine], 90):.1f} %"
                        for p in JUDGED)
        w90 = ", ".join(f"{np.percentile([r[f'w{c}_error'] for r in mine], 90):.3f}"
                        for c in (0, 1))
        verdicts = " / ".join(str(sum(r["level"] == v for r in mine))
                              for v in ("good", "imprecise", "doubtful"))
        longest = max(r["seconds"] for r in mine)
        lines.append(f"| {sway} | {len(mine)} | {med} | {w} | {p90} | {w90} | {verdicts} | "
                     f"{longest:.1f} s |")
    lines += ["", "90 % intervals holding the truth (in brackets: how many were the whole "
              "search range):", "",
              "| sway | " + " | ".join(WORDS[k] for k in keys) + " | all seven |",
              "|---|" + "---|" * (len(keys) + 1)]
    for sway in (*SWAYS, "both"):
        mine = [r for r in rows if r["sway"] == sway or sway == "both"]
        if not mine:
            continue
        cells = []
        for k in keys:
            whole = sum(r[f"{k}_undetermined"] for r in mine)
            cells.append(f"{100 * np.mean([r[f'{k}_inside'] for r in mine]):.0f} %"
                         + (f" ({whole})" if whole else ""))
        every = np.mean([r[f"{k}_inside"] for r in mine for k in keys])
        lines.append(f"| {sway} | " + " | ".join(cells) + f" | {100 * every:.1f} % |")
    lines += ["", "The sway (median over subjects):", "",
              "| sway | motor noise σ (°) | locked share on the PRTS trial | locked share on a "
              "sinusoid trial |", "|---|---|---|---|"]
    for sway in SWAYS:
        mine = [r for r in rows if r["sway"] == sway]
        if not mine:
            continue
        prts_share = [r["prts_locked_share"] for r in mine if r["prts_locked_share"]]
        lines.append(f"| {sway} | {np.median([r['motor_deg'] for r in mine]):.3f} | "
                     f"{f'{100 * np.median(prts_share):.0f} %' if prts_share else '–'} | "
                     f"{100 * np.median([r['sine_locked_share'] for r in mine]):.0f} % |")
    return "\n".join(lines) + "\n"


def calibrate(subjects: int) -> dict:
    """The joint fit's calibration from subjects of :data:`CALIBRATION_SEED` (both sways):
    per parameter (W of both conditions pooled), the quantiles at :data:`LEVELS` of
    |error| / standard error where the interval is not the whole search range (4
    significant digits), written to ``posture_id/fitting/joint_calibration.json``."""
    from posture_id.fileio import atomic_write_text, json_text
    from posture_id.fitting.joint_conditions import JOINT_CALIBRATION_FILE

    path = JOINT_CALIBRATION_FILE
    rows = run(subjects, CALIBRATION_SEED)
    quantiles = {}
    for name, keys in ((n, (n,)) for n in SHARED):
        quantiles[name] = _quantiles([r[f"{k}_z"] for r in rows for k in keys])
    quantiles["w"] = _quantiles([r[f"w{c}_z"] for r in rows for c in (0, 1)])
    calibration = {"ic": {"made_by": ".venv/bin/python benchmarks/joint_fit.py --calibrate "
                                     f"--subjects {subjects}",
                          "subjects_per_sway": subjects, "seed": CALIBRATION_SEED,
                          "levels": list(LEVELS), "quantiles": quantiles}}
    atomic_write_text(path, json_text(calibration))
    print(f"wrote {path}: at 90 %: " + ", ".join(
        f"{n} ×{q[LEVELS.index(0.9)]:.2f}" for n, q in quantiles.items()))
    return calibration


def _quantiles(z: list) -> list[float]:
    finite = np.array([v for v in z if v is not None], dtype=float)
    return [float(f"{np.quantile(finite, level):.4g}") for level in LEVELS]


def main(argv: list[str] | None = None) -> int:
    global TRIAL_S
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--subjects", type=int, default=24)
    parser.add_argument("--sway", choices=SWAYS, action="append",
                        help="only this sway (default: both)")
    parser.add_argument("--out", type=Path, default=ROOT / "docs/results/joint_fit")
    parser.add_argument("--calibrate", action="store_true",
                        help="print the quantiles of |error| / standard error on subjects of "
                             "another seed")
    parser.add_argument("--trial-s", type=float, default=TRIAL_S,
                        help="each sinusoid trial's length, s (default %(default)g)")
    parser.add_argument("--rows", type=Path, help="write the report of this rows.json "
                                                  "(measured before) instead of fitting")
    args = parser.parse_args(argv)
    from posture_id.fileio import atomic_write_text, json_text

    TRIAL_S = args.trial_s

    if args.calibrate:
        calibrate(args.subjects)
        return 0
    if args.rows is not None:  # the report of rows already measured
        import json

        rows = json.loads(args.rows.read_text(encoding="utf-8"))
    else:
        rows = run(args.subjects, SEED, tuple(args.sway or SWAYS))
    args.out.mkdir(parents=True, exist_ok=True)
    command = (f".venv/bin/python benchmarks/joint_fit.py --subjects {args.subjects}"
               + (f" --trial-s {TRIAL_S:g}" if TRIAL_S != 40.0 else "")
               + "".join(f" --sway {s}" for s in args.sway or ())
               + (f" --out {args.out.relative_to(ROOT)}" if args.out.is_relative_to(ROOT)
                  and args.out != ROOT / "docs/results/joint_fit" else ""))
    atomic_write_text(args.out / "report.md", report(rows, command))
    atomic_write_text(args.out / "rows.json", json_text(rows))
    print(report(rows, command))
    return 0


if __name__ == "__main__":
    sys.exit(main())
