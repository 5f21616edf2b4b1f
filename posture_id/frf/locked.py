"""The stimulus-locked part of a sway as a weighted vector: what the locked fit compares.

Raw sway is mostly not locked to the stimulus (spontaneous sway, drift); comparing a model
with it sample by sample fits the noise. :class:`LockedProjection` maps a sway (S, ...) to
its stimulus-locked content, a linear map applied alike to recorded and simulated sway:

1. the analysed span: whole stimulus cycles (P samples each) from ``start``;
2. a polynomial drift of order d removed jointly with the periodic part, then the cycle
   average (:func:`~posture_id.frf.cycles.cycle_average`): offsets and slow drift vanish;
3. its DFT at the harmonics the stimulus excites, up to ``max_frequency_hz`` (K of them):
   the same numbers as an FRF times the tilt's spectrum;
4. each harmonic of each channel divided by the noise level σ_k there (the SD of its real
   and of its imaginary part), estimated from the
   recorded sway's cycle average at the neighbouring harmonics the stimulus does *not*
   excite (a PRTS leaves every even harmonic empty): whatever is there is not locked to
   the stimulus. Frequencies where the sway is noisy count less, as in a fit of FRFs
   weighted by their coherence.

The result, real and imaginary parts stacked, is (2K, ...); with the weights, a residual
between a model and a recording is in units of its own noise (its squared norm is a
χ² with 2K·channels degrees of freedom when the model is right).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from posture_id.errors import PostureIdError
from posture_id.frf.cycles import cycle_average, cycle_spans
from posture_id.frf.response import (
    check_analysis_options,
    driven_harmonics,
    samples_per_cycle,
)
from posture_id.trials import PreparedTrial

__all__ = ["LockedOptions", "LockedProjection", "noise_levels", "floored", "cycle_spectrum"]


def cycle_spectrum(x: np.ndarray, start: int, period: int, cycles: int,
                   drift_order: int) -> np.ndarray:
    """(P/2, ...) complex DFT (÷P) at harmonics 1..P/2 of the cycle average of ``cycles``
    cycles of ``period`` samples of ``x`` (S, ...) from ``start``, drift of
    ``drift_order`` removed."""
    span = x[start : start + cycles * period]
    mean = cycle_average(span, period, 0, drift_order).mean
    return np.fft.rfft(mean, axis=0)[1 : period // 2 + 1] / period


def noise_levels(power: np.ndarray, excited: np.ndarray, rows: np.ndarray,
                 neighbours: int, exclude_self: bool = False) -> np.ndarray:
    """(K, ...) noise level (SD of the real and of the imaginary part) at harmonics
    ``rows`` (indices into the P/2 harmonics 1..P/2), from the mean ``power`` (P/2, ...) of
    the 2·``neighbours`` nearest harmonics the stimulus leaves empty (``excited`` false);
    with ``exclude_self``, an empty harmonic's own power is left out of its estimate."""
    empty = np.flatnonzero(~excited)
    distance = np.abs(empty[None, :] - np.asarray(rows)[:, None]).astype(float)
    if exclude_self:
        distance[distance == 0] = np.inf
    order = np.argsort(distance, axis=1, kind="stable")[:, : 2 * neighbours]
    # E|X|² = σ² splits evenly into the real and imaginary parts
    return np.sqrt(power[empty[order]].mean(axis=1) / 2)


def floored(noise: np.ndarray) -> np.ndarray:
    """``noise`` (K, ...) with none below 1 % of its median over the harmonics: a harmonic
    can never be trusted more than 100× the median one."""
    floor = 0.01 * np.median(noise, axis=0)
    return np.maximum(noise, np.where(floor > 0, floor, 1.0))


@dataclass(frozen=True)
class LockedOptions:
    """How the stimulus-locked part is taken.

    Attributes:
        drift_order: polynomial drift removed with the periodic part (needs ≥ 2 cycles;
            with one cycle only the offset is removed).
        skip_cycles: whole cycles left out at the start (a model simulated from rest
            shares the recording's transient, so 0 keeps it).
        max_frequency_hz: highest harmonic compared.
        weighted: divide each harmonic by the noise level estimated there (else by 1°).
        neighbours: harmonics on each side whose empty (non-excited) ones estimate the
            noise level of a harmonic.
        excited_threshold: a harmonic is excited when the tilt's amplitude there exceeds
            this share of its largest.
        max_offset_s: > 0: also fit a time offset of the stimulus within ±this, at most
            half a stimulus cycle (a platform lag, a lab's onset off its nominal one, or
            clocks that are not in step): after the fit the offsets that best align the
            fitted and the recorded locked sway are found, the fit is repeated with the
            stimulus shifted by each of the best few, and the best fit is kept. 0
            (default): none.
    """

    drift_order: int = 1
    skip_cycles: int = 0
    max_frequency_hz: float = 2.0
    weighted: bool = True
    neighbours: int = 3
    excited_threshold: float = 1e-3
    max_offset_s: float = 0.0

    def __post_init__(self) -> None:
        check_analysis_options(self, "locked", ("drift_order", "skip_cycles", "neighbours"))
        if not (math.isfinite(self.max_offset_s) and self.max_offset_s >= 0):
            raise PostureIdError(f"locked max_offset_s must be a finite time ≥ 0 s, got "
                                 f"{self.max_offset_s}")
        if self.neighbours < 1:
            raise PostureIdError("locked neighbours must be ≥ 1")


@dataclass(frozen=True)
class LockedProjection:
    """The linear map of a sway onto its weighted stimulus-locked harmonics.

    Attributes:
        start: first analysed sample. period: P, samples per cycle. cycles: C analysed.
        drift_order: the drift removed. excited: (P/2,) bool, the harmonics 1..P/2 where
        the tilt has power (driven, or a platform's distortion: no noise estimate there).
        harmonics: (K,) indices k of the compared harmonics, the driven ones (frequency
        k/(P·dt)). frequencies_hz: (K,). noise: (K, M) the noise
        level σ (SD of the real and of the imaginary part) of each harmonic of each of the
        M channels of the recording it was made for (ones when unweighted), in the
        recording's units.
    """

    start: int
    period: int
    cycles: int
    drift_order: int
    excited: np.ndarray
    harmonics: np.ndarray
    frequencies_hz: np.ndarray
    noise: np.ndarray

    @classmethod
    def for_recording(cls, tilt: np.ndarray, sway: np.ndarray, sample_rate_hz: float,
                      period_s: float, start_s: float = 0.0,
                      options: LockedOptions | None = None,
                      name: str = "recording", cycles: int | None = None,
                      driven_hz: tuple[float, ...] | None = None) -> LockedProjection:
        """The projection for one recording.

        Args:
            tilt: (S,) rad, the stimulus on the samples. sway: (S, M) the recorded channels.
            sample_rate_hz: the samples' rate. period_s: one stimulus cycle.
            start_s: where the periodic stimulus starts (after a lead-in), s.
            cycles: the stimulus's whole cycles from ``start_s`` (the platform level
                again after them), None: every whole cycle to the end.
            driven_hz: the frequencies the stimulus drives, Hz (None: every harmonic
                whose tilt amplitude clears ``options.excited_threshold``).
        """
        options = options or LockedOptions()
        p = samples_per_cycle(period_s, sample_rate_hz, name)
        sway = np.asarray(sway, dtype=float)
        first = int(math.ceil(start_s * sample_rate_hz - 1e-9))
        available = len(sway) - first if cycles is None else min(len(sway) - first,
                                                                 cycles * p)
        offset, cycles = cycle_spans(available, p, options.skip_cycles, name)
        start, drift = first + offset, options.drift_order if cycles >= 2 else 0

        def spectrum(x: np.ndarray) -> np.ndarray:
            return cycle_spectrum(x, start, p, cycles, drift)

        u = np.abs(spectrum(np.asarray(tilt, dtype=float)))
        frequencies = np.arange(1, p // 2 + 1) * sample_rate_hz / p
        # harmonics where the tilt has power are no noise estimate, driven or a
        # platform's distortion; only the driven ones are compared
        excited = u > options.excited_threshold * u.max()
        driven = excited if driven_hz is None else driven_harmonics(frequencies, driven_hz)
        keep = driven & (frequencies <= options.max_frequency_hz)
        if not keep.any():
            raise PostureIdError(f"{name}: the tilt excites no frequency up to "
                                 f"{options.max_frequency_hz:g} Hz")
        channels = sway.reshape(len(sway), -1).shape[1]
        noise = np.ones((int(keep.sum()), channels))
        if options.weighted:
            power = np.abs(spectrum(sway.reshape(len(sway), -1))) ** 2  # (P/2, M)
            if excited.all():
                raise PostureIdError(f"{name}: the stimulus excites every harmonic; the "
                                     "noise cannot be told apart (use weighted=False)")
            noise = floored(noise_levels(power, excited, np.flatnonzero(keep),
                                         options.neighbours))
        return cls(start, p, cycles, drift, excited, np.flatnonzero(keep) + 1,
                   frequencies[keep], noise)

    @classmethod
    def for_trial(cls, trial: PreparedTrial, options: LockedOptions | None = None
                  ) -> LockedProjection:
        """The projection for a prepared trial's segment angles (degrees), from where its
        stimulus's periodic part starts; the stimulus must be periodic."""
        rec = trial.recording
        return cls.for_stimulus(trial.stimulus, rec.tilt, np.degrees(rec.theta),
                                rec.sample_rate_hz, options, trial.name)

    @classmethod
    def for_stimulus(cls, stimulus, tilt: np.ndarray, sway: np.ndarray,
                     sample_rate_hz: float, options: LockedOptions | None = None,
                     name: str = "recording") -> LockedProjection:
        """:meth:`for_recording` for a periodic :class:`~posture_id.simulation.stimulus.
        TiltProfile`: its period, start, steady cycles and driven frequencies."""
        return cls.for_recording(tilt, sway, sample_rate_hz, stimulus.period_s,
                                 stimulus.periodic_from_s, options, name, stimulus.cycles,
                                 stimulus.frequencies_hz)

    @classmethod
    def for_periodic_trial(cls, trial: PreparedTrial, options: LockedOptions | None = None
                           ) -> LockedProjection | None:
        """:meth:`for_trial`, or None where there is nothing locked to compare: a stimulus
        that is not periodic, less than one whole cycle after its start, a period off
        the sample grid (or, weighted, no harmonic left empty)."""
        if trial.stimulus.period_s is None:
            return None
        try:
            return cls.for_trial(trial, options)
        except PostureIdError:
            return None

    def locked_share(self, x: np.ndarray) -> np.ndarray:
        """(M,) share of each channel's variance (over the analysed cycles, drift removed)
        that is stimulus-locked, corrected for the noise the cycle average keeps (NaN for
        a single cycle: :func:`~posture_id.frf.cycles.cycle_average`); ``x``: (S, M)."""
        return cycle_average(x[self.start :], self.period, 0, self.drift_order).locked_share

    def explained(self, recorded: np.ndarray, simulated: np.ndarray) -> np.ndarray:
        """(M,) share of the recorded locked sway (its compared harmonics, unweighted) that
        the simulated one explains: 1 − Σ|R_k − S_k|² / Σ|R_k|²; −∞ for a simulation
        that is not finite (it fell)."""
        if not np.all(np.isfinite(simulated)):
            return np.full(recorded.shape[1], -np.inf)
        r, s = self.spectrum(recorded), self.spectrum(simulated)
        with np.errstate(invalid="ignore", divide="ignore"):
            return 1.0 - np.sum(np.abs(r - s) ** 2, axis=0) / np.sum(np.abs(r) ** 2, axis=0)

    def all_harmonics(self, x: np.ndarray) -> np.ndarray:
        """(P/2, ...) complex DFT (÷P) of the drift-free cycle average of ``x`` (S, ...) at
        every harmonic 1..P/2, compared or not."""
        return cycle_spectrum(x, self.start, self.period, self.cycles, self.drift_order)

    def spectrum(self, x: np.ndarray) -> np.ndarray:
        """(K, ...) complex: the compared harmonics of a sway (S, ...), not weighted."""
        return self.all_harmonics(x)[self.harmonics - 1]

    def best_offsets(self, fitted: np.ndarray, recorded: np.ndarray, max_offset_s: float,
                     count: int = 3, step_s: float = 0.001) -> list[float]:
        """s, up to ``count`` offsets τ in [−max, max] at the deepest local minima of the
        weighted distance of :meth:`best_offset`, best first: the candidates of a wide
        search, whose cost has a minimum every stimulated period."""
        taus, cost = self._offset_cost(fitted, recorded, max_offset_s, step_s)
        inner = (cost[1:-1] <= cost[:-2]) & (cost[1:-1] <= cost[2:])
        minima = np.concatenate([[0] if cost[0] <= cost[1] else [],
                                 np.flatnonzero(inner) + 1,
                                 [len(cost) - 1] if cost[-1] <= cost[-2] else []]).astype(int)
        order = minima[np.argsort(cost[minima], kind="stable")]
        return [float(taus[k]) for k in order[:count]]

    def _offset_cost(self, fitted, recorded, max_offset_s, step_s):
        a, b = self.spectrum(fitted), self.spectrum(recorded)  # (K, M)
        taus = np.arange(-max_offset_s, max_offset_s + step_s / 2, step_s)
        cost = np.empty(len(taus))
        for start in range(0, len(taus), 512):  # bounded memory for a wide search
            shift = np.exp(-2j * np.pi * np.outer(taus[start:start + 512], self.frequencies_hz))
            cost[start:start + 512] = (np.abs((shift[:, :, None] * a[None] - b[None])
                                              / self.noise[None]) ** 2).sum(axis=(1, 2))
        return taus, cost

    def smoothest_offset(self, recorded: np.ndarray, tilt: np.ndarray, max_offset_s: float,
                         step_s: float = 0.01) -> float:
        """s, the stimulus offset τ in [−max, max] at which the recording's empirical
        stimulus-locked FRF, H_k = R_k / (U_k·e^{−2πif_kτ}) (the recorded harmonics over
        the tilt's, delayed by τ), is smoothest from one compared harmonic to the next:
        the least Σ|H_{k+1} − H_k|² over its noise, summed over the channels. A body's
        response changes smoothly with frequency; a stimulus off the sway's clock by τ
        adds a phase ramp that turns by 2π·τ·Δf between neighbours. Model-free, so it is
        off by the body's own group delay (a few tenths of a second): a start for a
        search, not an answer. ``recorded``: (S, M) and ``tilt``: (S,), one unit (the
        weighted projection's noise gives the weights; unweighted, each harmonic counts
        alike)."""
        r = self.spectrum(np.asarray(recorded, dtype=float))  # (K, M)
        u = self.spectrum(np.asarray(tilt, dtype=float)[:, None])[:, 0]  # (K,)
        with np.errstate(divide="ignore", invalid="ignore"):
            h = r / u[:, None]
            sd = self.noise / np.abs(u)[:, None]
        weights = 1.0 / (sd[1:] ** 2 + sd[:-1] ** 2)
        weights[~np.isfinite(weights)] = 0.0
        taus = np.arange(-max_offset_s, max_offset_s + step_s / 2, step_s)
        best, best_rough = 0.0, np.inf
        for start in range(0, len(taus), 512):  # bounded memory for a wide search
            turn = np.exp(2j * np.pi * np.outer(taus[start:start + 512], self.frequencies_hz))
            shifted = turn[:, :, None] * h[None]  # (T, K, M): H with the delay taken off
            rough = (np.abs(np.diff(shifted, axis=1)) ** 2 * weights[None]).sum(axis=(1, 2))
            k = int(np.argmin(rough))
            if rough[k] < best_rough:
                best, best_rough = float(taus[start + k]), float(rough[k])
        return best

    def best_offset(self, fitted: np.ndarray, recorded: np.ndarray, max_offset_s: float,
                    step_s: float = 0.001) -> float:
        """s, the stimulus offset τ in [−max, max] that minimises the weighted distance of
        the fitted locked sway delayed by τ (its harmonics times e^{−2πifτ}) from the
        recorded one; ``fitted``, ``recorded``: (S, M) in the recording's units."""
        taus, cost = self._offset_cost(fitted, recorded, max_offset_s, step_s)
        return float(taus[np.argmin(cost)])

    def apply(self, x: np.ndarray) -> np.ndarray:
        """(2K, ...) real: the weighted stimulus-locked harmonics of ``x`` (S, M, ...)
        whose channels M are the recording's (real parts, then imaginary parts)."""
        z = self.spectrum(x)
        weights = self.noise.reshape(self.noise.shape + (1,) * (z.ndim - self.noise.ndim))
        z = z / weights
        return np.concatenate([z.real, z.imag], axis=0)
