"""Could one body under one controller have made this recording? Mistakes the sway shows.

An identifier answers whatever it is given. These checks look for recordings that no
answer can be right about, each from the recording (and, for one, the identified model's
re-simulation) alone, each with a statistic in units of the recording's own noise:

- **the tilt's sign** (:func:`tilt_sign`): in every DEC model of docs/model.md §5's prior the body
  COM follows the platform at low frequencies: the real part of its FRF relative to the
  tilt, at every stimulated harmonic below :data:`LOW_FREQUENCY_HZ`, is positive (its
  1st percentile 0.14–0.20 over 400 draws each of 1-, 2- and 3-segment bodies under both
  PRTSs: docs/identify.md, "Mistakes"), and their sum, each harmonic weighted by its
  noise, is what the check reads. A tilt column of the wrong sign (or a stimulus
  named with the wrong sign) turns it negative: doubted when the negative part stands
  :data:`TILT_SIGN_Z` noise SDs below zero.
- **a step in the angles** (:func:`angle_steps`): a marker that moved, a re-zeroed sensor.
  The body's angles are smooth (a second-order plant behind torques); a jump between two
  samples, estimated from straight lines fitted to :data:`STEP_WINDOW_S` of samples on each
  side, that stands :data:`STEP_Z` robust SDs (of the same estimate over the whole
  recording) above the rest and is at least :data:`STEP_MIN_DEG` is not sway.
- **control that changes within the recording** (:func:`control_change`): the residual
  of the identified model (recorded minus re-simulated; the body's start transient and
  the model's own nonlinearity repeat in both, so they cancel), its first cycles' mean
  against its last cycles' mean at the stimulated harmonics, in units of the same
  difference at the harmonics the stimulus leaves empty nearby (noise, drift and sway of
  the subject's own are there too, and change with the noise's level within the trial
  just as much): one controller gives a mean ratio near 1 (the stimulated harmonics
  below the first empty one are left out: their empty neighbours lie only above them,
  where the sway of the subject's own is weaker); gains that change halfway give
  a stimulus-locked difference. Doubted above :data:`CONTROL_CHANGE_RATIO`.

Each returns a :class:`Mistake` when it finds one, None when it does not or cannot look
(a stimulus that is not periodic, one cycle, no empty harmonics).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from posture_id.choices import Choice
from posture_id.frf.cycles import cycle_average
from posture_id.frf.locked import LockedProjection, noise_levels
from posture_id.identify.noise_check import harmonic_noise, unweighted_projection
from posture_id.trials import PreparedTrial

__all__ = ["Mistake", "find_mistakes", "tilt_sign", "angle_steps", "control_change",
           "LOW_FREQUENCY_HZ", "TILT_SIGN_Z", "STEP_WINDOW_S", "STEP_Z", "STEP_MIN_DEG",
           "CONTROL_CHANGE_RATIO"]

#: The stimulated harmonics the tilt-sign check reads lie below this, Hz.
LOW_FREQUENCY_HZ = 0.3
#: A low-frequency FRF this many noise SDs below zero is a tilt of the wrong sign.
TILT_SIGN_Z = 4.0
#: Samples on each side of a step, s (10 samples at 50 Hz).
STEP_WINDOW_S = 0.2
#: A jump this many robust SDs above the recording's own is a step.
STEP_Z = 10.0
#: A step smaller than this (degrees) is not reported: sway curvature and rounding.
STEP_MIN_DEG = 0.25
#: The residual's first-against-last-cycles difference at the stimulated harmonics, in
#: units of the same at the empty ones, above which control changed within the recording
#: (one controller: about 1; docs/identify.md, "Mistakes").
CONTROL_CHANGE_RATIO = 3.0
#: Empty harmonics on each side that set a stimulated harmonic's noise in the
#: control-change check.
_NEIGHBOURS = 6


class Check(Choice):
    """The checks that find a mistake in a recording."""

    TILT_SIGN = "tilt sign"
    ANGLE_STEP = "angle step"
    CONTROL_CHANGE = "control change"
    COLUMNS_EXCHANGED = "columns exchanged"
    ANOTHER_BODY = "another body"



@dataclass(frozen=True)
class Mistake:
    """A recording that the model cannot have produced.

    Attributes:
        check: which check found it (:class:`Check`).
        statistic: the check's statistic (module docstring); threshold: where it doubts.
        sentence: what was found, for the verdict.
    """

    check: Check
    statistic: float
    threshold: float
    sentence: str

    def __post_init__(self) -> None:
        object.__setattr__(self, "check", Check(self.check))

    def to_dict(self) -> dict:
        return {"check": self.check.value, "statistic": self.statistic,
                "threshold": self.threshold, "sentence": self.sentence}


def find_mistakes(trial: PreparedTrial, body, resimulated: np.ndarray | None,
                  projection: LockedProjection | None = None) -> tuple[Mistake, ...]:
    """Every mistake the checks find in ``trial`` (recorded for ``body``);
    ``resimulated``: (S, N) rad, the identified model's sway (None, or not finite: the
    control-change check reads the recording itself)."""
    if projection is None:
        projection = unweighted_projection(trial)
    found = [tilt_sign(trial, body, projection), *angle_steps(trial),
             control_change(trial, resimulated, projection)]
    return tuple(m for m in found if m is not None)


def tilt_sign(trial: PreparedTrial, body, projection: LockedProjection | None
              ) -> Mistake | None:
    """The body COM's low-frequency response against the tilt's sign (module docstring)."""
    if projection is None:
        return None
    rec = trial.recording
    low = projection.frequencies_hz < LOW_FREQUENCY_HZ
    if not low.any():
        return None
    com = np.degrees(body.com_angles(rec.theta)[:, :1])
    y = projection.spectrum(com)[low, 0]
    u = projection.spectrum(np.degrees(rec.tilt)[:, None])[low, 0]
    variance = harmonic_noise(projection, com)[low, 0]  # E|noise|² of each cycle-averaged Y
    # each harmonic weighted by 1/variance: the most telling sum of Re(Y·conj(U))
    cross = float(np.sum((y * np.conj(u)).real / variance))
    sd = float(np.sqrt(np.sum(np.abs(u) ** 2 / (2 * variance))))
    gain = cross / float(np.sum(np.abs(u) ** 2 / variance))
    z = cross / sd if sd > 0 else (-math.inf if cross < 0 else math.inf)
    if not z < -TILT_SIGN_Z:
        return None
    source = rec.source or {}
    suspects = ("is --forward-axis the other way round (now "
                f"{source.get('forward_axis')}), or the tilt's sign reversed?"
                if source.get("format") == "c3d"
                else "is the tilt column's or the stimulus's sign reversed?")
    return Mistake(Check.TILT_SIGN, z, -TILT_SIGN_Z, (
        f"the body sways against the tilt at low frequencies (real FRF {gain:.2f} below "
        f"{LOW_FREQUENCY_HZ:g} Hz, {abs(z):.1f} noise SDs below zero; every body balanced "
        f"by DEC follows it): {suspects}"))


def angle_steps(trial: PreparedTrial) -> list[Mistake]:
    """A step in any segment's angle (module docstring): one :class:`Mistake` per segment
    with one, at its largest step."""
    rec = trial.recording
    w = max(2, int(round(STEP_WINDOW_S * rec.sample_rate_hz)))
    if len(rec.time) < 4 * w:
        return []
    # the jump at the boundary between samples m + w − 1 and m + w: a straight line
    # through the w samples after it minus one through the w before, both at the boundary
    after = np.arange(w) + 0.5  # positions from the boundary, in samples
    centred = after - w / 2
    line = 1 / w - centred * (w / 2) / np.sum(centred**2)  # least squares line at 0
    weights = np.concatenate([-line[::-1], line])  # before (mirrored), then after
    found = []
    degrees = np.degrees(rec.theta)
    for j, name in enumerate(rec.segments):
        jump = np.correlate(degrees[:, j], weights, mode="valid")
        spread = 1.4826 * float(np.median(np.abs(jump - np.median(jump))))
        k = int(np.argmax(np.abs(jump)))
        size = float(jump[k])
        z = abs(size) / spread if spread > 0 else math.inf
        if z > STEP_Z and abs(size) >= STEP_MIN_DEG:
            t = float(rec.time[k + w - 1] + 0.5 / rec.sample_rate_hz)
            found.append(Mistake(Check.ANGLE_STEP, z, STEP_Z, (
                f"the {name} angle jumps by {size:+.2f}° at t = {t:.2f} s ({z:.0f}× the "
                "recording's sample-to-sample spread): a body does not move so; a marker "
                "that moved or a sensor re-zeroed?")))
    return found


def control_change(trial: PreparedTrial, resimulated: np.ndarray | None,
                   projection: LockedProjection | None) -> Mistake | None:
    """The residual's first cycles against its last ones (module docstring)."""
    if projection is None or projection.cycles < 2 or projection.excited.all():
        return None
    rec = trial.recording
    signal = rec.theta
    if resimulated is not None and np.all(np.isfinite(resimulated)):
        signal = rec.theta - np.asarray(resimulated)[: len(rec.theta)]
    p, c = projection.period, projection.cycles
    cycles = cycle_average(np.degrees(signal)[projection.start:], p, 0,
                           projection.drift_order).cycles  # (C, P, N)
    spectra = np.fft.rfft(cycles, axis=1)[:, 1 : p // 2 + 1] / p  # (C, P/2, N)
    half = c // 2
    difference = spectra[:half].mean(axis=0) - spectra[half:].mean(axis=0)  # (P/2, N)
    power = np.abs(difference) ** 2
    # harmonics with an empty one below them: the lowest stimulated ones have empty
    # neighbours only above, where the sway of the subject's own is weaker
    empty = np.flatnonzero(~projection.excited)
    rows = projection.harmonics - 1
    rows = rows[rows > empty[0]]
    if len(rows) == 0:
        return None
    sd = noise_levels(power, projection.excited, rows, _NEIGHBOURS)  # σ of each part
    expected = np.maximum(2 * sd**2, 1e-30)
    ratio = float(np.mean(power[rows] / expected))
    if not ratio > CONTROL_CHANGE_RATIO:
        return None
    return Mistake(Check.CONTROL_CHANGE, ratio, CONTROL_CHANGE_RATIO, (
        f"the response to the stimulus differs between the first {half} and the last "
        f"{c - half} cycles by {ratio:.1f}× what the recording's noise leaves (one "
        "controller gives about 1): did the subject's control change within the recording "
        "(fatigue, learning, another condition)? identify the parts separately"))
