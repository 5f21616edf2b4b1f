"""Honest error bars: conformal intervals, their coverage, class-probability calibration
and identifiability (docs/uncertainty.md).

numpy and scipy only; the learning and fitting layers apply it to the CNN's and the
least-squares answers, :mod:`posture_id.identify.calibration` measures it.
"""

from posture_id.uncertainty.conformal import (
    LEVEL_GRID,
    ConformalCalibration,
    Normaliser,
    conformal_quantile,
)
from posture_id.uncertainty.coverage import (
    coverage,
    coverage_interval,
    expected_calibration_error,
    fit_temperature,
    reliability,
)
from posture_id.uncertainty.identifiability import (
    Determination,
    determination,
    prior_interval,
)
from posture_id.uncertainty.intervals import ParameterIntervals
from posture_id.uncertainty.noise import sensor_noise_deg

__all__ = [
    "LEVEL_GRID", "ConformalCalibration", "Normaliser", "conformal_quantile", "coverage",
    "coverage_interval", "expected_calibration_error", "fit_temperature", "reliability",
    "Determination", "determination", "prior_interval", "ParameterIntervals",
    "sensor_noise_deg",
]
