"""One entry point for identifying a recording: the CNN, least squares, or both.

    >>> from posture_id import load_body, Recording
    >>> from posture_id.identify import identify, Method
    >>> body = load_body()
    >>> rec = Recording.from_csv("rec.csv", body.segment_names)
    >>> result = identify(rec, body, Method.HYBRID)   # the CNN's answer refined
    >>> print(result.summary()); result.plot("result.png")

- :attr:`Method.CNN`: the trained network alone (milliseconds; only for the stimulus it
  was trained on);
- :attr:`Method.FIT`: least squares from the body's defaults (any tilt; seconds, and it
  can stall in a local minimum);
- :attr:`Method.HYBRID`: least squares started from the CNN's answer: its classes kept
  when it is sure of them and the fit then explains the sway as well as the recording's
  own noise allows, otherwise relaxed so that the fit can overturn a class
  (:func:`_refine`; docs/identify.md).

Every result is checked by simulating the identified model on the recording's tilt: the
body-sway errors E_id and E_rel (MODEL §7) and each segment's residual.
"""

from __future__ import annotations

import copy
import enum
import math
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from posture_id.bodies.body import Body, load_body
from posture_id.fitting.options import FitOptions, FixedClasses, RelaxedClasses
from posture_id.frf.locked import LockedOptions, LockedProjection
from posture_id.identify.method import DEFAULT_METHOD, Method
from posture_id.identify.networks import Network, network_for
from posture_id.identify.noise_check import noise_check
from posture_id.identify.result import IdentificationResult, SegmentFit
from posture_id.identify.verdict import PEOPLE_LIKE_SHARE, TrustVerdict, suggestion
from posture_id.learning.config import LearningError
from posture_id.learning.identifier import DEFAULT_LEVEL
from posture_id.progress import Progress
from posture_id.provenance import provenance
from posture_id.recording import Recording
from posture_id.simulation.batch import simulate
from posture_id.simulation.metrics import sway_errors
from posture_id.simulation.options import MAX_SWAY_LIMIT_DEG, SimulationOptions
from posture_id.simulation.stimulus import TiltProfile
from posture_id.trials import PreparedTrial, prepare_trial

__all__ = ["Method", "identify", "Identifier", "DEFAULT_METHOD", "Refinement", "auto_refinement"]

#: The CNN is said to be unsure of a class when P(C = +1) is inside this band.
UNSURE_CLASS = (0.05, 0.95)


def identify(recording: Recording, body: Body | None = None, method: Method = DEFAULT_METHOD,
             model: str | Path | Network | None = None,
             fit_options: FitOptions | None = None, progress: Progress | None = None,
             stimulus: TiltProfile | None = None,
             level: float = DEFAULT_LEVEL) -> IdentificationResult:
    """Identify every module's Kp, Ki, Kd, Δ and class from one recording: a one-off
    :class:`Identifier` (build one to identify many recordings).

    Args:
        recording: tilt and segment angles (the body's segments); its ``name`` names it
            in messages. body: default the TIP.
        method: :class:`Method` (default :data:`DEFAULT_METHOD`). model: a model
            directory (a universal model or a per-body specialist) or a loaded network
            (default: the bundled universal model, :func:`~.networks.network_for`).
            fit_options: for least squares.
        progress: told the fit's stages.
        stimulus: the tilt as the lab ran it (checked against the recording's tilt column);
            default: recognised from the tilt column.
        level: the intervals' nominal coverage (docs/uncertainty.md): the CNN's are
            conformal; least squares' are its Gauss-Newton standard errors times the scale
            calibrated for the hybrid, or ±z·SE, unchecked, for a fit from the defaults or
            a model without that calibration.
    """
    identifier = Identifier(body or load_body(), method, model, fit_options, level)
    return identifier.identify(recording, stimulus, progress)


class Identifier:
    """Built once for a body, a method and a model; identifies many recordings.

        >>> identifier = Identifier(load_body("subject.urdf"), Method.HYBRID)
        >>> results = [identifier.identify(Recording.from_csv(p)) for p in paths]

    Attributes:
        body, method, fit_options, level: as given. cnn: the loaded
            network (:func:`~.networks.network_for`; None for
            :attr:`Method.FIT`).
    """

    def __init__(self, body: Body, method: Method = DEFAULT_METHOD,
                 model: str | Path | Network | None = None,
                 fit_options: FitOptions | None = None,
                 level: float = DEFAULT_LEVEL) -> None:
        self.body = body
        self.method = Method(method)
        self.fit_options = fit_options or FitOptions()
        self.level = level
        #: why the bundled network cannot identify this body (``auto`` then fits), or None
        self.network_refusal: str | None = None
        self.cnn = None
        if self.method is not Method.FIT:
            try:
                self.cnn = network_for(model, body)
            except LearningError as error:
                if self.method is not Method.AUTO or model is not None:
                    raise
                self.network_refusal = str(error)

    def prepare(self, recording: Recording, stimulus: TiltProfile | None = None
                ) -> PreparedTrial:
        """The entrance: the recording checked against the body, its stimulus found or
        checked, at the model's rate."""
        recording.check_segments(self.body.segment_names)
        return prepare_trial(recording, stimulus, self.fit_options.simulation.sample_rate_hz)

    def identify(self, recording: Recording, stimulus: TiltProfile | None = None,
                 progress: Progress | None = None) -> IdentificationResult:
        """Identify one recording (see :func:`identify`)."""
        start = time.perf_counter()
        trial = self.prepare(recording, stimulus)
        return self.identify_trial(trial, progress, start)

    def identify_trial(self, trial: PreparedTrial, progress: Progress | None = None,
                       start: float | None = None) -> IdentificationResult:
        """Identify a trial already prepared by :meth:`prepare`."""
        start = time.perf_counter() if start is None else start
        if self.method is Method.AUTO:
            return self._auto(trial, progress, start)
        method, body, options = self.method, self.body, self.fit_options
        notices: list[str] = []
        cnn = fit = None
        relaxed_refit = False
        spent = 0.0
        if self.cnn is not None:
            began = time.perf_counter()
            cnn = self.cnn.identify(trial, self.level)
            spent = time.perf_counter() - began
            notices += cnn.notices
        began = time.perf_counter()
        if method is Method.FIT:
            # CasADi loads only when least squares runs: the CNN alone starts sooner
            from posture_id.fitting.least_squares import fit_recording

            fit = fit_recording(trial, body, None, options, progress)
        elif method is Method.HYBRID:
            fit, relaxed_refit = _refine(trial, body, cnn, options, progress, notices)
        if fit is not None:
            spent += time.perf_counter() - began
            notices += fit.notices
            parameters, normalised = fit.parameters, fit.normalised
            # the hybrid's scales are calibrated for the network's own body only
            calibration = (self.cnn.calibration if method is Method.HYBRID
                           and self.cnn.trained_on_this_body else None)
            scales = None if calibration is None else calibration.least_squares
            intervals = fit.intervals_at(self.level, scales)
            if scales is not None and scales.beyond(intervals.noise_deg):
                notices.append(f"{trial.name}: its sensor noise (about "
                               f"{intervals.noise_deg:.3f}°) is above the "
                               f"{scales.noise_deg[-1]:.3f}° the hybrid's intervals were "
                               "calibrated for: they are likely too narrow")
            trial = fit.trial  # with a fitted stimulus offset: the shifted trial
        else:
            parameters, normalised = cnn.parameters, cnn.normalised
            intervals = cnn.intervals
            notices += trial.notices
        locked = LockedProjection.for_periodic_trial(trial, LockedOptions(weighted=False))
        checked = _resimulate(body, trial, parameters, options.simulation, locked)
        body_share = checked.pop("locked_share")  # the verdict's, not a result field
        verdict = _verdict(method, options, trial, checked, body_share, cnn, fit, locked,
                           self.cnn is not None and self.cnn.reads_people_like)
        return IdentificationResult(
            method=method, parameters=parameters, normalised=np.asarray(normalised),
            class_probability=None if cnn is None else np.asarray(cnn.class_probability),
            wall_time_s=time.perf_counter() - start, identification_time_s=spent,
            joints=body.joint_names, cnn=cnn, fit=fit, intervals=intervals,
            notices=tuple(dict.fromkeys(notices)),
            provenance=provenance(options if fit is not None else None, body,
                                  recording=trial.name, method=method.value),
            verdict=verdict, relaxed_refit=relaxed_refit, **checked,
        )


    def _as(self, method: Method) -> Identifier:
        """This identifier with another method, sharing its network (none for least
        squares alone)."""
        other = copy.copy(self)
        other.method = method
        if method is Method.FIT:
            other.cnn = None
        return other

    def _auto(self, trial: PreparedTrial, progress: Progress | None,
              start: float) -> IdentificationResult:
        """:attr:`Method.AUTO`: the network's answer, refined by least squares (the hybrid)
        when its verdict is doubtful (:func:`auto_refinement`: on the locked sway when the
        recording is too noisy to check it); least squares from the body's defaults when the
        network cannot read the recording (a tilt that is not periodic, or less than one
        whole cycle of it) or identify the body (more than 3 segments)."""
        unread = self.network_refusal or _unreadable_by_network(trial)
        if unread is not None:
            fitted = self._as(Method.FIT).identify_trial(trial, progress, start)
            return replace(fitted, notices=(
                f"{trial.name}: {unread}: identified by least squares from the body's "
                "defaults (--method auto)", *fitted.notices))
        answer = self._as(Method.CNN).identify_trial(trial, progress, start)
        verdict = answer.verdict
        how = auto_refinement(verdict)
        if how is Refinement.KEEP:
            return answer
        hybrid = self._as(Method.HYBRID)
        on = "the sway"
        if how is Refinement.LOCKED:
            on = "the stimulus-locked sway"
            if self.fit_options.locked is None:
                hybrid.fit_options = replace(self.fit_options, locked=LockedOptions())
        refined = hybrid.identify_trial(trial, progress, start)
        why = "; ".join(verdict.reasons)
        return replace(refined, notices=(
            f"{trial.name}: the network's answer was doubtful ({why}): refined by least "
            f"squares on {on} (--method auto)", *refined.notices))


class Refinement(enum.Enum):
    """What ``auto`` does with the network's answer (:func:`auto_refinement`)."""

    #: keep it
    KEEP = "keep"
    #: least squares from it on every sample of the sway (the hybrid)
    RAW = "raw"
    #: least squares from it on the stimulus-locked sway (the hybrid with ``--locked``)
    LOCKED = "locked"


def auto_refinement(verdict: TrustVerdict) -> Refinement:
    """``auto``'s rule for the network's answer (measured in docs/universal.md, "The
    default method"): keep an answer that is not doubtful, and one on people-like sway
    (least squares fits the subject's own sway too; the network was trained on such
    sway). Refine a doubtful answer from its own values: on the stimulus-locked sway when
    the recording cannot check it (:attr:`~posture_id.identify.noise_check.NoiseCheck.
    unchecked`: the answer explains the recording as well as its noise allows, and that
    noise alone leaves more than 10 % of the locked sway; on motor-noisy sway, least
    squares on every sample fits the subject's own sway and ends further from the truth,
    `benchmarks/auto_rule.py`), except on a recording of one cycle, whose locked share
    cannot be measured (people-like or not, the network's answer is kept there:
    `benchmarks/auto_rule.py --cycles 1`), on every sample otherwise."""
    if not verdict.doubtful:
        return Refinement.KEEP
    share = verdict.locked_share
    if share is not None and share < PEOPLE_LIKE_SHARE:
        return Refinement.KEEP
    if verdict.noise is not None and verdict.noise.unchecked:
        # one cycle: no locked share to tell people-like sway from part-locked, and least
        # squares, raw or locked, ended further from the truth than the network on such
        # motor-noisy recordings (benchmarks/results/auto_rule_one_cycle.md)
        return Refinement.KEEP if share is None else Refinement.LOCKED
    return Refinement.RAW


def _unreadable_by_network(trial: PreparedTrial) -> str | None:
    """Why the network cannot read ``trial`` (it reads the stimulus-locked response over
    whole cycles of a periodic tilt), or None when it can."""
    if trial.stimulus.period_s is None:
        return (f"its tilt is not periodic over the {trial.recording.duration_s:.1f} s "
                "recorded, and the network reads the response to a periodic one")
    return trial.whole_cycle_shortfall()


def _refine(trial: PreparedTrial, body: Body, cnn, options: FitOptions,
            progress: Progress | None, notices: list[str]):
    """The hybrid's least squares from the CNN's answer: (the fit, whether it was fitted
    again with the classes relaxed).

    Classes the CNN is sure of (P(C = +1) outside :data:`UNSURE_CLASS` for every module)
    are kept and only the continuous parameters refined: the short route. It is accepted
    when its residual is consistent with the recording's own noise
    (:func:`~posture_id.identify.noise_check.noise_check`: stimulus-locked for a periodic
    stimulus, so that sway of the subject's own does not count against it; raw
    otherwise), whether the fit compares raw or locked sway. When the CNN is unsure of a
    class, or the short route leaves more than the noise allows (a confidently wrong
    class leaves a large locked residual), the fit runs again from the CNN's parameters
    with its classes relaxed half-way (c = ±0.5), so that it can overturn a class; the
    better of the two fits is kept.
    """
    from posture_id.fitting.least_squares import fit_recording

    low, high = UNSURE_CLASS
    unsure = [j for j, p in zip(body.joint_names, cnn.class_probability, strict=True)
              if low < p < high]
    fit = fit_short = None
    if unsure:
        notices.append(f"the CNN is unsure of the class of {', '.join(unsure)}: "
                       "least squares decides it")
    else:
        fit = fit_recording(trial, body, cnn.parameters,
                            replace(options, classes=FixedClasses()), progress)
        check = noise_check(fit.trial, fit.fitted)
        if not check.consistent:
            notices.append(f"with the CNN's classes the fit leaves a {check.sentence()}: "
                           "fitted again with the classes relaxed")
            fit_short, fit = fit, None
    if fit is None:
        relaxed = options.classes if isinstance(options.classes, RelaxedClasses) \
            else RelaxedClasses()
        fit = fit_recording(trial, body, cnn.parameters,
                            replace(options, classes=relaxed), progress)
        if fit_short is not None and fit_short.cost < fit.cost:
            fit = fit_short
    changed = [j for j in body.joint_names
               if fit.parameters[j].controls != cnn.parameters[j].controls]
    if changed:
        notices.append(f"least squares overturned the CNN's class of {', '.join(changed)}")
    return fit, fit_short is not None or bool(unsure)


def _resimulate(body: Body, trial: PreparedTrial, parameters,
                simulation: SimulationOptions, locked: LockedProjection | None) -> dict:
    """Simulate the identified model on the trial's stimulus (with any fitted offset);
    E_id, E_rel, segment fits; with ``locked`` (the trial's unweighted locked projection)
    the locked statistics too."""
    rec = trial.recording
    wide = replace(simulation, sway_limit_deg=MAX_SWAY_LIMIT_DEG)
    trial = simulate(body, parameters, trial.stimulus, wide)
    n = len(rec.time)
    theta = trial.theta[:n]
    sway_recorded = body.com_angles(rec.theta)[:, 0]
    sway_simulated = trial.alpha[:n, 0]
    e_id, e_rel = map(float, sway_errors(sway_recorded, sway_simulated))
    fell = math.isinf(e_rel)
    share = explained = body_share = None
    if locked is not None:
        share = locked.locked_share(rec.theta)
        explained = locked.explained(rec.theta, theta)
        body_share = float(locked.locked_share(np.degrees(sway_recorded)[:, None])[0])
    segments = []
    for j, name in enumerate(rec.segments):
        residual = rec.theta[:, j] - theta[:, j]
        statistics = {} if locked is None else {
            # a single cycle cannot tell noise from response: no share (None)
            "locked_share": float(share[j]) if np.isfinite(share[j]) else None,
            "locked_variance_explained": float(explained[j])}
        if fell:
            segments.append(SegmentFit(name, math.inf, -math.inf, **statistics))
            continue
        segments.append(SegmentFit(
            name, math.degrees(float(np.sqrt(np.mean(residual**2)))),
            float(1.0 - np.var(residual) / np.var(rec.theta[:, j])), **statistics))
    return {"e_id_deg": e_id, "e_rel": e_rel, "segments": tuple(segments), "time": rec.time,
            "recorded": rec.theta, "resimulated": theta, "sway_recorded": sway_recorded,
            "sway_resimulated": sway_simulated, "fell_at_s": trial.abort_time,
            "locked_share": None if body_share is None or not math.isfinite(body_share)
            else body_share}


def _verdict(method: Method, options: FitOptions, trial: PreparedTrial, checked: dict,
             share: float | None, cnn, fit, locked: LockedProjection | None,
             reads_people_like: bool = False) -> TrustVerdict:
    """The trust verdict (:mod:`posture_id.identify.verdict`) of one identification;
    ``share``: the recorded body sway's locked share; ``reads_people_like``: the network
    was trained on people-like sway (the universal model)."""
    noise = noise_check(trial, checked["resimulated"],
                        body_sway=(checked["sway_recorded"], checked["sway_resimulated"]),
                        projection=locked)
    locked_fit = options.locked is not None
    people_like = share is not None and share < PEOPLE_LIKE_SHARE
    outside = list(cnn.outside) if method is Method.CNN and cnn is not None else []
    if people_like and method is Method.CNN and not reads_people_like:
        outside.append(f"only {100 * share:.0f} % of the body sway is stimulus-locked; the "
                       "network was trained on sway that is the stimulus's response and "
                       "sensor noise")
    elif people_like and not locked_fit and method is not Method.CNN:
        outside.append(f"only {100 * share:.0f} % of the body sway is stimulus-locked: "
                       "least squares on the raw sway fits the subject's own sway too")
    on_bounds = () if fit is None else fit.on_bounds
    verdict = TrustVerdict(noise, on_bounds, tuple(outside), share)
    if not verdict.doubtful:
        return verdict
    return replace(verdict, suggestion=suggestion(method, locked_fit, share, on_bounds, noise,
                                                  options.prior_sd is not None,
                                                  reads_people_like,
                                                  _unreadable_by_network(trial) is None))
