"""Identify DEC parameters from one recording by nonlinear least squares (CasADi).

The iterative baseline the CNN is benchmarked against, and a refiner for the CNN's
answer. The model is :mod:`posture_id.fitting.symbolic` (the same plant, controller and
integrator as the fast simulator); the recorded tilt is the stimulus; the residual is
simulated minus recorded segment angles (degrees) at every sample.

Unknowns per module, scaled to O(1) as in docs/model.md §3 (p̃ = p/p_default − 1): K̃p, K̃i, K̃d,
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
from posture_id.fitting.class_stages import first_stages
from posture_id.fitting.evaluators import (
    Evaluator,
    ExactEvaluator,
    LockedResidual,
    SimulatorEvaluator,
    SwayResidual,
    run_stage,
)
from posture_id.fitting.options import FitError, FitOptions, FixedClasses
from posture_id.fitting.problem import FitProblem
from posture_id.fitting.result import FitResult, StageResult
from posture_id.fitting.structure import cluster_robust_covariance
from posture_id.fitting.symbolic import step_inputs
from posture_id.fitting.unknowns import (
    UnknownLayout,
    parameters_from_qs,
    passive_normalised,
    q_from_targets,
    targets_from_q,
)
from posture_id.frf.locked import LockedProjection
from posture_id.progress import Progress, report
from posture_id.provenance import provenance, recording_identity
from posture_id.trials import PreparedTrial

__all__ = ["fit_recording", "FitRun"]

#: The offset search: the candidate offsets fitted first, then at most this many re-fits,
#: stopping when the offset moves by less than this, s.
OFFSET_TRIES, OFFSET_ROUNDS, OFFSET_SETTLED_S = 3, 4, 1e-3


def fit_recording(
    trial: PreparedTrial,
    body: Body,
    init: DecParameters | None = None,
    options: FitOptions | None = None,
    progress: Progress | None = None,
    problem: FitProblem | None = None,
) -> FitResult:
    """Fit every module's Kp, Ki, Kd, Δ and class to one prepared recording.

    Args:
        trial: the recording at the model's rate with its stimulus
            (:func:`~posture_id.trials.prepare_trial`); its segments must be the body's.
        body: The body recorded.
        init: The initial guess (None: the body's defaults).
        options: The fit's options (:class:`~.options.FitOptions`; None: the defaults).
        progress: Told each stage's status (None: silent).
        problem: a :class:`~.problem.FitProblem` to reuse (default: the cached one for
            this body, recording length and options).

    Returns:
        The fit; its ``trial`` is the one fitted: with a fitted stimulus time offset
        (``LockedOptions.max_offset_s``), the trial shifted by it.
    """
    options = options or FitOptions()
    start = time.perf_counter()
    _check_offset_range(trial, options)  # before any work
    run = FitRun.start(trial, body, options, progress, problem)
    result = run.fit(init or run.problem.defaults)
    if options.locked is not None and options.locked.max_offset_s > 0:
        result = _search_offset(run, result)
    return replace(result, wall_time_s=time.perf_counter() - start)


class FitRun:
    """One prepared trial against one compiled problem: the stages of a fit.

    Built by :meth:`start` (checks, the compiled problem, the residual's target); :meth:`fit`
    runs the class strategy's first stages, then the polish, and assembles the result.
    """

    def __init__(self, trial: PreparedTrial, body: Body, options: FitOptions,
                 progress: Progress | None, problem: FitProblem, notices: list[str]) -> None:
        self.trial, self.body, self.options, self.progress = trial, body, options, progress
        self.problem, self.notices = problem, notices
        self.layout = UnknownLayout(body.n_segments)
        self.lower, self.upper = search_bounds(options, self.layout)
        sim = options.simulation
        tilt, tilt_vel = trial.stimulus.on_grid(sim.dt, problem.n_steps_u)
        self.u = step_inputs(tilt, tilt_vel, problem.n_steps_u)
        self.measured = trial.recording.theta
        self.target = _target(trial, options)
        self.prior_sd, self.prior_centre = _prior(options, self.layout)
        self.exact = ExactEvaluator(problem, self.u, self.measured, self.target)
        self.warm = SimulatorEvaluator(body, problem.defaults, trial.stimulus, sim,
                                       self.measured, self.target)
        self.stages: list[StageResult] = []

    @classmethod
    def start(cls, trial: PreparedTrial, body: Body, options: FitOptions,
              progress: Progress | None, problem: FitProblem | None = None) -> FitRun:
        trial.require_segments(body.segment_names)
        if options.min_duration_s is not None:
            trial.require_duration(options.min_duration_s, "the least duration asked for "
                                                          f"({options.min_duration_s:g} s)")
        else:
            trial.require_whole_cycle()
        notices = list(trial.notices)  # said once, with the result (not as progress too)
        n_samples = len(trial.recording.time)
        if problem is None:
            problem = FitProblem.get(body, n_samples, options, notify=lambda message: report(
                progress, 0, None, "message", message))
        elif problem.key.n_samples != n_samples or problem.key.body != body:
            raise ValueError("the given FitProblem was built for another body or recording "
                             "length")
        if not problem.backend.compiled:
            notices.append(f"CasADi runs in its virtual machine ({problem.backend.reason}): "
                           "slower")
        return cls(trial, body, options, progress, problem, notices)

    def say(self, message: str) -> None:
        report(self.progress, 0, None, "message", message)

    # what the class strategies call (class_stages.first_stages)
    @property
    def first_evaluator(self) -> tuple[Evaluator, float, int]:
        """The evaluator of the first stages, their tolerance and iteration limit."""
        if self.options.warm_start:
            return self.warm, self.options.warm_tolerance, self.options.max_iterations
        return self.exact, self.options.tolerance, self.options.max_iterations

    @property
    def suffix(self) -> str:
        return " (simulator)" if self.options.warm_start else ""

    def assemble(self, guess: np.ndarray, gains_delays: np.ndarray,
                 classes: np.ndarray) -> np.ndarray:
        """q with these gains and delays (clipped to the bounds) and classes, and the
        passive terms of ``guess``."""
        q = guess.copy()
        lay = self.layout
        q[lay.gains_delays] = np.clip(gains_delays, self.lower[lay.gains_delays],
                                      self.upper[lay.gains_delays])
        q[lay.classes] = classes
        return q

    def stage(self, name: str, evaluator: Evaluator, q0: np.ndarray, free: list[int],
              tolerance: float, limit: int) -> StageResult:
        """Run one bounded stage and keep it."""
        result = run_stage(name, evaluator, q0, free, self.lower, self.upper, tolerance,
                           limit, self.progress, self.prior_sd, self.prior_centre)
        self.stages.append(result)
        return result

    def fit(self, init: DecParameters) -> FitResult:
        """The strategy's first stages from ``init``, the polish, and the result."""
        self.stages = []
        start = time.perf_counter()
        defaults, lay, options = self.problem.defaults, self.layout, self.options
        guess = q_from_targets(normalise(init, defaults), passive_normalised(init, defaults))
        free = np.ones(lay.size, bool)
        free[lay.classes] = False  # classes are never clipped: ±1, or relaxed in between
        guess = np.where(free, np.clip(guess, self.lower, self.upper), guess)
        start_q, chosen = first_stages(options.classes, self, guess)
        continuous = lay.continuous(options.fit_passive)
        if chosen is not None and options.warm_start and chosen.converged:
            # the warm start solved the final problem (classes fixed): the exact model only
            # gives the Jacobian at its optimum, for the standard errors (docs/fit.md)
            best = self.stage("exact Jacobian at the optimum", self.exact, start_q,
                              continuous, options.tolerance, 1)
            best = replace(best, converged=True, status=chosen.status)
            self.stages[-1] = best
        else:
            best = self.stage("polish (exact derivatives)", self.exact, start_q, continuous,
                              options.tolerance, options.polish_iterations
                              if options.warm_start else options.max_iterations)
        return self._result(best, time.perf_counter() - start)

    def _result(self, best: StageResult, seconds: float) -> FitResult:
        defaults, body = self.problem.defaults, self.body
        params = parameters_from_qs(best.q[None], defaults).trial(0, body.joint_names)
        se_norm, se_phys, poorly, residual_sd, white = _standard_errors(
            best, params, defaults, self.options, self.layout, self.target.clusters())
        rms = np.sqrt(np.mean((self.exact.simulated(best.q) - self.measured) ** 2))
        return FitResult(
            parameters=params, normalised=targets_from_q(best.q), standard_errors=se_phys,
            standard_errors_normalised=se_norm, white_standard_errors_normalised=white,
            poorly_determined=poorly,
            converged=best.converged, iterations=sum(s.iterations for s in self.stages),
            evaluations=sum(s.evaluations for s in self.stages), wall_time_s=seconds,
            cost=best.cost, rms_deg=float(np.degrees(rms)), stages=tuple(self.stages),
            backend=str(self.problem.backend), notices=tuple(self.notices),
            time=self.trial.recording.time, recorded=self.measured,
            fitted=self.problem.simulate(best.q, self.u), segments=body.segment_names,
            joints=body.joint_names,
            provenance=provenance(self.options, body, **recording_identity(
                self.trial.name, self.trial.recording.source)),
            residual_sd=residual_sd, noise_floor_deg=self.options.noise_floor_deg,
            time_offset_s=self.trial.time_offset_s, trial=self.trial, defaults=defaults,
            on_bounds=self._on_bounds(best.q, params),
            precision_rel=self.options.precision_rel)

    def _on_bounds(self, q: np.ndarray, params: DecParameters) -> tuple[str, ...]:
        """The fitted parameters that ended within 0.1 % of the search range of a bound."""
        lay, out = self.layout, []
        names = (*TARGET_FIELDS, "class", "kpas", "bpas")
        for k in lay.continuous(self.options.fit_passive):
            margin = 1e-3 * (self.upper[k] - self.lower[k])
            side = ("lower" if q[k] <= self.lower[k] + margin
                    else "upper" if q[k] >= self.upper[k] - margin else None)
            if side is not None:
                field_name, joint = names[k // lay.n], self.body.joint_names[k % lay.n]
                value = params.array(field_name)[k % lay.n]
                shown = "0" if abs(value) < 1e-6 else f"{value:.4g}"  # the search's 1e-11
                out.append(f"{joint} {field_name} at its {side} bound ({shown})")
        return tuple(out)


def _search_offset(run: FitRun, result: FitResult) -> FitResult:
    """The stimulus's time offset. First the offsets at the deepest minima of the distance
    between the fitted locked sway, shifted, and the recorded one (:data:`OFFSET_TRIES`:
    over a wide range that distance has a minimum every stimulated period), each fitted
    again with the stimulus shifted by it (classes kept), the best fit kept; then, from
    it, the best offset again while it still moves to one not tried (at most
    :data:`OFFSET_ROUNDS` times), the fit of least cost over all of them kept. Every
    shifted trial analyses the moved stimulus's own whole cycles
    (:meth:`~posture_id.trials.PreparedTrial.shifted_whole`). The result's trial is the
    shifted one, so that what re-simulates it uses the offset.
    """
    limit = run.options.locked.max_offset_s  # within half a cycle (fit_recording checked)
    fixed = replace(run.options, classes=FixedClasses(),
                    locked=replace(run.options.locked, max_offset_s=0.0))
    projection = run.target.projection
    measured = np.degrees(run.measured)
    stages = list(result.stages)

    def fit_shifted(trial: PreparedTrial, start: FitResult) -> FitResult:
        run.say(f"stimulus time offset {1000 * trial.time_offset_s:+.0f} ms; fitting again "
                "with it")
        again = FitRun(trial, run.body, fixed, run.progress, run.problem, list(run.notices))
        fitted = again.fit(start.parameters)
        stages.extend(fitted.stages)
        return fitted

    # a candidate's cycles are counted from where its stimulus starts (a second's shift
    # later must not analyse a second of lead-in as the first cycle's start)
    candidates = [result] + [
        fit_shifted(shifted, result)
        for offset in projection.best_offsets(np.degrees(result.fitted), measured, limit,
                                              OFFSET_TRIES)
        if abs(offset) >= OFFSET_SETTLED_S
        and (shifted := run.trial.shifted_whole(offset)) is not None]
    fit = best = min(candidates, key=lambda f: f.cost)
    base = run.trial.time_offset_s  # offsets below are from the trial given
    seen = {round(f.trial.time_offset_s - base, 3) for f in candidates}
    for _ in range(OFFSET_ROUNDS):
        step = projection.best_offset(np.degrees(fit.fitted), measured, limit)
        total = fit.trial.time_offset_s - base + step
        if (abs(step) < OFFSET_SETTLED_S or abs(total) > limit
                or round(total, 3) in seen):  # settled, out of range, or back again
            break
        shifted = run.trial.shifted_whole(total)
        if shifted is None:
            break
        seen.add(round(total, 3))
        fit = fit_shifted(shifted, fit)
        best = min(best, fit, key=lambda f: f.cost)
    fit = best  # the best offset seen, not the last: two offsets can trade places
    return replace(fit, stages=tuple(stages), iterations=sum(s.iterations for s in stages),
                   evaluations=sum(s.evaluations for s in stages),
                   provenance=result.provenance)


def _target(trial: PreparedTrial, options: FitOptions) -> SwayResidual:
    """What the fit compares: every sample, or the weighted stimulus-locked harmonics."""
    if options.locked is None:
        return SwayResidual()
    if trial.stimulus.period_s is None:
        raise FitError(f"{trial.name}: the locked fit compares stimulus cycles, and this tilt is "
                       "not periodic (name the PRTS the lab ran, or fit the raw sway)")
    return LockedResidual(LockedProjection.for_trial(trial, options.locked))


def _standard_errors(best: StageResult, params: DecParameters, defaults: DecParameters,
                     options: FitOptions, layout: UnknownLayout,
                     clusters: np.ndarray | None = None):
    """Standard errors (N, 4) normalised and physical, the flags, the residual SD before
    the floor, and the Gauss-Newton standard errors (N, 4) normalised of a residual of
    independent rows. The standard errors are those, or with ``clusters`` (the group of
    each data row: :meth:`~posture_id.fitting.evaluators.SwayResidual.clusters`) the
    cluster-robust ones (:mod:`.structure`) where they are larger."""
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
    white = se_z[layout.gains_delays].reshape(4, layout.n).T
    robust = None if clusters is None else cluster_robust_covariance(jac, r, clusters)
    if robust is not None:
        se_z = np.maximum(se_z, np.sqrt(np.clip(np.diag(robust), 0, None)))
    se_norm = se_z[layout.gains_delays].reshape(4, layout.n).T  # the passive terms follow
    default_values = np.column_stack([defaults.array(f) for f in TARGET_FIELDS])
    se_phys = se_norm * default_values
    values = np.column_stack([params.array(f) for f in TARGET_FIELDS])
    with np.errstate(divide="ignore", invalid="ignore"):
        poorly = ~(1.96 * se_phys <= options.precision_rel * np.abs(values))
    return se_norm, se_phys, poorly, residual_sd, white


def search_bounds(options: FitOptions, layout: UnknownLayout) -> tuple[np.ndarray, np.ndarray]:
    """(7N,) lower and upper bounds of q: gains, delays, classes in [−1, 1], and the
    passive terms within the gains' bounds."""
    bounds = []
    for side in (0, 1):
        b = layout.per_unknown(options.gain_bounds[side], (-1.0, 1.0)[side],
                               options.gain_bounds[side])
        b[3 * layout.n : 4 * layout.n] = options.delay_bounds[side]  # Δ̃ after the gains
        bounds.append(b)
    return bounds[0], bounds[1]


def _check_offset_range(trial: PreparedTrial, options: FitOptions) -> None:
    """Refuse a stimulus offset search wider than half a stimulus cycle (an offset of a
    whole cycle cannot be told from none)."""
    if options.locked is None or options.locked.max_offset_s <= 0:
        return
    limit, period = options.locked.max_offset_s, trial.stimulus.period_s
    if period is not None and limit > period / 2 + 1e-9:
        raise FitError(f"{trial.name}: max_offset_s {limit:g} s is more than half a "
                       f"stimulus cycle ({period / 2:g} s): an offset of a whole cycle "
                       "cannot be told from none")


def _prior(options: FitOptions, layout: UnknownLayout
           ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(7N,) the prior's SD of every unknown (inf: none) and its centre, from
    ``options.prior_sd`` and ``prior_centre`` (None, None without a prior)."""
    if options.prior_sd is None:
        return None, None
    n = layout.size
    four = 4 * layout.n
    sd = layout.per_unknown(np.inf, np.inf, np.inf)
    centre = np.zeros(n)
    if isinstance(options.prior_sd, tuple):
        if len(options.prior_sd) != four:
            raise FitError(f"prior_sd holds {len(options.prior_sd)} values; this body needs "
                           f"{four} (Kp, Ki, Kd and delay of each of its {layout.n} modules)")
        sd[layout.gains_delays] = options.prior_sd
        sd[layout.passive] = float(np.median(options.prior_sd))
    else:
        sd = layout.per_unknown(options.prior_sd, np.inf, options.prior_sd)
    if options.prior_centre is not None:
        if len(options.prior_centre) != four:
            raise FitError(f"prior_centre holds {len(options.prior_centre)} values; this "
                           f"body needs {four}")
        centre[layout.gains_delays] = options.prior_centre
    return sd, centre
