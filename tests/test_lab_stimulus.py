"""The stimulus as a lab ran it: a PRTS with a lead-in, a starting state, a sign and a
platform lag; recordings without a tilt column; lengths of whole cycles."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from posture_id.cli import main
from posture_id.dec import sample_parameters
from posture_id.errors import RecordingError, StimulusError
from posture_id.recording import Recording
from posture_id.simulation import prts, simulate
from posture_id.simulation.stimulus import prts_symbols, recognise_prts
from posture_id.trials import prepare_trial

LAB = {"states": 80, "cycles": 3, "onset_s": 2.0, "start_state": 17, "sign": -1,
       "lag_s": 0.04}
LAB_FLAGS = ["--states", "80", "--cycles", "3", "--onset-s", "2", "--start-state", "17",
             "--sign", "-1", "--lag-s", "0.04"]


def test_a_lab_prts_is_the_sequence_shifted_delayed_and_signed():
    lab = prts(1.0, **LAB)
    plain = prts(1.0, 3, 80)
    delay = 2.04
    assert lab.period_s == 20.0 and lab.periodic_from_s == pytest.approx(delay)
    assert lab.whole_cycles_s == pytest.approx(22.04)
    assert lab.duration == pytest.approx(delay + 60.0)
    t = np.linspace(0, delay, 50)
    assert np.all(lab.angle(t) == 0)  # level during the lead-in and the lag
    # state k of the lab's sequence moves like state k + 17 of the plain one, negated
    k = np.arange(160)
    plain_velocity = plain.velocity(((k + 17) % 80 + 0.5) * 0.25)
    np.testing.assert_allclose(lab.velocity(delay + (k + 0.5) * 0.25), -plain_velocity,
                               atol=1e-12)
    symbols = np.tile(np.roll(prts_symbols(80), -17), 2)
    assert np.all(np.sign(lab.velocity(delay + (k + 0.5) * 0.25)) == -symbols)
    assert np.degrees(np.ptp(lab.angle(delay + np.arange(0, 20.0, 0.25)))) == pytest.approx(
        1.0)
    assert "onset 2 s" in lab.description and "negated" in lab.description


@pytest.mark.parametrize("kwargs, message", [
    ({"onset_s": -1.0}, "onset_s must be a finite time"),
    ({"lag_s": math.nan}, "lag_s must be a finite time"),
    ({"start_state": 80, "states": 80}, r"start state must be a number in \[0, 80\)"),
    ({"start_state": -0.5, "states": 80}, "start state must be a number in"),
    ({"sign": 0}, "sign must be"),
    ({"state_s": 0.0}, "state duration must be"),
])
def test_bad_lab_prts_arguments_are_refused(kwargs, message):
    with pytest.raises(StimulusError, match=message):
        prts(**kwargs)


def test_lengths_follow_the_sequence(tip):
    """Three 20 s cycles (60 s) are enough for the 80-state PRTS; less than one is not."""
    stimulus = prts(1.0, 3, 80)
    trial = simulate(tip, stimulus=stimulus)
    recording = trial.to_recording()
    assert recording.duration_s == pytest.approx(60.0)
    found = prepare_trial(recording).stimulus
    assert found.period_s == 20.0 and found.whole_cycles_s == 20.0
    short = Recording(recording.time[:750], recording.tilt[:750], recording.theta[:750],
                      recording.segments)
    assert recognise_prts(short.time, short.tilt).whole_cycles_s == 20.0
    with pytest.raises(RecordingError, match=r"shorter than one whole cycle of its stimulus "
                                             r"\(PRTS 80 states.*20 s\)"):
        prepare_trial(replace(short, name="lab.csv")).require_whole_cycle()


def test_a_tilt_column_that_is_not_the_named_stimulus_is_refused(tip):
    lab = prts(1.0, **LAB)
    recording = simulate(tip, stimulus=lab).to_recording()
    recording = replace(recording, name="lab.csv")
    prepare_trial(recording, lab)  # the right one passes
    other = prts(1.0, **{**LAB, "start_state": 5})
    with pytest.raises(StimulusError, match="lab.csv: the tilt column is not the named "
                                            "stimulus .*starting state"):
        prepare_trial(recording, other)


def _write_without_tilt(recording: Recording, path):
    lines = recording.to_csv(path).read_text().splitlines()
    rows = [",".join(line.split(",")[:1] + line.split(",")[2:]) for line in lines]
    path.write_text("\n".join(rows) + "\n")


def test_a_recording_without_a_tilt_column_takes_the_named_stimulus(tip, tmp_path, capsys):
    lab = prts(1.0, **LAB)
    recording = simulate(tip, stimulus=lab).to_recording()
    csv = tmp_path / "no_tilt.csv"
    _write_without_tilt(recording, csv)
    assert csv.read_text().startswith("time_s,shank_deg,")
    read = Recording.from_csv(csv, tip.segment_names, lab.angle)
    np.testing.assert_allclose(read.tilt, lab.angle(read.time), atol=1e-12)
    with pytest.raises(RecordingError, match="no 'tilt_deg' column after time_s; name the "
                                             "stimulus"):
        Recording.from_csv(csv, tip.segment_names)
    # the FRF from the named stimulus skips its lead-in and analyses the three cycles
    out = tmp_path / "frf.json"
    assert main(["frf", str(csv), *LAB_FLAGS, "--out", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["cycles"] == 3 and data["period_s"] == 20.0
    assert main(["frf", str(csv), "--out", str(tmp_path / "f2.json")]) == 2
    assert "no 'tilt_deg' column" in capsys.readouterr().err


def test_tilt_file_and_prts_flags_do_not_mix(tip, tmp_path, capsys):
    recording = simulate(tip).to_recording()
    csv = tmp_path / "rec.csv"
    recording.to_csv(csv)
    tilt = tmp_path / "tilt.csv"
    tilt.write_text("time_s,tilt_deg\n0,0\n1,0.5\n")
    for command in ("fit", "identify", "frf"):
        code = main([command, str(csv), "--tilt", str(tilt), "--onset-s", "2", "--out",
                     str(tmp_path / "x.json")])
        assert code == 2
        assert "--tilt replaces the PRTS: --onset-s do not apply" in capsys.readouterr().err
    assert not (tmp_path / "x.json").exists()


def test_a_specialist_refuses_a_lab_stimulus_the_universal_model_reads_it(tip, tmp_path,
                                                                         capsys):
    from posture_id.learning.bundled import MODELS_DIR

    lab = prts(1.0, **LAB)
    recording = simulate(tip, stimulus=lab).to_recording()
    csv = tmp_path / "lab.csv"
    recording.to_csv(csv)
    specialist = str(MODELS_DIR / "tip_default")
    assert main(["identify", str(csv), *LAB_FLAGS, "--network", specialist,
                 "--out", str(tmp_path / "r.json")]) == 2
    err = capsys.readouterr().err
    assert "the CNN was trained on" in err and "use posture-id fit" in err
    out = tmp_path / "u.json"
    assert main(["identify", str(csv), *LAB_FLAGS, "--out", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["cnn"]["model"]["layout"] == "universal"
    assert data["normalised"]["ankle"]["class"] == tip_default_class("ankle")


def tip_default_class(joint: str) -> float:
    from posture_id import load_body
    from posture_id.dec.parameters import default_parameters

    return float(default_parameters(load_body())[joint].sign)


@pytest.mark.slow("least squares through the command line, 3 segments")
def test_fit_of_a_lab_recording_with_its_stimulus_named(tip, tmp_path):
    """62 s of sway without a tilt column, the stimulus named by its flags: the fit
    recovers every class and Kp (noise-free, so within 2 %)."""
    rng = np.random.default_rng(8)
    lab = prts(1.0, **LAB)
    while True:
        truth = sample_parameters(tip, 1, rng).trial(0, tip.joint_names)
        trial = simulate(tip, truth, stimulus=lab)
        if trial.stable:
            break
    csv = tmp_path / "lab.csv"
    _write_without_tilt(trial.to_recording(), csv)
    out = tmp_path / "fit.json"
    assert main(["fit", str(csv), *LAB_FLAGS, "--out", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["status"]["converged"] and data["status"]["rms_deg"] < 1e-5
    for joint in tip.joint_names:
        assert data["parameters"][joint]["controls"] == truth[joint].controls
        assert abs(data["parameters"][joint]["kp"] / truth[joint].kp - 1) < 0.02, joint
