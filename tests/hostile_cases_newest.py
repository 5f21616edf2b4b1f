"""Hostile input for the newest commands: C3D trials, the IC model's fit,
simulation and design, ``compare`` (one recording, two amplitudes, a cohort), ``norm build``
(FRF JSONs, a CSV table, MATLAB files), ``norm test`` (FRF JSONs and recordings), ``norm
compare``, a cohort's norm columns, and a DEC command given the IC model's files or names.

The cases and the material they share; :mod:`hostile_cases` runs them with its own (the
outcomes, the report and the journal are its). Each case is a mistake a new user makes:
a wrong axis, unit or model the data give away, a file cut short or of another kind, a
norm or an FRF edited by hand, two groups or two amplitudes that are one.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

from hostile_harness import Case

__all__ = ["make_newest_material", "newest_cases"]

ROOT = Path(__file__).resolve().parents[1]

EXAMPLES = ROOT / "posture_id" / "studies" / "examples"
ONE_SEGMENT = ROOT / "urdf" / "winter_1.75m_70kg_1seg.urdf"
#: The example C3D trial's markers and tilt channel, as its tutorial reads it.
C3D_FLAGS = ("--segment-markers", "leg=LANK+RANK,LHIP+RHIP", "trunk=LHIP+RHIP,LSHO+RSHO",
             "--tilt-channel", "platform_angle", "--tilt-scale", "2")
C3D = (*C3D_FLAGS, "--forward-axis=-y")
#: Hz, the points of the FRFs (Peterka's eleven, as ``frf --band-preset peterka11``).
FREQUENCIES = ("0.05", "0.15", "0.3", "0.4", "0.55", "0.7", "0.9", "1.1", "1.35", "1.75",
               "2.2")


def make_newest_material(root: Path, paths: dict[str, str],
                         run: Callable[[list[str]], int]) -> None:
    """Add to ``paths`` what the newest commands' cases read, made in ``root``: four TIP
    subjects' FRFs at Peterka's points (JSON each, a CSV table, MATLAB files of one
    channel), norms of them, an IC parameter file, a one-segment recording and a cohort
    compared from it; ``run`` runs a command line quietly (its exit status 0 or an
    error)."""
    import numpy as np
    from scipy.io import savemat

    from posture_id import load_body
    from posture_id.models.ic import IcPlant, default_ic_parameters

    paths["c3d"] = str(EXAMPLES / "straight_leg_subject.c3d")
    paths["dec_params"] = str(EXAMPLES / "tip_subject.truth.json")
    paths["one_urdf"] = str(ONE_SEGMENT)
    frfs = []
    for k in range(1, 5):
        rec = root / f"subject{k}.csv"
        frf = root / f"subject{k}.frf.json"
        if not frf.exists():
            run(["simulate", "--motor-noise", "0.3", "--sensor-noise-deg", "0.05", "--seed",
                         str(k), "--out", str(rec)])
            run(["frf", str(rec), "--body", paths["tip_urdf"], "--band-preset",
                         "peterka11", "--lab-convention", "--out", str(frf)])
        frfs.append(frf)
    paths.update({f"frf{k}": str(p) for k, p in enumerate(frfs, 1)})
    paths["recording2"] = str(root / "subject2.csv")
    norms = {"norm": ("--channel", "body COM"), "norm_segments": ("--channel", "shank",
                                                                  "thigh", "trunk")}
    for name, channels in norms.items():
        target = root / f"{name}.json"
        if not target.exists():
            run(["norm", "build", *map(str, frfs), *channels, "--bootstrap", "50",
                         "--out", str(target)])
        paths[name] = str(target)
    f, com = _com_frfs(frfs)
    table = root / "table.csv"
    if not table.exists():
        cells = [",".join(f"{float(h.real)!r},{float(h.imag)!r}" for h in row) for row in com]
        table.write_text("subject," + ",".join(f"{x:g}_re,{x:g}_im" for x in f) + "\n"
                         + "".join(f"s{i},{c}\n" for i, c in enumerate(cells)),
                         encoding="utf-8")
    paths["table"] = str(table)
    mat = root / "group.mat"
    if not mat.exists():
        savemat(mat, {"H": com, "G": np.abs(com)})
    paths["mat"] = str(mat)
    ic = root / "ic_params.json"
    if not ic.exists():
        default_ic_parameters(IcPlant.of(load_body()).mgh).to_json(ic)
    paths["ic_params"] = str(ic)
    one = root / "one_segment"
    if not (one / "s1.csv").exists():
        one.mkdir(exist_ok=True)
        run(["simulate", "--body", str(ONE_SEGMENT), "--sensor-noise-deg", "0.02",
                     "--cycles", "2", "--out", str(one / "s1.csv")])
    other = root / "one_segment_again.csv"
    if not other.exists():
        run(["simulate", "--body", str(ONE_SEGMENT), "--sensor-noise-deg", "0.02",
                     "--cycles", "2", "--seed", "7", "--motor-noise", "0.2", "--out",
                     str(other)])
    paths["one_rec_again"] = str(other)
    paths["one_rec"] = str(one / "s1.csv")
    paths["one_dir"] = str(one)
    compared = root / "compared"
    if not (compared / "summary.csv").exists():
        run(["compare", str(one), "--body", str(ONE_SEGMENT), "--no-held-out",
                     "--starts", "1", "--out", str(compared)], allowed=(0, 1))
    paths["compared"] = str(compared)


def _com_frfs(frfs: list[Path]):
    """(frequencies (F,), body COM FRFs (N, F) complex) of the FRF JSONs."""
    import numpy as np

    rows = []
    for path in frfs:
        data = json.loads(path.read_text(encoding="utf-8"))
        c = data["channels"]["body COM"]
        rows.append(np.asarray(c["gain"]) * np.exp(1j * np.radians(c["phase_deg"])))
    return np.asarray(data["frequencies_hz"]), np.asarray(rows)


# ------------------------------------------------------------------------- file texts
def _edited(material_key: str, edit) -> str:
    """A marker: the material JSON ``material_key`` with ``edit(data)`` applied (written
    when the case's folder is built; see :func:`hostile_harness.run_case`)."""
    return ("edit", material_key, edit)


def _set(**changes):
    def edit(data):
        data.update(changes)
        return data
    return edit


def _nan_in_mean(data):
    data["mean_re_im"][3] = float("nan")
    return data


def _nan_in_covariance(data):
    data["covariance"][0][0] = float("nan")
    return data


def _short_pir(data):
    data["pir"]["mean"] = data["pir"]["mean"][:-5]
    data["pir"]["sd"] = data["pir"]["sd"][:-5]
    return data


def _nan_gain(data):
    data["channels"]["body COM"]["gain"][2] = float("nan")
    return data


def _re_without_im(data):
    c = data["channels"]["body COM"]
    data["channels"]["body COM"] = {"re": c["gain"]}
    return data


def _short_gain(data):
    data["channels"]["body COM"]["gain"] = data["channels"]["body COM"]["gain"][:-2]
    return data


def _other_points(data):
    data["frequencies_hz"] = [f * 1.5 for f in data["frequencies_hz"]]
    return data


def _no_lab_points(data):
    """A norm that does not say its bands, at points no preset has."""
    data["lab_bands"] = None
    data["frequencies_hz"] = [f * 1.5 for f in data["frequencies_hz"]]
    data["pir"] = None  # a norm as labs publish it: summary statistics only
    return data


def _com_only(data):
    data["channels"] = {"body COM": data["channels"]["body COM"]}
    return data


def _table_extra_field(text: str) -> str:
    lines = text.splitlines()
    lines[2] += ",0.5"
    return "\n".join(lines) + "\n"


def _table_short_row(text: str) -> str:
    lines = text.splitlines()
    lines[2] = lines[2].rsplit(",", 1)[0]
    return "\n".join(lines) + "\n"


def _table_nan(text: str) -> str:
    lines = text.splitlines()
    cells = lines[3].split(",")
    cells[4] = "nan"
    lines[3] = ",".join(cells)
    return "\n".join(lines) + "\n"


def _table_header_only(text: str) -> str:
    return text.splitlines()[0] + "\n"


#: A MATLAB v7.3 file: an HDF5 file behind MATLAB's 128-byte text header, at offset 512.
MAT73 = (b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Fri Nov 27 10:00:00 2026 "
         b"HDF5 schema 1.00 .".ljust(116) + b"\x00" * 8 + b"\x00\x02IM").ljust(512, b"\x00") \
    + b"\x89HDF\r\n\x1a\n" + b"\x00" * 600


# ------------------------------------------------------------------------- the cases
def _norm_build_cases() -> list[Case]:
    build = ("norm", "build")
    frfs = ("{frf1}", "{frf2}", "{frf3}", "{frf4}")
    mat = ("--variable", "H", "--frequencies", *FREQUENCIES)
    return [
        Case("a MATLAB v7.3 (HDF5) file", "norm build",
             (*build, "g.mat", *mat, "--out", "n.json"), ("g.mat", "v7.3"), {"g.mat": MAT73}),
        Case("a truncated .mat", "norm build", (*build, "g.mat", *mat, "--out", "n.json"),
             ("g.mat", "truncated"), {"g.mat": ("cut", "mat", 300)}),
        Case("a .mat of real numbers (gains alone)", "norm build",
             (*build, "{mat}", "--variable", "G", "--frequencies", *FREQUENCIES, "--out",
              "n.json"), ("group.mat", "G", "real")),
        Case("a .mat variable it lacks", "norm build",
             (*build, "{mat}", "--variable", "FRF", "--frequencies", *FREQUENCIES, "--out",
              "n.json"), ("group.mat", "'FRF'")),
        Case("a .mat with too few --frequencies", "norm build",
             (*build, "{mat}", "--variable", "H", "--frequencies", "0.1", "0.2", "--out",
              "n.json"), ("group.mat", "2 frequencies")),
        Case("a .mat without --variable", "norm build", (*build, "{mat}", "--out", "n.json"),
             ("group.mat", "--variable")),
        Case("a .mat that is a text file", "norm build",
             (*build, "g.mat", *mat, "--out", "n.json"), ("g.mat", "MATLAB"),
             {"g.mat": "subject,0.1_re\n"}),
        Case("a table row with one field too many", "norm build",
             (*build, "t.csv", "--out", "n.json"), ("t.csv", "line 3", "fields"),
             {"t.csv": ("text", "table", _table_extra_field)}),
        Case("a table row with one field too few", "norm build",
             (*build, "t.csv", "--out", "n.json"), ("t.csv", "line 3", "fields"),
             {"t.csv": ("text", "table", _table_short_row)}),
        Case("a table cell that is NaN", "norm build", (*build, "t.csv", "--out", "n.json"),
             ("t.csv", "line 4", "not finite"), {"t.csv": ("text", "table", _table_nan)}),
        Case("a table with a header and no subjects", "norm build",
             (*build, "t.csv", "--out", "n.json"), ("t.csv", "no subjects"),
             {"t.csv": ("text", "table", _table_header_only)}),
        Case("a table without FRF columns", "norm build", (*build, "t.csv", "--out", "n.json"),
             ("t.csv", "no FRF columns"), {"t.csv": "subject,gain\ns1,1\ns2,2\ns3,3\n"}),
        Case("an FRF JSON with a NaN gain", "norm build",
             (*build, "{frf1}", "{frf2}", "bad.frf.json", "--out", "n.json"),
             ("bad.frf.json", "body COM", "not finite"),
             {"bad.frf.json": _edited("frf3", _nan_gain)}),
        Case("an FRF JSON with re and no im", "norm build",
             (*build, "{frf1}", "{frf2}", "bad.frf.json", "--out", "n.json"),
             ("bad.frf.json", "body COM", "im"),
             {"bad.frf.json": _edited("frf3", _re_without_im)}),
        Case("an FRF JSON with fewer gains than frequencies", "norm build",
             (*build, "{frf1}", "{frf2}", "bad.frf.json", "--out", "n.json"),
             ("bad.frf.json", "body COM", "9 values", "11 frequencies"),
             {"bad.frf.json": _edited("frf3", _short_gain)}),
        Case("an identify result as a member", "norm build",
             (*build, "{frf1}", "{frf2}", "r.json", "--out", "n.json"),
             ("r.json", "not an FRF file"),
             {"r.json": json.dumps({"parameters": {}, "intervals": {}})}),
        Case("members at other frequencies", "norm build",
             (*build, "{frf1}", "{frf2}", "other.frf.json", "--out", "n.json"),
             ("other.frf.json", "other frequencies"),
             {"other.frf.json": _edited("frf3", _other_points)}),
        Case("the same member twice", "norm build",
             (*build, "{frf1}", "{frf2}", "{frf1}", "--out", "n.json"),
             ("subject1.frf.json", "twice")),
        Case("two members", "norm build", (*build, "{frf1}", "{frf2}", "--out", "n.json"),
             ("at least 3 members",)),
        Case("a channel the FRFs lack", "norm build",
             (*build, *frfs, "--channel", "COM", "--out", "n.json"),
             ("subject1.frf.json", "'COM'")),
        Case("--weights of another length", "norm build",
             (*build, *frfs, "--channel", "body COM", "--weights", "1", "2", "--out",
              "n.json"), ("--weights", "11 frequencies")),
        Case("--level 1.5", "norm build", (*build, *frfs, "--level", "1.5", "--out", "n.json"),
             ("level", "1.5")),
        Case("--bootstrap 5", "norm build", (*build, *frfs, "--bootstrap", "5", "--out",
                                             "n.json"), ("--bootstrap 5",)),
        Case("--out over a member", "norm build",
             (*build, "a.frf.json", "{frf2}", "{frf3}", "--out", "a.frf.json"),
             ("a.frf.json", "input"), {"a.frf.json": "@frf1"}),
        Case("a member that is a folder", "norm build",
             (*build, "{frf1}", "{frf2}", "m.frf.json", "--out", "n.json"),
             ("m.frf.json", "folder"), {"m.frf.json/": ""}),
        Case("a JSON and a table together", "norm build",
             (*build, "{frf1}", "{table}", "--out", "n.json"), ("not .csv, .json together",)),
    ]


def _norm_file_cases() -> list[Case]:
    test = ("norm", "test", "{frf1}", "--norm", "n.json")
    return [
        Case("a norm whose mean holds NaN", "norm test", test, ("n.json", "mean_re_im",
                                                                "not finite"),
             {"n.json": _edited("norm", _nan_in_mean)}),
        Case("a norm whose covariance holds NaN", "norm test", test,
             ("n.json", "covariance", "not finite"),
             {"n.json": _edited("norm", _nan_in_covariance)}),
        Case("a norm whose members are a word", "norm test", test, ("n.json", "members"),
             {"n.json": _edited("norm", _set(members="twelve"))}),
        Case("a norm whose channels are a word", "norm test", test, ("n.json", "channels"),
             {"n.json": _edited("norm", _set(channels="body COM"))}),
        Case("a norm whose level is a word", "norm test", test, ("n.json", "level"),
             {"n.json": _edited("norm", _set(prediction_band={"constant": 3.0,
                                                              "level": "high",
                                                              "bootstrap": 50}))}),
        Case("a norm whose PIRs are shorter than its members'", "norm test", test,
             ("n.json", "pir"), {"n.json": _edited("norm", _short_pir)}),
        Case("a norm whose lab bands are a word", "norm test",
             ("norm", "test", "{rec}", "--norm", "n.json"), ("n.json", "lab_bands"),
             {"n.json": _edited("norm", _set(lab_bands="peterka"))}),
        Case("a norm without a covariance", "norm test", test, ("n.json", "covariance"),
             {"n.json": _edited("norm", _set(covariance=None))}),
        Case("a norm whose weights are too few", "norm test", test, ("n.json", "weights"),
             {"n.json": _edited("norm", _set(weights=[1.0, 2.0]))}),
        Case("an FRF JSON given as the norm", "norm test",
             ("norm", "test", "{frf1}", "--norm", "{frf2}"), ("subject2.frf.json", "norm")),
        Case("a norm that is not JSON", "norm test", test, ("n.json", "not valid JSON"),
             {"n.json": "members: 12\n"}),
        Case("no such norm (norm test)", "norm test", test, ("n.json", "no such")),
        Case("an FRF at other points than the norm's", "norm test",
             ("norm", "test", "other.frf.json", "--norm", "{norm}"),
             ("other.frf.json", "the norm's"),
             {"other.frf.json": _edited("frf1", _other_points)}),
        Case("an FRF without the norm's channels", "norm test",
             ("norm", "test", "f.frf.json", "--norm", "{norm_segments}"),
             ("f.frf.json", "'shank'"), {"f.frf.json": _edited("frf1", _com_only)}),
        Case("a recording without the norm's channels", "norm test",
             ("norm", "test", "{lab}", "--norm", "{norm_segments}", "--body", "{winter2}",
              "--time-column", "Time", "--tilt-column", "Platform", "--angle-columns",
              "Legs", "Trunk"), ("lab2.csv", "shank")),
        Case("a recording against a norm of no lab points", "norm test",
             ("norm", "test", "{rec}", "--norm", "n.json"), ("n.json", "--band-preset"),
             {"n.json": _edited("norm", _no_lab_points)}),
        Case("--out over the norm", "norm test",
             ("norm", "test", "{frf1}", "--norm", "n.json", "--out", "n.json"),
             ("n.json", "input"), {"n.json": "@norm"}),
        Case("--plot over --out", "norm test",
             ("norm", "test", "{frf1}", "--norm", "{norm}", "--out", "t.png", "--plot",
              "t.png"), ("t.png",)),
        Case("a C3D without --forward-axis", "norm test",
             ("norm", "test", "{c3d}", "--norm", "{norm}", *C3D_FLAGS), ("--forward-axis",)),
        Case("a C3D with --tilt-column", "norm test",
             ("norm", "test", "{c3d}", "--norm", "{norm}", *C3D, "--tilt-column", "plate"),
             ("--tilt-column", "C3D")),
    ]


def _norm_compare_cases() -> list[Case]:
    compare = ("norm", "compare")
    return [
        Case("two groups of the same members", "norm compare",
             (*compare, "--group", "{frf1}", "{frf2}", "--group", "{frf1}", "{frf2}",
              "--out", "c.json"), ("subject1.frf.json", "both groups")),
        Case("a member in both groups", "norm compare",
             (*compare, "--group", "{frf1}", "{frf2}", "--group", "{frf2}", "{frf3}",
              "--out", "c.json"), ("subject2.frf.json", "both groups")),
        Case("copies of one group's members as the other", "norm compare",
             (*compare, "--group", "{frf1}", "{frf2}", "--group", "a.frf.json", "b.frf.json",
              "--out", "c.json"), ("a.frf.json", "same FRF"),
             {"a.frf.json": "@frf1", "b.frf.json": "@frf2"}),
        Case("one group", "norm compare", (*compare, "--group", "{frf1}", "{frf2}", "--out",
                                           "c.json"), ("two groups",)),
        Case("three groups", "norm compare",
             (*compare, "--group", "{frf1}", "--group", "{frf2}", "--group", "{frf3}",
              "--out", "c.json"), ("two groups", "3")),
        Case("a group of one", "norm compare",
             (*compare, "--group", "{frf1}", "--group", "{frf2}", "{frf3}", "--out",
              "c.json"), ("at least 2 members",)),
        Case("groups at different frequencies", "norm compare",
             (*compare, "--group", "{frf1}", "{frf2}", "--group", "{frf3}", "o.frf.json",
              "--out", "c.json"), ("o.frf.json", "other frequencies"),
             {"o.frf.json": _edited("frf4", _other_points)}),
        Case("groups of different channels", "norm compare",
             (*compare, "--group", "{frf1}", "{frf2}", "--group", "{table}", "--out",
              "c.json"), ("channels",)),
        Case("--out over a member (compare)", "norm compare",
             (*compare, "--group", "a.frf.json", "{frf2}", "--group", "{frf3}", "{frf4}",
              "--out", "a.frf.json"), ("a.frf.json", "input"), {"a.frf.json": "@frf1"}),
    ]


def _cohort_norm_cases() -> list[Case]:
    recs = {"recs/a.csv": "@rec", "recs/b.csv": "@recording2"}
    labs = {"recs/a.csv": "@lab", "recs/b.csv": "@lab"}
    columns = ("--body", "{winter2}", "--time-column", "Time", "--tilt-column", "Platform",
               "--angle-columns", "Legs", "Trunk")
    return [
        Case("a norm of channels the recordings lack", "cohort norm",
             ("identify", "recs", "--out", "o", "--method", "cnn", "--norm", "{norm_segments}",
              *columns), ("norm_segments.json", "shank", "leg"), labs),
        Case("a cohort's norm whose mean holds NaN", "cohort norm",
             ("identify", "recs", "--out", "o", "--method", "cnn", "--norm", "n.json"),
             ("n.json", "not finite"), {**recs, "n.json": _edited("norm", _nan_in_mean)}),
        Case("no such norm (cohort)", "cohort norm",
             ("identify", "recs", "--out", "o", "--method", "cnn", "--norm", "n.json"),
             ("n.json", "no such"), recs),
        Case("a norm at no preset's points without --band-preset", "cohort norm",
             ("identify", "recs", "--out", "o", "--method", "cnn", "--norm", "n.json"),
             ("n.json", "--band-preset"),
             {**recs, "n.json": _edited("norm", _no_lab_points)}),
        Case("--norm with one recording", "cohort norm",
             ("identify", "{rec}", "--method", "cnn", "--norm", "{norm}"), ("--norm",)),
    ]


def _c3d_cases() -> list[Case]:
    identify = ("identify", "{c3d}", "--method", "cnn")
    return [
        Case("a forward axis across the subject", "c3d",
             (*identify, *C3D_FLAGS, "--forward-axis", "x"), ("--forward-axis", "x", "y")),
        Case("a forward axis across the subject (frf)", "c3d",
             ("frf", "{c3d}", *C3D_FLAGS, "--forward-axis=-x", "--out", "f.json"),
             ("--forward-axis", "-x", "y")),
        Case("a forward axis the wrong way round", "c3d",
             (*identify, *C3D_FLAGS, "--forward-axis", "y"),
             ("--forward-axis the other way round",), handled=True),
        Case("--tilt-column on a C3D", "c3d", (*identify, *C3D, "--tilt-column", "plate"),
             ("--tilt-column", "C3D")),
        Case("--time-column on a C3D", "c3d", (*identify, *C3D, "--time-column", "t"),
             ("--time-column", "C3D")),
        Case("--units on a C3D", "c3d", (*identify, *C3D, "--units", "rad"),
             ("--units", "C3D")),
        Case("no --forward-axis", "c3d", (*identify, *C3D_FLAGS), ("--forward-axis",)),
        Case("a marker not in the file", "c3d",
             (*identify, "--segment-markers", "leg=LANK+RANK,LTRO+RTRO",
              "trunk=LHIP+RHIP,LSHO+RSHO", "--forward-axis=-y"), ("LTRO", "LHIP")),
        Case("a segment without '='", "c3d",
             (*identify, "--segment-markers", "LANK,LHIP", "LHIP,LSHO", "--forward-axis=-y"),
             ("LANK,LHIP", "SEGMENT=LOWER,UPPER")),
        Case("three segments for a two-segment subject", "c3d",
             (*identify, "--segment-markers", "shank=LANK,LKNE", "thigh=LKNE,LHIP",
              "trunk=LHIP,LSHO", "--forward-axis=-y"), ("LKNE",)),
        Case("the upper marker first", "c3d",
             (*identify, "--segment-markers", "leg=LHIP+RHIP,LANK+RANK",
              "trunk=LHIP+RHIP,LSHO+RSHO", "--forward-axis=-y"), ("leans", "lower point")),
        Case("--vertical-axis y", "c3d", (*identify, *C3D, "--vertical-axis", "y"),
             ("--vertical-axis",)),
        Case("--tilt-channel not in the file", "c3d",
             (*identify, "--segment-markers", "leg=LANK+RANK,LHIP+RHIP",
              "trunk=LHIP+RHIP,LSHO+RSHO", "--tilt-channel", "tilt", "--forward-axis=-y"),
             ("'tilt'", "platform_angle")),
        Case("--tilt-markers and --tilt-channel", "c3d",
             (*identify, *C3D, "--tilt-markers", "PLATB,PLATF"), ("--tilt-markers",
                                                                 "--tilt-channel")),
        Case("the platform markers front first", "c3d",
             (*identify, "--segment-markers", "leg=LANK+RANK,LHIP+RHIP",
              "trunk=LHIP+RHIP,LSHO+RSHO", "--tilt-markers", "PLATF,PLATB",
              "--forward-axis=-y"), ("PLATF", "back marker first")),
        Case("--max-gap-s shorter than the file's gap", "c3d",
             (*identify, *C3D, "--max-gap-s", "0.02"), ("LHIP", "0.02")),
        Case("a C3D cut short", "c3d",
             ("identify", "t.c3d", "--method", "cnn", *C3D), ("t.c3d", "truncated"),
             {"t.c3d": ("cut", "c3d", 4000)}),
        Case("a text file named .c3d", "c3d", ("identify", "t.c3d", "--method", "cnn", *C3D),
             ("t.c3d", "not a C3D file"), {"t.c3d": "time_s,tilt_deg\n0,0\n"}),
        Case("marker flags on a CSV", "c3d", ("identify", "{rec}", "--method", "cnn", *C3D),
             ("tip.csv",)),
        Case("--body of three segments for two segment angles", "c3d",
             (*identify, *C3D, "--body", "{tip_urdf}"), ("2 segment", "3")),
    ]


def _simulate_c3d_cases() -> list[Case]:
    sim = ("simulate", "--out", "t.c3d")
    return [
        Case("height in centimetres", "simulate c3d",
             (*sim, "--height-m", "175", "--mass-kg", "70"),
             ("--height-m 175", "metres")),
        Case("mass in grams", "simulate c3d",
             (*sim, "--height-m", "1.75", "--mass-kg", "70000"),
             ("--mass-kg 70000", "kg")),
        Case("a gap of negative length", "simulate c3d",
             (*sim, "--marker-gap", "LHIP", "40", "-1"), ("--marker-gap", "LHIP", "-1")),
        Case("a gap of no length", "simulate c3d", (*sim, "--marker-gap", "LHIP", "40", "0"),
             ("--marker-gap", "LHIP", "0")),
        Case("a gap after the trial ends", "simulate c3d",
             (*sim, "--marker-gap", "LHIP", "400", "1"), ("--marker-gap", "400", "ends")),
        Case("a gap before the trial starts", "simulate c3d",
             (*sim, "--marker-gap", "LHIP", "-5", "1"), ("--marker-gap", "-5")),
        Case("a gap of a marker not written", "simulate c3d",
             (*sim, "--marker-gap", "NOPE", "4", "1"), ("NOPE",)),
        Case("a gap of words", "simulate c3d", (*sim, "--marker-gap", "LHIP", "start", "1"),
             ("--marker-gap", "numbers")),
        Case("C3D flags with a CSV", "simulate c3d",
             ("simulate", "--out", "t.csv", "--marker-noise-mm", "0.3"),
             ("--marker-noise-mm", "NAME.c3d")),
    ]


def _ic_cases() -> list[Case]:
    return [
        Case("design --model ic with no noise at all", "ic",
             ("design", "--model", "ic", "--sensor-noise-deg", "0", "--draws", "1", "--out",
              "d", "--quiet"), ("--sensor-noise-deg 0", "noise")),
        Case("design with no noise at all", "ic",
             ("design", "--sensor-noise-deg", "0", "--draws", "1", "--out", "d", "--quiet"),
             ("sensor_noise_deg", "noise")),
        Case("an IC parameter file to simulate without --model ic", "ic",
             ("simulate", "--params", "{ic_params}", "--out", "s.csv"),
             ("ic_params.json", "--model ic")),
        Case("an IC parameter file as fit's --init", "ic",
             ("fit", "{rec}", "--init", "{ic_params}", "--out", "f.json"),
             ("ic_params.json", "--model ic")),
        Case("identify --model ic with --method", "ic",
             ("identify", "{rec}", "--model", "ic", "--method", "cnn"),
             ("--method", "--model ic")),
        Case("identify --model ic on a cohort", "ic",
             ("identify", "recs", "--model", "ic", "--out", "o"), ("recs", "compare DIR"),
             {"recs/a.csv": "@rec"}),
        Case("identify --model with a network's folder", "ic",
             ("identify", "{rec}", "--model", "nets/none", "--method", "cnn"),
             ("nets/none", "no such")),
        Case("identify --model misspelt", "ic",
             ("identify", "{rec}", "--model", "icm", "--method", "cnn"),
             ("--model", "'icm'", "'ic'")),
        Case("a DEC parameter file with --model ic", "ic",
             ("simulate", "--model", "ic", "--params", "{dec_params}", "--out", "s.csv"),
             ("tip_subject.truth.json", "\"ic\"")),
        Case("--deadband-rad-s with --model ic", "ic",
             ("simulate", "--model", "ic", "--deadband-rad-s", "0.01", "--out", "s.csv"),
             ("--deadband-rad-s",)),
        Case("fit --model ic --locked", "ic",
             ("fit", "{rec}", "--model", "ic", "--locked", "--out", "f.json"), ("--locked",)),
        Case("fit --model ic --init", "ic",
             ("fit", "{rec}", "--model", "ic", "--init", "{ic_params}", "--out", "f.json"),
             ("--init",)),
        Case("--fit-ki without --model ic", "ic",
             ("fit", "{rec}", "--fit-ki", "--out", "f.json"), ("--fit-ki", "--model ic")),
        Case("IC parameters with W 1.5", "ic",
             ("simulate", "--model", "ic", "--params", "p.json", "--out", "s.csv"),
             ("p.json", "w", "0–1"), {"p.json": _edited("ic_params", _set(w=1.5))}),
        Case("IC parameters with a delay in ms", "ic",
             ("simulate", "--model", "ic", "--params", "p.json", "--out", "s.csv"),
             ("p.json", "delay_s"), {"p.json": _edited("ic_params", _set(delay_s=120))}),
        Case("IC parameters with a field unknown", "ic",
             ("simulate", "--model", "ic", "--params", "p.json", "--out", "s.csv"),
             ("p.json", "gain"), {"p.json": _edited("ic_params", _set(gain=2.0))}),
        Case("IC parameters with Kp a word", "ic",
             ("simulate", "--model", "ic", "--params", "p.json", "--out", "s.csv"),
             ("p.json", "kp"), {"p.json": _edited("ic_params", _set(kp="high"))}),
        Case("design --model ic with --goal", "ic",
             ("design", "--model", "ic", "--goal", "kp", "--out", "d", "--quiet"),
             ("--goal", "DEC")),
    ]


def _compare_cases() -> list[Case]:
    one = ("--body", "{one_urdf}", "--no-held-out", "--starts", "1")
    return [
        Case("--second the recording itself", "compare",
             ("compare", "{one_rec}", "--second", "{one_rec}", *one, "--out", "c.json"),
             ("--second", "s1.csv", "itself")),
        Case("--second a copy of the recording", "compare",
             ("compare", "{one_rec}", "--second", "copy.csv", *one, "--out", "c.json"),
             ("copy.csv", "same samples"), {"copy.csv": "@one_rec"}),
        Case("--second at the same amplitude", "compare",
             ("compare", "{one_rec}", "--second", "{one_rec_again}", *one, "--out",
              "c.json"), ("one_segment_again.csv", "amplitude")),
        Case("--second missing", "compare",
             ("compare", "{one_rec}", "--second", "nothing.csv", *one, "--out", "c.json"),
             ("nothing.csv",)),
        Case("--second a file of other columns", "compare",
             ("compare", "{rec}", "--second", "{lab}", "--out", "c.json"), ("lab2.csv",)),
        Case("--second with a cohort", "compare",
             ("compare", "recs", "--second", "{rec}", "--out", "o"), ("--second",),
             {"recs/a.csv": "@rec"}),
        Case("--part with --second", "compare",
             ("compare", "{rec}", "--second", "{recording2}", "--part", "1", "--out",
              "c.json"), ("--part",)),
        Case("a cohort without --out", "compare", ("compare", "recs"), ("--out",),
             {"recs/a.csv": "@rec"}),
        Case("--plot with a compared cohort", "compare",
             ("compare", "recs", "--out", "o", "--plot", "p.png"), ("--plot",),
             {"recs/a.csv": "@rec"}),
        Case("--out over the compared recording", "compare",
             ("compare", "r.csv", "--out", "r.csv"),
             ("r.csv", "input"), {"r.csv": "@rec"}),
        Case("a cohort's --out holding the user's summary.csv", "compare",
             ("compare", "recs", "--out", "mine"), ("summary.csv", "did not write"),
             {"recs/a.csv": "@rec", "mine/summary.csv": "my,table\n"}),
        Case("a cohort compared again with other options", "compare",
             ("compare", "{one_dir}", *one, "--fit-ki", "--out", "o"),
             ("s1.csv", "--fit-ki", "compared again"), {"o": "@compared"}, handled=True,
             kept=("o",), limit_s=240),
    ]


def newest_cases() -> list[Case]:
    """Every case of the newest commands."""
    return (_norm_build_cases() + _norm_file_cases() + _norm_compare_cases()
            + _cohort_norm_cases() + _c3d_cases() + _simulate_c3d_cases() + _ic_cases()
            + _compare_cases())
