"""Identify DEC parameters from one recording by nonlinear least squares (CasADi).

The iterative baseline the CNN is benchmarked against, and a refiner for the CNN's
answer. The model is :mod:`posture_id.fitting.symbolic` (the same plant, controller and
integrator as the fast simulator); the recorded tilt is the stimulus; the residual is
simulated minus recorded segment angles (degrees) at every sample.

Unknowns per module, scaled to O(1) as in MODEL §3 (p̃ = p/p_default − 1): K̃p, K̃i, K̃d,
Δ̃ (continuous; the delay is interpolated in the buffer) within bounds; and the class C,
found by the strategy in ``FitOptions.classes``:

- :class:`~.options.RelaxedClasses` (default): C is relaxed to c ∈ [−1, 1] (the
  controlled variable is (1+c)/2·x_COM + (1−c)/2·x_joint, exact at ±1) and fitted with the
  rest; then C = sign(c) and the continuous parameters are refitted with C fixed. One
  relaxed fit and one polish instead of 2^N fits (``benchmarks/fit.py`` measures its
  class accuracy);
- :class:`~.options.ExhaustiveClasses`: every one of the 2^N class combinations is
  fitted, the best kept;
- :class:`~.options.FixedClasses`: the classes of the initial guess are kept.

Derivatives are exact (CasADi forward mode), evaluated in parallel threads; the functions
are compiled to C and cached (:mod:`.build`, :mod:`.problem`). Inside the exact stages
only, the tilt estimator's dead-band is smoothed (softplus of width
``smooth_deadband_rad_s``). Standard errors come from the Gauss-Newton approximation
σ²(JᵀJ)⁻¹ with σ the residual RMS, floored at ``noise_floor_deg``; a parameter whose 95 %
interval is wider than ±``precision_rel`` of its value is flagged as poorly determined.
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import replace

import numpy as np

from posture_id.bodies.body import Body
from posture_id.dec.parameters import (
    TARGET_FIELDS,
    DecParameters,
    normalise,
)
from posture_id.dec.prior import relative_factors
from posture_id.fitting.evaluators import (
    ExactEvaluator,
    LockedResidual,
    SimulatorEvaluator,
    SwayResidual,
    run_stage,
)
from posture_id.fitting.options import (
    ExhaustiveClasses,
    FitError,
    FitOptions,
    FixedClasses,
    RelaxedClasses,
)
from posture_id.fitting.prepare import prepare_recording
from posture_id.fitting.problem import FitProblem
from posture_id.fitting.result import FitResult, StageResult, class_names
from posture_id.fitting.symbolic import step_inputs
from posture_id.fitting.unknowns import (
    parameters_from_qs,
    passive_normalised,
    q_from_targets,
    targets_from_q,
)
from posture_id.frf.locked import LockedProjection
from posture_id.progress import Progress, report
from posture_id.provenance import provenance
from posture_id.recording import Recording
from posture_id.simulation.stimulus import TiltProfile

__all__ = ["fit_recording"]


def fit_recording(
    recording: Recording,
    body: Body,
    init: DecParameters | None = None,
    options: FitOptions | None = None,
    progress: Progress | None = None,
    source: str = "recording",
    problem: FitProblem | None = None,
    stimulus: TiltProfile | None = None,
) -> FitResult:
    """Fit every module's Kp, Ki, Kd, Δ and class to one recording.

    Args:
        recording: tilt and segment angles in space (segments must be the body's).
        body: the body. init: initial guess (default: the body's defaults).
        options: see :class:`~.options.FitOptions`. progress: told each stage's status.
        source: the recording's name in messages.
        problem: a :class:`~.problem.FitProblem` to reuse (default: the cached one for
            this body, recording length and options).
        stimulus: the tilt as the lab ran it (:func:`~posture_id.simulation.prts` with its
            onset, starting state, sign and lag, or a tilt file); the recording's tilt
            column is checked against it. Default: recognised from the tilt column.
    """
    options = options or FitOptions()
    recording.check_segments(body.segment_names, source)

    def say(message: str) -> None:
        report(progress, 0, None, "message", message)

    start = time.perf_counter()
    recording, stim, notices = prepare_recording(recording, source, options, stimulus)
    for notice in notices:
        say(notice)
    n = body.n_segments
    n_samples = len(recording.time)
    if problem is None:
        problem = FitProblem.get(body, n_samples, options, notify=say)
    elif problem.key.n_samples != n_samples or problem.key.body != body:
        raise ValueError("the given FitProblem was built for another body or recording length")
    if not problem.backend.compiled:
        notices.append(f"CasADi runs in its virtual machine ({problem.backend.reason}): slower")
    sim = options.simulation
    tilt, tilt_vel = stim.on_grid(sim.dt, problem.n_steps_u)
    u = step_inputs(tilt, tilt_vel, problem.n_steps_u)
    measured = recording.theta
    defaults = problem.defaults
    start_params = init or defaults
    guess = q_from_targets(normalise(start_params, defaults),
                           passive_normalised(start_params, defaults))
    lower, upper = _bounds(options, n)
    guess = np.where(np.arange(len(guess)) // n == 4, guess, np.clip(guess, lower, upper))
    passive = guess[5 * n :]  # kept, or fitted with the continuous parameters

    def assemble(gains_delays: np.ndarray, classes: np.ndarray) -> np.ndarray:
        return np.concatenate([np.clip(gains_delays, lower[: 4 * n], upper[: 4 * n]), classes,
                               passive])

    fitted_passive = list(range(5 * n, 7 * n)) if options.fit_passive else []
    continuous = list(range(4 * n)) + fitted_passive
    everything = list(range(5 * n)) + fitted_passive
    target = _target(recording, stim, options, source)
    prior_sd = (None if options.prior_sd is None
                else np.array([options.prior_sd] * 4 * n + [np.inf] * n
                              + [options.prior_sd] * 2 * n))
    exact = ExactEvaluator(problem, u, measured, target)
    warm = SimulatorEvaluator(body, defaults, stim, sim, measured, target)
    first_evaluator, first_tolerance, first_limit = (
        (warm, options.warm_tolerance, options.max_iterations) if options.warm_start
        else (exact, options.tolerance, options.max_iterations))
    stages: list[StageResult] = []

    def stage(name, evaluator, q0, free, tolerance, limit) -> StageResult:
        result = run_stage(name, evaluator, q0, free, lower, upper, tolerance, limit, progress,
                           prior_sd)
        stages.append(result)
        return result

    suffix = " (simulator)" if options.warm_start else ""
    chosen = None  # the warm fit with the classes fixed, when they are
    if isinstance(options.classes, RelaxedClasses):
        # the guess (classes half-way to their values), then draws of the MODEL §5 prior
        rng = np.random.default_rng(options.classes.seed)
        starts = [assemble(guess[: 4 * n], 0.5 * guess[4 * n : 5 * n])]
        for _ in range(options.classes.starts - 1):
            starts.append(assemble(relative_factors(rng, 4 * n) - 1, np.zeros(n)))
        tries = []
        for k, q0 in enumerate(starts):
            label = "relaxed classes" + (f", start {k + 1}/{len(starts)}" if k else "")
            tries.append(stage(label + suffix, first_evaluator, q0, everything,
                               first_tolerance, first_limit))
        best_relaxed = min(tries, key=lambda t: t.cost)
        signs = np.where(best_relaxed.q[4 * n : 5 * n] >= 0, 1.0, -1.0)
        say(f"classes from the relaxed fit: {class_names(signs)}")
        start_q = best_relaxed.q.copy()
        start_q[4 * n : 5 * n] = signs
    else:
        combos = (itertools.product((1.0, -1.0), repeat=n)
                  if isinstance(options.classes, ExhaustiveClasses) else [guess[4 * n : 5 * n]])
        candidates = []
        for combo in combos:
            q0 = assemble(guess[: 4 * n], np.asarray(combo, dtype=float))
            candidates.append(stage(f"classes {class_names(combo)}{suffix}", first_evaluator,
                                    q0, continuous, first_tolerance, first_limit))
        chosen = min(candidates, key=lambda s: s.cost)
        start_q = chosen.q
    if chosen is not None and options.warm_start and chosen.converged:
        # the warm start solved the final problem (classes fixed): the exact model only
        # gives the Jacobian at its optimum, for the standard errors (docs/fit.md)
        best = stage("exact Jacobian at the optimum", exact, start_q, continuous,
                     options.tolerance, 1)
        best = replace(best, converged=True, status=chosen.status)
        stages[-1] = best
    else:
        best = stage("polish (exact derivatives)", exact, start_q, continuous,
                     options.tolerance,
                     options.polish_iterations if options.warm_start else options.max_iterations)

    normalised = targets_from_q(best.q)
    params = parameters_from_qs(best.q[None], defaults).trial(0, body.joint_names)
    se_norm, se_phys, poorly, residual_sd = _standard_errors(best, params, defaults, options,
                                                             n)
    fitted = problem.simulate(best.q, u)
    result = FitResult(
        parameters=params, normalised=normalised, standard_errors=se_phys,
        standard_errors_normalised=se_norm, poorly_determined=poorly,
        converged=best.converged, iterations=sum(s.iterations for s in stages),
        evaluations=sum(s.evaluations for s in stages),
        wall_time_s=time.perf_counter() - start, cost=best.cost,
        rms_deg=float(np.degrees(np.sqrt(np.mean((exact.simulated(best.q) - measured) ** 2)))),
        stages=tuple(stages),
        backend=str(problem.backend), notices=tuple(notices), time=recording.time,
        recorded=measured, fitted=fitted, segments=body.segment_names,
        joints=body.joint_names, provenance=provenance(options, body, source=source),
        residual_sd=residual_sd, noise_floor_deg=options.noise_floor_deg,
    )
    if options.locked is None or options.locked.max_offset_s == 0:
        return result
    # the stimulus's time offset: the one that best aligns the fitted locked sway with the
    # recorded one, then the fit again with the stimulus shifted by it (classes kept);
    # repeated while the offset still moves by a millisecond or more (at most 4 times)
    offset, fit = 0.0, result
    fixed = replace(options, classes=FixedClasses(),
                    locked=replace(options.locked, max_offset_s=0.0))
    for _ in range(4):
        step = target.projection.best_offset(np.degrees(fit.fitted), np.degrees(measured),
                                             options.locked.max_offset_s)
        if abs(step) < 1e-3 or abs(offset + step) > options.locked.max_offset_s:
            break
        offset += step
        say(f"stimulus time offset {1000 * offset:+.0f} ms; fitting again with it")
        shifted = stim.delayed(offset)
        aligned = Recording(recording.time, shifted.angle(recording.time), recording.theta,
                            recording.segments)
        again = fit_recording(aligned, body, fit.parameters, fixed, progress, source,
                              stimulus=shifted)
        fit = replace(again, stages=fit.stages + again.stages,
                      iterations=fit.iterations + again.iterations,
                      evaluations=fit.evaluations + again.evaluations)
    return replace(fit, time_offset_s=offset, wall_time_s=time.perf_counter() - start,
                   notices=tuple(dict.fromkeys(result.notices + fit.notices)),
                   time=result.time, recorded=result.recorded, provenance=result.provenance)


def _target(recording: Recording, stimulus: TiltProfile, options: FitOptions,
            source: str) -> SwayResidual:
    """What the fit compares: every sample, or the weighted stimulus-locked harmonics."""
    if options.locked is None:
        return SwayResidual()
    if stimulus.period_s is None:
        raise FitError(f"{source}: the locked fit compares stimulus cycles, and this tilt is "
                       "not periodic (name the PRTS the lab ran, or fit the raw sway)")
    projection = LockedProjection.for_recording(
        recording.tilt, np.degrees(recording.theta), recording.sample_rate_hz,
        stimulus.period_s, stimulus.periodic_from_s, options.locked, source)
    return LockedResidual(projection)


def _standard_errors(best: StageResult, params: DecParameters, defaults: DecParameters,
                     options: FitOptions, n: int):
    """Gauss-Newton standard errors (N, 4) normalised and physical, the flags, and the
    residual SD before the floor."""
    jac = best.jacobian
    r = best.residual
    dof = max(len(r) - jac.shape[1], 1)
    residual_sd = math.sqrt(float(r @ r) / dof)
    sigma = max(residual_sd, options.noise_floor_deg)
    with np.errstate(divide="ignore", invalid="ignore"):
        try:
            cov = sigma**2 * np.linalg.inv(jac.T @ jac)
            se_z = np.sqrt(np.clip(np.diag(cov), 0, None))
        except np.linalg.LinAlgError:
            se_z = np.full(jac.shape[1], np.inf)
    se_norm = se_z[: 4 * n].reshape(4, n).T  # the passive terms, when fitted, follow
    default_values = np.column_stack([defaults.array(f) for f in TARGET_FIELDS])
    se_phys = se_norm * default_values
    values = np.column_stack([params.array(f) for f in TARGET_FIELDS])
    with np.errstate(divide="ignore", invalid="ignore"):
        poorly = ~(1.96 * se_phys <= options.precision_rel * np.abs(values))
    return se_norm, se_phys, poorly, residual_sd


def _bounds(options: FitOptions, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(7N,) lower and upper bounds of q: gains, delays, classes in [−1, 1], and the
    passive terms within the gains' bounds."""
    lo = ([options.gain_bounds[0]] * 3 * n + [options.delay_bounds[0]] * n + [-1.0] * n
          + [options.gain_bounds[0]] * 2 * n)
    hi = ([options.gain_bounds[1]] * 3 * n + [options.delay_bounds[1]] * n + [1.0] * n
          + [options.gain_bounds[1]] * 2 * n)
    return np.array(lo), np.array(hi)
