"""The one way a per-recording command runs over a cohort: a results folder with one JSON per
recording and ``summary.csv``, resumable.

Each finished JSON records the options it was made with (``"cohort_options"``). Started
again, a recording whose JSON holds the options wanted now is not done again ("skipped");
one made with other options is done again ("redone", and the run says which options
changed); one that cannot be done gets its one-line reason as its status while the others
go on. The commands differ only in what they do to one recording, what options they
record and what row of ``summary.csv`` a result makes (:class:`CohortTask`).
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from posture_id.choices import Choice
from posture_id.errors import PostureIdError
from posture_id.fileio import atomic_write_text, json_object, json_text
from posture_id.progress import Progress, report

__all__ = ["Status", "CohortRow", "CohortTask", "Journal", "option_differences",
           "write_summary", "changed_and_failed"]


class Status(Choice):
    """What became of a recording with a result (a failed one's status is its reason)."""

    DONE = "done"
    SKIPPED = "skipped"
    REDONE = "redone"



#: The statuses of a recording with a result.
FINISHED = frozenset(s.value for s in Status)


@dataclass(frozen=True)
class CohortRow:
    """One recording's row of ``summary.csv``.

    Attributes:
        recording: the file's name. status: a :class:`Status` value, or why it failed.
        values: the command's columns (SI units), in order.
    """

    recording: str
    status: str
    values: Mapping[str, object] = field(default_factory=dict)

    @property
    def finished(self) -> bool:
        return self.status in FINISHED

    def get(self, key: str, default=None):
        """A column of the row ("recording", "status" or one of ``values``)."""
        return self.as_dict().get(key, default)

    def __getitem__(self, key: str):
        return self.as_dict()[key]

    def __contains__(self, key: str) -> bool:
        return key in self.as_dict()

    def __iter__(self):
        """The row's column names."""
        return iter(self.as_dict())

    def as_dict(self) -> dict:
        return {"recording": self.recording, "status": self.status, **self.values}


def option_differences(old: Mapping, new: Mapping) -> tuple[str, ...]:
    """The top-level options that differ, as "name (old → new)" for short values."""
    out = []
    for key in sorted(set(old) | set(new)):
        a, b = old.get(key), new.get(key)
        if a != b:
            short = all(isinstance(x, str | int | float | type(None)) for x in (a, b))
            out.append(f"{key} ({a} → {b})" if short else key)
    return tuple(out)


@dataclass(frozen=True)
class CohortTask:
    """What a command does over a cohort.

    Attributes:
        finished_key: a key every finished result JSON holds (what tells it from a stub).
        options: the options one recording's result is made with (JSON-ready); it may raise
            :class:`~posture_id.errors.PostureIdError` (the recording is then done, and
            fails with the reason).
        row: the ``summary.csv`` columns of a finished result (its JSON as a dict).
    """

    finished_key: str
    options: Callable[[Path], dict]
    row: Callable[[dict], dict]


class Journal:
    """A cohort's results folder (the module doc): which recordings are to do, what each
    became, and the summary."""

    def __init__(self, out: str | Path, task: CohortTask) -> None:
        self.out = Path(out)
        self.task = task
        self.status: dict[str, str] = {}
        self.changed: dict[str, tuple[str, ...]] = {}

    def target(self, recording: Path) -> Path:
        return self.out / f"{recording.stem}.json"

    def _earlier(self, recording: Path) -> dict | None:
        """The options a finished result was made with ({} for one without), or None
        when there is no finished result."""
        data = json_object(self.target(recording))
        if self.task.finished_key not in data:
            return None
        return data.get("cohort_options") or {}

    def plan(self, recordings: Iterable[Path]) -> list[Path]:
        """The recordings to do; the others are marked skipped."""
        todo = []
        for path in recordings:
            earlier = self._earlier(path)
            if earlier is None:
                todo.append(path)
                continue
            try:
                wanted = json.loads(json_text(self.task.options(path)))
            except PostureIdError:  # said when it is done
                todo.append(path)
                continue
            if earlier == wanted:
                self.status[path.name] = Status.SKIPPED.value
            else:
                self.changed[path.name] = option_differences(earlier, wanted) \
                    or ("cohort_options",)
                todo.append(path)
        self.out.mkdir(parents=True, exist_ok=True)
        return todo

    def record(self, recording: Path, result: dict | str) -> None:
        """A recording's result (its JSON as a dict) or why it failed; the result is
        written with the options it was made with (its own ``"cohort_options"`` where it
        holds them)."""
        if isinstance(result, str):
            self.status[recording.name] = result
            return
        options = result.get("cohort_options")
        if options is None:
            try:
                options = self.task.options(recording)
            except PostureIdError as exc:
                self.status[recording.name] = str(exc)
                return
        atomic_write_text(self.target(recording),
                          json_text({**result, "cohort_options": options}))
        self.status[recording.name] = (Status.REDONE if recording.name in self.changed
                                       else Status.DONE).value

    def run(self, recordings: list[Path], work: Callable[[Path], dict | str],
            progress: Progress | None = None, verb: str = "recording") -> None:
        """Do every recording ``plan`` leaves, here, one by one (``work``: the result as a
        dict, or why it failed)."""
        todo = self.plan(recordings)
        done = len(recordings) - len(todo)
        report(progress, done, len(recordings), verb)
        for path in todo:
            try:
                result = work(path)
            except PostureIdError as exc:
                result = str(exc)
            self.record(path, result)
            done += 1
            report(progress, done, len(recordings), verb)

    def rows(self, recordings: list[Path]) -> list[CohortRow]:
        """Every recording's row: a finished one's from its JSON."""
        rows = []
        for path in recordings:
            status = self.status.get(path.name, "")
            values = {}
            if status in FINISHED:
                values = self.task.row(json.loads(self.target(path).read_text(
                    encoding="utf-8")))
            rows.append(CohortRow(path.name, status, values))
        return rows

    @property
    def failed(self) -> dict[str, str]:
        return {k: v for k, v in self.status.items() if v not in FINISHED}

    @property
    def redone(self) -> dict[str, tuple[str, ...]]:
        """Per recording done again, the options that changed."""
        return {k: v for k, v in self.changed.items()
                if self.status.get(k) == Status.REDONE.value}


def changed_and_failed(changed: Mapping[str, tuple[str, ...]], failed: Mapping[str, str],
                       again: str) -> str:
    """A cohort summary's lines for the recordings done again (``again``: "identified",
    "compared") with the options that changed, and for those that failed, with why."""
    return ("".join(f"\n  {k}: {again} again, its options changed: {', '.join(v)}"
                    for k, v in changed.items())
            + "".join(f"\n  {k}: {v}" for k, v in failed.items()))


def write_summary(path: Path, rows: list[CohortRow], fields: list[str]) -> None:
    """``summary.csv``: one row per recording, ``fields`` as its columns."""
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=fields, lineterminator="\n")
    writer.writeheader()
    writer.writerows(r.as_dict() for r in rows)
    atomic_write_text(path, text.getvalue())
