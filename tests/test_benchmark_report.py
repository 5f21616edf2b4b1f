"""The CNN-versus-optimiser benchmark machinery on a tiny run (the CNN only)."""

from __future__ import annotations

import json

import pytest

from posture_id.errors import PostureIdError
from posture_id.identify import Method
from posture_id.identify.benchmark import run_benchmark


def test_tiny_benchmark_writes_its_report(tip, tmp_path):
    report = run_benchmark(tip, trials=2, noise_levels=(0.0, 0.01), seed=3, workers=1,
                           methods=(Method.CNN,))
    assert len(report.rows) == 4
    stats = report.statistics()
    assert set(stats) == {"0|cnn", "0.01|cnn"}
    clean = stats["0|cnn"]
    assert clean["recordings"] == 2 and 0 <= clean["class_accuracy"] <= 1
    assert clean["seconds_median"] > 0
    # the CNN's own time excludes the checks and the re-simulation every method shares
    assert all(0 < r["identification_seconds"] < r["seconds"] for r in report.rows)
    assert len(clean["mean_abs_error"]) == 3 and len(clean["mean_abs_error"][0]) == 4
    paths = report.write(tmp_path)
    data = json.loads(paths[0].read_text())
    assert data["trials"] == 2 and len(data["rows"]) == 4
    text = paths[1].read_text()
    assert "## Sensor noise 0.01°" in text and "| cnn |" in text
    assert "Ending far from the truth, all noise levels: cnn " in text
    assert paths[2].stat().st_size > 10_000
    # the bundled model is calibrated: every row says whether its intervals held the truth
    assert all(len(r["inside_interval"]) == 3 for r in report.rows)
    assert clean["interval_recordings"] == 2 and 0 <= min(map(min, clean["interval_coverage"]))
    assert "## Do the 90 % intervals hold the truth?" in text
    assert "| 0° | cnn | conformal, CNN (validation split) | 2 |" in text


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
