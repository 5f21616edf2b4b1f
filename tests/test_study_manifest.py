"""A whole study from its manifest (posture_id/manifest): the manifest read and refused
clearly, every trial's FRF, resumable, summary.csv with the conditions as columns, paired
tests between the conditions; and on the command line."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from posture_id.bodies.anthropometry import winter_body_file
from posture_id.errors import PostureIdError
from posture_id.force_plate.reading import ForcePlateColumns
from posture_id.manifest import StudyOptions, read_manifest, run_study
from posture_id.recording import TimeUnit
from posture_id.studies.force_plate_study import make_study

PLATE = ForcePlateColumns(cop="COP AP", time="Time", tilt="Platform",
                          time_unit=TimeUnit.MILLISECONDS)


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """Three subjects, eyes open and closed, one sinusoid (0.2 Hz) each."""
    return make_study(tmp_path_factory.mktemp("study"), subjects=3, frequencies_hz=(0.2,))


def test_the_manifest_is_read_and_its_mistakes_named(study, tmp_path):
    manifest = read_manifest(study)
    assert manifest.subjects == ("S01", "S02", "S03")
    assert manifest.conditions == ("eyes_open", "eyes_closed")
    assert all(t.file.is_file() and t.height_m for t in manifest.trials)
    text = study.read_text().splitlines()
    cases = {
        "no column": [text[0].replace("condition", "cond"), *text[1:]],
        "line 3, column 'file': no such file": [text[0], text[1],
                                                text[2].replace(".txt", ".csv")],
        "line 2, column 'height_m': 175 is not a person's": [
            text[0], ",".join(text[1].split(",")[:3] + ["175"] + text[1].split(",")[4:])],
        "already the trial of line 2": [text[0], text[1], text[1]],
        "body differs from line 2": [text[0], text[1],
                                     text[2].replace(text[2].split(",")[-1], "99")],
    }
    for why, lines in cases.items():
        bad = study.parent / "bad.csv"
        bad.write_text("\n".join(lines) + "\n")
        with pytest.raises(PostureIdError, match=why.replace("(", r"\(").replace(")", r"\)")):
            read_manifest(bad)


def test_a_study_of_force_plate_trials_makes_every_frf_and_the_paired_test(study, tmp_path):
    out = tmp_path / "out"
    options = StudyOptions(layout=PLATE, model=None, workers=1)
    result = run_study(read_manifest(study), out, options)
    assert not result.failed and len(result.trial_rows) == 6
    with open(out / "summary.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["subject"] for r in rows] == ["S01", "S02", "S03"]
    for condition in ("eyes_open", "eyes_closed"):
        assert all(float(r[f"gain 0.2 Hz [{condition}]"]) > 0 for r in rows)
    # with the eyes closed (W 0.6 against 0.35) every subject follows the platform more
    assert all(float(r["gain 0.2 Hz [eyes_closed]"]) > float(r["gain 0.2 Hz [eyes_open]"])
               for r in rows)
    paired = json.loads((out / "paired" / "eyes_open_vs_eyes_closed.json").read_text())
    assert paired["frf"]["pairs"] == 3 and paired["frf"]["exact"]
    # started again: nothing is done twice
    again = run_study(read_manifest(study), out, options)
    assert {r.status for r in again.trial_rows} == {"skipped"}


@pytest.mark.slow("a whole study of IC fits")
def test_a_study_fits_every_subject_jointly_and_compares_the_conditions_weights(study,
                                                                               tmp_path):
    out = tmp_path / "out"
    result = run_study(read_manifest(study), out,
                       StudyOptions(layout=PLATE, model="ic", per_condition=("w",)))
    assert not result.failed
    row = result.summary_rows[0]
    assert row["w [eyes_closed]"] > row["w [eyes_open]"]
    tests = result.paired["eyes_open vs eyes_closed"]
    assert tests["parameters"]["parameters"][0]["parameter"] == "w"
    assert tests["parameters"]["parameters"][0]["difference"] < 0
    # the plot: every subject in the parameters' legend, every condition in the gains'
    figure = result.plot()
    weights, gains = figure.axes[0], figure.axes[-1]
    assert [t.get_text() for t in weights.get_legend().get_texts()] == ["S01", "S02", "S03"]
    labels = " ".join(t.get_text() for t in gains.get_legend().get_texts())
    assert "eyes_open" in labels and "eyes_closed" in labels


def test_the_command_line_runs_a_study(study, tmp_path, capsys):
    from posture_id.cli import main

    out = tmp_path / "cli"
    flags = ["--time-column", "Time", "--time-units", "ms", "--tilt-column", "Platform",
             "--cop-column", "COP AP"]
    assert main(["study", str(study), "--out", str(out), "--model", "none", "--workers",
                 "1", *flags, "--plot", str(tmp_path / "study.png")]) == 0
    assert "3 subject(s)" in capsys.readouterr().out
    assert (tmp_path / "study.png").is_file() and (out / "trials.csv").is_file()
    assert main(["study", str(study), "--out", str(out), "--model", "none",
                 "--per-condition", "w", *flags]) == 2
    assert "--per-condition goes with a model" in capsys.readouterr().err


def test_a_norm_of_sinusoid_trials_tests_a_sinusoid_recording_at_its_frequency(study,
                                                                                tmp_path,
                                                                                capsys):
    """A norm built from the study's eyes-open FRFs (one frequency, no bands) tests an
    eyes-closed trial's file directly: its FRF at the frequency its sinusoid drives, the
    same answer as its FRF JSON's."""
    from posture_id.cli import main

    out = tmp_path / "out"
    run_study(read_manifest(study), out, StudyOptions(layout=PLATE, model=None, workers=1))
    members = sorted((out / "frf").glob("*eyes_open*.json"))
    norm = tmp_path / "norm.json"
    assert main(["norm", "build", *map(str, members), "--out", str(norm)]) == 0
    closed = next(e for e in read_manifest(study).trials if e.condition == "eyes_closed")
    body = tmp_path / "subject.urdf"
    assert main(["body", "--height-m", str(closed.height_m), "--mass-kg", str(closed.mass_kg),
                 "--segments", "1", "--out", str(body)]) == 0
    capsys.readouterr()
    from_file, from_json = tmp_path / "file.json", tmp_path / "json.json"
    assert main(["norm", "test", str(closed.file), "--norm", str(norm), "--body", str(body),
                 "--time-column", "Time", "--time-units", "ms", "--tilt-column", "Platform",
                 "--cop-column", "COP AP", "--out",
                 str(from_file)]) in (0, 1)
    frf = out / "frf" / f"{closed.key}.json"
    assert main(["norm", "test", str(frf), "--norm", str(norm),
                 "--out", str(from_json)]) in (0, 1)
    a, b = (json.loads(p.read_text()) for p in (from_file, from_json))
    assert a["human_likeness"] == pytest.approx(b["human_likeness"], rel=1e-6)


@pytest.mark.slow("a whole study, twice (one on a cluster)")
def test_a_study_on_a_dask_cluster_equals_a_local_run(study, tmp_path):
    """Each task carries its file's bytes and its body's URDF: the cluster's FRFs are the
    local ones."""
    distributed = pytest.importorskip("distributed")
    local, remote = tmp_path / "local", tmp_path / "remote"
    run_study(read_manifest(study), local, StudyOptions(layout=PLATE, model=None, workers=1))
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster:
        result = run_study(read_manifest(study), remote,
                           StudyOptions(layout=PLATE, model=None,
                                        scheduler=cluster.scheduler_address))
    assert not result.failed
    for path in (local / "frf").glob("*.json"):
        a, b = (json.loads(p.read_text()) for p in (path, remote / "frf" / path.name))
        assert a["channels"] == b["channels"]


def _cell(row: str, k: int, value: str) -> str:
    cells = row.split(",")
    cells[k] = value
    return ",".join(cells)


def test_a_manifests_names_in_two_cases_and_malformed_rows_are_refused_and_choices_said(
        study, tmp_path):
    text = study.read_text().splitlines()
    header, rows = text[0], text[1:]
    bad = study.parent / "bad.csv"
    cases = {
        r"line 5, column 'condition': 'Eyes_closed' and 'eyes_closed' \(line 3\) differ "
        "only in case": [header, *rows[:3], _cell(rows[3], 1, "Eyes_closed")],
        r"line 5, column 'subject': 'S02' and 's02' \(line 4\)": [
            header, *rows[:2], _cell(rows[2], 0, "s02"), rows[3]],
        "column 'file' appears twice": [header + ",file", *(r + ",x" for r in rows)],
        "line 3: 6 fields, the header has 5": [header, rows[0], rows[1] + ",retest"],
    }
    for why, lines in cases.items():
        bad.write_text("\n".join(lines) + "\n")
        with pytest.raises(PostureIdError, match=why):
            read_manifest(bad)
    # a body beside a height: the body is used, said; UTF-16 without a mark: read, said
    urdf = study.parent / "S01.urdf"
    urdf.write_text(Path(winter_body_file(1.77, 70.4, 1)).read_text())
    bad.write_text("\n".join([header + ",body", *(r + (",S01.urdf" if r.startswith("S01")
                                                       else ",") for r in rows)]) + "\n")
    both = read_manifest(bad)
    assert both.trials[0].body == urdf.resolve() and both.trials[0].height_m is None
    assert any("line 2, 3: both a body and height_m and mass_kg: the body URDF is used" in n
               for n in both.notices)
    bad.write_bytes(study.read_text().encode("utf-16-le"))
    assert read_manifest(bad).trials == read_manifest(study).trials
    assert any("UTF-16" in n for n in read_manifest(bad).notices)


@pytest.mark.slow("a whole study, twice")
def test_a_study_run_again_on_fewer_rows_fits_again_and_says_what_it_left_out(study,
                                                                              tmp_path):
    out = tmp_path / "out"
    first = run_study(read_manifest(study), out, StudyOptions(layout=PLATE, workers=1))
    assert not first.notices and not first.answered_doubtfully
    fewer = study.parent / "fewer.csv"
    lines = study.read_text().splitlines()
    fewer.write_text("\n".join(line for line in lines
                               if not line.startswith("S02,eyes_closed")) + "\n")
    again = run_study(read_manifest(fewer), out, StudyOptions(layout=PLATE, workers=1))
    said = "\n".join(again.notices)
    assert "S02 fitted again" in said and "trials" in said
    assert "no longer names" in said and "S02__S02_eyes_closed" in said
    assert "subject S02 has no eyes_closed trial" in said
    status = {r.recording: r.status for r in again.subject_rows}
    assert status["S01.subject"] == "skipped" and status["S02.subject"] != "skipped"
    with pytest.raises(PostureIdError, match="per-condition parameter 'gain'"):
        run_study(read_manifest(study), out, StudyOptions(layout=PLATE,
                                                          per_condition=("gain",)))


def test_a_trials_internal_error_is_named_with_its_file_and_the_study_goes_on(study,
                                                                             monkeypatch):
    """A bug met on one trial (the periodic finder's crash on a real plate's trial) is
    that trial's failure, naming its file, not the study's end."""
    import posture_id.frf as frf
    from posture_id.manifest import run as study_run

    def broken(*args, **kwargs):
        raise ValueError("zero-size array to reduction operation maximum")

    monkeypatch.setattr(frf, "frequency_response", broken)
    entry = read_manifest(study).trials[0]
    why = study_run._trial_frf(study_run._task(entry, StudyOptions(layout=PLATE)))
    assert isinstance(why, str) and why.startswith(str(entry.file))
    assert "internal error (a bug" in why and "ValueError: zero-size array" in why
