"""Fit a linear model (the IC model, or any :class:`~posture_id.models.protocol.FrequencyModel`)
to a recording's stimulus-locked body COM sway (docs/model.md §8).

What is compared is what the locked DEC fit compares (:mod:`posture_id.frf.locked`): the
drift-free cycle average of the body COM sway at the harmonics the stimulus excites up to
2 Hz, each divided by the noise level estimated at the neighbouring harmonics it leaves
empty. The model's sway on the recording's samples is its response to the recorded
tilt from rest, computed exactly in the frequency domain (the tilt zero-padded far beyond
the recording's end, times H(jω), transformed back): the transient of the first cycle is
the model's own, as in a re-simulation, with no time-stepping
(:class:`~posture_id.models.exact.ExactResponse`). Its derivatives are the same
transform of dH/dp (the model's ``closed_loop``), so the least squares
(scipy's trust-region reflective) has the exact Jacobian. Several starts (the first at
the literature's typical values; the search stops at the first answer whose residual is
within the noise's 99th percentile); an answer
whose closed loop is unstable is never returned (the model's ``is_stable``): where every
start ends on an unstable loop, the stable starts are searched again with unstable loops
barred. A stimulus that excites one harmonic only (a sinusoid) is analysed over several
of its cycles at once (:func:`analysis_cycles`), so that its noise is estimated on both
sides of its frequency.

Several trials at once, grouped into conditions (:func:`search_conditions`,
:class:`ConditionLayout`): each trial's residual stacked, each with its condition's
parameters; :func:`~posture_id.fitting.models.fit_frequency_parts` is its special case
(every part its own condition), :func:`~posture_id.fitting.joint_conditions.fit_joint` the
fit of a session.

Intervals: Gauss-Newton standard errors, the covariance (JᵀJ)⁻¹ of the weighted residual
scaled by its χ² per degree of freedom where that exceeds 1, times the model's multiplier
per parameter and level (the IC model's calibrated on recordings the project simulated:
:mod:`posture_id.models.ic.model`; without a calibration, the normal quantile).
"""

from __future__ import annotations

import math
import time as clock
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from posture_id.bodies.body import Body
from posture_id.errors import PostureIdError
from posture_id.fileio import Result
from posture_id.frf.locked import LockedOptions, LockedProjection, floored, noise_levels
from posture_id.models.dec import com_deg
from posture_id.models.exact import ExactResponse
from posture_id.models.ic.model import IC
from posture_id.models.protocol import FrequencyModel, ModelParameters, TrustLevel
from posture_id.trials import PreparedTrial

__all__ = ["FrequencyFitOptions", "IcFitOptions", "FitVerdict", "FrequencyFitResult",
           "fit_frequency", "fit_ic", "com_sway_deg", "LockedCom", "locked_projection",
           "analysis_cycles", "ConditionLayout", "Precision", "on_search_bound",
           "ConditionSearch", "search_conditions"]


@dataclass(frozen=True)
class FrequencyFitOptions:
    """What a frequency-domain fit identifies and how.

    Attributes:
        parameters: the identified parameters (empty: the model's ``identified``).
        starts: least-squares starts (the first at the model's typical values, the
            others drawn within the bounds). seed: seeds those draws.
        locked: the locked harmonics compared (docs/model.md §8: up to 2 Hz).
        level: the intervals' nominal coverage.
    """

    parameters: tuple[str, ...] = ()
    starts: int = 6
    seed: int = 0
    locked: LockedOptions = field(default_factory=LockedOptions)
    level: float = 0.9

    def __post_init__(self) -> None:
        if self.starts < 1:
            raise PostureIdError(f"the fit's starts must be ≥ 1, got {self.starts}")
        if not 0.5 <= self.level <= 0.99:
            raise PostureIdError(f"the fit's level must be within 0.5–0.99, got {self.level}")

    def asked(self, model: FrequencyModel) -> tuple[str, ...]:
        """The parameters asked to be identified, in any order."""
        return tuple(self.parameters or model.identified)

    def free_of(self, model: FrequencyModel) -> tuple[str, ...]:
        """The identified parameters, in the model's ``parameter_order``."""
        names = self.asked(model)
        unknown = sorted(set(names) - set(model.parameter_order))
        if unknown:
            raise PostureIdError(f"{model.label} has no parameter(s) {unknown} (it has "
                                 f"{', '.join(model.parameter_order)})")
        return tuple(n for n in model.parameter_order if n in names)


@dataclass(frozen=True)
class IcFitOptions(FrequencyFitOptions):
    """What the IC fit identifies: its six parameters, and with ``fit_ki`` Ki, with
    ``fit_passive`` Kpas and Bpas (else 0); the rest as :class:`FrequencyFitOptions`."""

    fit_ki: bool = False
    fit_passive: bool = False

    @property
    def free(self) -> tuple[str, ...]:
        """The identified parameters, in the IC model's order."""
        return self.free_of(IC)

    def asked(self, model: FrequencyModel) -> tuple[str, ...]:
        return (*super().asked(model), *(("ki",) if self.fit_ki else ()),
                *(("kpas", "bpas") if self.fit_passive else ()))


def com_sway_deg(trial: PreparedTrial, body) -> np.ndarray:
    """(S,) degrees: the body COM sway α_BS of a trial (:func:`~posture_id.models.dec.com_deg`).

    Raises:
        PostureIdError: a recording whose segments are not the body's.
    """
    trial.recording.check_segments(body.segment_names)
    return com_deg(trial.recording.theta, body)


class FitVerdict:
    """The trust verdict of a fit of the locked COM sway, as one recording's fit
    (:class:`FrequencyFitResult`) and a joint fit
    (:class:`~posture_id.fitting.joint_conditions.JointFit`) give it (docs/identify.md,
    "Trust"), from their ``chi2``, ``dof``, ``on_bound`` and ``stable``, and the judged
    parameters' intervals (:meth:`_every_interval`, ``pins``, ``absolute_pins``; each
    line's ``level`` and ``calibrated``). A fit that names ``undetermined`` parameters
    (one recording's) also has ``harmonics`` and ``free``, which its line counts."""

    #: c, what χ²/dof is on average when the model is right (1: χ² taken as it is).
    chi2_correction: float = 1.0
    #: The identified parameters the trials leave undetermined (none said).
    undetermined: tuple[str, ...] = ()
    #: What an imprecise verdict says pinned its parameters not.
    _pinned_by = "by these trials"

    @property
    def noise_ratio(self) -> float:
        """√(χ²/(c·dof)), c = ``chi2_correction``: 1 when the model explains the sway as
        well as its noise allows."""
        return math.sqrt(self.chi2 / self.chi2_correction / max(self.dof, 1))

    @property
    def consistent(self) -> bool:
        """χ²/c within its 99th percentile for ``dof`` degrees of freedom."""
        from scipy.stats import chi2

        return self.chi2 / self.chi2_correction <= chi2.ppf(0.99, max(self.dof, 1))

    @property
    def unpinned(self) -> tuple[str, ...]:
        """The judged parameters (each condition's, for a per-condition one) whose interval
        is wider than its pin (IC: ±10 % of the value; W: ±0.1)."""
        out = []
        for label, name, value, (low, high) in self._every_interval():
            pin = self.pins.get(name)
            if pin is None:
                continue
            width = pin if name in self.absolute_pins else pin * abs(value)
            if (high - low) / 2 > width:
                out.append(label)
        return tuple(out)

    @property
    def trust_level(self) -> TrustLevel:
        """The trust verdict's level, as for every answer (docs/identify.md, "Trust"):
        doubtful (a residual beyond the noise, a judged parameter on a search bound, a
        model that does not balance), imprecise (consistent, but a judged parameter not
        pinned or left undetermined), or good."""
        if not self.consistent or self.on_bound or not self.stable:
            return TrustLevel.DOUBTFUL
        return (TrustLevel.IMPRECISE if self.unpinned or self.undetermined
                else TrustLevel.GOOD)

    def verdict_line(self) -> str:
        """One line: the trust level and why."""
        if self.trust_level is TrustLevel.DOUBTFUL:
            why = ([f"residual {self.noise_ratio:.2f}× the noise"] if not self.consistent
                   else []) + ([f"on a search bound: {', '.join(self.on_bound)}"]
                               if self.on_bound else []) + (
                [] if self.stable else ["a condition's model does not balance"])
            return f"trust: DOUBTFUL: {'; '.join(why)}"
        if self.trust_level is TrustLevel.IMPRECISE and self.undetermined:
            return (f"trust: imprecise: {', '.join(self.undetermined)} not determined by "
                    f"this recording ({2 * self.harmonics} numbers compared for "
                    f"{len(self.free)} parameters; its interval is its whole search range): "
                    "fit the trials of several frequencies or conditions at once "
                    "(posture-id fit TRIAL TRIAL ...)")
        if self.trust_level is TrustLevel.IMPRECISE:
            return (f"trust: imprecise: {', '.join(self.unpinned)} not pinned "
                    f"{self._pinned_by}; the intervals give the precision")
        return "trust: good"

    def _interval_line(self, name: str, value: float, low: float, high: float) -> str:
        """A summary's line of one parameter: its value and its interval."""
        how = "calibrated " if name in self.calibrated else ""
        return (f"  {name:<24} {value:10.4g}   {100 * self.level:.0f} % {how}interval "
                f"{low:.4g} – {high:.4g}")

    # what a comparison and a cohort read of a fit (posture_id.models.protocol.ModelFit)
    @property
    def fitted_com_deg(self):
        """The model's COM sway, degrees: (S,), or per trial (S_t,)."""
        return self.fitted_deg

    def comparison_dict(self) -> dict:
        """What a comparison reads of the fit: its JSON."""
        return self.to_dict()


@dataclass(frozen=True)
class FrequencyFitResult(FitVerdict, Result):
    """A model fitted in the frequency domain (the IC fit).

    Attributes:
        parameters: the identified parameters (SI units). free: what was identified.
        intervals: {name: (low, high)} at ``level`` for each identified parameter (SI).
        chi2: the weighted residual's squared norm (χ², in units of the noise).
        dof: its degrees of freedom (2·harmonics − identified parameters).
        harmonics: K, the locked harmonics compared. on_bound: identified parameters on
        a search bound. stable: the closed loop settles. seconds: the fit's time.
        explained: share of the recorded locked COM sway the model explains.
        fitted_deg: (S,) the model's COM sway, degrees. recorded_deg: (S,) the recording's.
        frequencies_hz, recorded_frf, model_frf: (K,) the locked FRF of the COM sway and
        the model's at the compared harmonics (tilt → sway, complex).
        model: the model fitted (default the IC model).
    """

    parameters: ModelParameters
    free: tuple[str, ...]
    intervals: dict
    level: float
    chi2: float
    dof: int
    harmonics: int
    on_bound: tuple[str, ...]
    stable: bool
    seconds: float
    explained: float
    fitted_deg: np.ndarray = field(repr=False)
    recorded_deg: np.ndarray = field(repr=False)
    frequencies_hz: np.ndarray = field(repr=False)
    recorded_frf: np.ndarray = field(repr=False)
    model_frf: np.ndarray = field(repr=False)
    coherence: np.ndarray = field(repr=False)
    name: str = "recording"
    standard_errors: dict = field(default_factory=dict)
    calibrated: tuple[str, ...] = ()
    model: FrequencyModel = IC

    _pinned_by = "to 10 % by this recording"

    @property
    def pins(self) -> Mapping[str, float]:
        """The model's judged parameters (IC: Kp, Kd, Δ and W) with their pins."""
        return self.model.pinned

    @property
    def absolute_pins(self) -> frozenset[str]:
        return self.model.absolute_pins

    def _every_interval(self):
        """(label, name, value, (low, high)) of every judged parameter identified."""
        for name in self.model.pinned:
            if name in self.intervals:
                yield name, name, getattr(self.parameters, name), self.intervals[name]

    @property
    def undetermined(self) -> tuple[str, ...]:
        """The identified parameters the recording leaves undetermined (fewer numbers
        compared than parameters, or parameters that trade off exactly): their interval
        is their whole search range."""
        return tuple(n for n in self.free
                     if not math.isfinite(self.standard_errors.get(n, 0.0)))

    @property
    def identified_count(self) -> int:
        return len(self.free)

    @property
    def falls(self) -> bool:
        return not bool(np.all(np.isfinite(self.fitted_deg)))

    def to_dict(self) -> dict:
        from posture_id.provenance import provenance

        return {"model": self.model.name, "parameters": self.parameters.to_dict(),
                "identified": list(self.free),
                "intervals": {k: list(v) for k, v in self.intervals.items()},
                "level": self.level, "calibrated": list(self.calibrated),
                "standard_errors": self.standard_errors,
                "chi2": self.chi2, "dof": self.dof,
                "noise_ratio": self.noise_ratio, "consistent": self.consistent,
                "harmonics": self.harmonics, "on_bound": list(self.on_bound),
                "trust": {"level": self.trust_level.value,
                          "doubtful": self.trust_level is TrustLevel.DOUBTFUL,
                          "unpinned": list(self.unpinned), "line": self.verdict_line()},
                "stable": self.stable, "explained": self.explained,
                "seconds": self.seconds, "recording": self.name,
                "provenance": provenance()}

    def summary(self) -> str:
        p = self.parameters
        lines = [p.summary(), f"{self.harmonics} locked harmonics up to "
                 f"{self.frequencies_hz.max():.2f} Hz; residual {self.noise_ratio:.2f}× the "
                 f"noise ({'consistent with' if self.consistent else 'beyond'} it); explains "
                 f"{100 * self.explained:.1f} % of the locked COM sway; {self.seconds:.2f} s"]
        for name in self.free:
            lines.append(self._interval_line(name, getattr(p, name), *self.intervals[name]))
        lines.append(self.verdict_line())
        return "\n".join(lines)

    def plot(self, path=None, ax=None):
        """The recording's locked FRF of the COM sway, the fitted model's over it."""
        from posture_id.plotting import plot_model_frfs

        label = self.model.label
        return plot_model_frfs(self.frequencies_hz, self.recorded_frf,
                               {f"{label} model": self.model_frf}, self.coherence,
                               f"{label} fit of {self.name}: residual {self.noise_ratio:.2f}× "
                               "the noise", path=path, ax=ax)


def locked_projection(trial: PreparedTrial, sway: np.ndarray, locked: LockedOptions
                      ) -> LockedProjection:
    """The projection of a trial's sway (S, M) onto its locked harmonics
    (:class:`~posture_id.frf.locked.LockedProjection`), analysed cycle by cycle of its
    stimulus; a stimulus that excites one harmonic only (a sinusoid), over several of its
    cycles at once (:func:`analysis_cycles`), so that its noise is estimated on both sides
    of the stimulated frequency."""
    rec, stimulus = trial.recording, trial.stimulus
    one = LockedProjection.for_stimulus(stimulus, rec.tilt, sway, rec.sample_rate_hz, locked,
                                        trial.name)
    together = analysis_cycles(one, locked)
    if together == 1:
        return one
    return LockedProjection.for_recording(rec.tilt, sway, rec.sample_rate_hz,
                                          together * stimulus.period_s,
                                          stimulus.periodic_from_s, locked, trial.name,
                                          None if stimulus.cycles is None
                                          else stimulus.cycles // together,
                                          stimulus.frequencies_hz)


def analysis_cycles(projection: LockedProjection, locked: LockedOptions) -> int:
    """How many stimulus cycles one analysed cycle spans: 1, but for a stimulus that
    excites one harmonic only (a sinusoid, with no cycles skipped). Its harmonic is the
    cycle's first, so every harmonic left empty, whose sway estimates the noise, lies
    above it, where sway is weaker: the noise was underestimated (at 0.4 Hz by a factor of
    about 7 in amplitude on people-like IC sway, docs/fit.md). Analysed over m cycles at
    once, the stimulus is harmonic m and the empty ones lie on both sides: m is half the
    cycles (two analysed cycles, the drift still removed) where that leaves at least
    ``neighbours`` empty harmonics below it, else every cycle (one analysed cycle, only
    the offset removed)."""
    if len(projection.harmonics) != 1 or locked.skip_cycles:
        return 1
    half = projection.cycles // 2
    return half if half >= locked.neighbours + 1 else projection.cycles


class LockedCom:
    """One recording's stimulus-locked body COM sway: its projection onto the locked
    harmonics (:class:`~posture_id.frf.locked.LockedProjection`), the sway (S,) degrees,
    the weights (K,) 1/σ of the compared harmonics and their recorded values (K,) complex,
    degrees. What every fit of the COM sway compares and its FRF plots."""

    def __init__(self, trial: PreparedTrial, body, locked: LockedOptions,
                 label: str = "the fit") -> None:
        if trial.stimulus.period_s is None:
            raise PostureIdError(f"{trial.name}: {label} compares "
                                 "stimulus-locked harmonics and needs a periodic stimulus (a "
                                 "PRTS or a protocol)")
        self.trial = trial
        self.sway = com_sway_deg(trial, body)
        self.projection = locked_projection(trial, self.sway[:, None], locked)
        self.weights = 1.0 / self.projection.noise[:, 0]
        self.recorded = self.projection.spectrum(self.sway[:, None])[:, 0]

    @property
    def tilt_spectrum(self) -> np.ndarray:
        """(K,) complex: the tilt's (degrees) at the compared harmonics."""
        tilt_deg = np.degrees(self.trial.recording.tilt)
        return self.projection.spectrum(tilt_deg[:, None])[:, 0]

    def frf(self, sway_deg: np.ndarray | None = None) -> np.ndarray:
        """(K,) complex, tilt → COM sway at the compared harmonics: the recording's, or
        that of ``sway_deg`` (S,) degrees (a fitted model's) on the same tilt."""
        spectrum = (self.recorded if sway_deg is None
                    else self.projection.spectrum(np.asarray(sway_deg)[:, None])[:, 0])
        return spectrum / self.tilt_spectrum

    def explained(self, fitted_deg: np.ndarray) -> float:
        """The share of the recorded locked COM sway ``fitted_deg`` (S,) explains."""
        return float(self.projection.explained(self.sway[:, None], fitted_deg[:, None])[0])

    def coherence(self) -> np.ndarray:
        """(K,) the share of the sway's power at each compared harmonic that is locked to
        the stimulus (its locked power over locked plus noise power; 1 without noise)."""
        locked = np.abs(self.recorded) ** 2
        noise = 2 * self.projection.noise[:, 0] ** 2
        return locked / (locked + noise)


class _Part(LockedCom):
    """One recording's share of a fit: its locked COM-sway harmonics, their noise and
    the model's response on its tilt."""

    def __init__(self, model: FrequencyModel, trial: PreparedTrial, body, plant,
                 locked: LockedOptions) -> None:
        super().__init__(trial, body, locked, f"the {model.label} fit")
        rec = trial.recording
        self.model = ExactResponse(model, rec.tilt, rec.sample_rate_hz, plant)
        weighted = self.recorded * self.weights
        self.target = np.concatenate([weighted.real, weighted.imag])

    def reweighted(self, fitted_deg: np.ndarray, neighbours: int) -> None:
        """Estimate the noise again from what ``fitted_deg`` (S,), a fitted model's sway,
        leaves of the recording at the harmonics the stimulus leaves empty (the model's own
        transient is not noise), and weight the compared harmonics by it."""
        projection = self.projection
        residual = (self.sway - fitted_deg)[:, None]
        power = np.abs(projection.all_harmonics(residual)) ** 2
        noise = floored(noise_levels(power, projection.excited, projection.harmonics - 1,
                                     neighbours))[:, 0]
        self.weights = 1.0 / noise
        weighted = self.recorded * self.weights
        self.target = np.concatenate([weighted.real, weighted.imag])

    def weighted(self, y: np.ndarray) -> np.ndarray:
        """(2K, ...) real: the compared harmonics of y (S, ...) ÷ the noise."""
        w = self.weights if y.ndim == 1 else self.weights[:, None]
        spectrum = self.projection.spectrum(y) * w
        return np.concatenate([spectrum.real, spectrum.imag])


@dataclass(frozen=True)
class ConditionLayout:
    """Where each part's parameters sit in the search vector x of a fit of several parts
    grouped into conditions: x holds every identified parameter once (``free``, in the
    model's order; a per-condition one there is the first condition's value), then, for
    every further condition, its ``per_condition`` parameters in turn.

    Attributes:
        free: the identified parameters, in the model's ``parameter_order``.
        per_condition: those that take one value per condition (in ``free``'s order).
        conditions: (parts,) the condition index 0..C−1 of each part.
    """

    free: tuple[str, ...]
    per_condition: tuple[str, ...]
    conditions: tuple[int, ...]

    @classmethod
    def of(cls, free: tuple[str, ...], per_condition, conditions, name: str
           ) -> ConditionLayout:
        """The layout; ``per_condition`` is put in ``free``'s order.

        Raises:
            PostureIdError: a per-condition parameter that is not identified (naming
                ``name``).
        """
        missing = [n for n in per_condition if n not in free]
        if missing:
            raise PostureIdError(f"{name}: per-condition parameter(s) {', '.join(missing)} "
                                 f"not identified (identified: {', '.join(free)})")
        return cls(tuple(free), tuple(n for n in free if n in per_condition),
                   tuple(int(c) for c in conditions))

    @property
    def count(self) -> int:
        """C, the conditions."""
        return max(self.conditions) + 1

    @property
    def names(self) -> tuple[str, ...]:
        """(X,) the parameter each entry of x stands for."""
        return self.free + self.per_condition * (self.count - 1)

    def index(self, condition: int, name: str) -> int:
        """The entry of x holding ``name``'s value in ``condition``."""
        if condition == 0 or name not in self.per_condition:
            return self.free.index(name)
        return (len(self.free) + (condition - 1) * len(self.per_condition)
                + self.per_condition.index(name))

    def entries(self, condition: int) -> list[int]:
        """(len(free),) the entries of x of ``condition``'s parameters, in ``free``'s
        order."""
        return [self.index(condition, n) for n in self.free]


@dataclass(frozen=True)
class _Search:
    """The best start: x (normalised), its scipy result, each part's parameters."""

    x: np.ndarray
    fit: object
    params: tuple
    names: tuple[str, ...]


def _search(model: FrequencyModel, parts: list[_Part], layout: ConditionLayout, plant,
            options: FrequencyFitOptions, name: str, first: np.ndarray | None = None
            ) -> _Search:
    """Multi-start bounded least squares over x (:class:`ConditionLayout`): every part's
    residual stacked, each part with its condition's parameters. The first start is
    ``first`` (search units) when given, else the model's typical values. Returns the best
    start; its ``params`` are per condition."""
    from scipy.optimize import least_squares
    from scipy.stats import chi2 as chi2_distribution

    order = model.parameter_order
    free, names = layout.free, layout.names
    entries = [layout.entries(c) for c in range(layout.count)]
    columns = [order.index(n) for n in free]
    scales = np.array([model.scale(n, plant) for n in free])
    fixed = model.search_start(plant)
    target = np.concatenate([p.target for p in parts])

    def conditions_of(x: np.ndarray) -> list:
        return [model.with_values(fixed, {n: float(x[i]) * model.scale(n, plant)
                                          for n, i in zip(free, index, strict=True)})
                for index in entries]

    def params_of(x: np.ndarray) -> list:
        each = conditions_of(x)
        return [each[c] for c in layout.conditions]

    def residual(x: np.ndarray) -> np.ndarray:
        return np.concatenate([p.weighted(np.degrees(p.model.sway(q)))
                               for p, q in zip(parts, params_of(x), strict=True)]) - target

    def jacobian(x: np.ndarray) -> np.ndarray:
        blocks = []
        for p, q, c in zip(parts, params_of(x), layout.conditions, strict=True):
            _, dy = p.model.sway(q, gradient=True)
            d = np.zeros((len(dy[0]), len(names)))
            d[:, entries[c]] = np.degrees(dy[columns]).T * scales[None, :]
            blocks.append(p.weighted(d))
        return np.vstack(blocks)

    low = np.array([model.search_bounds[n][0] for n in names])
    high = np.array([model.search_bounds[n][1] for n in names])
    rng = np.random.default_rng(options.seed)
    starts = [np.array([model.typical[n] for n in names]) if first is None
              else np.clip(first, low, high)]
    for _ in range(options.starts - 1):
        starts.append(low + (high - low) * rng.uniform(0.1, 0.9, len(names)))
    enough = float(chi2_distribution.ppf(0.99, max(len(target) - len(names), 1)))
    stable = [x0 for x0 in starts
              if all(model.is_stable(q, plant) for q in conditions_of(x0))]

    def barred(x: np.ndarray) -> np.ndarray:
        """The residual, far beyond any stable loop's where the loop is unstable: the
        trust region steps back from it."""
        if all(model.is_stable(q, plant) for q in conditions_of(x)):
            return residual(x)
        return np.full(len(target), 1e3 * (1.0 + float(np.linalg.norm(target))))

    best = None
    # first every start free to pass through unstable loops; where every one ended on an
    # unstable loop, the stable starts again with unstable loops barred
    for function, tries in ((residual, starts), (barred, stable)):
        for x0 in tries:
            try:
                fit = least_squares(function, x0, jac=jacobian, bounds=(low, high),
                                    method="trf", x_scale="jac", max_nfev=200)
            except (ValueError, FloatingPointError):
                continue
            if not np.all(np.isfinite(fit.fun)) or not all(model.is_stable(q, plant)
                                                            for q in conditions_of(fit.x)):
                continue
            if best is None or fit.cost < best.cost:
                best = fit
            if 2 * best.cost <= enough:  # as close as the noise allows: no start does better
                break
        if best is not None:
            break
    if best is None:  # every search ran off to an unstable loop: the best stable start
        if not stable:
            raise PostureIdError(f"{name}: no {model.label} model with a stable closed loop "
                                 "fits this recording within its search bounds")
        x0 = min(stable, key=lambda x: float(np.sum(residual(x) ** 2)))
        best = _StartOnly(x0, residual(x0), jacobian(x0))
    return _Search(best.x, best, tuple(conditions_of(best.x)), names)


@dataclass(frozen=True)
class Precision:
    """The intervals of a least-squares answer (the module doc).

    Attributes:
        standard_errors: (X,) SI units: Gauss-Newton, the covariance (JᵀJ)⁻¹ of the
            weighted residual scaled by χ²/dof where that exceeds 1.
        multipliers: (X,) what a ``level`` interval multiplies each by (the model's).
        calibrated: (X,) whether that multiplier is calibrated.
    """

    standard_errors: np.ndarray
    multipliers: np.ndarray
    calibrated: tuple[bool, ...]

    @classmethod
    def of(cls, model: FrequencyModel, plant, names: tuple[str, ...], jac: np.ndarray,
           chi2: float, dof: int, level: float, multiplier=None) -> Precision:
        """For x's entries standing for ``names`` (search units), from the Jacobian
        (R, X) of the weighted residual at the answer; ``multiplier(name, level)`` gives
        (multiplier, calibrated) (default: the model's ``interval_multiplier``)."""
        scales = np.array([model.scale(n, plant) for n in names])
        standard_errors = gauss_newton_errors(jac, chi2, dof) * scales
        # a direction the residual does not change along (fewer numbers compared than
        # parameters, or parameters that trade off exactly) has no finite variance: the
        # pseudo-inverse would give it none at all
        standard_errors[undetermined(jac)] = np.inf
        multipliers = [(multiplier or model.interval_multiplier)(n, level) for n in names]
        return cls(standard_errors, np.array([m for m, _ in multipliers]),
                   tuple(c for _, c in multipliers))

    @property
    def half_widths(self) -> np.ndarray:
        """(X,) SI units: each interval's half-width."""
        return self.multipliers * self.standard_errors


def gauss_newton_errors(jac: np.ndarray, chi2: float, dof: int) -> np.ndarray:
    """(X,) the standard errors of x (its units) from the Jacobian (R, X) of the weighted
    residual at the answer: √diag of (JᵀJ)⁺ scaled by χ²/dof where that exceeds 1 (inf
    where the pseudo-inverse fails)."""
    try:
        cov = np.linalg.pinv(jac.T @ jac) * max(1.0, chi2 / max(dof, 1))
    except np.linalg.LinAlgError:
        cov = np.full((jac.shape[1], jac.shape[1]), np.inf)
    return np.sqrt(np.clip(np.diag(cov), 0, None))


def undetermined(jac: np.ndarray, tolerance: float = 1e-10) -> np.ndarray:
    """(X,) bool: the parameters (columns of the Jacobian (R, X)) with a share in its
    null space: their value can change, with others, and leave the residual as it is
    (fewer rows than columns, or columns that are combinations of others, singular values
    below ``tolerance`` of the largest)."""
    jac = np.asarray(jac, dtype=float)
    if not jac.size or not np.all(np.isfinite(jac)):
        return np.zeros(jac.shape[1] if jac.ndim == 2 else 0, dtype=bool)
    _, singular, vt = np.linalg.svd(jac, full_matrices=True)
    rank = int(np.count_nonzero(singular > tolerance * max(float(singular.max()), 1e-300)))
    null = vt[rank:]
    return np.any(np.abs(null) > 1e-3, axis=0) if len(null) else np.zeros(jac.shape[1],
                                                                        dtype=bool)


def interval_bounds(values: dict, half: dict, ranges) -> dict:
    """{name: (low, high)}: value ± half-width, not below 0; the whole search range
    (``ranges``: {name: (low, high)}, SI) where the half-width is 0 or not finite: the
    recordings leave that parameter undetermined (:func:`undetermined`)."""
    out = {}
    for n, value in values.items():
        low, high = ranges[n]
        if not math.isfinite(half[n]) or half[n] <= 1e-9 * (high - low):
            out[n] = (float(low), float(high))
        else:
            out[n] = (max(value - half[n], 0.0), value + half[n])
    return out


def search_ranges(model: FrequencyModel, plant) -> dict:
    """{name: (low, high)}: every parameter's search range in SI units."""
    return {n: (lo * model.scale(n, plant), hi * model.scale(n, plant))
            for n, (lo, hi) in model.search_bounds.items()}


def on_search_bound(model: FrequencyModel, names: tuple[str, ...], x: np.ndarray
                    ) -> list[int]:
    """The entries of x (search units) of a judged parameter (the model's ``pinned``) whose
    search range starts above 0 that end within 0.1 % of the range of a bound."""
    out = []
    for k, (n, value) in enumerate(zip(names, x, strict=True)):
        lo, hi = model.search_bounds[n]
        span = hi - lo
        if n in model.pinned and lo > 0 and (value - lo < 1e-3 * span
                                             or hi - value < 1e-3 * span):
            out.append(k)
    return out


class _StartOnly:
    """A start kept as the answer (scipy's result's fields), its residual far beyond the
    noise: the verdict says doubtful."""

    def __init__(self, x: np.ndarray, fun: np.ndarray, jac: np.ndarray) -> None:
        self.x, self.fun, self.jac = x, fun, jac
        self.cost = 0.5 * float(fun @ fun)


def fit_frequency(model: FrequencyModel, trial: PreparedTrial, body,
                  options: FrequencyFitOptions | None = None) -> FrequencyFitResult:
    """The parameters of ``model`` that explain ``trial``'s body COM sway (the module doc).

    Args:
        model: a model with a closed loop (:class:`~posture_id.models.protocol.FrequencyModel`).
        trial: the recording with its periodic stimulus (a :class:`PreparedTrial`).
        body: the recorded body.
        options: what is identified, the starts, the locked harmonics and the intervals'
            level (default :class:`FrequencyFitOptions`).
    Returns:
        :class:`FrequencyFitResult`: the parameters (SI units), their intervals and the fit.
    Raises:
        PostureIdError: a stimulus that is not periodic (no locked harmonics), or no start
            that gives a stable closed loop.
    """
    options = options or FrequencyFitOptions()
    started = clock.perf_counter()
    joint = search_conditions(model, [trial], body, [0], (), options)
    part, free, found, plant = joint.parts[0], joint.layout.free, joint.found, joint.plant
    params, best = found.params[0], found.fit
    chi2 = float(2 * best.cost)
    dof = len(part.target) - len(free)
    precision = Precision.of(model, plant, free, best.jac, chi2, dof, options.level)
    intervals = interval_bounds({n: getattr(params, n) for n in free},
                                dict(zip(free, precision.half_widths, strict=True)),
                                search_ranges(model, plant))
    on_bound = tuple(free[k] for k in on_search_bound(model, free, found.x))
    fitted = np.degrees(part.model.sway(params))
    projection, sway = part.projection, part.sway
    model_frf = model.closed_loop(params, plant, 2j * np.pi * projection.frequencies_hz)
    return FrequencyFitResult(params, free, intervals, options.level, chi2, dof,
                              len(projection.harmonics), on_bound, True,
                              clock.perf_counter() - started, part.explained(fitted), fitted,
                              sway, projection.frequencies_hz, part.frf(), model_frf,
                              part.coherence(), trial.name,
                              dict(zip(free, precision.standard_errors.tolist(), strict=True)),
                              tuple(n for n, c in zip(free, precision.calibrated, strict=True)
                                    if c), model)


def fit_ic(trial: PreparedTrial, body: Body, options: IcFitOptions | None = None
           ) -> FrequencyFitResult:
    """The IC parameters of ``trial``'s body COM sway: :func:`fit_frequency` of the IC
    model.

    Args:
        trial: the recording with its periodic stimulus (a :class:`PreparedTrial`).
        body: the recorded body, turning as one about the ankle.
        options: what is identified and how (default :class:`IcFitOptions`: Ki and the
            passive terms held at 0).
    Returns:
        :class:`FrequencyFitResult`: the parameters (SI units), their intervals and the fit.
    """
    return fit_frequency(IC, trial, body, options or IcFitOptions())


@dataclass(frozen=True)
class ConditionSearch:
    """A search of several trials grouped into conditions (:func:`search_conditions`).

    Attributes:
        parts: (T,) each trial's locked harmonics, weights and model response.
        layout: where each condition's parameters sit in x. found: the best start (its x
        in search units, scipy's result with the Jacobian, ``params`` per condition).
        plant: what the closed loop needs of the body.
    """

    parts: list
    layout: ConditionLayout
    found: _Search
    plant: object


def search_conditions(model: FrequencyModel, trials: list[PreparedTrial], body,
                      conditions: list[int], per_condition: tuple[str, ...],
                      options: FrequencyFitOptions, noise_from_residual: bool = False
                      ) -> ConditionSearch:
    """The multi-start search over every trial at once, each with its condition's
    parameters (``conditions``: (T,) indices 0..C−1; ``per_condition``: the parameters
    that take one value per condition, the rest of the identified ones shared). With
    ``noise_from_residual``, the noise at each harmonic is estimated again from what the
    first answer leaves of every trial (:meth:`_Part.reweighted`) and the search is run
    again from that answer.

    Raises:
        PostureIdError: a stimulus that is not periodic, a per-condition parameter that is
            not identified, no start that gives a stable closed loop.
    """
    plant = model.plant(body)
    parts = [_Part(model, t, body, plant, options.locked) for t in trials]
    name = " + ".join(t.name for t in trials)
    layout = ConditionLayout.of(options.free_of(model), per_condition, conditions, name)
    found = _search(model, parts, layout, plant, options, name)
    if noise_from_residual:
        for part, c in zip(parts, layout.conditions, strict=True):
            part.reweighted(np.degrees(part.model.sway(found.params[c])),
                            options.locked.neighbours)
        found = _search(model, parts, layout, plant, replace(options, starts=1), name,
                        first=found.x)
    return ConditionSearch(parts, layout, found, plant)
