"""Residuals and Jacobians of one fit, and one bounded least-squares stage.

Two evaluators of the same model: :class:`ExactEvaluator` (CasADi, exact forward-mode
derivatives, smoothed dead-band) and :class:`SimulatorEvaluator` (the fast batch
simulator with forward differences: a cheap warm start). What is compared is a
:class:`SwayResidual` of simulated minus recorded segment angles in degrees: every sample
(:class:`SwayResidual`, sample-major (S·N,)) or their weighted stimulus-locked harmonics
(:class:`LockedResidual`, a linear map applied alike to residuals and Jacobians).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import least_squares

from posture_id.bodies.body import Body
from posture_id.dec.parameters import DecParameters
from posture_id.fitting.problem import FitProblem
from posture_id.fitting.result import StageResult
from posture_id.fitting.unknowns import parameters_from_qs
from posture_id.frf.locked import LockedProjection
from posture_id.progress import Progress, report
from posture_id.simulation.batch import simulate_batch
from posture_id.simulation.options import MAX_SWAY_LIMIT_DEG, SimulationOptions
from posture_id.simulation.stimulus import TiltProfile

__all__ = ["Evaluator", "ExactEvaluator", "SimulatorEvaluator", "run_stage", "SwayResidual",
           "LockedResidual"]

_DEG = 180.0 / math.pi


class SwayResidual:
    """Compare every sample: the residual is simulated minus recorded angles (deg)."""

    def values(self, difference_deg: np.ndarray) -> np.ndarray:
        """(S, N) deg → (R,) residual."""
        return difference_deg.ravel()

    def many(self, differences_deg: np.ndarray) -> np.ndarray:
        """(B, S, N) deg → (B, R): :meth:`values` of each, at once."""
        return differences_deg.reshape(len(differences_deg), -1)

    def columns(self, jacobian_deg: np.ndarray) -> np.ndarray:
        """(S, N, P) ∂θ/∂q (deg) → (R, P) Jacobian of :meth:`values`."""
        return jacobian_deg.reshape(-1, jacobian_deg.shape[-1])

    def clusters(self) -> np.ndarray | None:
        """(R,) the group of each residual row whose noise may be shared
        (:mod:`~posture_id.fitting.structure`), or None: every sample of the raw sway
        compared, whose noise is correlated in time, not in groups."""
        return None


class LockedResidual(SwayResidual):
    """Compare the weighted stimulus-locked harmonics
    (:class:`~posture_id.frf.locked.LockedProjection`, made for the recording in degrees)."""

    def __init__(self, projection: LockedProjection) -> None:
        self.projection = projection

    def values(self, difference_deg):
        return self.projection.apply(difference_deg).ravel()

    def many(self, differences_deg):
        # the projection takes trailing channels: (S, N, B) → (2K, N, B)
        out = self.projection.apply(np.moveaxis(differences_deg, 0, -1))
        return np.moveaxis(out, -1, 0).reshape(len(differences_deg), -1)

    def columns(self, jacobian_deg):
        return self.projection.apply(jacobian_deg).reshape(-1, jacobian_deg.shape[-1])

    def clusters(self):
        """The harmonic of each row: its real and imaginary part of every channel, one
        group (rows: real parts then imaginary parts, harmonic by harmonic, channels
        innermost, as :meth:`values` ravels them)."""
        harmonics, channels = self.projection.noise.shape
        return np.tile(np.repeat(np.arange(harmonics), channels), 2)


class Evaluator:
    """Residuals and Jacobians of simulated minus measured sway (S, N) rad, compared as
    ``target`` says (default: every sample, in degrees)."""

    def __init__(self, measured: np.ndarray, target: SwayResidual | None = None) -> None:
        self.measured = measured
        self.target = target or SwayResidual()
        self._last: tuple[np.ndarray, np.ndarray] | None = None

    def simulate(self, q: np.ndarray) -> np.ndarray:  # (S, N) rad
        raise NotImplementedError

    def simulated(self, q: np.ndarray) -> np.ndarray:
        """:meth:`simulate`, remembered for the last q (a Jacobian follows its residual)."""
        if self._last is not None and np.array_equal(self._last[0], q):
            return self._last[1]
        theta = self.simulate(q)
        self._last = (np.array(q, copy=True), theta)
        return theta

    def residual(self, q: np.ndarray) -> np.ndarray:
        return self.target.values((self.simulated(q) - self.measured) * _DEG)

    def jacobian(self, q: np.ndarray, free: list[int], residual: np.ndarray) -> np.ndarray:
        raise NotImplementedError


class ExactEvaluator(Evaluator):
    """The compiled CasADi problem: exact derivatives.

    A parameter set that makes the body fall is treated as the fast simulator treats it:
    from the first sample at which a segment passes :data:`MAX_SWAY_LIMIT_DEG` (or the
    rollout overflows), every angle is held at the limit and its derivatives are zero. So
    residuals and Jacobians stay finite wherever the optimiser steps.
    """

    LIMIT = math.radians(MAX_SWAY_LIMIT_DEG)

    def __init__(self, problem: FitProblem, u: np.ndarray, measured: np.ndarray,
                 target: SwayResidual | None = None) -> None:
        super().__init__(measured, target)
        self.problem = problem
        self.u = u

    def simulate(self, q):
        theta = self.problem.simulate(q, self.u)
        fall = self._fall(theta)
        if fall is not None:
            theta[fall:] = self.LIMIT
        return theta

    def jacobian(self, q, free, residual):
        jac = self.problem.jacobian(q, self.u, list(free)) * _DEG
        fall = self._fall(self.simulated(q))
        if fall is not None:
            jac[fall * self.measured.shape[1]:] = 0.0
        jac = np.where(np.isfinite(jac), jac, 0.0)
        return self.target.columns(jac.reshape(*self.measured.shape, -1))

    def _fall(self, theta: np.ndarray) -> int | None:
        """First sample (row of (S, N) ``theta``) at or past the limit, or None."""
        with np.errstate(invalid="ignore"):
            out = ~(np.abs(theta) < self.LIMIT * (1.0 - 1e-12)).all(axis=1)
        return int(np.argmax(out)) if out.any() else None


class SimulatorEvaluator(Evaluator):
    """The same model stepped by the fast batch simulator; Jacobians by forward
    differences, every perturbed parameter set a lane of one batch. Cheap and accurate to
    ~1e-6: a warm start for the exact stage."""

    STEP = 1e-6

    def __init__(self, body: Body, defaults: DecParameters, stimulus: TiltProfile,
                 simulation: SimulationOptions, measured: np.ndarray,
                 target: SwayResidual | None = None) -> None:
        super().__init__(measured, target)
        self.body = body
        self.stimulus = stimulus
        # a trial that falls is held at the limit (a large, finite residual), never aborted
        # before it: the widest limit the kernel allows
        self.options = SimulationOptions(
            dt=simulation.dt, sample_rate_hz=simulation.sample_rate_hz,
            deadband_rad_s=simulation.deadband_rad_s, sway_limit_deg=MAX_SWAY_LIMIT_DEG)
        self.n = body.n_segments
        self.defaults = defaults
        self.limit = math.radians(MAX_SWAY_LIMIT_DEG)

    def _simulate_many(self, qs: np.ndarray) -> np.ndarray:
        params = parameters_from_qs(qs, self.defaults)
        batch = simulate_batch(self.body, params, self.stimulus, self.options, workers=1)
        theta = batch.theta[:, : len(self.measured)]
        return np.where(np.isnan(theta), self.limit, theta)

    def simulate(self, q):
        return self._simulate_many(q[None])[0]

    def jacobian(self, q, free, residual):
        free = np.asarray(free)
        rows = np.arange(len(free))
        qs = np.repeat(q[None], len(free), axis=0)
        qs[rows, free] += self.STEP
        # a relaxed class at +1 is stepped downwards, inside its bounds
        over = (qs[rows, free] > 1.0) & (free >= 4 * self.n)
        qs[rows[over], free[over]] -= 2 * self.STEP
        steps = np.where(over, -self.STEP, self.STEP)
        theta = self._simulate_many(qs)
        r = self.target.many((theta - self.measured[None]) * _DEG)
        return ((r - residual[None]) / steps[:, None]).T


def run_stage(name: str, evaluator: Evaluator, q0: np.ndarray, free: list[int],
              lower: np.ndarray, upper: np.ndarray, tolerance: float, max_iterations: int,
              progress: Progress | None = None,
              prior_sd: np.ndarray | None = None,
              prior_centre: np.ndarray | None = None) -> StageResult:
    """One bounded trust-region least-squares stage over the ``free`` entries of q (7N,).

    ``lower``/``upper`` are (7N,) bounds; entries not free keep their q0 values.
    ``prior_sd``: (7N,) standard deviations of a Gaussian prior on q centred on
    ``prior_centre`` (7N,; default 0, the defaults; inf: none): each free entry adds the
    residual (q_k − centre_k) / sd_k, so the stage finds the maximum a posteriori estimate
    when the residuals are in units of their noise.
    """
    free = list(free)
    cache: dict = {}
    jacobians = [0]
    weights = (np.zeros(len(free)) if prior_sd is None
               else 1.0 / np.asarray(prior_sd, dtype=float)[free])
    priored = np.flatnonzero(weights > 0)
    centre = (np.zeros(len(free)) if prior_centre is None
              else np.asarray(prior_centre, dtype=float)[free])

    def full(x):
        q = q0.copy()
        q[free] = x
        return q

    def residual(x):
        r = np.concatenate([evaluator.residual(full(x)),
                            (x[priored] - centre[priored]) * weights[priored]])
        cache["x"], cache["r"] = x.copy(), r
        return r

    def jacobian(x):
        jacobians[0] += 1
        r = cache["r"] if np.array_equal(cache.get("x"), x) else residual(x)
        if jacobians[0] % 5 == 1:
            report(progress, jacobians[0], None, "iteration",
                   f"{name}: iteration {jacobians[0]}, RMS "
                   f"{math.sqrt(float(r @ r) / len(r)):.6f}°")
        jac = evaluator.jacobian(full(x), free, r[: len(r) - len(priored)])
        rows = np.zeros((len(priored), len(free)))
        rows[np.arange(len(priored)), priored] = weights[priored]
        return np.vstack([jac, rows])

    sol = least_squares(residual, np.clip(q0[free], lower[free], upper[free]), jac=jacobian,
                        bounds=(lower[free], upper[free]), method="trf", x_scale="jac",
                        ftol=tolerance, xtol=tolerance, gtol=tolerance,
                        max_nfev=max_iterations)
    return StageResult(name=name, q=full(sol.x), cost=float(sol.cost), status=int(sol.status),
                       converged=bool(sol.status > 0), iterations=int(sol.njev),
                       evaluations=int(sol.nfev), jacobian=sol.jac, residual=sol.fun)
