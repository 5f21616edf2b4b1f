"""One set of DEC parameters for several recordings of one subject (the parts of a
two-amplitude protocol): the locked fit of the first part, then a polish of every module's
gains and delays (classes and passive terms kept) against all parts at once, their
weighted locked harmonics stacked. DEC's claim is that one set of parameters explains
every amplitude (its dead-band makes the response depend on it); this is the fit that
tests it.

The same polish with some unknowns taken per condition (:func:`polish_by_condition`,
what :func:`~posture_id.fitting.joint_conditions.fit_joint` runs for DEC): the trials
grouped into conditions, the named unknowns (an ankle Kp, a delay) one per condition,
the rest shared. The unknowns are then the extended vector of
:class:`ConditionEvaluator`: q (7N,) as for one trial, its per-condition entries standing
for the first condition, then those entries again for every further condition."""

from __future__ import annotations

import numpy as np

from posture_id.bodies.body import Body
from posture_id.fitting.evaluators import Evaluator, run_stage
from posture_id.fitting.least_squares import FitRun, fit_recording
from posture_id.fitting.options import FitOptions
from posture_id.fitting.result import StageResult
from posture_id.fitting.unknowns import parameters_from_qs
from posture_id.trials import PreparedTrial

__all__ = ["ConditionEvaluator", "fit_recordings_jointly", "ConditionPolish",
           "polish_by_condition"]


class ConditionEvaluator(Evaluator):
    """Evaluators of several trials (``parts``) grouped into conditions, their residuals
    and Jacobians stacked, over the extended unknowns (the module doc).

    Args:
        parts: one evaluator per trial, each of q (Q,).
        conditions: (parts,) each part's condition index 0..C−1.
        per_condition: indices into q (Q,) of the unknowns that take one value per
            condition (empty: everything shared, the extended vector is q itself).
        size: Q, the length of one trial's q.
    """

    def __init__(self, parts: list[Evaluator], conditions: list[int] | None = None,
                 per_condition: tuple[int, ...] = (), size: int = 0) -> None:
        super().__init__(np.zeros((0, 0)))
        self.parts = parts
        self.conditions = list(conditions) if conditions is not None else [0] * len(parts)
        self.per_condition = tuple(per_condition)
        self.size = size

    def column(self, condition: int, index: int) -> int:
        """The entry of the extended vector that holds q[``index``] in ``condition``."""
        if condition == 0 or index not in self.per_condition:
            return index
        return (self.size + (condition - 1) * len(self.per_condition)
                + self.per_condition.index(index))

    def q_of(self, q: np.ndarray, condition: int) -> np.ndarray:
        """One trial's q (Q,) in ``condition`` from the extended vector."""
        if not self.per_condition or condition == 0:
            return q[: self.size] if self.size else q
        out = q[: self.size].copy()
        for k in self.per_condition:
            out[k] = q[self.column(condition, k)]
        return out

    def extended(self, q: np.ndarray, conditions: int) -> np.ndarray:
        """The extended vector of ``conditions`` conditions that all start at q (Q,)."""
        return np.concatenate([q] + [q[list(self.per_condition)]] * (conditions - 1))

    def residual(self, q: np.ndarray) -> np.ndarray:
        return np.concatenate([p.residual(self.q_of(q, c))
                               for p, c in zip(self.parts, self.conditions, strict=True)])

    def jacobian(self, q: np.ndarray, free: list[int], residual: np.ndarray) -> np.ndarray:
        out, start = [], 0
        position = {e: k for k, e in enumerate(free)}
        for p, c in zip(self.parts, self.conditions, strict=True):
            mine = self.q_of(q, c)
            rows = len(p.residual(mine))
            # the unknowns of this part's q that are free here, and their columns
            base = [i for i in range(len(mine)) if self.column(c, i) in position] \
                if self.per_condition else list(free)
            block = p.jacobian(mine, base, residual[start : start + rows])
            if self.per_condition:
                full = np.zeros((rows, len(free)))
                full[:, [position[self.column(c, i)] for i in base]] = block
                block = full
            out.append(block)
            start += rows
        return np.vstack(out)


class ConditionPolish:
    """The joint polish of a DEC fit of several trials, some unknowns per condition.

    Attributes:
        stage: the polish (its q the extended vector, its Jacobian (R, free) over
            ``free``, its residual (R,): the weighted locked harmonics of every trial,
            ``data_rows`` of them, then any prior's rows); the shared polish (every
            unknown shared) when nothing varies by condition.
        evaluator: the :class:`ConditionEvaluator` (how the extended vector reads).
        free: the extended vector's entries fitted. runs: one :class:`FitRun` per trial.
        parameters: per condition, its DecParameters. fitted: per trial, the (S, N) rad
        segment angles of the answer. data_rows: the residual's rows that are data.
    """

    def __init__(self, stage: StageResult, evaluator: ConditionEvaluator, free: list[int],
                 runs: list[FitRun], parameters: list, fitted: list[np.ndarray],
                 data_rows: int) -> None:
        self.stage, self.evaluator, self.free = stage, evaluator, free
        self.runs, self.parameters, self.fitted = runs, parameters, fitted
        self.data_rows = data_rows


def polish_by_condition(trials: list[PreparedTrial], body: Body, options: FitOptions,
                        conditions: list[int], per_condition: tuple[int, ...],
                        progress=None) -> ConditionPolish:
    """Every trial's parameters, shared but for the unknowns ``per_condition`` (indices
    into q, :mod:`~posture_id.fitting.unknowns`), one per condition (``conditions``: each
    trial's index 0..C−1): the first trial's locked fit, then every module's gains and
    delays polished against all trials at once (classes and passive terms kept), then
    polished again with those unknowns one per condition, each condition's starting at
    the shared answer. ``options`` must ask for the locked fit."""
    first = fit_recording(trials[0], body, None, options, progress)
    runs = [FitRun.start(t, body, options, progress) for t in trials]
    run = runs[0]
    count = max(conditions) + 1
    if count == 1:
        per_condition = ()
    exact, size = [r.exact for r in runs], run.layout.size
    continuous = run.layout.continuous(options.fit_passive)
    stage = run_stage("joint polish (every part)", ConditionEvaluator(exact, size=size),
                      first.stages[-1].q, continuous, run.lower, run.upper,
                      options.tolerance, options.max_iterations, progress, run.prior_sd,
                      run.prior_centre)
    evaluator = ConditionEvaluator(exact, conditions, per_condition, size)
    free = continuous + [evaluator.column(c, k) for c in range(1, count)
                         for k in per_condition]
    pick = list(per_condition) * (count - 1)

    def extend(values: np.ndarray | None) -> np.ndarray | None:
        return None if values is None else np.concatenate([values, values[pick]])

    if per_condition:
        stage = run_stage("joint polish (per condition)", evaluator,
                          evaluator.extended(stage.q, count), free, extend(run.lower),
                          extend(run.upper), options.tolerance, options.max_iterations,
                          progress, extend(run.prior_sd), extend(run.prior_centre))
    prior = extend(run.prior_sd)
    priored = 0 if prior is None else int(np.count_nonzero(1.0 / prior[free] > 0))
    defaults = run.problem.defaults
    parameters = [parameters_from_qs(evaluator.q_of(stage.q, c)[None], defaults).trial(
        0, body.joint_names) for c in range(count)]
    fitted = [r.problem.simulate(evaluator.q_of(stage.q, c), r.u)
              for r, c in zip(runs, conditions, strict=True)]
    return ConditionPolish(stage, evaluator, free, runs, parameters, fitted,
                           len(stage.residual) - priored)


def fit_recordings_jointly(trials: list[PreparedTrial], body: Body, options: FitOptions,
                           progress=None) -> ConditionPolish:
    """One set of parameters that explains every one of ``trials`` (the module doc):
    :func:`polish_by_condition` with every unknown shared; ``options`` must ask for the
    locked fit."""
    return polish_by_condition(trials, body, options, [0] * len(trials), (), progress)
