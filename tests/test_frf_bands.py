"""A lab's FRF points (issue 43): Peterka's 11 points, the labs' convention against the
band-averaged spectra computed directly, and the pseudo-impulse response against its
closed form."""

from __future__ import annotations

import numpy as np
import pytest

from posture_id import load_body
from posture_id.errors import PostureIdError
from posture_id.frf.bands import (
    PETERKA_11,
    FrequencyBands,
    common_period_s,
    pseudo_impulse_response,
)
from posture_id.frf.response import FrfOptions, frequency_response_arrays
from posture_id.simulation import prts, simulate


def _stimulated(period_s: float, states: int) -> np.ndarray:
    """The stimulated harmonics of a PRTS cycle up to 3 Hz (every odd one for a PRTS)."""
    profile = prts(1.0, 1, states, period_s / states)
    rate = 50.0
    n = int(round(period_s * rate))
    u = np.abs(np.fft.rfft(profile.angle(np.arange(n) / rate)))
    f = np.fft.rfftfreq(n, 1 / rate)
    keep = (u > 1e-3 * u[1:].max()) & (f > 0) & (f <= 3.0)
    return f[keep]


def test_peterkas_points_are_the_listed_bands_at_the_listed_frequencies():
    f20 = _stimulated(20.0, 80)
    assert f20[:3] == pytest.approx([0.05, 0.15, 0.25])
    groups = PETERKA_11.groups(f20, 20.0)
    listed = [(1, 1), (2, 2), (3, 4), (4, 5), (5, 7), (6, 9), (8, 11), (10, 13), (12, 16),
              (16, 20), (20, 25)]
    assert [(g[0] + 1, g[-1] + 1) for g in groups] == listed
    means = [f20[g].mean() for g in groups]
    np.testing.assert_allclose(means, PETERKA_11.centres_hz, atol=0.051)
    # another cycle (the 242-state PRTS, 60.5 s): the bands keep their frequencies
    f60 = _stimulated(60.5, 242)
    for (low, high), g in zip(PETERKA_11._ranges(), PETERKA_11.groups(f60, 60.5),
                              strict=True):
        assert len(g) >= 1 and np.all((f60[g] >= low) & (f60[g] < high))
        assert low < np.mean(f60[g]) < high


def test_the_labs_convention_is_the_band_averaged_spectra():
    """The first cycle left out, no drift removed, H = Σ conj(U)Y / Σ|U|² over the band's
    harmonics and the cycles: the same to 1e-9 as computing it by hand."""
    stimulus = prts(1.0, 6, 80)
    recording = simulate(load_body(), stimulus=stimulus).to_recording().with_sensor_noise(
        0.05, 3)
    rate, p = recording.sample_rate_hz, 1000
    tilt, sway = recording.tilt, recording.theta
    result = frequency_response_arrays(tilt, sway, rate, 20.0, ("a", "b", "c"),
                                       FrfOptions.lab_convention(PETERKA_11))
    cycles = [slice(c * p, (c + 1) * p) for c in range(1, 6)]
    u = np.stack([np.fft.rfft(tilt[s]) for s in cycles])  # (C, K)
    y = np.stack([np.fft.rfft(sway[s], axis=0) for s in cycles])  # (C, K, M)
    f = np.fft.rfftfreq(p, 1 / rate)
    amplitude = np.abs(u).mean(axis=0)
    excited = np.flatnonzero((amplitude > 1e-3 * amplitude[1:].max()) & (f > 0) & (f <= 3))
    for b, g in enumerate(PETERKA_11.groups(f[excited], 20.0)):
        k = excited[g]
        cross = (np.conj(u[:, k, None]) * y[:, k, :]).sum(axis=(0, 1))
        power = (np.abs(u[:, k]) ** 2).sum()
        np.testing.assert_allclose(result.response[b], cross / power, rtol=1e-9, atol=1e-12)
    assert result.frequencies_hz == pytest.approx(PETERKA_11.centres_hz)
    assert result.cycles == 5


def test_the_pseudo_impulse_response_of_a_pure_delay_is_a_dirichlet_kernel():
    """H_k = e^{−i2πf_kτ} at f_k = k/T, k = 1..K: x(t) = Σ cos(2πk(t − τ)/T)
    = [sin((K + ½)θ)/sin(θ/2) − 1]/2 with θ = 2π(t − τ)/T."""
    period, k, tau = 20.0, 25, 3.3
    f = np.arange(1, k + 1) / period
    t, x = pseudo_impulse_response(f, np.exp(-2j * np.pi * f * tau), rate_hz=22.0)
    assert common_period_s(f) == pytest.approx(period) and len(t) == 440
    theta = 2 * np.pi * (t - tau) / period
    with np.errstate(divide="ignore", invalid="ignore"):
        closed = (np.sin((k + 0.5) * theta) / np.sin(theta / 2) - 1) / 2
    closed = np.where(np.abs(np.sin(theta / 2)) < 1e-12, k, closed)
    np.testing.assert_allclose(x, closed, atol=1e-9)
    assert t[np.argmax(x)] == pytest.approx(tau, abs=1 / 22)
    _, two = pseudo_impulse_response(PETERKA_11.centres_hz,
                                     np.ones((11, 2)) * np.array([1, 2]), 22.0)
    np.testing.assert_allclose(two[:, 1], 2 * two[:, 0])


@pytest.mark.parametrize("make, named", [
    (lambda: FrequencyBands(), "one of the two"),
    (lambda: FrequencyBands(harmonics=((3, 2),)), "1 ≤ first ≤ last"),
    (lambda: FrequencyBands(ranges_hz=((0.5, 0.2),)), "0 ≤ low < high"),
    (lambda: FrfOptions(bands=4, lab_bands=PETERKA_11), "give one"),
    (lambda: pseudo_impulse_response([0.5, 20.0], [1, 1], 22.0), "twice the highest"),
])
def test_bands_that_cannot_be_are_refused(make, named):
    with pytest.raises(PostureIdError, match=named):
        make()


@pytest.mark.parametrize("flags, named", [
    (["--band-preset", "peterka11", "--bands", "5"], "one way of averaging"),
    (["--lab-convention"], "--lab-convention goes with a lab's bands"),
    (["--band-harmonics", "1;x-2"], "'x-2' is not a band"),
    (["--band-harmonics", "1;2;3-40"], "stimulates"),
])
def test_frf_band_flags_are_checked(flags, named, tmp_path, capsys):
    from posture_id.cli import main

    path = tmp_path / "rec.csv"
    simulate(load_body(), stimulus=prts(1.0, 3, 80)).to_recording().to_csv(path)
    assert main(["frf", str(path), *flags, "--out", str(tmp_path / "f.json")]) == 2
    assert named in capsys.readouterr().err
    assert not (tmp_path / "f.json").exists()
