"""A whole study from its manifest (``posture-id study MANIFEST --out DIR``): every trial's
FRF, each subject's joint fit over its trials (the subject's parameters shared, the named
ones per condition), ``summary.csv`` with a row per subject and the conditions as
columns, and paired tests between the conditions, on the FRFs and on the per-condition
parameters.

Resumable as every cohort (:mod:`posture_id.cohorts`): ``frf/<trial>.json`` and
``fits/<subject>.json`` record the options they were made with; started again, what holds
the options wanted now is not done again. Trials and subjects run in parallel, on local
processes or a Dask cluster (:func:`~posture_id.executors.executor_for`); each task
carries its file's bytes and its body's URDF text, so a cluster's workers need no shared
folder.
"""

from __future__ import annotations

import csv
import io
import json
import tempfile
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from posture_id.cohorts import CohortRow, CohortTask, Journal, write_summary
from posture_id.errors import PostureIdError, bug_line
from posture_id.fileio import Result, atomic_write_text, jsonable
from posture_id.force_plate.load import LoadColumns
from posture_id.frf.response import FrfOptions
from posture_id.manifest.reading import StudyManifest, TrialEntry
from posture_id.progress import Progress, report
from posture_id.trials.reading import RecordingLayout

__all__ = ["StudyOptions", "StudyResult", "run_study", "COM_CHANNEL"]

#: The channel the study's FRFs, fits and paired tests compare: the body-COM sway.
COM_CHANNEL = "body COM"


@dataclass(frozen=True)
class StudyOptions:
    """How a study runs.

    Attributes:
        layout: how every trial's file is read (a lab's columns, a force plate's, None:
            the standard header).
        model: the model fitted to each subject ("ic" or "dec"; None: FRFs only).
        per_condition: the parameters that take one value per condition (IC: "w").
        segments: the Winter body's segments for a subject given by height and mass.
        frf: the FRF options. permutations: of the paired tests. level: the intervals'.
        workers: local processes (None: every core). scheduler: a Dask scheduler's
        address (None: local). load: the plate's load columns that weigh a subject whose
        rows give a height and no mass (None: every row gives its mass or body).
    """

    layout: RecordingLayout = None
    model: str | None = "ic"
    per_condition: tuple[str, ...] = ("w",)
    segments: int = 1
    frf: FrfOptions = field(default_factory=FrfOptions)
    permutations: int = 2000
    workers: int | None = None
    scheduler: str | None = None
    load: LoadColumns | None = None

    def frf_record(self, entry: TrialEntry | None = None) -> dict:
        """What a trial's FRF is made with (its JSON's ``cohort_options``): the options
        and the trial's body (its URDF, or its height and mass: a subject weighed again
        makes its FRFs again)."""
        body = None if entry is None else (str(entry.body) if entry.body is not None
                                           else f"{entry.height_m:g} m, {entry.mass_kg:g} kg")
        return jsonable({"layout": self.layout, "frf": self.frf, "segments": self.segments,
                         "body": body})

    def fit_record(self, trials: tuple[TrialEntry, ...] = ()) -> dict:
        """What a subject's joint fit is made with (its JSON's ``cohort_options``): the
        options and the subject's ``trials`` (file and condition each: a trial added to
        or dropped from the manifest makes the fit again)."""
        return jsonable({**self.frf_record(trials[0] if trials else None), "model": self.model,
                         "per_condition": list(self.per_condition),
                         "trials": [f"{t.file.name} [{t.condition}]" for t in trials]})


def _body_file(entry: TrialEntry, segments: int) -> Path:
    from posture_id.bodies.anthropometry import winter_body_file

    if entry.body is not None:
        return entry.body
    return Path(winter_body_file(entry.height_m, entry.mass_kg, segments))


def _read(task: dict, rate_hz: float | None):
    """(the trial prepared at ``rate_hz``, the body it is of) from a task's bytes."""
    from posture_id.bodies.body import load_body
    from posture_id.bodies.one_segment import one_segment_body
    from posture_id.force_plate.reading import ForcePlateColumns
    from posture_id.trials import prepare_trial
    from posture_id.trials.reading import read_recording

    with tempfile.TemporaryDirectory() as folder:
        urdf = Path(folder) / task["urdf_name"]
        urdf.write_text(task["urdf"])
        body = load_body(urdf)
        body = one_segment_body(body) if isinstance(task["layout"], ForcePlateColumns) \
            else body
        path = Path(task["name"])
        if "bytes" in task:  # on a cluster's worker: the file travelled with the task
            path = Path(folder) / task["file_name"]
            path.write_bytes(task["bytes"])
        recording = read_recording(path, body.segment_names, None, task["layout"], body)
    recording = replace(recording, name=task["name"])
    return prepare_trial(recording, None, rate_hz=rate_hz), body


def _trial_frf(task: dict) -> dict | str:
    """One trial's FRF (its JSON as a dict with the subject, condition and file), or why
    it failed."""
    from posture_id.frf import frequency_response

    try:
        trial, body = _read(task, None)
        result = frequency_response(trial, body, task["frf"]).to_dict()
    except PostureIdError as exc:
        return str(exc)
    except Exception as exc:  # noqa: BLE001 - one trial's bug must not stop the study
        return f"{task['name']}: {bug_line(exc)}"
    return {**result, "subject": task["subject"], "condition": task["condition"],
            "file": task["name"], "notices": list(trial.notices)}


def _subject_fit(task: dict) -> dict | str:
    """One subject's joint fit over its trials (its JSON as a dict), or why it failed."""
    from posture_id.fitting.joint_conditions import fit_joint
    from posture_id.models import model_named

    try:
        prepared = [_read(t, 50.0) for t in task["trials"]]
        model = model_named(task["model"])
        fit = fit_joint(model, [p[0] for p in prepared], prepared[0][1],
                        [t["condition"] for t in task["trials"]], task["per_condition"])
    except PostureIdError as exc:
        return str(exc)
    except Exception as exc:  # noqa: BLE001 - one subject's bug must not stop the study
        return f"subject {task['subject']}: {bug_line(exc)}"
    return {**fit.to_dict(), "subject": task["subject"]}


def weighed(manifest: StudyManifest, options: StudyOptions) -> StudyManifest:
    """``manifest`` with the mass of every subject whose rows give a height and no mass:
    the median of its trials' plate masses (:func:`~posture_id.force_plate.load.
    standing_mass`, over the level stretches of the layout's tilt column), said.

    Raises:
        PostureIdError: such a row without ``options.load`` (naming the line), and what
            weighing refuses (naming the file).
    """
    unweighed = [t for t in manifest.trials if t.body is None and t.mass_kg is None]
    if not unweighed:
        return manifest
    if options.load is None:
        raise PostureIdError(f"{manifest.path}: line {unweighed[0].line}, column 'mass_kg': "
                             "no mass: give it, or weigh the subjects on the plate (its load "
                             "columns: --load-columns NAME ...)")
    from posture_id.force_plate.load import standing_mass
    from posture_id.force_plate.reading import ForcePlateColumns

    tilt = options.layout.tilt if isinstance(options.layout, ForcePlateColumns) else None
    masses, notices = {}, []
    for subject in dict.fromkeys(t.subject for t in unweighed):
        readings = [standing_mass(t.file, options.load, tilt).mass_kg
                    for t in manifest.of(subject)]
        masses[subject] = round(float(np.median(readings)), 2)
        notices.append(f"{manifest.path}: subject {subject}'s mass is {masses[subject]:.4g} kg, "
                       f"the median of what the plate weighs in its {len(readings)} trial(s) "
                       f"({min(readings):.4g}–{max(readings):.4g} kg, "
                       f"{', '.join(options.load.columns)})")
    trials = tuple(replace(t, mass_kg=masses[t.subject]) if t.body is None and
                   t.mass_kg is None else t for t in manifest.trials)
    return replace(manifest, trials=trials, notices=(*manifest.notices, *notices))


def _check_per_condition(manifest: StudyManifest, options: StudyOptions) -> None:
    """Refuse, before any work, per-condition parameters the model's joint fit does not
    identify (for the study's first body: a DEC module's parameters are named by its
    joints)."""
    from posture_id.bodies.body import load_body
    from posture_id.bodies.one_segment import one_segment_body
    from posture_id.fitting.joint_conditions import resolve_parameter
    from posture_id.force_plate.reading import ForcePlateColumns
    from posture_id.models import model_named

    body = load_body(_body_file(manifest.trials[0], options.segments))
    if isinstance(options.layout, ForcePlateColumns):
        body = one_segment_body(body)
    model = model_named(options.model)
    for name in options.per_condition:
        try:
            resolve_parameter(model, body, name)
        except PostureIdError as exc:
            raise PostureIdError(f"the per-condition parameter {exc}") from None


def _task(entry: TrialEntry, options: StudyOptions) -> dict:
    """A trial's task: its file (its bytes too for a cluster), its body's URDF text, how
    it is read."""
    urdf = _body_file(entry, options.segments)
    task = {"name": str(entry.file), "file_name": entry.file.name,
            "urdf": urdf.read_text(), "urdf_name": urdf.name, "layout": options.layout,
            "frf": options.frf, "subject": entry.subject, "condition": entry.condition}
    if options.scheduler:
        task["bytes"] = entry.file.read_bytes()
    return task


@dataclass(frozen=True)
class StudyResult(Result):
    """What a study run made.

    Attributes:
        out: the folder. subjects: (N,) in the manifest's order. conditions: (C,).
        trial_rows: ``trials.csv``'s rows. subject_rows: each subject's fit's status.
        summary_rows: ``summary.csv``'s rows (per subject: the shared parameters, and per
        condition the per-condition ones and the body-COM gain and phase).
        paired: {"A vs B": {"frf": the FRF test's JSON, "parameters": the per-condition
        parameters' test's JSON}} for each pair of conditions every subject has.
        failed: {trial or subject: why}. doubtful: the subjects whose fit's verdict is
        doubtful. notices: what the study assumed, left out or did again (a manifest's
        encoding, a subject without a condition, a fit made again, a trial no longer
        named). trial_notices: what reading each trial with an FRF noticed (its stimulus,
        encoding, a drop-out), in the manifest's order, each naming its file.
    """

    out: Path
    subjects: tuple[str, ...]
    conditions: tuple[str, ...]
    trial_rows: tuple[CohortRow, ...]
    subject_rows: tuple[CohortRow, ...]
    summary_rows: tuple[dict, ...] = ()
    paired: dict = field(default_factory=dict)
    failed: dict = field(default_factory=dict)
    doubtful: tuple[str, ...] = ()
    notices: tuple[str, ...] = ()
    trial_notices: tuple[str, ...] = ()

    @property
    def answered_doubtfully(self) -> bool:
        """Whether the study should not be used as it stands: a trial or subject without
        an answer, or a subject whose fit is doubtful (the exit status 1)."""
        return bool(self.failed or self.doubtful)

    def to_dict(self) -> dict:
        return {"out": str(self.out), "subjects": list(self.subjects),
                "conditions": list(self.conditions),
                "summary": list(self.summary_rows),
                "paired": {k: {"frf_p": v.get("frf", {}).get("p_value"),
                               "parameters": {p["parameter"]: p["p_value"] for p in
                                              v.get("parameters", {}).get("parameters", [])}}
                           for k, v in self.paired.items()},
                "failed": self.failed, "doubtful": list(self.doubtful),
                "notices": list(self.notices)}

    def summary(self) -> str:
        done = sum(r.finished for r in self.trial_rows)
        fitted = sum(r.finished for r in self.subject_rows)
        lines = [f"study in {self.out}: {len(self.subjects)} subject(s), conditions "
                 f"{', '.join(self.conditions)}; {done} of {len(self.trial_rows)} trial "
                 f"FRF(s), {fitted} of {len(self.subject_rows)} subject fit(s)"]
        for pair, tests in self.paired.items():
            frf = tests.get("frf")
            if frf:
                lines.append(f"  {pair}, paired, the whole body-COM FRF: p = "
                             f"{frf['p_value']:.4f}")
            for p in (tests.get("parameters") or {}).get("parameters", []):
                lines.append(f"  {pair}, paired, {p['parameter']}: {p['mean_a']:.4g} against "
                             f"{p['mean_b']:.4g} (difference {p['difference']:.4g}), p = "
                             f"{p['p_value']:.4f}")
        lines += [f"  {k}: {v}" for k, v in self.failed.items()]
        if self.doubtful:
            lines.append(f"  doubtful: the fit of {', '.join(self.doubtful)} (its verdict in "
                         "fits/<subject>.json): do not use as it stands")
        return "\n".join(lines)

    def plot(self, path=None, ax=None):
        from posture_id.plotting import plot_study_conditions

        return plot_study_conditions(self, path=path, ax=ax)


def _run(journal: Journal, keys: list[Path], tasks: dict, fn, options: StudyOptions,
         progress: Progress | None, unit: str) -> None:
    """``fn`` over the tasks ``journal`` still has to do, in parallel."""
    from posture_id.executors import executor_for

    todo = journal.plan(keys)
    done = len(keys) - len(todo)
    report(progress, done, len(keys), unit)
    if not todo:
        return
    with executor_for(options.scheduler, options.workers, processes=True) as pool:
        for key, result in pool.unordered(fn, [tasks[k.name] for k in todo]):
            journal.record(Path(key["key"]), result)
            done += 1
            report(progress, done, len(keys), unit)


def run_study(manifest: StudyManifest, out: str | Path, options: StudyOptions | None = None,
              progress: Progress | None = None) -> StudyResult:
    """The study ``manifest`` names, into ``out`` (the module doc).

    Args:
        manifest: the study (:func:`~posture_id.manifest.reading.read_manifest`).
        out: the results folder (made; a study started again goes on there).
        options: how the trials are read, the model and its per-condition parameters,
            the FRFs, the paired tests, where the work runs (default
            :class:`StudyOptions`).
        progress: told each trial's FRF and each subject's fit as they finish.
    Returns:
        :class:`StudyResult`.
    """
    options = options or StudyOptions()
    out = Path(out)
    manifest = weighed(manifest, options)
    if options.model is not None and options.per_condition:
        _check_per_condition(manifest, options)
    keys = {e.key: e for e in manifest.trials}
    trial_keys = [Path(f"{k}.trial") for k in keys]
    frf_journal = Journal(out / "frf", CohortTask("frequencies_hz",
                                                  lambda key: options.frf_record(
                                                      keys[key.stem]),
                                                  _trial_row))
    tasks = {f"{k}.trial": {**_task(e, options), "key": f"{k}.trial"}
             for k, e in keys.items()}
    _run(frf_journal, trial_keys, tasks, _trial_frf, options, progress, "trial FRF")
    trial_rows = frf_journal.rows(trial_keys)
    failed = dict(frf_journal.failed)
    notices = [*manifest.notices, *_left_out(out, keys, manifest.subjects),
               *_missing_conditions(manifest)]
    subject_rows = ()
    fits = {}
    if options.model is not None:
        fit_journal = Journal(out / "fits", CohortTask(
            "shared", lambda key: options.fit_record(manifest.of(key.stem)), _fit_row))
        subject_keys = [Path(f"{s}.subject") for s in manifest.subjects]
        subject_tasks = {
            f"{s}.subject": {"key": f"{s}.subject", "subject": s, "model": options.model,
                             "per_condition": options.per_condition,
                             "trials": [tasks[f"{e.key}.trial"] for e in manifest.of(s)]}
            for s in manifest.subjects}
        _run(fit_journal, subject_keys, subject_tasks, _subject_fit, options, progress,
             "subject fit")
        subject_rows = tuple(fit_journal.rows(subject_keys))
        failed.update(fit_journal.failed)
        notices += [f"{out / 'fits' / (k.removesuffix('.subject') + '.json')}: "
                    f"{', '.join(why)} changed since that fit: {k.removesuffix('.subject')} "
                    "fitted again" for k, why in fit_journal.changed.items()]
        fits = {r.recording.removesuffix(".subject"): json.loads(
            fit_journal.target(Path(r.recording)).read_text()) for r in subject_rows
            if r.finished}
    frfs = {k.name.removesuffix(".trial"): json.loads(frf_journal.target(k).read_text())
            for k, r in zip(trial_keys, trial_rows, strict=True) if r.finished}
    curves = {(s, c): _condition_frf(manifest, frfs, s, c)
              for s in manifest.subjects for c in manifest.conditions}
    rows = _subject_summary(manifest, curves, fits, subject_rows)
    fields = list(dict.fromkeys(k for r in rows for k in r))
    _write_csv(out / "summary.csv", rows, fields)
    write_summary(out / "trials.csv", list(trial_rows),
                  list(dict.fromkeys(k for r in trial_rows for k in r)))
    paired = _paired_tests(manifest, curves, fits, options, out)
    doubtful = tuple(subject for subject, fit in fits.items()
                     if (fit.get("trust") or {}).get("level") == "doubtful")
    result = StudyResult(out, manifest.subjects, manifest.conditions, tuple(trial_rows),
                         tuple(subject_rows), tuple(rows), paired, failed, doubtful,
                         tuple(notices), tuple(n for data in frfs.values()
                                               for n in data.get("notices", ())))
    result.to_json(out / "study.json")
    return result


def _left_out(out: Path, keys: dict, subjects: tuple[str, ...]) -> list[str]:
    """The notices of results in ``out`` of trials or subjects the manifest no longer
    names (kept on disk, left out of the summary and the tests)."""
    said = []
    for folder, named, what in (("frf", set(keys), "trial"), ("fits", set(subjects),
                                                              "subject")):
        stale = sorted(p.name for p in (out / folder).glob("*.json") if p.stem not in named)
        if stale:
            listed = ", ".join(stale[:4]) + (f" and {len(stale) - 4} more"
                                             if len(stale) > 4 else "")
            said.append(f"{out / folder}: {listed}: of a {what} the manifest no longer names; "
                        "kept, left out of the summary and the paired tests")
    return said


def _missing_conditions(manifest: StudyManifest) -> list[str]:
    """A notice per subject without a trial in one of the conditions."""
    said = []
    for subject in manifest.subjects:
        has = {t.condition for t in manifest.of(subject)}
        missing = [c for c in manifest.conditions if c not in has]
        if missing and len(manifest.conditions) > 1:
            said.append(f"{manifest.path}: subject {subject} has no "
                        f"{' and no '.join(missing)} trial: left out of the paired tests "
                        f"with {', '.join(missing)}")
    return said


def _trial_row(data: dict) -> dict:
    """trials.csv: the subject, condition, frequencies and the body-COM gain and phase."""
    channel = data["channels"].get(COM_CHANNEL) or next(iter(data["channels"].values()))
    return {"subject": data.get("subject"), "condition": data.get("condition"),
            "frequencies_hz": " ".join(f"{f:.4g}" for f in data["frequencies_hz"]),
            "gain": " ".join(f"{g:.4g}" for g in channel["gain"]),
            "phase_deg": " ".join(f"{p:.4g}" for p in channel["phase_deg"]),
            "locked_share": channel.get("locked_share")}


def _fit_row(data: dict) -> dict:
    return {"trust": (data.get("trust") or {}).get("level", "")}


def _write_csv(path: Path, rows: list[dict], fields: list[str]) -> None:
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=fields, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    atomic_write_text(path, text.getvalue())


def _condition_frf(manifest: StudyManifest, frfs: dict, subject: str, condition: str
                   ) -> dict[float, complex]:
    """{frequency: H} of the subject's body-COM FRF in a condition, its trials' driven
    frequencies together (a frequency two trials share: their mean)."""
    points: dict[float, list[complex]] = {}
    for entry in manifest.of(subject):
        data = frfs.get(entry.key)
        if entry.condition != condition or data is None:
            continue
        channel = data["channels"].get(COM_CHANNEL) or next(iter(data["channels"].values()))
        for f, re, im in zip(data["frequencies_hz"], channel["re"], channel["im"],
                             strict=True):
            points.setdefault(round(f, 6), []).append(complex(re, im))
    return {f: complex(np.mean(v)) for f, v in sorted(points.items())}


def _subject_summary(manifest: StudyManifest, curves: dict, fits: dict,
                     subject_rows) -> list[dict]:
    """summary.csv: per subject its fit's shared parameters and per condition its
    per-condition parameters and its body-COM gain and phase at each frequency
    (``curves``: {(subject, condition): :func:`_condition_frf`})."""
    status = {r.recording.removesuffix(".subject"): r.status for r in subject_rows}
    rows = []
    for subject in manifest.subjects:
        row: dict = {"subject": subject, "status": status.get(subject, ""),
                     "trials": len(manifest.of(subject))}
        fit = fits.get(subject)
        if fit is not None:
            row["trust"] = (fit.get("trust") or {}).get("level", "")
            for name, value in fit["shared"].items():
                low, high = fit["intervals"]["shared"][name]
                row.update({name: _sig(value), f"{name} low": _sig(low),
                            f"{name} high": _sig(high)})
        for condition in manifest.conditions:
            if fit is not None and condition in fit["per_condition"]:
                for name, value in fit["per_condition"][condition].items():
                    low, high = fit["intervals"]["per_condition"][condition][name]
                    row.update({f"{name} [{condition}]": _sig(value),
                                f"{name} low [{condition}]": _sig(low),
                                f"{name} high [{condition}]": _sig(high)})
            for f, h in curves[subject, condition].items():
                row[f"gain {f:g} Hz [{condition}]"] = _sig(abs(h))
                row[f"phase {f:g} Hz [{condition}]"] = _sig(np.degrees(np.angle(h)))
        rows.append(row)
    return rows


def _sig(x) -> float | None:
    return None if x is None or not np.isfinite(x) else float(f"{float(x):.5g}")


def _paired_tests(manifest: StudyManifest, curves: dict, fits: dict, options: StudyOptions,
                  out: Path) -> dict:
    """Each pair of conditions: the paired test of the subjects' body-COM FRFs (at the
    frequencies every subject has in both) and of their per-condition parameters;
    written to ``paired/<A>_vs_<B>.json``."""
    from posture_id.norms.norm import FrfSet
    from posture_id.norms.paired import compare_paired, compare_paired_parameters
    from posture_id.norms.parameters import IdentifiedGroup

    conditions = manifest.conditions
    results = {}
    for i, a in enumerate(conditions):
        for b in conditions[i + 1:]:
            tests: dict = {}
            both = [s for s in manifest.subjects if curves[s, a] and curves[s, b]]
            if len(both) >= 2:
                pair = {c: [curves[s, c] for s in both] for c in (a, b)}
                common = sorted(set.intersection(*(set(h) for c in (a, b)
                                                   for h in pair[c])))
                if common:
                    sets = [FrfSet(np.array(common), np.array([[[h[f]] for f in common]
                                                                for h in pair[c]]),
                                   (COM_CHANNEL,), tuple(both)) for c in (a, b)]
                    tests["frf"] = compare_paired(*sets, names=(a, b),
                                                  permutations=options.permutations
                                                  ).to_dict()
            fitted = [s for s in manifest.subjects
                      if s in fits and a in fits[s]["per_condition"]
                      and b in fits[s]["per_condition"]]
            if len(fitted) >= 2 and options.per_condition:
                groups = []
                for c in (a, b):
                    values = {n: np.array([fits[s]["per_condition"][c][n] for s in fitted])
                              for n in fits[fitted[0]]["per_condition"][c]}
                    sds = {n: np.array([fits[s]["standard_errors"]["per_condition"][c][n]
                                        for s in fitted]) for n in values}
                    groups.append(IdentifiedGroup(values, sds, tuple(fitted)))
                tests["parameters"] = compare_paired_parameters(
                    *groups, names=(a, b), permutations=options.permutations).to_dict()
            if tests:
                name = f"{a} vs {b}"
                results[name] = tests
                safe = "".join(ch if ch.isalnum() or ch in "-_" else "_"
                               for ch in f"{a}_vs_{b}")
                (out / "paired").mkdir(parents=True, exist_ok=True)
                atomic_write_text(out / "paired" / f"{safe}.json",
                                  json.dumps(jsonable(tests), indent=2) + "\n")
    return results
