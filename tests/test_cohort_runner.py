"""The cohort runner (posture_id.cohorts) on its own: one JSON per recording with the
options it was made with, done again only when they change (and saying which), a failed
recording's reason as its status, typed rows and summary.csv."""

from __future__ import annotations

import csv
import json

from posture_id.cohorts import CohortTask, Journal, Status, changed_and_failed, write_summary
from posture_id.errors import PostureIdError


def _run(folder, out, options: dict, done: list):
    recordings = sorted(folder.glob("*.csv"))

    def work(path):
        if path.stem == "bad":
            raise PostureIdError(f"{path.name}: unreadable")
        done.append(path.name)
        return {"answer": len(path.read_text())}

    journal = Journal(out, CohortTask("answer", lambda path: options,
                                      lambda data: {"answer": data["answer"]}))
    journal.run(recordings, work)
    rows = journal.rows(recordings)
    write_summary(out / "summary.csv", rows, ["recording", "status", "answer"])
    return journal, rows


def test_the_runner_does_each_recording_once_per_options_and_says_what_changed(tmp_path):
    folder, out = tmp_path / "in", tmp_path / "out"
    folder.mkdir()
    for name, text in (("a", "1"), ("b", "22"), ("bad", "x")):
        (folder / f"{name}.csv").write_text(text)
    done: list[str] = []
    journal, rows = _run(folder, out, {"--seed": 0}, done)
    assert done == ["a.csv", "b.csv"]
    assert journal.status == {"a.csv": "done", "b.csv": "done", "bad.csv": "bad.csv: unreadable"}
    assert journal.failed == {"bad.csv": "bad.csv: unreadable"}
    assert json.loads((out / "a.json").read_text()) == {"answer": 1,
                                                         "cohort_options": {"--seed": 0}}
    assert [(r.recording, r.finished, r.get("answer")) for r in rows] == [
        ("a.csv", True, 1), ("b.csv", True, 2), ("bad.csv", False, None)]
    table = list(csv.DictReader((out / "summary.csv").open()))
    assert [r["answer"] for r in table] == ["1", "2", ""]

    done.clear()  # the same options: nothing done again but the failed one
    journal, _ = _run(folder, out, {"--seed": 0}, done)
    assert done == [] and journal.status["a.csv"] == Status.SKIPPED

    (out / "b.json").write_text("{truncated")  # a killed write: done again, not "changed"
    journal, _ = _run(folder, out, {"--seed": 0}, done)
    assert done == ["b.csv"] and journal.status["b.csv"] == Status.DONE

    done.clear()  # other options: every finished one again, with what changed
    journal, _ = _run(folder, out, {"--seed": 1}, done)
    assert done == ["a.csv", "b.csv"]
    assert journal.redone == {"a.csv": ("--seed (0 → 1)",), "b.csv": ("--seed (0 → 1)",)}
    assert changed_and_failed(journal.redone, journal.failed, "compared").splitlines()[1:] == [
        "  a.csv: compared again, its options changed: --seed (0 → 1)",
        "  b.csv: compared again, its options changed: --seed (0 → 1)",
        "  bad.csv: bad.csv: unreadable"]
