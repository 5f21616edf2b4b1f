"""The first stages of a locked DEC fit under each class strategy
(:data:`~posture_id.fitting.options.ClassStrategy`): what comes before the polish, and the
start it gets (docs/fit.md)."""

from __future__ import annotations

import itertools
from typing import Protocol

import numpy as np

from posture_id.dec.prior import relative_factors
from posture_id.fitting.options import (
    ClassStrategy,
    ExhaustiveClasses,
    FixedClasses,
    RelaxedClasses,
)
from posture_id.fitting.result import StageResult
from posture_id.fitting.unknowns import class_names

__all__ = ["first_stages", "FitRun"]


class FitRun(Protocol):
    """What the first stages use of a running fit
    (:class:`posture_id.fitting.least_squares` implements it)."""

    layout: object
    options: object
    suffix: str

    @property
    def first_evaluator(self) -> tuple: ...

    def assemble(self, guess: np.ndarray, gains_delays: np.ndarray, classes: np.ndarray
                 ) -> np.ndarray: ...

    def stage(self, name: str, evaluator, q0: np.ndarray, free, tolerance: float,
              limit: int) -> StageResult: ...

    def say(self, message: str) -> None: ...


def first_stages(strategy: ClassStrategy, run: FitRun, guess: np.ndarray
                 ) -> tuple[np.ndarray, StageResult | None]:
    """(the polish's start q, the chosen stage or None) of ``strategy`` on ``run``."""
    if isinstance(strategy, RelaxedClasses):
        return _relaxed(strategy, run, guess)
    if isinstance(strategy, ExhaustiveClasses):
        combos = itertools.product((1.0, -1.0), repeat=run.layout.n)
        return _best_of_classes(run, guess, [np.asarray(c, dtype=float) for c in combos])
    if isinstance(strategy, FixedClasses):
        return _best_of_classes(run, guess, [guess[run.layout.classes]])
    raise TypeError(f"not a class strategy: {strategy!r}")


def _relaxed(strategy: RelaxedClasses, run: FitRun, guess: np.ndarray
             ) -> tuple[np.ndarray, None]:
    """Relaxed fits from the guess (classes half-way to their values) and from prior
    draws; the best one's classes rounded to ±1 start the polish."""
    lay = run.layout
    evaluator, tolerance, limit = run.first_evaluator
    rng = np.random.default_rng(strategy.seed)
    starts = [run.assemble(guess, guess[lay.gains_delays], 0.5 * guess[lay.classes])]
    for _ in range(strategy.starts - 1):
        starts.append(run.assemble(guess, relative_factors(rng, 4 * lay.n) - 1,
                                   np.zeros(lay.n)))
    tries = []
    for k, q0 in enumerate(starts):
        label = "relaxed classes" + (f", start {k + 1}/{len(starts)}" if k else "")
        tries.append(run.stage(label + run.suffix, evaluator, q0,
                               lay.everything(run.options.fit_passive), tolerance, limit))
    best = min(tries, key=lambda t: t.cost)
    signs = np.where(best.q[lay.classes] >= 0, 1.0, -1.0)
    run.say(f"classes from the relaxed fit: {class_names(signs)}")
    start_q = best.q.copy()
    start_q[lay.classes] = signs
    return start_q, None


def _best_of_classes(run: FitRun, guess: np.ndarray, combos: list[np.ndarray]
                     ) -> tuple[np.ndarray, StageResult]:
    """The continuous parameters fitted under each class combination; the best."""
    evaluator, tolerance, limit = run.first_evaluator
    candidates = []
    for combo in combos:
        q0 = run.assemble(guess, guess[run.layout.gains_delays], combo)
        candidates.append(run.stage(f"classes {class_names(combo)}{run.suffix}", evaluator,
                                    q0, run.layout.continuous(run.options.fit_passive),
                                    tolerance, limit))
    chosen = min(candidates, key=lambda s: s.cost)
    return chosen.q, chosen
