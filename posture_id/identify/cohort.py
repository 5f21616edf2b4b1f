"""Identify many recordings at once: locally or on a Dask cluster, resumable.

``posture-id identify DIR_OR_GLOB --out RESULTS_DIR`` writes ``<recording>.json`` per
recording (the :class:`~posture_id.identify.result.IdentificationResult`) and
``summary.csv`` (one row per recording: status, body, method, classes, E_rel in percent,
the trust verdict, and every module's parameters in SI units with their class
probability and interval bounds, to 5 significant digits). Each JSON records the options
it was made with (``"cohort_options"``: method, model weights, least-squares options,
level, stimulus, columns, body): a recording whose JSON holds the same options is not
identified again, so a killed run started again continues; one made with other options
(another ``--method``, say) is identified again and the run says which and why. A
recording that cannot be identified (a bad file) gets its one-line reason in the summary;
the others go on.

With a scheduler address the recordings are sent to a running Dask distributed cluster
as tasks that carry the recording file's bytes and the body's URDF text (the workers need
not see the files); results come back and are written here, so the folder is the same as a local
run's.
"""

from __future__ import annotations

import glob
import hashlib
import math
import tempfile
from dataclasses import dataclass, field, replace
from pathlib import Path

from posture_id.bodies.body import load_body
from posture_id.cohorts import (
    FINISHED,
    CohortRow,
    CohortTask,
    Journal,
    changed_and_failed,
    write_summary,
)
from posture_id.errors import PostureIdError
from posture_id.executors import DaskExecutor
from posture_id.fileio import Result, jsonable
from posture_id.fitting.options import FitOptions
from posture_id.identify.core import Identifier, Method
from posture_id.identify.verdict import TrustLevel
from posture_id.learning.identifier import DEFAULT_LEVEL
from posture_id.motion_capture.mapping import MarkerMapping
from posture_id.plotting import plot_cohort
from posture_id.progress import Progress, report
from posture_id.simulation.stimulus import TiltProfile
from posture_id.trials.reading import RECORDING_SUFFIXES, RecordingLayout, read_recording
from posture_id.trials.subjects import subject_urdf

__all__ = ["CohortResult", "SubjectIdentifiers", "find_recordings", "identify_cohort",
           "cohort_options", "stimulus_record"]

def cohort_options(identifier: Identifier, stimulus: TiltProfile | None,
                   columns: RecordingLayout) -> dict:
    """What a cohort's result depends on besides the recording (JSON-ready): the method,
    the network's weights, the least-squares options, the level, the stimulus, the
    columns and the body."""
    cnn = identifier.cnn
    return jsonable({
        "method": identifier.method.value,
        "model_weights_sha256": None if cnn is None
        else cnn.model.sidecar.get("weights_sha256"),
        "fit_options": identifier.fit_options if identifier.method is not Method.CNN
        else None,
        "level": identifier.level,
        "stimulus": stimulus_record(stimulus),
        "columns": columns,
        "body_sha256": identifier.body.sha256,
    })


def stimulus_record(stimulus: TiltProfile | None) -> dict | None:
    """The stimulus a cohort's recordings were read with, as its results record it: its
    description, period and a digest of its samples (None: each recording's own tilt)."""
    return None if stimulus is None else {
        "description": stimulus.description, "period_s": stimulus.period_s,
        "sha256": hashlib.sha256(stimulus.times.tobytes()
                                 + stimulus.angles.tobytes()).hexdigest()}


def find_recordings(pattern: str | Path) -> list[Path]:
    """The recordings (CSV and C3D files) of a folder, or the files a glob pattern
    matches, sorted."""
    path = Path(pattern)
    if path.is_dir():
        found = sorted(p for p in path.iterdir()
                       if p.is_file() and p.suffix.lower() in RECORDING_SUFFIXES)
    else:
        found = sorted(Path(p) for p in glob.glob(str(pattern)))
    if not found:
        raise PostureIdError(f"{pattern}: no recording (CSV or C3D) found")
    return found


@dataclass(frozen=True)
class CohortResult(Result):
    """What a cohort run did.

    Attributes:
        out: the results folder. status: per recording, "done", "skipped" (already done
            with the same options), "redone" (done before with other options: see
            ``changed``) or the error. rows: ``summary.csv``'s rows
            (:class:`~posture_id.cohorts.CohortRow`).
        changed: per redone recording, the options that differed.
    """

    out: Path
    status: dict[str, str]
    rows: tuple[CohortRow, ...] = ()
    changed: dict[str, tuple[str, ...]] = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"out": str(self.out), "status": dict(self.status),
                "rows": [r.as_dict() for r in self.rows],
                "changed": {k: list(v) for k, v in self.changed.items()}}

    def plot(self, path=None, ax=None):
        """Each identified recording's Kp per module and its E_rel."""
        done = [r for r in self.rows if "e_rel_pct" in r]  # rows of identified recordings
        joints = list(dict.fromkeys(k[: -len("_kp")] for r in done for k in r
                                    if k.endswith("_kp")))  # subjects' bodies may differ
        return plot_cohort([r["recording"] for r in done], joints,
                           [[r.get(f"{j}_kp", math.nan) for j in joints] for r in done],
                           [math.inf if r["e_rel_pct"] is None else r["e_rel_pct"] / 100
                            for r in done],
                           path=path, ax=ax)

    @property
    def failed(self) -> dict[str, str]:
        return {k: v for k, v in self.status.items() if v not in FINISHED}

    @property
    def doubtful(self) -> tuple[str, ...]:
        """The recordings whose answer is doubtful (``summary.csv``'s trust)."""
        return tuple(r.recording for r in self.rows if r.get("trust") is TrustLevel.DOUBTFUL)

    def summary(self) -> str:
        counts = {s: sum(v == s for v in self.status.values())
                  for s in ("done", "skipped", "redone")}
        doubtful = self.doubtful
        imprecise = sum(r.get("trust") is TrustLevel.IMPRECISE for r in self.rows)
        return (f"{self.out}: {len(self.status)} recordings, {counts['done']} identified, "
                f"{counts['skipped']} already done, {counts['redone']} identified again "
                f"(done before with other options), {len(self.failed)} failed"
                + changed_and_failed(self.changed, self.failed, "identified")
                + (f"\n  trust doubtful: {', '.join(doubtful)} (the JSON says why and what "
                   "to try)" if doubtful else "")
                + (f"\n  trust imprecise: {imprecise} (right as far as their noise shows; "
                   "their intervals give the precision)" if imprecise else ""))


def _identify_text(recording: tuple[str, bytes, str, str], method: str,
                   model: str | None, stimulus: TiltProfile | None = None,
                   fit_options: FitOptions | None = None, level: float = DEFAULT_LEVEL,
                   columns: RecordingLayout = None) -> dict:
    """One recording (its name and file's bytes, its body's URDF text and file name) on a
    cluster worker: the result as a dict, or the error."""
    name, content, urdf_text, urdf_name = recording
    with tempfile.TemporaryDirectory() as tmp:
        urdf = Path(tmp) / urdf_name
        urdf.write_text(urdf_text)
        rec_path = Path(tmp) / name
        rec_path.write_bytes(content)
        try:
            identifier = Identifier(load_body(urdf), Method(method), model, fit_options, level)
        except PostureIdError as exc:
            return {"error": str(exc)}
        return _identify_file(rec_path, identifier, stimulus, name, columns)


def _identify_file(path: Path, identifier: Identifier, stimulus: TiltProfile | None = None,
                   name: str | None = None, columns: RecordingLayout = None) -> dict:
    """One recording file through ``identifier``: the result as a dict, or the error;
    ``name``: what messages call it (default the path)."""
    try:
        recording = read_recording(path, identifier.body.segment_names,
                                   None if stimulus is None else stimulus.angle, columns,
                                   identifier.body)
        if name is not None:
            recording = replace(recording, name=name)
        result = identifier.identify(recording, stimulus).to_dict()
    except PostureIdError as exc:
        return {"error": str(exc)}
    return {**result, "cohort_options": cohort_options(identifier, stimulus, columns)}


def subjects_without_a_body(recordings: list[Path], bodies: str | Path) -> list[Path]:
    """The recordings whose subject has no ``<recording stem>.urdf`` in ``bodies``; a
    folder of bodies that holds none of the recordings' is refused (the names do not
    match: every subject would get the default body)."""
    bodies = _bodies_folder(bodies)
    missing = [p for p in recordings if not (bodies / f"{p.stem}.urdf").is_file()]
    if recordings and len(missing) == len(recordings):
        found = sorted(q.name for q in bodies.glob("*.urdf"))[:3]
        raise PostureIdError(
            f"{bodies}: holds no body of these recordings (wanted "
            f"{recordings[0].stem}.urdf and the like; found {', '.join(found) or 'no URDF'}):"
            " name each subject's URDF like their recording")
    return missing


def _bodies_folder(bodies: str | Path) -> Path:
    """``bodies`` as a folder of the subjects' bodies, refused when it is none."""
    bodies = Path(bodies)
    if not bodies.is_dir():
        raise PostureIdError(f"{bodies}: not a folder of bodies (one URDF per subject, named "
                             "like their recording)")
    return bodies


class SubjectIdentifiers:
    """The identifier of each recording of a cohort: for a subject with a body of their
    own (``bodies/<recording stem>.urdf``, or with ``trial_bodies`` the Winter body a C3D
    trial's metadata give) one made like ``identifier`` for that body, built once per body;
    otherwise ``identifier``."""

    def __init__(self, identifier: Identifier, bodies: str | Path | None = None,
                 model: str | Path | None = None,
                 trial_bodies: MarkerMapping | None = None) -> None:
        self.default, self.model = identifier, model
        self.bodies = None if bodies is None else _bodies_folder(bodies)
        self.trial_bodies = trial_bodies
        self._built: dict[Path, Identifier] = {}

    def urdf_of(self, recording: Path) -> Path:
        """The URDF of a recording's subject."""
        return subject_urdf(recording, self.bodies, Path(self.default.body.urdf_path),
                            self.trial_bodies)

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
                    columns: RecordingLayout = None,
                    bodies: str | Path | None = None,
                    trial_bodies: bool = False) -> CohortResult:
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
        trial_bodies: a C3D trial whose metadata give the subject's height and mass (and
            no URDF in ``bodies``) gets that subject's Winter body.
    """
    subjects = SubjectIdentifiers(identifier, bodies, model,
                                  columns if trial_bodies and isinstance(columns, MarkerMapping)
                                  else None)
    journal = Journal(out, CohortTask(
        "parameters", lambda path: cohort_options(subjects(path), stimulus, columns),
        _summary_row))

    def work(path: Path) -> dict | str:
        result = _identify_file(path, subjects(path), stimulus, columns=columns)
        return result.get("error", result)

    if scheduler:
        todo = journal.plan(recordings)
        done = len(recordings) - len(todo)
        report(progress, done, len(recordings), "recording")

        def record(path: Path, result: dict) -> None:
            nonlocal done
            journal.record(path, result.get("error", result))
            done += 1
            report(progress, done, len(recordings), "recording")

        _run_on_cluster(scheduler, todo, subjects, model, record, stimulus, columns)
    else:
        journal.run(recordings, work, progress)
    rows = journal.rows(recordings)
    write_summary(journal.out / "summary.csv", rows, _summary_fields(rows))
    return CohortResult(journal.out, journal.status, tuple(rows), journal.redone)


def _run_on_cluster(address: str, todo: list[Path], subjects: SubjectIdentifiers, model,
                    record, stimulus: TiltProfile | None = None,
                    columns: RecordingLayout = None) -> None:
    """The recordings as tasks that carry their files' bytes and their body's URDF text."""
    identifier = subjects.default
    by_name = {path.name: path for path in todo}
    tasks = [(p.name, p.read_bytes(), subjects.urdf_of(p).read_text(), subjects.urdf_of(p).name)
             for p in todo]
    with DaskExecutor(address) as cluster:
        for (name, *_), result in cluster.unordered(
                _identify_text, tasks, identifier.method.value,
                None if model is None else str(model), stimulus, identifier.fit_options,
                identifier.level, columns):
            record(by_name[name], result)


def _sig(x) -> float | None:
    """A number for the summary: 5 significant digits, None for a missing one."""
    return None if x is None else float(f"{float(x):.5g}")


def _trust_level(trust: dict) -> str:
    """A result JSON's trust level (good, imprecise or doubtful; JSONs written before the
    three levels: doubtful or good), "" without a verdict."""
    if not trust:
        return ""
    return trust.get("level") or ("doubtful" if trust.get("doubtful") else "good")


#: The first columns of summary.csv; each module's follow.
SUMMARY_FIELDS = ("recording", "status", "body", "method", "classes", "e_rel_pct", "trust",
                  "suggestion")


def _summary_row(data: dict) -> dict:
    """A result's columns of summary.csv: SI units throughout (N·m/rad, N·m·s/rad,
    N·m/(rad·s), s), E_rel in percent, 5 significant digits; per module its class
    probability (P(COM), the CNN's or none) and the bounds of each parameter's interval."""
    trust = data.get("trust") or {}
    level = _trust_level(trust)
    row = {"body": data.get("provenance", {}).get("body", {}).get("name", ""),
           "method": data["method"],
           "classes": "/".join(m["controls"] for m in data["parameters"].values()),
           "e_rel_pct": None if data["e_rel"] is None else _sig(100 * data["e_rel"]),
           "trust": TrustLevel(level) if level else "",
           "suggestion": trust.get("suggestion") or ""}
    probability = data.get("class_probability_com") or {}
    intervals = (data.get("intervals") or {}).get("modules", {})
    for joint, module in data["parameters"].items():
        row.update({f"{joint}_{key}": _sig(module[key]) for key in ("kp", "ki", "kd", "delay_s")})
        row[f"{joint}_p_com"] = _sig(probability.get(joint))
        for key in ("kp", "ki", "kd", "delay_s"):
            bounds = intervals.get(joint, {}).get(key, {})
            row[f"{joint}_{key}_low"] = _sig(bounds.get("lower_si"))
            row[f"{joint}_{key}_high"] = _sig(bounds.get("upper_si"))
    return row


def _summary_fields(rows: list[CohortRow]) -> list[str]:
    """summary.csv's columns: the first ones, then every module's as they come."""
    fields = list(SUMMARY_FIELDS)
    for row in rows:
        fields += [name for name in row.values if name not in fields]
    return fields
