"""Recordings on their way into the fit: checked, and brought to the model's rate."""

from __future__ import annotations

import numpy as np

from posture_id.errors import RecordingError
from posture_id.fitting.options import FitOptions
from posture_id.recording import Recording
from posture_id.simulation.stimulus import sample_rate_hint

__all__ = ["prepare_recording"]


def prepare_recording(recording: Recording, source: str, options: FitOptions
                      ) -> tuple[Recording, list[str]]:
    """Check a recording and bring it to the model's output rate (linear interpolation,
    with a notice).

    Raises:
        RecordingError: irregular sampling or shorter than ``min_duration_s``.
    """
    rate_hz = options.simulation.sample_rate_hz
    notices = []
    if np.ptp(recording.tilt) == 0:
        raise RecordingError(f"{source}: the tilt is constant: there is no stimulus, so the "
                             "controller's parameters cannot be identified from it")
    if not recording.evenly_sampled():
        raise RecordingError(f"{source}: samples are not evenly spaced in time")
    if recording.duration_s < options.min_duration_s - 1e-9:
        raise RecordingError(
            f"{source}: the recording lasts {recording.duration_s:.2f} s, shorter than one "
            f"PRTS cycle ({options.min_duration_s:g} s)"
        )
    hint = sample_rate_hint(recording.time, recording.tilt, source)
    if hint is not None:
        notices.append(hint)
    rate = recording.sample_rate_hz
    resampled = recording.resampled(rate_hz)
    if resampled is not recording:
        notices.append(f"{source}: resampled from {rate:.4g} Hz to {rate_hz:g} Hz "
                       "by linear interpolation")
    return resampled, notices
