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
whose closed loop is unstable is never returned (the model's ``is_stable``).

Intervals: Gauss-Newton standard errors, the covariance (JᵀJ)⁻¹ of the weighted residual
scaled by its χ² per degree of freedom where that exceeds 1, times the model's multiplier
per parameter and level (the IC model's calibrated on recordings the project simulated:
:mod:`posture_id.models.ic.model`; without a calibration, the normal quantile).
"""

from __future__ import annotations

import math
import time as clock
from dataclasses import dataclass, field

import numpy as np

from posture_id.errors import PostureIdError
from posture_id.fileio import Result
from posture_id.frf.locked import LockedOptions, LockedProjection
from posture_id.models.dec import com_deg
from posture_id.models.exact import ExactResponse
from posture_id.models.ic.model import IC
from posture_id.models.protocol import FrequencyModel, ModelParameters, TrustLevel
from posture_id.trials import PreparedTrial

__all__ = ["FrequencyFitOptions", "IcFitOptions", "FrequencyFitResult", "fit_frequency",
           "fit_ic", "com_sway_deg", "FrequencyPartsFit", "fit_frequency_parts",
           "fit_ic_parts"]


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


@dataclass(frozen=True)
class FrequencyFitResult(Result):
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

    @property
    def noise_ratio(self) -> float:
        """√(χ²/dof): 1 when the model explains the recording as well as its noise allows."""
        return math.sqrt(self.chi2 / max(self.dof, 1))

    @property
    def consistent(self) -> bool:
        """χ² within its 99th percentile for ``dof`` degrees of freedom."""
        from scipy.stats import chi2

        return self.chi2 <= chi2.ppf(0.99, max(self.dof, 1))

    @property
    def unpinned(self) -> tuple[str, ...]:
        """The model's judged parameters (IC: Kp, Kd, Δ and W) whose interval is wider
        than its pin (IC: ±10 % of the value; W: ±0.1)."""
        out = []
        for name, pin in self.model.pinned.items():
            if name not in self.intervals:
                continue
            low, high = self.intervals[name]
            width = pin if name in self.model.absolute_pins \
                else pin * abs(getattr(self.parameters, name))
            if (high - low) / 2 > width:
                out.append(name)
        return tuple(out)

    @property
    def trust_level(self) -> TrustLevel:
        """The trust verdict's level, as for every answer (docs/identify.md, "Trust"):
        doubtful (a residual beyond the noise, a judged parameter on a search bound),
        imprecise (consistent, but a judged parameter not pinned), or good."""
        if not self.consistent or self.on_bound or not self.stable:
            return TrustLevel.DOUBTFUL
        return TrustLevel.IMPRECISE if self.unpinned else TrustLevel.GOOD

    def verdict_line(self) -> str:
        if self.trust_level is TrustLevel.DOUBTFUL:
            why = ([f"residual {self.noise_ratio:.2f}× the noise"] if not self.consistent
                   else []) + ([f"on a search bound: {', '.join(self.on_bound)}"]
                               if self.on_bound else [])
            return f"trust: DOUBTFUL: {'; '.join(why)}"
        if self.trust_level is TrustLevel.IMPRECISE:
            return (f"trust: imprecise: {', '.join(self.unpinned)} not pinned to 10 % by this "
                    "recording; the intervals give the precision")
        return "trust: good"

    # what a comparison and a cohort read of a fit (posture_id.models.protocol.ModelFit)
    @property
    def fitted_com_deg(self) -> np.ndarray:
        return self.fitted_deg

    @property
    def identified_count(self) -> int:
        return len(self.free)

    @property
    def falls(self) -> bool:
        return not bool(np.all(np.isfinite(self.fitted_deg)))

    def comparison_dict(self) -> dict:
        return self.to_dict()

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
            low, high = self.intervals[name]
            how = "calibrated " if name in self.calibrated else ""
            lines.append(f"  {name:<24} {getattr(p, name):10.4g}   {100 * self.level:.0f} % "
                         f"{how}interval {low:.4g} – {high:.4g}")
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


class _Part:
    """One recording's share of a fit: its locked COM-sway harmonics, their noise and
    the model's response on its tilt."""

    def __init__(self, model: FrequencyModel, trial: PreparedTrial, body, plant,
                 locked: LockedOptions) -> None:
        rec = trial.recording
        if trial.stimulus.period_s is None:
            raise PostureIdError(f"{trial.name}: the {model.label} fit compares "
                                 "stimulus-locked harmonics and needs a periodic stimulus (a "
                                 "PRTS or a protocol)")
        self.trial = trial
        self.sway = com_sway_deg(trial, body)
        self.projection = LockedProjection.for_recording(
            rec.tilt, self.sway[:, None], rec.sample_rate_hz, trial.stimulus.period_s,
            trial.stimulus.periodic_from_s, locked, trial.name)
        self.weights = 1.0 / self.projection.noise[:, 0]
        self.recorded = self.projection.spectrum(self.sway[:, None])[:, 0]
        self.model = ExactResponse(model, rec.tilt, rec.sample_rate_hz, plant)
        weighted = self.recorded * self.weights
        self.target = np.concatenate([weighted.real, weighted.imag])

    def weighted(self, y: np.ndarray) -> np.ndarray:
        """(2K, ...) real: the compared harmonics of y (S, ...) ÷ the noise."""
        w = self.weights if y.ndim == 1 else self.weights[:, None]
        spectrum = self.projection.spectrum(y) * w
        return np.concatenate([spectrum.real, spectrum.imag])


@dataclass(frozen=True)
class _Search:
    """The best start: x (normalised), its scipy result, each part's parameters."""

    x: np.ndarray
    fit: object
    params: tuple
    names: tuple[str, ...]


def _search(model: FrequencyModel, parts: list[_Part], free: tuple[str, ...], plant,
            options: FrequencyFitOptions, name: str) -> _Search:
    """Multi-start bounded least squares over ``free`` (shared by every part) and, with
    several parts, one of the model's ``per_part`` parameter per part after the first (the
    first part's is in ``free``)."""
    from scipy.optimize import least_squares
    from scipy.stats import chi2 as chi2_distribution

    order = model.parameter_order
    per_part = model.per_part
    if len(parts) > 1 and per_part not in free:
        raise PostureIdError(f"{name}: fitting parts at once needs {per_part} identified")
    names = tuple(free) + (per_part,) * (len(parts) - 1)
    part_index = ([free.index(per_part)] + list(range(len(free), len(names)))
                  if per_part in free else [None] * len(parts))
    columns = [order.index(n) for n in free]
    scales = np.array([model.scale(n, plant) for n in free])
    fixed = model.search_start(plant)
    target = np.concatenate([p.target for p in parts])

    def params_of(x: np.ndarray) -> list:
        shared = model.with_values(fixed, {n: float(v) * model.scale(n, plant)
                                           for n, v in zip(free, x[: len(free)], strict=True)})
        if part_index[0] is None:
            return [shared] * len(parts)
        return [model.with_values(shared, {per_part: float(x[i]) * model.scale(per_part,
                                                                                plant)})
                for i in part_index]

    def residual(x: np.ndarray) -> np.ndarray:
        return np.concatenate([p.weighted(np.degrees(p.model.sway(q)))
                               for p, q in zip(parts, params_of(x), strict=True)]) - target

    def jacobian(x: np.ndarray) -> np.ndarray:
        blocks = []
        for k, (p, q) in enumerate(zip(parts, params_of(x), strict=True)):
            _, dy = p.model.sway(q, gradient=True)
            d = np.zeros((len(dy[0]), len(names)))
            d[:, : len(free)] = np.degrees(dy[columns]).T * scales[None, :]
            if part_index[k] is not None:
                column = order.index(per_part)
                d[:, free.index(per_part)] = 0.0
                d[:, part_index[k]] = np.degrees(dy[column]) * model.scale(per_part, plant)
            blocks.append(p.weighted(d))
        return np.vstack(blocks)

    low = np.array([model.search_bounds[n][0] for n in names])
    high = np.array([model.search_bounds[n][1] for n in names])
    rng = np.random.default_rng(options.seed)
    starts = [np.array([model.typical[n] for n in names])]
    for _ in range(options.starts - 1):
        starts.append(low + (high - low) * rng.uniform(0.1, 0.9, len(names)))
    enough = float(chi2_distribution.ppf(0.99, max(len(target) - len(names), 1)))
    best = None
    for x0 in starts:
        try:
            fit = least_squares(residual, x0, jac=jacobian, bounds=(low, high),
                                method="trf", x_scale="jac", max_nfev=200)
        except (ValueError, FloatingPointError):
            continue
        if not np.all(np.isfinite(fit.fun)) or not all(model.is_stable(q, plant)
                                                        for q in params_of(fit.x)):
            continue
        if best is None or fit.cost < best.cost:
            best = fit
        if 2 * best.cost <= enough:  # as close as the noise allows: no start does better
            break
    if best is None:  # every search ran off to an unstable loop: the best stable start
        stable = [x0 for x0 in starts
                  if all(model.is_stable(q, plant) for q in params_of(x0))]
        if not stable:
            raise PostureIdError(f"{name}: no {model.label} model with a stable closed loop "
                                 "fits this recording within its search bounds")
        x0 = min(stable, key=lambda x: float(np.sum(residual(x) ** 2)))
        best = _StartOnly(x0, residual(x0), jacobian(x0))
    return _Search(best.x, best, tuple(params_of(best.x)), names)


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
    plant = model.plant(body)
    part = _Part(model, trial, body, plant, options.locked)
    free = options.free_of(model)
    found = _search(model, [part], free, plant, options, trial.name)
    params, best = found.params[0], found.fit
    chi2 = float(2 * best.cost)
    dof = len(part.target) - len(free)
    jac = best.jac
    scale2 = max(1.0, chi2 / max(dof, 1))
    try:
        cov = np.linalg.pinv(jac.T @ jac) * scale2
    except np.linalg.LinAlgError:
        cov = np.full((len(free), len(free)), np.inf)
    scales = np.array([model.scale(n, plant) for n in free])
    standard_errors = np.sqrt(np.clip(np.diag(cov), 0, None)) * scales
    multipliers = [model.interval_multiplier(n, options.level) for n in free]
    half = np.array([m for m, _ in multipliers]) * standard_errors
    intervals = {n: (max(getattr(params, n) - h, 0.0), getattr(params, n) + h)
                 for n, h in zip(free, half, strict=True)}
    low = np.array([model.search_bounds[n][0] for n in free])
    high = np.array([model.search_bounds[n][1] for n in free])
    span = high - low
    on_bound = tuple(n for n, x, lo, hi, sp in zip(free, found.x, low, high, span, strict=True)
                     if n in model.pinned and lo > 0
                     and (x - lo < 1e-3 * sp or hi - x < 1e-3 * sp))
    fitted = np.degrees(part.model.sway(params))
    projection, sway = part.projection, part.sway
    explained = float(projection.explained(sway[:, None], fitted[:, None])[0])
    tilt_deg = np.degrees(trial.recording.tilt)
    u = projection.spectrum(tilt_deg[:, None])[:, 0]
    model_frf = model.closed_loop(params, plant, 2j * np.pi * projection.frequencies_hz)
    coherence = _coherence(projection, sway)
    return FrequencyFitResult(params, free, intervals, options.level, chi2, dof,
                              len(projection.harmonics), on_bound, True,
                              clock.perf_counter() - started, explained, fitted, sway,
                              projection.frequencies_hz, part.recorded / u, model_frf,
                              coherence, trial.name,
                              dict(zip(free, standard_errors.tolist(), strict=True)),
                              tuple(n for n, (_, c) in zip(free, multipliers, strict=True)
                                    if c), model)


def fit_ic(trial: PreparedTrial, body, options: IcFitOptions | None = None
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
class FrequencyPartsFit:
    """A model fitted to the parts of one subject's protocol at once (a two-amplitude
    protocol): every parameter shared but the model's ``per_part`` one (IC: W, sensory
    re-weighting).

    Attributes:
        parameters: per part, its parameters (they differ in the per-part one only).
        chi2: of all parts. fitted_deg: per part, the model's COM sway (S_p,) degrees.
        identified_count: the parameters identified over every part.
    """

    parameters: tuple
    chi2: float
    fitted_deg: tuple[np.ndarray, ...]
    identified_count: int = 0
    model: FrequencyModel = IC

    @property
    def w_by_part(self) -> tuple[float, ...]:
        """The per-part parameter of each part (IC: W)."""
        return tuple(getattr(p, self.model.per_part) for p in self.parameters)

    @property
    def reweighting(self) -> float:
        """How far W moved between the amplitudes: the last part's W minus the first's."""
        return self.w_by_part[-1] - self.w_by_part[0]

    @property
    def fitted_com_deg(self) -> tuple[np.ndarray, ...]:
        return self.fitted_deg

    @property
    def falls(self) -> bool:
        return not all(np.all(np.isfinite(f)) for f in self.fitted_deg)

    def comparison_dict(self) -> dict:
        return {"parameters": [p.to_dict() for p in self.parameters],
                "w_by_part": list(self.w_by_part), "reweighting": self.reweighting}


def fit_frequency_parts(model: FrequencyModel, trials: list[PreparedTrial], body,
                        options: FrequencyFitOptions | None = None) -> FrequencyPartsFit:
    """The parameters of ``model`` for every one of ``trials`` (the same subject at
    several amplitudes), shared but for the model's per-part one."""
    options = options or FrequencyFitOptions()
    plant = model.plant(body)
    parts = [_Part(model, t, body, plant, options.locked) for t in trials]
    free = options.free_of(model)
    found = _search(model, parts, free, plant, options, " + ".join(t.name for t in trials))
    fitted = tuple(np.degrees(p.model.sway(q)) for p, q in zip(parts, found.params,
                                                                strict=True))
    return FrequencyPartsFit(found.params, float(2 * found.fit.cost), fitted,
                             len(found.names), model)


def fit_ic_parts(trials: list[PreparedTrial], body,
                 options: IcFitOptions | None = None) -> FrequencyPartsFit:
    """The IC parameters of every one of ``trials``, shared but for W, one per part."""
    return fit_frequency_parts(IC, trials, body, options or IcFitOptions())


def _coherence(projection: LockedProjection, sway_deg: np.ndarray) -> np.ndarray:
    """(K,) the share of the sway's power at each compared harmonic that is locked to the
    stimulus (its locked power over locked plus noise power; 1 without noise)."""
    locked = np.abs(projection.spectrum(sway_deg[:, None])[:, 0]) ** 2
    noise = 2 * projection.noise[:, 0] ** 2
    return locked / (locked + noise)
