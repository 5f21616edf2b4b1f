"""Least squares on a data set's held-out trials, for checking its intervals.

Each of ``count`` trials of a split is made a recording: the stored noise-free segment
angles plus white sensor noise of a chosen SD (seeded by trial and level), on the data
set's PRTS. The CNN identifies it and least squares refines the CNN's answer with its
classes kept (the hybrid's usual route, :func:`posture_id.identify.core._refine`); the row
keeps what coverage needs: the true and fitted normalised parameters, the Gauss-Newton
standard errors (−1 where infinite), the residual RMS, the recording's estimated sensor
noise and the CNN's answer. Trials run in parallel processes (one per core by default),
each with the cores left to it as Jacobian threads (one each when every core has a
process; at most the fit's default), and every finished trial is appended to a journal,
so an interrupted run resumes.
"""

from __future__ import annotations

import functools
import json
import os
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from posture_id.executors import LocalExecutor
from posture_id.fitting.least_squares import fit_recording
from posture_id.fitting.options import FitOptions, FixedClasses
from posture_id.identify import Method
from posture_id.learning.data.store import Dataset
from posture_id.learning.model_files import SIDECAR
from posture_id.progress import Progress, report
from posture_id.recording import Recording
from posture_id.studies.journal import Journal
from posture_id.studies.workers import worker_identifier
from posture_id.trials import prepare_trial
from posture_id.uncertainty.noise import sensor_noise_deg

__all__ = ["FIT_JOURNAL", "held_out_recording", "run_fits", "split_trials"]

#: The journal of finished fits, in the calibration report's folder.
FIT_JOURNAL = "fits.journal.jsonl"


def split_trials(data: Dataset, split: str, count: int) -> list[tuple[int, int]]:
    """(shard, index among the shard's kept trials) of the first ``count`` trials of a
    split, in data-set order."""
    places = [(k, int(i)) for k, local in enumerate(data.split_local(split)) for i in local]
    return places[:count]


def held_out_recording(data: Dataset, shard: int, local: int, noise_deg: float,
                       seed: int) -> tuple[Recording, np.ndarray]:
    """(recording with white sensor noise of ``noise_deg``°, true normalised targets (N, 5))
    of one stored trial."""
    arrays = data.load_shard(shard, keys=("theta", "targets"))
    theta = arrays["theta"][local].astype(np.float64)
    t = np.arange(len(theta)) / data.rate_hz
    recording = Recording(t, data.stimulus.angle(t), theta,
                          tuple(data.manifest["body"]["segments"]), f"trial {shard}:{local}")
    if noise_deg > 0:
        recording = recording.with_sensor_noise(noise_deg, seed)
    return recording, np.asarray(arrays["targets"][local], dtype=np.float64)


@functools.cache
def _dataset(dataset_dir: str) -> Dataset:
    """A worker's data set, opened once."""
    return Dataset.open(dataset_dir, verify=False)


def _one(task: tuple) -> dict:
    """One trial identified by the hybrid (a worker process)."""
    model_dir, dataset_dir, split, position, shard, local, noise_deg, threads = task
    data = _dataset(dataset_dir)
    identifier = worker_identifier(data.manifest["body"]["urdf"], Method.CNN.value, model_dir)
    body = identifier.body
    seed = int(np.random.SeedSequence([shard, local, int(round(1e6 * noise_deg)), 0xC0FE])
               .generate_state(1)[0])
    recording, truth = held_out_recording(data, shard, local, noise_deg, seed)
    start = time.perf_counter()
    trial = prepare_trial(replace(recording, name=f"{split} trial {position}"))
    cnn = identifier.cnn.identify(trial)
    fit = fit_recording(trial, body, cnn.parameters,
                        FitOptions(threads=threads, classes=FixedClasses()))
    return {"split": split, "position": position, "noise_deg": noise_deg,
            "seconds": time.perf_counter() - start, "truth": truth.tolist(),
            "estimate": np.asarray(fit.normalised).tolist(),
            "standard_errors": np.where(np.isfinite(fit.standard_errors_normalised),
                                        fit.standard_errors_normalised, -1.0).tolist(),
            "rms_deg": fit.rms_deg, "converged": fit.converged,
            "noise_estimate_deg": sensor_noise_deg(recording.theta),
            "cnn": np.asarray(cnn.normalised).tolist(),
            "cnn_class_probability": np.asarray(cnn.class_probability).tolist()}


def _key(row: dict) -> tuple:
    return (row["split"], int(row["position"]), float(row["noise_deg"]))


def _task_key(task: tuple) -> tuple:
    """:func:`_key` of the row a task makes."""
    return task[2], task[3], task[6]


def run_fits(model_dir: str | Path, dataset_dir: str | Path, split: str, count: int,
             noise_levels: tuple[float, ...], journal: str | Path,
             workers: int | None = None, progress: Progress | None = None) -> list[dict]:
    """Rows of the first ``count`` trials of ``split`` at every noise level (see the
    module doc); finished rows are read back from ``journal`` (one of another model or data
    set is refused)."""
    data = Dataset.open(dataset_dir, verify=False)
    weights = json.loads((Path(model_dir) / SIDECAR).read_text(encoding="utf-8"))[
        "weights_sha256"]
    header = {"format": "posture_id-fit-journal", "model_weights_sha256": weights,
              "dataset": data.manifest["shards"][0]["sha256"]}
    trials = split_trials(data, split, count)
    cores = os.cpu_count() or 1
    # the cores a process has to itself, up to the fit's default (its prebuilt model)
    threads = max(1, min(FitOptions().threads, cores // (workers or cores)))
    tasks = [(str(model_dir), str(dataset_dir), split, p, k, i, float(noise), threads)
             for noise in noise_levels for p, (k, i) in enumerate(trials)]
    book = Journal(Path(journal), header, _key)
    done = book.read()
    rows = [done[_task_key(t)] for t in tasks if _task_key(t) in done]
    todo = [t for t in tasks if _task_key(t) not in done]
    report(progress, len(rows), len(tasks), "fit")
    with LocalExecutor(workers, processes=True) as pool:
        for _, row in pool.unordered(_one, todo):
            rows.append(row)
            book.append(row)
            report(progress, len(rows), len(tasks), "fit")
    return rows
