"""Calibrate a universal model on its set's calibration split and check it on the test
split, per regime: the numbers docs/universal.md quotes; and its typicality reference
from the sets it was trained on."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from posture_id.fileio import Result, atomic_write_text, json_text
from posture_id.learning.calibration import UniversalCalibration, calibrate
from posture_id.learning.data.drawn import open_sets
from posture_id.learning.evaluation import GroupScore, plot_scores, score_samples
from posture_id.learning.typicality import (
    ATYPICAL_P,
    TypicalityReport,
    fit_reference,
    recording_scores,
)
from posture_id.learning.universal_model import UniversalModel
from posture_id.learning.universal_samples import Samples, make_samples, split_shards
from posture_id.learning.universal_training import VALIDATION_SEED

__all__ = ["CALIBRATION_SEED", "TEST_SEED", "CheckReport", "calibrate_model", "true_regimes",
           "reference_from_sets"]

CALIBRATION_SEED, TEST_SEED = 0x43414C, 0x544553


def true_regimes(samples: Samples) -> np.ndarray:
    """Group labels by what was simulated: 'N-seg, clean|people-like, sensor a–b°'
    (people-like: motor noise leaving under 60 % of the body COM sway locked)."""
    kind = np.where(samples.locked_share < 0.6, "people-like",
                    np.where(samples.locked_share < 0.995, "part-locked", "clean"))
    bins = np.digitize(samples.sensor_noise_deg, [0.02, 0.05])
    noise = np.array(["sensor <0.02°", "sensor 0.02–0.05°", "sensor >0.05°"])[bins]
    seg = np.char.add(samples.segments.astype(str), "-seg")
    return np.char.add(np.char.add(np.char.add(np.char.add(seg, ", "), kind), ", "), noise)


def _left_out(model: UniversalModel) -> tuple[str, ...]:
    """The noise families ``model`` was trained without: its calibration, check and
    typicality reference leave them out too (they are what it is to be judged on)."""
    return tuple(model.sidecar.get("training", {}).get("exclude_families", ()))


def _held_out(model: UniversalModel, data: list, split: str, seed: int) -> Samples:
    """The module samples of ``split`` of the sets ``data``, their noise drawn from
    ``seed`` as in training, without the noise families of :func:`_left_out`."""
    return make_samples(split_shards(data, split, model.scope, _left_out(model)), model.scope,
                        np.random.default_rng(seed))


@dataclass(frozen=True)
class CheckReport(Result):
    """Test-split scores overall, per segment count and per simulated regime."""

    overall: GroupScore
    by_segments: dict
    by_regime: dict
    calibration: dict

    def to_dict(self) -> dict:
        return {"overall": self.overall.to_dict(),
                "by_segments": {k: v.to_dict() for k, v in self.by_segments.items()},
                "by_regime": {k: v.to_dict() for k, v in self.by_regime.items()},
                "calibration_counts": self.calibration}

    def markdown(self) -> str:
        head = ("| group | trials | classes % | all classes right % | Kp err % | Ki err % | "
                "Kd err % | delay err % | 90 % coverage Kp / Ki / Kd / delay | class ECE % |")
        lines = ["# The universal model on its held-out test shards", "",
                 "Made by `posture-id network universal calibrate MODEL_DIR DATA_DIR` "
                 "(posture_id.studies.universal_check): calibrated on the calibration shards, "
                 "checked on the test shards (bodies and stimuli no training trial had). "
                 "People-like: under 60 % of the body COM sway locked; part-locked: 60–99.5 "
                 "%; clean: no motor noise. Errors: median |identified / true − 1|.", "",
                 head, "|" + "---|" * 10]
        rows = [("all", self.overall), *self.by_segments.items(), *self.by_regime.items()]
        for name, s in rows:
            e = s.median_error_pct
            lines.append(f"| {name} | {s.trials} | {s.classes_pct:.1f} | "
                         f"{s.trials_all_right_pct:.1f} | {e['kp']:.1f} | {e['ki']:.1f} | "
                         f"{e['kd']:.1f} | {e['delay_s']:.1f} | {s.coverage_text} | "
                         f"{s.class_ece_pct:.1f} |")
        return "\n".join(lines)

    def summary(self) -> str:
        return self.markdown()

    def plot(self, path=None, ax=None):
        """Classes right, median Kp error and mean coverage per group (one row each)."""
        groups = {"all": self.overall, **self.by_segments, **self.by_regime}
        values = np.array([s.grid_values() for s in groups.values()]).T[:, :, None]
        return plot_scores(list(groups), ["test split"], values, self.overall.level, path, ax)


def calibrate_model(model_dir: str | Path, data_path: str | Path | Sequence[str | Path],
                    level: float = 0.9) -> CheckReport:
    """Calibrate the model at ``model_dir`` (written there as calibration.json) on the
    calibration split of the set (or sets) it was trained on (its difficulty trend on the
    validation split, noise drawn as in training), and check it on the test split; the
    report is written there as check.json and check.md. The noise families the model was
    trained without are left out of all three (they are what it is to be judged on)."""
    model = UniversalModel.load(model_dir)
    data = open_sets(data_path)
    cal = _held_out(model, data, "calibration", CALIBRATION_SEED)
    validation = _held_out(model, data, "validation", VALIDATION_SEED)
    calibration: UniversalCalibration = calibrate(model, cal, validation)
    calibration.save(model_dir)
    test = _held_out(model, data, "test", TEST_SEED)
    overall = score_samples(model, test, calibration, level)["all"]
    by_segments = score_samples(model, test, calibration, level,
                                np.char.add(test.segments.astype(str), "-seg"))
    by_regime = score_samples(model, test, calibration, level, true_regimes(test))
    report = CheckReport(overall, by_segments, by_regime, calibration.counts)
    folder = Path(model_dir)
    atomic_write_text(folder / "check.json", json_text(report.to_dict()))
    atomic_write_text(folder / "check.md", report.markdown() + "\n")
    return report


def reference_from_sets(model_dir: str | Path, data_path) -> TypicalityReport:
    """The typicality reference of the model at ``model_dir`` from the sets it was trained
    on (or sets drawn from the same distribution): fitted on their calibration split,
    scored on their validation split, its false alarms counted on their test split, each
    with noise drawn as in calibration (``universal check``'s seeds); the noise families
    the model was trained without are left out. Written into ``model_dir``
    (:data:`TYPICALITY_FILE`, ``typicality.json``, ``typicality.md``)."""
    model = UniversalModel.load(model_dir)
    data = open_sets(data_path)
    fit = _held_out(model, data, "calibration", CALIBRATION_SEED)
    scored = _held_out(model, data, "validation", VALIDATION_SEED)
    reference = fit_reference(
        model.standardised(fit.inputs), model.standardised(scored.inputs), scored.trial,
        model.sidecar.get("weights_sha256", ""),
        {"sets": [str(p) for p in ([data_path] if isinstance(data_path, (str, Path))
                                   else data_path)],
         "fit_modules": int(len(fit.inputs)), "left_out_families": list(_left_out(model))})
    test = _held_out(model, data, "test", TEST_SEED)
    scores = recording_scores(reference.d2(model.standardised(test.inputs)), test.trial)
    atypical = np.array([reference.tail(s) < ATYPICAL_P for s in scores])
    _, first = np.unique(test.trial, return_index=True)
    regimes = true_regimes(test)[np.sort(first)]
    false_alarms = {"all": (int(atypical.sum()), len(atypical))}
    for regime in sorted(set(regimes)):
        inside = regimes == regime
        false_alarms[str(regime)] = (int(atypical[inside].sum()), int(inside.sum()))
    report = TypicalityReport(reference, len(scores), false_alarms)
    folder = Path(model_dir)
    reference.save(folder)
    atomic_write_text(folder / "typicality.json", json_text(report.to_dict()))
    atomic_write_text(folder / "typicality.md", report.markdown() + "\n")
    return report
