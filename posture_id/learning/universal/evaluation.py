"""How well the universal network does on held-out module samples: classes, parameter
errors and interval coverage, overall and per group."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from posture_id.learning.universal.calibration import (
    UniversalCalibration,
    regime_of,
    trend_terms,
)
from posture_id.learning.universal.model import UniversalModel
from posture_id.learning.universal.samples import Samples
from posture_id.uncertainty.coverage import confidence_calibration_error

__all__ = ["GroupScore", "score_samples", "relative_errors"]

_NAMES = ("kp", "ki", "kd", "delay_s")


def relative_errors(estimate: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """(M, 4) |p̂/p − 1| from normalised values t = p/p_default − 1."""
    return np.abs((1.0 + estimate) / (1.0 + truth) - 1.0)


@dataclass(frozen=True)
class GroupScore:
    """Scores of one group of module samples.

    Attributes:
        modules: samples. trials: distinct trials. classes_pct: modules whose class is
        right, %. trials_all_right_pct: trials with every class right, %.
        median_error_pct: parameter → median |relative error|, %. coverage_pct: parameter →
        share of the truths inside the ``level`` intervals, % (NaN without a calibration).
        by_module: per module position (0: the ankle), parameter → median |relative
        error|, %. class_ece_pct: expected calibration error of the (calibrated) class
        probabilities, 10 bins of confidence, %.
    """

    modules: int
    trials: int
    classes_pct: float
    trials_all_right_pct: float
    median_error_pct: dict
    coverage_pct: dict
    level: float
    by_module: tuple = ()
    class_ece_pct: float = float("nan")

    def to_dict(self) -> dict:
        return {"modules": self.modules, "trials": self.trials, "by_module": list(self.by_module),
                "classes_pct": self.classes_pct, "trials_all_right_pct": self.trials_all_right_pct,
                "class_ece_pct": self.class_ece_pct,
                "median_error_pct": self.median_error_pct, "coverage_pct": self.coverage_pct,
                "level": self.level}


def score_samples(model: UniversalModel, samples: Samples,
                  calibration: UniversalCalibration | None, level: float = 0.9,
                  groups: np.ndarray | None = None) -> dict[str, GroupScore]:
    """Scores per group label (``groups`` (M,) strings; default one group 'all')."""
    pred = model.predict(samples.inputs, samples.noise_ratio, samples.noise_colour)
    right = (pred.logit > 0) == (samples.targets[:, 4] > 0)
    errors = relative_errors(pred.mean, samples.targets[:, :4])
    inside = np.full(errors.shape, np.nan)
    probability = 1.0 / (1.0 + np.exp(-pred.logit))
    if calibration is not None:
        regimes = regime_of(samples.segments, samples.noise_ratio, samples.noise_colour)
        terms = trend_terms(samples.segments, samples.noise_ratio, samples.noise_colour,
                            samples.inputs)
        half = np.empty_like(pred.sd)
        for regime in np.unique(regimes):
            sel = regimes == regime
            probability[sel] = calibration.probability(str(regime), pred.logit[sel])
            half[sel] = calibration.half_width(str(regime), level, pred.sd[sel], terms[sel])
        low = np.maximum(pred.mean - half, -1.0)
        inside = ((samples.targets[:, :4] >= low)
                  & (samples.targets[:, :4] <= pred.mean + half)).astype(float)
    groups = np.full(len(samples), "all") if groups is None else np.asarray(groups)
    out = {}
    for g in sorted(set(groups.tolist())):
        sel = groups == g
        trials = samples.trial[sel]
        all_right = [right[sel][trials == t].all() for t in np.unique(trials)]
        out[g] = GroupScore(
            modules=int(sel.sum()), trials=len(all_right),
            classes_pct=float(100 * right[sel].mean()),
            trials_all_right_pct=float(100 * np.mean(all_right)),
            median_error_pct={n: float(100 * np.median(errors[sel, i]))
                              for i, n in enumerate(_NAMES)},
            coverage_pct={n: float(100 * np.mean(inside[sel, i])) for i, n in enumerate(_NAMES)},
            level=level, class_ece_pct=100 * confidence_calibration_error(
                probability[sel], samples.targets[sel, 4] > 0),
            by_module=tuple({n: float(100 * np.median(errors[sel & (samples.module == m), i]))
                             for i, n in enumerate(_NAMES)}
                            for m in np.unique(samples.module[sel])))
    return out
