"""A cohort of recordings: one JSON each and a summary, resumable, the same on a cluster."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from posture_id.cli import main
from posture_id.dec import sample_parameters
from posture_id.simulation import simulate_batch


@pytest.fixture(scope="module")
def cohort(tip, tmp_path_factory):
    folder = tmp_path_factory.mktemp("cohort") / "recordings"
    folder.mkdir()
    batch = simulate_batch(tip, sample_parameters(tip, 8, np.random.default_rng(77)))
    stable = np.flatnonzero(batch.stable)[:3]
    for k, b in enumerate(stable):
        batch.trial(b).to_csv(folder / f"subject{k}.csv")
    (folder / "broken.csv").write_text("time_s,tilt_deg,shank_deg\n0,0,0\n")
    return folder


def test_cohort_writes_one_json_each_and_a_summary(cohort, tmp_path, capsys):
    out = tmp_path / "results"
    assert main(["identify", str(cohort), "--out", str(out)]) == 1  # one recording is bad
    names = sorted(p.name for p in out.iterdir())
    assert names == ["subject0.json", "subject1.json", "subject2.json", "summary.csv"]
    rows = list(csv.DictReader((out / "summary.csv").open()))
    status = {r["recording"]: r["status"] for r in rows}
    assert status["subject0.csv"] == "done" and "do not match" in status["broken.csv"]
    assert rows[0].keys() >= {"ankle_kp", "hip_delay_s", "classes", "e_rel"}
    # started again, nothing finished is redone
    stamps = {p.name: p.stat().st_mtime_ns for p in out.glob("subject*.json")}
    assert main(["identify", str(cohort / "subject*.csv"), "--out", str(out)]) == 0
    assert {p.name: p.stat().st_mtime_ns for p in out.glob("subject*.json")} == stamps
    assert "3 already done" in capsys.readouterr().err


def test_cohort_on_a_local_cluster_equals_a_local_run(cohort, tmp_path):
    distributed = pytest.importorskip("distributed")
    local, remote = tmp_path / "local", tmp_path / "remote"
    pattern = str(cohort / "subject*.csv")
    assert main(["identify", pattern, "--out", str(local)]) == 0
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster:
        assert main(["identify", pattern, "--out", str(remote), "--scheduler",
                     cluster.scheduler_address]) == 0
    for path in local.glob("*.json"):
        a, b = json.loads(path.read_text()), json.loads((remote / path.name).read_text())
        assert a["parameters"] == b["parameters"] and a["e_rel"] == b["e_rel"]


def test_a_pattern_that_matches_nothing(tmp_path, capsys):
    assert main(["identify", str(tmp_path / "*.csv"), "--out", str(tmp_path / "r")]) == 2
    assert "no recording (CSV) found" in capsys.readouterr().err
