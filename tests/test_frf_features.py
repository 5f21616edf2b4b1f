"""FRF features against known answers: a sway equal to the tilt, scaled and delayed."""

from __future__ import annotations

import numpy as np
import pytest

from posture_id.frf.features import FRF_MAX_FREQUENCY_HZ, frf_features, frf_width
from posture_id.simulation import prts

RATE = 50.0


@pytest.mark.parametrize("states, cycles", [(242, 2), (80, 6)])
def test_a_scaled_delayed_copy_of_the_tilt_has_the_analytic_frf(states, cycles):
    stim = prts(states=states, cycles=cycles)
    t = np.arange(int(round(stim.duration * RATE)) + 1) / RATE
    tilt = stim.angle(t)
    delay = 0.1  # 5 samples; the cycle is periodic, so the shift wraps around exactly
    shifted = stim.angle((t - delay) % stim.period_s)
    sway = np.stack([tilt, 2.0 * shifted, -0.5 * tilt], axis=1)[None]  # (1, S, 3)
    features = frf_features(tilt, sway, RATE, stim.period_s)
    width = frf_width(tilt, RATE, stim.period_s)
    assert features.shape == (1, 9, 1, width)
    f = (2 * np.arange(width) + 1) / stim.period_s  # the odd harmonics a PRTS excites
    assert f[-1] <= FRF_MAX_FREQUENCY_HZ < f[-1] + 2 / stim.period_s
    h = features[0, 0::3, 0] + 1j * features[0, 1::3, 0]  # (3, F): Re, Im per segment
    np.testing.assert_allclose(h[0], 1.0, atol=1e-5)
    np.testing.assert_allclose(h[1], 2.0 * np.exp(-2j * np.pi * f * delay), atol=1e-4)
    np.testing.assert_allclose(h[2], -0.5, atol=1e-5)
    # nothing but the locked response: the empty harmonics hold only the tilt's aliasing
    # (an odd number of samples per cycle folds odd harmonics onto even ones), < 0.3 % of
    # the response at every harmonic
    assert np.all(features[0, 2::3, 0] - np.log10(np.abs(h)) < -2.5)


def test_a_drifting_noisy_sway_shows_its_noise_level():
    stim = prts(states=80, cycles=6)
    t = np.arange(int(round(stim.duration * RATE)) + 1) / RATE
    tilt = stim.angle(t)
    rng = np.random.default_rng(0)
    noise = np.radians(0.05) * rng.standard_normal((1, len(t), 1))
    drift = np.radians(2.0) * (t / t[-1])[None, :, None]
    clean = frf_features(tilt, tilt[None, :, None] + drift, RATE, stim.period_s)
    noisy = frf_features(tilt, tilt[None, :, None] + drift + noise, RATE, stim.period_s)
    np.testing.assert_allclose(clean[0, 0], 1.0, atol=1e-5)  # the drift is gone
    assert np.median(noisy[0, 2]) > np.median(clean[0, 2]) + 3
