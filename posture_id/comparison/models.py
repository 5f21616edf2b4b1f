"""Which model does the sway support, DEC or IC (or any two models)? (docs/model.md §8,
comparison.)

Both models are fitted to the same recording the way each one's capabilities allow
(:func:`~posture_id.fitting.models.fit_model`: DEC by the locked least-squares fit, IC by
its exact frequency-domain fit). Then both are judged on the same numbers:
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

from posture_id.bodies.body import Body
from posture_id.comparison.identified import fit_as_identified
from posture_id.errors import PostureIdError
from posture_id.fileio import Result
from posture_id.fitting.frequency import IcFitOptions, com_sway_deg, locked_projection
from posture_id.fitting.joint_conditions import JointFit
from posture_id.fitting.models import fit_model_parts
from posture_id.frf.locked import LockedOptions, LockedProjection, floored, noise_levels
from posture_id.models.dec import DEC
from posture_id.models.ic import IC
from posture_id.models.protocol import Capability
from posture_id.progress import Progress
from posture_id.trials import PreparedTrial

__all__ = ["ModelComparison", "compare_models", "AmplitudesComparison", "compare_amplitudes",
           "BIC_MARGIN", "HELD_OUT_MARGIN", "UNDECIDED"]

#: ΔBIC beyond which one model is preferred.
BIC_MARGIN = 10.0
#: A held-out cycle's χ²/dof difference beyond which it favours a model.
HELD_OUT_MARGIN = 0.25
#: The highest harmonic compared, Hz (docs/model.md §8).
MAX_FREQUENCY_HZ = 2.0
#: The verdict when the recording does not tell the models apart.
UNDECIDED = "undecided"
#: The models compared unless asked otherwise.
DEFAULT_MODELS = (DEC, IC)


def _chi2_quantile(dof: int) -> float:
    from scipy.stats import chi2

    return float(chi2.ppf(0.99, max(dof, 1)))


@dataclass(frozen=True)
class _Compared:
    """What both comparisons share: the two models, their fits, χ², k, BIC, n and the
    verdict, and what is said of them."""

    models: tuple
    fits: dict
    chi2: dict
    parameters: dict
    bic: dict
    compared: int
    preferred: str
    reason: str

    @property
    def names(self) -> tuple[str, str]:
        return tuple(m.name for m in self.models)

    @property
    def within_noise(self) -> dict:
        """Per model: whether its χ² is within the 99th percentile of its χ² distribution
        (``compared`` − its ``parameters`` degrees of freedom)."""
        return {m: bool(self.chi2[m] <= _chi2_quantile(self.compared - self.parameters[m]))
                for m in self.names}

    @property
    def doubtful(self) -> bool:
        """Neither model explains the locked sway within its noise: the comparison is
        between two models that both miss something."""
        return not any(self.within_noise.values())

    @property
    def delta_bic(self) -> float:
        """The second model's BIC minus the first's (IC − DEC)."""
        first, second = self.names
        return self.bic[second] - self.bic[first]

    def _common_dict(self) -> dict:
        first, second = self.names
        return {"preferred": self.preferred, "reason": self.reason,
                "within_noise": self.within_noise, "doubtful": self.doubtful,
                "chi2": self.chi2, "parameters": self.parameters, "bic": self.bic,
                f"delta_bic_{second}_minus_{first}": self.delta_bic,
                "compared_numbers": self.compared}

    def _scores(self) -> str:
        """Both models' χ² with their parameters, and their BIC."""
        (first, second), (a, b) = self.models, self.names
        return (f"χ² {first.label} {self.chi2[a]:.1f} ({self.parameters[a]} parameters), "
                f"{second.label} {self.chi2[b]:.1f} ({self.parameters[b]}); BIC "
                f"{first.label} {self.bic[a]:.1f}, {second.label} {self.bic[b]:.1f}")

    def _fit_lines(self) -> list[str]:
        """One line per model's answer."""
        lines = []
        for model in self.models:
            fit = self.fits[model.name]
            params = fit.parameters
            if isinstance(params, dict):  # a joint fit of the parts: the first part's
                params = next(iter(params.values()))
            if hasattr(params, "modules"):
                lines.append(f"{model.label}: " + ", ".join(
                    f"{j} Kp {m.kp:.1f} Kd {m.kd:.1f} Δ {m.delay_s:.3f} {m.controls}"
                    for j, m in params.modules.items()))
            else:
                lines.append(params.summary())
        return lines


@dataclass(frozen=True)
class ModelComparison(_Compared, Result):
    """Two models (DEC against IC) on one recording.

    Attributes:
        models: the two models, the first the one ΔBIC is measured from.
        fits: per model name, its fit (:class:`~posture_id.models.protocol.ModelFit`).
        frequencies_hz: (K,) every harmonic compared. stimulated: (K,) bool.
        chi2: per model, over every compared harmonic. parameters: per model, k.
        bic: per model. compared: n, the real numbers compared (2K).
        held_out: per model χ²/dof of the last cycle predicted by fits on the others,
            or None (fewer than 3 cycles).
        preferred: a model's name or "undecided". reason: the sentence that says why.
        recorded: (K,) complex cycle-average COM sway (deg). spectra: per model, its (K,).
    """

    frequencies_hz: np.ndarray = field(repr=False, default=None)
    stimulated: np.ndarray = field(repr=False, default=None)
    held_out: dict | None = None
    recorded: np.ndarray = field(repr=False, default=None)
    spectra: dict = field(repr=False, default_factory=dict)
    noise: np.ndarray = field(default=None, repr=False)
    seconds: float = 0.0
    name: str = "recording"

    def to_dict(self) -> dict:
        from posture_id.provenance import provenance

        return {"recording": self.name, **self._common_dict(),
                "harmonics": {"stimulated": int(self.stimulated.sum()),
                              "others": int((~self.stimulated).sum()),
                              "up_to_hz": MAX_FREQUENCY_HZ},
                "held_out_cycle": self.held_out,
                **{m: self.fits[m].comparison_dict() for m in self.names},
                "seconds": self.seconds, "provenance": provenance()}

    def summary(self) -> str:
        first, second = self.models
        held = ("" if self.held_out is None else
                f"; held-out cycle χ²/dof {first.label} {self.held_out[first.name]:.2f}, "
                f"{second.label} {self.held_out[second.name]:.2f}")
        fits = self.within_noise
        lines = [] if not self.doubtful else [
            "doubtful: neither model explains the locked sway within its noise (both miss "
            "something: a mistake in the recording, another body, or a third model)"]
        a, b = first.name, second.name
        return "\n".join([
            f"preferred: {self.preferred.upper()}: {self.reason}", *lines,
            f"within the noise: {first.label} {'yes' if fits[a] else 'no'}, {second.label} "
            f"{'yes' if fits[b] else 'no'}",
            f"on {len(self.frequencies_hz)} harmonics up to {MAX_FREQUENCY_HZ:g} Hz "
            f"({int(self.stimulated.sum())} stimulated): {self._scores()}{held}",
            *self._fit_lines()])

    def plot(self, path=None, ax=None):
        """The recorded locked COM sway at every compared harmonic, both models over it,
        and their residuals in units of the noise."""
        from posture_id.plotting import plot_model_comparison

        return plot_model_comparison(
            self.frequencies_hz, self.stimulated, self.recorded,
            {m.label: self.spectra[m.name] for m in self.models}, self.noise,
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
        # a sinusoid over several of its cycles, as the fits analyse it (its noise
        # estimated on both sides of its frequency)
        projection = locked_projection(trial, sway[:, None], locked)
        spectrum = projection.all_harmonics(sway[:, None])[:, 0]
        frequencies = np.arange(1, len(spectrum) + 1) * rec.sample_rate_hz / projection.period
        rows = np.flatnonzero(frequencies <= MAX_FREQUENCY_HZ)
        noise = floored(noise_levels(np.abs(spectrum) ** 2, projection.excited, rows,
                                     locked.neighbours, exclude_self=True))
        return cls(projection, rows, frequencies[rows], noise, spectrum[rows], sway)

    def judge(self, model_deg: np.ndarray, neighbours: int) -> tuple[float, np.ndarray]:
        return _judged(self.projection, self.rows, self.noise, self.recorded, model_deg,
                       neighbours)


def _locked_and_options(options: dict | None, ic_options: IcFitOptions | None
                        ) -> tuple[LockedOptions, dict]:
    """The harmonics compared (up to 2 Hz) and each model's fit options."""
    options = dict(options or {})
    if ic_options is not None:
        options["ic"] = ic_options
    options.setdefault("ic", IcFitOptions())
    locked = getattr(options["ic"], "locked", LockedOptions())
    return replace(locked, max_frequency_hz=MAX_FREQUENCY_HZ), options


def compare_models(trial: PreparedTrial, body: Body, ic_options: IcFitOptions | None = None,
                   progress: Progress | None = None, held_out: bool = True,
                   models: tuple = DEFAULT_MODELS,
                   options: dict | None = None, fitted: dict | None = None
                   ) -> ModelComparison:
    """Fit two models (DEC and IC) to ``trial`` and say which its sway supports (the module
    doc).

    Args:
        trial: the recording with its stimulus, which must be periodic (a
            :class:`PreparedTrial`).
        body: the recorded body (its segments are the recording's).
        ic_options: the IC fit's options (default :class:`IcFitOptions`); the harmonics
            compared stop at 2 Hz whatever its ``locked`` says.
        progress: a callback told the DEC fit's stages (None: no reports).
        held_out: also predict a held-out last cycle from fits on the others (with three
            or more cycles; each model is then fitted twice).
        models: the two models compared (:class:`~posture_id.models.protocol.Model`).
        options: per model name, its fit options (the IC model's default: ``ic_options``).
        fitted: per model name, a fit already made on this recording at these harmonics
            (it is not fitted again).
    Returns:
        :class:`ModelComparison`: both fits, χ², BIC, the held-out χ²/dof and the verdict.
    Raises:
        PostureIdError: a stimulus that is not periodic.
    """
    started = clock.perf_counter()
    locked, options = _locked_and_options(options, ic_options)
    judged = _Judged.of(trial, body, locked)
    projection = judged.projection
    fits, chi2, k, spectra = {}, {}, {}, {}
    for model in models:
        fit = (fitted or {}).get(model.name) or fit_as_identified(
            model, trial, body, locked, options.get(model.name), progress)
        fits[model.name] = fit
        chi2[model.name], spectra[model.name] = judged.judge(fit.fitted_com_deg,
                                                             locked.neighbours)
        k[model.name] = fit.identified_count
    n = 2 * len(judged.rows)
    bic = {m: chi2[m] + k[m] * math.log(n) for m in chi2}
    held = (_held_out(trial, body, projection, locked, models, options, judged.sway)
            if held_out and projection.cycles >= 3 else None)
    preferred, reason = _decide(models, fits, chi2, k, bic, n, held, projection.cycles)
    return ModelComparison(tuple(models), fits, chi2, k, bic, n, preferred, reason,
                           judged.frequencies_hz, projection.excited[judged.rows], held,
                           judged.recorded, spectra, judged.noise,
                           clock.perf_counter() - started, trial.name)


def _decide(models, fits, chi2, k, bic, n, held, cycles, parts: bool = False
            ) -> tuple[str, str]:
    """The verdict, and "undecided" where a fit ended on a model that falls."""
    within = {m: bool(chi2[m] <= _chi2_quantile(n - k[m])) for m in chi2}
    preferred, reason = _verdict(models, bic, held, cycles, within)
    for model in models:
        if fits[model.name].falls:
            what = "joint " if parts else ""
            tail = ("" if parts else f" (fit {model.label} alone, e.g. posture-id identify "
                    "REC, and compare the answers)")
            return UNDECIDED, (
                f"the {what}{model.label} fit ended on a model that falls in re-simulation: "
                f"a fit that failed is no evidence about {model.label} itself{tail}")
    return preferred, reason


@dataclass(frozen=True)
class AmplitudesComparison(_Compared, Result):
    """Two models on the parts of a two-amplitude protocol: DEC with one set of
    parameters for every part, IC with every parameter shared but W (one per part).

    Attributes:
        fits: per model, its fit of every part at once. chi2, parameters, bic, compared,
        preferred, reason: as :class:`ModelComparison`'s, over every part.
        recordings: the parts' recordings.
    """

    recordings: tuple[str, ...] = ()
    seconds: float = 0.0

    def to_dict(self) -> dict:
        from posture_id.provenance import provenance

        out = {"recordings": list(self.recordings), **self._common_dict()}
        out.update({m: _parts_dict(self.fits[m]) for m in reversed(self.names)})
        return {**out, "seconds": self.seconds, "provenance": provenance()}

    def _per_part(self):
        """The model whose parameters differ by part (IC), or None."""
        return next((m for m in self.models
                     if Capability.FREQUENCY_RESPONSE in m.capabilities), None)

    def summary(self) -> str:
        lines = [f"preferred: {self.preferred.upper()}: {self.reason}"]
        varying = self._per_part()
        w = ""
        if varying is not None:
            fit = self.fits[varying.name]
            w = ", ".join(f"{x:.3f}" for x in fit.w_by_part)
            lines.append(f"{varying.label} re-weighting: W {w} by part (it moved by "
                         f"{fit.reweighting:+.3f} from the first amplitude to the second)")
        lines.append(f"{self._scores()} over {len(self.recordings)} parts")
        fit_lines = self._fit_lines()
        if varying is not None:
            i = self.models.index(varying)
            fit_lines[i] += f" (W of the first part; {w})"
        return "\n".join(lines + fit_lines)

    def plot(self, path=None, ax=None):
        """The W each amplitude needed, beside the BIC of both models."""
        from posture_id.plotting import plot_reweighting

        varying = self._per_part()
        return plot_reweighting(self.recordings, self.fits[varying.name].w_by_part,
                                self.bic, path=path, ax=ax)


def _parts_dict(fit: JointFit) -> dict:
    """What a comparison's JSON keeps of a joint fit of the parts: a closed loop's
    parameters per part with its per-part one (IC: W), DEC's one set."""
    parameters = [p.to_dict() for p in fit.parameters.values()]
    if Capability.FREQUENCY_RESPONSE not in fit.model.capabilities:
        return {"parameters": parameters[0]}
    return {"parameters": parameters, "w_by_part": list(fit.w_by_part),
            "reweighting": fit.reweighting}


def compare_amplitudes(trials: list[PreparedTrial], body: Body,
                       ic_options: IcFitOptions | None = None,
                       progress: Progress | None = None, models: tuple = DEFAULT_MODELS,
                       options: dict | None = None) -> AmplitudesComparison:
    """Fit two models (DEC with one set of parameters, IC with a W per part) to the parts
    of a two-amplitude protocol, and say which the sway supports (the module doc: the same
    rule, the held-out cycle left out).

    Args:
        trials: the parts, one recording per amplitude, each with its periodic stimulus.
        body: the recorded body, the same for every part.
        ic_options: the IC fit's options (default :class:`IcFitOptions`); the harmonics
            compared stop at 2 Hz whatever its ``locked`` says.
        progress: a callback told the joint DEC fit's stages (None: no reports).
        models: The two models compared, as :func:`compare_models`'s.
        options: Each model's fit options by name, as :func:`compare_models`'s.
    Returns:
        :class:`AmplitudesComparison`: both fits, χ², BIC, each part's W and the verdict.
    Raises:
        PostureIdError: a part whose stimulus is not periodic.
    """
    started = clock.perf_counter()
    locked, options = _locked_and_options(options, ic_options)
    judged = [_Judged.of(t, body, locked) for t in trials]
    fits, chi2, k = {}, {}, {}
    for model in models:
        fit = fit_model_parts(model, trials, body, locked, options.get(model.name), progress)
        fits[model.name] = fit
        chi2[model.name] = sum(part.judge(sway, locked.neighbours)[0]
                               for part, sway in zip(judged, fit.fitted_com_deg, strict=True))
        k[model.name] = fit.identified_count
    n = sum(2 * len(p.rows) for p in judged)
    bic = {m: chi2[m] + k[m] * math.log(n) for m in chi2}
    preferred, reason = _decide(models, fits, chi2, k, bic, n, None, None, parts=True)
    return AmplitudesComparison(tuple(models), fits, chi2, k, bic, n, preferred, reason,
                                tuple(t.name for t in trials),
                                clock.perf_counter() - started)


def _held_out(trial: PreparedTrial, body, projection: LockedProjection,
              locked: LockedOptions, models, options: dict, sway: np.ndarray) -> dict:
    """χ²/dof of each model's prediction of the last cycle, fitted on the others."""
    c = projection.cycles
    train = _first_cycles(trial, c - 1, projection)
    last = slice(projection.start + (c - 1) * projection.period,
                 projection.start + c * projection.period)
    p = projection.period

    def spectrum(x: np.ndarray) -> np.ndarray:
        return np.fft.rfft(x[last] - x[last].mean())[1 : p // 2 + 1] / p

    recorded = spectrum(sway)
    rows = projection.harmonics - 1
    noise = projection.noise[:, 0] * math.sqrt(c)  # one cycle's noise, not the average's
    predicted = {}
    for model in models:
        fit = fit_as_identified(model, train, body, locked, options.get(model.name))
        predicted[model.name] = model.com_sway_deg(fit.parameters, body, trial)
    out = {}
    for name, model_com in predicted.items():
        if not np.all(np.isfinite(model_com[last])):
            out[name] = math.inf
            continue
        r = (spectrum(model_com) - recorded)[rows] / noise
        out[name] = float(np.sum(np.abs(r) ** 2) / (2 * len(rows)))
    return out


def _verdict(models, bic: dict, held: dict | None, cycles: int | None, within: dict
             ) -> tuple[str, str]:
    first, second = models
    delta = bic[second.name] - bic[first.name]
    if all(within.values()):
        return UNDECIDED, ("both models explain the locked sway within its noise (their "
                           f"BIC differ by {abs(delta):.1f}): the recording does not tell "
                           "them apart")
    if abs(delta) <= BIC_MARGIN:
        return UNDECIDED, (f"the models' BIC differ by {abs(delta):.1f}, within the "
                           f"{BIC_MARGIN:g} the noise allows: the recording does not tell "
                           "them apart")
    better, worse = (first, second) if delta > 0 else (second, first)
    if held is not None and held[worse.name] + HELD_OUT_MARGIN < held[better.name]:
        return UNDECIDED, (f"{better.label}'s BIC is lower by {abs(delta):.1f}, but "
                           f"{worse.label} predicts the held-out cycle better "
                           f"(χ²/dof {held[worse.name]:.2f} against {held[better.name]:.2f})")
    tail = ("" if held is None else
            f"; it predicts the held-out cycle as well or better (χ²/dof "
            f"{held[better.name]:.2f} against {held[worse.name]:.2f})")
    if held is None:
        tail = ("; every part fitted at once, no held-out cycle" if cycles is None
                else f"; no held-out cycle with {cycles} cycles")
    return better.name, (f"{better.label} explains the locked sway better by a BIC of "
                         f"{abs(delta):.1f} (beyond the {BIC_MARGIN:g} the noise allows), its "
                         f"parameters counted{tail}")
