"""The hostile-input cases of the newer commands: protocol files, a lab's columns, cohorts,
design, stimulus, frf, the universal tools and evaluate, and (:mod:`hostile_cases_newest`)
C3D trials, the IC model, compare and norms, each a mistake a new user makes, declared with
its good answer before it runs; and the material they share (recordings, a protocol, small
data sets), made once.

``tests/test_hostile_newer.py`` runs every case and requires *clear* or *handled*;
``benchmarks/hostile_input.py`` runs the same cases and writes their report. Each outcome is
sorted by :func:`hostile_harness.run_case` (clear, handled, unclear, traceback, silent,
data loss, hang).
"""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import hostile_harness as testing
from hostile_cases_newest import make_newest_material, newest_cases
from hostile_harness import Case, Outcome

ROOT = Path(__file__).resolve().parents[1]
URDF = ROOT / "urdf"
TIP_URDF = URDF / "tip_default.urdf"
WINTER2 = URDF / "winter_1.75m_70kg_2seg.urdf"


# ------------------------------------------------------------------------- material
def make_material(root: Path) -> dict[str, str]:
    """Shared inputs in ``root``: recordings (TIP, 121 s; a 2-segment lab file with its own
    column names), a protocol, a per-body data set of the 2-segment body, a tiny universal
    set; returns ``{name: path}``."""
    import numpy as np

    from posture_id import load_body, simulate
    from posture_id.simulation.protocols import MultisineProtocol, write_protocol

    root.mkdir(parents=True, exist_ok=True)
    paths = {"tip_urdf": str(TIP_URDF), "winter2": str(WINTER2)}
    rec = root / "tip.csv"
    if not rec.exists():
        simulate(load_body()).to_recording().with_sensor_noise(0.02, 1).to_csv(rec)
    paths["rec"] = str(rec)
    lab = root / "lab2.csv"
    if not lab.exists():
        recording = simulate(load_body(WINTER2)).to_recording()
        rows = "".join(f"{t:.3f},{np.degrees(p):.5f},{np.degrees(a):.5f},{np.degrees(b):.5f}\n"
                       for t, p, a, b in zip(recording.time, recording.tilt,
                                             recording.theta[:, 0], recording.theta[:, 1],
                                             strict=True))
        lab.write_text("Time,Platform,Legs,Trunk\n" + rows)
    paths["lab"] = str(lab)
    protocol = root / "multisine.json"
    if not protocol.exists():
        write_protocol(MultisineProtocol(period_s=20.0, harmonics=(1, 2, 3, 5, 8)), protocol)
    paths["protocol"] = str(protocol)
    dataset = root / "set_winter2"
    if not (dataset / "manifest.json").exists():
        _quiet_main(["dataset", "generate", "--trials", "6", "--shard-size", "6", "--body",
                     str(WINTER2), "--out", str(dataset), "--quiet"])
    paths["set_winter2"] = str(dataset)
    tip_set = root / "set_tip"
    if not (tip_set / "manifest.json").exists():
        _quiet_main(["dataset", "generate", "--trials", "6", "--shard-size", "6", "--out",
                     str(tip_set), "--quiet"])
    paths["set_tip"] = str(tip_set)
    paths["specialist"] = str(ROOT / "posture_id" / "learning" / "models" / "tip_default")
    tiny = root / "universal_tiny"
    if not (tiny / "manifest.json").exists():
        _quiet_main(["universal", "data", "--out", str(tiny), "--shards", "1", "--trials",
                     "4", "--quiet"])
    paths["universal_tiny"] = str(tiny)
    paths["model"] = str(ROOT / "posture_id" / "learning" / "models" / "universal")
    make_newest_material(root, paths, _quiet_main)
    return paths


#: The material that is the project's own files (not watched for changes).
SHIPPED = ("tip_urdf", "winter2", "model", "specialist", "c3d", "dec_params", "one_urdf")


#: (command, flag): the spelling a tree from before the command line's renaming knows
#: (one without ``posture_id.cli.renamed``), so that the suite runs on such a tree too.
OLD_SPELLINGS = {("simulate", "--sensor-noise-deg"): "--noise-deg",
                 ("simulate", "--height-m"): "--subject-height-m",
                 ("simulate", "--mass-kg"): "--subject-mass-kg",
                 ("body", "--height-m"): "--height", ("body", "--mass-kg"): "--mass",
                 ("identify", "--band-preset"): "--frf-preset",
                 ("identify", "--network"): "--model"}


def as_the_tree_spells(argv: list[str]) -> list[str]:
    """``argv`` for the posture_id imported: as it is, or in the old spellings on a tree
    from before the renaming."""
    import importlib.util

    if importlib.util.find_spec("posture_id.cli.renamed") is not None or not argv:
        return argv
    return [OLD_SPELLINGS.get((argv[0], a), a) for a in argv]


def _quiet_main(argv: list[str], allowed: tuple[int, ...] = (0,)) -> int:
    from posture_id.cli import main

    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        code = main(as_the_tree_spells(argv))
    if code not in allowed:
        raise RuntimeError(f"making the material failed: {argv}")
    return code


# ------------------------------------------------------------------------- running
def run_case(case: Case, material: dict[str, str], folder: Path) -> Outcome:
    """Run ``case`` in ``folder`` (made empty here) and sort its outcome, the shipped
    material unwatched, in the spelling of the tree under test."""
    return testing.run_case(case, material, folder, shipped=SHIPPED,
                            spelled=as_the_tree_spells, root=ROOT)


# ------------------------------------------------------------------------- the cases
def _protocol(**fields) -> str:
    return json.dumps(fields)


MS = {"kind": "multisine", "period_s": 20.0, "harmonics": [1, 2, 3]}
_PROTOCOL_COMMANDS = {
    "stimulus": ("stimulus", "{p}", "--out", "command.csv"),
    "design": ("design", "--protocol", "{p}", "--out", "report", "--draws", "1", "--quiet"),
    "simulate": ("simulate", "--protocol", "{p}", "--out", "sim.csv"),
    "identify": ("identify", "{rec}", "--protocol", "{p}", "--method", "cnn"),
    "fit": ("fit", "{rec}", "--protocol", "{p}", "--out", "fit.json"),
    "frf": ("frf", "{rec}", "--protocol", "{p}", "--out", "frf.json"),
}


def _via_every_command(name: str, files: dict, path: str, expect: tuple[str, ...]) -> list[Case]:
    return [Case(f"{name} ({command})", f"protocol: {command}",
                 tuple(a.replace("{p}", path) for a in argv), expect, files)
            for command, argv in _PROTOCOL_COMMANDS.items()]


BAD_PROTOCOLS = {  # name: (file text, words the line must hold)
    "empty file": ("", ("p.json", "not valid JSON")),
    "not JSON": ("kind: prts\n", ("p.json", "not valid JSON")),
    "a list, not an object": ("[1, 2]", ("p.json", "object")),
    "no kind": (_protocol(period_s=20.0), ("p.json", "kind")),
    "unknown kind": (_protocol(kind="chirp"), ("p.json", "chirp")),
    "unknown field": (_protocol(**MS, speed=2), ("p.json", "speed")),
    "harmonic a word": (_protocol(**{**MS, "harmonics": [1, "two"]}), ("p.json", "'two'")),
    "harmonic zero": (_protocol(**{**MS, "harmonics": [0, 1]}), ("p.json", "harmonics")),
    "harmonic 1.5": (_protocol(**{**MS, "harmonics": [1.5, 2]}), ("p.json", "harmonics")),
    "harmonics repeated": (_protocol(**{**MS, "harmonics": [1, 1, 2]}),
                           ("p.json", "harmonics")),
    "period negative": (_protocol(**{**MS, "period_s": -20}), ("p.json", "period_s")),
    "period a word": (_protocol(**{**MS, "period_s": "long"}), ("p.json", "period_s")),
    "amplitude 1e9": (_protocol(kind="prts", amplitude_deg=1e9), ("p.json", "20°")),
    "amplitude negative": (_protocol(kind="prts", amplitude_deg=-1), ("p.json", "amplitude")),
    "amplitude NaN": ('{"kind": "prts", "amplitude_deg": NaN}', ("p.json", "amplitude")),
    "weights too few": (_protocol(**MS, weights=[1.0]), ("p.json", "weights")),
    "phases too many": (_protocol(**MS, phases_rad=[0, 0, 0, 0]), ("p.json", "phases")),
    "prts 81 states": (_protocol(kind="prts", states=81), ("p.json", "states")),
    "cycles 0": (_protocol(**MS, cycles=0), ("p.json", "cycles")),
    "cycles 1e6": (_protocol(**MS, cycles=1000000), ("p.json", "cycles")),
    "frequencies above 50 Hz": (_protocol(kind="sum_of_sines", frequencies_hz=[0.1, 80.0],
                                          amplitudes_deg=[0.5, 0.5]), ("p.json", "Hz")),
    "two amplitudes, no base": (_protocol(kind="two_amplitudes", amplitudes_deg=[1, 3]),
                                ("p.json", "base")),
    "latin-1 bytes": (b'{"kind": "prts", "note": "\xe9"}', ("p.json", "UTF-8")),
}


def _protocol_cases() -> list[Case]:
    cases = _via_every_command("protocol a folder", {"p.json/": ""}, "p.json",
                               ("p.json", "folder"))
    cases += _via_every_command("protocol missing", {}, "p.json", ("p.json", "no such"))
    for name, (text, expect) in BAD_PROTOCOLS.items():
        command = "stimulus" if len(cases) % 2 else "simulate"
        argv = _PROTOCOL_COMMANDS[command]
        cases.append(Case(name, f"protocol: {command}",
                          tuple(a.replace("{p}", "p.json") for a in argv), expect,
                          {"p.json": text}))
    cases += [
        Case("--part 5 of a 2-part protocol", "stimulus",
             ("stimulus", "p.json", "--part", "5", "--out", "c.csv"), ("--part", "5"),
             {"p.json": _protocol(kind="two_amplitudes", base={"kind": "prts"})}),
        Case("--part with a one-part protocol", "stimulus",
             ("stimulus", "{protocol}", "--part", "2", "--out", "c.csv"), ("--part",)),
        Case("--rate-hz 1e7", "stimulus",
             ("stimulus", "{protocol}", "--rate-hz", "1e7", "--out", "c.csv"), ("--rate-hz",)),
        Case("--out over the protocol", "stimulus",
             ("stimulus", "p.json", "--out", "p.json"), ("p.json", "input"),
             {"p.json": "@protocol"}),
        Case("PRTS flags beside --protocol", "protocol: simulate",
             ("simulate", "--protocol", "{protocol}", "--amplitude-deg", "2", "--out", "s.csv"),
             ("--amplitude-deg", "--protocol")),
    ]
    return cases


def _design_cases() -> list[Case]:
    design = ("design", "--draws", "1", "--quiet")
    return [
        Case("--out holds the user's design.md", "design", (*design, "--out", "study"),
             ("study", "design.md", "did not write"), {"study/design.md": "my notes\n"}),
        Case("--out holds the user's recommended.json", "design", (*design, "--out", "study"),
             ("recommended.json", "did not write"),
             {"study/recommended.json": '{"mine": 1}'}),
        Case("design --out is a file", "design", (*design, "--out", "study"), ("study", "a file"),
             {"study": "x"}),
        Case("--out is the protocol", "design",
             (*design, "--protocol", "p.json", "--out", "p.json"), ("p.json",),
             {"p.json": "@protocol"}),
        Case("--locked-share 1.5", "design", (*design, "--locked-share", "1.5", "--out", "d"),
             ("--locked-share", "between 0 and 1")),
        Case("--locked-share 0", "design", (*design, "--locked-share", "0", "--out", "d"),
             ("--locked-share",)),
        Case("--body missing", "design", (*design, "--body", "nobody.urdf", "--out", "d"),
             ("nobody.urdf",)),
        Case("--body a folder", "design", (*design, "--body", "b", "--out", "d"),
             ("b", "folder"), {"b/": ""}),
        Case("limits no candidate meets", "design",
             (*design, "--max-minutes", "0.1", "--out", "d"), ("no candidate keeps within",),
             handled=True, kept=("d",)),
        Case("--max-peak-to-peak-deg 100", "design",
             (*design, "--max-peak-to-peak-deg", "100", "--out", "d"),
             ("max_peak_to_peak_deg 100", "20°")),
    ]


def _column_cases() -> list[Case]:
    lab = ("--body", "{winter2}", "--time-column", "Time", "--tilt-column", "Platform")
    frf_lab = ("--time-column", "Time", "--tilt-column", "Platform")
    return [
        Case("an angle column twice (identify)", "columns: identify",
             ("identify", "{lab}", *lab, "--angle-columns", "Legs", "Legs", "--method", "cnn"),
             ("'Legs'", "more than once")),
        Case("an angle column twice (frf)", "columns: frf",
             ("frf", "{lab}", *frf_lab, "--angle-columns", "Legs", "Legs", "--out", "f.json"),
             ("'Legs'", "more than once")),
        Case("an angle column twice (fit)", "columns: fit",
             ("fit", "{lab}", *lab, "--angle-columns", "Legs", "Legs", "--out", "f.json"),
             ("'Legs'", "more than once")),
        Case("an angle column not in the file", "columns: identify",
             ("identify", "{lab}", *lab, "--angle-columns", "Legs", "Torso", "--method", "cnn"),
             ("'Torso'", "Trunk")),
        Case("one angle column for two segments", "columns: identify",
             ("identify", "{lab}", *lab, "--angle-columns", "Legs", "--method", "cnn"),
             ("(Legs)", "2 segment")),
        Case("three angle columns for two segments", "columns: fit",
             ("fit", "{lab}", *lab, "--angle-columns", "Legs", "Trunk", "Platform",
              "--out", "f.json"), ("'Platform'", "more than once")),
        Case("a time column not in the file", "columns: identify",
             ("identify", "{lab}", "--body", "{winter2}", "--time-column", "t",
              "--tilt-column", "Platform", "--angle-columns", "Legs", "Trunk", "--method", "cnn"),
             ("'t'",)),
        Case("a tilt column not in the file", "columns: frf",
             ("frf", "{lab}", "--time-column", "Time", "--tilt-column", "plate",
              "--angle-columns", "Legs", "Trunk", "--out", "f.json"), ("'plate'",)),
        Case("the tilt column also an angle", "columns: identify",
             ("identify", "{lab}", *lab, "--angle-columns", "Legs", "Platform", "--method",
              "cnn"), ("'Platform'",)),
        Case("the time column also an angle", "columns: identify",
             ("identify", "{lab}", "--body", "{winter2}", "--time-column", "Time",
              "--tilt-column", "Platform", "--angle-columns", "Time", "Trunk", "--method",
              "cnn"), ("'Time'",)),
        Case("--time-column alone (fit)", "columns: fit",
             ("fit", "{lab}", "--body", "{winter2}", "--time-column", "Time", "--out", "f.json"),
             ("--time-column", "--angle-columns")),
        Case("--tilt-column alone (frf)", "columns: frf",
             ("frf", "{lab}", "--tilt-column", "Platform", "--out", "f.json"),
             ("--tilt-column", "--angle-columns")),
        Case("degrees read as radians", "columns: identify",
             ("identify", "{lab}", *lab, "--angle-columns", "Legs", "Trunk", "--units", "rad",
              "--method", "cnn"), ("'Platform'", "degrees")),
        Case("degrees read as radians (frf)", "columns: frf",
             ("frf", "{lab}", *frf_lab, "--angle-columns", "Legs", "Trunk", "--units", "rad",
              "--out", "f.json"), ("'Platform'", "degrees")),
        Case("--units with the project's own columns", "columns: identify",
             ("identify", "{rec}", "--units", "rad", "--method", "cnn"), ("--units",)),
        Case("an empty column name", "columns: identify",
             ("identify", "{lab}", *lab, "--angle-columns", "Legs", "", "--method", "cnn"),
             ("no column ''",)),
        Case("--onset-s beyond the recording", "columns: identify",
             ("identify", "{lab}", "--body", "{winter2}", "--time-column", "Time",
              "--tilt-column", "none", "--angle-columns", "Legs", "Trunk", "--onset-s", "500",
              "--method", "cnn"), ("500 s", "after the recording ends")),
    ]


def _cohort_cases() -> list[Case]:
    recs = {"recs/a.csv": "@rec", "recs/b.csv": "@rec"}
    return [
        Case("--out holds the user's summary.csv", "cohort",
             ("identify", "recs", "--out", "mine", "--method", "cnn"),
             ("summary.csv", "did not write"), {**recs, "mine/summary.csv": "my,table\n"}),
        Case("--out holds the user's a.json", "cohort",
             ("identify", "recs", "--out", "mine", "--method", "cnn"),
             ("a.json", "did not write"), {**recs, "mine/a.json": '{"mine": true}'}),
        Case("--out is the recordings' folder", "cohort",
             ("identify", "recs", "--out", "recs", "--method", "cnn"), ("recs", "--out")),
        Case("cohort --out is a file", "cohort", ("identify", "recs", "--out", "mine", "--method",
                                           "cnn"), ("mine", "a file"), {**recs, "mine": "x"}),
        Case("a folder with no CSV", "cohort",
             ("identify", "recs", "--out", "o", "--method", "cnn"), ("recs", "no"),
             {"recs/notes.txt": "x"}),
        Case("a pattern matching nothing", "cohort",
             ("identify", "recs/*.tsv", "--out", "o", "--method", "cnn"), ("recs/*.tsv",),
             recs),
        Case("--plot with a cohort", "cohort",
             ("identify", "recs", "--out", "o", "--plot", "p.png"), ("--plot",), recs),
        Case("--bodies missing", "cohort",
             ("identify", "recs", "--out", "o", "--bodies", "nobodies", "--method", "cnn"),
             ("nobodies",), recs),
        Case("--bodies a file", "cohort",
             ("identify", "recs", "--out", "o", "--bodies", "b.urdf", "--method", "cnn"),
             ("b.urdf", "folder"), {**recs, "b.urdf": "@tip_urdf"}),
        Case("--bodies holding no URDF of a subject", "cohort",
             ("identify", "recs", "--out", "o", "--bodies", "bodies", "--method", "cnn"),
             ("bodies", "holds no body of these recordings"), {**recs, "bodies/A.urdf": "x"}),
        Case("--bodies holding one subject's URDF", "cohort",
             ("identify", "recs", "--out", "o", "--bodies", "bodies", "--method", "cnn"),
             ("1 of 2 recordings have no body",),
             {**recs, "bodies/a.urdf": "@tip_urdf"}, handled=True, kept=("o",)),
        Case("one recording unreadable", "cohort",
             ("identify", "recs", "--out", "o", "--method", "cnn"), ("b.csv",),
             {"recs/a.csv": "@rec", "recs/b.csv": "time_s,tilt_deg\n1,x\n"}, handled=True,
             kept=("o",)),
        Case("--scheduler with one recording", "cohort",
             ("identify", "{rec}", "--scheduler", "tcp://127.0.0.1:1"), ("--scheduler",)),
        Case("--scheduler nobody listens at", "cohort",
             ("identify", "recs", "--out", "o", "--scheduler", "tcp://127.0.0.1:9",
              "--method", "cnn"), ("tcp://127.0.0.1:9", "nothing accepts"), recs, limit_s=60),
    ]


def _universal_cases() -> list[Case]:
    data = ("universal", "data", "--shards", "1", "--trials", "2", "--quiet")
    return [
        Case("amplitude beyond a platform", "universal data",
             (*data, "--out", "u", "--amplitude-deg", "30", "40"), ("--amplitude-deg", "20")),
        Case("amplitude range reversed", "universal data",
             (*data, "--out", "u", "--amplitude-deg", "2", "1"), ("--amplitude-deg",)),
        Case("locked share reversed", "universal data",
             (*data, "--out", "u", "--locked-share", "0.5", "0.2"), ("--locked-share",)),
        Case("locked share above 1", "universal data",
             (*data, "--out", "u", "--locked-share", "0.2", "1.5"), ("--locked-share",)),
        Case("clean share 2", "universal data", (*data, "--out", "u", "--clean-share", "2"),
             ("--clean-share",)),
        Case("an unknown noise family", "universal data",
             (*data, "--out", "u", "--noise-families", "pink"), ("pink",)),
        Case("--out a file", "universal data", (*data, "--out", "u"), ("u", "a file"),
             {"u": "x"}),
        Case("--out a set of another scope", "universal data",
             (*data, "--out", "u", "--amplitude-deg", "1", "2"), ("u",),
             {"u": "@universal_tiny"}),
        Case("--out holding the user's files", "universal data", (*data, "--out", "u"),
             ("u", "holds no universal set"), {"u/notes.txt": "mine"}),
        Case("train: no such set", "universal train",
             ("universal", "train", "nothing", "--out", "m", "--quiet"), ("nothing",)),
        Case("train: a folder that is no set", "universal train",
             ("universal", "train", "s", "--out", "m", "--quiet"), ("s", "manifest"),
             {"s/notes.txt": "x"}),
        Case("train: a set too small to split", "universal train",
             ("universal", "train", "{universal_tiny}", "--out", "m", "--quiet"),
             ("no train trial",)),
        Case("train: --init no model", "universal train",
             ("universal", "train", "{universal_tiny}", "--out", "m", "--init", "nomodel",
              "--quiet"), ("nomodel",)),
        Case("train: --init with --hidden", "universal train",
             ("universal", "train", "{universal_tiny}", "--out", "m", "--init", "{model}",
              "--hidden", "64", "--quiet"), ("--hidden", "--init")),
        Case("train: --exclude-families of a set without them", "universal train",
             ("universal", "train", "{universal_tiny}", "--out", "m", "--exclude-families",
              "shallow", "--quiet"), ("shallow",)),
        Case("train: --out is the set", "universal train",
             ("universal", "train", "s", "--out", "s", "--quiet"), ("s", "input"),
             {"s": "@universal_tiny"}),
        Case("check: no such model", "universal check",
             ("universal", "check", "nomodel", "{universal_tiny}"), ("nomodel",)),
        Case("check: a set that is no set", "universal check",
             ("universal", "check", "{model}", "s"), ("s",), {"s/": ""}),
        Case("table: --out a file", "universal table",
             ("universal", "table", "--out", "t", "--trials", "2", "--quiet"), ("t", "a file"),
             {"t": "x"}),
        Case("table: a model folder without a model", "universal table",
             ("universal", "table", "m", "--out", "t", "--trials", "2", "--quiet"), ("m",),
             {"m/": ""}),
    ]


def _evaluate_cases() -> list[Case]:
    return [
        Case("the universal model as the model", "evaluate",
             ("evaluate", "{model}", "{set_tip}", "--out", "e"),
             ("the universal model", "--universal")),
        Case("a specialist on another body's set", "evaluate",
             ("evaluate", "{specialist}", "{set_winter2}", "--out", "e"),
             ("'winter", "trained on 'tip_default'")),
        Case("a model folder without a model", "evaluate",
             ("evaluate", "m", "{set_tip}", "--out", "e"), ("m/model.json", "missing"),
             {"m/": ""}),
        Case("a set folder that is no set", "evaluate",
             ("evaluate", "{specialist}", "s", "--out", "e"), ("s: not a data set",),
             {"s/": ""}),
        Case("--universal a folder without a model", "evaluate",
             ("evaluate", "{specialist}", "{set_tip}", "--out", "e", "--universal", "m"),
             ("m", "--universal"), {"m/": ""}),
        Case("--out holds the user's report.md", "evaluate",
             ("evaluate", "{specialist}", "{set_tip}", "--out", "e"),
             ("report.md", "did not write"), {"e/report.md": "mine\n"}),
        Case("the universal set given as a per-body set", "evaluate",
             ("evaluate", "{specialist}", "{universal_tiny}", "--out", "e"),
             ("universal_tiny", "universal")),
    ]


def _frf_fit_cases() -> list[Case]:
    return [
        Case("--period-s not the tilt's", "frf",
             ("frf", "{rec}", "--period-s", "20", "--out", "f.json"), ("20 s",)),
        Case("--skip-cycles all cycles", "frf",
             ("frf", "{rec}", "--skip-cycles", "2", "--out", "f.json"), ("skipping 2",)),
        Case("--max-frequency-hz above Nyquist", "frf",
             ("frf", "{rec}", "--max-frequency-hz", "500", "--out", "f.json"),
             ("max_frequency_hz 500 Hz", "Nyquist")),
        Case("--drift-order 50", "frf",
             ("frf", "{rec}", "--drift-order", "50", "--out", "f.json"),
             ("drift of order 50", "below 4")),
        Case("--bands 1000", "frf", ("frf", "{rec}", "--bands", "1000", "--out", "f.json"),
             ("held no stimulated frequency",), handled=True, kept=("f.json",)),
        Case("--max-offset-s beyond half a cycle", "fit",
             ("fit", "{rec}", "--locked", "--max-offset-s", "100", "--out", "f.json"),
             ("max_offset_s 100 s", "half a stimulus cycle")),
        Case("--max-offset-s without --locked", "fit",
             ("fit", "{rec}", "--max-offset-s", "2", "--out", "f.json"),
             ("--max-offset-s", "--locked")),
        Case("--prior-sd without --locked", "fit",
             ("fit", "{rec}", "--prior-sd", "0.5", "--out", "f.json"),
             ("--prior-sd", "--locked")),
        Case("--fit-passive with --method cnn", "identify",
             ("identify", "{rec}", "--fit-passive", "--method", "cnn"),
             ("--fit-passive", "--method cnn")),
        Case("--gain-range reversed", "fit",
             ("fit", "{rec}", "--gain-range", "2", "0.5", "--out", "f.json"),
             ("--gain-range",)),
        Case("--delay-range beyond 2 s", "fit",
             ("fit", "{rec}", "--delay-range", "0.1", "50", "--out", "f.json"),
             ("--delay-range", "2 s")),
        Case("--init a protocol, not parameters", "fit",
             ("fit", "{rec}", "--init", "{protocol}", "--out", "f.json"), ("multisine.json",)),
        Case("--out over the recording", "fit", ("fit", "r.csv", "--out", "r.csv"),
             ("r.csv", "input"), {"r.csv": "@rec"}),
    ]


def _body_cases() -> list[Case]:
    return [
        Case("--default-tip --segments 2", "body",
             ("body", "--default-tip", "--segments", "2", "--out", "x.urdf"),
             ("--default-tip",)),
        Case("URDF --out copy", "body", ("body", "{tip_urdf}", "--out", "copy.urdf"),
             ("--out",)),
        Case("--height without --mass", "body",
             ("body", "--height-m", "1.8", "--out", "x.urdf"), ("--mass-kg",)),
        Case("--height 18 (centimetres?)", "body",
             ("body", "--height-m", "180", "--mass-kg", "80", "--out", "x.urdf"),
             ("height 180", "0.5–2.5 m")),
        Case("--mass 0.08 (tonnes?)", "body",
             ("body", "--height-m", "1.8", "--mass-kg", "0.08", "--out", "x.urdf"),
             ("mass 0.08", "10–300 kg")),
    ]


def all_cases() -> list[Case]:
    cases = (_protocol_cases() + _design_cases() + _column_cases() + _cohort_cases()
             + _universal_cases() + _evaluate_cases() + _frf_fit_cases() + _body_cases()
             + newest_cases())
    names = [c.name for c in cases]
    duplicates = {n for n in names if names.count(n) > 1}
    if duplicates:
        raise ValueError(f"case names used twice: {sorted(duplicates)}")
    return cases
