"""The typicality score: the shrunk covariance against a known one, the tail probability's
calibration on draws from the reference's own distribution, the file, and the default
command doubting recordings unlike anything the universal network was trained on."""

from __future__ import annotations

import json

import numpy as np
import pytest

from posture_id.errors import PostureIdError
from posture_id.learning.typicality import (
    ATYPICAL_P,
    TYPICALITY_FILE,
    TypicalityReference,
    fit_reference,
    recording_scores,
    shrunk_covariance,
)


def test_shrinkage_beats_the_sample_covariance_when_samples_are_few():
    """Ledoit–Wolf: with as many samples as dimensions the shrunk estimate is nearer the
    true covariance than the sample covariance; with many samples it shrinks almost not."""
    rng = np.random.default_rng(0)
    d = 40
    a = rng.standard_normal((d, d))
    truth = a @ a.T / d + np.eye(d)
    root = np.linalg.cholesky(truth)
    few = rng.standard_normal((d, d)) @ root.T
    shrunk, delta = shrunk_covariance(few - few.mean(axis=0))
    sample = np.cov(few, rowvar=False, bias=True)
    assert 0.05 < delta < 1
    assert np.linalg.norm(shrunk - truth) < 0.8 * np.linalg.norm(sample - truth)
    many = rng.standard_normal((50_000, d)) @ root.T
    shrunk, delta = shrunk_covariance(many - many.mean(axis=0))
    assert delta < 0.01
    np.testing.assert_allclose(shrunk, truth, atol=0.05)


def test_a_recording_scores_its_largest_module():
    d2 = np.array([1.0, 5.0, 2.0, 7.0, 3.0])
    recording = np.array([4, 4, 9, 2, 9])
    np.testing.assert_array_equal(recording_scores(d2, recording), [5.0, 3.0, 7.0])


def _reference(rng, d=12, recordings=4000, modules=2):
    fit = rng.standard_normal((20_000, d))
    scored = rng.standard_normal((recordings * modules, d))
    which = np.repeat(np.arange(recordings), modules)
    return fit_reference(fit, scored, which, "sha", {"sets": ["drawn"]})


def test_the_tail_probability_is_calibrated_on_its_own_distribution():
    """New recordings from the reference's own distribution: p is uniform (its deciles
    within a few points), and about ATYPICAL_P of them are atypical; a module far off in
    one input is atypical."""
    rng = np.random.default_rng(1)
    reference = _reference(rng)
    p = np.array([reference.of(rng.standard_normal((2, 12))).p for _ in range(4000)])
    for q in (0.1, 0.5, 0.9):
        assert abs(np.mean(p <= q) - q) < 0.03
    assert np.mean(p < ATYPICAL_P) < 4 * ATYPICAL_P
    far = rng.standard_normal((2, 12))
    far[1, 3] = 9.0
    found = reference.of(far)
    assert found.atypical and found.p == pytest.approx(1 / 4001)
    assert "unlike any the network was trained on" in found.sentence()


def test_the_reference_file_round_trips_and_a_damaged_one_is_named(tmp_path):
    reference = _reference(np.random.default_rng(2), recordings=100)
    reference.save(tmp_path)
    again = TypicalityReference.load(tmp_path)
    assert again.weights_sha256 == "sha" and again.source == reference.source
    x = np.random.default_rng(3).standard_normal((3, 12))
    assert again.of(x).score == pytest.approx(reference.of(x).score, rel=1e-5)
    assert TypicalityReference.load(tmp_path / "none") is None
    (tmp_path / TYPICALITY_FILE).write_bytes(b"not safetensors")
    with pytest.raises(PostureIdError, match="not a readable typicality reference"):
        TypicalityReference.load(tmp_path)


@pytest.fixture(scope="module")
def subject(tip):
    from posture_id.dec.parameters import default_parameters
    from posture_id.simulation import prts
    from posture_id.simulation.subjects import people_like

    return people_like(tip, default_parameters(tip), prts(), 0.3, seed=1)


def test_the_bundled_reference_is_the_bundled_models(tip):
    from posture_id.learning.universal_identifier import UniversalIdentifier

    identifier = UniversalIdentifier.bundled(tip)
    assert identifier.typicality is not None
    assert identifier.typicality.weights_sha256 == identifier.model.sidecar["weights_sha256"]
    assert len(identifier.typicality.scores) >= 1000  # p can reach below ATYPICAL_P


def test_the_default_command_doubts_sway_unlike_any_trained_on(tip, subject, tmp_path):
    """A people-like recording as recorded is typical; the same angles ten times as large
    (a lab's file in tenths of a degree read as degrees) are unlike anything the network
    was trained on: the default command says so and doubts the answer for it."""
    from dataclasses import replace

    from posture_id.cli import main
    from posture_id.identify import identify

    as_recorded = identify(subject.recording, tip)
    assert not as_recorded.cnn.typicality.atypical
    assert not any("unlike any the network" in m for m in as_recorded.verdict.mistakes)
    tenfold = replace(subject.recording, theta=10 * subject.recording.theta)
    result = identify(tenfold, tip)
    assert result.cnn.typicality.atypical
    assert result.verdict.doubtful
    assert any("unlike any the network was trained on" in m for m in result.verdict.mistakes)
    path = tmp_path / "tenfold.csv"
    tenfold.to_csv(path)
    out = tmp_path / "tenfold.json"
    assert main(["identify", str(path), "--out", str(out)]) == 1
    data = json.loads(out.read_text())
    assert data["trust"]["level"] == "doubtful"
    assert data["cnn"]["typicality"]["atypical"] and data["cnn"]["typicality"]["p"] < ATYPICAL_P


def test_a_reference_made_for_other_weights_is_not_used(tip, tmp_path):
    import shutil

    from posture_id.learning.universal_identifier import BUNDLED_DIR, UniversalIdentifier

    folder = tmp_path / "model"
    shutil.copytree(BUNDLED_DIR, folder)
    bundled = TypicalityReference.load(folder)
    TypicalityReference(bundled.mean, bundled.whitening, bundled.scores, bundled.shrinkage,
                        "0" * 64, bundled.source).save(folder)
    identifier = UniversalIdentifier.load(folder, tip)
    assert identifier.typicality is None
    assert any("typicality reference was made for other weights" in n
               for n in identifier.notices)
