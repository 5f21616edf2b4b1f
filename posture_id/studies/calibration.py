"""Are the error bars honest? Calibration of a model's intervals and class probabilities.

:func:`run_calibration` (``posture-id network cnn calibrate MODEL_DIR DATASET --out DIR``):

1. **Calibrates the CNN** on the data set's validation split at several sensor-noise
   levels (:func:`posture_id.learning.calibration.calibrate_cnn`).
2. **Checks it** on every trial of the test split (held out from training and
   calibration) at each checked noise level: the empirical coverage of the 50, 80, 90 and
   95 % intervals per module and parameter (with its exact 95 % binomial interval), the
   class probabilities' reliability and expected calibration error (ECE) before and after
   temperature scaling, and how much the recording narrows each parameter (interval
   width against the prior's).
3. **Least squares** (``fits`` > 0): the first ``fits`` test trials at each checked level
   are refined by least squares from the CNN's answer (:mod:`.fit_runs`, parallel,
   resumable). Reported: the coverage of the Gauss-Newton intervals ±z·SE as they are,
   and of the calibrated ones, scale·SE with the conformal scale of |error|/SE, never
   below z·σ_residual/σ_SE (:func:`~posture_id.fitting.result.noise_allows`: an interval
   is never narrower than the Gauss-Newton one of the fit's own residual noise). The
   calibrated coverage is cross-validated: each trial's interval uses the scales of the
   other folds. The scales from all fits go into ``calibration.json`` for ``identify``.

The report and ``calibration.json`` are written into the report folder;
:func:`install_calibration` (``--install``) puts the calibration beside the model.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from scipy.stats import norm

from posture_id.dec.parameters import TARGET_FIELDS
from posture_id.errors import PostureIdError
from posture_id.fileio import Result, atomic_write_text
from posture_id.fitting.options import FitOptions
from posture_id.fitting.result import noise_allows
from posture_id.learning.calibration import (
    CnnCalibration,
    calibrate_cnn,
    held_out_predictions,
    noise_levels_of,
)
from posture_id.learning.checkpoint import load_model
from posture_id.learning.config import LearningError
from posture_id.learning.data.store import Dataset
from posture_id.plotting import plot_coverage, plot_identifiability, plot_reliability
from posture_id.progress import Progress, report
from posture_id.studies.fit_runs import FIT_JOURNAL, run_fits
from posture_id.uncertainty.conformal import ConformalCalibration, Normaliser
from posture_id.uncertainty.coverage import (
    coverage,
    coverage_interval,
    expected_calibration_error,
    reliability,
)
from posture_id.uncertainty.identifiability import PARTLY, WELL, determination, prior_interval

__all__ = ["CalibrationReport", "CoverageAtLevel", "ClassCheck", "CnnCheck", "LeastSquaresCheck",
           "run_calibration", "install_calibration", "least_squares_check", "CHECKED_LEVELS",
           "TARGET_BAND"]

#: Nominal levels whose coverage is reported.
CHECKED_LEVELS = (0.5, 0.8, 0.9, 0.95)
#: The band the 90 % intervals' coverage must fall in (issue 13).
TARGET_BAND = (0.87, 0.93)
#: Folds of the cross-validated least-squares coverage.
FOLDS = 5
#: Bins of the reliability diagram and of the ECE.
BINS = 10


@dataclass(frozen=True)
class CoverageAtLevel:
    """How intervals at one nominal level did on T trials.

    Attributes:
        coverage: (N, 4) share of truths inside, per module and parameter.
        coverage_95ci: (N, 4, 2) its exact 95 % binomial interval.
        median_width: (N, 4) median interval width, normalised units.
        width_to_prior: (N, 4) that against the prior's width at the same level.
        determination: (N, 4) :class:`Determination` by that ratio.
    """

    coverage: np.ndarray
    coverage_95ci: np.ndarray
    median_width: np.ndarray
    width_to_prior: np.ndarray
    determination: np.ndarray

    @classmethod
    def measure(cls, truth: np.ndarray, estimate: np.ndarray, half_width: np.ndarray,
                level: float) -> CoverageAtLevel:
        """Of (T, N, 4) truth and estimate with half-widths (T, N, 4) or (N, 4) (the median
        width: a few fits with huge standard errors would make a mean say little about the
        typical recording)."""
        lower = np.maximum(estimate - half_width, -1.0)
        upper = estimate + half_width
        share = coverage(truth, lower, upper)
        width = np.median(np.broadcast_to(upper - lower, truth.shape), axis=0)
        ratio, words = determination(width, level)
        ci = np.array([[coverage_interval(c, len(truth)) for c in row] for row in share])
        return cls(share, ci, width, ratio, words)

    def to_dict(self) -> dict:
        return {"coverage": self.coverage.tolist(), "coverage_95ci": self.coverage_95ci.tolist(),
                "median_width": self.median_width.tolist(),
                "width_to_prior": self.width_to_prior.tolist(),
                "determination": [[w.value for w in row] for row in self.determination]}


def _coverage_block(truth: np.ndarray, estimate: np.ndarray,
                    half_widths: dict[float, np.ndarray]) -> dict[float, CoverageAtLevel]:
    return {level: CoverageAtLevel.measure(truth, estimate, h, level)
            for level, h in half_widths.items()}


def _levels_dict(block: dict[float, CoverageAtLevel]) -> dict:
    return {f"{level:g}": c.to_dict() for level, c in block.items()}


@dataclass(frozen=True)
class ClassReliability:
    """Class probabilities' calibration: the modules' temperatures, ECE (all and per
    module) and the reliability diagram's bins (mean probability, frequency, count)."""

    temperature: np.ndarray
    ece: float
    ece_per_module: tuple[float, ...]
    mean_probability: np.ndarray
    frequency: np.ndarray
    count: np.ndarray

    def to_dict(self) -> dict:
        return {"temperature": self.temperature.tolist(), "ece": self.ece,
                "ece_per_module": list(self.ece_per_module),
                "reliability": {"mean_probability": self.mean_probability.tolist(),
                                "frequency": self.frequency.tolist(),
                                "count": self.count.tolist()}}


@dataclass(frozen=True)
class ClassCheck:
    """Class accuracy, and the reliability raw and after temperature scaling (None for a
    calibration without temperatures)."""

    accuracy: float
    raw: ClassReliability
    calibrated: ClassReliability | None

    @classmethod
    def measure(cls, logit: np.ndarray, truth_class: np.ndarray,
                temperature: tuple[float, ...] | None) -> ClassCheck:
        """Of (T, N) class logits against (T, N) true classes (±1)."""
        outcome = truth_class > 0

        def reliability_at(t: np.ndarray) -> ClassReliability:
            p = 1.0 / (1.0 + np.exp(-logit / t))
            mean_p, freq, count = reliability(p, outcome, BINS)
            return ClassReliability(
                t, expected_calibration_error(p, outcome, BINS),
                tuple(expected_calibration_error(p[:, m], outcome[:, m], BINS)
                      for m in range(p.shape[1])), mean_p, freq, count)

        return cls(float(np.mean((logit > 0) == outcome)),
                   reliability_at(np.ones(logit.shape[1])),
                   None if temperature is None else reliability_at(np.asarray(temperature)))

    @property
    def best(self) -> ClassReliability:
        """The calibrated reading when there is one."""
        return self.calibrated or self.raw

    def to_dict(self) -> dict:
        out = {"accuracy": self.accuracy, "raw": self.raw.to_dict()}
        if self.calibrated is not None:
            out["calibrated"] = self.calibrated.to_dict()
        return out


@dataclass(frozen=True)
class CnnCheck:
    """The CNN at one sensor-noise level on the test split."""

    trials: int
    noise_estimate_deg_median: float
    intervals: dict[float, CoverageAtLevel]
    classes: ClassCheck

    def to_dict(self) -> dict:
        return {"trials": self.trials, "noise_estimate_deg_median": self.noise_estimate_deg_median,
                "intervals": _levels_dict(self.intervals), "classes": self.classes.to_dict()}


@dataclass(frozen=True)
class LeastSquaresCheck:
    """Least squares (from the CNN's answer) at one sensor-noise level on test trials:
    Gauss-Newton's intervals as they are and the calibrated ones (cross-validated)."""

    trials: int
    noise_estimate_deg_median: float
    residual_rms_deg_median: float
    gauss_newton: dict[float, CoverageAtLevel]
    calibrated: dict[float, CoverageAtLevel]
    every_class_right: float

    def to_dict(self) -> dict:
        return {"trials": self.trials, "noise_estimate_deg_median": self.noise_estimate_deg_median,
                "residual_rms_deg_median": self.residual_rms_deg_median,
                "gauss_newton": _levels_dict(self.gauss_newton),
                "calibrated": _levels_dict(self.calibrated),
                "every_class_right": self.every_class_right}


@dataclass(frozen=True)
class CalibrationReport(Result):
    """See the module doc.

    Attributes:
        model_dir, dataset_dir: what was calibrated and on what. joints: module names.
        calibration: the calibration made (:class:`CnnCalibration`, least-squares scales
            included when fitted or kept). noise_levels_deg: calibrated at.
        fits: least-squares fits asked for per checked level.
        cnn: checked noise level → :class:`CnnCheck`.
        least_squares: checked noise level → :class:`LeastSquaresCheck` (empty without
            enough fits).
    """

    model_dir: str
    dataset_dir: str
    joints: tuple[str, ...]
    calibration: CnnCalibration
    noise_levels_deg: tuple[float, ...]
    fits: int
    cnn: dict[float, CnnCheck]
    least_squares: dict[float, LeastSquaresCheck]

    def to_dict(self) -> dict:
        summary = {"noise_levels_deg": list(self.noise_levels_deg),
                   "checked_noise_deg": list(self.cnn),
                   "temperature": self.calibration.temperature,
                   "validation_trials": self.calibration.intervals.trials,
                   "least_squares_fits": self.fits}
        return {"model_dir": self.model_dir, "dataset_dir": self.dataset_dir,
                "joints": list(self.joints), "checked_levels": list(CHECKED_LEVELS),
                "target_band_90": list(TARGET_BAND), "calibration": summary,
                "cnn": {f"{n:g}": c.to_dict() for n, c in self.cnn.items()},
                "least_squares": {f"{n:g}": c.to_dict() for n, c in self.least_squares.items()}}

    def _readings(self, what: str) -> list[tuple[str, float, int, dict[float, CoverageAtLevel]]]:
        """(method label, noise, trials, coverage by level) of the CNN ("cnn"), least
        squares as it is ("gauss_newton") or calibrated ("calibrated")."""
        if what == "cnn":
            return [("CNN", n, c.trials, c.intervals) for n, c in self.cnn.items()]
        label = {"gauss_newton": "least squares, Gauss-Newton",
                 "calibrated": "least squares, calibrated"}[what]
        return [(label, n, c.trials, getattr(c, what)) for n, c in self.least_squares.items()]

    def _coverage_rows(self, method: str, what: str) -> list[str]:
        rows = []
        for _, noise, trials, block in self._readings(what):
            for j, row in zip(self.joints, block[0.9].coverage, strict=True):
                rows.append(f"| {method} | {noise:g}° | {trials} | {j} | "
                            + " | ".join(f"{100 * c:.1f} %" for c in row) + " |")
        return rows

    def to_markdown(self) -> str:
        names = " | ".join(TARGET_FIELDS)
        low, high = prior_interval(0.9)
        prior_width = high - low
        lines = ["# Calibration of the intervals and class probabilities", "",
                 f"Model `{self.model_dir}`, data set `{self.dataset_dir}`. CNN intervals: "
                 f"conformal on the validation split at sensor noise "
                 f"{', '.join(f'{n:g}°' for n in self.noise_levels_deg)}; "
                 "checked on the test split. Made by `posture-id network cnn calibrate` "
                 "(docs/uncertainty.md).", "",
                 "## Coverage of the 90 % intervals", "",
                 f"Target: {100 * TARGET_BAND[0]:g}–{100 * TARGET_BAND[1]:g} % for every "
                 "parameter and module.", "",
                 f"| method | sensor noise | trials | module | {names} |",
                 "|---|---|---|---|" + "---|" * len(TARGET_FIELDS)]
        lines += self._coverage_rows("CNN (conformal)", "cnn")
        lines += self._coverage_rows("least squares, Gauss-Newton ±1.645·SE", "gauss_newton")
        lines += self._coverage_rows("least squares, calibrated (cross-validated)",
                                     "calibrated")
        if not self.least_squares:
            lines += ["", "Least squares was not run (`--fits 0`)."]
        else:
            lines += ["", "Least squares refined the CNN's answer with its classes kept; every "
                      "class was right in " + ", ".join(
                          f"{100 * r.every_class_right:.1f} % of the fits at {n:g}°"
                          for n, r in self.least_squares.items())
                      + " (a fit with a wrong class is far off; no interval of its width "
                      "holds it). Median residual RMS: " + ", ".join(
                          f"{r.residual_rms_deg_median:.2g}° at {n:g}°"
                          for n, r in self.least_squares.items()) + "."]
        lines += ["", "Coverage at every checked level (mean over modules and parameters; "
                      "min–max):", "", "| method | sensor noise | "
                  + " | ".join(f"{100 * lv:g} %" for lv in CHECKED_LEVELS) + " |",
                  "|---|---|" + "---|" * len(CHECKED_LEVELS)]
        for what in ("cnn", "gauss_newton", "calibrated"):
            for method, noise, _, block in self._readings(what):
                cells = []
                for lv in CHECKED_LEVELS:
                    c = block[lv].coverage
                    cells.append(f"{100 * c.mean():.1f} % ({100 * c.min():.1f}–"
                                 f"{100 * c.max():.1f})")
                lines.append(f"| {method} | {noise:g}° | " + " | ".join(cells) + " |")
        lines += ["", "## Class probabilities", "",
                  "| sensor noise | accuracy | ECE before | ECE after temperature scaling | "
                  "per module (after) |", "|---|---|---|---|---|"]
        for noise, result in self.cnn.items():
            c = result.classes
            after = c.best
            lines.append(f"| {noise:g}° | {100 * c.accuracy:.2f} % | {c.raw.ece:.4f} | "
                         f"{after.ece:.4f} (T = "
                         f"{', '.join(f'{t:.3g}' for t in after.temperature)}) | "
                         + ", ".join(f"{j} {e:.4f}" for j, e in
                                     zip(self.joints, after.ece_per_module, strict=True))
                         + " |")
        lines += ["", "## Identifiability: 90 % interval width against the prior's", "",
                  f"The prior's 90 % interval of p̃ = p/p_default − 1 is {prior_width:.2f} wide "
                  f"(docs/model.md §5). Below {WELL:g}: well determined; below {PARTLY:g}: partly; "
                  "otherwise not determined by the recording.", "",
                  f"| method | sensor noise | module | {names} |",
                  "|---|---|---|" + "---|" * len(TARGET_FIELDS)]
        for what in ("cnn", "calibrated"):
            for method, noise, _, block in self._readings(what):
                entry = block[0.9]
                for j, ratio, words in zip(self.joints, entry.width_to_prior,
                                           entry.determination, strict=True):
                    lines.append(f"| {method} | {noise:g}° | {j} | " + " | ".join(
                        f"{r:.2f} ({w.value})" for r, w in zip(ratio, words, strict=True))
                        + " |")
        lines += ["", "![coverage](coverage.png)", "", "![reliability](reliability.png)", "",
                  "![identifiability](identifiability.png)", ""]
        return "\n".join(lines)

    @property
    def _labels(self) -> list[str]:
        return [f"{j} {f}" for j in self.joints for f in TARGET_FIELDS]

    def plot(self, path=None, ax=None):
        """Coverage against the nominal level, per method and noise level."""
        short = {"cnn": "CNN", "gauss_newton": "LS Gauss-Newton", "calibrated": "LS calibrated"}
        curves = {f"{short[what]}, {noise:g}°": np.array(
                      [np.ravel(block[lv].coverage) for lv in CHECKED_LEVELS])
                  for what in short for _, noise, _, block in self._readings(what)}
        return plot_coverage(CHECKED_LEVELS, curves, self._labels, TARGET_BAND, path=path,
                             ax=ax)

    def plot_reliability(self, path=None, ax=None):
        """The class probabilities' reliability diagrams, raw and temperature-scaled."""
        diagrams = {}
        for noise, result in self.cnn.items():
            for name, r in (("raw", result.classes.raw),
                            ("calibrated", result.classes.calibrated)):
                if r is not None:
                    diagrams[f"{noise:g}°, {name} (ECE {r.ece:.3f})"] = r.to_dict()[
                        "reliability"]
        return plot_reliability(diagrams, path=path, ax=ax)

    def plot_identifiability(self, path=None, ax=None):
        """Each parameter's 90 % interval width against the prior's."""
        ratios = {f"{'LS' if what == 'calibrated' else 'CNN'}, {noise:g}°":
                  np.ravel(block[0.9].width_to_prior)
                  for what in ("cnn", "calibrated") for _, noise, _, block in self._readings(what)}
        return plot_identifiability(ratios, self._labels, path=path, ax=ax)

    def summary(self) -> str:
        """The 90 % intervals' coverage range per method and noise level."""
        lines = [f"calibration of {self.model_dir} on {self.dataset_dir}: 90 % coverage"]
        for what in ("cnn", "gauss_newton", "calibrated"):
            for method, noise, trials, block in self._readings(what):
                c = block[0.9].coverage
                lines.append(f"  {method}, {noise:g}° ({trials} trials): "
                             f"{100 * c.min():.1f}–{100 * c.max():.1f} %")
        return "\n".join(lines)

    def write(self, folder: str | Path) -> list[Path]:
        """The report (JSON, Markdown, PNGs) and the calibration itself
        (:data:`~posture_id.learning.calibration.CALIBRATION`) into ``folder``."""
        folder = Path(folder)
        paths = [folder / "coverage.png", folder / "reliability.png",
                 folder / "identifiability.png"]
        self.plot(paths[0])
        self.plot_reliability(paths[1])
        self.plot_identifiability(paths[2])
        return [self.to_json(folder / "calibration_report.json"),
                atomic_write_text(folder / "calibration_report.md", self.to_markdown()),
                self.calibration.save(folder), *paths]


def _cnn_check(model, data: Dataset, calibration: CnnCalibration, noise: float,
               progress: Progress | None) -> CnnCheck:
    run = held_out_predictions(model, data, "test", noise, progress)
    conformal = calibration.intervals
    half = {lv: np.stack([conformal.scale(lv, x) for x in run.noise_estimate_deg])
            for lv in CHECKED_LEVELS}
    return CnnCheck(len(run.truth), float(np.median(run.noise_estimate_deg)),
                    _coverage_block(run.truth[..., :4], run.estimate[..., :4], half),
                    ClassCheck.measure(run.logit, run.truth[..., 4], calibration.temperature))


def least_squares_check(rows: list[dict], noise_levels: tuple[float, ...]
                        ) -> tuple[dict[float, LeastSquaresCheck], ConformalCalibration | None]:
    """The coverage of Gauss-Newton's and the calibrated (cross-validated) intervals per
    noise level, and the conformal scales from all fits; ``({}, None)`` with fewer than
    2 × :data:`FOLDS` fits at some level.

    Args:
        rows: least-squares runs (:func:`~.fit_runs.run_fits`): each with ``noise_deg``,
            ``position``, ``truth`` and ``estimate`` (N, 5), ``standard_errors`` (N, 4,
            −1 for infinite), ``noise_estimate_deg`` and ``rms_deg``.
    """
    by_level = {lv: sorted((r for r in rows if r["noise_deg"] == lv),
                           key=lambda r: r["position"]) for lv in noise_levels}
    n = min(len(v) for v in by_level.values())
    if n < 2 * FOLDS:
        return {}, None
    arrays = {}
    for lv, group in by_level.items():
        group = group[:n]
        truth = np.array([r["truth"] for r in group])[..., :4]
        estimate = np.array([r["estimate"] for r in group])[..., :4]
        se = np.array([r["standard_errors"] for r in group])
        se = np.where(se < 0, np.inf, se)
        arrays[lv] = (truth, estimate, se,
                      np.array([r["noise_estimate_deg"] for r in group]),
                      np.array([r["rms_deg"] for r in group]))
    with np.errstate(divide="ignore", invalid="ignore"):
        scores = np.stack([np.abs(t - e) / s for t, e, s, _, _ in arrays.values()])
    noise_est = np.array([np.median(a[3]) for a in arrays.values()])
    nominal = np.array(noise_levels, dtype=float)
    fold = np.arange(n) % FOLDS
    out = {}
    floor = FitOptions().noise_floor_deg  # what the fits' standard errors assumed
    for lv, (truth, estimate, se, noise, rms) in arrays.items():
        gauss = {level: norm.ppf((1 + level) / 2) * se for level in CHECKED_LEVELS}
        calibrated = {level: np.empty_like(se) for level in CHECKED_LEVELS}
        for f in range(FOLDS):
            scales = ConformalCalibration.from_scores(
                Normaliser.STANDARD_ERROR, scores[:, fold != f], noise_est, nominal)
            for level in CHECKED_LEVELS:
                for t in np.flatnonzero(fold == f):
                    # the rows' fits compare every sample: their residual SD is the RMS
                    least = noise_allows(level, rms[t], floor)
                    calibrated[level][t] = np.maximum(scales.scale(level, noise[t]),
                                                      least) * se[t]
        out[lv] = LeastSquaresCheck(
            n, float(np.median(noise)), float(np.median(rms)),
            _coverage_block(truth, estimate, gauss), _coverage_block(truth, estimate, calibrated),
            float(np.mean([np.array_equal(np.array(r["truth"])[:, 4],
                                          np.array(r["estimate"])[:, 4])
                           for r in by_level[lv][:n]])))
    return out, ConformalCalibration.from_scores(Normaliser.STANDARD_ERROR, scores, noise_est,
                                                 nominal)


def run_calibration(model_dir: str | Path, dataset_dir: str | Path, out: str | Path,
                    check_noise_deg: tuple[float, ...] | None = None,
                    calibration_noise_deg: tuple[float, ...] | None = None, fits: int = 0,
                    workers: int | None = None,
                    progress: Progress | None = None) -> CalibrationReport:
    """Calibrate and check (see the module doc). The report and the calibration
    (``calibration.json``) go into ``out``; nothing is written beside the model (the
    command line's ``--install`` puts the calibration there, where ``identify`` reads it:
    :func:`install_calibration`)."""
    model = load_model(model_dir)
    try:
        previous = CnnCalibration.load(model_dir)
    except LearningError:
        previous = None  # an unreadable or older calibration is about to be made anew
    data = Dataset.open(dataset_dir)
    if data.n_segments != len(model.sidecar.get("body", {}).get("joints", [])):
        raise PostureIdError(f"{dataset_dir}: a {data.n_segments}-segment data set; the model "
                             f"{model_dir} was trained for another body")
    levels = calibration_noise_deg or noise_levels_of(data)
    checked = check_noise_deg or tuple(sorted({levels[0], levels[-1]}))
    report(progress, 0, None, "message", "calibrating the CNN on the validation split")
    calibration = calibrate_cnn(model, data, tuple(levels), progress)
    cnn = {lv: _cnn_check(model, data, calibration, lv, progress) for lv in checked}
    least_squares, ls_scales = {}, None
    if fits > 0:
        report(progress, 0, None, "message", f"least squares on {fits} test trials per level")
        rows = run_fits(model_dir, dataset_dir, "test", fits, tuple(checked),
                        Path(out) / FIT_JOURNAL, workers, progress)
        least_squares, ls_scales = least_squares_check(rows, tuple(checked))
    if ls_scales is not None:
        calibration = replace(calibration, least_squares=ls_scales)
    elif previous is not None and previous.weights_sha256 == calibration.weights_sha256:
        calibration = replace(calibration, least_squares=previous.least_squares)  # kept
    joints = tuple(data.manifest["body"]["joints"])
    result = CalibrationReport(str(model_dir), str(dataset_dir), joints, calibration,
                               tuple(levels), fits, cnn, least_squares)
    result.write(out)
    return result


def install_calibration(report: CalibrationReport) -> Path:
    """Put the report's calibration beside its model's weights, where ``identify`` reads
    it; the path written."""
    return report.calibration.save(report.model_dir)
