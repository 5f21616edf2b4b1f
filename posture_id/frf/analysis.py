"""The FRF of a recording: its segments and, with a body, its whole-body COM sway."""

from __future__ import annotations

import numpy as np

from posture_id.bodies.body import Body
from posture_id.errors import RecordingError
from posture_id.frf.response import FrequencyResponse, FrfOptions, frequency_response_arrays
from posture_id.recording import Recording
from posture_id.simulation.stimulus import (
    TiltProfile,
    check_recorded_tilt,
    recognise_prts,
    sample_rate_hint,
)

__all__ = ["frequency_response"]


def frequency_response(recording: Recording, body: Body | None = None,
                       options: FrfOptions | None = None, period_s: float | None = None,
                       source: str = "recording", stimulus: TiltProfile | None = None
                       ) -> FrequencyResponse:
    """FRFs of every segment angle (and of the body COM sway α_BS when ``body`` is given)
    relative to the recording's tilt.

    Args:
        recording: evenly sampled, starting with the stimulus. body: its segments must be
            the recording's. options: :class:`FrfOptions`. period_s: one stimulus cycle, s
            (default: the named stimulus's, or recognised from a PRTS tilt).
        source: the recording's name in messages.
        stimulus: the stimulus as the lab ran it (:func:`~posture_id.simulation.prts`):
            the recording's tilt is checked against it and the analysis starts where its
            periodic part does (after a lead-in and the platform's lag).
    """
    if not recording.evenly_sampled():
        raise RecordingError(f"{source}: the samples are not evenly spaced in time")
    start = 0
    if stimulus is not None:
        check_recorded_tilt(recording.time, recording.tilt, stimulus, source)
        period_s = period_s or stimulus.period_s
        start = int(np.searchsorted(recording.time, stimulus.periodic_from_s - 1e-9))
    if period_s is None:
        stimulus = recognise_prts(recording.time, recording.tilt)
        if stimulus is None or stimulus.period_s is None:
            hint = sample_rate_hint(recording.time, recording.tilt, source)
            raise RecordingError(f"{source}: the tilt is not a PRTS of 242 or 80 states; "
                                 "give the stimulus's period (period_s, --period-s)"
                                 + ("" if hint is None
                                    else f"; and {hint.removeprefix(source + ': ')}"))
        period_s = stimulus.period_s
    channels = tuple(recording.segments)
    outputs = recording.theta[start:]
    if body is not None:
        recording.check_segments(body.segment_names, source)
        outputs = np.column_stack([outputs, body.com_angles(recording.theta[start:])[:, 0]])
        channels += ("body COM",)
    return frequency_response_arrays(recording.tilt[start:], outputs, recording.sample_rate_hz,
                                     period_s, channels, options, source)
