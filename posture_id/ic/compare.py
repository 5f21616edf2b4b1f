"""Which model does the sway support, DEC or IC? (docs/model.md §8, comparison.)

Both models are fitted to the same recording: DEC by the locked least-squares fit, IC by
its FRF fit (:func:`~posture_id.ic.fit.fit_ic`). Then both are judged on the same numbers:
the drift-free cycle average of the body COM sway at **every** harmonic of the stimulus
cycle up to 2 Hz, the stimulated ones and the others (where DEC's dead-band can answer and
a linear model cannot), each divided by its noise level (estimated at the nearest
harmonics the stimulus leaves empty, the harmonic itself left out; the χ² corrected for
the estimate's own scatter, ν/(ν − 2) with ν its degrees of freedom). For each model:

- χ², the weighted residual's squared norm, and the Bayesian information criterion
  BIC = χ² + k·ln n (k the model's identified parameters, n the real numbers compared);
- with three or more cycles, the prediction of a held-out cycle: both models fitted again
  on every cycle but the last, their sway on the last cycle against the recorded one
  (χ² per degree of freedom, the single cycle's noise being √C times the average's).

**[decision]** A model is preferred when the other does not explain the locked sway within
its noise (χ² beyond its 99th percentile), its BIC is lower by more than
:data:`BIC_MARGIN` (10: "very strong" evidence on Kass & Raftery's scale) and the held-out
cycle, where there is one, does not favour the other (its χ² per degree of freedom lower
by more than :data:`HELD_OUT_MARGIN`); otherwise "undecided": when both explain the sway
as well as its noise allows, fewer parameters are no evidence about which controller made
it.
"""

from __future__ import annotations

import math
import time as clock
from dataclasses import dataclass, field, replace

import numpy as np

from posture_id.errors import PostureIdError
from posture_id.fileio import Result
from posture_id.frf.locked import LockedOptions, LockedProjection, floored, noise_levels
from posture_id.ic.fit import (
    IcFitOptions,
    IcFitResult,
    IcModelResponse,
    com_deg,
    com_sway_deg,
    fit_ic,
)
from posture_id.ic.response import IcPlant
from posture_id.trials import PreparedTrial

__all__ = ["ModelComparison", "compare_models", "AmplitudesComparison", "compare_amplitudes",
           "BIC_MARGIN", "HELD_OUT_MARGIN"]

#: ΔBIC beyond which one model is preferred.
BIC_MARGIN = 10.0
#: A held-out cycle's χ²/dof difference beyond which it favours a model.
HELD_OUT_MARGIN = 0.25
#: The highest harmonic compared, Hz (docs/model.md §8).
MAX_FREQUENCY_HZ = 2.0


def _within(chi2: dict, compared: int, parameters: dict) -> dict:
    """{"dec", "ic"}: whether the model's χ² is within the 99th percentile of its χ²
    distribution (``compared`` − its ``parameters`` degrees of freedom)."""
    return {m: bool(chi2[m] <= _chi2_quantile(compared - parameters[m])) for m in ("dec", "ic")}


class _ModelVerdicts:
    """What both comparisons say of their models' residuals (their fields ``chi2``,
    ``compared`` and ``parameters``)."""

    @property
    def within_noise(self) -> dict:
        return _within(self.chi2, self.compared, self.parameters)

    @property
    def doubtful(self) -> bool:
        """Neither model explains the locked sway within its noise: the comparison is
        between two models that both miss something."""
        return not any(self.within_noise.values())


@dataclass(frozen=True)
class ModelComparison(_ModelVerdicts, Result):
    """DEC against IC on one recording.

    Attributes:
        dec: the locked DEC fit. ic: the IC fit.
        frequencies_hz: (K,) every harmonic compared. stimulated: (K,) bool.
        chi2: {"dec", "ic"} over every compared harmonic. parameters: {"dec", "ic"} k.
        bic: {"dec", "ic"}. compared: n, the real numbers compared (2K).
        held_out: {"dec", "ic"} χ²/dof of the last cycle predicted by fits on the others,
            or None (fewer than 3 cycles).
        preferred: "dec", "ic" or "undecided". reason: the sentence that says why.
        recorded, dec_spectrum, ic_spectrum: (K,) complex cycle-average COM sway (deg).
    """

    dec: object
    ic: IcFitResult
    frequencies_hz: np.ndarray = field(repr=False)
    stimulated: np.ndarray = field(repr=False)
    chi2: dict
    parameters: dict
    bic: dict
    compared: int
    held_out: dict | None
    preferred: str
    reason: str
    recorded: np.ndarray = field(repr=False)
    dec_spectrum: np.ndarray = field(repr=False)
    ic_spectrum: np.ndarray = field(repr=False)
    noise: np.ndarray = field(default=None, repr=False)
    seconds: float = 0.0
    name: str = "recording"

    def to_dict(self) -> dict:
        from posture_id.provenance import provenance

        return {"recording": self.name, "preferred": self.preferred, "reason": self.reason,
                "within_noise": self.within_noise, "doubtful": self.doubtful,
                "chi2": self.chi2, "parameters": self.parameters, "bic": self.bic,
                "delta_bic_ic_minus_dec": self.bic["ic"] - self.bic["dec"],
                "compared_numbers": self.compared,
                "harmonics": {"stimulated": int(self.stimulated.sum()),
                              "others": int((~self.stimulated).sum()),
                              "up_to_hz": MAX_FREQUENCY_HZ},
                "held_out_cycle": self.held_out,
                "dec": {"parameters": self.dec.parameters.to_dict(),
                        "residual_sd": self.dec.residual_sd},
                "ic": self.ic.to_dict(), "seconds": self.seconds,
                "provenance": provenance()}

    def summary(self) -> str:
        held = ("" if self.held_out is None else
                f"; held-out cycle χ²/dof DEC {self.held_out['dec']:.2f}, IC "
                f"{self.held_out['ic']:.2f}")
        fits = self.within_noise
        lines = [] if not self.doubtful else [
            "doubtful: neither model explains the locked sway within its noise (both miss "
            "something: a mistake in the recording, another body, or a third model)"]
        return "\n".join([
            f"preferred: {self.preferred.upper()}: {self.reason}", *lines,
            f"within the noise: DEC {'yes' if fits['dec'] else 'no'}, IC "
            f"{'yes' if fits['ic'] else 'no'}",
            f"on {len(self.frequencies_hz)} harmonics up to {MAX_FREQUENCY_HZ:g} Hz "
            f"({int(self.stimulated.sum())} stimulated): χ² DEC {self.chi2['dec']:.1f} "
            f"({self.parameters['dec']} parameters), IC {self.chi2['ic']:.1f} "
            f"({self.parameters['ic']}); BIC DEC {self.bic['dec']:.1f}, IC "
            f"{self.bic['ic']:.1f}{held}",
            "DEC: " + ", ".join(f"{j} Kp {m.kp:.1f} Kd {m.kd:.1f} Δ {m.delay_s:.3f} "
                                f"{m.controls}" for j, m in self.dec.parameters.modules.items()),
            self.ic.parameters.summary()])

    def plot(self, path=None, ax=None):
        """The recorded locked COM sway at every compared harmonic, both models over it,
        and their residuals in units of the noise."""
        from posture_id.plotting import plot_model_comparison

        return plot_model_comparison(
            self.frequencies_hz, self.stimulated, self.recorded,
            {"DEC": self.dec_spectrum, "IC": self.ic_spectrum}, self.noise,
            f"{self.name}: preferred {self.preferred.upper()}", path=path, ax=ax)


def _judged(projection: LockedProjection, rows: np.ndarray, noise: np.ndarray,
            recorded: np.ndarray, model_deg: np.ndarray, neighbours: int
            ) -> tuple[float, np.ndarray]:
    """(χ², the model's spectrum (K,)) at the harmonic indices ``rows``. Each noise power
    is estimated from 2·``neighbours`` harmonics (4·neighbours real numbers): its inverse
    is biased high by ν/(ν − 2), ν = 4·neighbours, which the χ² is corrected for."""
    spectrum = projection.all_harmonics(model_deg[:, None])[rows, 0]
    if not np.all(np.isfinite(spectrum)):  # the model falls: it explains nothing
        return math.inf, np.full(len(rows), np.nan, dtype=complex)
    nu = 4 * neighbours
    chi2 = float(np.sum(np.abs((spectrum - recorded) / noise) ** 2)) * (nu - 2) / nu
    return chi2, spectrum


def _falls(theta: np.ndarray) -> bool:
    """Whether a fitted DEC sway (S, N) rad leaves the sway limit (or is not finite)."""
    from posture_id.simulation.options import MAX_SWAY_LIMIT_DEG

    theta = np.asarray(theta, dtype=float)
    return bool(not np.all(np.isfinite(theta))
                or np.max(np.abs(theta)) >= math.radians(MAX_SWAY_LIMIT_DEG) * (1 - 1e-9))


def _dec_fit(trial: PreparedTrial, body, locked: LockedOptions, progress=None):
    from posture_id.fitting.least_squares import fit_recording
    from posture_id.fitting.options import FitOptions

    return fit_recording(trial, body, None, FitOptions(locked=locked), progress=progress)


def _first_cycles(trial: PreparedTrial, cycles: int, projection: LockedProjection
                  ) -> PreparedTrial:
    """The trial cut after ``cycles`` analysed cycles."""
    from posture_id.recording import Recording

    end = projection.start + cycles * projection.period
    rec = trial.recording
    cut = Recording(rec.time[:end], rec.tilt[:end], rec.theta[:end], rec.segments,
                    rec.name, rec.tilt_recorded)
    return replace(trial, recording=cut)


@dataclass(frozen=True)
class _Judged:
    """One recording's compared harmonics: every harmonic up to 2 Hz, its noise."""

    projection: LockedProjection
    rows: np.ndarray
    frequencies_hz: np.ndarray
    noise: np.ndarray
    recorded: np.ndarray
    sway: np.ndarray

    @classmethod
    def of(cls, trial: PreparedTrial, body, locked: LockedOptions) -> _Judged:
        if trial.stimulus.period_s is None:
            raise PostureIdError(f"{trial.name}: comparing the models needs a periodic "
                                 "stimulus (its locked harmonics)")
        rec = trial.recording
        sway = com_sway_deg(trial, body)
        projection = LockedProjection.for_recording(
            rec.tilt, sway[:, None], rec.sample_rate_hz, trial.stimulus.period_s,
            trial.stimulus.periodic_from_s, locked, trial.name)
        spectrum = projection.all_harmonics(sway[:, None])[:, 0]
        frequencies = np.arange(1, len(spectrum) + 1) * rec.sample_rate_hz / projection.period
        rows = np.flatnonzero(frequencies <= MAX_FREQUENCY_HZ)
        noise = floored(noise_levels(np.abs(spectrum) ** 2, projection.excited, rows,
                                     locked.neighbours, exclude_self=True))
        return cls(projection, rows, frequencies[rows], noise, spectrum[rows], sway)

    def judge(self, model_deg: np.ndarray, neighbours: int) -> tuple[float, np.ndarray]:
        return _judged(self.projection, self.rows, self.noise, self.recorded, model_deg,
                       neighbours)


def compare_models(trial: PreparedTrial, body, ic_options: IcFitOptions | None = None,
                   progress=None, held_out: bool = True) -> ModelComparison:
    """Fit DEC and IC to ``trial`` and say which its sway supports (the module doc).

    Args:
        trial: the recording with its stimulus, which must be periodic (a
            :class:`PreparedTrial`).
        body: the recorded body (its segments are the recording's).
        ic_options: the IC fit's options (default :class:`IcFitOptions`); the harmonics
            compared stop at 2 Hz whatever its ``locked`` says.
        progress: a callback told the DEC fit's stages (None: no reports).
        held_out: also predict a held-out last cycle from fits on the others (with three
            or more cycles; each model is then fitted twice).
    Returns:
        :class:`ModelComparison`: both fits, χ², BIC, the held-out χ²/dof and the verdict.
    Raises:
        PostureIdError: a stimulus that is not periodic.
    """
    started = clock.perf_counter()
    ic_options = ic_options or IcFitOptions()
    locked = replace(ic_options.locked, max_frequency_hz=MAX_FREQUENCY_HZ)
    judged = _Judged.of(trial, body, locked)
    projection = judged.projection
    dec = _dec_fit(trial, body, locked, progress)
    ic = fit_ic(trial, body, replace(ic_options, locked=locked))
    chi2_dec, dec_spectrum = judged.judge(com_deg(dec.fitted, body), locked.neighbours)
    chi2_ic, ic_spectrum = judged.judge(ic.fitted_deg, locked.neighbours)
    n = 2 * len(judged.rows)
    k = {"dec": 5 * body.n_segments, "ic": len(ic.free)}
    chi2 = {"dec": chi2_dec, "ic": chi2_ic}
    bic = {m: chi2[m] + k[m] * math.log(n) for m in ("dec", "ic")}
    held = (_held_out(trial, body, projection, locked, ic_options, judged.sway)
            if held_out and projection.cycles >= 3 else None)
    within = _within(chi2, n, k)
    preferred, reason = _verdict(bic, held, projection.cycles, within)
    if _falls(dec.fitted):
        preferred, reason = "undecided", (
            "the DEC fit ended on a model that falls in re-simulation: a fit that failed is "
            "no evidence about DEC itself (fit DEC alone, e.g. posture-id identify REC, and "
            "compare the answers)")
    return ModelComparison(dec, ic, judged.frequencies_hz, projection.excited[judged.rows],
                           chi2, k, bic, n, held, preferred, reason, judged.recorded,
                           dec_spectrum, ic_spectrum, judged.noise,
                           clock.perf_counter() - started, trial.name)


@dataclass(frozen=True)
class AmplitudesComparison(_ModelVerdicts, Result):
    """DEC against IC on the parts of a two-amplitude protocol: DEC with one set of
    parameters for every part, IC with every parameter shared but W (one per part).

    Attributes:
        dec: the joint DEC fit (:class:`~posture_id.fitting.joint.JointFit`). ic: the IC
        fit (:class:`~posture_id.ic.fit.IcPartsFit`). chi2, parameters, bic, compared,
        preferred, reason: as :class:`ModelComparison`'s, over every part.
        names: the parts' recordings.
    """

    dec: object
    ic: object
    chi2: dict
    parameters: dict
    bic: dict
    compared: int
    preferred: str
    reason: str
    names: tuple[str, ...]
    seconds: float = 0.0

    def to_dict(self) -> dict:
        from posture_id.provenance import provenance

        return {"recordings": list(self.names), "preferred": self.preferred,
                "reason": self.reason, "within_noise": self.within_noise,
                "doubtful": self.doubtful, "chi2": self.chi2, "parameters": self.parameters,
                "bic": self.bic, "delta_bic_ic_minus_dec": self.bic["ic"] - self.bic["dec"],
                "compared_numbers": self.compared,
                "ic": {"parameters": [p.to_dict() for p in self.ic.parameters],
                       "w_by_part": list(self.ic.w_by_part),
                       "reweighting": self.ic.reweighting},
                "dec": {"parameters": self.dec.parameters.to_dict()},
                "seconds": self.seconds, "provenance": provenance()}

    def summary(self) -> str:
        w = ", ".join(f"{x:.3f}" for x in self.ic.w_by_part)
        return "\n".join([
            f"preferred: {self.preferred.upper()}: {self.reason}",
            f"IC re-weighting: W {w} by part (it moved by {self.ic.reweighting:+.3f} from the "
            "first amplitude to the second)",
            f"χ² DEC {self.chi2['dec']:.1f} ({self.parameters['dec']} parameters), IC "
            f"{self.chi2['ic']:.1f} ({self.parameters['ic']}); BIC DEC "
            f"{self.bic['dec']:.1f}, IC {self.bic['ic']:.1f} over {len(self.names)} parts",
            "DEC: " + ", ".join(f"{j} Kp {m.kp:.1f} Kd {m.kd:.1f} Δ {m.delay_s:.3f} "
                                f"{m.controls}" for j, m in self.dec.parameters.modules.items()),
            self.ic.parameters[0].summary() + f" (W of the first part; {w})"])

    def plot(self, path=None, ax=None):
        """The W each amplitude needed, beside the BIC of both models."""
        from posture_id.plotting import plot_reweighting

        return plot_reweighting(self.names, self.ic.w_by_part, self.bic, path=path, ax=ax)


def compare_amplitudes(trials: list[PreparedTrial], body,
                       ic_options: IcFitOptions | None = None,
                       progress=None) -> AmplitudesComparison:
    """Fit DEC (one set of parameters) and IC (a W per part) to the parts of a
    two-amplitude protocol, and say which the sway supports (the module doc: the same
    rule, the held-out cycle left out).

    Args:
        trials: the parts, one recording per amplitude, each with its periodic stimulus.
        body: the recorded body, the same for every part.
        ic_options: the IC fit's options (default :class:`IcFitOptions`); the harmonics
            compared stop at 2 Hz whatever its ``locked`` says.
        progress: a callback told the joint DEC fit's stages (None: no reports).
    Returns:
        :class:`AmplitudesComparison`: both fits, χ², BIC, each part's W and the verdict.
    Raises:
        PostureIdError: a part whose stimulus is not periodic.
    """
    from posture_id.fitting.joint import fit_recordings_jointly
    from posture_id.fitting.options import FitOptions
    from posture_id.ic.fit import fit_ic_parts

    started = clock.perf_counter()
    ic_options = ic_options or IcFitOptions()
    locked = replace(ic_options.locked, max_frequency_hz=MAX_FREQUENCY_HZ)
    judged = [_Judged.of(t, body, locked) for t in trials]
    dec = fit_recordings_jointly(trials, body, FitOptions(locked=locked), progress)
    ic = fit_ic_parts(trials, body, replace(ic_options, locked=locked))
    chi2 = {"dec": 0.0, "ic": 0.0}
    for part, theta, ic_deg in zip(judged, dec.fitted, ic.fitted_deg, strict=True):
        chi2["dec"] += part.judge(com_deg(theta, body), locked.neighbours)[0]
        chi2["ic"] += part.judge(ic_deg, locked.neighbours)[0]
    n = sum(2 * len(p.rows) for p in judged)
    k = {"dec": 5 * body.n_segments, "ic": len(ic_options.free) + len(trials) - 1}
    bic = {m: chi2[m] + k[m] * math.log(n) for m in ("dec", "ic")}
    within = _within(chi2, n, k)
    preferred, reason = _verdict(bic, None, None, within)
    if any(_falls(theta) for theta in dec.fitted):
        preferred, reason = "undecided", (
            "the joint DEC fit ended on a model that falls in re-simulation: a fit that "
            "failed is no evidence about DEC itself")
    return AmplitudesComparison(dec, ic, chi2, k, bic, n, preferred, reason,
                                tuple(t.name for t in trials),
                                clock.perf_counter() - started)


def _held_out(trial: PreparedTrial, body, projection: LockedProjection,
              locked: LockedOptions, ic_options: IcFitOptions, sway: np.ndarray) -> dict:
    """χ²/dof of each model's prediction of the last cycle, fitted on the others."""
    from posture_id.simulation.batch import simulate
    from posture_id.simulation.options import SimulationOptions

    c = projection.cycles
    train = _first_cycles(trial, c - 1, projection)
    dec = _dec_fit(train, body, locked)
    ic = fit_ic(train, body, replace(ic_options, locked=locked))
    rec = trial.recording
    options = SimulationOptions(sample_rate_hz=rec.sample_rate_hz)
    dec_sway = simulate(body, dec.parameters, trial.stimulus, options).theta[: len(rec.time)]
    dec_com = com_deg(dec_sway, body)
    ic_com = np.degrees(IcModelResponse(rec.tilt, rec.sample_rate_hz, IcPlant.of(body))
                        .sway(ic.parameters))
    last = slice(projection.start + (c - 1) * projection.period,
                 projection.start + c * projection.period)
    p = projection.period

    def spectrum(x: np.ndarray) -> np.ndarray:
        return np.fft.rfft(x[last] - x[last].mean())[1 : p // 2 + 1] / p

    recorded = spectrum(sway)
    rows = projection.harmonics - 1
    noise = projection.noise[:, 0] * math.sqrt(c)  # one cycle's noise, not the average's
    out = {}
    for name, model in (("dec", dec_com), ("ic", ic_com)):
        if not np.all(np.isfinite(model[last])):
            out[name] = math.inf
            continue
        r = (spectrum(model) - recorded)[rows] / noise
        out[name] = float(np.sum(np.abs(r) ** 2) / (2 * len(rows)))
    return out


def _chi2_quantile(dof: int) -> float:
    from scipy.stats import chi2

    return float(chi2.ppf(0.99, max(dof, 1)))


def _verdict(bic: dict, held: dict | None, cycles: int | None, within: dict) -> tuple[str, str]:
    delta = bic["ic"] - bic["dec"]
    if all(within.values()):
        return "undecided", ("both models explain the locked sway within its noise (their "
                             f"BIC differ by {abs(delta):.1f}): the recording does not tell "
                             "them apart")
    if abs(delta) <= BIC_MARGIN:
        return "undecided", (f"the models' BIC differ by {abs(delta):.1f}, within the "
                             f"{BIC_MARGIN:g} the noise allows: the recording does not tell "
                             "them apart")
    better, worse = ("dec", "ic") if delta > 0 else ("ic", "dec")
    names = {"dec": "DEC", "ic": "IC"}
    if held is not None and held[worse] + HELD_OUT_MARGIN < held[better]:
        return "undecided", (f"{names[better]}'s BIC is lower by {abs(delta):.1f}, but "
                             f"{names[worse]} predicts the held-out cycle better "
                             f"(χ²/dof {held[worse]:.2f} against {held[better]:.2f})")
    tail = ("" if held is None else
            f"; it predicts the held-out cycle as well or better (χ²/dof {held[better]:.2f} "
            f"against {held[worse]:.2f})")
    if held is None:
        tail = ("; every part fitted at once, no held-out cycle" if cycles is None
                else f"; no held-out cycle with {cycles} cycles")
    return better, (f"{names[better]} explains the locked sway better by a BIC of "
                    f"{abs(delta):.1f} (beyond the {BIC_MARGIN:g} the noise allows), its "
                    f"parameters counted{tail}")
