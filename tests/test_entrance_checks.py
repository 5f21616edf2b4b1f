"""Checks made at the entrance, before any work, that name the real problem: a stimulus
named to start after the recording ends, an offset search wider than half a cycle."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from posture_id.bodies.body import load_body
from posture_id.dec.parameters import default_parameters
from posture_id.errors import StimulusError
from posture_id.fitting.options import FitError, FitOptions
from posture_id.frf.locked import LockedOptions
from posture_id.simulation import prts, simulate
from posture_id.trials import prepare_trial

#: The project's shipped URDFs (``make bodies``).
URDF_DIR = Path(__file__).resolve().parents[1] / "urdf"


def test_a_stimulus_named_to_start_after_the_recording_is_named_so(tip, tmp_path, capsys):
    from posture_id.cli import main

    recording = simulate(tip, default_parameters(tip)).to_recording()
    late = prts(1.0, 2, 242, onset_s=500.0)
    with pytest.raises(StimulusError, match="starts moving at 500 s .* after the recording "
                                            "ends \\(121 s\\)"):
        prepare_trial(recording, late)
    path = tmp_path / "sway_only.csv"
    lines = recording.to_csv(tmp_path / "full.csv").read_text().splitlines()
    path.write_text("\n".join(",".join(c for k, c in enumerate(line.split(",")) if k != 1)
                              for line in lines) + "\n")
    assert main(["identify", str(path), "--onset-s", "500"]) == 2
    err = capsys.readouterr().err
    assert "starts moving at 500 s" in err and "tilt is constant" not in err


def test_an_offset_search_beyond_half_a_cycle_is_refused_before_any_fit(tip, monkeypatch):
    from posture_id.fitting import least_squares

    def no_work(*args, **kwargs):
        raise AssertionError("the fit started before the options were checked")

    monkeypatch.setattr(least_squares.FitRun, "start", no_work)
    recording = simulate(tip, default_parameters(tip)).to_recording()
    trial = prepare_trial(recording, prts())
    options = FitOptions(locked=LockedOptions(max_offset_s=100.0))
    with pytest.raises(FitError, match="max_offset_s 100 s is more than half a stimulus "
                                       "cycle \\(30.25 s\\)"):
        least_squares.fit_recording(trial, tip, None, options)


@pytest.mark.parametrize("flags", [["--fit-passive"], ["--locked", "--prior-sd", "0.5"],
                                   ["--gain-range", "0.5", "2"]])
def test_least_squares_flags_with_the_network_alone_are_refused(flags, tmp_path, capsys):
    from posture_id.cli import main

    path = tmp_path / "rec.csv"
    simulate(load_body()).to_recording().to_csv(path)
    assert main(["identify", str(path), "--method", "cnn", *flags]) == 2
    err = capsys.readouterr().err
    assert f"{flags[0]}" in err and "--method cnn runs none" in err


@pytest.mark.parametrize("flags, named", [
    (["--angle-columns", "a", "a"], "'a' is named more than once"),
    (["--time-column", "t"], "--time-column and --tilt-column go with --angle-columns"),
])
def test_a_labs_columns_are_each_their_own_and_go_together(flags, named, tmp_path, capsys):
    from posture_id.cli import main

    path = tmp_path / "rec.csv"
    path.write_text("t,tilt,a\n0,0,0\n0.02,0.1,0.1\n")
    assert main(["identify", str(path), "--body", str(URDF_DIR / "winter_1.75m_70kg_2seg.urdf"),
                 *flags]) == 2
    assert named in capsys.readouterr().err


@pytest.mark.parametrize("flags, named", [
    (["--default-tip", "--segments", "2", "--out", "x.urdf"], "--default-tip writes the 3"),
    (["urdf/tip_default.urdf", "--out", "copy.urdf"], "--out writes a body"),
    (["--segments", "2"], "--segments goes with a body to write"),
    (["--height-m", "1.8", "--mass-kg", "80", "--hip-joints", "a", "b", "--out", "x.urdf"],
     "--hip-joints go with --lump"),
])
def test_body_flags_that_would_do_nothing_are_refused(flags, named, tmp_path, capsys,
                                                      monkeypatch):
    from posture_id.cli import main

    monkeypatch.chdir(URDF_DIR.parent)
    flags = [str(tmp_path / f) if f.endswith(".urdf") and not f.startswith("urdf/") else f
             for f in flags]
    assert main(["body", *flags]) == 2
    assert named in capsys.readouterr().err
    assert not any(tmp_path.iterdir())  # nothing written


def test_degrees_read_as_radians_are_refused_naming_the_column(tmp_path, capsys):
    """A lab's degrees with --units rad: a 2° tilt would be 115°, and so would the sway
    that follows it: one line naming the column; without the tilt column, the sway's."""
    from posture_id.cli import main

    recording = simulate(load_body(URDF_DIR / "winter_1.75m_70kg_1seg.urdf"), stimulus=prts(
        2.0)).to_recording()
    path = tmp_path / "lab.csv"
    rows = "".join(f"{t:.2f},{a:.5f},{b:.5f}\n" for t, a, b in zip(
        recording.time, np.degrees(recording.tilt), np.degrees(recording.theta[:, 0]),
        strict=True))
    path.write_text("time,platform,COM\n" + rows)
    common = ["identify", str(path), "--body", str(URDF_DIR / "winter_1.75m_70kg_1seg.urdf"),
              "--time-column", "time", "--tilt-column", "platform", "--angle-columns", "COM"]
    assert main([*common, "--units", "rad", "--method", "cnn"]) == 2
    err = capsys.readouterr().err
    assert "column 'platform' spans" in err and "look like degrees" in err
    assert main([*common, "--method", "cnn"]) == 0  # the same file in degrees is read
    tall = path.with_name("tall.csv")  # sway only (the stimulus named), up to 40 "radians"
    tall.write_text("time,COM\n" + "".join(f"{t:.2f},{40 * np.sin(t):.5f}\n"
                                           for t in recording.time))
    assert main(["identify", str(tall), "--body", str(URDF_DIR / "winter_1.75m_70kg_1seg.urdf"),
                 "--time-column", "time", "--tilt-column", "none", "--angle-columns", "COM",
                 "--units", "rad", "--method", "cnn", "--amplitude-deg", "2"]) == 2
    assert "column 'COM' reaches 40" in capsys.readouterr().err


def test_a_period_the_tilt_does_not_repeat_with_is_refused(tip, tmp_path, capsys):
    """The 242-state PRTS (60.5 s) analysed with --period-s 20: one line, not an FRF of
    cycles that are not the stimulus's; its own period is read."""
    from posture_id.cli import main

    path = tmp_path / "rec.csv"
    simulate(tip).to_recording().to_csv(path)
    out = tmp_path / "frf.json"
    assert main(["frf", str(path), "--period-s", "20", "--out", str(out)]) == 2
    assert "the tilt does not repeat every 20 s" in capsys.readouterr().err
    assert not out.exists()
    assert main(["frf", str(path), "--period-s", "60.5", "--out", str(out)]) == 0


@pytest.mark.parametrize("protocol, named", [
    ({"kind": "multisine", "period_s": 20.0, "harmonics": [1, "two", 3]},
     "protocol harmonics must be a whole number ≥ 1, got 'two'"),
    ({"kind": "multisine", "period_s": 20.0, "harmonics": [1, 2], "weights": [1, "x"]},
     "protocol weights must be 2 finite numbers"),
    ({"kind": "prts", "amplitude_deg": 1e9}, "more than the 20° a posture platform tilts"),
])
def test_a_protocol_holding_a_word_or_an_impossible_tilt_is_refused(protocol, named,
                                                                    tmp_path, capsys):
    import json

    from posture_id.cli import main

    path = tmp_path / "protocol.json"
    path.write_text(json.dumps(protocol))
    out = tmp_path / "command.csv"
    assert main(["stimulus", str(path), "--out", str(out)]) == 2
    assert named in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.slow("least squares through the command line, 3 segments")
def test_a_fit_stopped_at_the_noise_level_is_converged_and_exits_0(tip, tmp_path, monkeypatch,
                                                                   capsys):
    """The optimiser's own status says 'not converged' (forced here) while the residual is
    the recording's 0.05° of noise: converged as far as the recording can tell, exit 0; a
    residual beyond the noise stays not converged, exit 1."""
    from dataclasses import replace

    from posture_id.cli import main
    from posture_id.fitting import least_squares

    real = least_squares.fit_recording
    spoil = {"on": False}

    def stops_short(*args, **kwargs):
        result = real(*args, **kwargs)
        fitted = result.fitted * (3.0 if spoil["on"] else 1.0)
        return replace(result, converged=False, fitted=fitted)

    monkeypatch.setattr(least_squares, "fit_recording", stops_short)
    path = tmp_path / "rec.csv"
    # one 80-state cycle (20 s): the status, not the length, is under test
    simulate(tip, default_parameters(tip), prts(cycles=1, states=80)).to_recording(
    ).with_sensor_noise(0.05, 3).to_csv(path)
    assert main(["fit", str(path), "--locked", "--out", str(tmp_path / "fit.json")]) == 0
    out = capsys.readouterr().out
    assert "converged in" in out and "NOT converged" not in out
    assert "converged as far as the recording can tell" in out
    spoil["on"] = True
    assert main(["fit", str(path), "--locked", "--out", str(tmp_path / "fit2.json")]) == 1
    assert "NOT converged" in capsys.readouterr().out
