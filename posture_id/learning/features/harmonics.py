"""A sway's stimulus-locked harmonics, and the noise the training adds to them.

Everything the universal identifier sees of a recording comes from the DFT (÷P) of the
drift-free cycle average of its whole stimulus cycles
(:meth:`posture_id.frf.locked.LockedProjection.all_harmonics`) at every harmonic of the
cycle up to :data:`STORED_MAX_HZ`: recorded and simulated sway alike, at any sample rate
and length. Because that map is linear, noise can be added to stored harmonics instead
of to the sway, with a fresh draw every epoch:

- white sensor noise of SD σ per sample: each harmonic's real and imaginary parts get
  independent N(0, σ²/(2·C·P)) (C cycles of P samples averaged);
- slow drift, a random walk of the lean whose SD reaches d in 60 s (diffusion
  q = d²/60 s): its one-sided PSD q/(2π²f²) gives each part N(0, q/(8π²f²T)) at a
  harmonic f of a record of T = C·P/rate seconds.

``tests/test_universal.py`` checks both against noise added to the sway itself.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from posture_id.errors import RecordingError
from posture_id.frf.locked import LockedOptions, LockedProjection

__all__ = ["STORED_MAX_HZ", "HarmonicLayout", "harmonic_layout", "sway_harmonics",
           "sensor_noise_parts", "drift_parts"]

#: Highest harmonic kept, Hz (the features use up to 2.5 Hz; the rest estimates noise).
STORED_MAX_HZ = 3.0
_OPTIONS = LockedOptions(drift_order=1, max_frequency_hz=STORED_MAX_HZ, weighted=False)


@dataclass(frozen=True)
class HarmonicLayout:
    """Where a recording's harmonics lie.

    Attributes:
        projection: the cycle-average map (None for harmonics read from a training
        set). frequencies_hz: (K,) the harmonics 1..K of the
        cycle up to :data:`STORED_MAX_HZ`. excited: (K,) bool, those the tilt excites.
        tilt: (K,) complex, the tilt's harmonics, rad. period_samples: P. cycles: C.
        sample_rate_hz: the rate. amplitude_deg: the tilt's peak to peak over the
        analysed cycles. velocity_deg_s: its RMS velocity.
    """

    projection: LockedProjection | None
    frequencies_hz: np.ndarray
    excited: np.ndarray
    tilt: np.ndarray
    period_samples: int
    cycles: int
    sample_rate_hz: float
    amplitude_deg: float
    velocity_deg_s: float

    @property
    def record_s(self) -> float:
        """T, s: the analysed span."""
        return self.cycles * self.period_samples / self.sample_rate_hz


def harmonic_layout(tilt: np.ndarray, sample_rate_hz: float, period_s: float,
                    start_s: float = 0.0, name: str = "recording",
                    cycles: int | None = None) -> HarmonicLayout:
    """The layout of a recording's tilt (S,) rad with a stimulus of period ``period_s``
    from ``start_s``; ``cycles``: its whole cycles from there (None: every whole cycle to
    the end).

    Raises:
        RecordingError: the tilt over those cycles leaves no harmonic empty (it is not
            periodic there), so that no noise can be estimated beside the driven ones.
    """
    tilt = np.asarray(tilt, dtype=float)
    projection = LockedProjection.for_recording(tilt, np.zeros((len(tilt), 1)), sample_rate_hz,
                                                period_s, start_s, _OPTIONS, name, cycles)
    if projection.excited.all():
        raise RecordingError(
            f"{name}: the tilt over the {projection.cycles} cycle(s) of {period_s:g} s from "
            f"{start_s:.2f} s has power at every harmonic of its period: it does not repeat "
            "there, and no harmonic is left to estimate the noise beside the driven ones")
    u = projection.all_harmonics(tilt)
    p = projection.period
    k = np.arange(1, len(u) + 1)
    keep = k * sample_rate_hz / p <= STORED_MAX_HZ
    span = tilt[projection.start : projection.start + projection.cycles * p]
    return HarmonicLayout(
        projection=projection, frequencies_hz=k[keep] * sample_rate_hz / p,
        excited=projection.excited[keep], tilt=u[keep], period_samples=p,
        cycles=projection.cycles, sample_rate_hz=float(sample_rate_hz),
        amplitude_deg=float(np.degrees(np.ptp(span))),
        velocity_deg_s=float(np.degrees(np.sqrt(np.mean((np.diff(span) * sample_rate_hz)**2)))))


def sway_harmonics(layout: HarmonicLayout, sway: np.ndarray) -> np.ndarray:
    """(K, ...) complex harmonics of a sway (S, ...) rad."""
    if layout.projection is None:
        raise ValueError("this layout was read from a training set: it has no projection")
    return layout.projection.all_harmonics(np.asarray(sway, dtype=float))[: len(layout.tilt)]


def sensor_noise_parts(period_samples: int, cycles: int, sd_rad: np.ndarray) -> np.ndarray:
    """SD of each part (real, imaginary) of a harmonic for white sensor noise ``sd_rad``."""
    return np.asarray(sd_rad) / math.sqrt(2.0 * cycles * period_samples)


def drift_parts(frequencies_hz: np.ndarray, record_s: float, drift_deg: np.ndarray
                ) -> np.ndarray:
    """(..., K) SD of each part of each harmonic for a random walk reaching ``drift_deg``
    (...,) in 60 s over a record of ``record_s``."""
    q = np.radians(np.asarray(drift_deg, dtype=float))[..., None] ** 2 / 60.0
    return np.sqrt(q / (8.0 * math.pi**2 * np.asarray(frequencies_hz) ** 2 * record_s))


def coloured_noise_parts(period_samples: int, cycles: int, sd_rad: np.ndarray,
                         frequencies_hz: np.ndarray, sample_rate_hz: float,
                         slope: np.ndarray) -> np.ndarray:
    """(..., K) SD of each part of each harmonic for coloured sensor noise of SD ``sd_rad``
    (...,) and one-sided PSD ∝ (1 + (f/f_0)²)^(−slope/2) (:class:`~posture_id.simulation.
    measurement.MeasurementNoise`; slope (...,), 0 for white).

    A harmonic of the cycle average of C cycles of P samples is the DFT (÷N, N = C·P) of
    the whole span at that frequency, so red noise leaks into it from below through the
    Fejér kernel: E|X_k|² = (1/N²)·[N·r(0) + 2·Σ_{m≥1} (N − m)·r(m)·cos(2π f_k m/f_s)],
    r the noise's autocovariance (the inverse DFT of its PSD, scaled to r(0) = sd²). It is
    computed on a grid of slopes (:data:`_SLOPE_GRID`, kept per layout) and interpolated
    in log variance; white noise gives sd²/N (within the 1e-4 of the offset the draw leaves
    out)."""
    slope = np.asarray(slope, dtype=float)
    sd = np.asarray(sd_rad, dtype=float)
    n = cycles * period_samples
    grid = _coloured_unit_variance(n, float(sample_rate_hz),
                                   tuple(np.asarray(frequencies_hz, dtype=float)))  # (G, K)
    if np.any(slope < _SLOPE_GRID[0]) or np.any(slope > _SLOPE_GRID[-1]):
        raise ValueError(f"coloured noise slopes must lie within {_SLOPE_GRID[0]:g} to "
                         f"{_SLOPE_GRID[-1]:g}")
    logs = np.log(grid)
    at = np.stack([np.interp(slope, _SLOPE_GRID, logs[:, k]) for k in range(grid.shape[1])],
                  axis=-1)  # (..., K)
    return sd[..., None] * np.sqrt(np.exp(at) / 2)


#: The slopes :func:`coloured_noise_parts` computes exactly (it interpolates between them).
_SLOPE_GRID = np.linspace(0.0, 3.0, 25)


@lru_cache(maxsize=256)
def _coloured_unit_variance(n: int, sample_rate_hz: float, frequencies_hz: tuple[float, ...]
                            ) -> np.ndarray:
    """(G, K) E|X_k|² of unit-variance coloured noise of each slope of :data:`_SLOPE_GRID`
    over a span of n samples (:func:`coloured_noise_parts`)."""
    from posture_id.simulation.measurement import COLOUR_CORNER_HZ
    from posture_id.simulation.noise import corner_psd

    m = 2 * n  # the PSD on the grid MeasurementNoise draws it on (twice the span)
    f = np.fft.rfftfreq(m, 1.0 / sample_rate_hz)
    lags = np.arange(n)
    weights = np.where(lags == 0, n, 2.0 * (n - lags))  # (N,)
    cosines = np.cos(2 * np.pi * np.outer(lags, frequencies_hz) / sample_rate_hz)  # (N, K)
    out = np.empty((len(_SLOPE_GRID), len(frequencies_hz)))
    for g, slope in enumerate(_SLOPE_GRID):
        psd = corner_psd(f, COLOUR_CORNER_HZ, slope)
        psd[0] = 0.0  # the noise has no offset
        r = np.fft.irfft(psd, n=m)[:n]
        r = r / r[0]
        out[g] = (weights * r) @ cosines / n**2
    return out
