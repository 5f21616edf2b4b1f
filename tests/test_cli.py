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
    assert main(["body", "--height", "1.8", "--mass", "80", "--segments", "2",
                 "--out", str(out)]) == 0
    body = load_body(out)
    assert body.segment_names == ("leg", "trunk")
    np.testing.assert_allclose(body.mgh, [770.0, 172.7], atol=0.5)


def test_body_from_robot(tmp_path, capsys):
    out = tmp_path / "talos.urdf"
    assert main(["body", "--from-robot", "talos", "--segments", "2", "--out", str(out)]) == 0
    assert "half_sitting" in capsys.readouterr().err
    assert load_body(out).segment_names == ("leg", "trunk")
    assert main(["body", "--from-robot", "g1", "--height", "1.8", "--out", str(out)]) == 2
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
