"""Training data at scale: sampling, generation into shards, splits and statistics.

A data set is a directory::

    manifest.json        what made it (body and its hash, stimulus, options, defaults,
                         sampling, seed, split, counts, package version) and its shards
    shard-00000.npz ...  simulated trials (nothing pickled), written atomically
    split.npz            trial indices of the train / validation / test sets
    stats.npz            standardisation statistics from the training set only

Shard k simulates ``shard_size`` trials with parameters drawn (docs/model.md §5) from the k-th
child of ``SeedSequence([seed, 0])``, so a shard's bytes depend only on (arguments, k):
never on the number of workers or on the order in which shards finish. Shards are made
in waves until the kept trials reach ``trials``; the set is shards 0..K−1, the last one
used in part; shards past K (made by a parallel wave) are removed at the end.

A killed run started again with the same arguments keeps every shard the manifest lists
(after checking its SHA-256) and makes the rest; the finished directory has the same
bytes as an uninterrupted run. Different arguments, a changed body file or a corrupt
shard stop the run with a one-line error before anything is written.
"""


from __future__ import annotations

import math
import shutil
from dataclasses import asdict
from pathlib import Path

import numpy as np

from posture_id._version import __version__
from posture_id.bodies.body import Body, load_body
from posture_id.dec.parameters import default_parameters
from posture_id.fileio import file_sha256
from posture_id.learning.data.runners import shard_runner
from posture_id.learning.data.store import (
    FORMAT,
    FORMAT_VERSION,
    Dataset,
    check_shard,
    read_manifest,
    save_npz,
    shard_name,
    write_manifest,
)
from posture_id.learning.data.trial_config import DatasetConfig, DatasetError
from posture_id.learning.features.spectrograms import FEATURE_DEFINITION
from posture_id.progress import Progress, report

__all__ = ["generate_dataset"]


#: Simulated trials after which the kept rate is judged, and the least rate accepted.
HOPELESS_AFTER, LEAST_KEPT_RATE = 256, 0.01


def _refuse_hopeless(config: DatasetConfig, simulated: int, rate: float) -> None:
    """Stop when (almost) no trial stays within the sway limit: the set would never end."""
    if simulated < HOPELESS_AFTER or rate >= LEAST_KEPT_RATE:
        return
    limit = config.simulation.sway_limit_deg
    raise DatasetError(
        f"only {100 * rate:.2f} % of the {simulated} trials simulated so far stayed within "
        f"±{limit:g}° (at least {100 * LEAST_KEPT_RATE:g} % is needed): {config.trials} kept "
        "trials are out of reach; check the body and --sway-limit-deg")


class _RunningMoments:
    """Mean and variance over a stream of batches (Chan et al.'s parallel update)."""

    def __init__(self) -> None:
        self.count = 0
        self.mean: np.ndarray | None = None
        self.m2: np.ndarray | None = None

    def update(self, batch: np.ndarray) -> None:
        if len(batch) == 0:
            return
        batch = batch.astype(np.float64)
        n = len(batch)
        mean = batch.mean(axis=0)
        m2 = ((batch - mean) ** 2).sum(axis=0)
        if self.mean is None:
            self.count, self.mean, self.m2 = n, mean, m2
            return
        total = self.count + n
        delta = mean - self.mean
        self.mean = self.mean + delta * (n / total)
        self.m2 = self.m2 + m2 + delta**2 * (self.count * n / total)
        self.count = total

    def std(self) -> np.ndarray:
        return np.sqrt(self.m2 / max(self.count - 1, 1))


def _new_manifest(config: DatasetConfig, body: Body, body_hash: str) -> dict:
    return {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "package_version": __version__,
        "config": config.identity(),
        "body": {
            "urdf": str(Path(config.body).resolve()),
            "sha256": body_hash,
            "name": body.name,
            "n_segments": body.n_segments,
            "segments": list(body.segment_names),
            "joints": list(body.joint_names),
            "mgh": body.mgh.tolist(),
        },
        "stimulus": {"kind": "prts", "states": config.states, "cycles": config.cycles,
                     "amplitude_deg": config.amplitude_deg,
                     "description": config.stimulus().description},
        "options": asdict(config.simulation),
        "defaults": default_parameters(body).to_dict(),
        "sampling": {
            "sigma": config.sigma,
            "rule": "p = p_default*|1 + X|, X ~ N(0, sigma^2) for kp, ki, kd, delay_s; "
                    "class +1/-1 with probability 1/2; passive terms at defaults",
            "seed": config.seed,
            "shard_seeds": "shard k: numpy.random.SeedSequence([seed, 0]).spawn(k + 1)[k]",
            "split_seed": "numpy.random.SeedSequence([seed, 1])",
            "motor_noise": "shard k: levels uniform in [0, motor_noise_deg] and per-trial "
                           "seeds from numpy.random.SeedSequence([seed, 2, k])",
        },
        "features": FEATURE_DEFINITION,
        "shards": [],
        "complete": False,
    }


def _prepare(config: DatasetConfig, out: Path) -> tuple[Body, dict]:
    """Load the body and the manifest to continue, or a new one; refuse any mismatch."""
    body_path = Path(config.body)
    if not body_path.is_file():
        raise DatasetError(f"{body_path}: no such body URDF")
    body_hash = file_sha256(body_path)
    body = load_body(body_path)
    manifest = read_manifest(out) if out.exists() else None
    if manifest is None:
        if out.exists() and any(out.iterdir()):
            raise DatasetError(f"{out}: exists, is not empty and holds no data-set manifest")
        return body, _new_manifest(config, body, body_hash)
    if manifest["config"] != config.identity():
        theirs, ours = manifest["config"], config.identity()
        diff = [k for k in ours if theirs.get(k) != ours[k]]
        raise DatasetError(
            f"{out}: was made with other arguments ({', '.join(diff)} differ); "
            "choose another directory or repeat the original arguments"
        )
    if manifest["body"]["sha256"] != body_hash:
        raise DatasetError(
            f"{out}: the body file {body_path} changed since this data set was started "
            "(SHA-256 differs from the manifest)"
        )
    for entry in manifest["shards"]:
        check_shard(out, entry)
    return body, manifest


def generate_dataset(
    config: DatasetConfig,
    out: str | Path,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: Progress | None = None,
) -> Dataset:
    """Generate (or finish) the data set ``config`` into ``out``.

    Args:
        config: What the set holds (its trials, body, stimulus, noise and seed).
        out: The set's folder (made, or resumed where a run stopped).
        workers: local threads making shards (default: all cores).
        scheduler: address of a Dask distributed scheduler; shards then run as tasks
            there and come back to be written here.
        progress: told the kept trials so far (of those wanted) as shards complete.
    """
    out = Path(out)
    fresh = not out.exists()  # a folder this run makes is this run's to clear away
    body, manifest = _prepare(config, out)
    out.mkdir(parents=True, exist_ok=True)
    entries = {e["index"]: e for e in manifest["shards"]}

    def kept_total() -> int:
        return sum(e["kept"] for e in entries.values())

    def needed_shards() -> int | None:
        """K if shards 0..K−1 already hold enough kept trials, else None."""
        total = 0
        for k in range(len(entries)):
            if k not in entries:
                return None
            total += entries[k]["kept"]
            if total >= config.trials:
                return k + 1
        return None

    def record(k: int, arrays: dict[str, np.ndarray]) -> None:
        file = out / shard_name(k)
        save_npz(file, arrays)
        entries[k] = {"index": k, "file": file.name, "simulated": int(len(arrays["kept"])),
                      "kept": int(arrays["kept"].sum()), "sha256": file_sha256(file)}
        manifest["shards"] = [entries[i] for i in sorted(entries)]
        write_manifest(out, manifest)
        report(progress, min(kept_total(), config.trials), config.trials, "trial")

    write_manifest(out, manifest)
    report(progress, min(kept_total(), config.trials), config.trials, "trial")
    runner, executor = shard_runner(config, body, workers, scheduler)
    try:
        next_k = 0
        while needed_shards() is None:
            # estimate how many more shards the wave needs from the acceptance so far
            done = [e for e in entries.values()]
            simulated = sum(e["simulated"] for e in done)
            rate = sum(e["kept"] for e in done) / simulated if done else 0.75
            try:
                _refuse_hopeless(config, simulated, rate)
            except DatasetError:
                if fresh:  # nothing worth keeping: leave no folder of shards behind
                    shutil.rmtree(out, ignore_errors=True)
                raise
            missing = max(config.trials - kept_total(), 1)
            wave = max(1, math.ceil(missing / max(rate, 0.05) / config.shard_size))
            todo = []
            while len(todo) < wave:
                if next_k not in entries:
                    todo.append(next_k)
                next_k += 1
            for k, arrays in runner(todo):
                record(k, arrays)
    finally:
        executor.close()
    return _finish(config, out, manifest, entries, needed_shards())


def _finish(config: DatasetConfig, out: Path, manifest: dict, entries: dict,
            n_shards: int) -> Dataset:
    """Drop surplus shards, mark how many kept trials each uses, write split and stats."""
    for k in [k for k in entries if k >= n_shards]:
        (out / entries[k]["file"]).unlink(missing_ok=True)
        del entries[k]
    remaining = config.trials
    shards = []
    for k in range(n_shards):
        entry = dict(entries[k])
        entry["used"] = min(entry["kept"], remaining)
        remaining -= entry["used"]
        shards.append(entry)
    manifest["shards"] = shards
    simulated = sum(e["simulated"] for e in shards)
    kept = sum(e["kept"] for e in shards)
    manifest["counts"] = {"simulated": simulated, "kept": kept, "rejected": simulated - kept,
                          "used": config.trials,
                          "rejection_rate": (simulated - kept) / simulated}
    split = _split(config)
    save_npz(out / "split.npz", split)
    n = manifest["body"]["n_segments"]
    manifest["split"] = {
        "by": "trial",
        "file": "split.npz",
        **{name: {"trials": int(len(idx)), "modular_samples": int(len(idx) * n)}
           for name, idx in split.items()},
    }
    data = Dataset(out, manifest)
    save_npz(out / "stats.npz", _statistics(data, split["train"]))
    manifest["stats"] = {"file": "stats.npz", "from": "train"}
    manifest["complete"] = True
    write_manifest(out, manifest)
    return data


def _split(config: DatasetConfig) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(np.random.SeedSequence([config.seed, 1]))
    order = rng.permutation(config.trials)
    n_train = round(config.trials * config.split[0])
    n_val = round(config.trials * config.split[1])
    n_train = min(max(n_train, 1), config.trials - 2)
    n_val = min(max(n_val, 1), config.trials - n_train - 1)
    return {
        "train": np.sort(order[:n_train]),
        "validation": np.sort(order[n_train : n_train + n_val]),
        "test": np.sort(order[n_train + n_val :]),
    }


def _statistics(data: Dataset, train: np.ndarray) -> dict[str, np.ndarray]:
    """Pixel- and channel-wise image statistics and target statistics, training set only."""
    modular, monolithic = _RunningMoments(), _RunningMoments()
    targets_mod, targets_mono = _RunningMoments(), _RunningMoments()
    start = 0
    train_set = np.zeros(data.manifest["config"]["trials"], dtype=bool)
    train_set[train] = True
    for arrays in data.iter_shards():
        used = len(arrays["targets"])
        mask = train_set[start : start + used]
        start += used
        n = arrays["modular"].shape[1]
        modular.update(arrays["modular"][mask].reshape(-1, *arrays["modular"].shape[2:]))
        monolithic.update(arrays["monolithic"][mask])
        targets_mod.update(arrays["targets"][mask].reshape(-1, 5))
        targets_mono.update(arrays["targets"][mask].reshape(-1, n * 5))
    return {
        "modular_mean": modular.mean, "modular_std": modular.std(),
        "monolithic_mean": monolithic.mean, "monolithic_std": monolithic.std(),
        "targets_mean": targets_mod.mean, "targets_std": targets_mod.std(),
        "monolithic_targets_mean": targets_mono.mean,
        "monolithic_targets_std": targets_mono.std(),
        "train_trials": np.array(len(train)),
    }
