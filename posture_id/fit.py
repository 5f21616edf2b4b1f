"""Identify DEC parameters from one recording by nonlinear least squares (CasADi).

The iterative baseline the CNN is benchmarked against, and a refiner for the CNN's
answer. The model is :mod:`posture_id.symbolic` (the same plant, controller and
integrator as the fast simulator); the recorded tilt is the stimulus; the residual is
simulated minus recorded segment angles (degrees) at every 50 Hz sample.

Unknowns per module, scaled to O(1) as in MODEL §3 (p̃ = p/p_default − 1): K̃p, K̃i, K̃d,
Δ̃ (continuous; the delay is interpolated in the buffer) within bounds; and the class C.
Classes (``FitOptions.classes``):

- ``"relaxed"`` (default): C is relaxed to c ∈ [−1, 1] (the controlled variable is
  (1+c)/2·x_COM + (1−c)/2·x_joint, exact at ±1) and fitted with the rest; then C =
  sign(c) and the continuous parameters are refitted with C fixed. One relaxed fit and
  one polish instead of 2^N fits (``benchmarks/fit.py`` measures its class accuracy);
- ``"exhaustive"``: every one of the 2^N class combinations is fitted, the best kept;
- ``"fixed"``: the classes of the initial guess are kept.

Derivatives are exact (CasADi forward mode), evaluated in parallel threads; the functions
are compiled to C and cached (:mod:`posture_id.casadi_build`). Inside the fit only, the
tilt estimator's dead-band is smoothed (softplus of width ``smooth_deadband_rad_s``).
Standard errors come from the Gauss-Newton approximation σ²(JᵀJ)⁻¹ with σ the residual
RMS, floored at ``noise_floor_deg``; a parameter whose 95 % interval is wider than
±``precision_rel`` of its value is flagged as poorly determined.
"""

from __future__ import annotations

import itertools
import json
import math
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import casadi as ca
import numpy as np

from posture_id import symbolic
from posture_id.body import Body
from posture_id.casadi_build import compile_functions
from posture_id.errors import RecordingError
from posture_id.parameters import TARGET_FIELDS, DecParameters, denormalise, normalise
from posture_id.recording import Recording
from posture_id.stimulus import recognise_prts, tilt_from_array
from posture_id.symbolic import (
    SymbolicModel,
    buffer_sizes,
    delay_weights,
    rollout_function,
    rollout_steps,
    step_function,
    step_inputs,
)

__all__ = ["FitOptions", "FitResult", "fit_recording", "prepare_recording"]

SAMPLE_RATE_HZ = 50.0
_DEG = 180.0 / math.pi


@dataclass(frozen=True)
class FitOptions:
    """How to fit (see the module doc).

    Attributes:
        classes: "relaxed", "exhaustive" or "fixed".
        gain_bounds: bounds of K̃p, K̃i, K̃d (normalised: −1 = zero, 3 = 4× the default).
        delay_bounds: bounds of Δ̃ (the upper one sizes the delay buffers).
        max_iterations: residual evaluations per stage at most.
        polish_iterations: the same for the exact polish after a warm start (it needs a
            few when the warm start has converged; more cannot rescue one that has not).
        tolerance: relative tolerance on cost, step and gradient (scipy's ftol/xtol/gtol).
        smooth_deadband_rad_s: softplus width of the smoothed dead-band.
        noise_floor_deg: least σ assumed for standard errors (sensor resolution).
        precision_rel: a parameter is poorly determined when 1.96·SE > this × |value|.
        min_duration_s: shortest recording accepted (one 242-state PRTS cycle).
        dt, deadband_rad_s: the simulation's step and dead-band (MODEL §2).
        compile: "auto", "always" or "never" (CasADi VM).
        threads: threads evaluating Jacobian columns.
        warm_start: first fit with the fast simulator and finite differences (cheap), then
            finish with CasADi's exact derivatives; otherwise CasADi does every stage.
        warm_tolerance: tolerance of the warm-start stage.
        starts: relaxed fits from the guess and from ``starts − 1`` draws of the MODEL §5
            prior (seeded by ``seed``); the best goes on to the polish. Each start costs a
            warm stage; they may escape a local minimum (on benchmark recording 8 three
            starts all ended in the same one).
    """

    classes: str = "relaxed"
    gain_bounds: tuple[float, float] = (-1.0, 3.0)
    delay_bounds: tuple[float, float] = (-1.0, 1.5)
    max_iterations: int = 60
    polish_iterations: int = 20
    tolerance: float = 1e-10
    smooth_deadband_rad_s: float = 1e-5
    noise_floor_deg: float = 0.001
    precision_rel: float = 0.05
    min_duration_s: float = 60.5
    dt: float = 0.002
    deadband_rad_s: float = 0.0003
    compile: str = "auto"
    threads: int = 2
    warm_start: bool = True
    warm_tolerance: float = 1e-7
    starts: int = 1
    seed: int = 0

    def __post_init__(self) -> None:
        if self.starts < 1:
            raise ValueError(f"starts must be ≥ 1, got {self.starts}")
        if self.classes not in ("relaxed", "exhaustive", "fixed"):
            raise ValueError(f"classes must be relaxed, exhaustive or fixed, not {self.classes}")


@dataclass
class FitResult:
    """The identified parameters and how the fit went.

    Attributes:
        parameters: physical units (DecParameters). normalised: (N, 5) [K̃p, K̃i, K̃d, Δ̃, C].
        standard_errors: (N, 4) SE of Kp, Ki, Kd, Δ in physical units;
        standard_errors_normalised: (N, 4) the same relative to the defaults.
        poorly_determined: (N, 4) bool. converged: the last stage met its tolerance.
        iterations: Jacobian evaluations in all. evaluations: residual evaluations.
        wall_time_s: s. cost: ½Σr² (deg²). rms_deg: residual RMS.
        stages: per-stage summaries. backend: compiled or VM. notices: things to know.
        time (S,) s, recorded and fitted (S, N) rad; segments, joints: names.
    """

    parameters: DecParameters
    normalised: np.ndarray
    standard_errors: np.ndarray
    standard_errors_normalised: np.ndarray
    poorly_determined: np.ndarray
    converged: bool
    iterations: int
    evaluations: int
    wall_time_s: float
    cost: float
    rms_deg: float
    stages: list[dict]
    backend: str
    notices: list[str]
    time: np.ndarray = field(repr=False)
    recorded: np.ndarray = field(repr=False)
    fitted: np.ndarray = field(repr=False)
    segments: tuple[str, ...] = ()
    joints: tuple[str, ...] = ()

    @property
    def classes(self) -> tuple[str, ...]:
        return tuple(self.parameters[j].controls for j in self.joints)

    def to_dict(self) -> dict:
        fields = TARGET_FIELDS
        return {
            "parameters": self.parameters.to_dict(),
            "normalised": {j: dict(zip((*fields, "class"), map(float, row), strict=True))
                           for j, row in zip(self.joints, self.normalised, strict=True)},
            "standard_errors": {j: dict(zip(fields, map(float, row), strict=True))
                                for j, row in zip(self.joints, self.standard_errors,
                                                  strict=True)},
            "poorly_determined": {j: [f for f, bad in zip(fields, row, strict=True) if bad]
                                  for j, row in zip(self.joints, self.poorly_determined,
                                                    strict=True)},
            "status": {
                "converged": self.converged, "iterations": self.iterations,
                "evaluations": self.evaluations, "wall_time_s": self.wall_time_s,
                "cost_deg2": self.cost, "rms_deg": self.rms_deg, "backend": self.backend,
                "stages": self.stages,
            },
            "notices": self.notices,
        }

    def to_json(self, path: str | Path | None = None) -> str:
        text = json.dumps(self.to_dict(), indent=2) + "\n"
        if path is not None:
            from posture_id.io_utils import atomic_write_text

            atomic_write_text(Path(path), text)
        return text

    def plot(self, path=None):
        """Recorded versus fitted sway per segment (degrees); saved to ``path`` if given."""
        from posture_id.plotting import plot_fit

        return plot_fit(self, path=path)


def prepare_recording(recording: Recording, source: str, options: FitOptions
                      ) -> tuple[Recording, list[str]]:
    """Check a recording and bring it to 50 Hz (linear interpolation, with a notice).

    Raises:
        RecordingError: irregular sampling or shorter than ``min_duration_s``.
    """
    notices = []
    steps = np.diff(recording.time)
    median = float(np.median(steps))
    if np.any(np.abs(steps - median) > 0.01 * median):
        raise RecordingError(f"{source}: samples are not evenly spaced in time")
    duration = float(recording.time[-1])
    if duration < options.min_duration_s - 1e-9:
        raise RecordingError(
            f"{source}: the recording lasts {duration:.2f} s, shorter than one PRTS cycle "
            f"({options.min_duration_s:g} s)"
        )
    rate = 1.0 / median
    if abs(rate - SAMPLE_RATE_HZ) > 1e-6 * SAMPLE_RATE_HZ:
        n = int(math.floor(duration * SAMPLE_RATE_HZ + 1e-9)) + 1
        t = np.arange(n) / SAMPLE_RATE_HZ
        theta = np.stack([np.interp(t, recording.time, recording.theta[:, j])
                          for j in range(recording.theta.shape[1])], axis=1)
        recording = Recording(t, np.interp(t, recording.time, recording.tilt), theta,
                              recording.segments)
        notices.append(f"{source}: resampled from {rate:.4g} Hz to {SAMPLE_RATE_HZ:g} Hz "
                       "by linear interpolation")
    return recording, notices


class _Problem:
    """Compiled simulation and Jacobian of one body and recording length."""

    def __init__(self, body: Body, n_samples: int, options: FitOptions, notify=None):
        n = body.n_segments
        self.n = n
        every = round(1.0 / (SAMPLE_RATE_HZ * options.dt))
        self.n_steps_u = rollout_steps(n_samples, every)
        defaults = body.default_parameters()
        self.defaults = defaults
        base = {f: defaults.array(f) for f in ("kp", "ki", "kd", "delay_s", "kpas", "bpas")}
        delay0 = base["delay_s"] / options.dt
        sizes = buffer_sizes(delay0 * (1 + options.delay_bounds[1]))
        model = SymbolicModel(body, tuple(sizes), options.dt, options.deadband_rad_s,
                              smooth=options.smooth_deadband_rad_s)
        self.width = -(-5 * n // max(options.threads, 1))  # Jacobian columns per thread

        def build() -> list[ca.Function]:
            rollout = rollout_function(model, n_samples, every)
            q = ca.MX.sym("q", 5 * n)
            u = ca.MX.sym("u", 3, self.n_steps_u)
            delay = delay0 * (1 + q[3 * n : 4 * n])
            p = ca.vertcat(base["kp"] * (1 + q[0:n]), base["ki"] * (1 + q[n : 2 * n]),
                           base["kd"] * (1 + q[2 * n : 3 * n]), delay, q[4 * n : 5 * n],
                           base["kpas"], base["bpas"])
            theta = rollout(u, p, delay_weights(delay, sizes))
            seeds = ca.MX.sym("V", 5 * n, self.width)
            sim = ca.Function("dec_sim", [q, u], [theta])
            # vec() of the (N, S) samples is sample-major: row s·N + j, as numpy ravels (S, N)
            dirs = ca.Function("dec_dirs", [q, u, seeds],
                               [ca.jtimes(ca.vec(theta), q, seeds)])
            return [sim, dirs]

        # everything the compiled functions depend on: the step (its generated C holds the
        # body's constants), sizes, defaults, and this module's and the model's code
        step_c = ca.CodeGenerator("step.c")
        step_c.add(step_function(model))
        key = "|".join([
            step_c.dump(), repr((n_samples, every, sizes, self.width)),
            repr({k: v.tolist() for k, v in base.items()}),
            Path(__file__).read_text(), Path(symbolic.__file__).read_text(),
        ]).encode()
        (self.sim, self.dirs), self.backend = compile_functions(
            f"dec_fit_{body.name}_{n_samples}", key, build, notify=notify,
            mode=options.compile)
        self.pool = ThreadPoolExecutor(max_workers=max(options.threads, 1))

    def simulate(self, q: np.ndarray, u: np.ndarray) -> np.ndarray:
        """(S, N) rad."""
        return np.array(self.sim(q, u)).T

    def jacobian(self, q: np.ndarray, u: np.ndarray, columns: list[int]) -> np.ndarray:
        """(S·N, len(columns)) ∂θ/∂q (rad), columns evaluated in parallel chunks."""
        chunks = [columns[i : i + self.width] for i in range(0, len(columns), self.width)]

        def run(chunk):
            seeds = np.zeros((5 * self.n, self.width))
            seeds[chunk, range(len(chunk))] = 1.0
            return np.array(self.dirs(q, u, seeds))[:, : len(chunk)]

        return np.hstack(list(self.pool.map(run, chunks)))


_PROBLEMS: dict = {}


def _problem(body: Body, n_samples: int, options: FitOptions, notify=None) -> _Problem:
    """The compiled problem, built once per (body, length, options) in a process."""
    key = (body, n_samples, options)
    if key not in _PROBLEMS:
        for old in _PROBLEMS.values():  # one at a time: each holds compiled code and threads
            old.pool.shutdown(wait=False)
        _PROBLEMS.clear()
        _PROBLEMS[key] = _Problem(body, n_samples, options, notify)
    return _PROBLEMS[key]


def fit_recording(
    recording: Recording,
    body: Body,
    init: DecParameters | None = None,
    options: FitOptions | None = None,
    progress: Callable[[str], None] | None = None,
    source: str = "recording",
) -> FitResult:
    """Fit every module's Kp, Ki, Kd, Δ and class to one recording.

    Args:
        recording: tilt and segment angles in space (segments must be the body's).
        body: the body. init: initial guess (default: the body's defaults).
        options: see :class:`FitOptions`. progress: called with one-line status messages.
    """

    options = options or FitOptions()
    say = progress or (lambda message: None)
    if tuple(recording.segments) != body.segment_names:
        raise RecordingError(
            f"{source}: segment columns {','.join(recording.segments)} do not match the body's "
            f"segments {','.join(body.segment_names)}"
        )
    start = time.perf_counter()
    recording, notices = prepare_recording(recording, source, options)
    for notice in notices:
        say(notice)
    n = body.n_segments
    n_samples = len(recording.time)
    problem = _problem(body, n_samples, options, say)
    if problem.backend.startswith("vm"):
        notices.append(f"CasADi runs in its virtual machine ({problem.backend[4:]}): slower")
    stim = recognise_prts(recording.time, recording.tilt)
    if stim is not None:
        notices.append(f"{source}: the tilt is a {stim.description}; the exact profile is "
                       "used (50 Hz samples miss its corners)")
    else:
        stim = tilt_from_array(recording.time, recording.tilt, description=source)
        notices.append(f"{source}: the tilt is not a PRTS; it is interpolated linearly "
                       "between samples")
    tilt, tilt_vel = stim.on_grid(options.dt, problem.n_steps_u)
    u = step_inputs(tilt, tilt_vel, problem.n_steps_u)
    measured = recording.theta
    defaults = problem.defaults
    guess = normalise(init or defaults, defaults)
    lo_z, hi_z = _bounds_vector(options, n, classes=False)
    lo_c, hi_c = _bounds_vector(options, n, classes=True)
    z0 = np.clip(guess[:, :4].T.ravel(), lo_z, hi_z)
    signs0 = guess[:, 4]
    counts = {"evaluations": 0, "iterations": 0}
    continuous = list(range(4 * n))
    everything = list(range(5 * n))
    exact = _Evaluator(lambda q: problem.simulate(q, u),
                       lambda q, free: problem.jacobian(q, u, free), measured)
    warm = _SimulatorEvaluator(body, stim, options, measured, n_samples)

    def stage(name, evaluator, q0, free, lower, upper, tolerance, limit=options.max_iterations):
        result = _least_squares(name, evaluator, q0, free, lower, upper, tolerance,
                                limit, counts, say)
        stages.append(result)
        return result

    stages: list[dict] = []
    if options.classes == "relaxed":
        # the guess, then (options.starts > 1) draws from the MODEL §5 prior, classes open
        rng = np.random.default_rng(options.seed)
        starts = [np.concatenate([z0, 0.5 * signs0])]
        for _ in range(options.starts - 1):
            draw = np.abs(1 + 0.5 * rng.standard_normal(4 * n)) - 1
            starts.append(np.concatenate([np.clip(draw, lo_z, hi_z), np.zeros(n)]))
        tries = []
        for k, q0 in enumerate(starts):
            label = "relaxed classes" + (f", start {k + 1}/{len(starts)}" if k else "")
            if options.warm_start:
                tries.append(stage(label + " (simulator)", warm, q0, everything, lo_c, hi_c,
                                   options.warm_tolerance))
            else:
                tries.append(stage(label, exact, q0, everything, lo_c, hi_c,
                                   options.tolerance))
        first = min(tries, key=lambda t: t["cost"])
        signs = np.where(first["q"][4 * n :] >= 0, 1.0, -1.0)
        say(f"classes from the relaxed fit: {_class_names(signs)}")
        start_q = np.concatenate([np.clip(first["q"][: 4 * n], lo_z, hi_z), signs])
    else:
        combos = (itertools.product((1.0, -1.0), repeat=n) if options.classes == "exhaustive"
                  else [tuple(signs0)])
        candidates = []
        for combo in combos:
            q0 = np.concatenate([z0, combo])
            evaluator, tol = (warm, options.warm_tolerance) if options.warm_start else (
                exact, options.tolerance)
            candidates.append(stage(f"classes {_class_names(combo)}", evaluator, q0,
                                    continuous, lo_z, hi_z, tol))
        start_q = min(candidates, key=lambda s: s["cost"])["q"]
    best = stage("polish (exact derivatives)", exact, start_q, continuous, lo_z, hi_z,
                 options.tolerance,
                 options.polish_iterations if options.warm_start else options.max_iterations)

    q = best["q"]
    normalised = np.column_stack([q[: 4 * n].reshape(4, n).T, q[4 * n :]])
    params = denormalise(normalised, defaults)
    jac = best["jac"]
    r = best["residual"]
    dof = max(len(r) - jac.shape[1], 1)
    sigma = max(math.sqrt(float(r @ r) / dof), options.noise_floor_deg)
    with np.errstate(divide="ignore", invalid="ignore"):
        try:
            cov = sigma**2 * np.linalg.inv(jac.T @ jac)
            se_z = np.sqrt(np.clip(np.diag(cov), 0, None))
        except np.linalg.LinAlgError:
            se_z = np.full(jac.shape[1], np.inf)
    se_norm = se_z.reshape(4, n).T
    default_values = np.column_stack([defaults.array(f) for f in TARGET_FIELDS])
    se_phys = se_norm * default_values
    values = np.column_stack([params.array(f) for f in TARGET_FIELDS])
    with np.errstate(divide="ignore", invalid="ignore"):
        poorly = ~(1.96 * se_phys <= options.precision_rel * np.abs(values))
    fitted = problem.simulate(q, u)
    elapsed = time.perf_counter() - start
    summaries = [{k: v for k, v in s.items() if k not in ("q", "jac", "residual")}
                 | {"classes": _class_names(np.sign(s["q"][4 * n :]))} for s in stages]
    return FitResult(
        parameters=params, normalised=normalised, standard_errors=se_phys,
        standard_errors_normalised=se_norm, poorly_determined=poorly,
        converged=best["converged"], iterations=counts["iterations"],
        evaluations=counts["evaluations"], wall_time_s=elapsed, cost=best["cost"],
        rms_deg=math.sqrt(2 * best["cost"] / len(r)), stages=summaries,
        backend=problem.backend, notices=notices, time=recording.time,
        recorded=measured, fitted=fitted, segments=body.segment_names,
        joints=body.joint_names,
    )


class _Evaluator:
    """Residuals (degrees) and Jacobians of simulated minus measured sway."""

    def __init__(self, simulate, jacobian, measured: np.ndarray) -> None:
        self._simulate = simulate
        self._jacobian = jacobian
        self.measured = measured

    def residual(self, q: np.ndarray) -> np.ndarray:
        return (self._simulate(q) - self.measured).ravel() * _DEG

    def jacobian(self, q: np.ndarray, free: list[int], residual: np.ndarray) -> np.ndarray:
        return self._jacobian(q, free) * _DEG


class _SimulatorEvaluator(_Evaluator):
    """The same model stepped by the fast batch simulator; Jacobians by forward
    differences, every perturbed parameter set a lane of one batch. Cheap and accurate to
    ~1e-6: a warm start for the exact stage."""

    STEP = 1e-6

    def __init__(self, body: Body, stimulus, options: FitOptions, measured, n_samples):
        from posture_id.simulation import MAX_SWAY_LIMIT_DEG, SimulationOptions

        self.body = body
        self.stimulus = stimulus
        self.sim_options = SimulationOptions(
            dt=options.dt, deadband_rad_s=options.deadband_rad_s,
            sway_limit_deg=MAX_SWAY_LIMIT_DEG, workers=1)
        self.n = body.n_segments
        self.n_samples = n_samples
        self.defaults = body.default_parameters()
        self.limit = math.radians(MAX_SWAY_LIMIT_DEG)
        self.measured = measured

    def _simulate_many(self, qs: np.ndarray) -> np.ndarray:
        from posture_id.parameters import denormalise_arrays
        from posture_id.simulation import simulate_batch

        # q is field-major (K̃p of every module, then K̃i, …, then the classes)
        targets = qs.reshape(len(qs), 5, self.n).transpose(0, 2, 1)
        params = denormalise_arrays(targets, self.defaults)
        batch = simulate_batch(self.body, params, self.stimulus, self.sim_options)
        # a trial that falls is held at the limit: a large, finite residual
        theta = batch.theta[:, : self.n_samples]
        return np.where(np.isnan(theta), self.limit, theta)

    def residual(self, q):
        return (self._simulate_many(q[None])[0] - self.measured).ravel() * _DEG

    def jacobian(self, q, free, residual):
        qs = np.repeat(q[None], len(free), axis=0)
        qs[np.arange(len(free)), free] += self.STEP
        # a relaxed class at +1 is stepped downwards, inside its bounds
        over = qs[np.arange(len(free)), free] > 1.0
        over &= np.array(free) >= 4 * self.n
        qs[np.arange(len(free))[over], np.array(free)[over]] -= 2 * self.STEP
        steps = np.where(over, -self.STEP, self.STEP)
        theta = self._simulate_many(qs)
        r = (theta - self.measured[None]).reshape(len(free), -1) * _DEG
        return ((r - residual[None]) / steps[:, None]).T


def _least_squares(name, evaluator, q0, free, lower, upper, tolerance, max_iterations,
                   counts, say) -> dict:
    """One bounded trust-region least-squares stage over the ``free`` entries of q."""
    from scipy.optimize import least_squares

    free = list(free)
    cache: dict = {}

    def full(x):
        q = q0.copy()
        q[free] = x
        return q

    def residual(x):
        counts["evaluations"] += 1
        r = evaluator.residual(full(x))
        cache["x"], cache["r"] = x.copy(), r
        return r

    def jacobian(x):
        counts["iterations"] += 1
        r = cache["r"] if np.array_equal(cache.get("x"), x) else residual(x)
        if counts["iterations"] % 5 == 1:
            say(f"{name}: iteration {counts['iterations']}, RMS "
                f"{math.sqrt(float(r @ r) / len(r)):.6f}°")
        return evaluator.jacobian(full(x), free, r)

    sol = least_squares(residual, np.clip(q0[free], lower[free], upper[free]), jac=jacobian,
                        bounds=(lower[free], upper[free]), method="trf", x_scale="jac",
                        ftol=tolerance, xtol=tolerance, gtol=tolerance,
                        max_nfev=max_iterations)
    return {"name": name, "q": full(sol.x), "cost": float(sol.cost), "status": int(sol.status),
            "converged": bool(sol.status > 0), "iterations": int(sol.njev),
            "evaluations": int(sol.nfev), "jac": sol.jac, "residual": sol.fun}


def _bounds_vector(options: FitOptions, n: int, classes: bool):
    lo = [options.gain_bounds[0]] * 3 * n + [options.delay_bounds[0]] * n
    hi = [options.gain_bounds[1]] * 3 * n + [options.delay_bounds[1]] * n
    if classes:
        lo += [-1.0] * n
        hi += [1.0] * n
    return np.array(lo), np.array(hi)


def _class_names(signs) -> str:
    return "/".join("com" if s >= 0 else "joint" for s in signs)

