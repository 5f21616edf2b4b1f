"""Fit the IC model to a recording's stimulus-locked body COM sway (docs/model.md §8).

What is compared is what the locked DEC fit compares (:mod:`posture_id.frf.locked`): the
drift-free cycle average of the body COM sway at the harmonics the stimulus excites up to
2 Hz, each divided by the noise level estimated at the neighbouring harmonics it leaves
empty. The model's sway on the recording's samples is the IC response to the recorded
tilt from rest, computed exactly in the frequency domain (the tilt zero-padded far beyond
the recording's end, times H(jω), transformed back): the transient of the first cycle is
the model's own, as in a re-simulation, with no time-stepping. Its derivatives are the same
transform of dH/dp (:func:`~posture_id.ic.response.closed_loop`), so the least squares
(scipy's trust-region reflective) has the exact Jacobian. Several starts (the first at
the literature's typical values; the search stops at the first answer whose residual is
within the noise's 99th percentile); an answer
whose closed loop is unstable is never returned (:func:`~posture_id.ic.response.is_stable`).

Intervals: Gauss-Newton standard errors, the covariance (JᵀJ)⁻¹ of the weighted residual
scaled by its χ² per degree of freedom where that exceeds 1, times a calibrated multiplier
per parameter and level: the quantile of |estimate − truth| / standard error over IC
recordings the project simulated (clean and people-like; ``calibration.json`` beside this
module, made by ``benchmarks/ic_recovery.py --calibrate`` on recordings apart from those
its report checks the coverage on). Without it, the normal quantile.
"""

from __future__ import annotations

import json
import math
import time as clock
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from posture_id.errors import PostureIdError
from posture_id.fileio import Result
from posture_id.frf.locked import LockedOptions, LockedProjection
from posture_id.ic.parameters import IcParameters
from posture_id.ic.response import PARAMETER_ORDER, IcPlant, closed_loop, is_stable
from posture_id.trials import PreparedTrial

__all__ = ["IcFitOptions", "IcFitResult", "fit_ic", "IcModelResponse", "com_sway_deg",
           "BOUNDS", "IcPartsFit", "fit_ic_parts"]

#: docs/model.md §8's search bounds: (low, high) per parameter; gains in units of m·g·h (·s for
#: Kd, /s for Ki), W and G as they are, times in s.
BOUNDS = {"kp": (0.5, 4.0), "kd": (0.05, 1.0), "ki": (0.0, 0.5), "delay_s": (0.02, 0.35),
          "w": (0.0, 1.0), "torque_feedback_gain": (0.0, 0.9),
          "torque_feedback_time_s": (2.0, 100.0), "kpas": (0.0, 1.0), "bpas": (0.0, 0.5)}
#: The parameters whose unit is m·g·h (times s or per s).
_PER_MGH = ("kp", "kd", "ki", "kpas", "bpas")


@dataclass(frozen=True)
class IcFitOptions:
    """What the IC fit identifies and how.

    Attributes:
        fit_ki: also identify Ki (else 0). fit_passive: also Kpas and Bpas (else 0).
        starts: least-squares starts (the first at the literature's typical values, the
            others drawn within the bounds). seed: seeds those draws.
        locked: the locked harmonics compared (docs/model.md §8: up to 2 Hz).
        level: the intervals' nominal coverage.
    """

    fit_ki: bool = False
    fit_passive: bool = False
    starts: int = 6
    seed: int = 0
    locked: LockedOptions = field(default_factory=LockedOptions)
    level: float = 0.9

    def __post_init__(self) -> None:
        if self.starts < 1:
            raise PostureIdError(f"IC fit starts must be ≥ 1, got {self.starts}")
        if not 0.5 <= self.level <= 0.99:
            raise PostureIdError(f"IC fit level must be within 0.5–0.99, got {self.level}")

    @property
    def free(self) -> tuple[str, ...]:
        """The identified parameters, in :data:`PARAMETER_ORDER`."""
        names = ["kp", "kd", "delay_s", "w", "torque_feedback_gain", "torque_feedback_time_s"]
        if self.fit_ki:
            names.append("ki")
        if self.fit_passive:
            names += ["kpas", "bpas"]
        return tuple(n for n in PARAMETER_ORDER if n in names)


def com_deg(theta: np.ndarray, body) -> np.ndarray:
    """(S,) degrees: the body COM sway α_BS of segment angles ``theta`` (S, N) rad, from
    the body's reference posture."""
    theta = np.asarray(theta, dtype=float)
    return np.degrees(body.com_angles(theta)[:, 0] - body.reference_com_angles[0])


def com_sway_deg(trial: PreparedTrial, body) -> np.ndarray:
    """(S,) degrees: the body COM sway α_BS of a trial (:func:`com_deg`)."""
    return com_deg(trial.recording.theta, body)


class IcModelResponse:
    """The IC model's COM sway on a trial's samples (its locked harmonics), with exact
    derivatives.

    The tilt (S,) is zero-padded to L ≥ 8·S samples (a power of two) so that the circular
    convolution by H equals the linear one from rest over the recording.
    """

    def __init__(self, tilt_rad: np.ndarray, sample_rate_hz: float, plant: IcPlant) -> None:
        self.samples = len(tilt_rad)
        self.plant = plant
        length = 1 << int(math.ceil(math.log2(8 * self.samples)))
        self.tilt_spectrum = np.fft.rfft(np.asarray(tilt_rad, float), n=length)
        omega = 2 * np.pi * np.fft.rfftfreq(length, 1.0 / sample_rate_hz)
        omega[0] = 1e-6  # H(0) as its limit: the static response
        self.s = 1j * omega
        self.length = length

    def sway(self, params: IcParameters, gradient: bool = False):
        """(S,) rad of COM sway; with ``gradient``, also (9, S) d sway / dp (SI units)."""
        if not gradient:
            h = closed_loop(params, self.plant, self.s)
            return np.fft.irfft(h * self.tilt_spectrum, n=self.length)[: self.samples]
        h, dh = closed_loop(params, self.plant, self.s, gradient=True)
        both = np.vstack([h[None], dh]) * self.tilt_spectrum[None]
        out = np.fft.irfft(both, n=self.length, axis=1)[:, : self.samples]
        return out[0], out[1:]


@dataclass(frozen=True)
class IcFitResult(Result):
    """An IC fit.

    Attributes:
        parameters: the identified IC parameters (SI units). free: what was identified.
        intervals: {name: (low, high)} at ``level`` for each identified parameter (SI).
        chi2: the weighted residual's squared norm (χ², in units of the noise).
        dof: its degrees of freedom (2·harmonics − identified parameters).
        harmonics: K, the locked harmonics compared. on_bound: identified parameters on
        a search bound. stable: the closed loop settles. seconds: the fit's time.
        explained: share of the recorded locked COM sway the model explains.
        fitted_deg: (S,) the model's COM sway, degrees. recorded_deg: (S,) the recording's.
        frequencies_hz, recorded_frf, model_frf: (K,) the locked FRF of the COM sway and
        the model's at the compared harmonics (tilt → sway, complex).
    """

    parameters: IcParameters
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
        """Kp, Kd, Δ and W whose interval is wider than ±10 % of the value (W: ±0.1)."""
        out = []
        for name in ("kp", "kd", "delay_s", "w"):
            if name not in self.intervals:
                continue
            low, high = self.intervals[name]
            wide = (high - low) / 2 > (0.1 if name == "w" else 0.1 * abs(getattr(
                self.parameters, name)))
            if wide:
                out.append(name)
        return tuple(out)

    @property
    def trust_level(self) -> str:
        """The trust verdict's level, as for every answer (docs/identify.md, "Trust"):
        doubtful (a residual beyond the noise, Kp, Kd, Δ or W on a search bound),
        imprecise (consistent, but Kp, Kd, Δ or W not pinned to 10 %), or good."""
        if not self.consistent or self.on_bound or not self.stable:
            return "doubtful"
        return "imprecise" if self.unpinned else "good"

    def verdict_line(self) -> str:
        if self.trust_level == "doubtful":
            why = ([f"residual {self.noise_ratio:.2f}× the noise"] if not self.consistent
                   else []) + ([f"on a search bound: {', '.join(self.on_bound)}"]
                               if self.on_bound else [])
            return f"trust: DOUBTFUL: {'; '.join(why)}"
        if self.trust_level == "imprecise":
            return (f"trust: imprecise: {', '.join(self.unpinned)} not pinned to 10 % by this "
                    "recording; the intervals give the precision")
        return "trust: good"

    def to_dict(self) -> dict:
        from posture_id.provenance import provenance

        return {"model": "ic", "parameters": self.parameters.to_dict(),
                "identified": list(self.free),
                "intervals": {k: list(v) for k, v in self.intervals.items()},
                "level": self.level, "calibrated": list(self.calibrated),
                "standard_errors": self.standard_errors,
                "chi2": self.chi2, "dof": self.dof,
                "noise_ratio": self.noise_ratio, "consistent": self.consistent,
                "harmonics": self.harmonics, "on_bound": list(self.on_bound),
                "trust": {"level": self.trust_level,
                          "doubtful": self.trust_level == "doubtful",
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

        return plot_model_frfs(self.frequencies_hz, self.recorded_frf,
                               {"IC model": self.model_frf}, self.coherence,
                               f"IC fit of {self.name}: residual {self.noise_ratio:.2f}× the "
                               "noise", path=path, ax=ax)


#: The calibration of the intervals (the module doc).
CALIBRATION = Path(__file__).with_name("calibration.json")


@lru_cache(maxsize=1)
def _calibration() -> dict | None:
    try:
        return json.loads(CALIBRATION.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def interval_multiplier(name: str, level: float) -> tuple[float, bool]:
    """(the multiplier of the standard error for a ``level`` interval of ``name``,
    whether it is calibrated)."""
    from scipy.stats import norm

    calibration = _calibration()
    quantiles = None if calibration is None else calibration.get("quantiles", {}).get(name)
    if quantiles is None or not all(isinstance(q, int | float) for q in quantiles):
        return float(norm.ppf(0.5 + level / 2)), False
    return float(np.interp(level, calibration["levels"], quantiles)), True


def parameter_scale(name: str, plant: IcPlant) -> float:
    """The unit a parameter is searched in: m·g·h for the gains, 1 for the rest."""
    return plant.mgh if name in _PER_MGH else 1.0


def _to_params(x: np.ndarray, free: tuple[str, ...], plant: IcPlant,
               fixed: IcParameters) -> IcParameters:
    return fixed.replace(**{n: float(v) * parameter_scale(n, plant) for n, v in zip(free, x,
                                                                            strict=True)})


class _Part:
    """One recording's share of an IC fit: its locked COM-sway harmonics, their noise and
    the model's response on its tilt."""

    def __init__(self, trial: PreparedTrial, body, plant: IcPlant,
                 locked: LockedOptions) -> None:
        rec = trial.recording
        if trial.stimulus.period_s is None:
            raise PostureIdError(f"{trial.name}: the IC fit compares stimulus-locked "
                                 "harmonics and needs a periodic stimulus (a PRTS or a "
                                 "protocol)")
        self.trial = trial
        self.sway = com_sway_deg(trial, body)
        self.projection = LockedProjection.for_recording(
            rec.tilt, self.sway[:, None], rec.sample_rate_hz, trial.stimulus.period_s,
            trial.stimulus.periodic_from_s, locked, trial.name)
        self.weights = 1.0 / self.projection.noise[:, 0]
        self.recorded = self.projection.spectrum(self.sway[:, None])[:, 0]
        self.model = IcModelResponse(rec.tilt, rec.sample_rate_hz, plant)
        weighted = self.recorded * self.weights
        self.target = np.concatenate([weighted.real, weighted.imag])

    def weighted(self, y: np.ndarray) -> np.ndarray:
        """(2K, ...) real: the compared harmonics of y (S, ...) ÷ the noise."""
        w = self.weights if y.ndim == 1 else self.weights[:, None]
        spectrum = self.projection.spectrum(y) * w
        return np.concatenate([spectrum.real, spectrum.imag])


#: The literature's typical values, the first start of every search (units of BOUNDS).
_TYPICAL = {"kp": 1.5, "kd": 0.35, "ki": 0.05, "delay_s": 0.15, "w": 0.6,
            "torque_feedback_gain": 0.3, "torque_feedback_time_s": 20.0, "kpas": 0.1,
            "bpas": 0.05}


@dataclass(frozen=True)
class _Search:
    """The best start: x (normalised), its scipy result, each part's parameters."""

    x: np.ndarray
    fit: object
    params: tuple[IcParameters, ...]
    names: tuple[str, ...]


def _search(parts: list[_Part], free: tuple[str, ...], plant: IcPlant,
            options: IcFitOptions, name: str) -> _Search:
    """Multi-start bounded least squares over ``free`` (shared by every part) and, with
    several parts, one W per part after the first (``w`` is the first part's)."""
    from scipy.optimize import least_squares
    from scipy.stats import chi2 as chi2_distribution

    names = tuple(free) + ("w",) * (len(parts) - 1)
    w_index = [free.index("w")] + list(range(len(free), len(names)))
    columns = [PARAMETER_ORDER.index(n) for n in free]
    w_column = PARAMETER_ORDER.index("w")
    scales = np.array([parameter_scale(n, plant) for n in free])
    fixed = IcParameters(kp=plant.mgh, kd=0.3 * plant.mgh, delay_s=0.15, w=0.5)
    target = np.concatenate([p.target for p in parts])

    def params_of(x: np.ndarray) -> list[IcParameters]:
        shared = _to_params(x[: len(free)], free, plant, fixed)
        return [shared.replace(w=float(x[i])) for i in w_index]

    def residual(x: np.ndarray) -> np.ndarray:
        return np.concatenate([p.weighted(np.degrees(p.model.sway(q)))
                               for p, q in zip(parts, params_of(x), strict=True)]) - target

    def jacobian(x: np.ndarray) -> np.ndarray:
        blocks = []
        for k, (p, q) in enumerate(zip(parts, params_of(x), strict=True)):
            _, dy = p.model.sway(q, gradient=True)
            d = np.zeros((len(dy[0]), len(names)))
            d[:, : len(free)] = np.degrees(dy[columns]).T * scales[None, :]
            d[:, free.index("w")] = 0.0
            d[:, w_index[k]] = np.degrees(dy[w_column])
            blocks.append(p.weighted(d))
        return np.vstack(blocks)

    low = np.array([BOUNDS[n][0] for n in names])
    high = np.array([BOUNDS[n][1] for n in names])
    rng = np.random.default_rng(options.seed)
    starts = [np.array([_TYPICAL[n] for n in names])]
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
        if not np.all(np.isfinite(fit.fun)) or not all(is_stable(q, plant)
                                                        for q in params_of(fit.x)):
            continue
        if best is None or fit.cost < best.cost:
            best = fit
        if 2 * best.cost <= enough:  # as close as the noise allows: no start does better
            break
    if best is None:  # every search ran off to an unstable loop: the best stable start
        stable = [x0 for x0 in starts if all(is_stable(q, plant) for q in params_of(x0))]
        if not stable:
            raise PostureIdError(f"{name}: no IC model with a stable closed loop fits this "
                                 "recording within docs/model.md §8's bounds")
        x0 = min(stable, key=lambda x: float(np.sum(residual(x) ** 2)))
        best = _StartOnly(x0, residual(x0), jacobian(x0))
    return _Search(best.x, best, tuple(params_of(best.x)), names)


class _StartOnly:
    """A start kept as the answer (scipy's result's fields), its residual far beyond the
    noise: the verdict says doubtful."""

    def __init__(self, x: np.ndarray, fun: np.ndarray, jac: np.ndarray) -> None:
        self.x, self.fun, self.jac = x, fun, jac
        self.cost = 0.5 * float(fun @ fun)


def fit_ic(trial: PreparedTrial, body, options: IcFitOptions | None = None) -> IcFitResult:
    """The IC parameters of ``trial``'s body COM sway (the module doc).

    Args:
        trial: the recording with its periodic stimulus (a :class:`PreparedTrial`).
        body: the recorded body, turning as one about the ankle (:class:`IcPlant`).
        options: what is identified, the starts, the locked harmonics and the intervals'
            level (default :class:`IcFitOptions`: Ki and the passive terms held at 0).
    Returns:
        :class:`IcFitResult`: the parameters (SI units), their intervals and the fit.
    Raises:
        PostureIdError: a stimulus that is not periodic (no locked harmonics), or no start
            that gives a stable closed loop.
    """
    options = options or IcFitOptions()
    started = clock.perf_counter()
    plant = IcPlant.of(body)
    part = _Part(trial, body, plant, options.locked)
    free = options.free
    found = _search([part], free, plant, options, trial.name)
    params, best = found.params[0], found.fit
    chi2 = float(2 * best.cost)
    dof = len(part.target) - len(free)
    jac = best.jac
    scale2 = max(1.0, chi2 / max(dof, 1))
    try:
        cov = np.linalg.pinv(jac.T @ jac) * scale2
    except np.linalg.LinAlgError:
        cov = np.full((len(free), len(free)), np.inf)
    scales = np.array([parameter_scale(n, plant) for n in free])
    standard_errors = np.sqrt(np.clip(np.diag(cov), 0, None)) * scales
    multipliers = [interval_multiplier(n, options.level) for n in free]
    half = np.array([m for m, _ in multipliers]) * standard_errors
    intervals = {n: (max(getattr(params, n) - h, 0.0), getattr(params, n) + h)
                 for n, h in zip(free, half, strict=True)}
    low = np.array([BOUNDS[n][0] for n in free])
    high = np.array([BOUNDS[n][1] for n in free])
    span = high - low
    on_bound = tuple(n for n, x, lo, hi, sp in zip(free, found.x, low, high, span, strict=True)
                     if n in ("kp", "kd", "delay_s", "w") and lo > 0
                     and (x - lo < 1e-3 * sp or hi - x < 1e-3 * sp))
    fitted = np.degrees(part.model.sway(params))
    projection, sway = part.projection, part.sway
    explained = float(projection.explained(sway[:, None], fitted[:, None])[0])
    tilt_deg = np.degrees(trial.recording.tilt)
    u = projection.spectrum(tilt_deg[:, None])[:, 0]
    model_frf = closed_loop(params, plant, 2j * np.pi * projection.frequencies_hz)
    coherence = _coherence(projection, sway)
    return IcFitResult(params, free, intervals, options.level, chi2, dof,
                       len(projection.harmonics), on_bound, True,
                       clock.perf_counter() - started, explained, fitted, sway,
                       projection.frequencies_hz, part.recorded / u, model_frf, coherence,
                       trial.name, dict(zip(free, standard_errors.tolist(), strict=True)),
                       tuple(n for n, (_, c) in zip(free, multipliers, strict=True) if c))


@dataclass(frozen=True)
class IcPartsFit:
    """The IC model fitted to the parts of a two-amplitude protocol at once: every
    parameter shared but W, one per part (sensory re-weighting).

    Attributes:
        parameters: per part, its IC parameters (they differ in W only).
        chi2: of all parts. fitted_deg: per part, the model's COM sway (S_p,) degrees.
    """

    parameters: tuple[IcParameters, ...]
    chi2: float
    fitted_deg: tuple[np.ndarray, ...]

    @property
    def w_by_part(self) -> tuple[float, ...]:
        return tuple(p.w for p in self.parameters)

    @property
    def reweighting(self) -> float:
        """How far W moved between the amplitudes: the last part's W minus the first's."""
        return self.w_by_part[-1] - self.w_by_part[0]


def fit_ic_parts(trials: list[PreparedTrial], body,
                 options: IcFitOptions | None = None) -> IcPartsFit:
    """The IC parameters of every one of ``trials`` (the same subject at several
    amplitudes), shared but for W, one per part."""
    options = options or IcFitOptions()
    plant = IcPlant.of(body)
    parts = [_Part(t, body, plant, options.locked) for t in trials]
    found = _search(parts, options.free, plant, options, " + ".join(t.name for t in trials))
    fitted = tuple(np.degrees(p.model.sway(q)) for p, q in zip(parts, found.params,
                                                                strict=True))
    return IcPartsFit(found.params, float(2 * found.fit.cost), fitted)


def _coherence(projection: LockedProjection, sway_deg: np.ndarray) -> np.ndarray:
    """(K,) the share of the sway's power at each compared harmonic that is locked to the
    stimulus (its locked power over locked plus noise power; 1 without noise)."""
    locked = np.abs(projection.spectrum(sway_deg[:, None])[:, 0]) ** 2
    noise = 2 * projection.noise[:, 0] ** 2
    return locked / (locked + noise)
