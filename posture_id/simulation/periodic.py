"""Any periodic tilt as labs run it, found in the tilt column: a sinusoid, a sum of sines,
a multisine (or a PRTS that is not one of docs/model.md §4's), with the platform level
before and after the oscillation and a fade-in or fade-out left out.

How (:func:`recognise_periodic`):

1. **The moving span.** The platform moves from where it leaves its first level until it
   last leaves the level it comes to rest at (not always the first), by more than five
   times the column's noise (estimated from its second differences) and 0.1 % of its
   peak-to-peak; the first level is subtracted.
2. **The period**, a whole number of samples: the difference function
   d(P) = mean_t (x[t+P] − x[t])² over the moving span, normalised by its running mean
   (the cumulative-mean normalisation of de Cheveigné and Kawahara's YIN estimator, so
   that small lags of a smooth tilt do not count as repeats); the first lag where the
   normalised function falls below :data:`REPEAT_LEVEL`, then the deepest lag within a
   sample or two of it. Two whole cycles of motion at least.
3. **The steady part**: the longest run of samples whose next cycle repeats them: the
   difference from the next cycle, averaged over a twentieth of a cycle, within four
   times its noise and :data:`STEADY_TOLERANCE` of the tilt's peak at every sample, and
   each cycle moving (its peak-to-peak at least :data:`MOVING_SHARE` of the moving
   span's: a level stretch repeats itself too). The
   period is refined on the roughly steady part, then on the steady part (a fade-in
   shifts the first estimate by a few samples); the cycles analysed are then those that
   repeat within :data:`PLATFORM_TOLERANCE` (a real platform's own irregularity). A fade-in and a
   fade-out (an amplitude ramping up or down) do not repeat and are left out; the
   analysis starts where the steady part does and spans its whole cycles.
4. **The driven frequencies**: the harmonics k/P of the steady cycles' average above the
   noise. One harmonic that holds :data:`SINUSOID_SHARE` of the power makes a
   sinusoid: its multiples are the platform's distortion, not driven. Otherwise every
   harmonic above the noise is driven but a weak multiple of a stronger driven one
   (below :data:`DISTORTION_SHARE` of every driven harmonic it is a multiple of).

The stimulus returned is the tilt column itself (linear between samples: the platform's
own motion, fade-in and distortion included, drives the model), with the period, the
start and the number of steady cycles, and the driven frequencies, so that the FRF and
the locked fits analyse only those.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from posture_id.simulation.stimulus import TiltProfile, column_noise, tilt_from_array

__all__ = ["PeriodicTilt", "recognise_periodic", "find_periodic", "true_runs", "REPEAT_LEVEL",
           "STEADY_TOLERANCE", "PLATFORM_TOLERANCE", "SINUSOID_SHARE", "DISTORTION_SHARE",
           "MOVING_SHARE"]

#: The normalised difference below which a lag counts as a repeat of the tilt.
REPEAT_LEVEL = 0.1
#: The period is refined on the cycles that repeat the next within the column's noise and
#: this share of its peak.
STEADY_TOLERANCE = 0.01
#: The cycles analysed repeat the next within the column's noise and this share of its
#: peak: a real platform's cycles differ by up to 1.9 % of it (its servo's irregularity
#: at 0.4 Hz, on the public force-plate study's trials: benchmarks/real_force_plate.py),
#: a fade's by far more.
PLATFORM_TOLERANCE = 0.02
#: One harmonic with this share of the steady cycle's power makes a sinusoid.
SINUSOID_SHARE = 0.95
#: A multiple of a driven harmonic weaker than this share of it is distortion.
DISTORTION_SHARE = 0.05
#: A steady cycle spans at least this share of the moving span's peak-to-peak (a level
#: stretch repeats itself, but does not move).
MOVING_SHARE = 0.25
#: Harmonics weaker than this share of the strongest are not driven, whatever the noise.
_SMALLEST_SHARE = 2e-3


@dataclass(frozen=True)
class PeriodicTilt:
    """What :func:`find_periodic` found in a tilt column.

    Attributes:
        period_samples: P, samples in one cycle. period_s: s.
        start: the first sample of the steady part; start_s: s.
        cycles: whole steady cycles from ``start``.
        moving_from_s, moving_until_s: s, where the platform leaves and regains its level.
        harmonics: (K,) the driven harmonics k of 1/period_s. frequencies_hz: (K,).
        amplitudes_deg: (K,) each driven sine's amplitude (half its peak-to-peak), deg.
        distortion_hz: frequencies of the platform's distortion left out, Hz.
        distortion_share: each one's amplitude against the strongest harmonic.
        kind: "sinusoid", "sum of sines" or "multisine".
    """

    period_samples: int
    period_s: float
    start: int
    start_s: float
    cycles: int
    moving_from_s: float
    moving_until_s: float
    harmonics: tuple[int, ...]
    frequencies_hz: tuple[float, ...]
    amplitudes_deg: tuple[float, ...]
    distortion_hz: tuple[float, ...]
    distortion_share: tuple[float, ...]
    kind: str

    def describe(self) -> str:
        """One line: the kind, frequencies, amplitude, cycles and where they start."""
        if self.kind == "sinusoid":
            what = (f"sinusoid {self.frequencies_hz[0]:.4g} Hz, "
                    f"±{self.amplitudes_deg[0]:.3g}°")
        else:
            f = self.frequencies_hz
            what = (f"{self.kind} of {len(f)} frequencies {min(f):.4g}–{max(f):.4g} Hz, "
                    f"period {self.period_s:g} s")
        return (f"{what}, {self.cycles} steady cycle(s) from {self.start_s:.3f} s "
                f"(moving {self.moving_from_s:.2f}–{self.moving_until_s:.2f} s)")

    def distortion_note(self) -> str | None:
        """The distortion harmonics left out, or None."""
        if not self.distortion_hz:
            return None
        listed = ", ".join(f"{f:.4g} Hz ({100 * s:.1f} %)"
                           for f, s in zip(self.distortion_hz, self.distortion_share,
                                           strict=True))
        return (f"the platform's distortion at {listed} of the driven amplitude is not a "
                "driven frequency and is left out")


def _difference_function(x: np.ndarray, max_lag: int) -> np.ndarray:
    """(max_lag + 1,) d(P) = mean_t (x[t+P] − x[t])² over t = 0..S−1−P (d(0) = 0)."""
    n = len(x)
    size = 1 << int(math.ceil(math.log2(2 * n)))
    spectrum = np.fft.rfft(x, size)
    correlation = np.fft.irfft(spectrum * np.conj(spectrum), size)[: max_lag + 1]
    squares = np.concatenate([[0.0], np.cumsum(x**2)])
    lags = np.arange(max_lag + 1)
    head = squares[n - lags]  # Σ_{t<S−P} x[t]²
    tail = squares[n] - squares[lags]  # Σ_{t≥P} x[t]²
    return np.maximum(head + tail - 2 * correlation, 0.0) / np.maximum(n - lags, 1)


def _period(x: np.ndarray, min_lag: int) -> int | None:
    """The tilt's period in samples (the module doc, step 2), or None."""
    max_lag = len(x) // 2
    if max_lag <= min_lag:
        return None
    d = _difference_function(x, max_lag)
    running = np.cumsum(d[1:]) / np.arange(1, max_lag + 1)
    normalised = np.ones(max_lag + 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        normalised[1:] = np.where(running > 0, d[1:] / running, 1.0)
    below = np.flatnonzero(normalised[min_lag:] < REPEAT_LEVEL)
    if not below.size:
        return None
    lag = int(below[0]) + min_lag
    while lag + 1 <= max_lag and d[lag + 1] < d[lag]:
        lag += 1
    return lag


def true_runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(starts (R,), stops (R,)): the runs of True in a boolean ``mask`` (S,),
    ``mask[starts[r]:stops[r]]`` each."""
    edges = np.diff(np.concatenate([[0], np.asarray(mask).astype(np.int8), [0]]))
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)


def _steady_run(x: np.ndarray, p: int, tolerance: float) -> tuple[int, int] | None:
    """(first, end): the steady part x[first:end], the longest run of samples t whose
    next cycle repeats them: |x[t+p] − x[t]| ≤ ``tolerance`` for every sample of the
    cycle from t."""
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    n = len(x) - p
    if n < p:
        return None
    # the difference averaged over a twentieth of a cycle: the column's noise shrinks,
    # a fade (smooth) does not
    width = max(p // 20, 1)
    e = np.abs(np.convolve(x[p:] - x[:-p], np.ones(width) / width, mode="same"))
    # the largest difference over [t, t+p), t = 0..n−p
    worst = maximum_filter1d(e, size=p, origin=-(p // 2), mode="nearest")[: n - p + 1]
    # a cycle that moves: a level stretch (at any level) repeats itself too
    top = maximum_filter1d(x, size=p, origin=-(p // 2), mode="nearest")[: n - p + 1]
    bottom = minimum_filter1d(x, size=p, origin=-(p // 2), mode="nearest")[: n - p + 1]
    good = (worst <= tolerance) & (top - bottom >= MOVING_SHARE * float(np.ptp(x)))
    if not good.any():
        return None
    starts, stops = true_runs(good)
    k = int(np.argmax(stops - starts))
    # a window [t, t+p) that repeats: the samples t..t+2p−1 are two equal cycles
    return int(starts[k]), int(stops[k]) - 1 + 2 * p


def _refined_period(x: np.ndarray, p: int, share: float = 0.03) -> int:
    """The lag within ``share`` of ``p`` with the least mean squared difference over
    ``x`` (a steady part: a fade-in shifts the first estimate)."""
    lags = np.arange(max(2, int(p * (1 - share))), min(len(x) // 2, int(p * (1 + share))) + 1)
    if not len(lags):
        return p
    d = _difference_function(x, int(lags[-1]))[lags]
    return int(lags[int(np.argmin(d))])


def _driven(amplitude: np.ndarray, noise: float) -> tuple[list[int], list[int]]:
    """The driven harmonics and the distortion ones (indices k ≥ 1 into ``amplitude``,
    which is indexed by harmonic, entry 0 unused)."""
    a = amplitude.copy()
    a[0] = 0.0
    strongest = float(a.max())
    above = np.flatnonzero(a > max(6.0 * noise, _SMALLEST_SHARE * strongest))
    if not above.size:  # nothing above the noise: no driven frequency
        return [], []
    power = a[above] ** 2
    order = above[np.argsort(-a[above], kind="stable")]
    if power.max() >= SINUSOID_SHARE * power.sum():
        return [int(order[0])], [int(k) for k in order[1:] if k % order[0] == 0]
    driven: list[int] = []
    distortion: list[int] = []
    for k in order:
        divisors = [j for j in driven if k % j == 0]
        if divisors and all(a[k] < DISTORTION_SHARE * a[j] for j in divisors):
            distortion.append(int(k))
        else:
            driven.append(int(k))
    return sorted(driven), sorted(distortion)


def find_periodic(times_s: np.ndarray, tilt_rad: np.ndarray,
                  min_period_s: float = 1.0) -> PeriodicTilt | None:
    """The periodic tilt in an evenly sampled column (the module doc), or None when the
    column does not repeat (noise, a single step) or moves for less than two cycles.

    Args:
        times_s: (S,) s, evenly sampled from 0. tilt_rad: (S,) rad.
        min_period_s: the shortest period considered, s (a posture platform's stimuli
            repeat every few seconds at least).
    """
    t = np.asarray(times_s, dtype=float)
    a = np.asarray(tilt_rad, dtype=float)
    if len(t) < 16 or np.ptp(a) == 0:
        return None
    dt = float(np.median(np.diff(t)))
    noise = column_noise(a)
    span = float(np.ptp(a))
    edge = max(len(a) // 20, 2)
    level_guess = float(np.median(a[:edge]))
    end_guess = float(np.median(a[-edge:]))  # a platform may come to rest at another level
    still = max(5.0 * noise, 1e-3 * span)
    leaves = np.flatnonzero(np.abs(a - level_guess) > still)
    returns = np.flatnonzero(np.abs(a - end_guess) > still)
    if len(leaves) < 16 or len(returns) < 16:
        return None
    first, last = int(leaves[0]), int(returns[-1])
    if last - first < 16:
        return None
    before = a[:first]
    level = float(np.median(before)) if len(before) else level_guess
    x = a[first: last + 1] - level
    p = _period(x, max(int(round(min_period_s / dt)), 2))
    if p is None:
        return None
    peak = float(np.max(np.abs(x)))
    # roughly steady first (a fade-in can shift the period a few samples), the period
    # from that part, then the steady part for that period
    rough = _steady_run(x, p, 0.1 * peak)
    if rough is not None and rough[1] - rough[0] >= 2 * p:
        p = _refined_period(x[rough[0]: rough[1]], p)
    tolerance = (4.0 * math.sqrt(2.0 / max(p // 20, 1)) * noise
                 + STEADY_TOLERANCE * peak)
    run = _steady_run(x, p, tolerance)
    if run is not None and run[1] - run[0] >= 2 * p:  # the period from the steady part
        p = _refined_period(x[run[0]: run[1]], p)
    # the cycles analysed: those that repeat within a real platform's irregularity
    run = _steady_run(x, p, tolerance + (PLATFORM_TOLERANCE - STEADY_TOLERANCE) * peak)
    if run is None:
        return None
    begin, end = run
    cycles = (end - begin) // p
    if cycles < 2:
        return None
    steady = x[begin: begin + cycles * p].reshape(cycles, p)
    spectrum = np.abs(np.fft.rfft(steady.mean(axis=0))) * 2 / p  # amplitude per harmonic
    remainder = steady - steady.mean(axis=0)
    # the average keeps 1/C of the noise; its amplitude SD per harmonic ~ σ·2/√(P·C)
    harmonic_noise = (float(np.sqrt(np.mean(remainder**2) * cycles / max(cycles - 1, 1)))
                      * 2 / math.sqrt(p * cycles))
    spectrum = spectrum[: p // 2 + 1]
    driven, distortion = _driven(spectrum, harmonic_noise)
    if not driven:
        return None
    if len(driven) == 1:
        kind = "sinusoid"
    elif len(driven) <= 6:
        kind = "sum of sines"
    else:
        kind = "multisine"
    period_s = round(p * dt, 9)  # a whole number of samples; the time column's rounding out
    strongest = float(spectrum[driven].max())
    return PeriodicTilt(
        period_samples=p, period_s=period_s, start=first + begin,
        start_s=float(t[first + begin]), cycles=int(cycles),
        moving_from_s=float(t[first]), moving_until_s=float(t[last]),
        harmonics=tuple(driven), frequencies_hz=tuple(k / period_s for k in driven),
        amplitudes_deg=tuple(math.degrees(float(spectrum[k])) for k in driven),
        distortion_hz=tuple(k / period_s for k in distortion),
        distortion_share=tuple(float(spectrum[k]) / strongest for k in distortion),
        kind=kind)


def recognise_periodic(times_s: np.ndarray, tilt_rad: np.ndarray
                       ) -> tuple[TiltProfile, PeriodicTilt] | None:
    """The tilt column as a periodic stimulus (:func:`find_periodic`), or None.

    Args:
        times_s: (S,) s, evenly sampled.
        tilt_rad: (S,) rad, the tilt column.

    Returns:
        (the column itself as a :class:`TiltProfile` carrying the period, the steady
        start, the steady cycles and the driven frequencies; what was found).
    """
    found = find_periodic(times_s, tilt_rad)
    if found is None:
        return None
    profile = tilt_from_array(np.asarray(times_s, dtype=float)
                              - float(np.asarray(times_s)[0]), tilt_rad,
                              description=found.describe())
    return replace(profile, period_s=found.period_s, periodic_from_s=found.start_s,
                   cycles=found.cycles, frequencies_hz=found.frequencies_hz), found
