"""The CNN-versus-optimiser benchmark machinery on a tiny run (the CNN only)."""

from __future__ import annotations

import json

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
    assert clean["seconds_median"] < 5
    assert len(clean["mean_abs_error"]) == 3 and len(clean["mean_abs_error"][0]) == 4
    paths = report.write(tmp_path)
    data = json.loads(paths[0].read_text())
    assert data["trials"] == 2 and len(data["rows"]) == 4
    text = paths[1].read_text()
    assert "## Sensor noise 0.01°" in text and "| cnn |" in text
    assert paths[2].stat().st_size > 10_000
