"""Spectrogram images of body sway (docs/model.md §6).

The STFT equals MATLAB's ``spectrogram(x, 250, 135, 250, 50)``: symmetric Hamming window
of 250 samples, hop 115 (overlap 135), FFT length 250 (0.2 Hz bins), no detrending, no
scaling, each segment's FFT taken from its first sample; 6051 samples give exactly 51
windows; the first 51 bins (0–10 Hz) are kept: a (51 frequencies × 51 windows) complex
matrix per signal.

- Modular image of module i (3 channels): |S| of segment i (above joint i), |S| of the
  segment below (the platform tilt for the ankle), and angle(S_above) − angle(S_below)
  wrapped to (−π, π].
- Monolithic image (2N − 1 channels): |S| of each segment, then the phase differences
  of neighbouring segments (the tilt, the same in every trial, is left out).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

__all__ = [
    "WINDOW",
    "HOP",
    "NFFT",
    "N_BINS",
    "N_WINDOWS",
    "FS_HZ",
    "FEATURE_DEFINITION",
    "stft",
    "modular_images",
    "monolithic_images",
    "wrap_phase",
]

WINDOW = 250
OVERLAP = 135
HOP = WINDOW - OVERLAP
NFFT = 250
#: Sample rate the features are defined for (docs/model.md §6, the 5th argument of spectrogram).
FS_HZ = 50.0
N_BINS = 51
N_WINDOWS = 51

#: What the images are, written into data-set manifests and model checkpoints; a model is
#: refused by code whose definition differs.
FEATURE_DEFINITION = {
    "version": 1,
    "stft": f"MATLAB spectrogram(x, {WINDOW}, {OVERLAP}, {NFFT}, {FS_HZ:g}), symmetric "
            f"Hamming window, first {N_BINS} bins, {N_WINDOWS} windows",
    "sample_rate_hz": FS_HZ,
    "window": WINDOW,
    "overlap": OVERLAP,
    "nfft": NFFT,
    "bins": N_BINS,
    "windows": N_WINDOWS,
    "modular": "(N, 3, 51, 51): |S_above|, |S_below| (the tilt below the ankle), "
               "wrapped phase difference",
    "monolithic": "(2N-1, 51, 51): |S| of each segment, neighbour phase differences",
    "targets": "(N, 5): kp, ki, kd, delay_s normalised (p - p0)/p0, class C",
}


@lru_cache(maxsize=1)
def _window() -> np.ndarray:
    """The symmetric Hamming window, MATLAB's ``hamming(250)``: 0.54 − 0.46 cos(2πn/(L−1))
    (written out: importing scipy.signal for it costs half a second of start-up)."""
    n = np.arange(WINDOW)
    return 0.54 - 0.46 * np.cos(2.0 * np.pi * n / (WINDOW - 1))


def stft(x: np.ndarray) -> np.ndarray:
    """STFT of signals (..., S) with S ≥ 250 + 50·115 samples → (..., 51, 51) complex.

    Axis −2 is frequency (0, 0.2, …, 10 Hz), axis −1 the window (segment j starts at
    sample 115·j). The 51 windows are strided views of the signal, windowed and
    transformed in one batched real FFT.
    """
    x = np.asarray(x)
    need = WINDOW + (N_WINDOWS - 1) * HOP
    if x.shape[-1] < need:
        raise ValueError(f"STFT needs at least {need} samples, got {x.shape[-1]}")
    frames = np.lib.stride_tricks.sliding_window_view(x[..., :need], WINDOW, axis=-1)[..., ::HOP, :]
    import scipy.fft  # loaded with the first spectrogram, not with every command

    spectrum = scipy.fft.rfft(frames * _window(), n=NFFT, axis=-1)  # (..., windows, bins)
    return np.swapaxes(spectrum[..., :N_BINS], -1, -2)


def wrap_phase(phi: np.ndarray) -> np.ndarray:
    """Angles wrapped to (−π, π]."""
    wrapped = np.angle(np.exp(1j * phi))
    return np.where(wrapped == -np.pi, np.pi, wrapped)


def modular_images(tilt_s: np.ndarray, segments_s: np.ndarray) -> np.ndarray:
    """Modular images from spectra.

    Args:
        tilt_s: (51, 51) complex spectrum of the tilt.
        segments_s: (T, N, 51, 51) complex spectra of the N segments of T trials.
    Returns:
        (T, N, 3, 51, 51) float32: |S_above|, |S_below|, wrapped phase difference.
    """
    t, n = segments_s.shape[:2]
    below = np.concatenate(
        [np.broadcast_to(tilt_s, (t, 1, *tilt_s.shape)), segments_s[:, :-1]], axis=1
    )
    out = np.empty((t, n, 3, N_BINS, N_WINDOWS), dtype=np.float32)
    out[:, :, 0] = np.abs(segments_s)
    out[:, :, 1] = np.abs(below)
    out[:, :, 2] = wrap_phase(np.angle(segments_s) - np.angle(below))
    return out


def monolithic_images(segments_s: np.ndarray) -> np.ndarray:
    """(T, N, 51, 51) complex spectra → (T, 2N − 1, 51, 51) float32 monolithic images."""
    t, n = segments_s.shape[:2]
    out = np.empty((t, 2 * n - 1, N_BINS, N_WINDOWS), dtype=np.float32)
    out[:, :n] = np.abs(segments_s)
    out[:, n:] = wrap_phase(np.angle(segments_s[:, 1:]) - np.angle(segments_s[:, :-1]))
    return out
