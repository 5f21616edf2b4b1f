"""The entrance: a Recording checks itself; prepare_trial checks, finds the stimulus and
resamples once, and nothing past it looks at the stimulus recognition again."""

from __future__ import annotations

import sys
from dataclasses import replace

import numpy as np
import pytest

from posture_id.errors import RecordingError, StimulusError
from posture_id.identify import Method, identify
from posture_id.recording import Recording
from posture_id.simulation import SimulationOptions, prts, simulate
from posture_id.simulation import stimulus as stimulus_module
from posture_id.trials import prepare_trial

ENTRANCE = ("recognise_prts", "likely_sample_rate", "sample_rate_hint", "check_recorded_tilt",
            "tilt_from_array")


def test_a_recording_checks_itself_and_names_itself():
    t = np.arange(5) / 50
    theta = np.zeros((5, 2))
    with pytest.raises(RecordingError, match="^lab.csv: segment angles have shape"):
        Recording(t, t, np.zeros((5, 3)), ("leg", "trunk"), "lab.csv")
    with pytest.raises(RecordingError, match="^lab.csv: tilt has shape"):
        Recording(t, t[:4], theta, ("leg", "trunk"), "lab.csv")
    with pytest.raises(RecordingError, match=r"^lab.csv: sample 3: time does not increase"):
        Recording(np.array([0, 0.02, 0.04, 0.04, 0.08]), t, theta, ("leg", "trunk"), "lab.csv")
    with pytest.raises(RecordingError, match="start at 0"):
        Recording(t + 1, t, theta, ("leg", "trunk"))
    rec = Recording(t, t, theta, ("leg", "trunk"), "lab.csv")
    assert rec.resampled(100.0).name == "lab.csv"
    assert rec.with_sensor_noise(0.1, 1).name == "lab.csv"


def test_prepare_trial_finds_the_stimulus_and_resamples_once(tip):
    fine = simulate(tip, options=SimulationOptions(sample_rate_hz=100.0)).to_recording()
    trial = prepare_trial(replace(fine, name="rec100.csv"), rate_hz=50.0)
    assert trial.name == "rec100.csv" and trial.rate_hz == pytest.approx(50.0)
    assert trial.resampled and trial.original_rate_hz == pytest.approx(100.0)
    assert trial.stimulus.period_s == pytest.approx(60.5)
    assert [n.split(": ", 1)[0] for n in trial.notices] == ["rec100.csv"] * 2
    kept = prepare_trial(fine, rate_hz=None)  # the FRF keeps the recording's own rate
    assert not kept.resampled and kept.recording is fine
    with pytest.raises(StimulusError, match="is not the named stimulus"):
        prepare_trial(fine, prts(2.0))


def test_a_shifted_trial_moves_its_stimulus_and_tilt_column(tip):
    named = prts(states=80, cycles=3)
    trial = prepare_trial(simulate(tip, stimulus=named).to_recording(), named)
    late = trial.shifted(0.04).shifted(0.02)
    assert late.time_offset_s == pytest.approx(0.06)
    t = late.recording.time
    np.testing.assert_allclose(late.recording.tilt, named.angle(t - 0.06), atol=1e-15)
    np.testing.assert_array_equal(late.recording.theta, trial.recording.theta)


def _count_entrance(monkeypatch) -> dict[str, int]:
    """Count calls of the stimulus module's recognition and checks, wherever a module
    imported them by name."""
    calls = dict.fromkeys(ENTRANCE, 0)
    for name in ENTRANCE:
        original = getattr(stimulus_module, name)

        def counted(*args, _name=name, _original=original, **kwargs):
            calls[_name] += 1
            return _original(*args, **kwargs)

        for module in list(sys.modules.values()):
            if (getattr(module, "__name__", "").startswith("posture_id")
                    and getattr(module, name, None) is original):
                monkeypatch.setattr(module, name, counted)
    return calls


def test_the_cnn_route_enters_the_stimulus_module_once(tip, monkeypatch):
    recording = simulate(tip).to_recording().with_sensor_noise(0.01, 3)
    calls = _count_entrance(monkeypatch)
    result = identify(recording, tip, Method.CNN)
    # a PRTS of 0.25 s states recognised at the stated rate: no rate to hint at
    assert calls == {"recognise_prts": 1, "likely_sample_rate": 0, "sample_rate_hint": 0,
                     "check_recorded_tilt": 0, "tilt_from_array": 0}
    assert sum("the exact profile is used" in n for n in result.notices) == 1


@pytest.mark.slow("least squares from the defaults, 3 segments")
def test_the_fit_route_enters_the_stimulus_module_once(tip, monkeypatch):
    named = prts(states=80, cycles=3)
    recording = simulate(tip, stimulus=named).to_recording()
    calls = _count_entrance(monkeypatch)
    identify(recording, tip, Method.FIT, stimulus=named)
    assert calls == {"recognise_prts": 0, "likely_sample_rate": 0, "sample_rate_hint": 0,
                     "check_recorded_tilt": 1, "tilt_from_array": 0}
