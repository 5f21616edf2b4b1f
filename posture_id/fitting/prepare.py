"""Recordings on their way into the fit: checked, and brought to the model's rate."""

from __future__ import annotations

import numpy as np

from posture_id.errors import RecordingError
from posture_id.fitting.options import FitOptions
from posture_id.recording import Recording
from posture_id.simulation.stimulus import (
    TiltProfile,
    check_recorded_tilt,
    recognise_prts,
    sample_rate_hint,
    tilt_from_array,
)

#: Shortest recording of a tilt that is not periodic, s.
MIN_ANY_TILT_S = 20.0

__all__ = ["prepare_recording", "MIN_ANY_TILT_S"]


def prepare_recording(recording: Recording, source: str, options: FitOptions,
                      stimulus: TiltProfile | None = None
                      ) -> tuple[Recording, TiltProfile, list[str]]:
    """Check a recording, find its stimulus, and bring it to the model's output rate
    (linear interpolation, with a notice).

    Args:
        stimulus: the stimulus as the lab ran it; the recording's tilt must follow it.
            Default: a PRTS recognised in the tilt, else the tilt itself, interpolated.

    Returns:
        (the recording at the model's rate, its stimulus, notices).

    Raises:
        RecordingError: a constant tilt, irregular sampling, a tilt that is not the named
            stimulus, or shorter than one whole cycle of the stimulus.
    """
    rate_hz = options.simulation.sample_rate_hz
    notices = []
    if np.ptp(recording.tilt) == 0:
        raise RecordingError(f"{source}: the tilt is constant: there is no stimulus, so the "
                             "controller's parameters cannot be identified from it")
    bad = ~np.isfinite(recording.theta).all(axis=1) | ~np.isfinite(recording.tilt)
    if bad.any():
        first = int(np.argmax(bad))
        raise RecordingError(f"{source}: angles are not finite (NaN or ∞) from sample {first} "
                             f"(t = {recording.time[first]:g} s) in {int(bad.sum())} samples; "
                             "a simulated body that fell stops there: cut the recording")
    if not recording.evenly_sampled():
        raise RecordingError(f"{source}: samples are not evenly spaced in time")
    hint = sample_rate_hint(recording.time, recording.tilt, source)
    if hint is not None:
        notices.append(hint)
    if stimulus is not None:
        check_recorded_tilt(recording.time, recording.tilt, stimulus, source)
    else:
        stimulus = recognise_prts(recording.time, recording.tilt)
        if stimulus is not None:
            notices.append(f"{source}: the tilt is a {stimulus.description}; the exact profile "
                           "is used (samples miss its corners)")
        else:
            stimulus = tilt_from_array(recording.time, recording.tilt, description=source)
            notices.append(f"{source}: the tilt is not a PRTS from the start of its cycle; it "
                           "is interpolated linearly between samples (name the stimulus to "
                           "use its exact profile)")
    if options.min_duration_s is not None:
        needed = options.min_duration_s
        what = f"the least duration asked for ({needed:g} s)"
    elif stimulus.whole_cycles_s is not None:
        needed = stimulus.whole_cycles_s
        what = f"one whole cycle of its stimulus ({stimulus.description}: {needed:g} s)"
    else:
        needed = MIN_ANY_TILT_S
        what = f"{needed:g} s (the least for a tilt that is not periodic)"
    if recording.duration_s < needed - 1e-9:
        raise RecordingError(
            f"{source}: the recording lasts {recording.duration_s:.2f} s, shorter than {what}")
    rate = recording.sample_rate_hz
    resampled = recording.resampled(rate_hz)
    if resampled is not recording:
        notices.append(f"{source}: resampled from {rate:.4g} Hz to {rate_hz:g} Hz "
                       "by linear interpolation")
    return resampled, stimulus, notices
