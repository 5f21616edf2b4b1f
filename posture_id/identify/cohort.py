"""Identify many recordings at once: locally or on a Dask cluster, resumable.

``posture-id identify DIR_OR_GLOB --out RESULTS_DIR`` writes ``<recording>.json`` per
recording (the :class:`~posture_id.identify.result.IdentificationResult`) and
``summary.csv`` (one row per recording: status, classes, every module's parameters,
E_rel, time). A recording whose JSON exists is not identified again, so a killed run
started again continues. A recording that cannot be identified (a bad file) gets its
one-line reason in the summary; the others go on.

With a scheduler address the recordings are sent to a running Dask distributed cluster
as tasks that carry the CSV text and the body's URDF text (the workers need not see the
files); results come back and are written here, so the folder is the same as a local
run's.
"""

from __future__ import annotations

import csv
import glob
import io
import json
import math
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path

from posture_id.bodies.body import load_body
from posture_id.errors import PostureIdError
from posture_id.executors import DaskExecutor
from posture_id.fileio import Result, atomic_write_text, json_text
from posture_id.fitting.options import FitOptions
from posture_id.identify.core import Identifier, Method
from posture_id.learning.identifier import DEFAULT_LEVEL
from posture_id.plotting import plot_cohort
from posture_id.progress import Progress, report
from posture_id.recording import Recording, RecordingColumns
from posture_id.simulation.stimulus import TiltProfile

__all__ = ["CohortResult", "SubjectIdentifiers", "find_recordings", "identify_cohort"]


def find_recordings(pattern: str | Path) -> list[Path]:
    """The CSV files of a folder, or those a glob pattern matches, sorted."""
    path = Path(pattern)
    if path.is_dir():
        found = sorted(path.glob("*.csv"))
    else:
        found = sorted(Path(p) for p in glob.glob(str(pattern)))
    if not found:
        raise PostureIdError(f"{pattern}: no recording (CSV) found")
    return found


@dataclass(frozen=True)
class CohortResult(Result):
    """What a cohort run did.

    Attributes:
        out: the results folder. status: per recording, "done", "skipped" (already done)
            or the error. rows: ``summary.csv``'s rows (recording, status, method,
            classes, e_rel and every module's parameters).
    """

    out: Path
    status: dict[str, str]
    rows: tuple[dict, ...] = ()

    def to_dict(self) -> dict:
        return {"out": str(self.out), "status": dict(self.status), "rows": list(self.rows)}

    def plot(self, path=None, ax=None):
        """Each identified recording's Kp per module and its E_rel."""
        done = [r for r in self.rows if "e_rel" in r]
        joints = list(dict.fromkeys(k[: -len("_kp")] for r in done for k in r
                                    if k.endswith("_kp")))  # subjects' bodies may differ
        return plot_cohort([r["recording"] for r in done], joints,
                           [[r.get(f"{j}_kp", math.nan) for j in joints] for r in done],
                           [math.inf if r["e_rel"] is None else r["e_rel"] for r in done],
                           path=path, ax=ax)

    @property
    def failed(self) -> dict[str, str]:
        return {k: v for k, v in self.status.items() if v not in ("done", "skipped")}

    def summary(self) -> str:
        counts = {s: sum(v == s for v in self.status.values()) for s in ("done", "skipped")}
        return (f"{self.out}: {len(self.status)} recordings, {counts['done']} identified, "
                f"{counts['skipped']} already done, {len(self.failed)} failed"
                + "".join(f"\n  {k}: {v}" for k, v in self.failed.items()))


def _identify_text(recording: tuple[str, str, str, str], method: str,
                   model: str | None, stimulus: TiltProfile | None = None,
                   fit_options: FitOptions | None = None, level: float = DEFAULT_LEVEL,
                   columns: RecordingColumns | None = None) -> dict:
    """One recording (its name and CSV text, its body's URDF text and file name) on a
    cluster worker: the result as a dict, or the error."""
    name, csv_text, urdf_text, urdf_name = recording
    with tempfile.TemporaryDirectory() as tmp:
        urdf = Path(tmp) / urdf_name
        urdf.write_text(urdf_text)
        rec_path = Path(tmp) / name
        rec_path.write_text(csv_text)
        try:
            identifier = Identifier(load_body(urdf), Method(method), model, fit_options, level)
        except PostureIdError as exc:
            return {"error": str(exc)}
        return _identify_file(rec_path, identifier, stimulus, name, columns)


def _identify_file(path: Path, identifier: Identifier, stimulus: TiltProfile | None = None,
                   name: str | None = None, columns: RecordingColumns | None = None) -> dict:
    """One recording file through ``identifier``: the result as a dict, or the error;
    ``name``: what messages call it (default the path)."""
    try:
        recording = Recording.read(path, identifier.body.segment_names,
                                   None if stimulus is None else stimulus.angle, columns)
        if name is not None:
            recording = replace(recording, name=name)
        return identifier.identify(recording, stimulus).to_dict()
    except PostureIdError as exc:
        return {"error": str(exc)}


class SubjectIdentifiers:
    """The identifier of each recording of a cohort: for a subject with a body of their
    own (``bodies/<recording stem>.urdf``) one made like ``identifier`` for that body,
    built once per body; otherwise ``identifier``."""

    def __init__(self, identifier: Identifier, bodies: str | Path | None = None,
                 model: str | Path | None = None) -> None:
        self.default, self.model = identifier, model
        self.bodies = None if bodies is None else Path(bodies)
        if self.bodies is not None and not self.bodies.is_dir():
            raise PostureIdError(f"{self.bodies}: not a folder of bodies (one URDF per "
                                 "subject, named like their recording)")
        self._built: dict[Path, Identifier] = {}

    def urdf_of(self, recording: Path) -> Path:
        """The URDF of a recording's subject."""
        own = None if self.bodies is None else self.bodies / f"{recording.stem}.urdf"
        return own if own is not None and own.is_file() else Path(self.default.body.urdf_path)

    def __call__(self, recording: Path) -> Identifier:
        urdf = self.urdf_of(recording)
        if urdf == Path(self.default.body.urdf_path):
            return self.default
        if urdf not in self._built:
            d = self.default
            self._built[urdf] = Identifier(load_body(urdf), d.method, self.model,
                                           d.fit_options, d.level)
        return self._built[urdf]


def identify_cohort(recordings: list[Path], out: str | Path, identifier: Identifier,
                    scheduler: str | None = None, progress: Progress | None = None,
                    stimulus: TiltProfile | None = None, model: str | Path | None = None,
                    columns: RecordingColumns | None = None,
                    bodies: str | Path | None = None) -> CohortResult:
    """Identify ``recordings`` into ``out`` (see the module doc) with ``identifier``.

    Args:
        scheduler: a Dask distributed scheduler address, or None for this process.
        stimulus: the stimulus every recording was made with (default: each one's tilt).
        model: the identifier's model directory, for the cluster's workers (default: the
            bundled model for the body).
        columns: the recordings' columns and units, when they are a lab's own
            (default: ``time_s,tilt_deg,<segment>_deg``).
        bodies: a folder of the subjects' own bodies, ``<recording stem>.urdf`` each (a
            subject without one gets ``identifier``'s body).
    """
    out = Path(out)
    subjects = SubjectIdentifiers(identifier, bodies, model)
    status: dict[str, str] = {}
    todo = []
    for path in recordings:
        target = out / f"{path.stem}.json"
        if _finished(target):
            status[path.name] = "skipped"
        else:
            todo.append(path)
    out.mkdir(parents=True, exist_ok=True)
    done = len(status)
    report(progress, done, len(recordings), "recording")

    def record(path: Path, result: dict) -> None:
        nonlocal done
        if "error" in result:
            status[path.name] = result["error"]
        else:
            atomic_write_text(out / f"{path.stem}.json", json_text(result))
            status[path.name] = "done"
        done += 1
        report(progress, done, len(recordings), "recording")

    if scheduler:
        _run_on_cluster(scheduler, todo, subjects, model, record, stimulus, columns)
    else:
        for path in todo:
            try:
                chosen = subjects(path)
            except PostureIdError as exc:  # a subject's body that cannot be loaded
                record(path, {"error": str(exc)})
                continue
            record(path, _identify_file(path, chosen, stimulus, columns=columns))
    rows = _write_summary(out, recordings, status)
    return CohortResult(out, status, tuple(rows))


def _run_on_cluster(address: str, todo: list[Path], subjects: SubjectIdentifiers, model,
                    record, stimulus: TiltProfile | None = None,
                    columns: RecordingColumns | None = None) -> None:
    """The recordings as tasks that carry their CSV text and their body's URDF text."""
    identifier = subjects.default
    by_name = {path.name: path for path in todo}
    tasks = [(p.name, p.read_text(), subjects.urdf_of(p).read_text(), subjects.urdf_of(p).name)
             for p in todo]
    with DaskExecutor(address) as cluster:
        for (name, *_), result in cluster.unordered(
                _identify_text, tasks, identifier.method.value,
                None if model is None else str(model), stimulus, identifier.fit_options,
                identifier.level, columns):
            record(by_name[name], result)


def _finished(target: Path) -> bool:
    try:
        return "parameters" in json.loads(target.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False


def _write_summary(out: Path, recordings: list[Path], status: dict[str, str]) -> list[dict]:
    rows, fields = [], ["recording", "status", "body", "method", "classes", "e_rel"]
    for path in recordings:
        row = {"recording": path.name, "status": status.get(path.name, "")}
        target = out / f"{path.stem}.json"
        if status.get(path.name) in ("done", "skipped"):
            data = json.loads(target.read_text(encoding="utf-8"))
            row.update(body=data.get("provenance", {}).get("body", {}).get("name", ""),
                       method=data["method"], e_rel=data["e_rel"], classes="/".join(
                m["controls"] for m in data["parameters"].values()))
            for joint, module in data["parameters"].items():
                for key in ("kp", "ki", "kd", "delay_s"):
                    name = f"{joint}_{key}"
                    row[name] = module[key]
                    if name not in fields:
                        fields.append(name)
        rows.append(row)
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=fields, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    atomic_write_text(out / "summary.csv", text.getvalue())
    return rows
