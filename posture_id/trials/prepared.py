"""The entrance: a recording and its stimulus, checked once, at the rate the model needs.

Everything past the entrance (least squares, the CNN, the FRF, the re-simulation check,
cohorts) takes a :class:`PreparedTrial` and checks nothing of the recording again.

    >>> trial = prepare_trial(Recording.from_csv("rec.csv"), rate_hz=50.0)
    >>> trial.stimulus.description, trial.notices
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from posture_id.errors import RecordingError, StimulusError
from posture_id.recording import Recording
from posture_id.simulation.periodic import recognise_periodic, true_runs
from posture_id.simulation.stimulus import (
    LAB_STATE_RANGE_S,
    PRTS_REGISTERS,
    PRTS_STATE_S,
    TiltProfile,
    check_recorded_tilt,
    likely_sample_rate,
    recognise_prts,
    sample_rate_hint,
    tilt_from_array,
)

__all__ = ["PreparedTrial", "prepare_trial", "MIN_ANY_TILT_S"]

#: Shortest recording of a tilt that is not periodic, s.
MIN_ANY_TILT_S = 20.0


@dataclass(frozen=True)
class PreparedTrial:
    """A recording ready for identification.

    Attributes:
        recording: finite, evenly sampled, at ``rate_hz`` (resampled when it was not).
        stimulus: the tilt as it was run: named and checked against the tilt column,
            recognised as a PRTS, or the tilt column itself interpolated.
        notices: what was noticed on the way in (resampling, a recognised stimulus, a
            time column that gives the wrong rate), each naming the recording.
        original_rate_hz: Hz, the rate of the recording as given.
        time_offset_s: s, how far the stimulus has been shifted from the one named or
            recognised (:meth:`shifted`; a fitted platform lag).
        rate_hint: the notice that the tilt is a PRTS at another rate than the time column
            says (also among ``notices``), or None.
    """

    recording: Recording
    stimulus: TiltProfile
    notices: tuple[str, ...] = ()
    original_rate_hz: float = math.nan
    time_offset_s: float = 0.0
    rate_hint: str | None = None

    @property
    def name(self) -> str:
        return self.recording.name

    @property
    def tilt_recorded(self) -> bool:
        """The tilt column was recorded (False: filled in from the named stimulus)."""
        return self.recording.tilt_recorded

    @property
    def rate_hz(self) -> float:
        return self.recording.sample_rate_hz

    @property
    def resampled(self) -> bool:
        """Whether the recording was brought to another rate on the way in."""
        return abs(self.original_rate_hz / self.rate_hz - 1.0) > 1e-6

    def shifted(self, offset_s: float) -> PreparedTrial:
        """The same sway with the stimulus ``offset_s`` later than the one prepared (the
        tilt column follows it); offsets add up in :attr:`time_offset_s`."""
        stimulus = self.stimulus.delayed(offset_s)
        recording = replace(self.recording, tilt=stimulus.angle(self.recording.time))
        return replace(self, recording=recording, stimulus=stimulus,
                       time_offset_s=self.time_offset_s + offset_s)

    def shifted_whole(self, offset_s: float) -> PreparedTrial | None:
        """:meth:`shifted`, its analysed cycles the moved stimulus's own whole cycles
        inside the recording: counted from where its periodic part now starts, a cycle
        that moved before the recording's start left out, and none past the recording's
        end or, for a stimulus of a given number of cycles, past its last (an offset
        either way must not analyse lead-in or the level rest after the stimulus as
        part of a cycle); None when less than one whole cycle is left."""
        shifted = self.shifted(offset_s)
        stimulus, period = self.stimulus, self.stimulus.period_s
        if period is not None:
            duration = self.recording.duration_s
            start = stimulus.periodic_from_s + offset_s
            # the whole cycles the profile holds (a recording may end before the last)
            held = math.floor((min(duration, stimulus.duration) - stimulus.periodic_from_s)
                              / period + 1e-9)
            held = held if stimulus.cycles is None else min(held, stimulus.cycles)
            skipped = max(0, math.ceil(-start / period - 1e-9))
            start += skipped * period
            fits = math.floor((duration - start) / period + 1e-9)
            cycles = min(held - skipped, fits)
            if cycles < 1:
                return None
            shifted = replace(shifted, stimulus=replace(shifted.stimulus, periodic_from_s=start,
                                                        cycles=cycles))
        return None if shifted.whole_cycle_shortfall() is not None else shifted

    def require_segments(self, segments: tuple[str, ...]) -> None:
        """Refuse a trial whose segment columns are not ``segments`` (a body's)."""
        self.recording.check_segments(segments)

    def shorter_than(self, needed_s: float, what: str) -> str | None:
        """Why the trial is shorter than ``needed_s`` seconds (``what`` says why that
        long), or None when it is not."""
        if self.recording.duration_s < needed_s - 1e-9:
            return (f"the recording lasts {self.recording.duration_s:.2f} s, shorter than "
                    f"{what}")
        return None

    def require_duration(self, needed_s: float, what: str) -> None:
        """Refuse a trial shorter than ``needed_s`` seconds; ``what`` says why that long."""
        short = self.shorter_than(needed_s, what)
        if short is not None:
            raise RecordingError(f"{self.name}: {short}")

    def whole_cycle_shortfall(self) -> str | None:
        """Why the trial is shorter than one whole cycle of its stimulus (after its
        lead-in), or than :data:`MIN_ANY_TILT_S` for a tilt that is not periodic; None
        when it is not."""
        needed = self.stimulus.whole_cycles_s
        if needed is None:
            return self.shorter_than(MIN_ANY_TILT_S, f"{MIN_ANY_TILT_S:g} s (the least for a "
                                                     "tilt that is not periodic)")
        return self.shorter_than(needed, f"one whole cycle of its stimulus "
                                         f"({self.stimulus.description}: {needed:g} s)")

    def require_whole_cycle(self) -> None:
        """Refuse a trial :meth:`whole_cycle_shortfall` finds too short."""
        short = self.whole_cycle_shortfall()
        if short is not None:
            raise RecordingError(f"{self.name}: {short}")


def prepare_trial(recording: Recording, stimulus: TiltProfile | None = None,
                  rate_hz: float | None = 50.0) -> PreparedTrial:
    """Check a recording once, find its stimulus, and bring it to ``rate_hz``.

    Args:
        recording: as read or simulated; its ``name`` names it in every message.
        stimulus: the stimulus as the lab ran it; the tilt column must follow it.
            Default: a PRTS recognised in the tilt, else the tilt itself, interpolated.
        rate_hz: the rate the consumer needs (the model's output rate; 50 Hz); None
            keeps the recording's own rate (the FRF).

    Raises:
        RecordingError: a constant tilt, angles that are not finite, irregular sampling,
            a tilt column that is not the named stimulus.
    """
    name = recording.name
    if stimulus is not None:
        moves = stimulus.times[np.flatnonzero(np.diff(stimulus.angles) != 0)]
        if len(moves) and moves[0] >= recording.duration_s:
            raise StimulusError(
                f"{name}: the stimulus named starts moving at {moves[0]:g} s (its onset, "
                f"lead-in and lag), after the recording ends ({recording.duration_s:g} s); "
                "check --onset-s and --lag-s")
    if np.ptp(recording.tilt) == 0:
        raise RecordingError(f"{name}: the tilt is constant: there is no stimulus, so the "
                             "controller's parameters cannot be identified from it")
    bad = ~np.isfinite(recording.theta).all(axis=1) | ~np.isfinite(recording.tilt)
    if bad.any():
        first = int(np.argmax(bad))
        raise RecordingError(f"{name}: angles are not finite (NaN or ∞) from sample {first} "
                             f"(t = {recording.time[first]:g} s) in {int(bad.sum())} samples; "
                             "a simulated body that fell stops there: cut the recording")
    if not recording.evenly_sampled():
        raise RecordingError(f"{name}: samples are not evenly spaced in time")
    notices: list[str] = list(recording.notices)
    hint = None
    if stimulus is not None:
        try:
            check_recorded_tilt(recording.time, recording.tilt, stimulus, name)
        except StimulusError as error:  # a wrong time column shows as a wrong stimulus
            hint = sample_rate_hint(recording.time, recording.tilt, name)
            if hint is None:
                raise
            raise StimulusError(f"{error}; and {hint.removeprefix(name + ': ')}") from None
    else:
        stimulus = recognise_prts(recording.time, recording.tilt)
        # a PRTS of 0.25 s states at the stated rate says the time column is right; a
        # tilt that is no PRTS here, or one of other states, may be a PRTS of 0.25 s
        # states at another rate: a wrong time column
        if stimulus is None or not any(
                abs(stimulus.period_s - states * PRTS_STATE_S) < 1e-9
                for states in PRTS_REGISTERS):
            found = likely_sample_rate(recording.time, recording.tilt)
            if found is not None and stimulus is not None and _lab_states(stimulus):
                # states a lab runs at the stated rate are as likely as 0.25 s states at
                # another rate: the samples alone cannot tell, so say both
                hint = found.alternative(name, stimulus.description)
            elif found is not None:
                hint = found.hint(name)
            notices += [] if hint is None else [hint]
        if stimulus is not None:
            notices.append(f"{name}: the tilt is a {stimulus.description}; the exact profile "
                           "is used (samples miss its corners)")
        elif (periodic := recognise_periodic(recording.time, recording.tilt)) is not None:
            stimulus, found = periodic
            notices.append(f"{name}: the tilt is a {stimulus.description}; the analysis "
                           "spans the steady cycles (level stretches and any fade left out)")
            if found.distortion_note() is not None:
                notices.append(f"{name}: {found.distortion_note()}")
            notices += _motion_left_out(recording, found)
        else:
            stimulus = tilt_from_array(recording.time, recording.tilt, description=name)
            notices.append(f"{name}: the tilt is neither a PRTS at the rate its time "
                           "column gives nor a periodic tilt repeated twice or more; it is "
                           "interpolated linearly between samples (name the stimulus to use "
                           "its exact profile)")
    original = recording.sample_rate_hz
    _check_clock(recording, stimulus, original if rate_hz is None else rate_hz)
    why = ""
    if rate_hz is None and stimulus.period_s is not None:
        # the analysis at the recording's own rate needs whole cycles of samples: at a
        # headset's 89.53 Hz a 20 s cycle is 1790.7; the nearest rate above that holds one
        if not _whole_samples(stimulus.period_s, original):
            samples = math.ceil(stimulus.period_s * original)
            rate_hz = samples / stimulus.period_s
            why = (f" (so that a stimulus cycle of {stimulus.period_s:g} s is a whole "
                   f"{samples} samples)")
    resampled = recording if rate_hz is None else recording.resampled(rate_hz)
    if resampled is not recording:
        notices.append(f"{name}: resampled from {original:.4g} Hz to {rate_hz:.6g} Hz "
                       f"by linear interpolation{why}")
    # the model runs exactly as long as the recording: a stimulus that ends before it
    # (a level tail) is held, one that ends after it (a shorter recording) is cut
    stimulus = stimulus.spanning(resampled.duration_s)
    if stimulus.period_s is not None:
        # a named or recognised PRTS: the tilt is its exact profile at the samples (a
        # tilt column's noise, a sensor's or two platform markers', stays out of the
        # stimulus-locked sway and the network's inputs)
        exact = stimulus.angle(resampled.time)
        if not np.array_equal(exact, resampled.tilt):
            resampled = replace(resampled, tilt=exact)
    return PreparedTrial(resampled, stimulus, tuple(notices), original, rate_hint=hint)


#: s, a lab's PRTS states last a whole number of these; a state found within
#: :data:`CLOCK_SHARE` of one says the recording's clock is off by that share.
ROUND_STATE_S = 0.05
CLOCK_SHARE = 0.02


def _check_clock(recording: Recording, stimulus: TiltProfile, rate_hz: float) -> None:
    """Refuse a PRTS whose cycle is not a whole number of samples at ``rate_hz`` because
    its states, by the recording's clock, last a hair off a round time (0.2487 s for
    0.25 s): the clock (a time column, or ``--sample-rate-hz``) is off by that share, and
    the message gives the rate the states say."""
    period, states = stimulus.period_s, stimulus.states
    if period is None or states is None or _whole_samples(period, rate_hz):
        return
    state = period / states
    nearest = round(state / ROUND_STATE_S) * ROUND_STATE_S
    share = state / nearest - 1.0 if nearest > 0 else math.inf
    if not 1e-6 < abs(share) <= CLOCK_SHARE:
        return
    rate = recording.sample_rate_hz
    true_rate = rate * state / nearest
    raise RecordingError(
        f"{recording.name}: the PRTS's states last {state:.5g} s by the recording's clock "
        f"({rate:.6g} Hz), a cycle of {period:.5g} s that is not a whole number of samples "
        f"at {rate_hz:g} Hz; a lab's states last a round time ({nearest:g} s), so the clock "
        f"is {100 * abs(share):.2g} % {'slow' if share > 0 else 'fast'}: the samples come "
        f"at {true_rate:.6g} Hz (--sample-rate-hz {true_rate:.6g}; or leave "
        "--sample-rate-hz out where the time column's stamps are right)")


def _whole_samples(period_s: float, rate_hz: float) -> bool:
    """Whether a stimulus cycle of ``period_s`` is a whole number of samples at
    ``rate_hz`` (what the cycle averages need)."""
    samples = period_s * rate_hz
    return abs(samples - round(samples)) <= 1e-6 * samples


#: Motion outside the steady cycles longer than this many cycles is said (a fade is
#: shorter), s per cycle.
_LEFT_OUT_CYCLES = 1.5
#: A tilt that holds one value this long within the motion is a drop-out, s.
_HELD_S = 0.2


def _motion_left_out(recording: Recording, found) -> list[str]:
    """Notices of the motion a periodic tilt's analysis leaves out beyond its fades
    (``found``: :class:`~posture_id.simulation.periodic.PeriodicTilt`): where the tilt
    stops repeating its cycle, and a stretch where the tilt column holds one value within
    the motion (a sensor's drop-out)."""
    name, period = recording.name, found.period_s
    end = found.start_s + found.cycles * period
    before, after = found.start_s - found.moving_from_s, found.moving_until_s - end
    said = []
    t, tilt = recording.time, recording.tilt
    inside = (t >= found.moving_from_s) & (t <= found.moving_until_s)
    same = np.concatenate([[False], np.diff(tilt) == 0]) & inside
    starts, stops = true_runs(same)
    held = [(int(a) - 1, int(b) - 1) for a, b in zip(starts, stops, strict=True)
            if t[int(b) - 1] - t[int(a) - 1] >= _HELD_S]
    for a, b in held[:3]:
        said.append(f"{name}: the tilt holds still at {np.degrees(tilt[a]):.4g}° from "
                    f"{t[a]:.2f} to {t[b]:.2f} s within the platform's motion (a sensor's "
                    "drop-out?)")
    if max(before, after) > _LEFT_OUT_CYCLES * period or held:
        parts = [f"{found.moving_from_s:.2f}–{found.start_s:.2f} s" if before > 0.05 else "",
                 f"{end:.2f}–{found.moving_until_s:.2f} s" if after > 0.05 else ""]
        said.append(f"{name}: the tilt repeats its cycle from {found.start_s:.2f} to {end:.2f} "
                    f"s only ({found.cycles} cycles): the motion at "
                    f"{' and '.join(p for p in parts if p)} does not repeat it and is left out "
                    "(a fade, a drop-out, another stimulus)")
    return said


def _lab_states(stimulus: TiltProfile) -> bool:
    """A periodic stimulus whose cycle is a PRTS of states lasting as long as a lab's
    (:data:`~posture_id.simulation.stimulus.LAB_STATE_RANGE_S`, rounding aside)."""
    low, high = LAB_STATE_RANGE_S
    return stimulus.period_s is not None and any(
        low - 1e-6 <= stimulus.period_s / states <= high + 1e-6 for states in PRTS_REGISTERS)
