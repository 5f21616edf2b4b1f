"""The white sensor noise of a recording, estimated from its own samples.

Body sway is smooth at the sampling rate (its power lies below a few hertz), so the third
difference of a segment angle is almost all noise: it scales a sinusoid of frequency f by
(2·sin(πf/fs))³ (0.004 at 1.3 Hz and 50 Hz), while white noise of SD σ comes out with SD
√20·σ (20 = C(6, 3)). A robust SD (the median absolute deviation, × 1.4826) keeps the
PRTS's velocity steps from counting; the segments' estimates are pooled by their median.
"""

from __future__ import annotations

import numpy as np

__all__ = ["sensor_noise_deg"]

_MAD_TO_SD = 1.482602218505602


def sensor_noise_deg(theta_rad: np.ndarray) -> float | np.ndarray:
    """Estimated white sensor noise SD, degrees, of (S, N) segment angles (rad) or of a
    batch (B, S, N) (then (B,))."""
    theta = np.asarray(theta_rad, dtype=np.float64)
    third = np.diff(theta, n=3, axis=-2)
    centred = third - np.median(third, axis=-2, keepdims=True)
    sd = _MAD_TO_SD * np.median(np.abs(centred), axis=-2) / np.sqrt(20.0)
    out = np.degrees(np.median(sd, axis=-1))
    return float(out) if out.ndim == 0 else out
