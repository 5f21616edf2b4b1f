"""``posture-id calibration`` end to end on a tiny data set and network, and what the
CNN identifier does with (and without) a calibration."""

from __future__ import annotations

import json
import shutil
from dataclasses import replace

import numpy as np
import pytest

from posture_id.cli import main
from posture_id.learning.calibration import CALIBRATION, CnnCalibration
from posture_id.learning.config import Layout, LearningError, NetworkConfig, TrainingConfig
from posture_id.learning.data import DatasetConfig, generate_dataset
from posture_id.learning.identifier import CnnIdentifier
from posture_id.learning.training import train
from posture_id.simulation.batch import simulate
from posture_id.studies.calibration import ClassCheck, CoverageAtLevel
from posture_id.trials import prepare_trial
from posture_id.uncertainty.identifiability import Determination


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory, tip):
    root = tmp_path_factory.mktemp("calibration")
    generate_dataset(DatasetConfig(trials=64, body=str(tip.urdf_path), shard_size=16, seed=5,
                                   sensor_noise_deg=0.05), root / "set", workers=2)
    network = NetworkConfig.for_body(Layout.MODULAR, 3, widths=(8, 8, 12, 12, 16),
                                     head=(16,))
    train(root / "set", root / "model", network,
          TrainingConfig(threads=1, batch_size=16, epochs=1))
    status = main(["network", "cnn", "calibrate", str(root / "model"), str(root / "set"),
                   "--out", str(root / "report"), "--install"])
    assert status == 0
    return root


@pytest.mark.slow("trains and calibrates a network (module fixture)")
def test_calibration_writes_the_calibration_and_its_report(calibrated):
    model, report = calibrated / "model", calibrated / "report"
    for name in ("calibration_report.md", "calibration_report.json", "coverage.png",
                 "reliability.png", "identifiability.png"):
        assert (report / name).stat().st_size > 0, name
    data = json.loads((report / "calibration_report.json").read_text())
    assert data["calibration"]["noise_levels_deg"] == [0.0, 0.0125, 0.025, 0.0375, 0.05]
    assert sorted(data["cnn"]) == ["0", "0.05"]
    block = data["cnn"]["0.05"]
    assert np.array(block["intervals"]["0.9"]["coverage"]).shape == (3, 4)
    assert set(block["classes"]) == {"accuracy", "raw", "calibrated"}
    assert data["least_squares"] == {}
    saved = CnnCalibration.load(model)  # --install put it beside the model
    assert (model / CALIBRATION).read_text() == (report / CALIBRATION).read_text()
    assert saved.intervals.scales.shape[:2] == (5, 50)
    assert len(saved.temperature) == 3 and all(t > 0 for t in saved.temperature)
    assert "Least squares was not run" in (report / "calibration_report.md").read_text()


@pytest.mark.slow("trains and calibrates a network (module fixture)")
def test_the_identifier_gives_intervals_and_says_when_noise_is_beyond_them(calibrated, tip):
    identifier = CnnIdentifier.load(calibrated / "model", tip)
    recording = simulate(tip, _truth(tip)).to_recording()
    quiet = identifier.identify(
        prepare_trial(replace(recording.with_sensor_noise(0.01, 1), name="quiet")), level=0.8)
    iv = quiet.intervals
    assert iv is not None and iv.level == 0.8 and iv.lower.shape == (3, 4)
    assert np.all(iv.lower <= quiet.normalised[:, :4]) and np.all(
        quiet.normalised[:, :4] <= iv.upper)
    assert iv.noise_deg == pytest.approx(0.01, rel=0.1)
    assert not any("calibrated for" in n for n in quiet.notices)
    assert "intervals" in quiet.to_dict() and "80 % intervals" in quiet.summary()
    noisy = identifier.identify(
        prepare_trial(replace(recording.with_sensor_noise(0.3, 2), name="noisy")))
    assert any("noisy: its sensor noise (about 0.3" in n and "too narrow" in n
               for n in noisy.notices)


@pytest.mark.slow("trains and calibrates a network (module fixture)")
def test_a_calibration_of_other_weights_is_not_used(calibrated, tip, tmp_path):
    model = tmp_path / "model"
    shutil.copytree(calibrated / "model", model)
    data = json.loads((model / CALIBRATION).read_text())
    data["weights_sha256"] = "0" * 64
    (model / CALIBRATION).write_text(json.dumps(data))
    identifier = CnnIdentifier.load(model, tip)
    result = identifier.identify(prepare_trial(simulate(tip, _truth(tip)).to_recording()))
    assert result.intervals is None
    assert any("made for other weights" in n for n in result.notices)
    (model / CALIBRATION).write_text("{not json")
    with pytest.raises(LearningError, match="calibration.json: unreadable calibration"):
        CnnIdentifier.load(model, tip)
    (model / CALIBRATION).unlink()
    bare = CnnIdentifier.load(model, tip)
    assert bare.calibration is None and any("no calibration" in n for n in bare.notices)


def _truth(body):
    from posture_id.dec.parameters import default_parameters

    return default_parameters(body)


@pytest.mark.slow("least-squares fits of a calibration set, 3 segments")
def test_least_squares_runs_resume_from_their_journal(calibrated, tmp_path):
    from posture_id.bodies.body import load_body
    from posture_id.errors import PostureIdError
    from posture_id.learning.bundled import bundled_model_dir
    from posture_id.studies.fit_runs import run_fits

    model, _ = bundled_model_dir(load_body())
    journal = tmp_path / "fits.journal.jsonl"
    first = run_fits(model, calibrated / "set", "test", 1, (0.05,), journal, workers=1)
    assert len(first) == 1
    row = first[0]
    assert np.array(row["estimate"]).shape == (3, 5) and row["converged"]
    assert np.all(np.array(row["standard_errors"]) > 0)
    assert row["noise_estimate_deg"] == pytest.approx(0.05, rel=0.1)
    again = run_fits(model, calibrated / "set", "test", 2, (0.05,), journal, workers=1)
    assert len(again) == 2 and again[0] == row  # the first read back, one new fit
    assert len(journal.read_text().splitlines()) == 3
    with pytest.raises(PostureIdError, match="journal of another set-up"):
        run_fits(calibrated / "model", calibrated / "set", "test", 2, (0.05,), journal)


@pytest.mark.slow("trains and calibrates a network (module fixture)")
def test_an_unreadable_calibration_is_made_anew(calibrated, tmp_path):
    model = tmp_path / "model"
    shutil.copytree(calibrated / "model", model)
    (model / CALIBRATION).write_text("{not json")
    assert main(["network", "cnn", "calibrate", str(model), str(calibrated / "set"), "--out",
                 str(tmp_path / "report"), "--sensor-noise-deg", "0.05"]) == 0
    assert (model / CALIBRATION).read_text() == "{not json"  # told to write elsewhere only
    assert CnnCalibration.load(tmp_path / "report").weights_sha256 == CnnCalibration.load(
        calibrated / "model").weights_sha256


def test_coverage_of_known_intervals():
    """Truths uniform on [−0.5, 0.5] around an estimate of 0: ±0.25 holds half of them,
    ±0.45 nine in ten; the width is clipped at p̃ = −1 (a gain cannot go below zero)."""
    rng = np.random.default_rng(3)
    truth = rng.uniform(-0.5, 0.5, size=(20_000, 3, 4))
    estimate = np.zeros_like(truth)
    for half, share in ((0.25, 0.5), (0.45, 0.9)):
        c = CoverageAtLevel.measure(truth, estimate, np.full((3, 4), half), 0.9)
        np.testing.assert_allclose(c.coverage, share, atol=0.012)
        low, high = c.coverage_95ci[..., 0], c.coverage_95ci[..., 1]
        assert np.all((low < c.coverage) & (c.coverage < high))
        np.testing.assert_allclose(c.median_width, 2 * half)
    clipped = CoverageAtLevel.measure(truth, estimate - 0.9, np.full((3, 4), 0.5), 0.9)
    np.testing.assert_allclose(clipped.median_width, 0.6)  # from −1 (not −1.4) to −0.4
    prior = CoverageAtLevel.measure(truth, estimate, np.full((3, 4), 10.0), 0.9)
    assert np.all(prior.determination == Determination.NOT) and np.all(prior.coverage == 1)


def test_class_calibration_of_known_probabilities():
    """Outcomes drawn with P = σ(logit): ECE near 0; the same logits doubled are
    over-confident and temperature 2 puts them right again."""
    rng = np.random.default_rng(4)
    logit = rng.normal(0, 2, size=(50_000, 2))
    truth = np.where(rng.uniform(size=logit.shape) < 1 / (1 + np.exp(-logit)), 1, -1)
    honest = ClassCheck.measure(logit, truth, None)
    assert honest.raw.ece < 0.01 and honest.calibrated is None
    assert honest.accuracy == pytest.approx(np.mean((logit > 0) == (truth > 0)))
    sharp = ClassCheck.measure(2 * logit, truth, (2.0, 2.0))
    assert sharp.raw.ece > 0.05 and sharp.calibrated.ece < 0.01
    assert sharp.best is sharp.calibrated and sharp.raw.count.sum() == logit.size
