"""A cohort of recordings: one JSON each and a summary, resumable, the same on a cluster."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from posture_id.cli import main
from posture_id.cli.exit_status import answered
from posture_id.cli.output_folder import LEDGER
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


@pytest.mark.slow("a whole cohort through the command line")
def test_cohort_writes_one_json_each_and_a_summary(cohort, tmp_path, capsys):
    out = tmp_path / "results"
    assert main(["identify", str(cohort), "--out", str(out)]) == 1  # one recording is bad
    names = sorted(p.name for p in out.iterdir())
    # the folder's ledger records what posture-id wrote there (cli/output_folder.py)
    assert names == [LEDGER, "subject0.json", "subject1.json", "subject2.json", "summary.csv"]
    rows = list(csv.DictReader((out / "summary.csv").open()))
    status = {r["recording"]: r["status"] for r in rows}
    assert status["subject0.csv"] == "done" and "do not match" in status["broken.csv"]
    assert rows[0].keys() >= {"ankle_kp", "hip_delay_s", "classes", "e_rel_pct", "trust",
                              "ankle_p_com", "ankle_kp_low", "ankle_kp_high"}
    done = next(r for r in rows if r["recording"] == "subject0.csv")
    data = json.loads((out / "subject0.json").read_text())
    # one unit convention (SI; E_rel in percent), 5 significant digits
    assert float(done["e_rel_pct"]) == pytest.approx(100 * data["e_rel"], rel=1e-4)
    assert len(done["ankle_kp"].replace(".", "").lstrip("0")) <= 6
    low, high = float(done["ankle_kp_low"]), float(done["ankle_kp_high"])
    assert low <= float(done["ankle_kp"]) <= high
    assert 0 <= float(done["ankle_p_com"]) <= 1
    assert done["trust"] == data["trust"]["level"] in ("good", "imprecise", "doubtful")
    # started again, nothing finished is redone
    stamps = {p.name: p.stat().st_mtime_ns for p in out.glob("subject*.json")}
    doubtful = any(r["trust"] == "doubtful" for r in rows)
    assert main(["identify", str(cohort / "subject*.csv"), "--out", str(out)]) == answered(
        doubtful)
    assert {p.name: p.stat().st_mtime_ns for p in out.glob("subject*.json")} == stamps
    assert "3 already done" in capsys.readouterr().err


@pytest.mark.slow("a whole cohort through the command line, twice")
def test_cohort_on_a_local_cluster_equals_a_local_run(cohort, tmp_path):
    distributed = pytest.importorskip("distributed")
    local, remote = tmp_path / "local", tmp_path / "remote"
    pattern = str(cohort / "subject*.csv")
    status = main(["identify", pattern, "--out", str(local)])
    assert status in (0, 1)  # 1: an answer is doubtful (the same on the cluster)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster:
        assert main(["identify", pattern, "--out", str(remote), "--scheduler",
                     cluster.scheduler_address]) == status
    for path in local.glob("subject*.json"):
        a, b = json.loads(path.read_text()), json.loads((remote / path.name).read_text())
        assert a["parameters"] == b["parameters"] and a["e_rel"] == b["e_rel"]


def test_a_pattern_that_matches_nothing(tmp_path, capsys):
    assert main(["identify", str(tmp_path / "*.csv"), "--out", str(tmp_path / "r")]) == 2
    assert "no recording (CSV or C3D) found" in capsys.readouterr().err


def test_a_cohort_of_subjects_with_bodies_of_their_own(tmp_path, capsys):
    """Each subject identified with their own anthropometric body (--bodies), the others
    with --body; the summary names each one's body and plots."""
    from posture_id.bodies import load_body
    from posture_id.identify.cohort import find_recordings
    from posture_id.simulation import simulate

    recordings, bodies = tmp_path / "recordings", tmp_path / "bodies"
    recordings.mkdir()
    bodies.mkdir()
    for name, height, mass in (("ann", 1.62, 58.0), ("bob", 1.85, 90.0)):
        urdf = bodies / f"{name}.urdf"
        assert main(["body", "--height-m", str(height), "--mass-kg", str(mass), "--segments", "2",
                     "--out", str(urdf)]) == 0
        simulate(load_body(urdf)).to_recording().with_sensor_noise(0.01, 3).to_csv(
            recordings / f"{name}.csv")
    two_segment = load_body(bodies / "ann.urdf")
    simulate(load_body()).to_recording().to_csv(recordings / "tip.csv")  # no body of its own
    out = tmp_path / "results"
    assert main(["identify", str(recordings), "--bodies", str(bodies), "--out", str(out)]) == 0
    rows = {r["recording"]: r for r in csv.DictReader((out / "summary.csv").open())}
    assert rows["ann.csv"]["body"].startswith("winter_1.62m_58kg")
    assert rows["bob.csv"]["body"].startswith("winter_1.85m_90kg")
    # tip.csv has three segments, the default --body (the TIP) has too: identified with it
    assert rows["tip.csv"]["status"] == "done" and rows["tip.csv"]["body"] == "tip_default"
    kp = {n: json.loads((out / f"{n}.json").read_text())["parameters"] for n in ("ann", "bob")}
    assert kp["ann"] != kp["bob"] and len(kp["ann"]) == two_segment.n_segments
    from posture_id.identify import Identifier
    from posture_id.identify.cohort import identify_cohort

    again = identify_cohort(find_recordings(recordings), out, Identifier(load_body()),
                            bodies=bodies)  # all done already: read back, and plotted
    assert set(again.status.values()) == {"skipped"}
    assert again.plot(tmp_path / "cohort.png") is not None


@pytest.mark.slow("a whole cohort through the command line")
def test_a_cohort_run_again_with_other_options_redoes_what_they_change(cohort, tmp_path,
                                                                        capsys):
    """The options a result was made with are in its JSON: started again with the same
    options nothing is redone; with another interval level (or method, or model) every
    recording is identified again, and the run says which and what changed."""
    out = tmp_path / "results"
    pattern = str(cohort / "subject*.csv")
    assert main(["identify", pattern, "--out", str(out)]) in (0, 1)  # 1: a doubtful answer
    first = {p.name: json.loads(p.read_text()) for p in out.glob("subject*.json")}
    assert all(d["cohort_options"]["level"] == 0.9 for d in first.values())
    capsys.readouterr()
    assert main(["identify", pattern, "--out", str(out), "--level", "0.8"]) in (0, 1)
    err = capsys.readouterr().err
    assert "3 identified again" in err and "level (0.9 → 0.8)" in err
    again = {p.name: json.loads(p.read_text()) for p in out.glob("subject*.json")}
    assert all(d["cohort_options"]["level"] == 0.8 for d in again.values())
    assert all(d["intervals"]["level"] == 0.8 for d in again.values())
    rows = list(csv.DictReader((out / "summary.csv").open()))
    assert {r["status"] for r in rows} == {"redone"}
    doubtful = any(r["trust"] == "doubtful" for r in rows)
    assert main(["identify", pattern, "--out", str(out), "--level", "0.8"]) == answered(doubtful)
    assert "3 already done" in capsys.readouterr().err
