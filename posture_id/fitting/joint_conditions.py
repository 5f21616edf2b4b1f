"""One subject, several trials: one joint fit of a model to every trial of a session, the
parameters that are the subject's shared, the named ones one per condition (eyes open and
closed, firm and foam, several amplitudes; docs/fit.md, "One subject, several trials").

:func:`fit_joint` fits, the way the model's capabilities allow:

- a model with a closed loop (the IC model, any
  :class:`~posture_id.models.protocol.FrequencyModel`): the exact frequency-domain fit of
  :mod:`posture_id.fitting.frequency`, every trial's weighted locked COM-sway harmonics
  stacked, each trial with its condition's parameters (:class:`~.frequency.ConditionLayout`).
  ``fit_frequency_parts`` (a W per part of a two-amplitude protocol) is this fit with every
  part its own condition;
- DEC (per-joint modules): the locked time-domain least squares, one set of parameters
  for every trial first, then polished with the named module parameters (``"ankle.kp"``,
  ``"ankle.delay_s"``, any module's Kp, Ki, Kd or delay) one per condition, both stages
  by :func:`~posture_id.fitting.joint.polish_by_condition`.

Intervals: the Gauss-Newton covariance of the joint weighted residual (every trial's
harmonics in units of their noise), scaled by χ²/(c·dof) where that exceeds 1 (c: what
the estimated noise levels make χ²/dof on average, :func:`chi2_correction`), times the
joint fit's calibrated multiplier (:func:`joint_calibration`, made by
``benchmarks/joint_fit.py --calibrate``; a model it does not hold: the model's own; DEC's
locked fit: the normal quantile); a parameter the trials leave undetermined (a standard
error of 0) gets its whole search range. The verdict is the frequency fit's
(:class:`JointFit`).
"""

from __future__ import annotations

import json
import math
import time as clock
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import lru_cache
from pathlib import Path

import numpy as np

from posture_id.bodies.body import Body
from posture_id.errors import PostureIdError
from posture_id.fileio import Result
from posture_id.fitting.frequency import (
    FitVerdict,
    FrequencyFitOptions,
    LockedCom,
    gauss_newton_errors,
    interval_bounds,
)
from posture_id.fitting.options import FitOptions
from posture_id.frf.locked import LockedOptions
from posture_id.models.protocol import Capability, Model, ModelParameters, TrustLevel
from posture_id.progress import Progress
from posture_id.trials import PreparedTrial

__all__ = ["JointFit", "fit_joint", "joint_parameter_names", "resolve_parameter",
           "options_kind", "sway_falls", "DEC_PER_CONDITION", "JOINT_CALIBRATION_FILE",
           "joint_calibration",
           "joint_multiplier", "chi2_correction"]

#: DEC's module parameters that may take one value per condition.
DEC_PER_CONDITION = ("kp", "ki", "kd", "delay_s")
#: DEC's judged parameters (as ``identify``'s verdict: each module's Kp, Kd and delay
#: pinned to ±10 %; Kp or Kd on a search bound makes the answer doubtful).
_DEC_PINNED = {"kp": 0.1, "kd": 0.1, "delay_s": 0.1}
_DEC_BOUND_JUDGED = ("kp", "kd")
#: The level of DEC's joint intervals (the normal quantile: DEC's locked fit has no
#: calibrated multiplier).
DEC_LEVEL = 0.9
#: Where each module parameter's block sits in the fit's unknowns q
#: (:mod:`posture_id.fitting.unknowns`: Kp, Ki, Kd, Δ, class, Kpas, Bpas, N each).
_Q_BLOCK = {"kp": 0, "ki": 1, "kd": 2, "delay_s": 3, "kpas": 5, "bpas": 6}


#: The joint fit's interval calibration (made by ``.venv/bin/python benchmarks/joint_fit.py
#: --calibrate``), per model name: per parameter, the quantiles of |estimate − truth| /
#: standard error at ``levels`` over simulated subjects of its own seed (docs/fit.md, "One
#: subject, several trials"). A model or a parameter not in it takes the model's own
#: multiplier (:func:`joint_multiplier`).
JOINT_CALIBRATION_FILE = Path(__file__).with_name("joint_calibration.json")


@lru_cache(maxsize=1)
def joint_calibration() -> dict:
    """:data:`JOINT_CALIBRATION_FILE` read: model name → its calibration (empty where the
    file cannot be read: every model then takes its own multiplier)."""
    try:
        return json.loads(JOINT_CALIBRATION_FILE.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}


def joint_multiplier(model: Model, name: str, level: float) -> tuple[float, bool]:
    """(what a joint fit's ``level`` interval of ``name`` multiplies its standard error
    by, whether it is calibrated): :func:`joint_calibration`'s quantile for the model and
    parameter, else the model's own ``interval_multiplier``."""
    calibration = joint_calibration().get(model.name)
    quantiles = None if calibration is None else calibration["quantiles"].get(name)
    if quantiles is None:
        return model.interval_multiplier(name, level)
    return float(np.interp(level, calibration["levels"], quantiles)), True


def chi2_correction(locked: LockedOptions) -> float:
    """ν/(ν − 2), ν = 4·neighbours: the mean of χ²/dof for a right model when every
    harmonic's noise is estimated from 2·neighbours empty harmonics (1 unweighted)."""
    if not locked.weighted:
        return 1.0
    nu = 4 * locked.neighbours
    return nu / (nu - 2)


def _labelled(name: str, condition: str | None) -> str:
    """How a parameter is named in a verdict: ``w [eyes closed]`` for a per-condition one."""
    return name if condition is None else f"{name} [{condition}]"


@dataclass(frozen=True)
class JointFit(FitVerdict, Result):
    """One model fitted to several trials of one subject at once: the shared parameters
    and, per condition, the per-condition ones.

    Attributes:
        model: the model fitted.
        trials: (T,) the trials' names. trial_conditions: (T,) each one's condition.
        conditions: (C,) the distinct condition labels, in the order they first appear.
        per_condition_names: the parameters that take one value per condition.
        shared: {name: value} the shared identified parameters (SI units).
        per_condition: {condition: {name: value}} (SI units).
        parameters: {condition: the model's full parameter object in that condition}.
        intervals: {"shared": {name: (low, high)}, "per_condition": {condition: {name:
            (low, high)}}} at ``level`` (SI units).
        standard_errors: the same shape, one standard error each (SI units).
        level: the intervals' nominal coverage. calibrated: the parameters whose interval
            multiplier is calibrated.
        chi2: the joint weighted residual's squared norm (units of the noise).
        dof: its degrees of freedom (real numbers compared − identified parameters).
        compared: the real numbers compared (2 per locked harmonic and channel).
        on_bound: judged parameters on a search bound (labelled as in the verdict).
        stable: every condition's model balances (a closed loop that settles; a DEC
            answer that does not fall).
        seconds: the fit's time.
        explained: (T,) the share of each trial's locked COM sway the model explains.
        frequencies_hz, recorded_frf, model_frf: per trial (K_t,): the compared
            harmonics, the recorded locked FRF of the COM sway (tilt → sway, complex) and
            the model's.
        curves: {condition: (F,) Hz, (F,) complex}: the model's FRF in that condition.
        fitted_deg: per trial (S_t,) the model's COM sway, degrees.
        pins: the judged parameters' pins (half-width beyond which one is not pinned:
            relative to the value, absolute for ``absolute_pins``).
        identified_count: the parameters identified in all.
        provenance_options: the fit's options, as the JSON records them.
        chi2_correction: c, what χ²/dof is on average when the model is right: each
            harmonic's noise is estimated from 2·``neighbours`` empty harmonics (ν = 4·
            neighbours degrees of freedom), which makes it ν/(ν − 2) (1.2 for the default
            3 neighbours; the comparison's correction). The verdict, the noise ratio and
            the intervals' χ² scaling take χ²/c.

    The verdict is :class:`~posture_id.fitting.frequency.FitVerdict`'s: doubtful (the
    joint residual beyond the noise, a judged parameter on a search bound, a model that
    does not balance), imprecise (consistent, but a judged parameter not pinned), or good.
    """

    model: Model = field(repr=False)
    trials: tuple[str, ...]
    trial_conditions: tuple[str, ...]
    conditions: tuple[str, ...]
    per_condition_names: tuple[str, ...]
    shared: dict
    per_condition: dict
    parameters: dict[str, ModelParameters] = field(repr=False)
    intervals: dict = field(repr=False)
    standard_errors: dict = field(repr=False)
    level: float
    calibrated: tuple[str, ...]
    chi2: float
    dof: int
    compared: int
    on_bound: tuple[str, ...]
    stable: bool
    seconds: float
    explained: tuple[float, ...]
    frequencies_hz: tuple = field(repr=False)
    recorded_frf: tuple = field(repr=False)
    model_frf: tuple = field(repr=False)
    curves: dict = field(repr=False)
    fitted_deg: tuple = field(repr=False)
    pins: dict = field(repr=False, default_factory=dict)
    absolute_pins: frozenset = field(repr=False, default=frozenset())
    identified_count: int = 0
    provenance_options: object = field(repr=False, default=None)
    chi2_correction: float = 1.0

    def _every_interval(self):
        """(label, name, value, (low, high)) of every identified parameter."""
        for name, bounds in self.intervals["shared"].items():
            yield name, name, self.shared[name], bounds
        for condition, inner in self.intervals["per_condition"].items():
            for name, bounds in inner.items():
                yield (_labelled(name, condition), name, self.per_condition[condition][name],
                       bounds)

    @property
    def falls(self) -> bool:
        """Whether any condition's model fell: its sway of a trial is not finite, or it does
        not balance (``stable``)."""
        return not self.stable or not all(np.all(np.isfinite(f)) for f in self.fitted_deg)

    @property
    def w_by_part(self) -> tuple[float, ...]:
        """The model's per-part parameter (IC: W) in each condition, in order: of the parts
        of one protocol, each its own condition
        (:func:`~posture_id.fitting.models.fit_model_parts`)."""
        return tuple(getattr(p, self.model.per_part) for p in self.parameters.values())

    @property
    def reweighting(self) -> float:
        """How far W moved between the amplitudes: the last part's W minus the first's."""
        return self.w_by_part[-1] - self.w_by_part[0]

    def to_dict(self) -> dict:
        """Strict JSON-ready: the shared and per-condition parameters, the intervals, the
        verdict, the trials."""
        from posture_id.provenance import provenance

        def pairs(d: dict) -> dict:
            return {k: list(v) for k, v in d.items()}

        return {"model": self.model.name,
                "shared": dict(self.shared),
                "per_condition": {c: dict(v) for c, v in self.per_condition.items()},
                "per_condition_parameters": list(self.per_condition_names),
                "parameters": {c: p.to_dict() for c, p in self.parameters.items()},
                "intervals": {"shared": pairs(self.intervals["shared"]),
                              "per_condition": {c: pairs(v) for c, v in
                                                self.intervals["per_condition"].items()}},
                "standard_errors": self.standard_errors,
                "level": self.level, "calibrated": list(self.calibrated),
                "chi2": self.chi2, "dof": self.dof, "compared": self.compared,
                "noise_ratio": self.noise_ratio, "consistent": self.consistent,
                "chi2_correction": self.chi2_correction, "on_bound": list(self.on_bound),
                "trust": {"level": self.trust_level.value,
                          "doubtful": self.trust_level is TrustLevel.DOUBTFUL,
                          "unpinned": list(self.unpinned), "line": self.verdict_line()},
                "stable": self.stable, "seconds": self.seconds,
                "conditions": list(self.conditions),
                "trials": [{"name": n, "condition": c, "explained": e,
                            "frequencies_hz": f}
                           for n, c, e, f in zip(self.trials, self.trial_conditions,
                                                 self.explained, self.frequencies_hz,
                                                 strict=True)],
                "identified": self.identified_count,
                "provenance": provenance(self.provenance_options)}

    def summary(self) -> str:
        """Printable: the parameters with their intervals, each trial's share explained,
        the verdict."""
        lines = [f"{self.model.label} joint fit of {len(self.trials)} trial(s) in "
                 f"{len(self.conditions)} condition(s): residual {self.noise_ratio:.2f}× the "
                 f"noise ({'consistent with' if self.consistent else 'beyond'} it; χ² "
                 f"{self.chi2:.1f} on {self.dof} dof); {self.seconds:.2f} s"]
        lines.append("shared:")
        for name, value in self.shared.items():
            lines.append(self._interval_line(name, value, *self.intervals["shared"][name]))
        for condition in self.conditions:
            lines.append(f"{condition}:")
            for name, value in self.per_condition[condition].items():
                lines.append(self._interval_line(
                    name, value, *self.intervals["per_condition"][condition][name]))
        for name, condition, share in zip(self.trials, self.trial_conditions, self.explained,
                                          strict=True):
            lines.append(f"  trial {name} [{condition}]: explains {100 * share:.1f} % of its "
                         "locked COM sway")
        lines.append(self.verdict_line())
        return "\n".join(lines)

    def plot(self, path=None, ax=None):
        """Every trial's recorded locked FRF of the COM sway (gain and phase; points,
        coloured by condition) with the joint model's FRF in its condition over it."""
        from posture_id.plotting import plot_condition_frfs

        trials = [(c, f, r, m) for c, f, r, m in zip(
            self.trial_conditions, self.frequencies_hz, self.recorded_frf, self.model_frf,
            strict=True)]
        return plot_condition_frfs(
            self.conditions, trials, self.curves,
            f"{self.model.label} joint fit of {len(self.trials)} trials: residual "
            f"{self.noise_ratio:.2f}× the noise", path=path, ax=ax)


def sway_falls(theta: np.ndarray) -> bool:
    """Whether a fitted DEC sway (S, N) rad leaves the sway limit (or is not finite)."""
    from posture_id.simulation.options import MAX_SWAY_LIMIT_DEG

    theta = np.asarray(theta, dtype=float)
    return bool(not np.all(np.isfinite(theta))
                or np.max(np.abs(theta)) >= math.radians(MAX_SWAY_LIMIT_DEG) * (1 - 1e-9))


def options_kind(model: Model) -> type:
    """The class of ``model``'s fit options: a
    :class:`~posture_id.fitting.frequency.FrequencyFitOptions` for a model with a closed
    loop, a :class:`~posture_id.fitting.options.FitOptions` for DEC's modules.

    Raises:
        PostureIdError: a model with neither (no way to fit it).
    """
    if Capability.FREQUENCY_RESPONSE in model.capabilities:
        return FrequencyFitOptions
    if Capability.LOCKED_FIT in model.capabilities:
        return FitOptions
    raise PostureIdError(f"{model.label}: no way to fit it (it declares neither a closed "
                         "loop nor per-joint modules)")


def joint_parameter_names(model: Model, body, options=None) -> tuple[str, ...]:
    """The names :func:`fit_joint` accepts as per-condition parameters of ``model``: a
    closed loop's identified parameters (``options``' or the model's), DEC's
    ``"<joint>.kp"``, ``".ki"``, ``".kd"`` and ``".delay_s"`` of every module of ``body``."""
    kind = options_kind(model)  # refuses a model with no way to fit it
    if Capability.FREQUENCY_RESPONSE in model.capabilities:
        return (options or kind()).free_of(model)
    return tuple(f"{joint}.{name}" for joint in body.joint_names
                 for name in DEC_PER_CONDITION)


def resolve_parameter(model: Model, body, name: str, options=None) -> str:
    """``name`` as :func:`fit_joint` spells it (``W`` → ``w``, ``ankle.Kp`` →
    ``ankle.kp``).

    Raises:
        PostureIdError: not a parameter of the model that may vary by condition (the
            message lists those that may).
    """
    names = joint_parameter_names(model, body, options)
    for known in names:
        if known.lower() == str(name).lower():
            return known
    raise PostureIdError(f"{name!r} is not a parameter of the {model.label} model that a "
                         f"joint fit identifies (its parameters: {', '.join(names)})")


def _condition_indices(conditions: Sequence[str], trials: list[PreparedTrial]
                       ) -> tuple[tuple[str, ...], list[int]]:
    """(the distinct labels in order of first appearance, each trial's index)."""
    if len(conditions) != len(trials):
        raise PostureIdError(f"{len(conditions)} condition label(s) for {len(trials)} "
                             "trial(s): give one label per trial")
    labels: list[str] = []
    folded: dict[str, str] = {}
    for label in conditions:
        if not isinstance(label, str) or not label.strip():
            raise PostureIdError(f"condition labels must be non-empty text, got {label!r}")
        first = folded.setdefault(label.casefold(), label)
        if first != label:
            raise PostureIdError(f"condition labels {first!r} and {label!r} differ only in "
                                 "case: write one condition the same way for every trial "
                                 "(or name two apart)")
        if label not in labels:
            labels.append(label)
    return tuple(labels), [labels.index(c) for c in conditions]


def fit_joint(model: Model, trials: list[PreparedTrial], body: Body,
              conditions: Sequence[str], per_condition: tuple[str, ...] = (),
              options: FrequencyFitOptions | FitOptions | None = None,
              progress: Progress | None = None, noise_from_residual: bool = True
              ) -> JointFit:
    """One fit of ``model`` to every one of ``trials`` (one subject): the parameters
    ``per_condition`` names one per condition, the rest of the identified ones shared.

    Args:
        model: a model with a closed loop (IC, any
            :class:`~posture_id.models.protocol.FrequencyModel`) or DEC.
        trials: (T,) the trials, each with its periodic stimulus, all of ``body``.
        body: the subject's body.
        conditions: (T,) one label per trial ("eyes open", "eyes closed"...); trials with
            the same label share the per-condition parameters too.
        per_condition: the parameters that take one value per condition (IC: ``"w"``;
            DEC: ``"ankle.kp"``; :func:`joint_parameter_names`); empty: every parameter
            shared.
        options: the model's fit options: a
            :class:`~posture_id.fitting.frequency.FrequencyFitOptions` for a closed loop, a
            :class:`~posture_id.fitting.options.FitOptions` for DEC (its ``locked``
            defaulting to :class:`~posture_id.frf.locked.LockedOptions`); None: defaults.
        progress: told the stages of DEC's fit.
        noise_from_residual: a model with a closed loop: after a first fit, estimate each
            harmonic's noise again from the residual's empty harmonics (the model's own
            transient from rest taken out of them) and fit again from the first answer
            (False: the recorded sway's, as :func:`~.frequency.fit_frequency`).
    Returns:
        :class:`JointFit`.
    Raises:
        PostureIdError: no trials, a label count other than the trials', a per-condition
            name that is not the model's (the message lists them), a stimulus that is not
            periodic, a trial of another body.
    """
    started = clock.perf_counter()
    trials = list(trials)
    if not trials:
        raise PostureIdError("a joint fit needs at least one trial")
    labels, index = _condition_indices(conditions, trials)
    _check_options(model, options)
    names = joint_parameter_names(model, body, options)
    unknown = [n for n in per_condition if n not in names]
    if unknown:
        raise PostureIdError(f"per-condition parameter(s) {', '.join(map(repr, unknown))} "
                             f"not among the {model.label} model's (its parameters: "
                             f"{', '.join(names)})")
    per = tuple(n for n in names if n in per_condition)
    return fit_conditions(model, trials, body, labels, index, per, options, progress,
                          noise_from_residual, started)


def fit_conditions(model: Model, trials: list[PreparedTrial], body, labels: tuple[str, ...],
                   index: Sequence[int], per: tuple[str, ...], options=None, progress=None,
                   noise_from_residual: bool = True, started: float | None = None
                   ) -> JointFit:
    """:func:`fit_joint` once its call is checked, the way the model's capabilities allow
    (the module doc): ``labels`` (C,) the distinct conditions, ``index`` (T,) each
    trial's condition 0..C−1, ``per`` the per-condition parameters (in the order of
    :func:`joint_parameter_names`); ``started``: the clock (``time.perf_counter``) the
    fit's seconds count from (default: now)."""
    started = clock.perf_counter() if started is None else started
    if Capability.FREQUENCY_RESPONSE in model.capabilities:
        return _fit_frequency_joint(model, trials, body, labels, list(index), per, options,
                                    started, noise_from_residual)
    return _fit_locked_joint(model, trials, body, labels, list(index), per, options,
                             progress, started)


def _check_options(model: Model, options) -> None:
    """Refuse options of another kind than the model's fit takes (None is its default)."""
    if options is None:
        return
    wanted = (FrequencyFitOptions if Capability.FREQUENCY_RESPONSE in model.capabilities
              else FitOptions)
    if not isinstance(options, wanted):
        raise PostureIdError(f"the {model.label} joint fit takes {wanted.__name__}, got "
                             f"{type(options).__name__}")


def _split(names: tuple[str, ...], per: tuple[str, ...], conditions: tuple[str, ...],
           each) -> tuple[dict, dict]:
    """({name: each(name, 0)} of the shared names, {condition: {name: each(name, c)}})."""
    shared = {n: each(n, 0) for n in names if n not in per}
    by_condition = {c: {n: each(n, k) for n in per} for k, c in enumerate(conditions)}
    return shared, by_condition


def _values(names: tuple[str, ...], per: tuple[str, ...], labels: tuple[str, ...], value,
            se, half, ranges: dict) -> tuple[dict, dict, dict, dict]:
    """(the shared values, the per-condition ones, the intervals, the standard errors) as
    :class:`JointFit` holds them, from ``value(name, c)``, ``se(name, c)`` and ``half(name,
    c)`` (an interval's half-width) of each name in condition c, SI units; ``ranges``:
    {name: (low, high)} the search ranges (SI)."""
    shared, by_condition = _split(names, per, labels, value)
    se_shared, se_by = _split(names, per, labels, se)
    half_shared, half_by = _split(names, per, labels, half)
    intervals = {"shared": interval_bounds(shared, half_shared, ranges),
                 "per_condition": {c: interval_bounds(by_condition[c], half_by[c], ranges)
                                   for c in labels}}
    return shared, by_condition, intervals, {"shared": se_shared, "per_condition": se_by}


def _joint_fit(model, trials, labels, index, per, values, params, coms, fitted, model_frf,
               started, **rest) -> JointFit:
    """The :class:`JointFit` of ``values`` (:func:`_values`) and ``params`` ({condition:
    parameters}), each trial's :class:`~posture_id.fitting.frequency.LockedCom`
    (``coms``), the model's COM sway (``fitted``, per trial (S_t,) degrees) and FRF
    (``model_frf``, per trial (K_t,)); ``rest``: the other fields by name."""
    shared, by_condition, intervals, standard_errors = values
    return JointFit(
        model, tuple(t.name for t in trials), tuple(labels[c] for c in index), labels, per,
        shared, by_condition, params, intervals, standard_errors,
        seconds=clock.perf_counter() - started,
        explained=tuple(lc.explained(f) for lc, f in zip(coms, fitted, strict=True)),
        frequencies_hz=tuple(lc.projection.frequencies_hz for lc in coms),
        recorded_frf=tuple(lc.frf() for lc in coms), model_frf=model_frf, fitted_deg=fitted,
        **rest)


def _fit_frequency_joint(model, trials, body, labels, index, per, options, started,
                         noise_from_residual: bool) -> JointFit:
    """The joint fit of a model with a closed loop (the module doc)."""
    from posture_id.fitting.frequency import (
        Precision,
        on_search_bound,
        search_conditions,
        search_ranges,
    )

    options = options or FrequencyFitOptions()
    joint = search_conditions(model, trials, body, index, per, options, noise_from_residual)
    parts, layout, found, plant = joint.parts, joint.layout, joint.found, joint.plant
    free = layout.free
    chi2 = float(2 * found.fit.cost)
    compared = int(sum(len(p.target) for p in parts))
    dof = compared - len(layout.names)
    correction = chi2_correction(options.locked)
    precision = Precision.of(model, plant, layout.names, found.fit.jac, chi2 / correction,
                             dof, options.level,
                             lambda n, level: joint_multiplier(model, n, level))

    def entry(array):
        return lambda n, c: float(array[layout.index(c, n)])

    values = found.x * np.array([model.scale(n, plant) for n in layout.names])
    bound_entries = set(on_search_bound(model, layout.names, found.x))
    on_bound = tuple(_labelled(n, None if n not in layout.per_condition else labels[c])
                     for c in range(layout.count) for n in free
                     if layout.index(c, n) in bound_entries
                     and (c == 0 or n in layout.per_condition))
    params = dict(zip(labels, found.params, strict=True))
    fitted = tuple(np.degrees(p.model.sway(params[labels[c]]))
                   for p, c in zip(parts, index, strict=True))
    model_frf = tuple(model.closed_loop(params[labels[c]], plant,
                                        2j * np.pi * p.projection.frequencies_hz)
                      for p, c in zip(parts, index, strict=True))
    curves = {}
    for c, label in enumerate(labels):
        f = np.concatenate([p.projection.frequencies_hz
                            for p, k in zip(parts, index, strict=True) if k == c])
        grid = np.geomspace(0.8 * f.min(), 1.25 * f.max(), 200)
        curves[label] = (grid, model.closed_loop(params[label], plant, 2j * np.pi * grid))
    calibrated = tuple(n for n in free
                       if precision.calibrated[layout.names.index(n)])
    return _joint_fit(
        model, trials, labels, index, layout.per_condition,
        _values(free, layout.per_condition, labels, entry(values),
                entry(precision.standard_errors), entry(precision.half_widths),
                search_ranges(model, plant)),
        params, parts, fitted, model_frf, started, level=options.level,
        calibrated=calibrated, chi2=chi2, dof=dof, compared=compared, on_bound=on_bound,
        stable=True, curves=curves, pins=dict(model.pinned),
        absolute_pins=frozenset(model.absolute_pins), identified_count=len(layout.names),
        provenance_options=options, chi2_correction=correction)


def _fit_locked_joint(model, trials, body, labels, index, per, options, progress, started
                      ) -> JointFit:
    """DEC's joint fit: the locked least squares, shared, then per condition (the module
    doc). Its intervals are at :data:`DEC_LEVEL`, the normal quantile (uncalibrated)."""
    from scipy.stats import norm

    from posture_id.fitting.joint import polish_by_condition
    from posture_id.models.dec import com_deg

    options = options or FitOptions()
    if options.locked is None:
        options = replace(options, locked=LockedOptions())
    joints = body.joint_names
    fields = (*DEC_PER_CONDITION, *(("kpas", "bpas") if options.fit_passive else ()))
    names = tuple(f"{j}.{f}" for f in fields for j in joints)
    split = {n: tuple(n.split(".")) for n in names}  # (joint, field) of each name

    def q_index(name: str) -> int:  # where a module parameter sits in q (fitting.unknowns)
        joint, field_name = name.split(".")
        return _Q_BLOCK[field_name] * len(joints) + joints.index(joint)

    polish = polish_by_condition(trials, body, options, index, tuple(q_index(p) for p in per),
                                 progress)
    stage, evaluator, free = polish.stage, polish.evaluator, polish.free
    data = polish.data_rows
    residual = stage.residual[:data]
    chi2 = float(residual @ residual)
    dof = data - len(free)
    correction = chi2_correction(options.locked)
    se_normalised = dict(zip(free, gauss_newton_errors(stage.jacobian, chi2 / correction,
                                                       dof), strict=True))
    multiplier = float(norm.ppf(0.5 + DEC_LEVEL / 2))
    defaults = polish.runs[0].problem.defaults
    default = {n: float(getattr(defaults[j], f)) for n, (j, f) in split.items()}
    params = dict(zip(labels, polish.parameters, strict=True))
    lower, upper = polish.runs[0].lower, polish.runs[0].upper

    def value(name: str, c: int) -> float:
        joint, field_name = split[name]
        return float(getattr(params[labels[c]][joint], field_name))

    def se(name: str, c: int) -> float:  # normalised p̃ = p/p_default − 1: dp = p_default·dp̃
        return (se_normalised.get(evaluator.column(c, q_index(name)), math.inf)
                * default[name])

    ranges = {n: (default[n] * (1 + lower[q_index(n)]), default[n] * (1 + upper[q_index(n)]))
              for n in names}
    on_bound = []
    for c, label in enumerate(labels):
        for name in names:
            if split[name][1] not in _DEC_BOUND_JUDGED or (c > 0 and name not in per):
                continue
            base = q_index(name)
            x = stage.q[evaluator.column(c, base)]
            margin = 1e-3 * (upper[base] - lower[base])
            if x <= lower[base] + margin or x >= upper[base] - margin:
                on_bound.append(_labelled(name, label if name in per else None))
    coms = [LockedCom(t, body, options.locked, "the DEC joint fit") for t in trials]
    fitted = tuple(com_deg(theta, body) for theta in polish.fitted)
    model_frf = tuple(lc.frf(f) for lc, f in zip(coms, fitted, strict=True))
    curves = {}
    for c, label in enumerate(labels):
        f = np.concatenate([lc.projection.frequencies_hz
                            for lc, k in zip(coms, index, strict=True) if k == c])
        h = np.concatenate([m for m, k in zip(model_frf, index, strict=True) if k == c])
        order = np.argsort(f, kind="stable")
        curves[label] = (f[order], h[order])
    return _joint_fit(
        model, trials, labels, index, per,
        _values(names, per, labels, value, se, lambda n, c: multiplier * se(n, c), ranges),
        params, coms, fitted, model_frf, started, level=DEC_LEVEL, calibrated=(), chi2=chi2,
        dof=dof, compared=data, on_bound=tuple(on_bound),
        stable=not any(sway_falls(theta) for theta in polish.fitted), curves=curves,
        pins={f"{j}.{f}": pin for f, pin in _DEC_PINNED.items() for j in joints},
        absolute_pins=frozenset(), identified_count=len(free) + len(joints),
        provenance_options=options, chi2_correction=correction)
