"""Command line: body description, URDF generation, simulation, one-line errors."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from posture_id.bodies.body import load_body
from posture_id.cli import main
from posture_id.dec.parameters import default_parameters
from posture_id.recording import Recording


def test_body_table_and_json(capsys):
    assert main(["body"]) == 0
    out = capsys.readouterr().out
    assert "465.975" in out and "245.250" in out and "73.575" in out
    assert main(["body", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [m["joint"] for m in data["modules"]] == ["ankle", "knee", "hip"]
    assert data["default_parameters"]["hip"]["delay_s"] == 0.121


def test_body_writes_winter_urdf(tmp_path, capsys):
    out = tmp_path / "subject.urdf"
    assert main(["body", "--height-m", "1.8", "--mass-kg", "80", "--segments", "2",
                 "--out", str(out)]) == 0
    body = load_body(out)
    assert body.segment_names == ("leg", "trunk")
    np.testing.assert_allclose(body.mgh, [770.0, 172.7], atol=0.5)


def test_body_from_robot(tmp_path, capsys):
    out = tmp_path / "talos.urdf"
    assert main(["body", "--from-robot", "talos", "--segments", "2", "--out", str(out)]) == 0
    assert "half_sitting" in capsys.readouterr().err
    assert load_body(out).segment_names == ("leg", "trunk")
    assert main(["body", "--from-robot", "g1", "--height-m", "1.8", "--out", str(out)]) == 2
    assert "not allowed with argument" in capsys.readouterr().err


def test_simulate_writes_recording_and_plot(tmp_path, tip):
    csv, png = tmp_path / "trial.csv", tmp_path / "trial.png"
    params = tmp_path / "p.json"
    default_parameters(tip).replace("knee", controls="com").to_json(params)
    assert main(["simulate", "--params", str(params), "--amplitude-deg", "2", "--cycles", "1",
                 "--out", str(csv), "--plot", str(png)]) == 0
    rec = Recording.from_csv(csv, tip.segment_names)
    assert rec.theta.shape == (3026, 3)
    assert rec.sample_rate_hz == pytest.approx(50.0)
    assert np.degrees(np.ptp(rec.tilt)) == pytest.approx(2.0, rel=1e-9)
    assert png.stat().st_size > 10_000


def test_simulate_reports_an_abort(tmp_path, tip, capsys):
    d = default_parameters(tip)
    params = tmp_path / "weak.json"
    d.replace("ankle", kp=0.1 * d["ankle"].kp, ki=0.0, kpas=0.3 * d["ankle"].kpas).to_json(params)
    csv = tmp_path / "trial.csv"
    assert main(["simulate", "--params", str(params), "--out", str(csv)]) == 1
    assert "left the ±6° sway limit" in capsys.readouterr().err
    rec = Recording.from_csv(csv)
    assert rec.time[-1] < 121


def _write_params(tmp_path, tip, mutate):
    data = default_parameters(tip).to_dict()
    mutate(data)
    path = tmp_path / "p.json"
    path.write_text(json.dumps(data))
    return path


@pytest.mark.parametrize(
    "make_args, fragment",
    [
        (lambda tmp, tip: ["body", str(tmp / "none.urdf")], "no such URDF"),
        (lambda tmp, tip: ["simulate", "--params",
                           str(_write_params(tmp, tip, lambda d: d.pop("hip"))),
                           "--out", str(tmp / "x.csv")], "module 'hip' is missing"),
        (lambda tmp, tip: ["simulate", "--params",
                           str(_write_params(tmp, tip,
                                             lambda d: d["knee"].__setitem__("delay_s", -1))),
                           "--out", str(tmp / "x.csv")], "field 'delay_s' is negative"),
    ],
)
def test_errors_are_one_line(tmp_path, tip, capsys, make_args, fragment):
    assert main(make_args(tmp_path, tip)) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("posture-id: error: ")
    assert fragment in err


def test_console_script_prints_no_traceback(tmp_path):
    tilt = tmp_path / "tilt.csv"
    tilt.write_text("time_s,tilt_deg\n0,0\n1,NaN\n2,0\n")
    proc = subprocess.run(
        [sys.executable, "-m", "posture_id.cli", "simulate", "--tilt", str(tilt),
         "--out", str(tmp_path / "x.csv")],
        capture_output=True, text=True, check=False,
    )
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert proc.stderr.strip().count("\n") == 0
    assert str(tilt) in proc.stderr and "line 3" in proc.stderr


def test_search_ranges_of_the_fit(tmp_path, capsys):
    """--gain-range / --delay-range widen the search box (the paper's own human ankle Ki,
    74.7 for a 70 kg subject, lies outside the default 4×)."""
    from posture_id.cli import build_parser
    from posture_id.cli.fit import options_from

    args = build_parser().parse_args(["fit", "rec.csv", "--out", "o.json", "--gain-range",
                                      "0", "10", "--delay-range", "0.5", "3"])
    options = options_from(args)
    assert options.gain_bounds == (-1.0, 9.0) and options.delay_bounds == (-0.5, 2.0)
    defaults = options_from(build_parser().parse_args(["fit", "rec.csv", "--out", "o.json"]))
    assert defaults.gain_bounds == (-1.0, 3.0) and defaults.delay_bounds == (-1.0, 1.5)
    for command in ("fit", "identify"):
        assert main([command, "rec.csv", "--out", str(tmp_path / "o.json"), "--gain-range",
                     "3", "2"]) == 2
        assert "--gain-range: MIN must be below MAX, got 3 2" in capsys.readouterr().err


def test_a_negative_axis_is_taken_as_typed(tmp_path, capsys):
    """``--forward-axis -y`` (as anyone types it) reads the example C3D trial exactly as
    ``--forward-axis=-y`` does."""
    from pathlib import Path

    from posture_id.cli.renamed import normalised

    assert normalised(["frf", "t.c3d", "--forward-axis", "-y", "--vertical-axis", "z"]) == \
        ["frf", "t.c3d", "--forward-axis=-y", "--vertical-axis", "z"]
    c3d = Path(__file__).resolve().parents[1] / "posture_id/studies/examples/" \
        "straight_leg_subject.c3d"
    markers = ["--segment-markers", "leg=LANK+RANK,LHIP+RHIP", "trunk=LHIP+RHIP,LSHO+RSHO",
               "--tilt-channel", "platform_angle", "--tilt-scale", "2"]
    outs = []
    for k, axis in enumerate((["--forward-axis", "-y"], ["--forward-axis=-y"])):
        out = tmp_path / f"f{k}.json"
        assert main(["frf", str(c3d), *markers, *axis, "--out", str(out)]) == 0
        outs.append(json.loads(out.read_text())["channels"])
    assert outs[0] == outs[1]


def test_old_spellings_work_with_a_notice_of_their_new_name(tmp_path, capsys):
    """A renamed flag's old spelling gives the same answer and says the new name once."""
    from posture_id.cli.renamed import RENAMED

    assert RENAMED[("simulate", "--noise-deg")] == "--sensor-noise-deg"
    texts = []
    for k, flag in enumerate(("--sensor-noise-deg", "--noise-deg", "--noise-deg=0.05")):
        out = tmp_path / f"s{k}.csv"
        value = [] if "=" in flag else ["0.05"]
        assert main(["simulate", "--cycles", "1", "--seed", "3", flag, *value,
                     "--out", str(out)]) == 0
        err = capsys.readouterr().err
        assert ("--noise-deg is now --sensor-noise-deg" in err) == (k > 0)
        texts.append(out.read_text())
    assert texts[0] == texts[1] == texts[2]
    # identify's network folder: --network now, --model DIR still read as it
    from posture_id.cli.renamed import normalised

    assert normalised(["identify", "r.csv", "--model", "nets/mine"]) == \
        ["identify", "r.csv", "--network", "nets/mine"]
    assert "--model DIR is now --network DIR" in capsys.readouterr().err
    assert normalised(["identify", "r.csv", "--model", "ic"]) == \
        ["identify", "r.csv", "--model", "ic"]
    assert normalised(["body", "--height", "1.8", "--mass=80"]) == \
        ["body", "--height-m", "1.8", "--mass-kg=80"]


def test_the_network_commands_old_names_work_with_a_notice_of_their_family(tmp_path, capsys):
    """Each command that moved into ``posture-id network`` is read in its new words, says
    them once, and does what it did: a data set made by the old spelling is the one the
    new spelling makes, byte for byte."""
    from posture_id.cli.renamed import MOVED_COMMANDS, normalised

    assert normalised(["--debug", "train", "set", "--out", "m", "--noise-deg", "0.1"]) == \
        ["--debug", "network", "cnn", "train", "set", "--out", "m", "--noise-deg", "0.1"]
    assert "posture-id train is now posture-id network cnn train" in capsys.readouterr().err
    assert normalised(["universal", "check", "m", "set"]) == \
        ["network", "universal", "calibrate", "m", "set"]
    assert normalised(["calibration", "m", "set", "--noise-deg", "0"]) == \
        ["network", "cnn", "calibrate", "m", "set", "--sensor-noise-deg", "0"]
    capsys.readouterr()
    for old, new in MOVED_COMMANDS.items():  # every one reaches a parser of the family
        assert main([old, "--help"]) == 0
        assert f"usage: posture-id {' '.join(new)}" in capsys.readouterr().out
    made = []
    for k, argv in enumerate((["dataset", "generate"], ["network", "cnn", "data", "generate"])):
        out = tmp_path / f"set{k}"
        assert main([*argv, "--trials", "3", "--shard-size", "4", "--seed", "2", "--quiet",
                     "--out", str(out)]) == 0
        err = capsys.readouterr().err
        assert ("posture-id dataset is now posture-id network cnn data" in err) == (k == 0)
        made.append((out / "shard-00000.npz").read_bytes())
    assert made[0] == made[1]


def test_the_top_level_help_lists_every_command_once_by_task(capsys):
    from posture_id.cli import COMMAND_GROUPS, build_parser

    parser = build_parser()
    text = parser.format_help()
    names = [n for _, group in COMMAND_GROUPS for n in group]
    sub = next(a for a in parser._actions if a.dest == "command")
    assert sorted(names) == sorted(sub.choices) and len(set(names)) == len(names)
    for title, group in COMMAND_GROUPS:
        assert f"\n{title}:\n" in text
        for name in group:
            assert text.count(f"\n  {name} ") == 1, name
    assert "examples:" in text


def test_a_command_s_error_names_the_command(capsys):
    """``posture-id body: error: ...``: every sub-command's one line names it."""
    assert main(["body", "--segments", "x"]) == 2
    assert capsys.readouterr().err.startswith("posture-id body: error: argument --segments")
    assert main(["norm", "build", "--bootstrap", "0"]) == 2
    assert capsys.readouterr().err.startswith("posture-id norm build: error: ")
