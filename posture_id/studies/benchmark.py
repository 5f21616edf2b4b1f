"""The CNN against the optimiser, measured: accuracy, failures and time per recording.

On ``trials`` held-out simulated recordings (docs/model.md §5 parameters drawn from a seed no data
set uses; stable trials only), in each condition: clean sway at each sensor-noise level
(white, on the segment angles), and, with ``people_like``, the same subjects with motor
noise that leaves a share drawn per recording from :data:`PEOPLE_LIKE_SHARE` of their
body COM sway stimulus-locked (:func:`~posture_id.simulation.subjects.people_like`, 0.05°
sensor noise), every method identifies every recording:

- ``cnn``: the bundled universal network alone;
- ``paper-cnn``: the paper's spectrogram CNN, the body's per-body specialist
  (``posture_id/learning/models/<body>``; bodies with one only);
- ``fit``: least squares from the body's defaults;
- ``hybrid``: least squares started from the universal network's answer;
- ``auto``: ``identify``'s default (docs/identify.md).

Each worker process loads the body and the network once. Per method and noise level: the
mean absolute error of each normalised parameter (|p̃ − p̃_true|, medians too), class
accuracy, E_rel of the body sway re-simulated with the identified parameters against the
noise-free truth (docs/model.md §7), how many recordings end far from the truth (a wrong class or
E_rel above :data:`FAR_E_REL`: a local minimum for the fits), and two times per
recording: identifying (the CNN and/or least squares) and the whole ``identify`` call
(with the checks and the re-simulation every method shares). Recordings are identified in
parallel processes, one per core, each on one thread.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, fields, replace
from pathlib import Path

import numpy as np

from posture_id.bodies.body import Body, load_body
from posture_id.dec.parameters import ParameterArrays, default_parameters, normalise
from posture_id.dec.prior import sample_parameters
from posture_id.errors import PostureIdError, SimulationError
from posture_id.executors import LocalExecutor
from posture_id.fileio import Result, atomic_write_text, json_text, jsonable
from posture_id.identify import Method
from posture_id.identify.networks import network_for
from posture_id.learning.bundled import MODELS_DIR
from posture_id.learning.model_files import SIDECAR
from posture_id.plotting import plot_benchmark
from posture_id.progress import Progress, report
from posture_id.simulation.batch import simulate, simulate_batch
from posture_id.simulation.metrics import sway_errors
from posture_id.studies.journal import Journal
from posture_id.studies.workers import worker_identifier

__all__ = ["BenchmarkReport", "MethodStatistics", "run_benchmark", "FAR_E_REL", "JOURNAL",
           "METHODS", "PAPER_CNN", "PEOPLE_LIKE", "PEOPLE_LIKE_SHARE"]

#: A result whose re-simulated body sway differs from the truth's by more than this
#: (relative) is counted as ending far from the truth.
FAR_E_REL = 0.10
#: The file in the report folder that finished identifications are appended to.
JOURNAL = "cnn_vs_optimizer.journal.jsonl"
#: The paper's spectrogram CNN: the body's per-body specialist, alone.
PAPER_CNN = "paper-cnn"
#: Every method, by its label in the report, in the report's order.
METHODS = (Method.CNN.value, PAPER_CNN, Method.FIT.value, Method.HYBRID.value,
           Method.AUTO.value)
#: The people-like condition's label, and the range its locked shares are drawn from.
PEOPLE_LIKE = "people-like"
PEOPLE_LIKE_SHARE = (0.15, 0.40)
#: The people-like condition's white sensor noise, degrees.
PEOPLE_LIKE_SENSOR_DEG = 0.05


def specialist_folder(body: Body) -> Path:
    """The per-body specialist (the paper's spectrogram CNN) shipped for ``body``."""
    if not _has_specialist(body):
        raise PostureIdError(f"{PAPER_CNN}: no per-body specialist is shipped for body "
                             f"{body.name!r} (posture_id/learning/models/): leave it out "
                             f"of --methods")
    return MODELS_DIR / body.name


def _has_specialist(body: Body) -> bool:
    return (MODELS_DIR / body.name / SIDECAR).is_file()


def condition_label(condition: float | str) -> str:
    """How the report names a condition: a sensor-noise level, or people-like sway."""
    if condition == PEOPLE_LIKE:
        low, high = PEOPLE_LIKE_SHARE
        return (f"People-like sway ({100 * low:g}–{100 * high:g} % of the body COM sway "
                f"locked, {PEOPLE_LIKE_SENSOR_DEG:g}° sensor noise)")
    return f"Sensor noise {condition:g}°"


def _lowered(label: str) -> str:
    """A label inside a sentence: its first letter in lower case."""
    return label[:1].lower() + label[1:]


def _short(condition: float | str) -> str:
    return condition if isinstance(condition, str) else f"{condition:g}°"


def _held_out(body: Body, trials: int, seed: int) -> ParameterArrays:
    rng = np.random.default_rng(np.random.SeedSequence([seed, 7919]))
    params = sample_parameters(body, 3 * trials, rng)
    batch = simulate_batch(body, params)
    keep = np.flatnonzero(batch.stable)[:trials]
    return type(params)(**{f: getattr(params, f)[keep] for f in params.FIELDS})


def _recording(body: Body, truth, condition: float | str, seed: int):
    """(the recording, the noise-free truth's simulation) of one condition."""
    if condition == PEOPLE_LIKE:
        from posture_id.simulation.stimulus import prts
        from posture_id.simulation.subjects import people_like

        share = float(np.random.default_rng([seed, 4049]).uniform(*PEOPLE_LIKE_SHARE))
        subject = people_like(body, truth, prts(), share, seed, PEOPLE_LIKE_SENSOR_DEG)
        return subject.recording, subject.locked
    clean = simulate(body, truth)
    recording = clean.to_recording()
    if condition > 0:
        recording = recording.with_sensor_noise(condition, seed)
    return recording, clean


def _one(task: tuple) -> dict:
    """Identify one recording with one method (a worker process)."""
    urdf, arrays, index, condition, method, seed = task
    if method == PAPER_CNN:
        identifier = worker_identifier(urdf, Method.CNN.value,
                                       str(specialist_folder(load_body(urdf))))
    else:
        identifier = worker_identifier(urdf, method)
    body = identifier.body
    truth = ParameterArrays(**arrays).trial(0, body.joint_names)
    base = {"index": index, "noise_deg": condition, "method": method}
    try:
        recording, clean = _recording(body, truth, condition, seed)
    except SimulationError as exc:  # the subject falls with its motor noise: no recording
        return {**base, "skipped": str(exc)}
    start = time.perf_counter()
    result = identifier.identify(replace(recording, name=f"trial {index}"))
    seconds = time.perf_counter() - start
    # E_rel against the noise-free truth's sway, on the same tilt
    sway_truth = clean.alpha[:, 0]
    e_rel = float(sway_errors(sway_truth, result.sway_resimulated[: len(sway_truth)])[1])
    defaults_norm = normalise(truth, default_parameters(body))
    error = np.abs(result.normalised[:, :4] - defaults_norm[:, :4])
    correct = [result.parameters[j].controls == truth[j].controls for j in body.joint_names]
    row = {**base, "seconds": seconds,
           "identification_seconds": result.identification_time_s, "e_rel": e_rel,
           "abs_error": error.tolist(), "classes_correct": correct,
           "relaxed": result.relaxed_refit}
    if result.verdict is not None:
        row.update(result.verdict.benchmark_fields())
    if result.intervals is not None:  # is the truth inside each 90 % interval?
        iv = result.intervals
        true = defaults_norm[:, :4]
        row["inside_interval"] = ((iv.lower <= true) & (true <= iv.upper)).tolist()
        row["interval_method"] = iv.method
    return row


@dataclass(frozen=True)
class MethodStatistics:
    """One method at one sensor-noise level over the benchmark's recordings.

    Attributes:
        noise_deg: the condition: sensor noise SD, degrees, or :data:`PEOPLE_LIKE`.
        method: the method's label (:data:`METHODS`). recordings: how many.
        mean_abs_error, median_abs_error: (N, 4) |error| of K̃p, K̃i, K̃d, Δ̃ per module.
        class_accuracy: share of classes right. e_rel_median, e_rel_p90: E_rel (fraction).
        far_from_truth: recordings with a wrong class or E_rel above :data:`FAR_E_REL`.
        seconds_median, seconds_mean: the whole call, s. identification_seconds_median,
        identification_seconds_mean: identifying alone, s.
        interval_coverage: (N, 4) share of truths inside the 90 % intervals (None without
            intervals); interval_method, interval_recordings: their kind and count.
        doubtful_far, doubtful_right: of the recordings far from the truth / not far, how
            many the trust verdict called doubtful (None without verdicts).
        relaxed: recordings the hybrid fitted again with its classes relaxed.
    """

    noise_deg: float | str
    method: str
    recordings: int
    mean_abs_error: np.ndarray
    median_abs_error: np.ndarray
    class_accuracy: float
    e_rel_median: float
    e_rel_p90: float
    far_from_truth: int
    seconds_median: float
    seconds_mean: float
    identification_seconds_median: float
    identification_seconds_mean: float
    interval_coverage: np.ndarray | None = None
    interval_method: str | None = None
    interval_recordings: int = 0
    doubtful_far: int | None = None
    doubtful_right: int | None = None
    relaxed: int = 0

    @classmethod
    def of_rows(cls, noise: float | str, method: str, rows: list[dict]) -> MethodStatistics:
        """The statistics of ``rows`` (one per recording) of one condition and method."""
        err = np.array([r["abs_error"] for r in rows])  # (R, N, 4)
        e_rel = np.array([r["e_rel"] for r in rows])
        correct = np.array([r["classes_correct"] for r in rows])
        far = (~correct.all(axis=1)) | ~(e_rel <= FAR_E_REL)
        seconds = [r["seconds"] for r in rows]
        identifying = [r["identification_seconds"] for r in rows]
        inside = [r["inside_interval"] for r in rows if "inside_interval" in r]
        judged = all("doubtful" in r for r in rows)
        doubtful = np.array([bool(r.get("doubtful")) for r in rows])
        return cls(
            noise_deg=noise, method=method, recordings=len(rows),
            mean_abs_error=err.mean(axis=0), median_abs_error=np.median(err, axis=0),
            class_accuracy=float(correct.mean()), e_rel_median=float(np.median(e_rel)),
            e_rel_p90=float(np.percentile(e_rel, 90, method="higher")),
            far_from_truth=int(far.sum()), seconds_median=float(np.median(seconds)),
            seconds_mean=float(np.mean(seconds)),
            identification_seconds_median=float(np.median(identifying)),
            identification_seconds_mean=float(np.mean(identifying)),
            interval_coverage=np.mean(inside, axis=0) if inside else None,
            interval_method=rows[0].get("interval_method") if inside else None,
            interval_recordings=len(inside),
            doubtful_far=int((doubtful & far).sum()) if judged else None,
            doubtful_right=int((doubtful & ~far).sum()) if judged else None,
            relaxed=sum(bool(r.get("relaxed")) for r in rows))

    def to_dict(self) -> dict:
        """JSON-ready: every field."""
        return jsonable({f.name: getattr(self, f.name) for f in fields(self)})


@dataclass(frozen=True)
class BenchmarkReport(Result):
    """Per-recording rows and their statistics (see the module doc)."""

    body: str
    joints: tuple[str, ...]
    trials: int
    noise_levels: tuple[float | str, ...]
    rows: tuple[dict, ...]
    workers: int

    @classmethod
    def from_json(cls, path: str | Path) -> BenchmarkReport:
        """The report its ``cnn_vs_optimizer.json`` holds (an E_rel written as null, a
        re-simulation that fell, read back as infinite): remade without running again."""
        import json

        data = json.loads(Path(path).read_text(encoding="utf-8"))
        rows = tuple({**r, "e_rel": math.inf} if "e_rel" in r and r["e_rel"] is None else r
                     for r in data["rows"])
        return cls(data["body"], tuple(data["joints"]), data["trials"],
                   tuple(data["noise_levels"]), rows, data["workers"])

    def _rows(self, noise: float | str, method: str) -> list[dict]:
        return [r for r in self.rows if r["noise_deg"] == noise and r["method"] == method
                and "skipped" not in r]

    @property
    def skipped(self) -> int:
        """Recordings not made: the people-like subject fell with its motor noise (each
        counted once, not per method)."""
        return len({(r["noise_deg"], r["index"]) for r in self.rows if "skipped" in r})

    def statistics(self) -> dict[tuple[float | str, str], MethodStatistics]:
        """Every (condition, method) that has rows, in the order of the report."""
        return {(noise, method): MethodStatistics.of_rows(noise, method, rows)
                for noise in self.noise_levels for method in METHODS
                if (rows := self._rows(noise, method))}

    def summary(self) -> str:
        """Per noise level and method: classes, median E_rel, far ones, median time."""
        lines = [f"CNN against the optimiser on {self.body}, {self.trials} recordings"]
        for (noise, method), s in self.statistics().items():
            lines.append(f"  {_short(noise)} {method}: classes {100 * s.class_accuracy:.1f} %, "
                         f"E_rel median {100 * s.e_rel_median:.2f} %, far "
                         f"{s.far_from_truth}/{s.recordings}, "
                         f"{s.identification_seconds_median:.3g} s")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-ready: the set-up, every statistic and every row."""
        return {"body": self.body, "joints": list(self.joints), "trials": self.trials,
                "noise_levels": list(self.noise_levels), "workers": self.workers,
                "far_e_rel": FAR_E_REL,
                "statistics": [s.to_dict() for s in self.statistics().values()],
                "rows": list(self.rows)}

    def to_markdown(self) -> str:
        stats = self.statistics()
        lines = ["# The CNN against the optimiser", "",
                 f"Body `{self.body}`, {self.trials} held-out simulated 121 s recordings "
                 f"(docs/model.md §5 parameters, stable); "
                 f"{'; '.join(_lowered(condition_label(n)) for n in self.noise_levels)}; "
                 f"{self.workers} recordings identified at a time. E_rel: body sway "
                 "re-simulated with the identified parameters against the noise-free truth. "
                 f"Far: a wrong class or E_rel above {100 * FAR_E_REL:g} %. Time: identifying "
                 "(the CNN's features and network; least squares; both for the hybrid) and the "
                 "whole `identify` call, with the checks and the re-simulation every method "
                 "shares; each worker process on one thread. Made by `posture-id network cnn "
                 "benchmark` (`benchmarks/cnn_vs_optimizer.py`).", ""]
        far = {m: sum(s.far_from_truth for (_, method), s in stats.items()
                      if method == m) for m in METHODS}
        total = {m: sum(s.recordings for (_, method), s in stats.items()
                        if method == m) for m in METHODS}
        lines += ["Ending far from the truth, all conditions: " + ", ".join(
            f"{m} {far[m]}/{total[m]}" for m in far if total[m]) + ".", ""]
        if self.skipped:
            lines += [f"{self.skipped} people-like subject(s) fell with their motor noise: "
                      "no recording, left out.", ""]
        for noise in self.noise_levels:
            lines += [f"## {condition_label(noise)}", "",
                      "| method | classes | E_rel median | E_rel 90 % | far | s identifying "
                      "(median) | s whole call (median) | mean \\|error\\| Kp, Ki, Kd, Δ "
                      "(per module) |",
                      "|---|---|---|---|---|---|---|---|"]
            for method in METHODS:
                s = stats.get((noise, method))
                if s is None:
                    continue
                errors = "; ".join(", ".join(f"{e:.3f}" for e in module)
                                   for module in s.mean_abs_error)
                lines.append(f"| {method} | {100 * s.class_accuracy:.1f} % | "
                             f"{100 * s.e_rel_median:.2f} % | {100 * s.e_rel_p90:.1f} % | "
                             f"{s.far_from_truth}/{s.recordings} | "
                             f"{s.identification_seconds_median:.3g} | "
                             f"{s.seconds_median:.3g} | {errors} |")
            cnn, fit, hybrid = (stats.get((noise, m.value)) for m in (Method.CNN, Method.FIT,
                                                                        Method.HYBRID))
            if cnn and fit and hybrid:
                t_cnn, t_fit, t_hybrid = (x.identification_seconds_median
                                          for x in (cnn, fit, hybrid))
                lines += ["", f"Ratios (identifying, medians): least squares from the defaults "
                              f"takes {t_fit / t_cnn:.0f}× the CNN's time "
                              f"({fit.seconds_median / cnn.seconds_median:.0f}× for the "
                              f"whole call); the hybrid is {t_fit / t_hybrid:.2f}× "
                              f"faster than least squares from the defaults; its median E_rel "
                              f"is {_ratio(hybrid.e_rel_median, cnn.e_rel_median)} of "
                              "the CNN's."]
            lines.append("")
        lines += self._coverage_markdown(stats)
        lines += self._verdict_markdown(stats)
        lines += ["![E_rel per method](cnn_vs_optimizer.png)", ""]
        return "\n".join(lines)

    def _verdict_markdown(self, stats: dict[tuple[float | str, str], MethodStatistics]
                          ) -> list[str]:
        """How often the trust verdict called far answers and right ones doubtful."""
        judged = [s for s in stats.values() if s.doubtful_far is not None]
        if not judged:
            return []
        lines = ["## Does the trust verdict know?", "",
                 "Of the answers far from the truth, how many the verdict called doubtful "
                 "(want ≥ 90 %), and of the others (want ≤ 10 %); hybrid: recordings fitted "
                 "again with relaxed classes.", "",
                 "| sensor noise | method | far: doubtful | right: doubtful | relaxed |",
                 "|---|---|---|---|---|"]
        for s in judged:
            right = s.recordings - s.far_from_truth
            lines.append(f"| {_short(s.noise_deg)} | {s.method} | "
                         f"{s.doubtful_far}/{s.far_from_truth} | {s.doubtful_right}/{right} | "
                         + (f"{s.relaxed}/{s.recordings}" if s.method == Method.HYBRID.value
                            else "") + " |")
        far = sum(s.far_from_truth for s in judged)
        right = sum(s.recordings - s.far_from_truth for s in judged)
        lines += ["", f"All: doubtful for {sum(s.doubtful_far for s in judged)} of {far} far "
                      f"answers and {sum(s.doubtful_right for s in judged)} of {right} right "
                      "ones.", ""]
        return lines

    def _coverage_markdown(self, stats: dict[tuple[float | str, str], MethodStatistics]
                           ) -> list[str]:
        """How often each method's 90 % intervals held the truth on these recordings."""
        rows = [s for s in stats.values() if s.interval_coverage is not None]
        if not rows:
            return []
        lines = ["## Do the 90 % intervals hold the truth?", "",
                 "Share of the true values inside each identified parameter's 90 % interval "
                 "(`identify`'s intervals; docs/uncertainty.md). On this few recordings a "
                 "share has a sampling spread of about ±4 points; the calibration report "
                 "(`posture-id network cnn calibrate`, docs/models/tip_default/calibration/) "
                 "checks coverage on 5 398 CNN and 500 least-squares test trials.", "",
                 "| sensor noise | method | intervals | recordings | all | Kp | Ki | Kd | Δ |",
                 "|---|---|---|---|---|---|---|---|---|"]
        for s in rows:
            cov = s.interval_coverage
            lines.append(f"| {_short(s.noise_deg)} | {s.method} | {s.interval_method} | "
                         f"{s.interval_recordings} | {100 * cov.mean():.1f} % | "
                         + " | ".join(f"{100 * c:.1f} %" for c in cov.mean(axis=0)) + " |")
        return lines + [""]

    def write(self, folder: str | Path) -> list[Path]:
        """cnn_vs_optimizer.json, .md and .png in ``folder``; their paths."""
        folder = Path(folder)
        paths = [atomic_write_text(folder / "cnn_vs_optimizer.json", json_text(self.to_dict())),
                 atomic_write_text(folder / "cnn_vs_optimizer.md", self.to_markdown()),
                 folder / "cnn_vs_optimizer.png"]
        self.plot(paths[2])
        return paths

    def plot(self, path=None, ax=None):
        """E_rel and time per recording, a box per condition and method."""
        groups = {}
        for noise in self.noise_levels:
            for method in METHODS:
                rows = self._rows(noise, method)
                if rows:
                    groups[f"{method}\n{_short(noise)}"] = (
                        [min(r["e_rel"], 10.0) for r in rows],
                        [r["identification_seconds"] for r in rows])
        return plot_benchmark(groups, path=path, ax=ax)


def run_benchmark(body: Body | None = None, trials: int = 50,
                  noise_levels: tuple[float, ...] = (0.0, 0.01, 0.05), seed: int = 0,
                  workers: int | None = None, methods=None,
                  progress: Progress | None = None,
                  journal: str | Path | None = None,
                  people_like: bool = False) -> BenchmarkReport:
    r"""Run the benchmark (see the module doc).

    Args:
        body: default the TIP. trials: held-out recordings per condition. noise_levels:
            the clean conditions' sensor noise, degrees. seed: of the held-out subjects.
        workers: processes (default: every core). methods: labels of :data:`METHODS` (or
            :class:`Method`\ s); default all of them (``paper-cnn`` only for a body with a
            shipped specialist). progress: told each identification.
        journal: a JSON-lines file that every finished identification is appended to; a
            run given the journal of an interrupted one with the same body, model, trials
            and seed redoes only what is missing (a journal of another set-up is refused).
        people_like: also the people-like condition (the module doc).
    """
    body = body or load_body()
    if methods is None:
        methods = tuple(m for m in METHODS if m != PAPER_CNN or _has_specialist(body))
    methods = tuple(m.value if isinstance(m, Method) else m for m in methods)
    if PAPER_CNN in methods:
        specialist_folder(body)  # refused before any work when there is none
    conditions = (*noise_levels, *((PEOPLE_LIKE,) if people_like else ()))
    held_out = _held_out(body, trials, seed)
    tasks = []
    for noise in conditions:
        for b in range(held_out.n_trials):
            arrays = {f: getattr(held_out, f)[b : b + 1] for f in held_out.FIELDS}
            for method in methods:
                tasks.append((str(body.urdf_path), arrays, b, noise, method,
                              int(1000 * seed + b)))
    weights = network_for(None, body).model.sidecar["weights_sha256"]
    header = {"format": "posture_id-benchmark-journal", "body_sha256": body.sha256,
              "model_weights_sha256": weights, "trials": trials, "seed": seed}
    book = None if journal is None else Journal(Path(journal), header, _task_key)
    done = {} if book is None else book.read()
    rows = [done[_task_key(t)] for t in tasks if _task_key(t) in done]
    todo = [t for t in tasks if _task_key(t) not in done]
    report(progress, len(rows), len(tasks), "identification")
    workers = workers or os.cpu_count() or 1
    with LocalExecutor(workers, processes=True) as pool:
        for _, row in pool.unordered(_one, todo):
            rows.append(row)
            if book is not None:
                book.append(row)
            report(progress, len(rows), len(tasks), "identification")
    rows.sort(key=lambda r: (conditions.index(r["noise_deg"]), r["index"],
                             methods.index(r["method"])))
    return BenchmarkReport(body.name, body.joint_names, held_out.n_trials, tuple(conditions),
                           tuple(rows), workers)


def _task_key(task_or_row) -> tuple:
    if isinstance(task_or_row, dict):
        noise, index, method = (task_or_row[k] for k in ("noise_deg", "index", "method"))
    else:
        _, _, index, noise, method, _ = task_or_row
    return (noise if isinstance(noise, str) else float(noise), int(index), method)


def _ratio(a: float, b: float) -> str:
    if not (math.isfinite(a) and math.isfinite(b)) or b == 0:
        return "not defined (a median is infinite: half the re-simulations fell)"
    return f"{a / b:.3f}"
