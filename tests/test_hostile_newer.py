"""Hostile input for the newer commands: every case of ``tests/hostile_cases.py``
(protocol files, design, stimulus, a lab's columns, cohorts, the universal tools, evaluate,
frf, fit, body) and of ``tests/hostile_cases_newest.py`` (C3D trials, the IC model, compare,
norm build, test and compare, a cohort's norm) must be *clear* (exit 2, one line naming the
file or flag and the problem, no file of the user's changed, nothing new left) or, where an
answer is right, *handled* (an answer with the notice that says what was done). The report
of the same cases with their counts is docs/results/hostile_input/report.md
(``benchmarks/hostile_input.py``).
"""

from __future__ import annotations

import json

import pytest
from hostile_cases import all_cases, make_material, run_case
from hostile_cases_newest import newest_cases

CASES = all_cases()
#: Cases that run a whole command before their outcome (over 5 s here).
SLOW = {"limits no candidate meets"}


@pytest.fixture(scope="module")
def material(tmp_path_factory):
    return make_material(tmp_path_factory.mktemp("hostile") / "material")


def test_the_suite_is_at_least_80_cases_over_every_newer_surface():
    surfaces = {c.surface.split(":")[0] for c in CASES}
    assert len(CASES) >= 80
    assert {"protocol", "design", "stimulus", "columns", "cohort", "universal data",
            "universal train", "evaluate", "frf", "fit", "body"} <= surfaces


def test_the_newest_commands_have_at_least_80_cases_over_each_of_their_surfaces():
    newest = newest_cases()
    assert len(newest) >= 80
    assert {c.surface for c in newest} == {"norm build", "norm test", "norm compare",
                                           "cohort norm", "c3d", "simulate c3d", "ic",
                                           "compare"}
    assert len(CASES) - len(newest) >= 120  # the earlier surfaces' cases run beside them


@pytest.mark.parametrize("case", [pytest.param(
    c, id=c.name, marks=[pytest.mark.slow("a protocol design through the command line")]
    if c.name in SLOW else []) for c in CASES])
def test_every_bad_input_is_refused_clearly_or_handled(case, material, tmp_path):
    outcome = run_case(case, material, tmp_path / "case")
    wanted = "handled" if case.handled else "clear"
    assert outcome.outcome == wanted, (outcome.outcome, outcome.status, outcome.line)


def test_a_report_folder_is_the_users_again_once_they_edit_a_file(material, tmp_path,
                                                                  monkeypatch, capsys):
    """posture-id overwrites only files it wrote and that nobody changed since: a
    report it wrote is written again; the same report edited by the user is refused."""
    from posture_id.cli import main
    from posture_id.cli.output_folder import LEDGER

    monkeypatch.chdir(tmp_path)
    command = ["network", "cnn", "evaluate", material["specialist"], material["set_tip"], "--out",
               "e",
               "--resimulate", "0"]
    assert main(command) == 0
    ledger = json.loads((tmp_path / "e" / LEDGER).read_text())["files"]
    assert {"report.md", "report.json"} <= set(ledger)
    assert main(command) == 0  # its own files: written again
    (tmp_path / "e" / "report.md").write_text("my notes on the model\n")
    capsys.readouterr()
    assert main(command) == 2
    assert "report.md, which posture-id did not write" in capsys.readouterr().err
    assert (tmp_path / "e" / "report.md").read_text() == "my notes on the model\n"


def test_a_result_json_from_before_the_ledger_is_known_by_its_provenance(tmp_path):
    from posture_id.cli.output_folder import OutputFolder

    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "a.json").write_text(json.dumps(
        {"provenance": {"package": "posture_id", "version": "0.1.0"}}))
    (tmp_path / "out" / "b.json").write_text(json.dumps({"provenance": {"package": "other"}}))
    assert OutputFolder(tmp_path / "out", "--out", ("a.json",)).foreign_files() == []
    assert [p.name for p in OutputFolder(tmp_path / "out", "--out",
                                         ("a.json", "b.json")).foreign_files()] == ["b.json"]


def test_a_failed_run_leaves_no_new_folder(tmp_path):
    from posture_id.cli.output_folder import OutputFolder
    from posture_id.errors import PostureIdError

    with pytest.raises(PostureIdError), OutputFolder(tmp_path / "new", "--out", ("x.md",)):
        (tmp_path / "new").mkdir()
        raise PostureIdError("the work failed")
    assert not (tmp_path / "new").exists()


def test_exit_statuses_mean_the_same_for_every_command():
    """One meaning per status, said in every command's help."""
    from posture_id.cli import build_parser
    from posture_id.cli import exit_status as status

    assert (status.ANSWERED, status.DOUBTFUL, status.REFUSED, status.BUG) == (0, 1, 2, 3)
    assert status.answered(True) == 1 and status.answered(False) == 0
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    assert all(p.epilog == status.EPILOG for p in sub.choices.values())


def test_a_doubtful_answer_is_written_and_exits_1(tmp_path, capsys):
    """identify's answer to a recording with its tilt negated (a mistake: doubtful) is
    written, and the exit status says it is doubtful; the same recording as it was: 0."""
    from posture_id import load_body, simulate
    from posture_id.cli import main

    recording = simulate(load_body()).to_recording().with_sensor_noise(0.02, 1)
    right = recording.to_csv(tmp_path / "right.csv")
    lines = right.read_text().splitlines()
    header, rows = lines[0], [line.split(",") for line in lines[1:]]
    negated = tmp_path / "negated.csv"
    negated.write_text(header + "\n" + "\n".join(
        ",".join([r[0], str(-float(r[1])), *r[2:]]) for r in rows) + "\n")
    out = tmp_path / "negated.json"
    assert main(["identify", str(negated), "--method", "cnn", "--out", str(out)]) == 1
    assert json.loads(out.read_text())["trust"]["level"] == "doubtful"
    assert main(["identify", str(right), "--method", "cnn"]) == 0
