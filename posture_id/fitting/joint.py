"""One set of DEC parameters for several recordings of one subject (the parts of a
two-amplitude protocol): the locked fit of the first part, then a polish of every module's
gains and delays (classes and passive terms kept) against all parts at once, their
weighted locked harmonics stacked. DEC's claim is that one set of parameters explains
every amplitude (its dead-band makes the response depend on it); this is the fit that
tests it."""

from __future__ import annotations

import numpy as np

from posture_id.bodies.body import Body
from posture_id.fitting.evaluators import Evaluator, run_stage
from posture_id.fitting.least_squares import FitRun, fit_recording
from posture_id.fitting.options import FitOptions
from posture_id.fitting.result import FitResult, StageResult
from posture_id.fitting.unknowns import parameters_from_qs
from posture_id.trials import PreparedTrial

__all__ = ["JointEvaluator", "JointFit", "fit_recordings_jointly"]


class JointEvaluator(Evaluator):
    """Several evaluators of the same unknowns, their residuals and Jacobians stacked."""

    def __init__(self, parts: list[Evaluator]) -> None:
        super().__init__(np.zeros((0, 0)))
        self.parts = parts

    def residual(self, q: np.ndarray) -> np.ndarray:
        return np.concatenate([p.residual(q) for p in self.parts])

    def jacobian(self, q: np.ndarray, free: list[int], residual: np.ndarray) -> np.ndarray:
        out, start = [], 0
        for p in self.parts:
            mine = p.residual(q)
            out.append(p.jacobian(q, free, residual[start : start + len(mine)]))
            start += len(mine)
        return np.vstack(out)


class JointFit:
    """The joint fit: ``parameters`` (DecParameters), ``stage`` (its last
    :class:`~posture_id.fitting.result.StageResult`), ``first`` (the first part's own
    fit), and ``fitted``: per part, the (S, N) rad segment angles of the joint answer."""

    def __init__(self, parameters, stage: StageResult, first: FitResult,
                 fitted: list[np.ndarray]) -> None:
        self.parameters, self.stage, self.first, self.fitted = (parameters, stage, first,
                                                                fitted)


def fit_recordings_jointly(trials: list[PreparedTrial], body: Body, options: FitOptions,
                           progress=None) -> JointFit:
    """The parameters that explain every one of ``trials`` (the module doc); ``options``
    must ask for the locked fit."""
    first = fit_recording(trials[0], body, None, options, progress)
    runs = [FitRun.start(t, body, options, progress) for t in trials]
    joint = JointEvaluator([r.exact for r in runs])
    q0 = first.stages[-1].q
    free = runs[0].layout.continuous(options.fit_passive)
    stage = run_stage("joint polish (every part)", joint, q0, free, runs[0].lower,
                      runs[0].upper, options.tolerance, options.max_iterations, progress,
                      runs[0].prior_sd, runs[0].prior_centre)
    params = parameters_from_qs(stage.q[None], runs[0].problem.defaults).trial(
        0, body.joint_names)
    fitted = [r.problem.simulate(stage.q, r.u) for r in runs]
    return JointFit(params, stage, first, fitted)
