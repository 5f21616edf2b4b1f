"""Recordings on their way into the fit: checked, and brought to the model's rate."""

from __future__ import annotations

import math

import numpy as np

from posture_id.errors import RecordingError
from posture_id.fitting.options import FitOptions
from posture_id.recording import Recording

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
    steps = np.diff(recording.time)
    median = float(np.median(steps))
    if np.any(np.abs(steps - median) > 0.01 * median):
        raise RecordingError(f"{source}: samples are not evenly spaced in time")
    duration = float(recording.time[-1])
    if duration < options.min_duration_s - 1e-9:
        raise RecordingError(
            f"{source}: the recording lasts {duration:.2f} s, shorter than one PRTS cycle "
            f"({options.min_duration_s:g} s)"
        )
    rate = 1.0 / median
    if abs(rate - rate_hz) > 1e-6 * rate_hz:
        n = int(math.floor(duration * rate_hz + 1e-9)) + 1
        t = np.arange(n) / rate_hz
        theta = np.stack([np.interp(t, recording.time, recording.theta[:, j])
                          for j in range(recording.theta.shape[1])], axis=1)
        recording = Recording(t, np.interp(t, recording.time, recording.tilt), theta,
                              recording.segments)
        notices.append(f"{source}: resampled from {rate:.4g} Hz to {rate_hz:g} Hz "
                       "by linear interpolation")
    return recording, notices
