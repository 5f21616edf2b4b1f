"""Any periodic tilt as labs run it, found in the tilt column (posture_id/simulation/
periodic.py): sinusoids, sums of sines and multisines between level stretches, with a
fade-in and a platform's distortion; the FRF and the locked analysis on them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from posture_id.bodies.anthropometry import winter_body_file
from posture_id.bodies.body import load_body
from posture_id.errors import RecordingError
from posture_id.frf import frequency_response
from posture_id.frf.locked import LockedProjection
from posture_id.models.ic.model import IC
from posture_id.models.ic.subjects import ic_recording
from posture_id.recording import Recording
from posture_id.simulation.periodic import find_periodic
from posture_id.simulation.protocols import MultisineProtocol
from posture_id.simulation.stimulus import tilt_from_array
from posture_id.trials import prepare_trial


def lab_tilt(shape, rate_hz: float, lead_s: float, moving_s: float, tail_s: float,
             fade_s: float = 0.0, noise_deg: float = 0.0, offset_deg: float = 0.0,
             seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(t (S,) s, tilt (S,) rad): level for ``lead_s``, ``shape(τ)`` (deg, τ from the
    start of the motion) for ``moving_s`` with a raised-cosine fade-in and fade-out of
    ``fade_s``, level for ``tail_s``; a constant offset and white noise on the column."""
    t = np.arange(int(round((lead_s + moving_s + tail_s) * rate_hz))) / rate_hz
    tau = t - lead_s
    envelope = ((tau >= 0) & (tau < moving_s)).astype(float)
    if fade_s:
        rising = (tau >= 0) & (tau < fade_s)
        envelope[rising] = 0.5 - 0.5 * np.cos(np.pi * tau[rising] / fade_s)
        falling = (tau > moving_s - fade_s) & (tau < moving_s)
        envelope[falling] = 0.5 - 0.5 * np.cos(np.pi * (moving_s - tau[falling]) / fade_s)
    x = shape(tau) * envelope + offset_deg
    x = x + noise_deg * np.random.default_rng(seed).standard_normal(len(t))
    return t, np.radians(x)


def sinusoid(f_hz: float, amplitude_deg: float, distortion: float = 0.0):
    """A sinusoid with a platform's third and fifth harmonics (``distortion`` and half of
    it, shares of the amplitude)."""
    def shape(tau):
        w = 2 * np.pi * f_hz * tau
        return amplitude_deg * (np.sin(w) + distortion * np.sin(3 * w + 0.4)
                                + 0.5 * distortion * np.sin(5 * w + 1.1))
    return shape


@pytest.mark.parametrize("f_hz", [0.1, 0.2, 0.4])
@pytest.mark.parametrize("rate_hz", [100.0, 1000.0])
def test_a_sinusoid_between_level_stretches_is_found_exactly(f_hz, rate_hz):
    t, tilt = lab_tilt(sinusoid(f_hz, 4.0, distortion=0.06), rate_hz, lead_s=60,
                       moving_s=64 if f_hz != 0.1 else 80, tail_s=56, fade_s=1 / f_hz,
                       noise_deg=0.01, offset_deg=0.2)
    found = find_periodic(t, tilt)
    assert found is not None and found.kind == "sinusoid"
    assert found.period_samples == round(rate_hz / f_hz)  # exact to the sample
    assert found.frequencies_hz == pytest.approx((f_hz,), rel=1e-9)
    # the distortion harmonics are named and not driven
    assert found.distortion_hz[:2] == pytest.approx((3 * f_hz, 5 * f_hz), rel=1e-9)
    # the steady part leaves out the fade-in and the fade-out: where it starts and ends
    # the amplitude is within 3 % of its own (the raised cosine is flat at its ends, and
    # the column's noise hides less), and it holds every whole cycle between the fades
    moving_s, fade_s = (64 if f_hz != 0.1 else 80), 1 / f_hz
    end_s = found.start_s + found.cycles / f_hz

    def envelope(s):
        tau = s - 60
        return min(0.5 - 0.5 * math.cos(math.pi * min(tau / fade_s, 1.0)),
                   0.5 - 0.5 * math.cos(math.pi * min((moving_s - tau) / fade_s, 1.0)))

    assert envelope(found.start_s) >= 0.97 and envelope(end_s) >= 0.97
    assert found.cycles >= math.floor((moving_s - 2 * fade_s) * f_hz + 1e-9)
    assert found.amplitudes_deg[0] == pytest.approx(4.0, rel=0.01)


def test_a_sum_of_sines_and_a_multisine_are_found_with_their_frequencies():
    def sines(tau):
        return (0.5 * np.sin(2 * np.pi * 0.1 * tau) + 0.3 * np.sin(2 * np.pi * 0.3 * tau + 1)
                + 0.2 * np.sin(2 * np.pi * 0.7 * tau + 2))

    t, tilt = lab_tilt(sines, 100.0, 30, 80, 30, fade_s=5.0, noise_deg=0.002)
    found = find_periodic(t, tilt)
    assert found.kind == "sum of sines" and found.period_samples == 1000
    assert found.frequencies_hz == pytest.approx((0.1, 0.3, 0.7), rel=1e-9)
    assert found.distortion_hz == ()

    protocol = MultisineProtocol(period_s=20.0, harmonics=(1, 2, 3, 5, 8, 12, 18, 27, 40),
                                 amplitude_deg=2.0, cycles=5)
    profile = protocol.profile()
    t, tilt = lab_tilt(lambda tau: np.degrees(profile.angle(tau)), 200.0, 20, 100, 25,
                       fade_s=4.0, noise_deg=0.002)
    found = find_periodic(t, tilt)
    assert found.kind == "multisine" and found.period_samples == 4000
    assert found.frequencies_hz == pytest.approx(tuple(protocol.frequencies_hz), rel=1e-9)


@pytest.mark.parametrize("column", ["noise", "step", "ramp", "one cycle"])
def test_what_is_not_a_repeated_tilt_is_not_taken_for_one(column):
    rate = 100.0
    t = np.arange(6000) / rate
    rng = np.random.default_rng(3)
    tilt = {"noise": np.radians(rng.standard_normal(len(t))),
            "step": np.radians(np.where(t > 20, 1.0, 0.0)),
            "ramp": np.radians(0.05 * t),
            "one cycle": np.radians(np.where((t > 10) & (t < 20),
                                             np.sin(2 * np.pi * 0.1 * (t - 10)), 0.0))}[column]
    assert find_periodic(t, tilt) is None


def _ic_trial(tilt_t, tilt, seed=1):
    body = load_body(winter_body_file(1.75, 70.0, 1))
    params = IC.default_parameters(body)
    recording, _ = ic_recording(body, params, tilt_from_array(tilt_t, tilt, "lab tilt"),
                                locked_share=None, seed=seed, sensor_noise_deg=0.0)
    return body, params, recording


def test_a_sinusoid_trials_frf_lists_only_its_own_frequency_and_is_the_models():
    t, tilt = lab_tilt(sinusoid(0.2, 1.0, distortion=0.08), 100.0, 60, 64, 56, fade_s=5)
    body, params, recording = _ic_trial(t, tilt)
    trial = prepare_trial(recording, None, rate_hz=None)
    assert trial.stimulus.period_s == pytest.approx(5.0)
    assert any("distortion" in n for n in trial.notices)
    frf = frequency_response(trial, body)
    assert frf.frequencies_hz == pytest.approx([0.2])
    exact = IC.closed_loop(params, IC.plant(body), np.array([2j * np.pi * 0.2]))[0]
    measured = frf.response[0, -1]
    assert abs(measured) == pytest.approx(abs(exact), rel=0.01)
    assert math.degrees(abs(np.angle(measured / exact))) < 1.0
    # the locked analysis compares the driven frequency alone, and never the level tail
    projection = LockedProjection.for_trial(trial)
    assert projection.frequencies_hz == pytest.approx([0.2])
    assert projection.start + projection.cycles * projection.period <= round(124 * 50)


def test_a_trial_too_short_for_its_period_says_so(tmp_path):
    t, tilt = lab_tilt(sinusoid(0.1, 1.0), 50.0, 10, 15, 10)
    recording = Recording(t, tilt, np.zeros((len(t), 1)) + 0.01 * np.sin(t)[:, None],
                          ("body",), name="short.csv")
    trial = prepare_trial(recording, None, rate_hz=None)
    with pytest.raises(RecordingError, match="two whole cycles"):
        frequency_response(trial)


def test_a_labs_sinusoid_trial_as_written_gives_the_frf_at_its_one_frequency(tmp_path, capsys):
    """The trial a new user brings: tab-separated, a title line, times in ms, a ±4°
    sinusoid at 0.2 Hz with the platform's distortion between 60 and 124 s of 180 s; the
    sway 0.8 times the tilt, 0.3 s late. By the command line alone."""
    import json

    from posture_id.cli import main

    rate = 100.0
    t, tilt = lab_tilt(sinusoid(0.2, 4.0, distortion=0.04), rate, 60, 64, 56, noise_deg=0.005)
    sway = 0.8 * np.interp(t - 0.3, t, np.degrees(tilt), left=0.0)
    sway += 0.05 * np.random.default_rng(5).standard_normal(len(t))
    lines = ["Trial 7 - sinusoid 0.2 Hz - subject 3",
             "Time [ms]\tPlatform [deg]\tCOM [deg]"]
    lines += [f"{1000 * a:.0f}\t{np.degrees(b):.5f}\t{c:.5f}" for a, b, c in zip(t, tilt, sway,
                                                                                 strict=True)]
    path = tmp_path / "trial07.txt"
    path.write_text("\n".join(lines) + "\n")
    out = tmp_path / "trial07.frf.json"
    assert main(["frf", str(path), "--angle-columns", "COM", "--time-column", "Time",
                 "--tilt-column", "Platform", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "sinusoid 0.2 Hz" in err and "distortion" in err
    frf = json.loads(out.read_text())
    assert frf["frequencies_hz"] == pytest.approx([0.2])
    channel = frf["channels"]["COM"]
    assert channel["gain"][0] == pytest.approx(0.8, rel=0.01)
    assert channel["phase_deg"][0] == pytest.approx(-360 * 0.2 * 0.3, abs=1.0)


@pytest.mark.parametrize("noise_deg", [0.0, 0.0005])
def test_a_platform_resting_at_another_level_after_the_sine_is_not_taken_for_cycles(noise_deg):
    """A real plate's trial: level at 0° for 60 s, ±3.9° at 0.4 Hz for 60 s, then at rest
    at −0.1° for 60 s (longer than it moved), the column rounded to 0.001°. The rest at the
    other level repeats itself but does not move: the sinusoid's cycles are found, and the
    motion ends where the platform comes to rest."""
    t = np.arange(18001) / 100.0
    tilt = np.where((t >= 60) & (t < 120), 3.9 * np.sin(2 * np.pi * 0.4 * (t - 60)), 0.0)
    tilt[t >= 120] = -0.1
    tilt = np.round(tilt + noise_deg * np.random.default_rng(3).standard_normal(len(t)), 3)
    found = find_periodic(t, np.radians(tilt))
    assert found is not None and found.kind == "sinusoid"
    assert found.frequencies_hz == pytest.approx((0.4,), rel=1e-3)
    assert 60 <= found.start_s < 62.5 and found.cycles >= 22
    assert found.moving_until_s == pytest.approx(120, abs=0.1)


def test_a_real_platforms_irregular_cycles_are_all_analysed():
    """A real platform at 0.4 Hz: each cycle's amplitude and phase off by about 0.6 % (its
    cycles differ by up to 1.8 % of the peak; the public force-plate study's, up to
    1.9 %), the column rounded to 0.001°, at rest at another level after. Every whole cycle but the
    last is analysed, at the frequency the platform drove."""
    rng = np.random.default_rng(7)
    t = np.arange(18001) / 100.0
    tau = t - 60
    k = np.clip(np.floor(tau * 0.4).astype(int), 0, 23)
    amplitude = 3.79 * (1 + 0.006 * rng.standard_normal(24))
    phase = 0.006 * rng.standard_normal(24)
    tilt = np.where((tau >= 0) & (tau < 60),
                    amplitude[k] * np.sin(2 * np.pi * 0.4 * tau + phase[k]), 0.0)
    tilt[tau >= 60] = -0.05
    found = find_periodic(t, np.radians(np.round(tilt, 3)))
    assert found is not None and found.kind == "sinusoid"
    assert found.frequencies_hz == pytest.approx((0.4,), rel=1e-6)
    assert found.cycles >= 23 and 60 <= found.start_s < 60.5
    assert found.moving_until_s == pytest.approx(120, abs=0.1)
