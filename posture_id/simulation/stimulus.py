"""Support-surface tilt α_FS(t): the PRTS of MODEL §4 and user-given profiles.

Every stimulus is a piecewise-linear tilt angle (a :class:`TiltProfile`): the PRTS is a
sequence of constant tilt *velocities* held for 0.25 s each, so its position is exactly
piecewise linear; a user profile (array or CSV) is interpolated linearly between samples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from posture_id.errors import StimulusError
from posture_id.fileio import check_time_column, read_numeric_csv

__all__ = [
    "TiltProfile",
    "prts_symbols",
    "prts",
    "tilt_from_array",
    "tilt_from_csv",
    "recognise_prts",
    "check_recorded_tilt",
    "prts_match",
    "sample_rate_hint",
    "COMMON_RATES_HZ",
    "PRTS_REGISTERS",
]

#: Shift-register definitions (MODEL §4): states per cycle → (feedback, start register).
PRTS_REGISTERS = {
    242: ((0, 0, 1, -1, -1), (0, 0, 0, 0, 1)),
    80: ((0, 0, -1, 1), (0, 0, 0, 1)),
}
#: Duration of one PRTS state, s (Peterka 2002).
PRTS_STATE_S = 0.25


@dataclass(frozen=True)
class TiltProfile:
    """Piecewise-linear platform tilt.

    Attributes:
        times: (K,) s, strictly increasing knot times starting at 0.
        angles: (K,) rad, tilt at the knots (positive = toes down / forward, MODEL §1).
        description: a short human-readable origin ("PRTS 242 ×2, 1° p-p", a file name).
        period_s: s, the period of a periodic stimulus (one PRTS cycle), None otherwise.
        periodic_from_s: s, when the periodic part starts (after a lead-in and the
            platform's lag); 0 for a stimulus that starts at once.
    """

    times: np.ndarray
    angles: np.ndarray
    description: str = "tilt"
    period_s: float | None = None
    periodic_from_s: float = 0.0

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
        return TiltProfile(np.concatenate([[0.0], times[keep], [end]]),
                           np.interp(np.concatenate([[0.0], times[keep], [end]]) - offset_s,
                                     self.times, self.angles),
                           f"{self.description}, offset {offset_s:+.3f} s", self.period_s,
                           self.periodic_from_s)

    def on_grid(self, dt: float, n_steps: int) -> tuple[np.ndarray, np.ndarray]:
        """Tilt and tilt velocity at t = n·dt, n = 0..n_steps → two (n_steps + 1,) arrays."""
        t = np.arange(n_steps + 1) * dt
        return self.angle(t), self.velocity(t)


def prts_symbols(states: int = 242) -> np.ndarray:
    """One cycle of the ternary sequence, (states,) int8 in {−1, 0, +1} (MODEL §4).

    Each state emits x = (feedback · register) mod 3, read as +1, 0, −1 (2 → −1), then
    shifts the register right with x entering first.
    """
    if states not in PRTS_REGISTERS:
        raise StimulusError(f"PRTS with {states} states is not defined (use 242 or 80)")
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
    start_state: int = 0,
    sign: int = 1,
    lag_s: float = 0.0,
) -> TiltProfile:
    """The PRTS tilt: velocity = the ternary sequence, position scaled to a peak-to-peak.

    The defaults are MODEL §4's stimulus; the keyword-only arguments describe a PRTS as a
    lab ran it.

    Args:
        amplitude_deg: peak-to-peak tilt over a cycle, degrees (default 1° **[decision]**).
        cycles: number of cycles (default 2: 121 s for 242 states).
        states: 242 (5 stages, 60.5 s) or 80 (4 stages, 20 s).
        state_s: s per state.
        onset_s: s of level platform before the sequence starts (a lead-in).
        start_state: the sequence starts at this state of its cycle (0: the register's
            start state; the lab's PRTS may start part-way into its cycle).
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
    if int(start_state) != start_state or not 0 <= start_state < states:
        raise StimulusError(f"PRTS start state must be an integer in [0, {states}), "
                            f"got {start_state}")
    symbols = np.tile(np.roll(symbols, -int(start_state)).astype(float), int(cycles))
    steps = np.concatenate([[0.0], np.cumsum(symbols)])
    one_cycle = steps[: states + 1]
    scale = math.radians(amplitude_deg) / float(one_cycle.max() - one_cycle.min())
    delay = float(onset_s + lag_s)
    times = delay + np.arange(len(steps)) * state_s
    angles = sign * steps * scale
    if delay > 0:
        times, angles = np.concatenate([[0.0], times]), np.concatenate([[0.0], angles])
    extras = [text for text, used in (
        (f"state {state_s:g} s", state_s != PRTS_STATE_S),
        (f"onset {onset_s:g} s", onset_s > 0), (f"from state {int(start_state)}", start_state),
        ("negated", sign < 0), (f"lag {lag_s:g} s", lag_s > 0)) if used]
    return TiltProfile(
        times=times,
        angles=angles,
        description=f"PRTS {states} states x{int(cycles)}, {amplitude_deg:g} deg p-p"
                    + "".join(f", {e}" for e in extras),
        period_s=states * state_s,
        periodic_from_s=delay,
    )


def recognise_prts(times_s: np.ndarray, tilt_rad: np.ndarray,
                   tolerance: float = 1e-6) -> TiltProfile | None:
    """The PRTS a sampled tilt follows, or None.

    Recordings sample the tilt at 50 Hz, which misses the PRTS corners at odd multiples of
    0.25 s; when the samples are a PRTS of MODEL §4 (242 or 80 states from the start of
    its cycle, at once, either sign, any amplitude: the least-squares scale of the unit
    sequence), within ``tolerance`` of its peak-to-peak, the exact profile is returned,
    extended to whole cycles covering the recording. A recording shorter than one cycle
    is recognised too (at least 4 states long), so that it can be told it is too short.
    A PRTS with a lead-in, a lag or another starting state is not guessed: name it
    (:func:`prts` and the command line's stimulus flags).
    """
    t = np.asarray(times_s, dtype=float)
    a = np.asarray(tilt_rad, dtype=float)
    if len(t) < 2 or t[-1] < 4 * PRTS_STATE_S or not np.any(a):
        return None
    for states in (242, 80):
        cycles = max(1, int(math.ceil(t[-1] / (states * PRTS_STATE_S) - 1e-9)))
        unit = prts(1.0, cycles, states).angle(t)  # 1° peak to peak over a cycle
        k = float(unit @ a) / float(unit @ unit)
        if k == 0.0:
            continue
        if np.max(np.abs(k * unit - a)) <= tolerance * abs(k) * math.radians(1.0):
            return prts(abs(k), cycles, states, sign=1 if k > 0 else -1)
    return None


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
    x = x[:n] - x[:n].mean()
    template = prts(1.0, 1, states, state_s).angle(np.arange(n) / rate_hz)
    template = template - template.mean()
    norm = float(np.linalg.norm(x) * np.linalg.norm(template))
    if norm == 0:
        return 0.0
    correlation = np.fft.irfft(np.fft.rfft(x) * np.conj(np.fft.rfft(template)), n)
    return float(np.max(np.abs(correlation)) / norm)


def sample_rate_hint(times_s: np.ndarray, tilt_rad: np.ndarray, source: str,
                     state_s: float = PRTS_STATE_S) -> str | None:
    """A warning when the tilt is a PRTS (242 or 80 states of ``state_s``) sampled at a
    rate other than the one the time column gives, naming the likely true rate; None when
    the stated rate fits or no PRTS fits at any common rate (:data:`COMMON_RATES_HZ`).

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
    return (f"{source}: the tilt is a {states}-state PRTS sampled at {rate:g} Hz "
            f"(match {match:.2f}), not at the {stated:.4g} Hz the time column says "
            f"(match {at_stated:.2f}): check the time column")


def check_recorded_tilt(times_s: np.ndarray, tilt_rad: np.ndarray, stimulus: TiltProfile,
                        source: str, tolerance: float = 0.05) -> None:
    """Refuse a recorded tilt (``times_s``, ``tilt_rad``) that departs from the named
    stimulus by more than ``tolerance`` of its peak-to-peak (measurement noise stays well
    inside)."""
    expected = stimulus.angle(times_s)
    span = float(np.ptp(stimulus.angles)) or 1.0
    error = np.abs(tilt_rad - expected)
    worst = int(np.argmax(error))
    if error[worst] > tolerance * span:
        raise StimulusError(
            f"{source}: the tilt column is not the named stimulus ({stimulus.description}): "
            f"at t = {times_s[worst]:.3f} s it reads "
            f"{np.degrees(tilt_rad[worst]):.4g}° where the stimulus is at "
            f"{np.degrees(expected[worst]):.4g}° "
            f"({100 * error[worst] / span:.0f} % of its peak-to-peak); check the stimulus's "
            "states, onset, starting state, sign and lag")


def tilt_from_array(times_s, angles_rad, description: str = "array") -> TiltProfile:
    """A tilt profile from samples: ``times_s`` (K,) s from 0, ``angles_rad`` (K,) rad."""
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
    edge; other columns, such as a recording's segments, are ignored)."""
    header, values = read_numeric_csv(path, StimulusError, "tilt file")
    for col in ("time_s", "tilt_deg"):
        if col not in header:
            raise StimulusError(f"{path}: column '{col}' is missing (header: {','.join(header)})")
    times = values[:, header.index("time_s")]
    check_time_column(Path(path), times, StimulusError)
    angles = np.radians(values[:, header.index("tilt_deg")])
    if np.ptp(angles) == 0:
        raise StimulusError(f"{path}: column 'tilt_deg' is constant: there is no stimulus")
    return tilt_from_array(times, angles, description=str(path))
