"""FRF features: what the FRF network sees of a sway, instead of a spectrogram.

For every segment j and every harmonic k the stimulus excites up to
:data:`FRF_MAX_FREQUENCY_HZ` (F of them), three numbers, in this channel order:

    Re H_j(f_k),  Im H_j(f_k),  log10(σ_j(f_k) / |U(f_k)|)

with H_j = Y_j / U the FRF of the segment's angle relative to the tilt, from the
drift-free cycle average (:class:`~posture_id.frf.locked.LockedProjection`: whole cycles,
linear drift removed), and σ_j the noise level at that harmonic estimated from the nearest
harmonics the stimulus leaves empty: how far H_j can be trusted there. An input is
(3N, 1, F): one row of F frequencies with 3N channels, which the CNN's blocks of
:mod:`posture_id.learning.network` take like an image one pixel high.
"""

from __future__ import annotations

import numpy as np

from posture_id.frf.locked import LockedOptions, LockedProjection, noise_levels

__all__ = ["FRF_FEATURE_DEFINITION", "FRF_MAX_FREQUENCY_HZ", "frf_features", "frf_width"]

#: Highest stimulated frequency the FRF features hold, Hz.
FRF_MAX_FREQUENCY_HZ = 2.5
_OPTIONS = LockedOptions(drift_order=1, max_frequency_hz=FRF_MAX_FREQUENCY_HZ, weighted=False,
                         neighbours=3)

#: What the FRF features are, written into model checkpoints; a model is refused by code
#: whose definition differs.
FRF_FEATURE_DEFINITION = {
    "version": 1,
    "kind": "frf",
    "channels": "per segment: Re H, Im H, log10(noise level / |U|) at the excited harmonics",
    "cycle_average": "whole cycles from the stimulus's start, linear drift removed",
    "max_frequency_hz": FRF_MAX_FREQUENCY_HZ,
    "noise_neighbours": _OPTIONS.neighbours,
}


def _projection(tilt: np.ndarray, sample_rate_hz: float, period_s: float,
                start_s: float) -> LockedProjection:
    return LockedProjection.for_recording(tilt, np.zeros((len(tilt), 1)), sample_rate_hz,
                                          period_s, start_s, _OPTIONS, "tilt")


def frf_width(tilt: np.ndarray, sample_rate_hz: float, period_s: float,
              start_s: float = 0.0) -> int:
    """F: the excited harmonics up to :data:`FRF_MAX_FREQUENCY_HZ` of this stimulus."""
    return len(_projection(tilt, sample_rate_hz, period_s, start_s).harmonics)


def frf_features(tilt: np.ndarray, sway: np.ndarray, sample_rate_hz: float, period_s: float,
                 start_s: float = 0.0) -> np.ndarray:
    """(B, 3N, 1, F) float32 FRF features of B sways (B, S, N) rad under one tilt (S,) rad.

    Args:
        sample_rate_hz: the samples' rate. period_s: one stimulus cycle, s.
        start_s: where the periodic stimulus starts, s.
    """
    sway = np.asarray(sway, dtype=float)
    b, s, n = sway.shape
    projection = _projection(np.asarray(tilt, dtype=float), sample_rate_hz, period_s, start_s)
    u = projection.all_harmonics(np.asarray(tilt, dtype=float))  # (P/2,)
    y = projection.all_harmonics(np.moveaxis(sway, 1, 0).reshape(s, b * n))  # (P/2, B·N)
    rows = projection.harmonics - 1
    h = y[rows] / u[rows, None]  # (F, B·N)
    noise = noise_levels(np.abs(y) ** 2, projection.excited, rows, _OPTIONS.neighbours)
    with np.errstate(divide="ignore"):
        log_noise = np.log10(np.maximum(noise / np.abs(u[rows, None]), 1e-12))
    out = np.stack([h.real, h.imag, log_noise])  # (3, F, B·N)
    out = out.reshape(3, len(rows), b, n).transpose(2, 3, 0, 1)  # (B, N, 3, F)
    return out.reshape(b, 3 * n, 1, len(rows)).astype(np.float32)
