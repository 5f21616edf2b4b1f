"""Stimulus-locked analysis against known answers: linear filters driven by the PRTS, a
pure delay, polynomial drift, white noise of a known share."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest
from scipy import signal

from posture_id.cli import main
from posture_id.errors import PostureIdError
from posture_id.frf import FrfOptions, cycle_average, frequency_response, frequency_response_arrays
from posture_id.recording import Recording
from posture_id.simulation import prts, simulate
from posture_id.trials import prepare_trial

RATE = 50.0


def _prts_samples(states=80, cycles=4, amplitude_deg=1.0):
    stimulus = prts(amplitude_deg, cycles, states)
    t = np.arange(int(round(stimulus.duration * RATE)) + 1) / RATE
    return stimulus, t, stimulus.angle(t)


@pytest.mark.parametrize("states", [80, 242])
def test_frf_of_a_linear_filter_is_its_transfer_function(states):
    """The periodic steady state of a discrete filter driven by the PRTS: at every excited
    harmonic the FRF equals H(e^{jωT}) (scipy.signal.freqz), and the coherence is 1."""
    stimulus, _, u = _prts_samples(states, cycles=3)
    b, a = signal.butter(2, 1.2, fs=RATE)  # a 1.2 Hz low-pass
    y = signal.lfilter(b, a, u)
    result = frequency_response_arrays(u, y[:, None], RATE, stimulus.period_s, ("y",),
                                       FrfOptions(skip_cycles=1, drift_order=0))
    _, expected = signal.freqz(b, a, worN=result.frequencies_hz, fs=RATE)
    assert result.cycles == 2
    np.testing.assert_allclose(result.response[:, 0], expected, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(result.coherence[:, 0], 1.0, atol=1e-9)
    # the analysed frequencies are harmonics of the cycle
    fundamental = 1.0 / stimulus.period_s
    harmonics = result.frequencies_hz / fundamental
    np.testing.assert_allclose(harmonics, np.round(harmonics), atol=1e-9)
    assert result.frequencies_hz[-1] <= 3.0 and len(result.frequencies_hz) > 10


def test_a_band_holds_the_tilt_power_weighted_mean_of_the_frf():
    """Σ conj(U)·H·U / Σ|U|² over a band's harmonics, the band at their geometric mean."""
    stimulus, _, u = _prts_samples(80, cycles=3)
    b, a = signal.butter(2, 1.2, fs=RATE)
    y = signal.lfilter(b, a, u)
    bands = 6
    result = frequency_response_arrays(u, y[:, None], RATE, stimulus.period_s, ("y",),
                                       FrfOptions(skip_cycles=1, drift_order=0, bands=bands))
    every = frequency_response_arrays(u, y[:, None], RATE, stimulus.period_s, ("y",),
                                      FrfOptions(skip_cycles=1, drift_order=0))
    p = int(round(stimulus.period_s * RATE))
    power = np.abs(np.fft.rfft(u[p : 2 * p])) ** 2
    f = every.frequencies_hz
    weights = power[np.round(f * stimulus.period_s).astype(int)]
    edges = np.geomspace(f[0], f[-1] * (1 + 1e-9), bands + 1)
    which = np.clip(np.searchsorted(edges, f, side="right") - 1, 0, bands - 1)
    members = [np.flatnonzero(which == k) for k in range(bands)]
    members = [m for m in members if len(m)]
    _, h = signal.freqz(b, a, worN=f, fs=RATE)
    expected = [np.sum(weights[m] * h[m]) / np.sum(weights[m]) for m in members]
    np.testing.assert_allclose(result.response[:, 0], expected, rtol=1e-9)
    np.testing.assert_allclose(result.frequencies_hz,
                               [np.exp(np.log(f[m]).mean()) for m in members], rtol=1e-12)
    assert result.coherence is not None and np.all(result.coherence <= 1.0)


def test_a_pure_delay_has_a_linear_phase():
    stimulus, _, u = _prts_samples(80, cycles=3)
    k = 7  # 140 ms
    y = np.concatenate([np.zeros(k), u[:-k]])
    result = frequency_response_arrays(u, y[:, None], RATE, stimulus.period_s, ("late",),
                                       FrfOptions(skip_cycles=1, drift_order=0))
    np.testing.assert_allclose(result.gain[:, 0], 1.0, rtol=1e-9)
    np.testing.assert_allclose(result.phase_deg[:, 0],
                               -360.0 * result.frequencies_hz * k / RATE, atol=1e-6)


def test_cycle_averaging_removes_a_drift_ten_times_the_locked_amplitude():
    stimulus, t, u = _prts_samples(80, cycles=4)
    b, a = signal.butter(2, 1.2, fs=RATE)
    locked = signal.lfilter(b, a, u)
    p = int(round(stimulus.period_s * RATE))
    span = slice(p, 4 * p)
    tau = (t - t[p]) / (t[4 * p - 1] - t[p])
    drift = 10 * np.ptp(locked[span]) * (0.3 + tau - 1.7 * tau**2)
    clean = frequency_response_arrays(u, locked[:, None], RATE, stimulus.period_s, ("y",),
                                      FrfOptions(skip_cycles=1, drift_order=0))
    removed = frequency_response_arrays(u, (locked + drift)[:, None], RATE, stimulus.period_s,
                                        ("y",), FrfOptions(skip_cycles=1, drift_order=2))
    np.testing.assert_allclose(removed.response, clean.response, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(removed.coherence, 1.0, atol=1e-8)
    assert removed.locked_share[0] == pytest.approx(1.0, abs=1e-9)  # all locked but drift
    average = cycle_average(locked + drift, p, skip_cycles=1, drift_order=2)
    # the drift's constant is the cycle average's: compare both about their means
    offset = drift[span].mean() - average.drift.mean()
    np.testing.assert_allclose(average.mean, locked[p : 2 * p] + offset,
                               atol=1e-9 * np.ptp(drift))
    np.testing.assert_allclose(average.drift - average.drift.mean(),
                               drift[span] - drift[span].mean(), atol=1e-9 * np.ptp(drift))
    # and without drift removal the same data give a wrong FRF (the test can fail)
    kept = frequency_response_arrays(u, (locked + drift)[:, None], RATE, stimulus.period_s,
                                     ("y",), FrfOptions(skip_cycles=1, drift_order=0))
    assert np.max(np.abs(kept.response - clean.response) / np.abs(clean.response)) > 0.05


def test_locked_share_and_coherence_of_a_noisy_response():
    """White noise of a chosen share of the variance: the cycle average keeps 1/C of the
    noise, (σ_l² + σ_n²/C)/(σ_l² + σ_n²) uncorrected; the locked share, corrected for it,
    is the true σ_l²/(σ_l² + σ_n²); coherence falls below 1."""
    stimulus, _, u = _prts_samples(80, cycles=10)
    b, a = signal.butter(2, 1.2, fs=RATE)
    locked = signal.lfilter(b, a, u)
    p = int(round(stimulus.period_s * RATE))
    var_locked = float(np.var(locked[p : 10 * p]))
    share = 0.2  # as in real sway: 20 % stimulus-locked
    sd = math.sqrt(var_locked * (1 - share) / share)
    rng = np.random.default_rng(3)
    y = locked + sd * rng.standard_normal(len(locked))
    result = frequency_response_arrays(u, y[:, None], RATE, stimulus.period_s, ("y",),
                                       FrfOptions(skip_cycles=1, drift_order=0))
    cycles = result.cycles
    assert result.locked_share[0] == pytest.approx(share, rel=0.1)
    averaged = cycle_average(y[p : 10 * p], p)
    assert averaged.locked_share == pytest.approx(result.locked_share[0])
    expected = (var_locked + sd**2 / cycles) / (var_locked + sd**2)
    assert averaged.uncorrected_share == pytest.approx(expected, rel=0.05)
    assert 0 < np.median(result.coherence) < 0.999


def test_frf_of_a_simulated_recording(tip, tmp_path):
    trial = simulate(tip)  # default parameters, 2 cycles of the 242-state PRTS
    recording = trial.to_recording()
    result = frequency_response(prepare_trial(recording, rate_hz=None), tip,
                                FrfOptions(drift_order=0))
    assert result.channels == (*tip.segment_names, "body COM")
    assert result.cycles == 2 and result.period_s == pytest.approx(60.5)
    assert np.all(np.isfinite(result.response))
    # a noise-free simulation is stimulus-locked but for the start-up transient
    assert np.all(result.locked_share > 0.9)
    # the body COM follows slow tilts in phase and lags behind faster ones
    assert 0.2 < result.gain[0, -1] < 1.5 and abs(result.phase_deg[0, -1]) < 30
    near_08_hz = int(np.argmin(np.abs(result.frequencies_hz - 0.8)))
    assert result.phase_deg[near_08_hz, -1] < result.phase_deg[0, -1] - 45
    text = result.to_json()
    data = json.loads(text)
    assert set(data["channels"]) == set(result.channels)
    fig = result.plot(tmp_path / "frf.png")
    assert len(fig.axes) == 3 and (tmp_path / "frf.png").stat().st_size > 10_000
    assert "body COM" in result.summary()


def test_frf_command_line(tip, tmp_path, capsys):
    recording = simulate(tip).to_recording()
    csv = tmp_path / "rec.csv"
    recording.to_csv(csv)
    out = tmp_path / "frf.json"
    assert main(["frf", str(csv), "--body", str(tip.urdf_path), "--out", str(out), "--plot",
                 str(tmp_path / "frf.png"), "--bands", "12"]) == 0
    data = json.loads(out.read_text())
    assert len(data["frequencies_hz"]) <= 12
    assert data["channels"]["body COM"]["coherence"] is not None
    assert data["provenance"]["options"]["bands"] == 12
    # a lab's COM-only recording: no body, the columns as they are
    com = tip.com_angles(recording.theta)[:, 0]
    only = tmp_path / "com_only.csv"
    only.write_text("time_s,tilt_deg,com_deg\n" + "".join(
        f"{t:.6f},{np.degrees(a):.12g},{np.degrees(c):.12g}\n"
        for t, a, c in zip(recording.time, recording.tilt, com, strict=True)))
    assert main(["frf", str(only), "--bands", "12", "--out", str(tmp_path / "com.json")]) == 0
    alone = json.loads((tmp_path / "com.json").read_text())
    assert list(alone["channels"]) == ["com"]
    np.testing.assert_allclose(alone["channels"]["com"]["gain"],
                               data["channels"]["body COM"]["gain"], rtol=1e-6)


def test_bad_input_is_refused(tip):
    recording = simulate(tip).to_recording()
    noise = Recording(recording.time, recording.tilt + 2e-3 * np.sin(recording.time),
                      recording.theta, recording.segments)
    with pytest.raises(PostureIdError, match="^rec.csv: .*not a PRTS"):
        frequency_response(prepare_trial(replace(noise, name="rec.csv"), rate_hz=None), tip)
    uneven = Recording(recording.time * (1 + 0.05 * (recording.time / recording.time[-1])),
                       recording.tilt, recording.theta, recording.segments, "rec.csv")
    with pytest.raises(PostureIdError, match="not evenly spaced"):
        frequency_response(prepare_trial(uneven, rate_hz=None), tip)
    trial = prepare_trial(replace(recording, name="rec.csv"), rate_hz=None)
    with pytest.raises(PostureIdError, match="leaves none to analyse"):
        frequency_response(trial, tip, FrfOptions(skip_cycles=2))
    with pytest.raises(PostureIdError, match="whole number of samples"):
        frequency_response(trial, tip, period_s=60.51)
    with pytest.raises(PostureIdError, match="bands must be an integer"):
        FrfOptions(bands=-1)


@pytest.mark.parametrize(("states", "cycles"), [(242, 2), (80, 6)])
def test_pure_noise_shows_no_locked_sway_and_no_significant_coherence(states, cycles):
    """Random sway with no response to the tilt at all (low-passed noise, the spectrum of
    body sway): the noise-corrected locked share is about 0 (uncorrected it would be about
    1/C), and the coherence clears its 5 % significance level at about 5 % of the
    frequencies, never at most of them (uncorrected: 1/C and more, the "locked 44–51 %"
    that pure random sway of 2 cycles used to report)."""
    stimulus, _, u = _prts_samples(states, cycles=cycles)
    rng = np.random.default_rng(17)
    b, a = signal.butter(2, 0.5, fs=RATE)
    shares, significant, coherences = [], [], []
    for _ in range(8):
        y = signal.lfilter(b, a, rng.standard_normal((len(u), 3)), axis=0)
        result = frequency_response_arrays(u, y, RATE, stimulus.period_s, ("a", "b", "c"),
                                           FrfOptions(drift_order=1))
        shares.append(result.locked_share)
        significant.append(result.significant)
        uncorrected = cycle_average(y[: cycles * len(u) // cycles], len(u) // cycles, 0, 1)
        assert np.all(uncorrected.uncorrected_share > 0.5 / cycles)
        coherences.append(result.coherence)
    # clipped at 0, so many draws are exactly 0 and the rest small (the drift removed with
    # the periodic part also takes some of the slow noise out of the remainder)
    assert float(np.median(shares)) < 0.05
    assert float(np.max(shares)) < 0.5 / cycles ** 0.5
    # what the reported median coherence of pure noise was: about 1/C, far from 0
    assert float(np.mean(coherences)) == pytest.approx(1 / cycles, rel=0.2)
    fraction = float(np.mean(np.concatenate(significant)))
    assert 0.02 < fraction < 0.09  # 5 % expected


def test_coherence_level_is_the_noise_quantile():
    """1 − α^{1/(n−1)}: the magnitude-squared coherence of n spectra of pure noise exceeds
    it with probability α (checked by drawing such spectra)."""
    from posture_id.frf.response import coherence_level

    rng = np.random.default_rng(5)
    for n in (2, 6, 20):
        u = rng.standard_normal((20000, n)) + 1j * rng.standard_normal((20000, n))
        y = rng.standard_normal((20000, n)) + 1j * rng.standard_normal((20000, n))
        gamma = (np.abs((np.conj(u) * y).sum(axis=1)) ** 2
                 / ((np.abs(u) ** 2).sum(axis=1) * (np.abs(y) ** 2).sum(axis=1)))
        assert float(np.mean(gamma > coherence_level(n))) == pytest.approx(0.05, abs=0.006)
    assert float(coherence_level(1)) == 1.0


def test_a_linear_response_in_noise_is_significant_and_bands_are_counted():
    """A known linear system (a 1.2 Hz low-pass) under noise of 5× its variance: its
    locked share is 1/6, its coherence clears the level in its passband; with 12 bands
    asked, the summary says how many held a stimulated frequency."""
    stimulus, _, u = _prts_samples(80, cycles=10)
    b, a = signal.butter(2, 1.2, fs=RATE)
    locked = signal.lfilter(b, a, u)
    rng = np.random.default_rng(8)
    y = locked + math.sqrt(5 * np.var(locked)) * rng.standard_normal(len(u))
    result = frequency_response_arrays(u, y[:, None], RATE, stimulus.period_s, ("y",),
                                       FrfOptions(skip_cycles=1, drift_order=0))
    assert result.locked_share[0] == pytest.approx(1 / 6, rel=0.15)
    # significant where the filter passes the tilt, not where it has cut it to below the
    # noise (the local signal-to-noise ratio at each harmonic decides)
    passband = result.frequencies_hz < 0.8
    assert float(np.mean(result.significant[passband])) > 0.8
    assert float(np.mean(result.significant[result.frequencies_hz > 2.0])) < 0.3
    banded = frequency_response_arrays(u, y[:, None], RATE, stimulus.period_s, ("y",),
                                       FrfOptions(skip_cycles=1, drift_order=0, bands=12))
    held = len(banded.frequencies_hz)
    assert held + banded.bands_empty == 12
    first = banded.summary().splitlines()[0]
    assert f"{held} bands" in first
    assert (f"of 12 asked: {banded.bands_empty} held no stimulated" in first) == (held < 12)
