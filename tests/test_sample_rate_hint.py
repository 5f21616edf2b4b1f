"""A time column that gives the wrong rate is noticed from the PRTS in the tilt."""

from __future__ import annotations

import json

import numpy as np
import pytest

from posture_id.cli import main
from posture_id.recording import Recording
from posture_id.simulation import prts, simulate
from posture_id.simulation.stimulus import sample_rate_hint
from posture_id.trials import prepare_trial


def _lab_tilt(states, true_rate, rng):
    """Two PRTS cycles as a lab records them: 2 s lead-in, starting part-way into the
    cycle, 0.02° of measurement noise; sampled at ``true_rate``."""
    stimulus = prts(1.0, 2, states)
    t = np.arange(int(stimulus.duration * true_rate) + 1) / true_rate
    tilt = np.roll(stimulus.angle(t), int(3.7 * true_rate))
    tilt = np.concatenate([np.zeros(int(2 * true_rate)), tilt])[: len(t)]
    return tilt + np.radians(0.02) * rng.standard_normal(len(t))


@pytest.mark.parametrize("states", [242, 80])
@pytest.mark.parametrize("true_rate", [25, 60, 100, 200])
def test_the_likely_true_rate_is_named(states, true_rate):
    tilt = _lab_tilt(states, true_rate, np.random.default_rng(true_rate))
    said = np.arange(len(tilt)) / 50.0  # the time column claims 50 Hz
    hint = sample_rate_hint(said, tilt, "lab.csv")
    assert hint is not None and hint.startswith("lab.csv: ")
    assert f"{states}-state PRTS sampled at {true_rate} Hz" in hint
    assert "not at the 50 Hz the time column says" in hint


@pytest.mark.parametrize("states", [242, 80])
def test_a_right_time_column_or_another_tilt_gets_no_hint(states):
    rng = np.random.default_rng(1)
    tilt = _lab_tilt(states, 50, rng)
    assert sample_rate_hint(np.arange(len(tilt)) / 50.0, tilt, "lab.csv") is None
    t = np.arange(6051) / 50.0
    assert sample_rate_hint(t, np.radians(0.5) * np.sin(t), "sine.csv") is None
    assert sample_rate_hint(t, rng.standard_normal(len(t)), "noise.csv") is None


def test_fit_and_identify_say_it(tip, tmp_path, capsys):
    trial = simulate(tip)
    recording = trial.to_recording()
    # 50 Hz samples written with a time column of 25 Hz (a lab's mistake)
    wrong = Recording(recording.time * 2, recording.tilt, recording.theta, recording.segments,
                      "lab.csv")
    notices = prepare_trial(wrong).notices
    assert any("sampled at 50 Hz" in n and "25 Hz the time column" in n for n in notices)
    csv = tmp_path / "lab.csv"
    wrong.to_csv(csv)
    from posture_id.learning.bundled import MODELS_DIR

    specialist = str(MODELS_DIR / "tip_default")
    assert main(["identify", str(csv), "--network", specialist,
                 "--out", str(tmp_path / "r.json")]) == 2
    err = capsys.readouterr().err
    assert "valid for that stimulus only" in err and "sampled at 50 Hz" in err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "r.json").exists()
    # the universal model reads the PRTS it finds (0.5 s states) and says what is odd
    assert main(["identify", str(csv), "--method", "cnn", "--out",
                 str(tmp_path / "u.json")]) == 1  # written, doubtful
    out = capsys.readouterr().out
    assert "sampled at 50 Hz" in out and "states of 0.5 s outside the 0.2–0.3 s" in out
    assert json.loads((tmp_path / "u.json").read_text())["trust"]["doubtful"]


def test_a_lab_s_other_state_duration_is_not_called_a_wrong_time_column(tip):
    """0.3 s states at 50 Hz are the same samples as 0.25 s states at 60 Hz: both are
    protocols labs run, so the entrance names both instead of blaming the time column."""
    stimulus = prts(2.0, 2, 80, state_s=0.3)
    recording = simulate(tip, stimulus=stimulus).to_recording()
    notices = prepare_trial(recording).notices
    said = [n for n in notices if "60 Hz" in n]
    assert len(said) == 1, notices
    assert "80-state PRTS of 0.25 s states at 60 Hz" in said[0]
    assert "state 0.3 s" in said[0] and "check the time column" not in said[0]
