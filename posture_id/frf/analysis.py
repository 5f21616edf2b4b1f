"""The FRF of a recording: its segments and, with a body, its whole-body COM sway."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from posture_id.bodies.body import Body
from posture_id.errors import RecordingError
from posture_id.frf.response import FrequencyResponse, FrfOptions, frequency_response_arrays
from posture_id.trials import PreparedTrial

__all__ = ["frequency_response"]


def frequency_response(trial: PreparedTrial, body: Body | None = None,
                       options: FrfOptions | None = None, period_s: float | None = None
                       ) -> FrequencyResponse:
    """FRFs of every segment angle (and of the body COM sway α_BS when ``body`` is given)
    relative to the recording's tilt.

    Args:
        trial: the recording at its own rate (``prepare_trial(rec, stimulus, rate_hz=None)``)
            with its stimulus: named, or recognised from a PRTS tilt; the analysis starts
            where the stimulus's periodic part does (after a lead-in and the platform's lag).
        body: The body recorded; its segments must be the recording's (None: the TIP).
        options: The analysis's options (:class:`FrfOptions`; None: the defaults).
        period_s: one stimulus cycle, s (default: the stimulus's).
    """
    recording, stimulus = trial.recording, trial.stimulus
    period_s = period_s or stimulus.period_s
    if period_s is None:
        hint = trial.rate_hint
        raise RecordingError(f"{trial.name}: the tilt is not a PRTS of 242 or 80 states "
                             "and does not repeat for two whole cycles or more while the "
                             "platform moves (too short for its lowest frequency, or not "
                             "periodic); give the stimulus's period (period_s, --period-s)"
                             + ("" if hint is None
                                else f"; and {hint.removeprefix(trial.name + ': ')}"))
    start = int(np.searchsorted(recording.time, stimulus.periodic_from_s - 1e-9))
    own_period = stimulus.period_s is not None and abs(period_s - stimulus.period_s) < 1e-9
    stop = len(recording.time)
    if own_period and stimulus.cycles is not None:  # level again after its steady cycles
        stop = min(stop, start + stimulus.cycles * int(round(period_s
                                                             * recording.sample_rate_hz)))
    _check_period(trial, start, stop, period_s)
    channels = tuple(recording.segments)
    outputs = recording.theta[start:stop]
    if body is not None:
        trial.require_segments(body.segment_names)
        outputs = np.column_stack([outputs, body.com_angles(outputs)[:, 0]])
        channels += ("body COM",)
    response = frequency_response_arrays(recording.tilt[start:stop], outputs,
                                         recording.sample_rate_hz, period_s, channels, options,
                                         trial.name,
                                         stimulus.frequencies_hz if own_period else None)
    return replace(response, recording_source=recording.source)


#: The tilt's change from one cycle to the next, against its own RMS, above which a
#: period is not the tilt's.
PERIOD_MISMATCH = 0.1


def _check_period(trial: PreparedTrial, start: int, stop: int, period_s: float) -> None:
    """Refuse a period the tilt does not repeat with (with two whole cycles or more to
    compare): an FRF over cycles that are not the stimulus's is meaningless."""
    rec = trial.recording
    p = int(round(period_s * rec.sample_rate_hz))
    tilt = rec.tilt[start:stop]
    cycles = len(tilt) // p if p > 0 else 0
    if cycles < 2:
        return
    whole = tilt[: cycles * p].reshape(cycles, p)
    change = float(np.sqrt(np.mean((whole[1:] - whole[:-1]) ** 2)))
    size = float(np.sqrt(np.mean((whole - whole.mean()) ** 2)))
    if size > 0 and change > PERIOD_MISMATCH * size:
        raise RecordingError(
            f"{trial.name}: the tilt does not repeat every {period_s:g} s (from one cycle to "
            f"the next it changes by {100 * change / size:.0f} % of its RMS): give the "
            "stimulus's own period (--period-s), or name the PRTS")
