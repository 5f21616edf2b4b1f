"""Frequency-response functions of sway relative to a periodic tilt (Peterka 2002).

Every analysed stimulus cycle c gives the DFTs U_c(f) of the tilt and Y_c(f) of each
response channel (segment angles, the body COM) at the frequencies the stimulus excites
(the harmonics of the cycle with power in the tilt). Over the cycles, and optionally over
the excited frequencies of a band, the cross- and auto-spectra are summed:

    H = Σ conj(U) Y / Σ |U|²,      γ² = |Σ conj(U) Y|² / (Σ |U|² · Σ |Y|²),

H the FRF (gain |H| in deg/deg, phase ∠H in degrees, unwrapped along frequency) and γ² the
coherence: the share of the response's power at those frequencies that is linearly locked
to the tilt (1 for a noise-free linear response; defined only when something is averaged:
≥ 2 cycles or bands). Before the DFTs a polynomial drift may be removed jointly with the
periodic part (:func:`~posture_id.frf.cycles.cycle_average`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from posture_id.errors import PostureIdError
from posture_id.fileio import Result
from posture_id.frf.cycles import cycle_average

__all__ = ["FrfOptions", "FrequencyResponse", "frequency_response_arrays",
           "check_analysis_options", "samples_per_cycle"]


def samples_per_cycle(period_s: float, sample_rate_hz: float, name: str) -> int:
    """P, the samples in one stimulus cycle; refused unless a whole number."""
    samples = period_s * sample_rate_hz
    p = int(round(samples))
    if abs(samples - p) > 1e-6 * max(samples, 1.0):
        raise PostureIdError(f"{name}: a stimulus cycle of {period_s:g} s is not a whole "
                             f"number of samples at {sample_rate_hz:g} Hz")
    return p


def check_analysis_options(options, label: str, integer_fields: tuple[str, ...]) -> None:
    """Refuse an options object whose ``integer_fields`` are not integers ≥ 0, whose
    ``max_frequency_hz`` is not > 0 or whose ``excited_threshold`` is not in (0, 1)."""
    for name in integer_fields:
        value = getattr(options, name)
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            raise PostureIdError(f"{label} {name} must be an integer ≥ 0, got {value!r}")
    if not (math.isfinite(options.max_frequency_hz) and options.max_frequency_hz > 0):
        raise PostureIdError(f"{label} max_frequency_hz must be > 0, got "
                             f"{options.max_frequency_hz}")
    if not (0 < options.excited_threshold < 1):
        raise PostureIdError(f"{label} excited_threshold must be in (0, 1), got "
                             f"{options.excited_threshold}")


@dataclass(frozen=True)
class FrfOptions:
    """How to compute an FRF.

    Attributes:
        skip_cycles: whole stimulus cycles left out at the start (the transient).
        drift_order: order of the polynomial drift removed with the periodic part (0: none).
        bands: 0 keeps every excited frequency; k > 0 averages them into k bands of
            logarithmically equal width (empty bands dropped), as the field does.
        max_frequency_hz: excited frequencies above this are left out.
        excited_threshold: a harmonic is excited when its tilt amplitude exceeds this
            share of the largest one.
    """

    skip_cycles: int = 0
    drift_order: int = 1
    bands: int = 0
    max_frequency_hz: float = 3.0
    excited_threshold: float = 1e-3

    def __post_init__(self) -> None:
        check_analysis_options(self, "FRF", ("skip_cycles", "drift_order", "bands"))


@dataclass(frozen=True)
class FrequencyResponse(Result):
    """FRFs of several channels relative to the tilt.

    Attributes:
        frequencies_hz: (F,) excited frequencies (band centres, geometric, when banded).
        response: (F, M) complex H, rad/rad = deg/deg. coherence: (F, M) γ² in [0, 1], or
            None when nothing was averaged (one cycle, no bands).
        channels: (M,) names. cycles: analysed cycles. period_s: one stimulus cycle.
        locked_share: (M,) share of each channel's variance that is stimulus-locked.
        options: how it was computed. name: the recording's name.
    """

    frequencies_hz: np.ndarray
    response: np.ndarray
    coherence: np.ndarray | None
    channels: tuple[str, ...]
    cycles: int
    period_s: float
    locked_share: np.ndarray
    options: FrfOptions
    name: str = "recording"

    @property
    def gain(self) -> np.ndarray:
        """(F, M) |H|, deg/deg."""
        return np.abs(self.response)

    @property
    def phase_deg(self) -> np.ndarray:
        """(F, M) ∠H in degrees, unwrapped along frequency from the first frequency."""
        return np.degrees(np.unwrap(np.angle(self.response), axis=0))

    def to_dict(self) -> dict:
        from posture_id.provenance import provenance

        channels = {}
        for m, name in enumerate(self.channels):
            channels[name] = {
                "gain": self.gain[:, m].tolist(),
                "phase_deg": self.phase_deg[:, m].tolist(),
                "coherence": None if self.coherence is None else self.coherence[:, m].tolist(),
                "locked_share": float(self.locked_share[m]),
            }
        return {"frequencies_hz": self.frequencies_hz.tolist(), "channels": channels,
                "cycles": self.cycles, "period_s": self.period_s,
                "provenance": provenance(self.options, recording=self.name)}

    def summary(self) -> str:
        lines = [f"FRF of {self.name}: {self.cycles} cycle(s) of {self.period_s:g} s, "
                 f"{len(self.frequencies_hz)} frequencies "
                 f"{self.frequencies_hz[0]:.3g}–{self.frequencies_hz[-1]:.3g} Hz",
                 f"{'channel':<12} {'locked':>7} {'gain@f1':>8} {'phase@f1':>9} "
                 f"{'coherence':>10}"]
        for m, name in enumerate(self.channels):
            coherence = ("" if self.coherence is None
                         else f"{float(np.median(self.coherence[:, m])):.2f} (median)")
            lines.append(f"{name:<12} {100 * self.locked_share[m]:6.1f}% "
                         f"{self.gain[0, m]:8.3f} {self.phase_deg[0, m]:8.1f}° {coherence:>10}")
        return "\n".join(lines)

    def plot(self, path=None, ax=None):
        from posture_id.plotting import plot_frf

        return plot_frf(self, path=path, ax=ax)


def frequency_response_arrays(tilt: np.ndarray, outputs: np.ndarray, sample_rate_hz: float,
                              period_s: float, channels: tuple[str, ...],
                              options: FrfOptions | None = None,
                              name: str = "recording") -> FrequencyResponse:
    """FRFs of ``outputs`` (S, M) relative to ``tilt`` (S,), both rad, sampled evenly at
    ``sample_rate_hz`` from the stimulus's start; ``period_s``: one stimulus cycle."""
    options = options or FrfOptions()
    p = samples_per_cycle(period_s, sample_rate_hz, name)
    y = np.asarray(outputs, dtype=float)
    u = np.asarray(tilt, dtype=float)
    if y.ndim != 2 or len(u) != len(y) or y.shape[1] != len(channels):
        raise PostureIdError(f"{name}: tilt (S,) and outputs (S, {len(channels)}) must have "
                             f"the same S; got {u.shape} and {y.shape}")
    u_cycles = cycle_average(u, p, options.skip_cycles, 0, name)
    y_cycles = cycle_average(y, p, options.skip_cycles, options.drift_order, name)
    n_cycles = y_cycles.cycles.shape[0]
    uf = np.fft.rfft(u_cycles.cycles, axis=1)  # (C, K)
    yf = np.fft.rfft(y_cycles.cycles, axis=1)  # (C, K, M)
    freqs = np.fft.rfftfreq(p, 1.0 / sample_rate_hz)
    amplitude = np.abs(uf).mean(axis=0)
    excited = ((amplitude > options.excited_threshold * amplitude[1:].max()) & (freqs > 0)
               & (freqs <= options.max_frequency_hz))
    if not excited.any():
        raise PostureIdError(f"{name}: the tilt excites no frequency up to "
                             f"{options.max_frequency_hz:g} Hz")
    idx = np.flatnonzero(excited)
    cross = (np.conj(uf[:, idx, None]) * yf[:, idx, :]).sum(axis=0)  # (F, M)
    u_power = (np.abs(uf[:, idx]) ** 2).sum(axis=0)[:, None]  # (F, 1)
    y_power = (np.abs(yf[:, idx, :]) ** 2).sum(axis=0)  # (F, M)
    f = freqs[idx]
    averaged = n_cycles > 1
    if options.bands:
        edges = np.geomspace(f[0], f[-1] * (1 + 1e-9), options.bands + 1)
        which = np.clip(np.searchsorted(edges, f, side="right") - 1, 0, options.bands - 1)
        groups = [np.flatnonzero(which == b) for b in range(options.bands)]
        groups = [g for g in groups if len(g)]
        cross = np.stack([cross[g].sum(axis=0) for g in groups])
        u_power = np.stack([u_power[g].sum(axis=0) for g in groups])
        y_power = np.stack([y_power[g].sum(axis=0) for g in groups])
        f = np.array([math.exp(np.log(f[g]).mean()) for g in groups])
        averaged = averaged or any(len(g) > 1 for g in groups)
    response = cross / u_power
    with np.errstate(invalid="ignore", divide="ignore"):
        coherence = np.abs(cross) ** 2 / (u_power * y_power)
    return FrequencyResponse(
        frequencies_hz=f, response=response,
        coherence=np.clip(coherence, 0.0, 1.0) if averaged else None,
        channels=tuple(channels), cycles=n_cycles, period_s=float(period_s),
        locked_share=np.asarray(y_cycles.locked_share, dtype=float), options=options,
        name=name)
