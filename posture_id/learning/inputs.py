"""A network's inputs from sway: spectrogram images or FRF features, batched."""

from __future__ import annotations

import numpy as np

from posture_id.frf.features import frf_features
from posture_id.learning.config import Layout
from posture_id.learning.features.spectrograms import FS_HZ, modular_images, monolithic_images, stft
from posture_id.simulation.stimulus import TiltProfile

__all__ = ["sway_features"]


def sway_features(layout: Layout, profile: TiltProfile, tilt: np.ndarray,
                  theta: np.ndarray) -> np.ndarray:
    """The network inputs of B sways at 50 Hz under one tilt.

    Args:
        layout: the model's. profile: its stimulus. tilt: (S,) rad. theta: (B, S, N) rad.
    Returns:
        modular (B, N, 3, 51, 51); monolithic (B, 2N − 1, 51, 51); FRF (B, 3N, 1, F).
    """
    if layout is Layout.FRF:
        return frf_features(profile.angle(np.arange(theta.shape[1]) / FS_HZ), theta, FS_HZ,
                            profile.period_s, profile.periodic_from_s)
    spectra = stft(np.moveaxis(theta, 1, 2))  # (B, N, 51, 51)
    if layout is Layout.MODULAR:
        return modular_images(stft(tilt), spectra)
    return monolithic_images(spectra)
