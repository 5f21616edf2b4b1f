"""Support-surface tilt α_FS(t): the PRTS of docs/model.md §4 and user-given profiles.

Every stimulus is a piecewise-linear tilt angle (a :class:`TiltProfile`): the PRTS is a
sequence of constant tilt *velocities* held for 0.25 s each, so its position is exactly
piecewise linear; a user profile (array or CSV) is interpolated linearly between samples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from posture_id.errors import StimulusError
from posture_id.fileio import check_time_column
from posture_id.text_table import read_text_table

__all__ = [
    "TiltProfile",
    "prts_symbols",
    "prts",
    "tilt_from_array",
    "tilt_from_csv",
    "read_tilt_file",
    "recognise_prts",
    "recognise_lab_prts",
    "unit_position",
    "check_recorded_tilt",
    "prts_match",
    "sample_rate_hint",
    "likely_sample_rate",
    "RateMatch",
    "LAB_STATE_RANGE_S",
    "COMMON_RATES_HZ",
    "PRTS_REGISTERS",
    "column_noise",
]

#: Shift-register definitions (docs/model.md §4): states per cycle → (feedback, start register).
PRTS_REGISTERS = {
    242: ((0, 0, 1, -1, -1), (0, 0, 0, 0, 1)),
    80: ((0, 0, -1, 1), (0, 0, 0, 1)),
}
#: Duration of one PRTS state, s (Peterka 2002).
PRTS_STATE_S = 0.25
#: The range of state durations posture labs usually run, s.
LAB_STATE_RANGE_S = (0.2, 0.3)


@dataclass(frozen=True)
class TiltProfile:
    """Piecewise-linear platform tilt.

    Attributes:
        times: (K,) s, strictly increasing knot times starting at 0.
        angles: (K,) rad, tilt at the knots (positive = toes down / forward, docs/model.md §1).
        description: a short human-readable origin ("PRTS 242 ×2, 1° p-p", a file name).
        period_s: s, the period of a periodic stimulus (one PRTS cycle), None otherwise.
        periodic_from_s: s, when the periodic part starts (after a lead-in and the
            platform's lag); 0 for a stimulus that starts at once.
        states: the states of a PRTS's cycle (242 or 80), None for another tilt.
        cycles: the whole cycles of the periodic part from ``periodic_from_s`` (a
            periodic tilt between level stretches or after a fade-in), None: every whole
            cycle until the recording ends.
        frequencies_hz: the frequencies the stimulus drives (a recognised sinusoid's, not
            its platform's distortion), None: every harmonic of the period the tilt has
            power at.
    """

    times: np.ndarray
    angles: np.ndarray
    description: str = "tilt"
    period_s: float | None = None
    periodic_from_s: float = 0.0
    states: int | None = None
    cycles: int | None = None
    frequencies_hz: tuple[float, ...] | None = None

    @property
    def whole_cycles_s(self) -> float | None:
        """s, the shortest recording that holds one whole cycle (None: not periodic)."""
        return None if self.period_s is None else self.periodic_from_s + self.period_s

    @property
    def duration(self) -> float:
        """s, time of the last knot."""
        return float(self.times[-1])

    def angle(self, t: np.ndarray | float) -> np.ndarray:
        """Tilt at times ``t`` (s) → rad, same shape; held constant after the end."""
        return np.interp(t, self.times, self.angles)

    def velocity(self, t: np.ndarray | float) -> np.ndarray:
        """Tilt velocity at ``t`` (s) → rad/s: slope of the interval starting at or before t."""
        slopes = np.diff(self.angles) / np.diff(self.times)
        idx = np.searchsorted(self.times, np.asarray(t) + 1e-9, side="right") - 1
        inside = (idx >= 0) & (idx < len(slopes))
        return np.where(inside, slopes[np.clip(idx, 0, len(slopes) - 1)], 0.0)

    def delayed(self, offset_s: float) -> TiltProfile:
        """The same tilt ``offset_s`` later (earlier when negative), over the same duration:
        the knots move, the tilt before the first one is the first angle, what moves
        outside [0, duration] is cut. The
        periodic part is still counted from where it started (``periodic_from_s``): a small
        offset does not cost a whole cycle of analysis, and the cycle average of a periodic
        response does not depend on where its cycles are cut."""
        if not math.isfinite(offset_s):
            raise StimulusError(f"a time offset must be finite, got {offset_s}")
        times = self.times + offset_s
        end = self.duration
        keep = (times > 1e-12) & (times < end - 1e-12)
        knots = np.concatenate([[0.0], times[keep], [end]])
        return replace(self, times=knots,
                       angles=np.interp(knots - offset_s, self.times, self.angles),
                       description=f"{self.description}, offset {offset_s:+.3f} s")

    def spanning(self, duration_s: float) -> TiltProfile:
        """The same tilt over exactly ``duration_s``: cut there (a recording shorter than
        the stimulus) or held at its last angle until then (a recording with a tail)."""
        if not (math.isfinite(duration_s) and duration_s > 0):
            raise StimulusError(f"a duration must be a finite time > 0 s, got {duration_s}")
        end = self.duration
        if abs(end - duration_s) <= 1e-9:
            return self
        if end > duration_s:
            keep = self.times < duration_s - 1e-9
            times = np.concatenate([self.times[keep], [duration_s]])
            angles = np.concatenate([self.angles[keep], [float(self.angle(duration_s))]])
        else:
            times = np.concatenate([self.times, [duration_s]])
            angles = np.concatenate([self.angles, [self.angles[-1]]])
        return replace(self, times=times, angles=angles)

    def on_grid(self, dt: float, n_steps: int) -> tuple[np.ndarray, np.ndarray]:
        """Tilt and tilt velocity at t = n·dt, n = 0..n_steps → two (n_steps + 1,) arrays."""
        t = np.arange(n_steps + 1) * dt
        return self.angle(t), self.velocity(t)


@lru_cache(maxsize=32)
def _unit_prts(cycles: int, states: int) -> TiltProfile:
    """docs/model.md §4's PRTS of 1° peak to peak (cached: recognition tries it on every
    recording)."""
    return prts(1.0, cycles, states)


def prts_symbols(states: int = 242) -> np.ndarray:
    """One cycle of the ternary sequence, (states,) int8 in {−1, 0, +1} (docs/model.md §4).

    Each state emits x = (feedback · register) mod 3, read as +1, 0, −1 (2 → −1), then
    shifts the register right with x entering first.
    """
    if states not in PRTS_REGISTERS:
        raise StimulusError(f"PRTS with {states} states is not defined (use 242 or 80)")
    return _symbols(states).copy()


@lru_cache(maxsize=4)
def _symbols(states: int) -> np.ndarray:
    feedback, start = PRTS_REGISTERS[states]
    reg = list(start)
    out = np.empty(states, dtype=np.int8)
    for k in range(states):
        x = sum(f * r for f, r in zip(feedback, reg, strict=True)) % 3
        out[k] = -1 if x == 2 else x
        reg = [x, *reg[:-1]]
    return out


def prts(
    amplitude_deg: float = 1.0,
    cycles: int = 2,
    states: int = 242,
    state_s: float = PRTS_STATE_S,
    *,
    onset_s: float = 0.0,
    start_state: float = 0,
    sign: int = 1,
    lag_s: float = 0.0,
) -> TiltProfile:
    """The PRTS tilt: velocity = the ternary sequence, position scaled to a peak-to-peak.

    The defaults are docs/model.md §4's stimulus; the keyword-only arguments describe a PRTS as a
    lab ran it.

    Args:
        amplitude_deg: peak-to-peak tilt over a cycle, degrees (default 1° **[decision]**).
        cycles: number of cycles (default 2: 121 s for 242 states).
        states: 242 (5 stages, 60.5 s) or 80 (4 stages, 20 s).
        state_s: s per state.
        onset_s: s of level platform before the sequence starts (a lead-in).
        start_state: where in its cycle the sequence starts, in states from the register's
            start state, fractional for a start part-way through a state (a lab's PRTS
            may start anywhere in its cycle); the platform is level at the start, and
            after whole cycles it is level again.
        sign: +1, or −1 when the platform's positive tilt is the other way.
        lag_s: s the platform's tilt follows its command late (adds to the onset).
    """
    if not (math.isfinite(amplitude_deg) and amplitude_deg >= 0):
        raise StimulusError(f"PRTS amplitude must be a finite angle ≥ 0, got {amplitude_deg}")
    if int(cycles) != cycles or cycles < 1:
        raise StimulusError(f"PRTS cycles must be a positive integer, got {cycles}")
    if not (math.isfinite(state_s) and state_s > 0):
        raise StimulusError(f"PRTS state duration must be > 0 s, got {state_s}")
    for name, value in (("onset_s", onset_s), ("lag_s", lag_s)):
        if not (math.isfinite(value) and value >= 0):
            raise StimulusError(f"PRTS {name} must be a finite time ≥ 0 s, got {value}")
    if sign not in (1, -1):
        raise StimulusError(f"PRTS sign must be +1 or -1, got {sign}")
    symbols = prts_symbols(states)
    if not (math.isfinite(start_state) and 0 <= start_state < states):
        raise StimulusError(f"PRTS start state must be a number in [0, {states}), "
                            f"got {start_state}")
    first = float(start_state)
    # state-time knots: the start, every state boundary after it, the end
    inner = np.arange(math.floor(first) + 1, first + cycles * states - 1e-9)
    knots = np.concatenate([[first], inner[inner > first + 1e-9], [first + cycles * states]])
    unit = unit_position(symbols, knots) - unit_position(symbols, np.array([first]))[0]
    scale = math.radians(amplitude_deg) / float(np.ptp(unit_position(
        symbols, np.arange(states + 1, dtype=float))))
    delay = float(onset_s + lag_s)
    times = delay + (knots - first) * state_s
    angles = sign * unit * scale
    if delay > 0:
        times, angles = np.concatenate([[0.0], times]), np.concatenate([[0.0], angles])
    extras = [text for text, used in (
        (f"state {state_s:g} s", state_s != PRTS_STATE_S),
        (f"onset {onset_s:g} s", onset_s > 0), (f"from state {first:g}", first),
        ("negated", sign < 0), (f"lag {lag_s:g} s", lag_s > 0)) if used]
    return TiltProfile(
        times=times,
        angles=angles,
        description=f"PRTS {states} states x{int(cycles)}, {amplitude_deg:g} deg p-p"
                    + "".join(f", {e}" for e in extras),
        period_s=states * state_s,
        periodic_from_s=delay,
        states=states,
        cycles=int(cycles),
    )


def unit_position(symbols: np.ndarray, state_time: np.ndarray) -> np.ndarray:
    """The unit PRTS position (the running sum of the symbols, one unit per state at
    velocity ±1) at state times ``state_time`` (any real numbers; periodic, since a
    cycle's symbols sum to zero) → same shape."""
    symbols = np.asarray(symbols, dtype=float)
    n = len(symbols)
    cumulative = np.concatenate([[0.0], np.cumsum(symbols)])
    s = np.asarray(state_time, dtype=float)
    whole = np.floor(s)
    k = whole.astype(np.int64) % n
    return cumulative[k] + (s - whole) * symbols[k]


def recognise_prts(times_s: np.ndarray, tilt_rad: np.ndarray,
                   tolerance: float = 1e-6) -> TiltProfile | None:
    """The PRTS a sampled tilt follows, as the lab ran it, or None.

    First the plain case, exactly: a PRTS of docs/model.md §4 (242 or 80 states of 0.25 s from the
    start of its cycle, at once, either sign, any amplitude: the least-squares scale of the
    unit sequence) within ``tolerance`` of its peak-to-peak; the exact profile is
    returned, extended to whole cycles covering the recording (recordings sample the tilt
    at 50 Hz and miss the PRTS corners). A recording shorter than one cycle is recognised
    too (at least 4 states long), so that it can be told it is too short.

    Otherwise, as a lab runs it (:func:`recognise_lab_prts`): 242 or 80 states of any
    duration from 0.1 to 0.5 s, starting anywhere in the cycle (part-way through a state
    too), after a level lead-in and the platform's lag, either sign, with the platform
    level again after the last whole cycle or the recording ending before it.
    """
    t = np.asarray(times_s, dtype=float)
    a = np.asarray(tilt_rad, dtype=float)
    if len(t) < 2 or t[-1] < 4 * PRTS_STATE_S or not np.any(a):
        return None
    for states in (242, 80):
        cycles = max(1, int(math.ceil(t[-1] / (states * PRTS_STATE_S) - 1e-9)))
        unit = _unit_prts(cycles, states).angle(t)  # 1° peak to peak over a cycle
        k = float(unit @ a) / float(unit @ unit)
        if k == 0.0:
            continue
        if np.max(np.abs(k * unit - a)) <= tolerance * abs(k) * math.radians(1.0):
            return prts(abs(k), cycles, states, sign=1 if k > 0 else -1)
    return recognise_lab_prts(t, a)


#: The lab PRTS search: state durations tried (s), the rate it first searches at (Hz), the
#: least normalised correlation of the first cycle, and the RMS misfit of the refined
#: stimulus (share of the tilt's peak-to-peak) allowed beyond the column's own noise for
#: a tilt to count as a PRTS.
LAB_STATE_S = np.arange(0.10, 0.50 + 1e-9, 0.0025)
_SEARCH_RATE_HZ, _MIN_MATCH, _MAX_MISFIT = 50.0, 0.9, 0.005


def column_noise(x: np.ndarray) -> float:
    """Robust SD of a column's white measurement noise, from its second differences
    (Δ² of white noise has variance 6σ²; a smooth tilt adds little)."""
    if len(x) < 3:
        return 0.0
    return 1.4826 * float(np.median(np.abs(np.diff(x, 2)))) / math.sqrt(6.0)


def recognise_lab_prts(times_s: np.ndarray, tilt_rad: np.ndarray) -> TiltProfile | None:
    """The PRTS a lab ran, from an evenly sampled tilt column (see :func:`recognise_prts`),
    or None.

    The platform is level (0) until the sequence starts; the first whole cycle after it
    is matched against every state duration of :data:`LAB_STATE_S`, both sequences, every
    starting phase and both signs (circular cross-correlation of the samples at 50 Hz);
    the best match is refined by least squares on every sample (onset, starting state,
    state duration, amplitude). The cycles are those the moving part spans when the
    platform is level again before the recording ends, else enough to reach its end.
    """
    t = np.asarray(times_s, dtype=float)
    a = np.asarray(tilt_rad, dtype=float)
    span = float(np.ptp(a))
    if len(t) < 8 or span == 0:
        return None
    # a piecewise-linear tilt has no second difference but at its corners: what there is
    # elsewhere is the column's measurement noise
    noise = column_noise(a)
    still = max(1e-3 * span, 5.0 * noise)
    if abs(a[0]) > max(0.02 * span, still):  # not level at the start: not a lab PRTS
        return None
    moving = np.flatnonzero(np.abs(a) > still)
    if len(moving) < 8:
        return None
    first, last = max(int(moving[0]) - 1, 0), int(moving[-1])
    grid = np.arange(t[first], t[-1], 1.0 / _SEARCH_RATE_HZ)
    coarse = np.interp(grid, t, a)
    best = (0.0, 0, 0.0, 0, 1)  # (match, states, state_s, shift, sign)
    for states in (242, 80):
        symbols = prts_symbols(states)
        for state_s in LAB_STATE_S:
            n = int(round(states * state_s * _SEARCH_RATE_HZ))
            if n > len(coarse) or n < 8:
                continue
            template = unit_position(symbols, np.arange(n) / (state_s * _SEARCH_RATE_HZ))
            corr = _correlation(template, coarse[:n])
            if corr is None:
                continue
            k = int(np.argmax(np.abs(corr)))
            if abs(corr[k]) > best[0]:
                best = (float(abs(corr[k])), states, float(state_s), k,
                        1 if corr[k] > 0 else -1)
    match, states, state_s, shift, sign = best
    if match < _MIN_MATCH:
        return None
    period = states * state_s
    onset = float(t[first])
    level_after = last < len(a) - 1 and np.all(np.abs(a[last + 1:]) <= still)
    if level_after:
        cycles = max(1, int(round((t[last] - onset) / period)))
    else:
        cycles = max(1, int(math.ceil((t[-1] - onset) / period - 1e-6)))
    start = (shift / (state_s * _SEARCH_RATE_HZ)) % states
    symbols = prts_symbols(states)
    unit_cycle = np.ptp(unit_position(symbols, np.arange(states + 1, dtype=float)))
    x = coarse[: int(round(period * _SEARCH_RATE_HZ))]
    shape = unit_position(symbols, start + np.arange(len(x)) / (state_s * _SEARCH_RATE_HZ))
    shape = sign * (shape - unit_position(symbols, np.array([start]))[0])
    amplitude = math.degrees(float(shape @ x) / float(shape @ shape)) * unit_cycle

    def profile(p: np.ndarray, snap: bool = False) -> TiltProfile:
        onset_s, first_state, duration, peak = p
        first_state, negated = first_state % states, sign
        # half a cycle on, a PRTS is the same sequence negated: name the start in the
        # first half ("from state 121, negated" is the 242-state PRTS from its start)
        if first_state >= states / 2 - 1e-6:
            first_state, negated = max(first_state - states / 2, 0.0), -sign
        if snap:  # what least squares left a rounding error away from a round value
            onset_s = 0.0 if onset_s < 1e-6 else onset_s
            nearest = round(first_state)
            first_state = float(nearest % states) if abs(first_state - nearest) < 1e-6 \
                else first_state
        return prts(abs(peak), cycles, states, duration, onset_s=max(onset_s, 0.0),
                    start_state=first_state, sign=negated)

    def misfit(p: np.ndarray) -> np.ndarray:
        """The column less the profile ``p[:4]`` and a constant offset ``p[4]`` (rad: a
        sensor's zero, two platform markers at slightly different heights), per span."""
        return (profile(p[:4]).angle(t) + p[4] - a) / span

    from scipy.optimize import least_squares  # only for a tilt that is not the plain PRTS

    # the first motion shows late when the first states move little (or noise hides
    # them): the onset is where the level lead-in best meets the matched periodic
    # sequence, searched on the coarse grid from the recording's start to one state after
    # the first motion (the window: up to one cycle after that)
    coarse_t = np.arange(0.0, t[-1], 1.0 / _SEARCH_RATE_HZ)
    c = np.interp(coarse_t, t, a)
    window = coarse_t <= t[first] + period
    c, tau = c[window], coarse_t[window]
    scale = math.radians(amplitude) / unit_cycle
    m = sign * scale * unit_position(symbols, start + (tau - t[first]) / state_s)
    candidates = np.flatnonzero(tau <= t[first] + state_s)
    before = np.concatenate([[0.0], np.cumsum(c**2)])[candidates]  # Σ c² before τ0
    r = c - m
    after_r2 = np.cumsum((r**2)[::-1])[::-1][candidates]
    after_r = np.cumsum(r[::-1])[::-1][candidates]
    count = (len(c) - candidates).astype(float)
    m0 = m[candidates]
    cost = before + after_r2 + 2 * m0 * after_r + m0**2 * count
    k0 = int(candidates[int(np.argmin(cost))])
    onset = float(tau[k0])
    guess = np.array([onset, start + (onset - t[first]) / state_s, state_s, amplitude, 0.0])
    scales = np.array([0.01, 0.05, 0.001, abs(amplitude), 1e-3 * span])
    low = np.array([0.0, -np.inf, 0.05, 0.0, -np.inf])
    high = np.array([np.inf, np.inf, 1.0, np.inf, np.inf])

    def fit(x0: np.ndarray, free: np.ndarray):
        """Least squares over the parameters ``free`` (bool (5,)), the rest held at x0's."""
        def full(q: np.ndarray) -> np.ndarray:
            p = x0.copy()
            p[free] = q
            return p
        # a noise-free tilt leaves a misfit at rounding level, where the relative
        # tolerances never stop the search (500 evaluations for nothing, 10 s at
        # 1000 Hz); every other case stops within 50
        done = least_squares(lambda q: misfit(full(q)), x0[free], x_scale=scales[free],
                             bounds=(low[free], high[free]), method="trf", max_nfev=100)
        return full(done.x), float(done.cost)

    every = np.ones(5, dtype=bool)
    # the lead-in the search found, and the sequence from the recording's start: noise can
    # hide first states that move little, and the search then takes them for level
    at_once = np.array([0.0, start - t[first] / state_s, state_s, amplitude, 0.0])
    fitted, cost = min((fit(x0, every) for x0 in (guess, at_once)), key=lambda f: f[1])
    if fitted[0] > 0:
        # a short lead-in and a constant offset can stand in for the first part of a
        # state: no lead-in is kept unless the noise cannot explain the difference (a
        # χ² of one parameter at 1 %: 6.6 noise variances, cost being half the sum)
        without = every.copy()
        without[0] = False
        fitted_zero = fit(np.where(np.arange(5) == 0, 0.0, fitted), without)
        if fitted_zero[1] - cost <= 3.3 * (noise / span) ** 2 + 1e-12:
            fitted, cost = fitted_zero
    # a lab's state lasts a round number of 0.1 ms (its period is then a whole number of
    # samples at a lab's rates, as cycle averages need): the rest fitted again with it
    fitted[2] = round(fitted[2], 4)
    free = every.copy()
    free[2] = False
    if fitted[0] == 0.0:
        free[0] = False
    rounded, _ = fit(fitted, free)
    onset_s, first_state, state_s, peak, _ = rounded
    residual = misfit(rounded)
    # the right sequence leaves the column's own noise; a wrong one leaves more
    if np.sqrt(np.mean(residual**2)) > _MAX_MISFIT + 1.25 * noise / span:
        return None
    return profile(np.array([onset_s, first_state, state_s, peak]), snap=True)


#: Sampling rates (Hz) of posture labs' force plates and motion capture, tried by
#: :func:`sample_rate_hint` besides the stated one.
COMMON_RATES_HZ = (25.0, 30.0, 50.0, 60.0, 100.0, 120.0, 200.0, 240.0, 250.0, 500.0, 1000.0)


def prts_match(tilt_rad: np.ndarray, rate_hz: float, states: int,
               state_s: float = PRTS_STATE_S) -> float:
    """How well the first cycle of a sampled tilt matches the PRTS of ``states`` states
    sampled at ``rate_hz``: the largest |normalised circular cross-correlation| over all
    starting phases and both signs (1 = a perfect match; noise, a lead-in or a platform
    lag lower it a little). 0 when the tilt is shorter than one cycle."""
    period = states * state_s * rate_hz
    n = int(round(period))
    x = np.asarray(tilt_rad, dtype=float)
    if n < 8 or len(x) < n:
        return 0.0
    correlation = _correlation(x[:n], prts(1.0, 1, states, state_s).angle(np.arange(n) / rate_hz))
    return 0.0 if correlation is None else float(np.max(np.abs(correlation)))


def _correlation(a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
    """(n,) the circular cross-correlation of two (n,) series, each less its mean, over the
    product of their norms (its peak is 1 where one is the other shifted); None where
    either is constant."""
    a, b = a - a.mean(), b - b.mean()
    norm = float(np.linalg.norm(a) * np.linalg.norm(b))
    if norm == 0:
        return None
    return np.fft.irfft(np.fft.rfft(a) * np.conj(np.fft.rfft(b)), len(a)) / norm


@dataclass(frozen=True)
class RateMatch:
    """A PRTS found in a tilt at a rate other than its time column's.

    Attributes:
        rate_hz: the common rate it matches at. states: its length.
        match: its correlation there. stated_hz: the time column's rate.
        at_stated: the best match at the stated rate.
    """

    rate_hz: float
    states: int
    match: float
    stated_hz: float
    at_stated: float

    def hint(self, name: str) -> str:
        """The warning for recording ``name``."""
        return (f"{name}: the tilt is a {self.states}-state PRTS sampled at {self.rate_hz:g} "
                f"Hz (match {self.match:.2f}), not at the {self.stated_hz:.4g} Hz the time "
                f"column says (match {self.at_stated:.2f}): check the time column")

    def alternative(self, name: str, found: str) -> str:
        """The notice for recording ``name`` whose tilt is also ``found`` (a description
        of a PRTS of lab-length states) at the stated rate: the samples alone cannot tell
        the two apart, so both are named."""
        return (f"{name}: the tilt is a {found} at the {self.stated_hz:.4g} Hz the time "
                f"column says; the same samples are a {self.states}-state PRTS of "
                f"{PRTS_STATE_S:g} s states at {self.rate_hz:g} Hz: if the lab's states last "
                f"{PRTS_STATE_S:g} s, the time column is wrong")


def likely_sample_rate(times_s: np.ndarray, tilt_rad: np.ndarray,
                       state_s: float = PRTS_STATE_S) -> RateMatch | None:
    """The common rate (:data:`COMMON_RATES_HZ`) at which the tilt is a PRTS (242 or 80
    states of ``state_s``) when the time column's rate is not it; None when the stated
    rate fits or no PRTS fits at any common rate.

    A PRTS matches at its true rate with a correlation near 1 and poorly at any other
    rate, because the cycle then spans another number of samples.
    """
    stated = float(1.0 / np.median(np.diff(np.asarray(times_s, dtype=float))))
    best = (0.0, stated, 0)
    at_stated = 0.0
    for states in PRTS_REGISTERS:
        at_stated = max(at_stated, prts_match(tilt_rad, stated, states, state_s))
        for rate in COMMON_RATES_HZ:
            match = prts_match(tilt_rad, rate, states, state_s)
            if match > best[0]:
                best = (match, rate, states)
    match, rate, states = best
    if match < 0.9 or abs(rate / stated - 1) <= 0.01 or at_stated >= match - 0.05:
        return None
    return RateMatch(rate, states, match, stated, at_stated)


def sample_rate_hint(times_s: np.ndarray, tilt_rad: np.ndarray, name: str,
                     state_s: float = PRTS_STATE_S) -> str | None:
    """A warning when the tilt is a PRTS sampled at a rate other than the one the time
    column gives, naming the likely true rate (:func:`likely_sample_rate`); None when
    there is none."""
    found = likely_sample_rate(times_s, tilt_rad, state_s)
    return None if found is None else found.hint(name)


def check_recorded_tilt(times_s: np.ndarray, tilt_rad: np.ndarray, stimulus: TiltProfile,
                        name: str, tolerance: float = 0.05) -> None:
    """Refuse a recorded tilt (``times_s``, ``tilt_rad``) that departs from the named
    stimulus by more than ``tolerance`` of its peak-to-peak (measurement noise stays well
    inside)."""
    expected = stimulus.angle(times_s)
    span = float(np.ptp(stimulus.angles)) or 1.0
    error = np.abs(tilt_rad - expected)
    worst = int(np.argmax(error))
    if error[worst] > tolerance * span:
        raise StimulusError(
            f"{name}: the tilt column is not the named stimulus ({stimulus.description}): "
            f"at t = {times_s[worst]:.3f} s it reads "
            f"{np.degrees(tilt_rad[worst]):.4g}° where the stimulus is at "
            f"{np.degrees(expected[worst]):.4g}° "
            f"({100 * error[worst] / span:.0f} % of its peak-to-peak); check the stimulus's "
            "states, onset, starting state, sign and lag")


def tilt_from_array(times_s: ArrayLike, angles_rad: ArrayLike, description: str = "array"
                    ) -> TiltProfile:
    """A tilt profile from samples: ``times_s`` (K,) s from 0, ``angles_rad`` (K,) rad.

    Args:
        times_s: (K,) s, starting at 0 and increasing, K ≥ 2.
        angles_rad: (K,) rad, the tilt at those times.
        description: names the profile (its ``description``) and the samples in errors.
    Raises:
        StimulusError: arrays of other shapes, values that are not finite, or times that
            do not start at 0 or do not increase.
    """
    t = np.asarray(times_s, dtype=float)
    a = np.asarray(angles_rad, dtype=float)
    if t.ndim != 1 or a.shape != t.shape or len(t) < 2:
        raise StimulusError(f"{description}: times and angles must be two 1-D arrays of equal "
                            f"length ≥ 2 (got {t.shape} and {a.shape})")
    for name, arr in (("time_s", t), ("tilt", a)):
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            raise StimulusError(
                f"{description}: row {bad[0] + 1}: {name} is not a finite number ({arr[bad[0]]})"
            )
    if abs(t[0]) > 1e-9:
        raise StimulusError(f"{description}: time_s must start at 0, starts at {t[0]}")
    step = np.flatnonzero(np.diff(t) <= 0)
    if step.size:
        raise StimulusError(
            f"{description}: row {step[0] + 2}: time_s does not increase ({t[step[0] + 1]})"
        )
    return TiltProfile(times=t - t[0], angles=a, description=description)


def tilt_from_csv(path: str | Path) -> TiltProfile:
    """Read a tilt profile CSV with columns ``time_s`` and ``tilt_deg`` (degrees at the
    edge; other columns, such as a recording's segments, are ignored).

    Args:
        path: the CSV file; it names the profile (its ``description``).
    Returns:
        :class:`TiltProfile` in radians.
    Raises:
        StimulusError: naming the file: not a numeric CSV, a column missing, times that
            do not start at 0, do not increase or are not in seconds, or a constant tilt.
    """
    return read_tilt_file(path)[0]


def read_tilt_file(path: str | Path) -> tuple[TiltProfile, tuple[str, ...]]:
    """:func:`tilt_from_csv`'s profile and what reading the file noticed (its encoding,
    title lines skipped, decimal commas), each naming the file."""
    table = read_text_table(Path(path), StimulusError, "tilt file")
    header, values = list(table.header), table.values
    for col in ("time_s", "tilt_deg"):
        if col not in header:
            raise StimulusError(f"{path}: column '{col}' is missing (header: {','.join(header)})")
    times = values[:, header.index("time_s")]
    check_time_column(Path(path), times, StimulusError)
    angles = np.radians(values[:, header.index("tilt_deg")])
    if np.ptp(angles) == 0:
        raise StimulusError(f"{path}: column 'tilt_deg' is constant: there is no stimulus")
    return tilt_from_array(times, angles, description=str(path)), table.notices
