"""Checking uncertainty: interval coverage and the calibration of class probabilities.

- :func:`coverage`: the share of true values inside their intervals;
  :func:`coverage_interval`: its exact (Clopper-Pearson) 95 % confidence interval, from
  ``scipy.stats.binomtest``, to tell sampling scatter from miscalibration;
- :func:`reliability` and :func:`expected_calibration_error`: probabilities grouped in
  equal-width bins; ECE = Σ_b (n_b / n)·|mean probability_b − frequency_b| (Guo et al. 2017);
- :func:`fit_temperature`: the temperature T of logit/T that minimises the negative
  log-likelihood on calibration data (temperature scaling, Guo et al. 2017).
"""

from __future__ import annotations

import numpy as np

__all__ = ["coverage", "coverage_interval", "reliability", "expected_calibration_error",
           "calibrated_ece", "fit_temperature"]


def coverage(truth: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Share of samples (axis 0) with lower ≤ truth ≤ upper; shape of one sample."""
    inside = (np.asarray(lower) <= truth) & (truth <= np.asarray(upper))
    return inside.mean(axis=0)


def coverage_interval(share: float, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Clopper-Pearson interval of a coverage ``share`` measured on ``n`` samples."""
    k = int(round(share * n))
    from scipy.stats import binomtest  # loads scipy.stats: only where coverage is checked

    ci = binomtest(k, n).proportion_ci(confidence_level=confidence, method="exact")
    return float(ci.low), float(ci.high)


def reliability(probability: np.ndarray, outcome: np.ndarray, bins: int = 10
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per equal-width probability bin: (mean predicted probability, observed frequency of
    the outcome, count); empty bins give NaN and 0."""
    p = np.ravel(probability).astype(float)
    y = np.ravel(outcome).astype(float)
    index = np.clip((p * bins).astype(int), 0, bins - 1)
    count = np.bincount(index, minlength=bins)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_p = np.bincount(index, weights=p, minlength=bins) / count
        freq = np.bincount(index, weights=y, minlength=bins) / count
    return mean_p, freq, count


def expected_calibration_error(probability: np.ndarray, outcome: np.ndarray,
                               bins: int = 10) -> float:
    """ECE of predicted probabilities of a binary ``outcome`` (see the module doc)."""
    mean_p, freq, count = reliability(probability, outcome, bins)
    used = count > 0
    return float(np.sum(count[used] * np.abs(mean_p[used] - freq[used])) / count.sum())


def calibrated_ece(probability: np.ndarray, bins: int = 10, draws: int = 2000,
                   seed: int = 0) -> np.ndarray:
    """(draws,) the ECE of ``probability`` against outcomes drawn from it (each outcome
    true with its own probability): what the ECE of perfectly calibrated probabilities
    reads on this many samples (its sampling floor; the share of draws at or above an
    observed ECE is the chance of one that large from calibrated probabilities)."""
    p = np.ravel(probability).astype(float)
    rng = np.random.default_rng(seed)
    return np.array([expected_calibration_error(p, rng.random(len(p)) < p, bins)
                     for _ in range(draws)])


def confidence_calibration_error(probability: np.ndarray, outcome: np.ndarray,
                                 bins: int = 10) -> float:
    """ECE of a binary class's confidence max(p, 1 − p) (p the probability of the outcome):
    over ``bins`` equal bins of confidence from 0.5 to 1, the sample-weighted |share right −
    mean confidence| (what the universal table reports)."""
    p = np.ravel(probability).astype(float)
    truth = np.ravel(outcome).astype(bool)
    confidence = np.maximum(p, 1 - p)
    right = (p >= 0.5) == truth
    edges = np.linspace(0.5, 1.0, bins + 1)
    which = np.clip(np.digitize(confidence, edges) - 1, 0, bins - 1)
    total = 0.0
    for b in range(bins):
        sel = which == b
        if sel.any():
            total += sel.sum() * abs(right[sel].mean() - confidence[sel].mean())
    return float(total / max(len(p), 1))


def fit_temperature(logits: np.ndarray, outcome: np.ndarray,
                    log_bounds: tuple[float, float] = (float(np.log(0.05)), float(np.log(50.0))),
                    xatol: float = 1e-6) -> float:
    """T > 0 minimising the mean negative log-likelihood of sigmoid(logit / T), searched
    for log T within ``log_bounds`` to ``xatol``."""
    z = np.ravel(logits).astype(float)
    y = np.ravel(outcome).astype(float)

    def nll(log_t: float) -> float:
        s = z / np.exp(log_t)
        return float(np.mean(np.logaddexp(0.0, s) - y * s))

    from scipy.optimize import minimize_scalar  # only where a temperature is fitted

    best = minimize_scalar(nll, bounds=log_bounds, method="bounded",
                           options={"xatol": xatol})
    return float(np.exp(best.x))
