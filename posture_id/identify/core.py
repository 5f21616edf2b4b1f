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
  when it is sure of them and the fit then explains the sway, otherwise relaxed so that the
  fit can overturn a class (:func:`_refine`; docs/identify.md).

Every result is checked by simulating the identified model on the recording's tilt: the
body-sway errors E_id and E_rel (MODEL §7) and each segment's residual.
"""

from __future__ import annotations

import enum
import math
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from posture_id.bodies.body import Body, load_body
from posture_id.dec.parameters import default_parameters
from posture_id.fitting.options import FitOptions, FixedClasses, RelaxedClasses
from posture_id.identify.result import IdentificationResult, SegmentFit
from posture_id.learning.identifier import DEFAULT_LEVEL, CnnIdentifier
from posture_id.progress import Progress
from posture_id.provenance import provenance
from posture_id.recording import Recording
from posture_id.simulation.batch import simulate
from posture_id.simulation.options import MAX_SWAY_LIMIT_DEG, SimulationOptions
from posture_id.simulation.stimulus import (
    TiltProfile,
    check_recorded_tilt,
    recognise_prts,
    tilt_from_array,
)

__all__ = ["Method", "identify"]

#: The CNN is said to be unsure of a class when P(C = +1) is inside this band.
UNSURE_CLASS = (0.05, 0.95)
#: The hybrid's fit with the CNN's classes must explain this share of the recorded sway's
#: variance, or it is done again with the classes relaxed.
MIN_EXPLAINED = 0.9


class Method(enum.Enum):
    """How to identify (see the module doc)."""

    CNN = "cnn"
    FIT = "fit"
    HYBRID = "hybrid"


def identify(recording: Recording, body: Body | None = None, method: Method = Method.HYBRID,
             model: str | Path | CnnIdentifier | None = None,
             fit_options: FitOptions | None = None, progress: Progress | None = None,
             source: str = "recording", stimulus: TiltProfile | None = None,
             level: float = DEFAULT_LEVEL) -> IdentificationResult:
    """Identify every module's Kp, Ki, Kd, Δ and class from one recording.

    Args:
        recording: tilt and segment angles (the body's segments). body: default the TIP.
        method: :class:`Method`. model: a model directory or a loaded
            :class:`~posture_id.learning.identifier.CnnIdentifier` (default: the bundled
            model for the body). fit_options: for the least-squares stage.
        progress: told the fit's stages. source: the recording's name in messages.
        stimulus: the tilt as the lab ran it (checked against the recording's tilt column;
            see :func:`~posture_id.fitting.least_squares.fit_recording`); default:
            recognised from the tilt column.
        level: the intervals' nominal coverage (docs/uncertainty.md): the CNN's are
            conformal; least squares' are its Gauss-Newton standard errors times the scale
            calibrated for the hybrid (:mod:`.calibration`), or ±z·SE, unchecked, for a fit
            from the defaults or a model without that calibration.
    """
    body = body or load_body()
    start = time.perf_counter()
    options = fit_options or FitOptions()
    notices: list[str] = []
    cnn = fit = None
    if stimulus is not None and method is Method.CNN:  # least squares checks it itself
        check_recorded_tilt(recording.time, recording.tilt, stimulus, source)
    if method in (Method.CNN, Method.HYBRID):
        identifier = CnnIdentifier.resolve(model, body)
        began = time.perf_counter()
        cnn = identifier.identify(recording, source, level)
        spent = time.perf_counter() - began
        notices += cnn.notices
    else:
        spent = 0.0
    began = time.perf_counter()
    if method is Method.FIT:
        # CasADi loads only when least squares runs: the CNN alone starts half a second sooner
        from posture_id.fitting.least_squares import fit_recording

        fit = fit_recording(recording, body, None, options, progress, source,
                            stimulus=stimulus)
    elif method is Method.HYBRID:
        fit = _refine(recording, body, cnn, options, progress, source, notices, stimulus)
    spent += time.perf_counter() - began if fit is not None else 0.0
    if fit is not None:
        notices += [n for n in fit.notices if n not in notices]
        parameters, normalised = fit.parameters, fit.normalised
        calibration = identifier.calibration if method is Method.HYBRID else None
        intervals = fit.intervals(default_parameters(body), level, None if calibration is None
                                  else calibration.least_squares)
    else:
        parameters, normalised = cnn.parameters, cnn.normalised
        intervals = cnn.intervals
    checked = _resimulate(body, recording, parameters, options.simulation, stimulus)
    return IdentificationResult(
        method=method.value, parameters=parameters, normalised=np.asarray(normalised),
        class_probability=None if cnn is None else np.asarray(cnn.class_probability),
        wall_time_s=time.perf_counter() - start, identification_time_s=spent,
        joints=body.joint_names,
        cnn=None if cnn is None else cnn.to_dict(),
        fit=None if fit is None else {k: v for k, v in fit.to_dict().items()
                                      if k != "provenance"},
        intervals=intervals,
        notices=tuple(notices),
        provenance=provenance(options if fit is not None else None, body, source=source,
                              method=method.value),
        **checked,
    )


def _refine(recording: Recording, body: Body, cnn, options: FitOptions,
            progress: Progress | None, source: str, notices: list[str],
            stimulus: TiltProfile | None = None):
    """The hybrid's least squares from the CNN's answer.

    Classes the CNN is sure of (P(C = +1) outside :data:`UNSURE_CLASS` for every module)
    are kept and only the continuous parameters refined: the short route. When the CNN is
    unsure of a class, or the short route explains less than :data:`MIN_EXPLAINED` of the
    recorded sway's variance (a confidently wrong class leaves a large residual), the fit
    runs again from the CNN's parameters with its classes relaxed half-way (c = ±0.5), so
    that it can overturn a class; the better of the two fits is kept.
    """
    from posture_id.fitting.least_squares import fit_recording

    low, high = UNSURE_CLASS
    unsure = [j for j, p in zip(body.joint_names, cnn.class_probability, strict=True)
              if low < p < high]
    fit, explained = None, -math.inf
    if unsure:
        notices.append(f"the CNN is unsure of the class of {', '.join(unsure)}: "
                       "least squares decides it")
    else:
        fit = fit_recording(recording, body, cnn.parameters,
                            replace(options, classes=FixedClasses()), progress, source,
                            stimulus=stimulus)
        explained = _explained(fit.recorded, fit.fitted)
        if explained < MIN_EXPLAINED:
            notices.append(f"with the CNN's classes the fit explains {100 * explained:.0f} % "
                           "of the sway's variance: fitted again with the classes relaxed")
    if fit is None or explained < MIN_EXPLAINED:
        relaxed = options.classes if isinstance(options.classes, RelaxedClasses) \
            else RelaxedClasses()
        again = fit_recording(recording, body, cnn.parameters,
                              replace(options, classes=relaxed), progress, source,
                              stimulus=stimulus)
        if fit is None or again.cost < fit.cost:
            fit = again
    changed = [j for j in body.joint_names
               if fit.parameters[j].controls != cnn.parameters[j].controls]
    if changed:
        notices.append(f"least squares overturned the CNN's class of {', '.join(changed)}")
    return fit


def _explained(recorded: np.ndarray, fitted: np.ndarray) -> float:
    """Share of the variance of (S, N) ``recorded`` explained by ``fitted`` (all segments
    pooled); −inf when the fitted model fell."""
    residual = recorded - fitted
    if not np.all(np.isfinite(residual)):
        return -math.inf
    return float(1.0 - residual.var(axis=0).sum() / recorded.var(axis=0).sum())


def _resimulate(body: Body, recording: Recording, parameters, simulation: SimulationOptions,
                stimulus: TiltProfile | None = None) -> dict:
    """Simulate the identified model on the recording's tilt (or the named stimulus);
    E_id, E_rel, segment fits."""
    rec = recording.resampled(simulation.sample_rate_hz)
    stimulus = stimulus or recognise_prts(rec.time, rec.tilt) or tilt_from_array(
        rec.time, rec.tilt, "the recording's tilt")
    wide = replace(simulation, sway_limit_deg=MAX_SWAY_LIMIT_DEG)
    trial = simulate(body, parameters, stimulus, wide)
    n = len(rec.time)
    theta = trial.theta[:n]
    sway_recorded = body.com_angles(rec.theta)[:, 0]
    sway_simulated = trial.alpha[:n, 0]
    diff = sway_recorded - sway_simulated
    fell = not np.all(np.isfinite(diff))
    e_id = math.inf if fell else math.degrees(float(np.linalg.norm(diff))) / n
    e_rel = math.inf if fell else float(np.linalg.norm(diff) / np.linalg.norm(sway_recorded))
    segments = []
    for j, name in enumerate(rec.segments):
        residual = rec.theta[:, j] - theta[:, j]
        if fell:
            segments.append(SegmentFit(name, math.inf, -math.inf))
            continue
        segments.append(SegmentFit(
            name, math.degrees(float(np.sqrt(np.mean(residual**2)))),
            float(1.0 - np.var(residual) / np.var(rec.theta[:, j]))))
    return {"e_id_deg": e_id, "e_rel": e_rel, "segments": tuple(segments), "time": rec.time,
            "recorded": rec.theta, "resimulated": theta, "sway_recorded": sway_recorded,
            "sway_resimulated": sway_simulated}
