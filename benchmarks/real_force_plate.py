"""A lab's real force-plate trials, read as the lab wrote them: every trial's FRF, the study
through its manifest (heights from the lab's subject table, masses from the plate's load
cells), and each subject's eyes-closed against eyes-open gain.

Run:  .venv/bin/python benchmarks/real_force_plate.py --data DIR [--out DIR] [--model ic]

DIR holds the trials (``sNNN-C-F.brute``: C ``yo`` eyes open, ``yf`` eyes closed; F the
nominal stimulus ``f1``, ``f2``, ``f4``, 0.1, 0.2 and 0.4 Hz, which a file's name may
misstate) and ``subjects.csv`` (``;``-separated, ``nom`` and ``taille`` in cm). The trials
are given to the command line exactly as written, with the flags the docs give (no
``--period-s``, no cropping): ``posture-id frf`` for each, then ``posture-id study`` over a
manifest of them all (its rows a height and no mass: ``--load-columns`` weighs each
subject). Written (``--out``, default ``docs/results/real_force_plate``): ``report.md`` and
``rows.json``, derived numbers only (frequencies, gains, phases, coherences, masses,
parameters): none of the lab's samples.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import io
import json
import re
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: The lab's columns, as the docs spell them.
COLUMNS = ["--time-column", "temps (en ms)", "--time-units", "ms", "--tilt-column",
           "Angle(degre)", "--cop-column", "Barycentre y (mm)", "--cop-units", "mm"]
LOAD = ["--load-columns", *(f"Capteur (Kg)({corner})" for corner in
                            ("Nord Ouest", "Nord Est", "Sud Ouest", "Sud Est"))]
NOMINAL_HZ = {"f1": 0.1, "f2": 0.2, "f4": 0.4}
CONDITIONS = {"yo": "eyes_open", "yf": "eyes_closed"}


def _run(argv: list[str]) -> tuple[int, str]:
    """posture-id's exit status and what it said (stderr and stdout)."""
    from posture_id.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(argv)
    return status, err.getvalue() + out.getvalue()


def _trials(data: Path) -> list[dict]:
    """Every trial's subject, condition, nominal frequency and file, with its subject's
    height (m)."""
    with open(data / "subjects.csv", encoding="utf-8") as fh:
        heights = {r["nom"]: int(r["taille"]) / 100 for r in csv.DictReader(fh, delimiter=";")}
    trials = []
    for path in sorted(data.glob("*.brute")):
        subject, condition, nominal = path.stem.split("-")
        trials.append({"trial": path.stem, "subject": subject,
                       "condition": CONDITIONS[condition], "nominal_hz": NOMINAL_HZ[nominal],
                       "file": path, "height_m": heights[subject]})
    return trials


def _cycle_difference(path: Path) -> float | None:
    """The largest difference between one analysed cycle of the tilt and the next, % of
    its peak: the finder's own measure (the difference averaged over a twentieth of a
    cycle, :mod:`posture_id.simulation.periodic`), the platform's irregularity."""
    import numpy as np

    from posture_id.errors import RecordingError
    from posture_id.simulation.periodic import find_periodic
    from posture_id.text_table import read_text_table

    table = read_text_table(path, RecordingError, "trial")
    tilt = np.radians(table.column(COLUMNS[5]))
    found = find_periodic(table.column(COLUMNS[1]) / 1000.0, tilt)
    if found is None:
        return None
    p = found.period_samples
    x = tilt[found.start: found.start + found.cycles * p]
    width = max(p // 20, 1)
    smoothed = np.abs(np.convolve(x[p:] - x[:-p], np.ones(width) / width, mode="valid"))
    return float(100 * smoothed.max() / np.abs(x - np.median(tilt[:found.start])).max())


def _channel(data: dict) -> dict:
    return data["channels"].get("body COM") or next(iter(data["channels"].values()))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True, help="the trials' folder")
    parser.add_argument("--out", type=Path, default=ROOT / "docs/results/real_force_plate")
    parser.add_argument("--model", choices=("ic", "none"), default="ic",
                        help="the study's joint fit (default ic, w per condition)")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    from posture_id.fileio import atomic_write_text, json_text

    trials = _trials(args.data.resolve())
    started = time.perf_counter()
    rows = []
    with tempfile.TemporaryDirectory(prefix="real-plate-") as tmp:
        folder = Path(tmp)
        for t in trials:  # each trial alone: frf weighing the subject on the plate
            status, said = _run(["frf", str(t["file"]), *COLUMNS, "--height-m",
                                 f"{t['height_m']:g}", *LOAD,
                                 "--out", str(folder / f"{t['trial']}.json")])
            row = {k: t[k] for k in ("trial", "subject", "condition", "nominal_hz")}
            row["status"] = status
            if status == 0:
                data = json.loads((folder / f"{t['trial']}.json").read_text())
                channel = _channel(data)
                mass = re.search(r"mass is ([0-9.]+) kg", said)
                cycles = re.search(r"(\d+) steady cycle", said)
                row.update({"driven_hz": data["frequencies_hz"][0],
                            "gain": channel["gain"][0], "phase_deg": channel["phase_deg"][0],
                            "coherence": channel["coherence"][0],
                            "locked_share": channel.get("locked_share"),
                            "mass_kg": float(mass[1]) if mass else None,
                            "cycles": int(cycles[1]) if cycles else None,
                            "cycle_difference_pct": _cycle_difference(t["file"])})
            else:
                row["refusal"] = said.strip().splitlines()[-1][:200]
            rows.append(row)
            print(f"{t['trial']}: {row.get('driven_hz', row.get('refusal'))}", file=sys.stderr)
        manifest = folder / "manifest.csv"
        manifest.write_text("subject,condition,file,height_m,mass_kg\n" + "".join(
            f"{t['subject']},{t['condition']},{t['file']},{t['height_m']:g},\n"
            for t in trials))
        status, said = _run(["study", str(manifest), "--out", str(folder / "study"),
                             "--workers", str(args.workers), "--model", args.model, *COLUMNS,
                             *LOAD])
        if not (folder / "study" / "study.json").is_file():
            raise SystemExit(f"the study gave no answer: {said.strip()[-500:]}")
        study = json.loads((folder / "study" / "study.json").read_text())
        masses = dict(re.findall(r"subject (\w+)'s mass is ([0-9.]+) kg", said))
    seconds = time.perf_counter() - started
    ratios = []
    for subject in sorted({r["subject"] for r in rows}):
        for f in sorted({r["driven_hz"] for r in rows if "driven_hz" in r}):
            gain: dict[str, list[float]] = {}
            for r in rows:
                if r["subject"] == subject and r.get("driven_hz") is not None \
                        and abs(r["driven_hz"] - f) < 1e-3:
                    gain.setdefault(r["condition"], []).append(r["gain"])
            if len(gain) == 2:  # a condition's trials at one frequency: their mean gain
                ratios.append({"subject": subject, "frequency_hz": f,
                               "trials": {c: len(v) for c, v in gain.items()},
                               "closed_over_open": (sum(gain["eyes_closed"])
                                                    / len(gain["eyes_closed"]))
                               / (sum(gain["eyes_open"]) / len(gain["eyes_open"]))})
    result = {"trials": rows, "ratios": ratios, "study_status": status,
              "study_masses_kg": {k: float(v) for k, v in masses.items()},
              "study_summary": study.get("summary"), "study_doubtful": study.get("doubtful"),
              "seconds": round(seconds, 1)}
    args.out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(args.out / "rows.json", json_text(result))
    atomic_write_text(args.out / "report.md", _report(result, args))
    print(f"wrote {args.out / 'report.md'}", file=sys.stderr)
    return 0


def _report(result: dict, args: argparse.Namespace) -> str:
    rows = result["trials"]
    read = [r for r in rows if r["status"] == 0]
    misnamed = [r["trial"] for r in read if abs(r["driven_hz"] - r["nominal_hz"]) > 1e-3]
    lines = ["# A lab's real force-plate trials, read as written", "",
             f"Made by `.venv/bin/python benchmarks/real_force_plate.py --data DIR --model "
             f"{args.model}` (DIR: the public study's development trials and its subject "
             f"table; {result['seconds']:.0f} s here). Derived numbers only.", "",
             f"**{len(read)} of {len(rows)} trials** give an FRF with the docs' flags (no "
             "`--period-s`, no cropping), each at the frequency its tilt drove"
             + (f"; {', '.join(misnamed)} drove another than its name says" if misnamed
                else "") + ".", "",
             "Cycle difference: the largest difference between one analysed cycle of the "
             "tilt and the next, % of its peak (the platform's own irregularity; the finder "
             "analyses cycles within 2 %).", "",
             "| trial | subject | condition | nominal Hz | driven Hz | cycles | cycle "
             "difference | mass kg | gain | phase ° | coherence | locked |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r["status"] != 0:
            lines.append(f"| {r['trial']} | {r['subject']} | {r['condition']} | "
                         f"{r['nominal_hz']:g} | refused: {r['refusal']} ||||||||")
            continue
        locked = "" if r["locked_share"] is None else f"{100 * r['locked_share']:.0f} %"
        lines.append(f"| {r['trial']} | {r['subject']} | {r['condition']} | "
                     f"{r['nominal_hz']:g} | {r['driven_hz']:.4g} | {r['cycles']} | "
                     f"{r['cycle_difference_pct']:.2f} % | {r['mass_kg']:.4g} | "
                     f"{r['gain']:.3g} | {r['phase_deg']:.0f} | "
                     f"{r['coherence']:.2f} | {locked} |")
    lines += ["", "## Eyes closed against eyes open", "",
              "The body-COM gain with the eyes closed over that with the eyes open, per "
              "subject at each frequency both conditions drove (a condition's trials at "
              "one frequency: their mean gain):", "",
              "| subject | Hz | trials closed, open | closed / open |", "|---|---|---|---|"]
    lines += [f"| {q['subject']} | {q['frequency_hz']:.3g} | {q['trials']['eyes_closed']}, "
              f"{q['trials']['eyes_open']} | {q['closed_over_open']:.2f} |"
              for q in result["ratios"]]
    masses = ", ".join(f"{k} {v:.4g} kg" for k, v in result["study_masses_kg"].items())
    lines += ["", "## The study through its manifest", "",
              f"`posture-id study` over the {len(rows)} trials (heights from the subject "
              f"table, no masses: the plate weighs each subject, {masses}), "
              f"`--model {args.model}`: exit status {result['study_status']}"
              + (f"; the fit of {', '.join(result['study_doubtful'])} is doubtful"
                 if result["study_doubtful"] else "") + ".", ""]
    summary = result["study_summary"] or []
    if summary and args.model == "ic":
        lines += ["| subject | w [eyes open] | w [eyes closed] | trust |", "|---|---|---|---|"]
        lines += [f"| {s['subject']} | {s.get('w [eyes_open]')} | {s.get('w [eyes_closed]')} "
                  f"| {s.get('trust', '')} |" for s in summary]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    sys.exit(main())
