"""Spectrogram features (docs/model.md §6) against a direct numpy implementation."""

from __future__ import annotations

import numpy as np
import pytest

from posture_id.learning.features.spectrograms import (
    HOP,
    N_BINS,
    N_WINDOWS,
    WINDOW,
    modular_images,
    monolithic_images,
    stft,
    wrap_phase,
)


def _direct_stft(x: np.ndarray) -> np.ndarray:
    """MATLAB spectrogram(x, 250, 135, 250, 50): segments from sample 115·j, symmetric
    Hamming, unscaled 250-point FFT, first 51 bins — written out by hand."""
    n = np.arange(WINDOW)
    hamming = 0.54 - 0.46 * np.cos(2 * np.pi * n / (WINDOW - 1))
    n_windows = (x.shape[-1] - (WINDOW - HOP)) // HOP
    out = np.empty((N_BINS, n_windows), dtype=complex)
    k = np.arange(N_BINS)[:, None]
    basis = np.exp(-2j * np.pi * k * n / WINDOW)
    for j in range(n_windows):
        out[:, j] = basis @ (x[j * HOP : j * HOP + WINDOW] * hamming)
    return out


def test_stft_equals_direct_implementation():
    x = np.random.default_rng(0).standard_normal(6051)
    expected = _direct_stft(x)
    assert expected.shape == (51, 51)  # 6051 samples give exactly 51 windows
    np.testing.assert_allclose(stft(x), expected, rtol=0, atol=1e-11)
    batch = np.stack([x, 2 * x])
    np.testing.assert_allclose(stft(batch)[1], 2 * expected, atol=1e-10)


def test_stft_of_a_sine_peaks_at_its_bin():
    t = np.arange(6051) / 50.0
    s = stft(np.sin(2 * np.pi * 2.0 * t))  # 2 Hz = bin 10
    assert np.all(np.argmax(np.abs(s), axis=0) == 10)


def test_stft_needs_enough_samples():
    with pytest.raises(ValueError, match="at least 6000 samples"):
        stft(np.zeros(5000))


def test_images_channels():
    rng = np.random.default_rng(1)
    seg = rng.standard_normal((2, 3, N_BINS, N_WINDOWS)) + 1j * rng.standard_normal(
        (2, 3, N_BINS, N_WINDOWS))
    tilt = rng.standard_normal((N_BINS, N_WINDOWS)) + 1j
    mod = modular_images(tilt, seg)
    assert mod.shape == (2, 3, 3, 51, 51) and mod.dtype == np.float32
    np.testing.assert_allclose(mod[:, 0, 1], np.broadcast_to(np.abs(tilt), (2, 51, 51)),
                               rtol=1e-6)
    np.testing.assert_allclose(mod[:, 2, 1], np.abs(seg[:, 1]), rtol=1e-6)
    np.testing.assert_allclose(
        np.exp(1j * mod[:, 1, 2]), np.exp(1j * (np.angle(seg[:, 1]) - np.angle(seg[:, 0]))),
        atol=1e-5)
    assert mod[:, :, 2].max() <= np.pi and mod[:, :, 2].min() > -np.pi
    mono = monolithic_images(seg)
    assert mono.shape == (2, 5, 51, 51)
    np.testing.assert_allclose(mono[:, 3], mod[:, 1, 2], atol=1e-6)


def test_wrap_phase_interval():
    phi = np.array([-np.pi, np.pi, 3 * np.pi, -3 * np.pi + 1e-3, 0.5])
    w = wrap_phase(phi)
    assert np.all(w > -np.pi) and np.all(w <= np.pi)
    np.testing.assert_allclose(np.exp(1j * w), np.exp(1j * phi), atol=1e-12)
