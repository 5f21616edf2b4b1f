"""The IC fit on IC recordings: does it recover the parameters, how fast, and do its
intervals hold the truth?

Run:  .venv/bin/python benchmarks/ic_recovery.py [--per-cell 6] [--out docs/results/ic_recovery]
      .venv/bin/python benchmarks/ic_recovery.py --calibrate [--per-cell 6]

``--calibrate`` fits recordings of other seeds (the same cells) and writes the intervals'
calibration, ``posture_id/models/ic/calibration.json``: per parameter, the quantiles of
|estimate − truth| / standard error at the levels 0.5–0.99 (what an interval at that level
multiplies the standard error by). The report is then made on its own seed: its coverage
is measured on recordings the calibration never saw.

Recordings made by :func:`~posture_id.models.ic.simulation.simulate_ic` with parameters of
:func:`~posture_id.models.ic.subjects.draw_ic_parameters`, fitted by
:func:`~posture_id.fitting.frequency.fit_ic` as ``posture-id fit REC --model ic`` fits them. Cells:
the Winter bodies of 1, 2 and 3 segments (1.75 m, 70 kg) × the 242-state PRTS ×2 and the
80-state PRTS ×6, amplitudes 0.5–2° peak to peak; clean (0.02° sensor noise) and
people-like (motor noise leaving 15–40 % of the COM sway locked, 0.05° sensor noise).
Reports the median and 90th percentile |error| of Kp, Kd, Δ and W, the longest fit, and
the share of 90 % intervals that hold the truth. Writes ``report.md`` and ``rows.json``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SEED = 9191
CALIBRATION_SEED = 4242
PARAMETERS = ("kp", "kd", "delay_s", "w")
#: The calibrated parameters (every one the default fit identifies) and levels.
CALIBRATED = ("kp", "kd", "delay_s", "w", "torque_feedback_gain", "torque_feedback_time_s")
LEVELS = (0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 0.99)


def run(per_cell: int, seed: int = SEED) -> list[dict]:
    import scipy.optimize  # noqa: F401 - loaded before the first fit is timed
    import scipy.stats  # noqa: F401

    from posture_id import load_body
    from posture_id.fitting.frequency import fit_ic
    from posture_id.models.ic import IcPlant
    from posture_id.models.ic.subjects import draw_ic_parameters, ic_recording
    from posture_id.simulation.stimulus import prts
    from posture_id.trials import prepare_trial

    rows = []
    k = 0
    for segments in (1, 2, 3):
        body = load_body(ROOT / "urdf" / f"winter_1.75m_70kg_{segments}seg.urdf")
        plant = IcPlant.of(body)
        for states, cycles in ((242, 2), (80, 6)):
            for sway in ("clean", "people-like"):
                for _ in range(per_cell):
                    rng = np.random.default_rng([seed, k])
                    people = sway == "people-like"
                    while True:  # a subject whose noise topples them is drawn again
                        truth = draw_ic_parameters(rng, plant)
                        stimulus = prts(float(rng.uniform(0.5, 2.0)), cycles, states)
                        share = float(rng.uniform(0.15, 0.4)) if people else None
                        recording, _ = ic_recording(body, truth, stimulus, share, seed + k,
                                                    0.05 if people else 0.02)
                        if np.all(np.isfinite(recording.theta)):
                            break
                    started = time.perf_counter()
                    fit = fit_ic(prepare_trial(recording, stimulus), body)
                    seconds = time.perf_counter() - started
                    row = {"k": k, "segments": segments, "states": states, "sway": sway,
                           "seconds": seconds, "level": fit.trust_level}
                    for name in CALIBRATED:
                        se = fit.standard_errors[name]
                        row[f"{name}_z"] = (abs(getattr(fit.parameters, name)
                                                - getattr(truth, name)) / se if se > 0
                                            else float("inf"))
                    for name in PARAMETERS:
                        true, got = getattr(truth, name), getattr(fit.parameters, name)
                        low, high = fit.intervals[name]
                        row[f"{name}_error"] = abs(got - true) / abs(true)
                        row[f"{name}_inside"] = bool(low <= true <= high)
                    rows.append(row)
                    print(f"[{k + 1}] {segments}-segment PRTS {states} {sway}: Kp error "
                          f"{100 * row['kp_error']:.1f} % ({seconds:.2f} s)", file=sys.stderr,
                          flush=True)
                    k += 1
    return rows


def report(rows: list[dict], command: str) -> str:
    lines = ["# The IC fit on IC recordings", "", f"Made by `{command}` ({len(rows)} "
             "recordings; the module doc of `benchmarks/ic_recovery.py` says how).", "",
             "| sway | recordings | median |error| Kp, Kd, Δ, W | 90th percentile | "
             "90 % intervals holding the truth (Kp, Kd, Δ, W) | longest fit |",
             "|---|---|---|---|---|---|"]
    for sway in ("clean", "people-like"):
        mine = [r for r in rows if r["sway"] == sway]
        med = ", ".join(f"{100 * np.median([r[f'{p}_error'] for r in mine]):.1f} %"
                        for p in PARAMETERS)
        p90 = ", ".join(f"{100 * np.percentile([r[f'{p}_error'] for r in mine], 90):.1f} %"
                        for p in PARAMETERS)
        cover = ", ".join(f"{100 * np.mean([r[f'{p}_inside'] for r in mine]):.0f} %"
                          for p in PARAMETERS)
        longest = max(r["seconds"] for r in mine)
        lines.append(f"| {sway} | {len(mine)} | {med} | {p90} | {cover} | {longest:.2f} s |")
    lines += ["", "Per body and stimulus (median |error| of Kp, clean / people-like):", "",
              "| segments | PRTS | clean | people-like |", "|---|---|---|---|"]
    for segments in (1, 2, 3):
        for states in (242, 80):
            cells = [[r["kp_error"] for r in rows if r["segments"] == segments
                      and r["states"] == states and r["sway"] == s]
                     for s in ("clean", "people-like")]
            lines.append(f"| {segments} | {states} | {100 * np.median(cells[0]):.1f} % | "
                         f"{100 * np.median(cells[1]):.1f} % |")
    return "\n".join(lines) + "\n"


def calibrate(per_cell: int) -> int:
    """posture_id/models/ic/calibration.json from recordings of :data:`CALIBRATION_SEED`."""
    from posture_id.fileio import atomic_write_text, json_text
    from posture_id.models.ic.model import CALIBRATION

    rows = run(per_cell, CALIBRATION_SEED)
    quantiles = {}
    for name in CALIBRATED:
        z = np.array([r[f"{name}_z"] for r in rows])
        q = [float(np.quantile(z, level)) for level in LEVELS]
        # a parameter whose standard error is no guide (an error a thousand times it, or a
        # standard error of 0 on a bound) is left uncalibrated: its interval is the
        # normal one, and its width says what the recording leaves of it
        if all(np.isfinite(q)) and q[-1] < 1e3:
            quantiles[name] = q
    atomic_write_text(CALIBRATION, json_text({
        "about": "IC intervals: a level's interval is the estimate ± quantile × its "
                 "Gauss-Newton standard error (posture_id/fitting/frequency.py)",
        "made_by": ".venv/bin/python benchmarks/ic_recovery.py --calibrate "
                   f"--per-cell {per_cell}",
        "recordings": len(rows), "seed": CALIBRATION_SEED, "levels": list(LEVELS),
        "quantiles": quantiles}))
    print(f"wrote {CALIBRATION}: " + ", ".join(
        f"{n} ×{q[LEVELS.index(0.9)]:.2f}" for n, q in quantiles.items()) + " at 90 %; "
        f"uncalibrated: {', '.join(sorted(set(CALIBRATED) - set(quantiles))) or 'none'}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--per-cell", type=int, default=6)
    parser.add_argument("--out", type=Path, default=ROOT / "docs/results/ic_recovery")
    parser.add_argument("--calibrate", action="store_true",
                        help="write posture_id/models/ic/calibration.json from recordings of "
                             "another seed")
    args = parser.parse_args(argv)
    from posture_id.fileio import atomic_write_text, json_text

    if args.calibrate:
        return calibrate(args.per_cell)
    rows = run(args.per_cell)
    args.out.mkdir(parents=True, exist_ok=True)
    command = ".venv/bin/python benchmarks/ic_recovery.py"
    atomic_write_text(args.out / "report.md", report(rows, command))
    atomic_write_text(args.out / "rows.json", json_text(rows))
    print(report(rows, command))
    return 0


if __name__ == "__main__":
    sys.exit(main())
