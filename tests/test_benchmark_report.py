"""The CNN-versus-optimiser benchmark machinery on a tiny run (the CNN only)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from posture_id.errors import PostureIdError
from posture_id.identify import Method
from posture_id.studies.benchmark import (
    FAR_E_REL,
    BenchmarkReport,
    MethodStatistics,
    run_benchmark,
)


def _row(e_rel, correct, error, inside, seconds):
    return {"index": 0, "noise_deg": 0.05, "method": "hybrid", "e_rel": e_rel,
            "classes_correct": correct, "abs_error": error, "inside_interval": inside,
            "interval_method": "m", "seconds": seconds, "identification_seconds": seconds / 2}


def test_statistics_of_known_rows():
    """Three recordings whose statistics are known by hand: far = a wrong class or E_rel
    above FAR_E_REL (a fallen one, E_rel ∞, included); the 90th percentile is the
    higher neighbour; coverage is per module and parameter."""
    ones, zeros = np.ones((2, 4)), np.zeros((2, 4))
    rows = [_row(0.01, [True, True], 1 * ones, ones.astype(bool), 1.0),
            _row(FAR_E_REL + 0.01, [True, True], 2 * ones, ones.astype(bool), 2.0),
            _row(math.inf, [True, False], 6 * ones, zeros.astype(bool), 6.0)]
    s = MethodStatistics.of_rows(0.05, "hybrid", rows)
    assert s.recordings == 3 and s.far_from_truth == 2
    assert s.class_accuracy == pytest.approx(5 / 6)
    assert s.e_rel_median == FAR_E_REL + 0.01 and s.e_rel_p90 == math.inf
    np.testing.assert_array_equal(s.mean_abs_error, 3 * ones)
    np.testing.assert_array_equal(s.median_abs_error, 2 * ones)
    np.testing.assert_allclose(s.interval_coverage, 2 / 3 * ones)
    assert (s.seconds_median, s.seconds_mean) == (2.0, 3.0)
    assert s.identification_seconds_median == 1.0
    data = s.to_dict()
    assert data["method"] == "hybrid" and data["e_rel_p90"] is None  # strict JSON: ∞ → null
    report = BenchmarkReport("tip", ("a", "b"), 3, (0.05,), tuple(rows), 1)
    text = report.to_markdown()
    assert "Ending far from the truth, all conditions: hybrid 2/3." in text
    assert "| hybrid | 83.3 % | 11.00 % | inf % | 2/3 | 1 | 2 | 3.000, 3.000" in text


@pytest.mark.slow("a benchmark of a few recordings")
def test_tiny_benchmark_writes_its_report(tip, tmp_path):
    report = run_benchmark(tip, trials=2, noise_levels=(0.0, 0.01), seed=3, workers=1,
                           methods=(Method.CNN,))
    assert len(report.rows) == 4
    stats = report.statistics()
    assert list(stats) == [(0.0, "cnn"), (0.01, "cnn")]
    clean = stats[(0.0, "cnn")]
    rows = [r for r in report.rows if r["noise_deg"] == 0.0]
    assert clean.recordings == 2
    assert clean.class_accuracy == np.mean([r["classes_correct"] for r in rows])
    # the CNN's own time excludes the checks and the re-simulation every method shares
    assert all(0 < r["identification_seconds"] < r["seconds"] for r in report.rows)
    assert clean.mean_abs_error.shape == (3, 4)
    paths = report.write(tmp_path)
    data = json.loads(paths[0].read_text())
    assert data["trials"] == 2 and len(data["rows"]) == 4
    text = paths[1].read_text()
    assert "## Sensor noise 0.01°" in text and "| cnn |" in text
    assert "Ending far from the truth, all conditions: cnn " in text
    assert paths[2].stat().st_size > 10_000
    # the bundled model is calibrated: every row says whether its intervals held the truth
    assert all(len(r["inside_interval"]) == 3 for r in report.rows)
    assert clean.interval_recordings == 2
    assert "## Do the 90 % intervals hold the truth?" in text
    assert "| 0° | cnn | conformal, universal network (regime 3 segments, clean, white noise, " \
        "held-out bodies and stimuli) | 2 |" in text


@pytest.mark.slow("a benchmark of a few recordings")
def test_an_interrupted_benchmark_goes_on_from_its_journal(tip, tmp_path):
    journal = tmp_path / "journal.jsonl"
    args = dict(trials=2, noise_levels=(0.0,), seed=3, workers=1, methods=(Method.CNN,))
    first = run_benchmark(tip, journal=journal, **args)
    lines = journal.read_text().splitlines()
    assert len(lines) == 3  # header + one row per recording
    # the run stopped while writing its last row: a torn line and one row missing
    journal.write_text("\n".join(lines[:2]) + "\n" + lines[2][:25])
    again = run_benchmark(tip, journal=journal, **args)
    rows = [json.loads(line) for line in journal.read_text().splitlines()[1:]
            if line.endswith("}")]
    assert [r["index"] for r in rows] == [0, 1]  # only the missing recording was redone
    for a, b in zip(first.rows, again.rows, strict=True):
        assert a["index"] == b["index"] and a["abs_error"] == b["abs_error"]
    with pytest.raises(PostureIdError, match="another set-up"):
        run_benchmark(tip, journal=journal, **{**args, "seed": 4})


def test_the_command_line_names_the_benchmark_s_methods():
    from posture_id.cli.benchmark import BENCHMARK_METHODS
    from posture_id.studies.benchmark import METHODS

    assert BENCHMARK_METHODS == METHODS


@pytest.mark.slow("a benchmark of a few recordings")
def test_people_like_sway_and_the_paper_s_cnn_are_benchmarked(tip, tmp_path):
    """The people-like condition's recordings are the clean ones' subjects with motor
    noise; the paper's CNN (the TIP's specialist) answers beside the universal network."""
    report = run_benchmark(tip, trials=2, noise_levels=(0.05,), seed=3, workers=1,
                           methods=(Method.CNN, "paper-cnn"), people_like=True)
    stats = report.statistics()
    assert list(stats) == [(0.05, "cnn"), (0.05, "paper-cnn"), ("people-like", "cnn"),
                           ("people-like", "paper-cnn")]
    assert all(s.recordings == 2 for s in stats.values())
    text = report.to_markdown()
    assert "## People-like sway (15–40 % of the body COM sway locked" in text
    assert "| paper-cnn |" in text
    clean = [r for r in report.rows if r["noise_deg"] == 0.05 and r["method"] == "cnn"]
    noisy = [r for r in report.rows if r["noise_deg"] == "people-like" and r["method"] == "cnn"]
    # the same subjects: the noisy answers are worse on average than the clean ones
    assert np.mean([r["e_rel"] for r in noisy]) > np.mean([r["e_rel"] for r in clean])
