"""How long a study manifest of 264 force-plate trials takes to give every trial's FRF.

Run:  .venv/bin/python benchmarks/study_speed.py --out docs/results/study_speed [--subjects 44]

The study: ``posture_id.studies.force_plate_study.make_study`` with 44 subjects (eyes open
and closed, sinusoids at 0.1, 0.2 and 0.4 Hz: 264 trials of 140 s at 100 Hz, each a
posturography export: tab-separated, a title line, ms, the COP in mm). Timed: the command
line, ``posture-id study manifest.csv --model none`` with the force plate's columns, on
this machine's cores (every trial read, its stimulus found, its COP turned into the
body-COM sway, its FRF; the paired test between the conditions), from a fresh results
folder; then again, resumed (nothing to do). Writes ``report.md`` and ``timing.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

FLAGS = ["--time-column", "Time", "--time-units", "ms", "--tilt-column", "Platform",
         "--cop-column", "COP AP", "--model", "none"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--subjects", type=int, default=44)
    args = parser.parse_args()
    from posture_id.studies.force_plate_study import make_study

    with tempfile.TemporaryDirectory() as folder:
        started = time.perf_counter()
        manifest = make_study(Path(folder) / "study", args.subjects)
        made = time.perf_counter() - started
        trials = len(manifest.read_text().splitlines()) - 1
        command = [str(Path(sys.executable).with_name("posture-id")), "study", str(manifest),
                   "--out", str(Path(folder) / "out"), *FLAGS]
        timings = []
        for _ in range(2):
            started = time.perf_counter()
            done = subprocess.run(command, capture_output=True, text=True)
            timings.append(time.perf_counter() - started)
            if done.returncode != 0:
                raise SystemExit(done.stderr)
        summary = done.stdout.strip()
    numbers = {"trials": trials, "cores": os.cpu_count(), "made_s": made,
               "first_run_s": timings[0], "resumed_s": timings[1], "summary": summary}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "timing.json").write_text(json.dumps(numbers, indent=2) + "\n")
    lines = ["# A study manifest of force-plate trials: every trial's FRF", "",
             "Made by `.venv/bin/python benchmarks/study_speed.py --out "
             f"docs/results/study_speed --subjects {args.subjects}`.", "",
             f"{trials} force-plate trials (posturography exports of 140 s at 100 Hz: "
             "tab-separated, a title line, ms, the COP in mm; sinusoids between level "
             f"stretches), {os.cpu_count()} cores:", "",
             "| | seconds |", "|---|---|",
             f"| the study written (simulated) | {made:.1f} |",
             f"| `posture-id study ... --model none`: every FRF and the paired test | "
             f"{timings[0]:.1f} |",
             f"| the same again, resumed (every FRF already made) | {timings[1]:.1f} |", "",
             "What it said:", "", "```", summary, "```", ""]
    (args.out / "report.md").write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
