"""Are the error bars honest? Calibration of a model's intervals and class probabilities.

:func:`run_calibration` (``posture-id calibration MODEL_DIR DATASET --out DIR``):

1. **Calibrates the CNN** on the data set's validation split at several sensor-noise
   levels (:func:`posture_id.learning.calibration.calibrate_cnn`) and writes
   ``MODEL_DIR/calibration.json``.
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
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from scipy.stats import norm

from posture_id.datasets.store import Dataset
from posture_id.dec.parameters import TARGET_FIELDS
from posture_id.errors import PostureIdError
from posture_id.fileio import JsonResult, atomic_write_text
from posture_id.fitting.options import FitOptions
from posture_id.fitting.result import noise_allows
from posture_id.identify.fit_runs import FIT_JOURNAL, run_fits
from posture_id.learning.calibration import (
    CnnCalibration,
    calibrate_cnn,
    held_out_predictions,
    noise_levels_of,
)
from posture_id.learning.checkpoint import load_model
from posture_id.learning.config import LearningError
from posture_id.plotting import plot_coverage, plot_identifiability, plot_reliability
from posture_id.progress import Progress, report
from posture_id.uncertainty.conformal import ConformalCalibration, Normaliser
from posture_id.uncertainty.coverage import (
    coverage,
    coverage_interval,
    expected_calibration_error,
    reliability,
)
from posture_id.uncertainty.identifiability import PARTLY, WELL, determination, prior_interval

__all__ = ["CalibrationReport", "run_calibration", "CHECKED_LEVELS", "TARGET_BAND"]

#: Nominal levels whose coverage is reported.
CHECKED_LEVELS = (0.5, 0.8, 0.9, 0.95)
#: The band the 90 % intervals' coverage must fall in (issue 13).
TARGET_BAND = (0.87, 0.93)
#: Folds of the cross-validated least-squares coverage.
FOLDS = 5
#: Bins of the reliability diagram and of the ECE.
BINS = 10


def _coverage_block(truth: np.ndarray, estimate: np.ndarray, half_widths: dict) -> dict:
    """Coverage and median width per level of (T, N, 4) truth/estimate with half-widths
    {level: (T, N, 4) or (N, 4)} (the median: a few fits with huge standard errors would
    make a mean say little about the typical recording)."""
    out = {}
    for level, h in half_widths.items():
        lower = np.maximum(estimate - h, -1.0)
        upper = estimate + h
        share = coverage(truth, lower, upper)
        width = np.median(np.broadcast_to(upper - lower, truth.shape), axis=0)
        ratio, words = determination(width, level)
        out[f"{level:g}"] = {
            "coverage": share.tolist(),
            "coverage_95ci": [[list(coverage_interval(c, len(truth))) for c in row]
                              for row in share],
            "median_width": width.tolist(), "width_to_prior": ratio.tolist(),
            "determination": [[w.value for w in row] for row in words]}
    return out


def _classes(logit: np.ndarray, truth_class: np.ndarray,
             temperature: tuple[float, ...] | None) -> dict:
    """Accuracy, ECE and reliability of (T, N) class logits, raw and divided by the
    modules' temperatures."""
    outcome = truth_class > 0
    out = {"accuracy": float(np.mean((logit > 0) == outcome))}
    for name, t in (("raw", None), ("calibrated", temperature)):
        if name == "calibrated" and t is None:
            continue
        t = np.ones(logit.shape[1]) if t is None else np.asarray(t)
        p = 1.0 / (1.0 + np.exp(-logit / t))
        mean_p, freq, count = reliability(p, outcome, BINS)
        out[name] = {
            "temperature": t.tolist(), "ece": expected_calibration_error(p, outcome, BINS),
            "ece_per_module": [expected_calibration_error(p[:, m], outcome[:, m], BINS)
                               for m in range(p.shape[1])],
            "reliability": {"mean_probability": mean_p.tolist(), "frequency": freq.tolist(),
                            "count": count.tolist()}}
    return out


@dataclass(frozen=True)
class CalibrationReport(JsonResult):
    """See the module doc. ``cnn`` and ``least_squares``: noise level (str) → results;
    coverage arrays are (N, 4) lists per level."""

    model_dir: str
    dataset_dir: str
    joints: tuple[str, ...]
    calibration: dict
    cnn: dict
    least_squares: dict

    def to_dict(self) -> dict:
        return {"model_dir": self.model_dir, "dataset_dir": self.dataset_dir,
                "joints": list(self.joints), "checked_levels": list(CHECKED_LEVELS),
                "target_band_90": list(TARGET_BAND), "calibration": self.calibration,
                "cnn": self.cnn, "least_squares": self.least_squares}

    def _coverage_rows(self, method: str, block: dict, key: str) -> list[str]:
        rows = []
        for noise, result in block.items():
            cells = result[key]["0.9"]["coverage"]
            for j, row in zip(self.joints, cells, strict=True):
                rows.append(f"| {method} | {noise}° | {result['trials']} | {j} | "
                            + " | ".join(f"{100 * c:.1f} %" for c in row) + " |")
        return rows

    def to_markdown(self) -> str:
        names = " | ".join(TARGET_FIELDS)
        low, high = prior_interval(0.9)
        prior_width = high - low
        lines = ["# Calibration of the intervals and class probabilities", "",
                 f"Model `{self.model_dir}`, data set `{self.dataset_dir}`. CNN intervals: "
                 f"conformal on the validation split at sensor noise "
                 f"{', '.join(f'{n:g}°' for n in self.calibration['noise_levels_deg'])}; "
                 "checked on the test split. Made by `posture-id calibration` "
                 "(docs/uncertainty.md).", "",
                 "## Coverage of the 90 % intervals", "",
                 f"Target: {100 * TARGET_BAND[0]:g}–{100 * TARGET_BAND[1]:g} % for every "
                 "parameter and module.", "",
                 f"| method | sensor noise | trials | module | {names} |",
                 "|---|---|---|---|" + "---|" * len(TARGET_FIELDS)]
        lines += self._coverage_rows("CNN (conformal)", self.cnn, "intervals")
        lines += self._coverage_rows("least squares, Gauss-Newton ±1.645·SE",
                                     self.least_squares, "gauss_newton")
        lines += self._coverage_rows("least squares, calibrated (cross-validated)",
                                     self.least_squares, "calibrated")
        if not self.least_squares:
            lines += ["", "Least squares was not run (`--fits 0`)."]
        else:
            lines += ["", "Least squares refined the CNN's answer with its classes kept; every "
                      "class was right in " + ", ".join(
                          f"{100 * r['every_class_right']:.1f} % of the fits at {n}°"
                          for n, r in self.least_squares.items())
                      + " (a fit with a wrong class is far off; no interval of its width "
                      "holds it). Median residual RMS: " + ", ".join(
                          f"{r['residual_rms_deg_median']:.2g}° at {n}°"
                          for n, r in self.least_squares.items()) + "."]
        lines += ["", "Coverage at every checked level (mean over modules and parameters; "
                      "min–max):", "", "| method | sensor noise | "
                  + " | ".join(f"{100 * lv:g} %" for lv in CHECKED_LEVELS) + " |",
                  "|---|---|" + "---|" * len(CHECKED_LEVELS)]
        for method, block, key in (("CNN", self.cnn, "intervals"),
                                   ("least squares, Gauss-Newton", self.least_squares,
                                    "gauss_newton"),
                                   ("least squares, calibrated", self.least_squares,
                                    "calibrated")):
            for noise, result in block.items():
                cells = []
                for lv in CHECKED_LEVELS:
                    c = np.array(result[key][f"{lv:g}"]["coverage"])
                    cells.append(f"{100 * c.mean():.1f} % ({100 * c.min():.1f}–"
                                 f"{100 * c.max():.1f})")
                lines.append(f"| {method} | {noise}° | " + " | ".join(cells) + " |")
        lines += ["", "## Class probabilities", "",
                  "| sensor noise | accuracy | ECE before | ECE after temperature scaling | "
                  "per module (after) |", "|---|---|---|---|---|"]
        for noise, result in self.cnn.items():
            c = result["classes"]
            after = c.get("calibrated", c["raw"])
            lines.append(f"| {noise}° | {100 * c['accuracy']:.2f} % | {c['raw']['ece']:.4f} | "
                         f"{after['ece']:.4f} (T = "
                         f"{', '.join(f'{t:.3g}' for t in after['temperature'])}) | "
                         + ", ".join(f"{j} {e:.4f}" for j, e in
                                     zip(self.joints, after["ece_per_module"], strict=True))
                         + " |")
        lines += ["", "## Identifiability: 90 % interval width against the prior's", "",
                  f"The prior's 90 % interval of p̃ = p/p_default − 1 is {prior_width:.2f} wide "
                  f"(MODEL §5). Below {WELL:g}: well determined; below {PARTLY:g}: partly; "
                  "otherwise not determined by the recording.", "",
                  f"| method | sensor noise | module | {names} |",
                  "|---|---|---|" + "---|" * len(TARGET_FIELDS)]
        for method, block, key in (("CNN", self.cnn, "intervals"),
                                   ("least squares, calibrated", self.least_squares,
                                    "calibrated")):
            for noise, result in block.items():
                entry = result[key]["0.9"]
                for j, ratio, words in zip(self.joints, entry["width_to_prior"],
                                           entry["determination"], strict=True):
                    lines.append(f"| {method} | {noise}° | {j} | " + " | ".join(
                        f"{r:.2f} ({w})" for r, w in zip(ratio, words, strict=True)) + " |")
        lines += ["", "![coverage](coverage.png)", "", "![reliability](reliability.png)", "",
                  "![identifiability](identifiability.png)", ""]
        return "\n".join(lines)

    def plot(self, folder: str | Path) -> list[Path]:
        """coverage.png, reliability.png and identifiability.png in ``folder``."""
        folder = Path(folder)
        labels = [f"{j} {f}" for j in self.joints for f in TARGET_FIELDS]
        curves = {}
        for method, block, key in (("CNN", self.cnn, "intervals"),
                                   ("LS Gauss-Newton", self.least_squares, "gauss_newton"),
                                   ("LS calibrated", self.least_squares, "calibrated")):
            for noise, result in block.items():
                curves[f"{method}, {noise}°"] = np.array(
                    [np.ravel(result[key][f"{lv:g}"]["coverage"]) for lv in CHECKED_LEVELS])
        paths = [folder / "coverage.png", folder / "reliability.png",
                 folder / "identifiability.png"]
        plot_coverage(CHECKED_LEVELS, curves, labels, TARGET_BAND, path=paths[0])
        diagrams = {}
        for noise, result in self.cnn.items():
            for name in ("raw", "calibrated"):
                if name in result["classes"]:
                    r = result["classes"][name]
                    diagrams[f"{noise}°, {name} (ECE {r['ece']:.3f})"] = r["reliability"]
        plot_reliability(diagrams, path=paths[1])
        ratios = {f"{method}, {noise}°": np.ravel(result[key]["0.9"]["width_to_prior"])
                  for method, block, key in (("CNN", self.cnn, "intervals"),
                                             ("LS", self.least_squares, "calibrated"))
                  for noise, result in block.items()}
        plot_identifiability(ratios, labels, path=paths[2])
        return paths

    def write(self, folder: str | Path) -> list[Path]:
        folder = Path(folder)
        return [self.to_json(folder / "calibration_report.json"),
                atomic_write_text(folder / "calibration_report.md", self.to_markdown()),
                *self.plot(folder)]


def _cnn_check(model, data: Dataset, calibration: CnnCalibration, noise: float,
               progress: Progress | None) -> dict:
    run = held_out_predictions(model, data, "test", noise, progress)
    conformal = calibration.intervals
    half = {lv: np.stack([conformal.scale(lv, x) for x in run.noise_estimate_deg])
            for lv in CHECKED_LEVELS}
    return {"trials": len(run.truth),
            "noise_estimate_deg_median": float(np.median(run.noise_estimate_deg)),
            "intervals": _coverage_block(run.truth[..., :4], run.estimate[..., :4], half),
            "classes": _classes(run.logit, run.truth[..., 4], calibration.temperature)}


def _ls_check(rows: list[dict], noise_levels: tuple[float, ...]) -> tuple[dict, dict | None]:
    """(per-level coverage of Gauss-Newton and calibrated intervals, the scales from all
    fits as a dict)."""
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
        out[f"{lv:g}"] = {"trials": n, "noise_estimate_deg_median": float(np.median(noise)),
                          "residual_rms_deg_median": float(np.median(rms)),
                          "gauss_newton": _coverage_block(truth, estimate, gauss),
                          "calibrated": _coverage_block(truth, estimate, calibrated),
                          "every_class_right": float(np.mean(
                              [np.array_equal(np.array(r["truth"])[:, 4],
                                              np.array(r["estimate"])[:, 4])
                               for r in by_level[lv][:n]]))}
    return out, ConformalCalibration.from_scores(Normaliser.STANDARD_ERROR, scores, noise_est,
                                                 nominal).to_dict()


def run_calibration(model_dir: str | Path, dataset_dir: str | Path, out: str | Path,
                    check_noise_deg: tuple[float, ...] | None = None,
                    calibration_noise_deg: tuple[float, ...] | None = None, fits: int = 0,
                    workers: int | None = None,
                    progress: Progress | None = None) -> CalibrationReport:
    """Calibrate and check (see the module doc); the report goes into ``out``."""
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
    cnn = {f"{lv:g}": _cnn_check(model, data, calibration, lv, progress) for lv in checked}
    least_squares, ls_scales = {}, None
    if fits > 0:
        report(progress, 0, None, "message", f"least squares on {fits} test trials per level")
        rows = run_fits(model_dir, dataset_dir, "test", fits, tuple(checked),
                        Path(out) / FIT_JOURNAL, workers, progress)
        least_squares, ls_scales = _ls_check(rows, tuple(checked))
    if ls_scales is not None:
        calibration = replace(calibration, least_squares=ConformalCalibration.from_dict(
            ls_scales, "least-squares calibration"))
    elif previous is not None and previous.weights_sha256 == calibration.weights_sha256:
        calibration = replace(calibration, least_squares=previous.least_squares)  # kept
    calibration.save(model_dir)
    joints = tuple(data.manifest["body"]["joints"])
    summary = {"noise_levels_deg": list(levels), "checked_noise_deg": list(checked),
               "temperature": calibration.temperature,
               "validation_trials": calibration.intervals.trials,
               "least_squares_fits": fits}
    result = CalibrationReport(str(model_dir), str(dataset_dir), joints, summary, cnn,
                               least_squares)
    result.write(out)
    return result
