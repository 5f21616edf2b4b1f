"""Hostile input, through the command line: every bad file, folder and path gets one line
naming the file and the problem, exit status 2, no traceback, and no file of the user's
changed (nothing written either). Numeric flags: tests/test_cli_flags.py; checkpoints:
tests/test_learning.py.

Each case builds its files in a fresh folder, runs one command, and checks the folder's
files (name → SHA-256) are the same afterwards.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from posture_id.cli import main

# ------------------------------------------------------------------ shared material
URDF_HEAD = '<?xml version="1.0"?>\n<robot name="bad">\n<link name="foot"/>\n'
INERTIA = '<inertia ixx="0.2" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.01"/>'


def _inertial(mass="10", inertia=INERTIA):
    return f'<inertial><origin xyz="0 0 0.25"/><mass value="{mass}"/>{inertia}</inertial>'


def _link(name, inertial=None):
    return f'<link name="{name}">{_inertial() if inertial is None else inertial}</link>\n'


def _joint(name, parent, child, kind="revolute", axis="0 1 0", z=0.0):
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="0 0 {z}"/><axis xyz="{axis}"/>'
            '<limit lower="-1" upper="1" effort="1000" velocity="10"/></joint>\n')


def _urdf(body: str) -> str:
    return URDF_HEAD + body + "</robot>\n"


ONE = _link("shank") + _joint("ankle", "foot", "shank")

BAD_URDFS = {
    "empty": ("", "not well-formed XML"),
    "not_xml": ("robot: yes\n", "not well-formed XML"),
    "truncated": (URDF_HEAD + _link("shank"), "not well-formed XML"),
    "other_root": ('<?xml version="1.0"?><sdf version="1.6"/>', "root element is <sdf>"),
    "undefined_child": (_urdf(_joint("ankle", "foot", "shnak")),
                        "names child link 'shnak', which is not defined"),
    "undefined_parent": (_urdf(_link("shank") + _joint("ankle", "feet", "shank")),
                         "names parent link 'feet'"),
    "joint_without_child": (_urdf('<joint name="j" type="revolute"><parent link="foot"/>'
                                  '</joint>'), "joint 'j' has no <child"),
    "no_mass_element": (_urdf(_link("shank", f"<inertial>{INERTIA}</inertial>")
                              + _joint("ankle", "foot", "shank")), "has no <mass>"),
    "zero_mass": (_urdf(_link("shank", _inertial(mass="0")) + _joint("ankle", "foot", "shank")),
                  "mass must be > 0"),
    "negative_mass": (_urdf(_link("shank", _inertial(mass="-3"))
                            + _joint("ankle", "foot", "shank")), "mass must be > 0"),
    "nan_mass": (_urdf(_link("shank", _inertial(mass="nan")) + _joint("ankle", "foot", "shank")),
                 "is not finite"),
    "word_mass": (_urdf(_link("shank", _inertial(mass="heavy"))
                        + _joint("ankle", "foot", "shank")), "is not a number"),
    "no_inertia_element": (_urdf(_link("shank", '<inertial><mass value="10"/></inertial>')
                                 + _joint("ankle", "foot", "shank")), "no <inertia> element"),
    "negative_inertia": (_urdf(_link("shank", _inertial(inertia=INERTIA.replace(
        'ixx="0.2"', 'ixx="-0.2"'))) + _joint("ankle", "foot", "shank")),
        "not positive semi-definite"),
    "impossible_inertia": (_urdf(_link("shank", _inertial(inertia=INERTIA.replace(
        'izz="0.01"', 'izz="5"'))) + _joint("ankle", "foot", "shank")), "triangle inequality"),
    "prismatic": (_urdf(ONE + _link("thigh") + _joint("knee", "shank", "thigh", "prismatic",
                                                     "0 0 1", 0.5)), "prismatic"),
    "off_axis": (_urdf(ONE + _link("thigh") + _joint("knee", "shank", "thigh", axis="1 0 0",
                                                    z=0.5)), "off the common axis"),
    "vertical_axis": (_urdf(_link("shank") + _joint("ankle", "foot", "shank", axis="0 0 1")),
                      "not horizontal"),
    "branching": (_urdf(ONE + _link("l") + _link("r") + _joint("hl", "shank", "l", z=0.5)
                        + _joint("hr", "shank", "r", z=0.5)), "serial chain"),
    "no_joint": (_urdf(""), "no moving joint"),
    "hanging": (_urdf(_link("shank", _inertial().replace('xyz="0 0 0.25"', 'xyz="0 0 -0.25"'))
                      + _joint("ankle", "foot", "shank")), "must stand upright"),
}


def _written(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


def _tree_digest(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def _run(folder: Path, argv: list[str], capsys, problem: str, names: str | None = None):
    """Run; assert exit 2, one line naming ``names`` (a path) and ``problem``, no
    traceback, and the folder's files unchanged."""
    before = _tree_digest(folder)
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2, (argv, err)
    assert err.count("\n") == 1 and err.startswith("posture-id"), err
    assert "Traceback" not in err
    assert problem in err, (problem, err)
    if names is not None:
        assert names in err, (names, err)
    assert _tree_digest(folder) == before, "a file of the user's changed or appeared"


@pytest.fixture(scope="module")
def recording_lines(tmp_path_factory):
    """The lines of a valid 121 s TIP recording CSV (default parameters)."""
    from posture_id import load_body, simulate

    path = tmp_path_factory.mktemp("rec") / "rec.csv"
    simulate(load_body()).to_csv(path)
    return path.read_text().splitlines()


# ------------------------------------------------------------------ URDF files
@pytest.mark.parametrize("case", sorted(BAD_URDFS))
def test_bad_urdf(tmp_path, capsys, case):
    text, problem = BAD_URDFS[case]
    path = tmp_path / f"{case}.urdf"
    path.write_text(text)
    _run(tmp_path, ["body", str(path)], capsys, problem, names=str(path))


@pytest.mark.parametrize(("setup", "problem"), [
    (lambda d: d / "missing.urdf", "no such URDF file"),
    (lambda d: (d / "folder.urdf").mkdir() or d / "folder.urdf", "is a folder"),
    (lambda d: _written(d / "w.urdf", _urdf(ONE).replace("bad", "b\xe9").encode("cp1252")),
     "not UTF-8"),
])
def test_urdf_file_itself(tmp_path, capsys, setup, problem):
    path = setup(tmp_path)
    _run(tmp_path, ["simulate", "--body", str(path), "--out", str(tmp_path / "o.csv")],
         capsys, problem, names=str(path))


# ------------------------------------------------------------------ parameter files
def _params(tip_joints=("ankle", "knee", "hip")):
    return {j: {"kp": 400.0, "ki": 10.0, "kd": 100.0, "delay_s": 0.1, "controls": "com"}
            for j in tip_joints}


PARAMETER_CASES = {
    "not_json": ("{kp: 1}", "not valid JSON"),
    "empty": ("", "not valid JSON"),
    "a_list": ("[1, 2, 3]", "expected a JSON object"),
    "missing_module": (lambda p: p.pop("knee"), "module 'knee' is missing"),
    "unknown_module": (lambda p: p.update(elbow=p["hip"]), "module 'elbow' is not a joint"),
    "missing_field": (lambda p: p["hip"].pop("kd"), "field 'kd' is missing"),
    "unknown_field": (lambda p: p["hip"].update(gain=1), "unknown field 'gain'"),
    "word_value": (lambda p: p["ankle"].update(kp="high"), "field 'kp' must be a number"),
    "bool_value": (lambda p: p["ankle"].update(ki=True), "field 'ki' must be a number"),
    "negative": (lambda p: p["knee"].update(kd=-1), "field 'kd' is negative"),
    "nan": ('{"ankle": {"kp": NaN}}', "not finite"),
    "bad_class": (lambda p: p["hip"].update(controls="trunk"), "field 'controls'"),
    "class_list": (lambda p: p["hip"].update(controls=["com"]), "field 'controls' must be"),
    "delay_in_ms": (lambda p: p["hip"].update(delay_s=121), "longer than the 2 s supported"),
    "module_not_object": (lambda p: p.update(hip=5), "expected an object"),
}


@pytest.mark.parametrize("case", sorted(PARAMETER_CASES))
def test_bad_parameter_file(tmp_path, capsys, case):
    content, problem = PARAMETER_CASES[case]
    if callable(content):
        data = _params()
        content(data)
        content = json.dumps(data)
    path = tmp_path / "params.json"
    if case == "nan":
        data = _params()
        data["ankle"]["kp"] = float("nan")
        content = json.dumps(data)
    path.write_text(content)
    _run(tmp_path, ["simulate", "--params", str(path), "--out", str(tmp_path / "o.csv")],
         capsys, problem, names=str(path))


@pytest.mark.parametrize(("setup", "problem"), [
    (lambda d: d / "missing.json", "no such parameter file"),
    (lambda d: (d / "p.json").mkdir() or d / "p.json", "is a folder"),
    (lambda d: _written(d / "p.json", b'{"ankle": "\xe9"}'), "not UTF-8"),
])
def test_parameter_file_itself(tmp_path, capsys, setup, problem):
    path = setup(tmp_path)
    _run(tmp_path, ["simulate", "--params", str(path), "--out", str(tmp_path / "o.csv")],
         capsys, problem, names=str(path))


# ------------------------------------------------------------------ recordings
def _edit(lines, row=None, column=None, value=None):
    out = list(lines)
    if row is not None:
        cells = out[row].split(",")
        cells[column] = value
        out[row] = ",".join(cells)
    return out


RECORDING_CASES = {
    "empty": (lambda ls: [], "empty file"),
    "header_only": (lambda ls: ls[:1], "a header and no data rows"),
    "one_row": (lambda ls: ls[:2], "fewer than two samples"),
    "no_time": (lambda ls: [ls[0].replace("time_s", "t")] + ls[1:],
                "header must start with 'time_s,tilt_deg'"),
    "tilt_missing": (lambda ls: [",".join(c for i, c in enumerate(r.split(",")) if i != 1)
                                 for r in ls], "no 'tilt_deg' column after time_s; name the "
                                               "stimulus"),
    "misnamed_segment": (lambda ls: [ls[0].replace("thigh_deg", "femur_deg")] + ls[1:],
                         "do not match the body's segments"),
    "segment_without_unit": (lambda ls: [ls[0].replace("trunk_deg", "trunk")] + ls[1:],
                             "column 'trunk' is not '<segment>_deg'"),
    "extra_column": (lambda ls: [r + (",hat_deg" if i == 0 else ",0") for i, r in
                                 enumerate(ls)], "do not match the body's segments"),
    "missing_segment": (lambda ls: [r.rsplit(",", 1)[0] for r in ls],
                        "do not match the body's segments"),
    "nan_cell": (lambda ls: _edit(ls, 100, 3, "nan"), "line 101, column 'thigh_deg'"),
    "inf_cell": (lambda ls: _edit(ls, 7, 2, "inf"), "is not a finite number"),
    "text_cell": (lambda ls: _edit(ls, 5, 4, "n/a"), "not a number ('n/a')"),
    "empty_cell": (lambda ls: _edit(ls, 5, 4, ""), "not a number ('')"),
    "ragged_row": (lambda ls: ls[:10] + [ls[10] + ",1"] + ls[11:], "line 11: 6 fields"),
    "decreasing_time": (lambda ls: ls[:20] + [ls[21], ls[20]] + ls[22:],
                        "time_s does not increase"),
    "repeated_time": (lambda ls: ls[:20] + [ls[20], ls[20]] + ls[22:],
                      "time_s does not increase"),
    "milliseconds": (lambda ls: [ls[0]] + [",".join([str(float(r.split(",")[0]) * 1000),
                                                     *r.split(",")[1:]]) for r in ls[1:]],
                     "is the time in milliseconds"),
    "radians": (lambda ls: [ls[0]] + [",".join([r.split(",")[0], *(
        str(np.radians(float(c))) for c in r.split(",")[1:])]) for r in ls[1:]],
        "look like radians"),
    "constant_tilt": (lambda ls: [ls[0]] + [",".join([r.split(",")[0], "0",
                                                      *r.split(",")[2:]]) for r in ls[1:]],
                      "the tilt is constant"),
    "short": (lambda ls: ls[:1500], "shorter than one whole cycle of its stimulus"),
    "uneven": (lambda ls: ls[:3000] + ls[3001:], "not evenly spaced"),
}


@pytest.mark.parametrize("case", sorted(RECORDING_CASES))
def test_bad_recording_for_fit(tmp_path, capsys, recording_lines, case):
    change, problem = RECORDING_CASES[case]
    path = tmp_path / "rec.csv"
    path.write_text("\n".join(change(recording_lines)) + "\n")
    _run(tmp_path, ["fit", str(path), "--out", str(tmp_path / "fit.json")], capsys, problem,
         names=str(path))


#: identify and fit share one entrance (posture_id.trials): only the CNN's own length differs
IDENTIFY_ONLY = {
    "short": "shorter than one whole cycle of its stimulus",
}


@pytest.mark.parametrize("case", sorted(RECORDING_CASES))
def test_bad_recording_for_identify(tmp_path, capsys, recording_lines, case):
    change, problem = RECORDING_CASES[case]
    path = tmp_path / "rec.csv"
    path.write_text("\n".join(change(recording_lines)) + "\n")
    _run(tmp_path, ["identify", str(path), "--out", str(tmp_path / "r.json")], capsys,
         IDENTIFY_ONLY.get(case, problem), names=str(path))


@pytest.mark.parametrize(("setup", "problem"), [
    (lambda d: d / "missing.csv", "no such recording"),
    (lambda d: (d / "r.csv").mkdir() or d / "r.csv", "is a folder"),
    (lambda d: _written(d / "r.csv", "time_s,tilt_deg,shank_deg\n0,\xb0,1\n".encode(
        "cp1252")), "line 2, column 'tilt_deg': not a number ('\xb0')"),  # read as cp1252
    (lambda d: _written(d / "r.csv", b"time_s,tilt_deg\n0,\x00\n"), "binary data"),
])
def test_recording_file_itself(tmp_path, capsys, setup, problem):
    path = setup(tmp_path)
    _run(tmp_path, ["fit", str(path), "--out", str(tmp_path / "f.json")], capsys, problem,
         names=str(path))


def test_a_byte_order_mark_is_fine(tmp_path, recording_lines):
    path = tmp_path / "bom.csv"
    path.write_bytes(b"\xef\xbb\xbf" + ("\n".join(recording_lines) + "\n").encode())
    from posture_id.recording import Recording

    rec = Recording.from_csv(path, ("shank", "thigh", "trunk"))
    assert rec.theta.shape == (6051, 3)


# ------------------------------------------------------------------ tilt files
TILT_CASES = {
    "empty": ("", "empty file"),
    "no_tilt_column": ("time_s,angle\n0,0\n1,1\n", "column 'tilt_deg' is missing"),
    "no_time_column": ("t,tilt_deg\n0,0\n1,1\n", "column 'time_s' is missing"),
    "word": ("time_s,tilt_deg\n0,0\n1,one\n", "not a number ('one')"),
    "nan": ("time_s,tilt_deg\n0,0\n1,nan\n", "is not a finite number"),
    "decreasing": ("time_s,tilt_deg\n0,0\n2,1\n1,0\n", "time_s does not increase"),
    "milliseconds": ("time_s,tilt_deg\n" + "".join(f"{20 * k},{k % 3}\n" for k in range(50)),
                     "is the time in milliseconds"),
    "constant": ("time_s,tilt_deg\n0,1\n1,1\n2,1\n", "is constant: there is no stimulus"),
    "late_start": ("time_s,tilt_deg\n1,0\n2,1\n3,0\n", "must start at 0"),
    "ragged": ("time_s,tilt_deg\n0,0\n1,1,2\n", "line 3: 3 fields"),
    "header_only": ("time_s,tilt_deg\n", "a header and no data rows"),
}


@pytest.mark.parametrize("case", sorted(TILT_CASES))
def test_bad_tilt_file(tmp_path, capsys, case):
    text, problem = TILT_CASES[case]
    path = tmp_path / "tilt.csv"
    path.write_text(text)
    _run(tmp_path, ["simulate", "--tilt", str(path), "--out", str(tmp_path / "o.csv")], capsys,
         problem, names=str(path))


@pytest.mark.parametrize(("setup", "problem"), [
    (lambda d: d / "missing.csv", "no such tilt file"),
    (lambda d: (d / "t.csv").mkdir() or d / "t.csv", "is a folder"),
    (lambda d: _written(d / "t.csv", "time_s,tilt_deg\n0,\xb0\n".encode("cp1252")),
     "line 2, column 'tilt_deg': not a number ('\xb0')"),  # read as cp1252
    (lambda d: _written(d / "t.csv", b"time_s,tilt_deg\n0,\x00\n"), "binary data"),
])
def test_tilt_file_itself(tmp_path, capsys, setup, problem):
    path = setup(tmp_path)
    _run(tmp_path, ["simulate", "--tilt", str(path), "--out", str(tmp_path / "o.csv")],
         capsys, problem, names=str(path))


# ------------------------------------------------------------------ data-set folders
@pytest.fixture(scope="module")
def small_set(tmp_path_factory):
    out = tmp_path_factory.mktemp("set") / "set"
    assert main(["network", "cnn", "data", "generate", "--trials", "4", "--shard-size", "4",
                "--out", str(out),
                 "--quiet"]) == 0
    return out


def _manifest(folder: Path, change):
    data = json.loads((folder / "manifest.json").read_text())
    change(data)
    (folder / "manifest.json").write_text(json.dumps(data))


DATASET_CASES = {
    "missing": (lambda d: shutil.rmtree(d), "not a data set"),
    "empty_folder": (lambda d: [p.unlink() for p in d.iterdir()], "not a data set"),
    "manifest_not_json": (lambda d: (d / "manifest.json").write_text("{"), "not valid JSON"),
    "manifest_a_list": (lambda d: (d / "manifest.json").write_text("[]"),
                        "not a posture_id data-set manifest"),
    "foreign_manifest": (lambda d: _manifest(d, lambda m: m.update(format="other")),
                         "not a posture_id data-set manifest"),
    "old_format": (lambda d: _manifest(d, lambda m: m.update(format_version=1)),
                   "data-set format version 1"),
    "unfinished": (lambda d: _manifest(d, lambda m: m.update(complete=False)),
                   "generation did not finish"),
    "shard_missing": (lambda d: (d / "shard-00000.npz").unlink(), "is missing"),
    "shard_truncated": (lambda d: (d / "shard-00000.npz").write_bytes(
        (d / "shard-00000.npz").read_bytes()[:2000]), "corrupt or truncated"),
    "manifest_missing_key": (lambda d: _manifest(d, lambda m: m.pop("shards")),
                             "the manifest is missing 'shards'"),
    "manifest_wrong_type": (lambda d: _manifest(d, lambda m: m.update(shards="all")),
                            "'shards' must be a list"),
}


@pytest.mark.parametrize("case", sorted(DATASET_CASES))
@pytest.mark.parametrize("command", ["info", "train"])
def test_bad_dataset_folder(tmp_path, capsys, small_set, case, command):
    folder = tmp_path / "set"
    shutil.copytree(small_set, folder)
    damage, problem = DATASET_CASES[case]
    damage(folder)
    argv = (["network", "cnn", "data", "info", str(folder)] if command == "info"
            else ["network", "cnn", "train", str(folder), "--out", str(tmp_path / "model")])
    _run(tmp_path, argv, capsys, problem, names=str(folder))


def test_a_file_is_not_a_data_set(tmp_path, capsys):
    path = tmp_path / "set"
    path.write_text("x")
    _run(tmp_path, ["network", "cnn", "data", "info", str(path)], capsys, "not a data set",
         names=str(path))


def test_a_hopeless_data_set_stops(tmp_path, capsys):
    out = tmp_path / "set"
    code = main(["network", "cnn", "data", "generate", "--trials", "50", "--shard-size", "64",
                 "--sway-limit-deg", "0.05", "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and "out of reach" in err and "Traceback" not in err
    assert not out.exists()  # the folder it made holds nothing worth keeping: cleared


@pytest.mark.parametrize(("flags", "problem"), [
    (["--proportion-jitter", "1"], "--proportion-jitter must be within [0, 1), got 1.0"),
    (["--preset-jitter", "1.5"], "--preset-jitter must be within [0, 1), got 1.5"),
    (["--tip-share", "0.6", "--preset-share", "0.5"],
     "--tip-share and --preset-share must be ≥ 0 with a sum within [0, 1]"),
    (["--clean-share", "1.5"], "--clean-share must be within [0, 1], got 1.5"),
    (["--amplitude-deg", "2", "1"],
     "--amplitude-deg must be a range 0 ≤ low ≤ high, got (2.0, 1.0)"),
])
def test_a_universal_set_s_scope_is_checked_before_anything_runs(tmp_path, capsys, flags,
                                                                  problem):
    _run(tmp_path, ["network", "universal", "data", "--out", str(tmp_path / "set"), "--shards", "1",
                    *flags], capsys, problem)
    assert not (tmp_path / "set").exists()


# ------------------------------------------------------------------ output paths
def _files(folder: Path):
    (folder / "params.json").write_text(json.dumps(_params()))
    (folder / "tilt.csv").write_text("time_s,tilt_deg\n0,0\n1,1\n2,0\n")
    (folder / "sub").mkdir()
    (folder / "afile").write_text("x")


OUTPUT_CASES = {
    "simulate_out_folder": (["simulate", "--out", "{d}/sub"], "is a folder"),
    "simulate_out_is_tilt": (["simulate", "--tilt", "{d}/tilt.csv", "--out", "{d}/tilt.csv"],
                             "also an input"),
    "simulate_out_is_params": (["simulate", "--params", "{d}/params.json", "--out",
                                "{d}/params.json"], "also an input"),
    "simulate_plot_is_out": (["simulate", "--out", "{d}/o.csv", "--plot", "{d}/o.csv"],
                             "given as two different outputs"),
    "simulate_out_under_file": (["simulate", "--out", "{d}/afile/o.csv"], "is a file"),
    "simulate_plot_folder": (["simulate", "--out", "{d}/o.csv", "--plot", "{d}/sub"],
                             "is a folder"),
    "fit_out_is_recording": (["fit", "{d}/tilt.csv", "--out", "{d}/tilt.csv"], "also an input"),
    "fit_out_folder": (["fit", "{d}/tilt.csv", "--out", "{d}/sub"], "is a folder"),
    "fit_plot_is_out": (["fit", "{d}/tilt.csv", "--out", "{d}/f.json", "--plot",
                         "{d}/f.json"], "given as two different outputs"),
    "identify_out_is_recording": (["identify", "{d}/tilt.csv", "--out", "{d}/tilt.csv"],
                                  "also an input"),
    "identify_out_folder": (["identify", "{d}/tilt.csv", "--out", "{d}/sub"], "is a folder"),
    "body_out_folder": (["body", "--default-tip", "--out", "{d}/sub"], "is a folder"),
    "body_out_under_file": (["body", "--default-tip", "--out", "{d}/afile/x.urdf"],
                            "is a file"),
    "generate_out_file": (["network", "cnn", "data", "generate", "--trials", "3", "--out",
                          "{d}/afile"],
                          "is a file, not a folder"),
    "generate_out_under_file": (["network", "cnn", "data", "generate", "--trials", "3", "--out",
                                 "{d}/afile/set"], "is a file"),
    "generate_out_not_a_set": (["network", "cnn", "data", "generate", "--trials", "3", "--out",
                                "{d}"], "holds no data-set manifest"),
    "train_out_file": (["network", "cnn", "train", "{d}/sub", "--out", "{d}/afile"],
                       "is a file, not a folder"),
    "train_out_is_dataset": (["network", "cnn", "train", "{d}/sub", "--out", "{d}/sub"],
                             "also an input"),
    "evaluate_out_file": (["network", "cnn", "evaluate", "{d}/sub", "{d}/sub", "--out",
                          "{d}/afile"],
                          "is a file, not a folder"),
    "info_figures_file": (["network", "cnn", "data", "info", "{d}/sub", "--figures", "{d}/afile"],
                          "is a file, not a folder"),
}


@pytest.mark.parametrize("case", sorted(OUTPUT_CASES))
def test_bad_output_path(tmp_path, capsys, case):
    _files(tmp_path)
    argv, problem = OUTPUT_CASES[case]
    argv = [a.format(d=tmp_path) for a in argv]
    _run(tmp_path, argv, capsys, problem)


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_read_only_folder(tmp_path, capsys):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    try:
        _run(tmp_path, ["simulate", "--out", str(locked / "o.csv")], capsys, "not writable")
    finally:
        locked.chmod(0o755)


# ------------------------------------------------------------------ the rest
def test_broken_pipe_exits_quietly(tmp_path):
    import subprocess
    import sys

    code = ("import subprocess, sys\n"
            "p = subprocess.Popen([sys.executable, '-m', 'posture_id.cli', 'body', '--json'],"
            " stdout=subprocess.PIPE, stderr=subprocess.PIPE)\n"
            "p.stdout.close()\n"
            "err = p.stderr.read().decode()\n"
            "print(p.wait(), 'Traceback' in err, repr(err))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    status, traceback, _ = out.stdout.split(" ", 2)
    assert traceback == "False", out.stdout


def test_an_unexpected_error_is_one_line_and_says_bug(monkeypatch, capsys):
    import posture_id.cli.body as body_command

    def broken(args):
        raise ZeroDivisionError("deliberate")

    monkeypatch.setattr(body_command, "run", broken)
    from posture_id.cli import build_parser

    args = build_parser().parse_args(["body"])
    assert args.func is broken
    assert main(["body"]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "internal error (a bug" in err and "--debug" in err
    with pytest.raises(ZeroDivisionError):
        main(["--debug", "body"])



# ------------------------------------------------------------------ lumping, flags, shards
G1 = ("g1_description/urdf/g1_29dof_rev_1_0.urdf")


@pytest.mark.parametrize(("ankles", "hips", "problem"), [
    (("left_ankle_pitch_joint", "left_ankle_pitch_joint"),
     ("left_hip_pitch_joint", "right_hip_pitch_joint"), "are the same joint"),
    (("left_ankle_pitch_joint", "right_ankle_pitch_joint"),
     ("left_ankle_pitch_joint", "right_hip_pitch_joint"), "given as both the ankle and the hip"),
    (("left_ankle_pitch_joint", "right_knee_joint"),
     ("left_hip_pitch_joint", "right_hip_pitch_joint"), "not a mirrored left/right pair"),
    (("left_ankle_pitch_joint", "right_ankle_pitch"),
     ("left_hip_pitch_joint", "right_hip_pitch_joint"), "right_ankle_pitch"),
])
def test_bad_lumping_request(tmp_path, capsys, ankles, hips, problem):
    from posture_id.bodies.lumping import robots_dir

    urdf = robots_dir() / G1
    _run(tmp_path, ["body", "--lump", str(urdf), "--segments", "2", "--ankle-joints", *ankles,
                    "--hip-joints", *hips, "--out", str(tmp_path / "x.urdf")], capsys, problem,
         names=str(urdf))


@pytest.mark.parametrize("flag", [["--cycles", "1"], ["--amplitude-deg", "2"],
                                  ["--states", "80"]])
def test_prts_flags_next_to_a_tilt_file(tmp_path, capsys, flag):
    tilt = tmp_path / "tilt.csv"
    tilt.write_text("time_s,tilt_deg\n0,0\n1,1\n2,0\n")
    _run(tmp_path, ["simulate", "--tilt", str(tilt), *flag, "--out", str(tmp_path / "o.csv")],
         capsys, f"--tilt replaces the PRTS: {flag[0]} do not apply")


def test_truncated_shard_without_verification(tmp_path, capsys, small_set):
    folder = tmp_path / "set"
    shutil.copytree(small_set, folder)
    shard = folder / "shard-00000.npz"
    shard.write_bytes(shard.read_bytes()[:3000])
    _run(tmp_path, ["network", "cnn", "data", "info", str(folder), "--no-verify", "--figures",
                    str(tmp_path / "figs")], capsys, "cannot be read", names=str(shard))
