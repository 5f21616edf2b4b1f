"""How good a trained network is, one module for both architectures.

**The paper's CNN** (:func:`evaluate`, :class:`EvaluationReport`): its tables and
figures, and more.

On each split (training, validation, test) of a data set, in the training set's
standardised target units (docs/model.md §5, §7):

- total RMSE (all 5 targets of a module, the class included) and fit RMSE (the 4
  continuous ones), each in two readings, because the paper's is ambiguous:
  *per element*, the RMS over every target value (predicting the training mean gives
  about 1.0); *per sample*, the RMS over samples of each sample's error norm (predicting
  the mean gives about √5 ≈ 2.24 and 2.0 for a module; √(5N) and √(4N) for a monolithic
  sample). The paper's figures (modular test: 1.4846 and 1.4486) are on the per-sample
  scale: per element they would be worse than predicting the mean;
- class accuracy, overall and per module;
- a "predict the training mean" row for scale.

On the test split: each normalised parameter's mean absolute error and its spread (the
paper's Fig. 5); and, on ``resimulate`` test trials, the identification error by
re-simulation with the predicted parameters (docs/model.md §7): E_id = ‖α_BS − α̃_BS‖₂ / N in
degrees and E_rel = ‖α_BS − α̃_BS‖₂ / ‖α_BS‖₂, against the parameter MSE with their
correlation (the paper's Fig. 6). A re-simulation that falls is counted and its E_rel
taken as infinite.

**The universal network** (:func:`score_samples`, :class:`GroupScore`): how well it does
on held-out module samples: classes, parameter errors and interval coverage, overall and
per group.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr

from posture_id.bodies.body import load_body
from posture_id.dec.parameters import TARGET_FIELDS, default_parameters, denormalise_arrays
from posture_id.fileio import Result, atomic_write_text, json_text
from posture_id.learning.calibration import (
    UniversalCalibration,
    regime_of,
    trend_terms,
)
from posture_id.learning.checkpoint import LoadedModel, load_model
from posture_id.learning.config import LearningError, NetworkConfig
from posture_id.learning.data.store import Dataset
from posture_id.learning.prediction import predict_images
from posture_id.learning.samples import SplitSamples
from posture_id.learning.universal_model import UniversalModel
from posture_id.learning.universal_samples import Samples
from posture_id.plotting import plot_identification_error, plot_parameter_errors, plot_score_grid
from posture_id.progress import Progress, report
from posture_id.provenance import provenance
from posture_id.simulation.batch import simulate_batch
from posture_id.simulation.metrics import sway_errors
from posture_id.simulation.options import SimulationOptions
from posture_id.uncertainty.coverage import confidence_calibration_error

__all__ = ["SplitMetrics", "EvaluationReport", "evaluate", "split_metrics", "GroupScore",
           "score_samples", "relative_errors", "plot_scores"]

SPLITS = ("train", "validation", "test")
NAMES = (*TARGET_FIELDS, "class")


@dataclass(frozen=True)
class SplitMetrics:
    """Metrics of one split (see the module doc). Per-module arrays are (N,)."""

    samples: int
    total_rmse_per_element: float
    fit_rmse_per_element: float
    total_rmse_per_sample: float
    fit_rmse_per_sample: float
    class_accuracy: float
    class_accuracy_per_module: tuple[float, ...]

    def to_dict(self) -> dict:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.__dict__.items()}


def split_metrics(error: np.ndarray, correct: np.ndarray) -> SplitMetrics:
    """Metrics from standardised errors (B, M, 5) of B samples of M modules each, and
    class hits per trial and module (trials, N) for the per-module accuracy."""
    b = len(error)
    flat = error.reshape(b, -1, 5)
    total_sq = (flat**2).sum(axis=(1, 2))
    fit_sq = (flat[..., :4] ** 2).sum(axis=(1, 2))
    return SplitMetrics(
        samples=b,
        total_rmse_per_element=float(np.sqrt(np.mean(flat**2))),
        fit_rmse_per_element=float(np.sqrt(np.mean(flat[..., :4] ** 2))),
        total_rmse_per_sample=float(np.sqrt(np.mean(total_sq))),
        fit_rmse_per_sample=float(np.sqrt(np.mean(fit_sq))),
        class_accuracy=float(np.mean(correct)),
        class_accuracy_per_module=tuple(float(a) for a in np.mean(correct, axis=0)),
    )


@dataclass(frozen=True)
class EvaluationReport(Result):
    """The evaluation of one model on one data set.

    Attributes:
        splits: split → :class:`SplitMetrics`; ``mean_predictor``: the same for predicting
            the training mean (and the majority class) on the test split.
        parameter_error_mean, parameter_error_std: (N, 5) |error| of the normalised targets
            on the test split (the class column: the error rate).
        joints: module names. identification: E_id / E_rel statistics (or empty).
    """

    model_dir: str
    dataset_dir: str
    layout: str
    joints: tuple[str, ...]
    splits: dict
    mean_predictor: SplitMetrics
    parameter_error_mean: np.ndarray
    parameter_error_std: np.ndarray
    identification: dict
    provenance: dict = field(default_factory=dict, repr=False)

    def to_dict(self) -> dict:
        return {
            "model_dir": self.model_dir, "dataset_dir": self.dataset_dir,
            "layout": self.layout, "joints": list(self.joints),
            "splits": {k: v.to_dict() for k, v in self.splits.items()},
            "mean_predictor_test": self.mean_predictor.to_dict(),
            "parameter_error_test": {
                j: {n: {"mean": float(m), "std": float(s)}
                    for n, m, s in zip(NAMES, mrow, srow, strict=True)}
                for j, mrow, srow in zip(self.joints, self.parameter_error_mean,
                                         self.parameter_error_std, strict=True)},
            "identification": self.identification,
            "provenance": self.provenance,
        }

    def summary(self) -> str:
        """The paper's Table 2 layout (both RMSE readings), then E_id / E_rel."""
        lines = [
            f"{self.layout} model {self.model_dir} on {self.dataset_dir}",
            f"{'set':<16}{'samples':>8}  {'total RMSE':>21}  {'fit RMSE':>21}  "
            f"{'accuracy':>9}",
            f"{'':<16}{'':>8}  {'per sample':>10} {'per elem.':>10}  "
            f"{'per sample':>10} {'per elem.':>10}",
        ]
        rows = [*((k, self.splits[k]) for k in SPLITS), ("mean (test)", self.mean_predictor)]
        for name, m in rows:
            lines.append(
                f"{name:<16}{m.samples:>8}  {m.total_rmse_per_sample:>10.4f} "
                f"{m.total_rmse_per_element:>10.4f}  {m.fit_rmse_per_sample:>10.4f} "
                f"{m.fit_rmse_per_element:>10.4f}  {100 * m.class_accuracy:>8.2f}%")
        test = self.splits["test"]
        lines.append("class accuracy per module (test): " + ", ".join(
            f"{j} {100 * a:.2f}%" for j, a in zip(self.joints, test.class_accuracy_per_module,
                                                  strict=True)))
        lines.append("mean |error| of normalised parameters (test):")
        for j, row in zip(self.joints, self.parameter_error_mean, strict=True):
            lines.append(f"  {j:<8}" + "  ".join(
                f"{n} {v:.3f}" for n, v in zip(TARGET_FIELDS, row[:4], strict=True)))
        ident = self.identification
        if ident:
            lines.append(
                f"re-simulated {ident['trials']} test trials ({ident['fell']} fell): E_id "
                f"median {ident['e_id_deg_median']:.2e}°, mean {ident['e_id_deg_mean']:.2e}°; "
                f"E_rel median {100 * ident['e_rel_median']:.2f} %, 90th percentile "
                f"{100 * ident['e_rel_p90']:.2f} %; correlation with parameter MSE "
                f"{ident['correlation_e_rel_vs_parameter_mse']:.3f} (Spearman "
                f"{ident['spearman_e_rel_vs_parameter_mse']:.3f})")
        return "\n".join(lines)

    def to_markdown(self) -> str:
        """The tables as Markdown (what ``posture-id network cnn evaluate`` writes as report.md)."""
        out = [f"# Evaluation: {self.layout} model", "",
               f"Model `{self.model_dir}`, data set `{self.dataset_dir}`.", "",
               "| set | samples | total RMSE (per sample) | fit RMSE (per sample) | "
               "total RMSE (per element) | fit RMSE (per element) | class accuracy |",
               "|---|---|---|---|---|---|---|"]
        rows = [*((k, self.splits[k]) for k in SPLITS),
                ("predict the training mean (test)", self.mean_predictor)]
        for name, m in rows:
            out.append(f"| {name} | {m.samples} | {m.total_rmse_per_sample:.4f} | "
                       f"{m.fit_rmse_per_sample:.4f} | {m.total_rmse_per_element:.4f} | "
                       f"{m.fit_rmse_per_element:.4f} | {100 * m.class_accuracy:.2f} % |")
        out += ["", "Class accuracy per module (test): " + ", ".join(
            f"{j} {100 * a:.2f} %" for j, a in zip(
                self.joints, self.splits["test"].class_accuracy_per_module, strict=True)),
            "", "Mean absolute error ± standard deviation of the normalised parameters "
            "(test; class: error rate):", "",
            "| module | " + " | ".join(NAMES) + " |", "|---" * (len(NAMES) + 1) + "|"]
        for j, mrow, srow in zip(self.joints, self.parameter_error_mean,
                                 self.parameter_error_std, strict=True):
            out.append(f"| {j} | " + " | ".join(f"{m:.3f} ± {s:.3f}" for m, s in
                                                zip(mrow, srow, strict=True)) + " |")
        if self.identification:
            i = self.identification
            out += ["", f"Re-simulation of {i['trials']} test trials with the predicted "
                        f"parameters ({i['fell']} fell): E_id median {i['e_id_deg_median']:.2e}°"
                        f" (mean {i['e_id_deg_mean']:.2e}°), E_rel median "
                        f"{100 * i['e_rel_median']:.2f} % (90th percentile "
                        f"{100 * i['e_rel_p90']:.2f} %); Pearson correlation of E_rel with "
                        f"the parameter MSE {i['correlation_e_rel_vs_parameter_mse']:.3f}, "
                        f"Spearman {i['spearman_e_rel_vs_parameter_mse']:.3f}."]
        return "\n".join(out) + "\n"

    def plot(self, path=None, ax=None):
        """|error| of every normalised parameter on the test split (Fig. 5)."""
        names = [f"{j} {n}" for j in self.joints for n in TARGET_FIELDS]
        return plot_parameter_errors(
            names, self.parameter_error_mean[:, :4].ravel(),
            self.parameter_error_std[:, :4].ravel(), path=path, ax=ax,
            title=f"{self.layout}: |error| of normalised parameters (test)")

    def plot_identification(self, path=None, ax=None):
        """E_rel of the re-simulated test trials against their parameter MSE (Fig. 6);
        None without re-simulations."""
        ident = self.identification
        if not ident:
            return None
        per_trial = ident["per_trial"]
        kept = [i for i, e in enumerate(per_trial["e_rel"]) if e is not None]
        return plot_identification_error(
            [per_trial["parameter_mse"][i] for i in kept],
            [per_trial["e_rel"][i] for i in kept],
            path=path, ax=ax, ylabel="E_rel = ‖α_BS − α̃_BS‖ / ‖α_BS‖",
            title=f"re-simulated test trials: correlation "
                  f"{ident['correlation_e_rel_vs_parameter_mse']:.3f}")

    def write(self, folder: str | Path) -> list[Path]:
        """report.json, report.md and the plots, into ``folder``."""
        folder = Path(folder)
        json_path = atomic_write_text(folder / "report.json",
                                      json_text(self.to_dict()))
        md_path = atomic_write_text(folder / "report.md", self.to_markdown())
        paths = [json_path, md_path, folder / "parameter_errors.png"]
        self.plot(paths[-1])
        if self.identification:
            paths.append(folder / "identification_error.png")
            self.plot_identification(paths[-1])
        return paths


def _split_predictions(model: LoadedModel, samples: SplitSamples):
    """(standardised errors (B, M, 5), predicted (B, M, 5), true normalised (B, M, 5))."""
    images, targets_std = samples.arrays()
    m = model.config.modules
    pred = predict_images(model, images, standardised_input=True)
    truth_std = targets_std.reshape(len(targets_std), m, 5).astype(np.float64)
    truth = model.standardiser.raw_targets(targets_std).reshape(len(targets_std), m, 5)
    truth[..., 4] = np.where(truth[..., 4] >= 0, 1.0, -1.0)  # exact ±1 after float32 storage
    return pred.standardised - truth_std, pred.targets, truth


def evaluate(model_dir: str | Path, dataset_dir: str | Path, resimulate: int = 200,
             progress: Progress | None = None) -> EvaluationReport:
    """Evaluate a model on a data set (see the module doc)."""
    model = load_model(model_dir)
    data = Dataset.open(dataset_dir)
    n = data.n_segments
    layout = model.config.layout
    expected = NetworkConfig.for_body(layout, n)
    if (model.config.modules, model.config.in_channels) != (expected.modules,
                                                            expected.in_channels):
        raise LearningError(f"{model_dir}: a {layout.value} model for "
                            f"{model.config.modules} modules cannot read the {n}-segment "
                            f"data set {dataset_dir}")
    trained_on, scored_on = model.sidecar.get("body", {}), data.manifest["body"]
    if trained_on.get("sha256") not in (None, scored_on.get("sha256")):
        raise LearningError(
            f"{dataset_dir}: a data set of the body {scored_on.get('name')!r}, and the model "
            f"{model_dir} was trained on {trained_on.get('name')!r}: a per-body model is "
            "scored on its own body's data (the universal model reads any body: "
            "`posture-id network universal table`)")
    joints = tuple(data.manifest["body"]["joints"])
    splits, test_detail = {}, None
    for name in SPLITS:
        report(progress, 0, None, "message", f"predicting the {name} split")
        samples = SplitSamples(data, name, layout, model.standardiser)
        error, predicted, truth = _split_predictions(model, samples)
        correct = predicted[..., 4] == truth[..., 4]
        splits[name] = split_metrics(error, correct.reshape(-1, n))
        if name == "test":
            test_detail = (samples, error, predicted, truth)
    samples, error, predicted, truth = test_detail
    # the mean predictor: standardised 0 everywhere, the majority class of the training set
    std = model.standardiser
    majority = 1.0 if std.target_mean.reshape(-1, 5)[:, 4].mean() >= 0 else -1.0
    mean_error = -(std.targets(truth.reshape(len(truth), -1)).reshape(truth.shape))
    mean_error = mean_error.astype(np.float64)
    mean_class_std = (majority - std.target_mean.reshape(-1, 5)[:, 4]) / \
        std.target_std.reshape(-1, 5)[:, 4]
    mean_error[..., 4] += mean_class_std
    mean_predictor = split_metrics(mean_error, (truth[..., 4] == majority).reshape(-1, n))
    # per-parameter |error| by module (trials × N × 5), class column: error rate
    by_trial_pred = predicted.reshape(-1, n, 5)
    by_trial_true = truth.reshape(-1, n, 5)
    abs_err = np.abs(by_trial_pred - by_trial_true)
    abs_err[..., 4] = (by_trial_pred[..., 4] != by_trial_true[..., 4]).astype(float)
    identification = (_identification(model, data, samples, by_trial_pred, error, resimulate,
                                      progress) if resimulate > 0 else {})
    return EvaluationReport(
        model_dir=str(model_dir), dataset_dir=str(dataset_dir), layout=layout.value,
        joints=joints, splits=splits, mean_predictor=mean_predictor,
        parameter_error_mean=abs_err.mean(axis=0), parameter_error_std=abs_err.std(axis=0),
        identification=identification,
        provenance=provenance(None, None, model=model.sidecar.get("dataset", {}),
                              resimulated=resimulate),
    )


def _identification(model, data: Dataset, samples: SplitSamples, predicted: np.ndarray,
                    error: np.ndarray, count: int, progress) -> dict:
    """E_id and E_rel of the first ``count`` test trials, re-simulated (docs/model.md §7)."""
    manifest = data.manifest
    body = load_body(manifest["body"]["urdf"])
    if body.sha256 != manifest["body"]["sha256"]:
        raise LearningError(f"{manifest['body']['urdf']}: the body file changed since the data "
                            "set was made; E_id needs the same body")
    stimulus = data.stimulus
    options = SimulationOptions(**manifest["options"])
    truth = samples.trial_parameters()
    count = min(count, truth.n_trials)
    report(progress, 0, None, "message", f"re-simulating {count} test trials")
    pick = np.arange(count)
    true_params = type(truth)(**{f: getattr(truth, f)[pick] for f in truth.FIELDS})
    predicted_params = denormalise_arrays(predicted[pick], default_parameters(body))
    # the predicted parameters keep the truth's passive terms (the data set's defaults)
    both = simulate_batch(body, type(truth)(**{
        f: np.concatenate([getattr(true_params, f), getattr(predicted_params, f)])
        for f in truth.FIELDS}), stimulus, options)
    alpha_true = both.alpha[:count, :, 0]
    alpha_pred = both.alpha[count:, :, 0]
    fell = ~both.stable[count:]
    e_id, e_rel = sway_errors(alpha_true, alpha_pred, fell)
    n = predicted.shape[1]
    per_trial_mse = np.mean(error.reshape(-1, n, 5)[pick] ** 2, axis=(1, 2))
    finite = np.isfinite(e_rel)
    pearson = (float(np.corrcoef(per_trial_mse[finite], e_rel[finite])[0, 1])
               if finite.sum() > 2 else math.nan)
    spearman = float(spearmanr(per_trial_mse, e_rel).statistic) if count > 2 else math.nan
    return {
        "trials": int(count), "fell": int(fell.sum()),
        "e_id_deg_median": float(np.median(e_id)),
        "e_id_deg_mean": float(np.mean(e_id[finite])) if finite.any() else math.inf,
        "e_rel_median": float(np.median(e_rel)),
        "e_rel_p90": float(np.percentile(e_rel, 90, method="higher")),
        "correlation_e_rel_vs_parameter_mse": pearson,
        "spearman_e_rel_vs_parameter_mse": spearman,
        "parameter_mse": "mean over the trial's 5N standardised squared errors",
        "per_trial": {"e_id_deg": [float(x) if np.isfinite(x) else None for x in e_id],
                      "e_rel": [float(x) if np.isfinite(x) else None for x in e_rel],
                      "parameter_mse": per_trial_mse.tolist()},
    }




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

    @property
    def coverage_text(self) -> str:
        """The coverage of Kp, Ki, Kd and the delay, %: '90 / 91 / 89 / 90'."""
        return " / ".join(f"{self.coverage_pct[k]:.0f}" for k in TARGET_FIELDS)

    def grid_values(self) -> tuple[float, float, float]:
        """What :func:`plot_scores` draws of the group: classes right, %; the median |Kp
        error|, %; the mean of the four parameters' coverage, %."""
        return (self.classes_pct, self.median_error_pct["kp"],
                float(np.mean(list(self.coverage_pct.values()))))

    def to_dict(self) -> dict:
        return {"modules": self.modules, "trials": self.trials, "by_module": list(self.by_module),
                "classes_pct": self.classes_pct, "trials_all_right_pct": self.trials_all_right_pct,
                "class_ece_pct": self.class_ece_pct,
                "median_error_pct": self.median_error_pct, "coverage_pct": self.coverage_pct,
                "level": self.level}


def plot_scores(rows: list[str], columns: list[str], values: np.ndarray, level: float,
                path=None, ax=None):
    """Groups' :meth:`GroupScore.grid_values`, ``values`` (3, rows, columns), as three
    panels of a grid, the coverage's at the intervals' ``level``."""
    return plot_score_grid(rows, columns, {
        "classes right, %": (values[0], (80, 100), ".0f"),
        "median |Kp error|, %": (values[1], (0, 20), ".1f"),
        f"{100 * level:.0f} % interval coverage (mean of 4), %": (values[2], (75, 100), ".0f")},
        path, ax)


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
                              for i, n in enumerate(TARGET_FIELDS)},
            coverage_pct={n: float(100 * np.mean(inside[sel, i]))
                          for i, n in enumerate(TARGET_FIELDS)},
            level=level, class_ece_pct=100 * confidence_calibration_error(
                probability[sel], samples.targets[sel, 4] > 0),
            by_module=tuple({n: float(100 * np.median(errors[sel & (samples.module == m), i]))
                             for i, n in enumerate(TARGET_FIELDS)}
                            for m in np.unique(samples.module[sel])))
    return out
