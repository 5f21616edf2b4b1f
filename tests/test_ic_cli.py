"""The IC model and the comparison through the command line: simulate --model ic, fit
--model ic, compare (one recording and a cohort), and what they refuse."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from posture_id.cli import main
from posture_id.models.ic import IcParameters, IcPlant

WINTER1 = str(Path(__file__).resolve().parents[1] / "urdf" / "winter_1.75m_70kg_1seg.urdf")


@pytest.fixture(scope="module")
def ic_files(tmp_path_factory, winter1):
    folder = tmp_path_factory.mktemp("ic")
    plant = IcPlant.of(winter1)
    truth = IcParameters(kp=1.7 * plant.mgh, kd=0.35 * plant.mgh, delay_s=0.15, w=0.55,
                         torque_feedback_gain=0.2, torque_feedback_time_s=12.0)
    truth.to_json(folder / "truth.json")
    assert main(["simulate", "--model", "ic", "--params", str(folder / "truth.json"),
                 "--body", WINTER1, "--sensor-noise-deg", "0.02", "--seed", "2",
                 "--out", str(folder / "ic.csv")]) == 0
    assert main(["simulate", "--body", WINTER1, "--sensor-noise-deg", "0.02", "--seed", "2",
                 "--out", str(folder / "dec.csv")]) == 0
    return folder, truth


def test_fit_model_ic_recovers_the_simulated_subject(ic_files, tmp_path, capsys):
    folder, truth = ic_files
    out = tmp_path / "fit.json"
    assert main(["fit", str(folder / "ic.csv"), "--body", WINTER1, "--model", "ic", "--out",
                 str(out), "--plot", str(tmp_path / "fit.png")]) == 0
    data = json.loads(out.read_text())
    assert data["model"] == "ic" and data["trust"]["level"] in ("good", "imprecise")
    fitted = IcParameters.from_dict(data["parameters"])
    for name in ("kp", "kd", "delay_s", "w"):
        assert getattr(fitted, name) == pytest.approx(getattr(truth, name), rel=0.03), name
    assert (tmp_path / "fit.png").stat().st_size > 0
    assert "trust: " in capsys.readouterr().out


@pytest.mark.parametrize("flags, named", [
    (["--locked"], "--locked: DEC's fit only"),
    (["--classes", "fixed"], "--classes: DEC's fit only"),
    (["--gain-range", "0.5", "2"], "--gain-range: DEC's fit only"),
])
def test_fit_model_ic_refuses_decs_flags(flags, named, ic_files, tmp_path, capsys):
    folder, _ = ic_files
    assert main(["fit", str(folder / "ic.csv"), "--body", WINTER1, "--model", "ic", *flags,
                 "--out", str(tmp_path / "x.json")]) == 2
    assert named in capsys.readouterr().err
    assert not (tmp_path / "x.json").exists()


def test_fit_ki_goes_with_the_ic_model(ic_files, tmp_path, capsys):
    folder, _ = ic_files
    assert main(["fit", str(folder / "dec.csv"), "--body", WINTER1, "--fit-ki",
                 "--out", str(tmp_path / "x.json")]) == 2
    assert "--fit-ki goes with --model ic" in capsys.readouterr().err


def test_simulate_refuses_a_dec_file_as_ic_parameters(tmp_path, capsys):
    path = tmp_path / "dec.json"
    path.write_text(json.dumps({"ankle": {"kp": 1, "ki": 0, "kd": 1, "delay_s": 0.1,
                                          "controls": "com"}}))
    assert main(["simulate", "--model", "ic", "--params", str(path), "--out",
                 str(tmp_path / "x.csv")]) == 2
    assert "\"model\" must be \"ic\"" in capsys.readouterr().err


@pytest.mark.slow("model comparisons through the command line, 1 segment")
def test_compare_prefers_the_model_that_made_each_recording(ic_files, tmp_path, capsys):
    """One recording of each model (clean), then the two as a cohort with a third that
    cannot be read: one JSON each, summary.csv, the bad one named, exit 1."""
    folder, _ = ic_files
    for model in ("ic", "dec"):
        out = tmp_path / f"{model}.json"
        assert main(["compare", str(folder / f"{model}.csv"), "--body", WINTER1,
                     "--out", str(out)]) == 0
        assert json.loads(out.read_text())["preferred"] == model
    cohort = tmp_path / "cohort"
    cohort.mkdir()
    for model in ("ic", "dec"):
        (cohort / f"{model}.csv").write_bytes((folder / f"{model}.csv").read_bytes())
    (cohort / "broken.csv").write_text("time_s,tilt_deg,leg_deg\n0,0,0\n")
    results = tmp_path / "results"
    assert main(["compare", str(cohort), "--body", WINTER1, "--out", str(results)]) == 1
    rows = {r["recording"]: r for r in csv.DictReader((results / "summary.csv").open())}
    assert rows["ic.csv"]["preferred"] == "ic" and rows["dec.csv"]["preferred"] == "dec"
    assert rows["broken.csv"]["status"] not in ("done", "skipped")
    assert {p.name for p in results.glob("*.json")} == {"ic.json", "dec.json"}
    capsys.readouterr()
    # run again: nothing compared anew
    assert main(["compare", str(cohort), "--body", WINTER1, "--out", str(results)]) == 1
    rows = {r["recording"]: r for r in csv.DictReader((results / "summary.csv").open())}
    assert rows["ic.csv"]["status"] == "skipped"


@pytest.mark.slow("model comparisons through the command line, 1 segment")
def test_two_amplitudes_one_dec_or_an_ic_that_reweights(tmp_path, winter1, capsys):
    """A DEC subject at 1° and 3° (one set of parameters explains both) and an IC subject
    whose W falls from 0.6 to 0.35 at 3°: compare --second prefers each one's model, and
    the IC answer recovers the re-weighting."""
    from posture_id.models.ic.subjects import ic_recording
    from posture_id.simulation.stimulus import prts

    plant = IcPlant.of(winter1)
    truth = IcParameters(kp=1.8 * plant.mgh, kd=0.4 * plant.mgh, delay_s=0.15, w=0.6,
                         torque_feedback_gain=0.2, torque_feedback_time_s=15.0)
    # three 80-state cycles a part (60 s): what is under test is the two parts' model
    for part, (amplitude, w) in enumerate(((1.0, 0.6), (3.0, 0.35)), 1):
        recording, _ = ic_recording(winter1, truth.replace(w=w),
                                    prts(amplitude, cycles=3, states=80), None, part)
        recording.to_csv(tmp_path / f"ic{part}.csv")
        assert main(["simulate", "--body", WINTER1, "--amplitude-deg", str(amplitude),
                     "--states", "80", "--cycles", "3", "--sensor-noise-deg", "0.02", "--seed",
                     str(part), "--out", str(tmp_path / f"dec{part}.csv")]) == 0
    protocol = tmp_path / "two.json"
    protocol.write_text(json.dumps({"kind": "two_amplitudes",
                                    "base": {"kind": "prts", "states": 80, "cycles": 3},
                                    "amplitudes_deg": [1, 3]}))
    for model in ("dec", "ic"):
        out = tmp_path / f"{model}.json"
        assert main(["compare", str(tmp_path / f"{model}1.csv"), "--second",
                     str(tmp_path / f"{model}2.csv"), "--body", WINTER1, "--protocol",
                     str(protocol), "--out", str(out)]) == 0
        data = json.loads(out.read_text())
        assert data["preferred"] == model, data["reason"]
    w = json.loads((tmp_path / "ic.json").read_text())["ic"]["w_by_part"]
    assert w == pytest.approx([0.6, 0.35], abs=0.02)
    assert "IC re-weighting: W" in capsys.readouterr().out


@pytest.mark.parametrize("flags, named", [
    (["--second", "{dec}", "--part", "1"], "--part: with --second each recording"),
    (["--out", "{ic}"], "--out is also an input"),
])
def test_compare_refuses_what_cannot_work(flags, named, ic_files, capsys):
    folder, _ = ic_files
    flags = [f.replace("{dec}", str(folder / "dec.csv")).replace("{ic}", str(folder / "ic.csv"))
             for f in flags]
    assert main(["compare", str(folder / "ic.csv"), "--body", WINTER1, *flags]) == 2
    assert named in capsys.readouterr().err


def test_compare_a_cohort_refuses_second_and_plot(ic_files, tmp_path, capsys):
    folder, _ = ic_files
    for flags, named in ((["--second", str(folder / "dec.csv")], "--second goes with one"),
                         (["--plot", str(tmp_path / "p.png")], "--plot is for one recording")):
        assert main(["compare", str(folder), "--body", WINTER1, "--out", str(tmp_path / "o"),
                     *flags]) == 2
        assert named in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
