"""Frequency-response functions of sway relative to a periodic tilt (Peterka 2002).

Every analysed stimulus cycle c gives the DFTs U_c(f) of the tilt and Y_c(f) of each
response channel (segment angles, the body COM) at the frequencies the stimulus excites
(the harmonics of the cycle with power in the tilt). Over the cycles, and optionally over
the excited frequencies of a band, the cross- and auto-spectra are summed:

    H = Σ conj(U) Y / Σ |U|²,      γ² = |Σ conj(U) Y|² / (Σ |U|² · Σ |Y|²),

H the FRF (gain |H| in deg/deg, phase ∠H in degrees, unwrapped along frequency) and γ² the
coherence: the share of the response's power at those frequencies that is linearly locked
to the tilt (1 for a noise-free linear response; defined only when something is averaged:
≥ 2 cycles or bands). Averaged over n spectra (n = C cycles × the frequencies of a band),
pure noise gives γ² of about 1/n, and exceeds 1 − α^{1/(n−1)} with probability α
(the magnitude-squared coherence's null distribution, P(γ² > x) = (1 − x)^{n−1}; Carter,
Knapp and Nuttall 1973): :attr:`FrequencyResponse.coherence_level` is that level at
α = 5 %, the line a coherence must clear to show a response at all. Before the DFTs a
polynomial drift may be removed jointly with the periodic part
(:func:`~posture_id.frf.cycles.cycle_average`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from posture_id.errors import PostureIdError
from posture_id.fileio import Result
from posture_id.frf.bands import FrequencyBands, pseudo_impulse_response
from posture_id.frf.cycles import cycle_average

__all__ = ["FrfOptions", "FrequencyResponse", "frequency_response_arrays",
           "check_analysis_options", "samples_per_cycle", "driven_harmonics", "coherence_level",
           "SIGNIFICANCE"]

#: The coherence's significance level: pure noise exceeds the level this often.
SIGNIFICANCE = 0.05


def coherence_level(averages: np.ndarray | int, alpha: float = SIGNIFICANCE) -> np.ndarray:
    """The γ² that pure noise exceeds with probability ``alpha``, for a coherence
    averaged over ``averages`` (n ≥ 2) independent spectra: 1 − α^{1/(n−1)} (1 for n < 2)."""
    n = np.asarray(averages, dtype=float)
    with np.errstate(divide="ignore"):
        return np.where(n >= 2, 1.0 - alpha ** (1.0 / np.maximum(n - 1, 1e-12)), 1.0)


def driven_harmonics(frequencies_hz: np.ndarray, driven_hz) -> np.ndarray:
    """(K,) bool: which of the harmonics ``frequencies_hz`` are among ``driven_hz``."""
    f = np.asarray(frequencies_hz, dtype=float)
    driven = np.asarray(driven_hz, dtype=float)
    return np.any(np.abs(f[:, None] - driven[None, :]) <= 1e-6 * np.maximum(driven, 1e-9),
                  axis=1)


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
        lab_bands: a lab's FRF points (:class:`~posture_id.frf.bands.FrequencyBands`, e.g.
            :data:`~posture_id.frf.bands.PETERKA_11`): each band averages the stimulated
            harmonics it names and is reported at its centre; not with ``bands``.
    """

    skip_cycles: int = 0
    drift_order: int = 1
    bands: int = 0
    max_frequency_hz: float = 3.0
    excited_threshold: float = 1e-3
    lab_bands: FrequencyBands | None = None

    def __post_init__(self) -> None:
        check_analysis_options(self, "FRF", ("skip_cycles", "drift_order", "bands"))
        if self.lab_bands is not None and self.bands:
            raise PostureIdError("FRF: log-spaced bands and a lab's bands are two ways to "
                                 "average; give one")

    @classmethod
    def lab_convention(cls, bands: FrequencyBands, **changes) -> FrfOptions:
        """The labs' convention (Peterka 2002): the first cycle left out (the transient),
        no drift removed, the spectra averaged over ``bands``."""
        return cls(**{"skip_cycles": 1, "drift_order": 0, "lab_bands": bands, **changes})


@dataclass(frozen=True)
class FrequencyResponse(Result):
    """FRFs of several channels relative to the tilt.

    Attributes:
        frequencies_hz: (F,) excited frequencies (band centres, geometric, when banded).
        response: (F, M) complex H, rad/rad = deg/deg. coherence: (F, M) γ² in [0, 1], or
            None when nothing was averaged (one cycle, no bands).
        channels: (M,) names. cycles: analysed cycles. period_s: one stimulus cycle.
        locked_share: (M,) share of each channel's variance that is stimulus-locked,
            corrected for the noise left in the cycle average (NaN for one cycle).
        options: how it was computed. name: the recording's name.
        coherence_level: (F,) the γ² pure noise exceeds with probability
            :data:`SIGNIFICANCE` at each frequency (its averages: cycles × frequencies of
            the band), or None with the coherence.
        recording_source: how the recording's angles were derived (a motion-capture
            trial's markers, axes and channels), or None.
        bands_empty: with ``options.bands``, how many of the bands held no stimulated
            frequency (dropped).
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
    coherence_level: np.ndarray | None = None
    bands_empty: int = 0
    recording_source: dict | None = None

    @property
    def significant(self) -> np.ndarray | None:
        """(F, M) bool: the coherence clears its significance level, or None."""
        if self.coherence is None or self.coherence_level is None:
            return None
        return self.coherence > self.coherence_level[:, None]

    @property
    def gain(self) -> np.ndarray:
        """(F, M) |H|, deg/deg."""
        return np.abs(self.response)

    @property
    def phase_deg(self) -> np.ndarray:
        """(F, M) ∠H in degrees, unwrapped along frequency from the first frequency."""
        return np.degrees(np.unwrap(np.angle(self.response), axis=0))

    def to_dict(self) -> dict:
        from posture_id.provenance import provenance, recording_identity

        channels = {}
        for m, name in enumerate(self.channels):
            channels[name] = {
                "gain": self.gain[:, m].tolist(),
                "phase_deg": self.phase_deg[:, m].tolist(),
                "re": self.response[:, m].real.tolist(),
                "im": self.response[:, m].imag.tolist(),
                "coherence": None if self.coherence is None else self.coherence[:, m].tolist(),
                "locked_share": (float(self.locked_share[m])
                                 if np.isfinite(self.locked_share[m]) else None),
            }
        return {"frequencies_hz": self.frequencies_hz.tolist(), "channels": channels,
                "coherence_level": (None if self.coherence_level is None
                                    else self.coherence_level.tolist()),
                "coherence_significance": SIGNIFICANCE,
                "cycles": self.cycles, "period_s": self.period_s,
                "bands_empty": self.bands_empty,
                "lab_bands": (None if self.options.lab_bands is None
                              else self.options.lab_bands.to_dict()),
                "pir": self._pir_dict() if self.options.lab_bands is not None else None,
                "provenance": provenance(self.options, **recording_identity(
                    self.name, self.recording_source))}

    def pir(self, rate_hz: float = 22.0) -> tuple[np.ndarray, np.ndarray]:
        """(t (S,) s, x (S, M)): each channel's pseudo-impulse response over one common
        period of the frequencies (:func:`~posture_id.frf.bands.pseudo_impulse_response`)."""
        return pseudo_impulse_response(self.frequencies_hz, self.response, rate_hz)

    def _pir_dict(self, rate_hz: float = 22.0) -> dict | None:
        try:
            t, x = self.pir(rate_hz)
        except PostureIdError:  # frequencies above 11 Hz: no PIR at 22 Hz
            return None
        return {"rate_hz": rate_hz, "period_s": float(len(t) / rate_hz),
                "channels": {name: x[:, m].tolist() for m, name in enumerate(self.channels)}}

    def summary(self) -> str:
        count = len(self.frequencies_hz)
        if self.options.lab_bands is not None:
            lab = self.options.lab_bands
            what = f"{count} points ({lab.name})" + (
                f" (of {len(lab)}: {self.bands_empty} held no stimulated frequency)"
                if self.bands_empty else "")
        elif self.options.bands:
            what = f"{count} bands" + (
                f" (of {self.options.bands} asked: {self.bands_empty} held no stimulated "
                "frequency)" if self.bands_empty else "")
        else:
            what = f"{count} frequencies"
        lines = [f"FRF of {self.name}: {self.cycles} cycle(s) of {self.period_s:g} s, {what} "
                 f"{self.frequencies_hz[0]:.3g}–{self.frequencies_hz[-1]:.3g} Hz"]
        significant = self.significant
        if significant is not None:
            lines.append(f"coherence: significant where it clears the level pure noise "
                         f"exceeds {100 * SIGNIFICANCE:g} % of the time ("
                         f"{float(np.min(self.coherence_level)):.2f}–"
                         f"{float(np.max(self.coherence_level)):.2f} for these averages)")
        lines.append(f"{'channel':<12} {'locked':>7} {'gain@f1':>8} {'phase@f1':>9} "
                     f"{'coherence':>10} {'significant':>12}")
        for m, name in enumerate(self.channels):
            coherence = ("" if self.coherence is None
                         else f"{float(np.median(self.coherence[:, m])):.2f} (median)")
            where = ("" if significant is None
                     else f"{int(significant[:, m].sum())} of {count}")
            share = ("  n/a  " if not np.isfinite(self.locked_share[m])
                     else f"{100 * self.locked_share[m]:6.1f}%")
            lines.append(f"{name:<12} {share} "
                         f"{self.gain[0, m]:8.3f} {self.phase_deg[0, m]:8.1f}° {coherence:>10} "
                         f"{where:>12}")
        if self.cycles < 2:
            lines.append("locked share: n/a with one cycle (noise and response cannot be "
                         "told apart)")
        return "\n".join(lines)

    def plot(self, path=None, ax=None):
        from posture_id.plotting import plot_frf

        return plot_frf(self, path=path, ax=ax)


def frequency_response_arrays(tilt: np.ndarray, outputs: np.ndarray, sample_rate_hz: float,
                              period_s: float, channels: tuple[str, ...],
                              options: FrfOptions | None = None,
                              name: str = "recording",
                              driven_hz: tuple[float, ...] | None = None) -> FrequencyResponse:
    """FRFs of ``outputs`` (S, M) relative to ``tilt`` (S,), both rad, sampled evenly at
    ``sample_rate_hz`` from the stimulus's start; ``period_s``: one stimulus cycle;
    ``driven_hz``: the frequencies the stimulus drives, Hz (a recognised sinusoid's: its
    platform's distortion harmonics are not analysed), None: every harmonic whose tilt
    amplitude clears ``options.excited_threshold``."""
    options = options or FrfOptions()
    if options.max_frequency_hz > sample_rate_hz / 2:
        raise PostureIdError(f"{name}: max_frequency_hz {options.max_frequency_hz:g} Hz is above "
                             f"the recording's Nyquist frequency ({sample_rate_hz / 2:g} Hz at "
                             f"{sample_rate_hz:g} Hz): no frequency there can be analysed")
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
    excited = ((driven_harmonics(freqs, driven_hz) if driven_hz is not None
                else amplitude > options.excited_threshold * amplitude[1:].max())
               & (freqs > 0) & (freqs <= options.max_frequency_hz))
    if not excited.any():
        raise PostureIdError(f"{name}: the tilt excites no frequency up to "
                             f"{options.max_frequency_hz:g} Hz")
    idx = np.flatnonzero(excited)
    cross = (np.conj(uf[:, idx, None]) * yf[:, idx, :]).sum(axis=0)  # (F, M)
    u_power = (np.abs(uf[:, idx]) ** 2).sum(axis=0)[:, None]  # (F, 1)
    y_power = (np.abs(yf[:, idx, :]) ** 2).sum(axis=0)  # (F, M)
    f = freqs[idx]
    averaged = n_cycles > 1
    averages = np.full(len(f), n_cycles)
    empty = 0
    if options.bands or options.lab_bands is not None:
        if options.lab_bands is not None:
            groups = options.lab_bands.groups(f, period_s)
            centres = options.lab_bands.centres(f, groups)
        else:
            edges = np.geomspace(f[0], f[-1] * (1 + 1e-9), options.bands + 1)
            which = np.clip(np.searchsorted(edges, f, side="right") - 1, 0,
                            options.bands - 1)
            groups = [np.flatnonzero(which == b) for b in range(options.bands)]
            centres = np.array([math.exp(np.log(f[g]).mean()) if len(g) else math.nan
                                for g in groups])
        empty = sum(1 for g in groups if not len(g))
        centres = np.array([c for c, g in zip(centres, groups, strict=True) if len(g)])
        groups = [g for g in groups if len(g)]
        if not groups:
            raise PostureIdError(f"{name}: no band holds a stimulated frequency")
        averages = np.array([n_cycles * len(g) for g in groups])
        cross = np.stack([cross[g].sum(axis=0) for g in groups])
        u_power = np.stack([u_power[g].sum(axis=0) for g in groups])
        y_power = np.stack([y_power[g].sum(axis=0) for g in groups])
        f = centres
        averaged = averaged or any(len(g) > 1 for g in groups)
    response = cross / u_power
    with np.errstate(invalid="ignore", divide="ignore"):
        coherence = np.abs(cross) ** 2 / (u_power * y_power)
    return FrequencyResponse(
        frequencies_hz=f, response=response,
        coherence=np.clip(coherence, 0.0, 1.0) if averaged else None,
        channels=tuple(channels), cycles=n_cycles, period_s=float(period_s),
        locked_share=np.asarray(y_cycles.locked_share, dtype=float), options=options,
        name=name, coherence_level=coherence_level(averages) if averaged else None,
        bands_empty=empty)
