"""A linear model's body COM sway on a recording's tilt, computed exactly in the frequency
domain from its closed loop (:class:`~posture_id.models.protocol.FrequencyModel`), with
exact derivatives: the sway the frequency-domain fit compares and predicts."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["ExactResponse"]


class ExactResponse:
    """A model's COM sway on a trial's samples, from rest, with exact derivatives.

    The tilt (S,) rad is zero-padded to L ≥ 8·S samples (a power of two) so that the
    circular convolution by H equals the linear one from rest over the recording; the
    sway is the inverse transform of H(jω) times the tilt's spectrum.
    """

    def __init__(self, model, tilt_rad: np.ndarray, sample_rate_hz: float, plant) -> None:
        self.model = model
        self.samples = len(tilt_rad)
        self.plant = plant
        length = 1 << int(math.ceil(math.log2(8 * self.samples)))
        self.tilt_spectrum = np.fft.rfft(np.asarray(tilt_rad, float), n=length)
        omega = 2 * np.pi * np.fft.rfftfreq(length, 1.0 / sample_rate_hz)
        omega[0] = 1e-6  # H(0) as its limit: the static response
        self.s = 1j * omega
        self.length = length

    def sway(self, params, gradient: bool = False):
        """(S,) rad of COM sway; with ``gradient``, also (P, S) d sway / dp in the model's
        ``parameter_order`` (SI units)."""
        if not gradient:
            h = self.model.closed_loop(params, self.plant, self.s)
            return np.fft.irfft(h * self.tilt_spectrum, n=self.length)[: self.samples]
        h, dh = self.model.closed_loop(params, self.plant, self.s, gradient=True)
        both = np.vstack([h[None], dh]) * self.tilt_spectrum[None]
        out = np.fft.irfft(both, n=self.length, axis=1)[:, : self.samples]
        return out[0], out[1:]
