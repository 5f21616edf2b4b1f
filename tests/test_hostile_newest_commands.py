"""Hostile input for the newest commands (``study``, ``fit TRIAL TRIAL ...``, the
force-plate and lab-text flags, the periodic-stimulus finder, ``norm compare --paired``,
``robot check``, the flags given twice): each case is declared with its good answer before
it runs, a one-line refusal naming the file, field and problem (*clear*) or an answer with
the notice that says what was assumed, ignored or dropped (*handled*), and must get it
(:mod:`hostile_harness` sorts the outcome).

Run as a script it writes every case's outcome, and with ``--before ROWS`` (the same
script run on an earlier tree) the table of outcomes before and after::

    .venv/bin/python tests/test_hostile_newest_commands.py --out rows.json [--before old.json]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hostile_harness import Case, run_case

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ("tip_urdf", "specialist")
#: The columns of the force-plate exports below (a posturography system's: ms, mm, N).
PLATE = ("--time-column", "Time", "--tilt-column", "Platform", "--cop-column", "COP AP")
#: The same columns named without the header's units (a file whose header has none).
BARE = ("--time-column", "Time", "--time-units", "ms", "--tilt-column", "Platform",
        "--cop-column", "COP AP")
#: A lab's text export of a segment-angle trial (Time in s, degrees).
LAB = ("--time-column", "Time", "--tilt-column", "Platform", "--angle-columns", "COM")


# --------------------------------------------------------------------------- material
def _plate_table(path: Path) -> tuple[str, list[str], np.ndarray]:
    """(title, header, values (S, 4)) of a force-plate export written by the study maker."""
    lines = path.read_text(encoding="utf-8").splitlines()
    return lines[0], lines[1].split("\t"), np.array([[float(v) for v in line.split("\t")]
                                                     for line in lines[2:]])


def _plate_text(title: str | None, header: list[str], values: np.ndarray) -> str:
    rows = ["\t".join(f"{v:.10g}" for v in row) for row in values]
    return "\n".join(([title] if title else []) + ["\t".join(header)] + rows) + "\n"


def _moving(tilt_deg: np.ndarray) -> tuple[int, int]:
    moving = np.flatnonzero(np.abs(tilt_deg) > 1e-3)
    return int(moving[0]), int(moving[-1])


def _quiet(argv: list[str]) -> None:
    """Run a command to make material; its output is not the case's."""
    from posture_id.cli import main

    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        status = main(argv)
    if status != 0:
        raise RuntimeError(f"making the material failed: {argv}")


def make_material(root: Path) -> dict[str, str]:
    """The inputs the cases use, in ``root``: a study of two subjects (force-plate trials,
    eyes open and closed, 0.2 Hz) with its results folder, variants of one of its trials
    (units left out, a negative force, a constant COP, a tilt drop-out, the platform
    resting at another level after the sine, another rate, other encodings) and a lab's
    COM-angle export of it; returns ``{name: path}``."""
    from posture_id.studies.force_plate_study import make_study

    root.mkdir(parents=True, exist_ok=True)
    study = root / "study"
    if not (study / "manifest.csv").exists():
        make_study(study, subjects=2, frequencies_hz=(0.2,))
    paths = {"study": str(study), "tip_urdf": str(ROOT / "urdf" / "tip_default.urdf"),
             "specialist": str(ROOT / "posture_id" / "learning" / "models" / "tip_default")}
    for line in (study / "manifest.csv").read_text().splitlines()[1:3]:
        subject, condition, file, height, mass = line.split(",")
        paths[f"trial_{condition}"] = str(study / file)
    paths["height"], paths["mass"] = height, mass
    urdf = root / "S01.urdf"
    if not urdf.exists():
        _quiet(["body", "--height-m", height, "--mass-kg", mass, "--segments", "1",
                "--out", str(urdf)])
    paths["urdf"] = str(urdf)
    title, header, values = _plate_table(Path(paths["trial_eyes_open"]))
    first, last = _moving(values[:, 1])
    bare = [h.split(" [")[0] for h in header]
    variants = {
        "plate": (title, header, values),
        "plate_bare": (title, bare, values),
        "plate_in_m": (title, bare, values * [1, 1, 1e-3, 1]),
        "plate_negative_force": (title, header, values * [1, 1, 1, -1]),
        "plate_constant_cop": (title, header, np.column_stack(
            [values[:, :2], np.full(len(values), 12.5), values[:, 3]])),
    }
    dropout = values.copy()  # the tilt sensor holds its value for 1.5 s mid-oscillation
    middle = (first + last) // 2
    dropout[middle: middle + 150, 1] = dropout[middle, 1]
    variants["plate_dropout"] = (title, header, dropout)
    step_off = values.copy()  # the subject steps off the plate for a second
    step_off[middle: middle + 100, 3] = 40.0
    variants["plate_step_off"] = (title, header, step_off)
    flipped = values.copy()  # the sway the other way: no body of one controller does both
    flipped[:, 2] = 2 * values[:, 2].mean() - values[:, 2]
    variants["plate_flipped"] = (title, header, flipped)
    # level at 0.001° before the sine and at -0.05° after it, for longer than it moved, as
    # a real plate rests
    step = values[1, 0] - values[0, 0]
    tail = np.tile(values[:first], (3, 1))
    tail[:, 0] = values[-1, 0] + step * np.arange(1, len(tail) + 1)
    resting = np.concatenate([values, tail])
    resting[:first, 1] = 0.001
    resting[last + 1:, 1] = -0.05
    variants["plate_other_rest"] = (title, header, resting)
    cells = values[:, 3:4] / 9.81 * [[0.3, 0.2, 0.28, 0.22]]  # four load cells, in kg
    variants["plate_cells"] = (title, header + [f"Cell {c} (Kg)" for c in ("NW", "NE", "SW",
                                                                        "SE")],
                               np.column_stack([values, cells]))
    for name, (t, h, v) in variants.items():
        path = root / f"{name}.txt"
        path.write_text(_plate_text(t, h, v), encoding="utf-8")
        paths[name] = str(path)
    text = Path(paths["plate"]).read_text(encoding="utf-8")
    for name, data in {"plate_wide_le": text.encode("utf-16-le"),
                       "plate_wide_be": text.encode("utf-16-be"),
                       "plate_latin": ("Messung Müller, Ärztin Fußplatte\n"
                                        + text.split("\n", 1)[1]).encode("cp1252")}.items():
        (root / f"{name}.txt").write_bytes(data)
        paths[name] = str(root / f"{name}.txt")
    # a lab's COM-angle export of the same trial at 50 Hz (s, degrees), and its encodings
    from posture_id.bodies.body import load_body
    from posture_id.force_plate.reading import ForcePlateColumns, read_force_plate
    from posture_id.recording import TimeUnit

    recording = read_force_plate(paths["plate"], ForcePlateColumns(
        cop="COP AP", time="Time", tilt="Platform", time_unit=TimeUnit.MILLISECONDS),
        load_body(urdf))
    every = slice(None, None, 2)
    lab = "Time,Platform,COM\n" + "".join(
        f"{t:.3f},{np.degrees(a):.5f},{np.degrees(c):.5f}\n" for t, a, c in
        zip(recording.time[every], recording.tilt[every], recording.theta[every, 0],
            strict=True))
    (root / "lab50.csv").write_text(lab, encoding="utf-8")
    tilt = "time_s,tilt_deg\n" + "".join(f"{t:.3f},{np.degrees(a):.5f}\n" for t, a in zip(
        recording.time[every], recording.tilt[every], strict=True))
    for name, data in {"tilt_latin": ("Plattform Müller\n" + tilt).encode("cp1252"),
                       "tilt_wide": tilt.encode("utf-16-le")}.items():
        (root / f"{name}.csv").write_bytes(data)
        paths[name] = str(root / f"{name}.csv")
    # a headset's clock: the stamps jitter by up to 1 ms (a twentieth of the interval)
    stamps = recording.time[every] + np.random.default_rng(9).uniform(-1e-3, 1e-3, len(
        recording.time[every]))
    stamps[0] = 0.0
    jittered = "Time,Platform,COM\n" + "".join(
        f"{t:.4f},{np.degrees(a):.5f},{np.degrees(c):.5f}\n" for t, a, c in
        zip(stamps, recording.tilt[every], recording.theta[every, 0], strict=True))
    (root / "lab_jitter.csv").write_text(jittered, encoding="utf-8")
    lines = jittered.splitlines(keepends=True)
    (root / "lab_gap.csv").write_text("".join(lines[:2001] + lines[2003:]), encoding="utf-8")
    paths["lab_jitter"], paths["lab_gap"] = str(root / "lab_jitter.csv"), str(
        root / "lab_gap.csv")
    com_only = "Time,COM\n" + "".join(  # a lab's COM-only export: no tilt column
        f"{line.split(',')[0]},{line.split(',')[2]}\n" for line in lab.splitlines()[1:])
    (root / "com_only.csv").write_text(com_only, encoding="utf-8")
    paths["com_only"] = str(root / "com_only.csv")
    standard = "time_s,tilt_deg,body_deg\n" + lab.split("\n", 1)[1]  # the project's columns
    (root / "standard_wide.csv").write_bytes(standard.encode("utf-16-le"))
    paths["standard_wide"] = str(root / "standard_wide.csv")
    paths["lab50"] = str(root / "lab50.csv")
    for name, data in {"lab_wide_le": lab.encode("utf-16-le"),
                       "lab_latin": ("Labor Müller;Ärztin\n" + lab).encode("cp1252")}.items():
        (root / f"{name}.csv").write_bytes(data)
        paths[name] = str(root / f"{name}.csv")
    # the study run once: its results folder (a study's own)
    out = root / "study_out"
    if not (out / "study.json").exists():
        _quiet(["study", str(study / "manifest.csv"), "--out", str(out), "--workers", "1",
                *PLATE])
    paths["study_out"] = str(out)
    frf = sorted((out / "frf").glob("*.json"))
    for condition in ("open", "closed"):
        for k, p in enumerate([p for p in frf if condition in p.name], 1):
            paths[f"frf_{condition}_{k}"] = str(p)
    lines = (study / "manifest.csv").read_text().splitlines()
    manifest = root / "manifest_in_s.csv"  # the study's rows, its files under s/
    manifest.write_text("\n".join([lines[0]] + [
        ",".join(f"s/{c}" if k == 2 else c for k, c in enumerate(line.split(",")))
        for line in lines[1:]]) + "\n")
    paths["manifest"] = str(manifest)
    return paths


# --------------------------------------------------------------------------- the cases
def _manifest(edit=lambda rows: rows, header=lambda h: h, encoding: str | None = None):
    """A manifest made from the study's (:func:`make_material`'s ``manifest``): its rows
    (a list of lists of cells) edited, in ``encoding`` (None: UTF-8 text)."""
    def make(text: str):
        lines = text.splitlines()
        rows = edit([line.split(",") for line in lines[1:]])
        out = "\n".join([header(lines[0])] + [",".join(r) for r in rows]) + "\n"
        return out if encoding is None else out.encode(encoding)

    if encoding is None:
        return ("text", "manifest", make)
    return ("bytes", "manifest", make)


def _replace_file(row: int, name: str):
    def edit(rows):
        rows[row][2] = name
        return rows

    return edit


STUDY = ("study", "manifest.csv", "--out", "o", "--workers", "1", *PLATE)
#: The same with FRFs only (no joint fits): for what the fits do not change.
FRFS = (*STUDY, "--model", "none")
#: The study's trials (under s/) and its manifest.
TRIALS = {"s": "@study", "manifest.csv": _manifest()}
#: The study's trial files, as make_study names them.
STUDY_FILES = tuple(f"s/S0{k}_{c}_0.2Hz.txt" for k in (1, 2)
                    for c in ("eyes_open", "eyes_closed"))
CELLS = ("--load-columns", "Cell NW (Kg)", "Cell NE (Kg)", "Cell SW (Kg)", "Cell SE (Kg)")
#: The study's trials with the plate's load cells, and a manifest without masses.
WEIGHED = {"s": "@study", **{f: "@plate_cells" for f in STUDY_FILES},
           "manifest.csv": _manifest(lambda rows: [[*r[:4], ""] for r in rows])}



def _study_cases() -> list[Case]:
    three = _manifest(lambda rows: rows[:3])
    return [
        Case("--out holds the user's summary.csv", "study", STUDY,
             ("summary.csv", "did not write"), {**TRIALS, "o/summary.csv": "my,own\n1,2\n"}),
        Case("--out holds the user's trials.csv", "study", STUDY,
             ("trials.csv", "did not write"), {**TRIALS, "o/trials.csv": "trial\nmine\n"}),
        Case("--out holds the user's study.json", "study", STUDY,
             ("study.json", "did not write"), {**TRIALS, "o/study.json": '{"mine": 1}'}),
        Case("--out holds the user's paired result", "study", STUDY,
             ("eyes_open_vs_eyes_closed.json", "did not write"),
             {**TRIALS, "o/paired/eyes_open_vs_eyes_closed.json": '{"mine": 1}'}),
        Case("--out holds the user's fit of a subject", "study", STUDY,
             ("S01.json", "did not write"), {**TRIALS, "o/fits/S01.json": '{"mine": 1}'}),
        Case("--out holds files that are not a study's", "study", STUDY,
             ("o", "notes.txt", "not a study's"), {**TRIALS, "o/notes.txt": "my notes\n"}),
        Case("--out is a study's own: what it replaces is said", "study", FRFS,
             ("replaces",), {**TRIALS, "o": "@study_out"}, handled=True, kept=("o",)),
        Case("a resumed study whose manifest lost a row", "study", STUDY,
             ("S02", "fitted again"), {**TRIALS, "o": "@study_out", "manifest.csv": three},
             handled=True, kept=("o",)),
        Case("a resumed study whose manifest lost a row names the FRF left out", "study",
             STUDY, ("no longer names",), {**TRIALS, "o": "@study_out", "manifest.csv": three},
             handled=True, kept=("o",)),
        Case("a subject with one of the conditions", "study", FRFS,
             ("S02", "no eyes_closed trial"), {**TRIALS, "manifest.csv": three},
             handled=True, kept=("o",)),
        Case("a row with both a body and a height", "study", FRFS,
             ("line 2", "body", "height_m and mass_kg", "ignored"),
             {**TRIALS, "b.urdf": "@urdf", "manifest.csv": _manifest(
                 lambda rows: [r + (["b.urdf"] if k < 2 else [""]) for k, r in enumerate(rows)],
                 lambda h: h + ",body")}, handled=True, kept=("o",)),
        Case("conditions that differ only in case", "study", STUDY,
             ("manifest.csv", "line 5", "'Eyes_Closed'", "'eyes_closed'", "only in case"),
             {**TRIALS, "manifest.csv": _manifest(
                 lambda rows: rows[:3] + [[rows[3][0], "Eyes_Closed", *rows[3][2:]]])}),
        Case("subjects that differ only in case", "study", STUDY,
             ("manifest.csv", "line 4", "'s02'", "'S02'", "only in case"),
             {**TRIALS, "manifest.csv": _manifest(
                 lambda rows: rows[:2] + [["s02", *rows[2][1:]], rows[3]])}),
        Case("a study whose fits are doubtful exits 1 and says so", "study", STUDY,
             ("doubtful", "S01"), {**TRIALS, "s/flipped.txt": "@plate_flipped",
                                   "manifest.csv": _manifest(lambda rows: [
                                       rows[0], [rows[0][0], rows[0][1], "s/flipped.txt",
                                                 *rows[0][3:]], *rows[2:]])},
             handled=True, kept=("o",)),
        Case("a trial whose platform rests at another level after the sine", "study", FRFS,
             ("late.txt", "sinusoid"), {**TRIALS, "s/late.txt": "@plate_other_rest",
                                        "manifest.csv": _manifest(_replace_file(0,
                                                                                "s/late.txt"))},
             handled=True, kept=("o",)),
        Case("a trial with a constant COP", "study", FRFS,
             ("flat.txt", "constant"), {**TRIALS, "s/flat.txt": "@plate_constant_cop",
                                        "manifest.csv": _manifest(_replace_file(0,
                                                                                "s/flat.txt"))},
             handled=True, kept=("o",)),
        Case("a manifest in Windows Latin-1", "study", FRFS, ("manifest.csv", "cp1252"),
             {**TRIALS, "manifest.csv": _manifest(
                 lambda rows: [[r[0], r[1].replace("eyes", "Augen_für"), *r[2:]]
                               for r in rows], encoding="cp1252")},
             handled=True, kept=("o",)),
        Case("a manifest in UTF-16 without a byte-order mark", "study", FRFS,
             ("manifest.csv", "UTF-16"), {**TRIALS, "manifest.csv": _manifest(
                 encoding="utf-16-le")}, handled=True, kept=("o",)),
        Case("--segments with a force plate's trials", "study", (*STUDY, "--segments", "3"),
             ("--segments 3", "one segment"), TRIALS),
        Case("--segments with every row a URDF", "study", (*STUDY, "--segments", "2"),
             ("--segments 2", "URDF"), {**TRIALS, "b.urdf": "@urdf", "manifest.csv": _manifest(
                 lambda rows: [[*r[:3], "", "", "b.urdf"] for r in rows],
                 lambda h: h + ",body")}),
        Case("--workers with --scheduler", "study",
             ("study", "manifest.csv", "--out", "o", "--workers", "2", "--scheduler",
              "tcp://127.0.0.1:9", *PLATE), ("--workers", "--scheduler"), TRIALS),
        Case("--per-condition not the model's", "study", (*STUDY, "--per-condition", "gain"),
             ("'gain'", "IC", "per-condition"), TRIALS),
        Case("--per-condition w with --model dec", "study",
             (*STUDY, "--model", "dec", "--per-condition", "w"), ("'w'", "DEC"), TRIALS),
        Case("a manifest column twice in the header", "study", STUDY,
             ("manifest.csv", "'file'", "twice"), {**TRIALS, "manifest.csv": _manifest(
                 lambda rows: [[*r, r[2]] for r in rows], lambda h: h + ",file")}),
        Case("a manifest row with more fields than the header", "study", STUDY,
             ("manifest.csv", "line 3", "6 fields", "5"), {**TRIALS, "manifest.csv": _manifest(
                 lambda rows: [rows[0], [*rows[1], "retest"], *rows[2:]])}),
        Case("a manifest without masses, weighed by the plate", "study", (*FRFS, *CELLS),
             ("subject S01's mass is", "Cell NW (Kg)"), WEIGHED, handled=True, kept=("o",)),
        Case("a manifest without masses and no load columns", "study", FRFS,
             ("manifest.csv", "line 2", "mass_kg", "--load-columns"), WEIGHED),
        Case("--load-columns where every row gives its mass", "study", (*FRFS, *CELLS),
             ("--load-columns", "every row"), TRIALS),
        Case("--cop-units m on a COP in mm (study)", "study",
             ("study", "manifest.csv", "--out", "o", "--workers", "1", *BARE,
              "--cop-units", "m"), ("--cop-units", "m"),
             {**TRIALS, **{f: "@plate_bare" for f in STUDY_FILES}}, handled=True,
             kept=("o",)),
    ]


def _fit_cases() -> list[Case]:
    ic = ("--model", "ic", "--body", "{urdf}", *PLATE, "--out", "f.json")
    two = {"a.txt": "@trial_eyes_open", "b.txt": "@trial_eyes_closed"}
    return [
        Case("the same file twice", "fit: joint", ("fit", "a.txt", "a.txt", *ic),
             ("a.txt", "twice"), two),
        Case("the same file by two paths", "fit: joint",
             ("fit", "a.txt", "sub/../a.txt", *ic), ("sub/../a.txt", "twice"),
             {**two, "sub/": ""}),
        Case("a file and its copy", "fit: joint", ("fit", "a.txt", "b.txt", *ic),
             ("b.txt", "a.txt", "same"), {"a.txt": "@trial_eyes_open",
                                          "b.txt": "@trial_eyes_open"}),
        Case("condition labels that differ only in case", "fit: joint",
             ("fit", "a.txt", "b.txt", *ic, "--conditions", "open", "Open", "--per-trial", "w"),
             ("'open'", "'Open'", "only in case"), two),
        Case("a joint fit of one condition", "fit: joint",
             ("fit", "a.txt", "b.txt", *ic, "--conditions", "open", "open", "--per-trial",
              "w"), ("one condition", "nothing differs"), two, handled=True,
             kept=("f.json",)),
        Case("conditions without --per-trial", "fit: joint",
             ("fit", "a.txt", "b.txt", *ic, "--conditions", "open", "closed"),
             ("--per-trial", "nothing differs"), two, handled=True, kept=("f.json",)),
        Case("several trials, nothing per trial", "fit: joint",
             ("fit", "a.txt", "b.txt", *ic), ("--per-trial", "nothing differs"), two,
             handled=True, kept=("f.json",)),
    ]


def _plate_cases() -> list[Case]:
    frf = ("frf", "--body", "{urdf}", "--out", "r.json")
    fit = ("fit", "--model", "ic", "--body", "{urdf}", "--out", "r.json")
    cases = []
    for command, argv in (("frf", frf), ("fit", fit)):
        name = f"force plate: {command}"
        cases += [
            Case(f"--cop-units m on a COP in mm ({command})", name,
                 (*argv, "{plate_bare}", *BARE, "--cop-units", "m"),
                 ("plate_bare.txt", "--cop-units", "COP", "m")),
            Case(f"--cop-units mm on a COP in m ({command})", name,
                 (*argv, "{plate_in_m}", *BARE, "--cop-units", "mm"),
                 ("plate_in_m.txt", "--cop-units", "COP", "mm")),
            Case(f"a constant COP ({command})", name, (*argv, "{plate_constant_cop}", *PLATE),
                 ("plate_constant_cop.txt", "COP AP", "constant")),
            Case(f"a negative normal force ({command})", name,
                 (*argv, "{plate_negative_force}", *PLATE, "--force-column", "Fz"),
                 ("Fz", "negative"), handled=True, kept=("r.json",)),
            Case(f"the platform resting at another level after the sine ({command})", name,
                 (*argv, "{plate_other_rest}", *PLATE), ("sinusoid 0.2 Hz",), handled=True,
                 kept=("r.json",)),
            Case(f"a tilt drop-out ({command})", name, (*argv, "{plate_dropout}", *PLATE),
                 ("holds still", "left out"), handled=True, kept=("r.json",)),
            Case(f"a step off the plate ({command})", name,
                 (*argv, "{plate_step_off}", *PLATE, "--force-column", "Fz"),
                 ("Fz", "below half the body's weight"), handled=True, kept=("r.json",)),
            Case(f"--sample-rate-hz against the time column ({command})", name,
                 (*argv, "{plate}", *PLATE, "--sample-rate-hz", "200"),
                 ("--sample-rate-hz 200", "100 Hz"), handled=True, kept=("r.json",)),
            Case(f"a force plate's file in UTF-16 without a byte-order mark ({command})", name,
                 (*argv, "{plate_wide_le}", *PLATE), ("plate_wide_le.txt", "UTF-16"),
                 handled=True, kept=("r.json",)),
            Case(f"a force plate's file in Windows Latin-1 ({command})", name,
                 (*argv, "{plate_latin}", *PLATE),
                 ("plate_latin.txt", "cp1252"), handled=True, kept=("r.json",)),
        ]
    frf_h = ("frf", "--out", "r.json", *PLATE, "--height-m", "{height}")
    cases += [
        Case("frf weighing the subject on the plate (--height-m)", "force plate: frf",
             (*frf_h, "{plate_cells}", *CELLS), ("the subject's mass is", "Winter's tables"),
             handled=True, kept=("r.json",)),
        Case("frf --height-m without load columns", "force plate: frf",
             (*frf_h, "{plate_cells}"), ("--height-m", "--load-columns")),
        Case("frf --load-columns without --height-m", "force plate: frf",
             ("frf", "{plate_cells}", "--out", "r.json", *PLATE, "--body", "{urdf}", *CELLS),
             ("--load-columns", "--height-m")),
        Case("a load column that is a length", "force plate: frf",
             (*frf_h, "{plate_cells}", "--load-columns", "COP AP"),
             ("plate_cells.txt", "'COP AP'", "mm", "not a load")),
        Case("load columns without a unit", "force plate: frf",
             (*frf_h, "{plate_bare}", "--time-units", "ms", "--load-columns", "Fz"),
             ("plate_bare.txt", "no unit", "--load-units")),
        Case("body --mass-from a plate's trial", "force plate: body",
             ("body", "--height-m", "{height}", "--mass-from", "{plate_cells}", *CELLS,
              "--tilt-column", "Platform", "--segments", "1", "--out", "b.urdf"),
             ("the subject's mass is",), handled=True, kept=("b.urdf",)),
        Case("body --mass-from and --mass-kg", "force plate: body",
             ("body", "--height-m", "{height}", "--mass-kg", "70", "--mass-from",
              "{plate_cells}", *CELLS, "--out", "b.urdf"), ("--mass-kg", "--mass-from")),
        Case("body --load-columns without --mass-from", "force plate: body",
             ("body", "--height-m", "{height}", "--mass-kg", "70", *CELLS, "--out", "b.urdf"),
             ("--load-columns", "--mass-from")),
        Case("a force plate's file in UTF-16 big-endian without a byte-order mark (frf)",
             "force plate: frf",
             (*frf, "{plate_wide_be}", *PLATE), ("plate_wide_be.txt", "UTF-16"),
             handled=True, kept=("r.json",)),
        Case("a negative normal force (identify --model ic)", "force plate: identify",
             ("identify", "{plate_negative_force}", "--model", "ic", "--body", "{urdf}",
              *PLATE, "--force-column", "Fz", "--out", "r.json"), ("Fz", "negative"),
             handled=True, kept=("r.json",)),
        Case("a constant COP (identify --model ic)", "force plate: identify",
             ("identify", "{plate_constant_cop}", "--model", "ic", "--body", "{urdf}",
              *PLATE, "--out", "r.json"), ("plate_constant_cop.txt", "constant")),
        Case("--cop-units m on a COP in mm (identify --model ic)", "force plate: identify",
             ("identify", "{plate_bare}", "--model", "ic", "--body", "{urdf}", *BARE,
              "--cop-units", "m", "--out", "r.json"), ("--cop-units", "m")),
        Case("the platform resting at another level (identify --model ic)",
             "force plate: identify",
             ("identify", "{plate_other_rest}", "--model", "ic", "--body", "{urdf}", *PLATE,
              "--out", "r.json"), ("sinusoid 0.2 Hz",), handled=True, kept=("r.json",)),
    ]
    return cases


def _lab_text_cases() -> list[Case]:
    body = ("--body", "{urdf}")
    frf = ("frf", *body, "--out", "r.json")
    fit = ("fit", "--model", "ic", *body, "--out", "r.json")
    cases = []
    for command, argv in (("frf", frf), ("fit", fit)):
        name = f"lab text: {command}"
        cases += [
            Case(f"--sample-rate-hz 100 on a 50 Hz time column ({command})", name,
                 (*argv, "{lab50}", *LAB, "--sample-rate-hz", "100"),
                 ("--sample-rate-hz 100", "50 Hz"), handled=True, kept=("r.json",)),
            Case(f"a lab's export in UTF-16 without a byte-order mark ({command})", name,
                 (*argv, "{lab_wide_le}", *LAB), ("lab_wide_le.csv", "UTF-16"),
                 handled=True, kept=("r.json",)),
            Case(f"a lab's export in Windows Latin-1 ({command})", name,
                 (*argv, "{lab_latin}", *LAB),
                 ("lab_latin.csv", "cp1252"), handled=True, kept=("r.json",)),
        ]
    cases += [
        Case("--sample-rate-hz 100 on a 50 Hz time column (identify --model ic)",
             "lab text: identify",
             ("identify", "{lab50}", "--model", "ic", *body, *LAB, "--sample-rate-hz", "100",
              "--out", "r.json"), ("--sample-rate-hz 100", "50 Hz"), handled=True,
             kept=("r.json",)),
        Case("a lab's export in UTF-16 without a byte-order mark (identify --model ic)",
             "lab text: identify",
             ("identify", "{lab_wide_le}", "--model", "ic", *body, *LAB, "--out", "r.json"),
             ("lab_wide_le.csv", "UTF-16"), handled=True, kept=("r.json",)),
        Case("the project's columns in UTF-16 without a byte-order mark (frf)",
             "lab text: frf", ("frf", "{standard_wide}", "--out", "r.json"),
             ("standard_wide.csv", "UTF-16"), handled=True, kept=("r.json",)),
        Case("a tilt file in Windows Latin-1 (simulate --tilt)", "lab text: simulate",
             ("simulate", "--tilt", "{tilt_latin}", "--out", "s.csv"),
             ("tilt_latin.csv", "cp1252"), handled=True, kept=("s.csv",)),
        Case("a tilt file in UTF-16 without a byte-order mark (simulate --tilt)",
             "lab text: simulate", ("simulate", "--tilt", "{tilt_wide}", "--out", "s.csv"),
             ("tilt_wide.csv", "UTF-16"), handled=True, kept=("s.csv",)),
        Case("time stamps that jitter (frf)", "lab text: frf", (*frf, "{lab_jitter}", *LAB),
             ("lab_jitter.csv", "jitter by up to", "Hz clock"), handled=True,
             kept=("r.json",)),
        Case("time stamps that jitter (fit)", "lab text: fit", (*fit, "{lab_jitter}", *LAB),
             ("lab_jitter.csv", "jitter by up to", "Hz clock"), handled=True,
             kept=("r.json",)),
        Case("time stamps with a gap (frf)", "lab text: frf", (*frf, "{lab_gap}", *LAB),
             ("lab_gap.csv", "line 2002", "gap")),
        Case("a COM-only file without a tilt column (identify)", "lab text: identify",
             ("identify", "{com_only}", "--model", "ic", *body, "--time-column", "Time",
              "--angle-columns", "COM", "--out", "r.json"),
             ("com_only.csv", "no tilt column 'tilt_deg'", "--tilt-column NAME",
              "--tilt-column none", "--tilt FILE")),
        Case("a COM-only file with --tilt-column none and no stimulus (frf)", "lab text: frf",
             (*frf, "{com_only}", "--time-column", "Time", "--tilt-column", "none",
              "--angle-columns", "COM"), ("com_only.csv", "the PRTS flags", "--protocol FILE")),
        Case("a lab file in UTF-16 named by a wrong column", "lab text: frf",
             (*frf, "{lab_wide_le}", "--time-column", "Time", "--tilt-column", "Plate",
              "--angle-columns", "COM"), ("lab_wide_le.csv", "'Plate'")),
    ]
    return cases


def _nyquist_cases() -> list[Case]:
    at_nyquist = json.dumps({"kind": "sum_of_sines", "frequencies_hz": [0.2, 25.0],
                             "amplitudes_deg": [1.0, 0.1]})
    harmonic = json.dumps({"kind": "multisine", "period_s": 20.0,
                           "harmonics": [1, 2, 500]})
    commands = {
        "simulate": ("simulate", "--protocol", "p.json", "--out", "s.csv"),
        "stimulus": ("stimulus", "p.json", "--out", "c.csv"),
        "design": ("design", "--protocol", "p.json", "--out", "d", "--draws", "1",
                   "--quiet"),
        "frf": ("frf", "{lab50}", *LAB, "--protocol", "p.json", "--out", "r.json"),
        "fit": ("fit", "{lab50}", *LAB, "--model", "ic", "--body", "{urdf}", "--protocol",
                "p.json", "--out", "r.json"),
    }
    cases = [Case(f"a sine at the Nyquist frequency ({command})", f"protocol: {command}",
                  argv, ("p.json", "25 Hz", "Nyquist"), {"p.json": at_nyquist})
             for command, argv in commands.items()]
    cases += [Case(f"a multisine harmonic at the Nyquist frequency ({command})",
                   f"protocol: {command}", argv, ("p.json", "25 Hz", "Nyquist"),
                   {"p.json": harmonic}) for command, argv in commands.items()
              if command in ("simulate", "stimulus")]
    cases.append(Case("a sine at the command file's Nyquist frequency", "protocol: stimulus",
                      ("stimulus", "p.json", "--rate-hz", "40", "--out", "c.csv"),
                      ("--rate-hz", "20 Hz", "Nyquist"),
                      {"p.json": json.dumps({"kind": "sum_of_sines",
                                             "frequencies_hz": [0.2, 20.0],
                                             "amplitudes_deg": [1.0, 0.1]})}))
    return cases


def _flag_cases() -> list[Case]:
    paired = ("norm", "compare", "--paired", "--group", "{frf_open_1}", "{frf_open_2}",
              "--group", "{frf_closed_1}", "{frf_closed_2}", "--out", "c.json")
    robot = ("robot", "check", "--out", "r")
    return [
        Case("identify --network with --method fit", "flags: identify",
             ("identify", "{lab50}", *LAB, "--network", "{specialist}", "--method", "fit"),
             ("--network", "--method fit")),
        Case("identify --model DIR with --method fit", "flags: identify",
             ("identify", "{lab50}", *LAB, "--model", "{specialist}", "--method", "fit"),
             ("--network", "--method fit")),
        Case("norm compare --paired --bootstrap", "flags: norm compare",
             (*paired, "--bootstrap", "500"), ("--bootstrap", "--paired")),
        Case("norm compare --paired --rate-hz", "flags: norm compare",
             (*paired, "--rate-hz", "30"), ("--rate-hz", "--paired")),
        Case("norm compare --paired, both groups of one name", "flags: norm compare",
             (*paired, "--names", "open", "open"), ("--names", "'open'")),
        Case("norm compare, both groups of one name", "flags: norm compare",
             (*paired[:2], *paired[3:], "--names", "A", "A"), ("--names", "'A'")),
        Case("robot check --held on a chain", "flags: robot check",
             (*robot, "--body", "{tip_urdf}", "--held", "rigid"), ("--held", "chain")),
        Case("robot check --held servos on a chain", "flags: robot check",
             (*robot, "--body", "{tip_urdf}", "--held", "servos"), ("--held", "chain")),
        Case("robot check --servo-stiffness with --held rigid", "flags: robot check",
             (*robot, "--body", "talos", "--held", "rigid", "--servo-stiffness", "5"),
             ("--servo-stiffness", "--held rigid")),
        Case("robot check --servo-stiffness on a chain", "flags: robot check",
             (*robot, "--body", "{tip_urdf}", "--servo-stiffness", "5"),
             ("--servo-stiffness", "chain")),
        Case("robot check --segments on a chain", "flags: robot check",
             (*robot, "--body", "{tip_urdf}", "--segments", "2"), ("--segments", "chain")),
        Case("body --height and --height-m, two values", "flags: twice",
             ("body", "--height", "1.8", "--height-m", "1.7", "--mass-kg", "70", "--out",
              "b.urdf"), ("--height-m", "1.8", "1.7", "twice")),
        Case("body --mass and --mass-kg, two values", "flags: twice",
             ("body", "--height-m", "1.7", "--mass", "70", "--mass-kg", "60", "--out",
              "b.urdf"), ("--mass-kg", "70", "60", "twice")),
        Case("body --height-m twice", "flags: twice",
             ("body", "--height-m", "1.8", "--height-m", "1.7", "--mass-kg", "70", "--out",
              "b.urdf"), ("--height-m", "twice")),
        Case("simulate --noise-deg and --sensor-noise-deg, two values", "flags: twice",
             ("simulate", "--noise-deg", "0.1", "--sensor-noise-deg", "0.2", "--out",
              "s.csv"), ("--sensor-noise-deg", "twice")),
        Case("frf --out twice", "flags: twice",
             ("frf", "{lab50}", *LAB, "--out", "a.json", "--out", "b.json"),
             ("--out", "twice")),
        Case("fit --body twice", "flags: twice",
             ("fit", "{lab50}", *LAB, "--model", "ic", "--body", "{urdf}", "--body",
              "{tip_urdf}", "--out", "r.json"), ("--body", "twice")),
        Case("study --model twice", "flags: twice",
             ("study", "manifest.csv", "--out", "o", "--model", "ic", "--model", "none"),
             ("--model", "twice")),
        Case("identify --network and --model DIR", "flags: twice",
             ("identify", "{lab50}", "--network", "{specialist}", "--model", "d/",
              "--method", "cnn"), ("--network", "twice"), {"d/": ""}),
    ]


def all_cases() -> list[Case]:
    """Every case (``{name}`` fields and ``@name`` files: :func:`make_material`'s)."""
    return (_study_cases() + _fit_cases() + _plate_cases() + _lab_text_cases()
            + _nyquist_cases() + _flag_cases())


#: The answers whose exit status is part of the good answer (1: answered, doubtful).
EXIT_STATUS = {"a study whose fits are doubtful exits 1 and says so": 1,
               "a trial with a constant COP": 1}
#: The commands whose cases run a whole fit or study (over 5 s here).
SLOW_COMMANDS = ("study", "fit", "identify")
CASES = all_cases()
_MATERIAL: dict[str, str] = {}


def _material() -> dict[str, str]:
    """Made once per process, in a folder of its own."""
    if not _MATERIAL:
        _MATERIAL.update(make_material(Path(tempfile.mkdtemp(prefix="hostile-newest-"))))
    return _MATERIAL


def test_the_suite_has_at_least_80_cases_over_every_newest_surface():
    names = [c.name for c in CASES]
    assert len(names) == len(set(names)) >= 80
    surfaces = {c.surface.split(":")[0] for c in CASES}
    assert {"study", "fit", "force plate", "lab text", "protocol", "flags"} <= surfaces


@pytest.mark.parametrize("case", [pytest.param(
    c, id=c.name, marks=[pytest.mark.slow("a study, fit or identify command")]
    if c.argv[0] in SLOW_COMMANDS else []) for c in CASES])
def test_every_bad_input_is_refused_clearly_or_handled(case, tmp_path):
    material = _material()
    outcome = run_case(case, material, tmp_path / "case", shipped=SHIPPED, root=ROOT)
    wanted = "handled" if case.handled else "clear"
    assert outcome.outcome == wanted, (outcome.outcome, outcome.status, outcome.line)
    if case.name in EXIT_STATUS:
        assert outcome.status == EXIT_STATUS[case.name], (outcome.status, outcome.line)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, required=True, help="the outcomes (JSON)")
    parser.add_argument("--before", type=Path, help="the outcomes on an earlier tree")
    parser.add_argument("--only", help="the cases whose name holds this")
    args = parser.parse_args(argv)
    from hostile_harness import Outcome, before_after

    material = _material()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for case in CASES:
            if args.only and args.only not in case.name:
                continue
            row = run_case(case, material, Path(tmp) / "case", shipped=SHIPPED, root=ROOT)
            print(f"{row.outcome:9s} {case.name}: {row.line[:160]}", file=sys.stderr,
                  flush=True)
            rows.append(row)
    args.out.write_text(json.dumps([r.to_dict() for r in rows], indent=1) + "\n")
    if args.before is not None:
        before = json.loads(args.before.read_text())
        print(before_after(before, [Outcome(**{**r.to_dict()}) for r in rows]))
    return 0


if __name__ == "__main__":
    sys.exit(main())

