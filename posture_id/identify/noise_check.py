"""Does a model explain a recording as well as the recording's own noise allows?

A model that is right leaves a residual that is the recording's noise; a wrong class, a
fit stuck in a local minimum or a parameter pinned at a bound leaves more. The noise is
estimated from the recording itself, in the way that suits its stimulus:

- **locked** (a periodic stimulus, at least one whole cycle): the residual's
  stimulus-locked harmonics (recorded minus model: the DFT of its drift-free cycle
  average at the stimulated frequencies up to 2 Hz) divided by the noise level at each.
  With C ≥ 2 cycles the noise level is the spread of the residual's harmonics from cycle
  to cycle (the variance of their mean, pooled over the neighbouring harmonics): whatever
  differs between cycles is not locked to the stimulus, while a deterministic response,
  the dead-band's even harmonics included, repeats in every cycle and never counts as
  noise. With one cycle it is the power at the neighbouring harmonics the stimulus leaves
  empty, in the recording or in the residual, whichever is smaller (the recording's also
  holds the body's transient from its start, which a right model shares). Sway of the
  subject's own, drift and sensor noise are all "noise" here, so a people-like recording
  whose sway is mostly not locked to the stimulus is judged as fairly as a clean one. A
  right model leaves an RMS of about 1.
- **raw** (any other stimulus): the residual's SD against the white sensor noise
  estimated from the recording's third differences
  (:func:`~posture_id.uncertainty.noise.sensor_noise_deg`). Sway of the subject's own is
  not told apart here, so a people-like recording without a periodic stimulus is judged
  strictly.

:data:`NOISE_RATIO_LIMIT` is where "as well as the noise allows" ends: the hybrid accepts
its short route up to it (docs/identify.md). The trust verdict asks something else: is the
answer close to the recording? A model can be statistically distinguishable from the
truth and still close to it (a clean recording shows a 3 % error as many times its
noise), and on a noisy recording a far answer can hide inside the noise. ``relative``,
the residual against the recorded stimulus-locked body sway itself, answers it:
:attr:`NoiseCheck.acceptable` allows up to :data:`CLOSE_ENOUGH` of it (measured on the
benchmarks: docs/identify.md), and ``noise_relative`` says how much of that the noise
alone would leave, so that a recording too noisy to check an answer says so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from posture_id.choices import Choice
from posture_id.frf.cycles import cycle_average
from posture_id.frf.locked import LockedOptions, LockedProjection, noise_levels
from posture_id.trials import PreparedTrial
from posture_id.uncertainty.noise import sensor_noise_deg


class Basis(Choice):
    """What sway a residual is measured on: the stimulus-locked cycle average, or every
    sample."""

    LOCKED = "locked"
    RAW = "raw"


__all__ = ["NoiseCheck", "noise_check", "harmonic_noise", "unweighted_projection",
           "NOISE_RATIO_LIMIT", "CLOSE_ENOUGH"]

#: The residual's RMS in units of the recording's noise up to which a model is said to
#: explain the recording as well as its noise allows.
NOISE_RATIO_LIMIT = 1.5
#: The relative residual (of the locked sway, or the raw one) a model may leave beyond the
#: noise and still count as close: the benchmarks' line between right and far (an E_rel of
#: 10 %).
CLOSE_ENOUGH = 0.10
#: A noise estimate below this (degrees) is raised to it: quantisation and rounding of a
#: recording's file leave at least this much.
_NOISE_FLOOR_DEG = 1e-4
#: Harmonics on each side pooled into one harmonic's cycle-to-cycle noise level.
_NEIGHBOURS = 3


@dataclass(frozen=True)
class NoiseCheck:
    """The residual of a model against the noise estimated from the recording.

    Attributes:
        ratio: the residual's RMS in units of the recording's noise (inf for a model that
            falls). basis: "locked" or "raw" (module docstring). noise_deg: for "raw", the
            estimated sensor noise SD (degrees); for "locked", the median noise level of
            the compared harmonics (degrees, DFT ÷ P). limit: :data:`NOISE_RATIO_LIMIT`.
        relative: the residual's RMS against the recorded sway's (its compared locked
            harmonics, or the raw sway about its mean), of the whole-body COM sway when
            it was given (else of the segments); inf for a model that falls.
        noise_relative: the ``relative`` the recording's noise alone leaves (the noise in
            the cycle average against the locked sway: from how the cycles differ, or
            with one cycle from the harmonics the stimulus leaves empty; NaN for a
            stimulus that is not periodic).
    """

    ratio: float
    basis: Basis
    noise_deg: float
    limit: float = NOISE_RATIO_LIMIT
    relative: float = math.nan
    noise_relative: float = math.nan

    def __post_init__(self) -> None:
        object.__setattr__(self, "basis", Basis(self.basis))

    @property
    def consistent(self) -> bool:
        """The residual is no larger than the recording's noise allows."""
        return self.ratio <= self.limit

    @property
    def unchecked(self) -> bool:
        """The residual is what the noise leaves, and the noise alone leaves more than
        :data:`CLOSE_ENOUGH` of the recorded locked sway: the recording cannot tell this
        answer from one a little off (False when that share cannot be estimated)."""
        return self.consistent and self.noise_relative > CLOSE_ENOUGH

    @property
    def acceptable(self) -> bool:
        """Close to the recording: the residual is at most :data:`CLOSE_ENOUGH` of the
        recorded (locked) sway."""
        return self.relative <= CLOSE_ENOUGH

    def weighting_note(self) -> str:
        """Why the ratio and the shares seem to disagree, or "": the ratio weighs each
        compared harmonic by its own noise and the shares do not, so a residual at
        harmonics quieter (or noisier) than the rest is beyond (within) the noise by the
        ratio, which decides, while its amplitude is within (beyond) what the noise leaves."""
        if not (math.isfinite(self.ratio) and math.isfinite(self.noise_relative)
                and self.noise_relative > 0):
            return ""
        unweighted = self.relative / self.noise_relative
        if self.ratio > self.limit and unweighted <= 1.0:
            return ("by amplitude it is within what the noise leaves, but it lies at the "
                    "harmonics where the noise is small: beyond the noise there")
        if self.ratio <= 1.0 and unweighted > self.limit:
            return ("by amplitude it is beyond what the noise leaves, but it lies at the "
                    "harmonics where the noise is large: within the noise there")
        return ""

    def sentence(self) -> str:
        """The residual in one clause: first the measure that decides whether it is within
        the noise (its RMS in units of the noise at each compared harmonic, against
        :attr:`limit`), then its share of the recorded sway (which decides whether it is
        close, against :data:`CLOSE_ENOUGH`), with the share the noise alone leaves, and
        :meth:`weighting_note` where the two seem to disagree."""
        if not math.isfinite(self.ratio):
            return "residual without end: the model falls in re-simulation"
        what = ("stimulus-locked residual" if self.basis is Basis.LOCKED else "residual")
        verdict = (f"within the {self.limit:g}× the noise allows" if self.consistent
                   else f"beyond the {self.limit:g}× the noise allows")
        close = ("a close answer's" if self.acceptable
                 else f"more than the {100 * CLOSE_ENOUGH:g} % of a close answer")
        noisy = ""
        if math.isfinite(self.noise_relative):
            noisy = (f"; the noise alone leaves about {100 * self.noise_relative:.0f} %"
                     + (", too much to check an answer to "
                        f"{100 * CLOSE_ENOUGH:g} %" if self.noise_relative > CLOSE_ENOUGH
                        else ""))
        note = self.weighting_note()
        return (f"{what} of {self.ratio:.2f}× the recording's own noise ({verdict}), "
                f"{100 * self.relative:.1f} % of the recorded {self.basis} sway ({close})"
                f"{noisy}" + (f"; {note}" if note else ""))

    def to_dict(self) -> dict:
        return {"ratio": self.ratio if math.isfinite(self.ratio) else None,
                "basis": self.basis.value, "noise_deg": self.noise_deg, "limit": self.limit,
                "relative": self.relative if math.isfinite(self.relative) else None,
                "noise_relative": (self.noise_relative
                                   if math.isfinite(self.noise_relative) else None),
                "acceptable": self.acceptable,
                "consistent": self.consistent}


def noise_check(trial: PreparedTrial, model_theta: np.ndarray,
                limit: float = NOISE_RATIO_LIMIT,
                body_sway: tuple[np.ndarray, np.ndarray] | None = None,
                projection: LockedProjection | None = None) -> NoiseCheck:
    """Judge a model's sway ``model_theta`` (S, N) rad against ``trial``'s recording (the
    trial the model was fitted on: with a fitted offset, the shifted one).

    Args:
        body_sway: (recorded, model) whole-body COM sway α_BS (S,) rad: when given,
            ``relative`` is measured on it (the sway E_rel judges), else on the segments.
        projection: the trial's unweighted locked projection, when the caller has it
            (default: made here).
    """
    recorded = trial.recording.theta
    model_theta = np.asarray(model_theta, dtype=float)[: len(recorded)]
    residual = np.degrees(recorded - model_theta)
    if projection is None:
        projection = unweighted_projection(trial)
    if projection is not None and projection.cycles < 2 and projection.excited.all():
        projection = None  # one cycle of a tilt that leaves no harmonic empty: no noise there
    if projection is not None:
        finite = bool(np.all(np.isfinite(residual)))
        # the noise: with C ≥ 2 cycles what differs between them (in the recording, a
        # transient of the body's own repeats in the model and is no noise; in the
        # residual, a model whose sway is not periodic adds its own); with one cycle the
        # power at the harmonics the stimulus leaves empty (in the recording, the body's
        # transient from its start is there too, and a right model shares it; in the
        # residual, a wrong model adds its own). Each only ever adds: the smaller holds
        variance = harmonic_noise(projection, np.degrees(recorded))
        if finite:
            variance = np.minimum(variance, harmonic_noise(projection, residual))
        ratio = (float(np.sqrt(np.mean(np.abs(projection.spectrum(residual)) ** 2
                                       / variance))) if finite else math.inf)
        noise = float(np.median(np.sqrt(variance / 2)))
        theirs = np.degrees(recorded)
        ours = residual
        if body_sway is not None:
            theirs = np.degrees(np.asarray(body_sway[0], dtype=float))[:, None]
            model_sway = np.degrees(np.asarray(body_sway[1], dtype=float))[: len(theirs)]
            ours = theirs - model_sway[:, None]
        locked_power = np.sum(np.abs(projection.spectrum(theirs)) ** 2)
        relative = (float(np.sqrt(np.sum(np.abs(projection.spectrum(ours)) ** 2)
                                  / locked_power)) if finite else math.inf)
        noise_power = harmonic_noise(projection, theirs)
        if projection.cycles < 2 and finite:  # the start's transient: as above
            noise_power = np.minimum(noise_power, harmonic_noise(projection, ours))
        noise_relative = float(np.sqrt(np.sum(noise_power) / locked_power))
        return NoiseCheck(ratio, Basis.LOCKED, noise, limit, relative, noise_relative)
    noise = max(float(sensor_noise_deg(recorded)), _NOISE_FLOOR_DEG)
    if not np.all(np.isfinite(residual)):
        return NoiseCheck(math.inf, Basis.RAW, noise, limit, math.inf)
    spread = np.degrees(recorded - recorded.mean(axis=0))
    relative = float(np.sqrt(np.sum(residual**2) / np.sum(spread**2)))
    return NoiseCheck(float(np.sqrt(np.mean(residual**2))) / noise, Basis.RAW, noise, limit,
                      relative)


def unweighted_projection(trial: PreparedTrial) -> LockedProjection | None:
    """The trial's unweighted locked projection, the one an answer is judged by
    (:meth:`~posture_id.frf.locked.LockedProjection.for_periodic_trial`; None where there
    is nothing locked to compare)."""
    return LockedProjection.for_periodic_trial(trial, LockedOptions(weighted=False))


def harmonic_noise(projection: LockedProjection, signal_deg: np.ndarray) -> np.ndarray:
    """(K, N) E|X|² of the noise in each compared harmonic of the cycle average of
    ``signal_deg`` (S, N) degrees (DFT ÷ P): from how its cycles differ (C ≥ 2), else from
    the harmonics the stimulus leaves empty (module docstring)."""
    spread = _between_cycles if projection.cycles >= 2 else _empty_harmonics
    return spread(projection, np.asarray(signal_deg, dtype=float))


def _empty_harmonics(projection: LockedProjection, recorded: np.ndarray) -> np.ndarray:
    """(K, N) the noise power E|X|² (DFT ÷ P, degrees²) at the compared harmonics of one
    cycle, from the mean power at the nearest harmonics the stimulus leaves empty,
    floored at :data:`_NOISE_FLOOR_DEG`. ``recorded``: (S, N) degrees."""
    power = np.abs(projection.all_harmonics(recorded)) ** 2
    sd = noise_levels(power, projection.excited, projection.harmonics - 1,
                      LockedOptions().neighbours)
    return np.maximum(2 * sd**2, _NOISE_FLOOR_DEG**2 / projection.period)  # σ of each part


def _between_cycles(projection: LockedProjection, recorded: np.ndarray) -> np.ndarray:
    """(K, N) the variance of the cycle-averaged compared harmonics that the recording's
    noise leaves (DFT ÷ P, degrees²), from how its cycles (C ≥ 2) differ from their mean:
    pooled over ±:data:`_NEIGHBOURS` harmonics, floored at :data:`_NOISE_FLOOR_DEG`.
    ``recorded``: (S, N) degrees."""
    p, c = projection.period, projection.cycles
    average = cycle_average(recorded[projection.start :], p, 0, projection.drift_order)
    spectra = np.fft.rfft(average.cycles, axis=1)[:, 1 : p // 2 + 1] / p  # (C, P/2, N)
    spread = (np.abs(spectra - spectra.mean(axis=0)) ** 2).sum(axis=0) / (c * (c - 1))
    kernel = np.ones(2 * _NEIGHBOURS + 1)
    counts = np.convolve(np.ones(len(spread)), kernel, mode="same")
    pooled = np.stack([np.convolve(spread[:, j], kernel, mode="same") / counts
                       for j in range(spread.shape[1])], axis=1)
    return np.maximum(pooled[projection.harmonics - 1], _NOISE_FLOOR_DEG**2 / (p * c))
