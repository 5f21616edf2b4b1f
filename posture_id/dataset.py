"""Training data at scale: sampling, generation into shards, splits and statistics.

A data set is a directory::

    manifest.json        what made it (body and its hash, stimulus, options, defaults,
                         sampling, seed, split, counts, package version) and its shards
    shard-00000.npz ...  simulated trials (nothing pickled), written atomically
    split.npz            trial indices of the train / validation / test sets
    stats.npz            standardisation statistics from the training set only

Shard k simulates ``shard_size`` trials with parameters drawn (MODEL §5) from the k-th
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

import hashlib
import json
import math
import os
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from posture_id import __version__
from posture_id.body import Body, load_body
from posture_id.errors import PostureIdError
from posture_id.features import modular_images, monolithic_images, stft
from posture_id.io_utils import atomic_write, atomic_write_text
from posture_id.parameters import ParameterArrays, normalise_arrays
from posture_id.sampling import SIGMA, sample_parameters
from posture_id.simulation import SimulationOptions, simulate_batch
from posture_id.stimulus import prts

__all__ = [
    "DatasetError",
    "DatasetConfig",
    "Dataset",
    "generate_dataset",
    "make_shard",
    "PAPER_SPLIT",
]

FORMAT = "posture_id-dataset"
FORMAT_VERSION = 1
#: The paper's split of 20 730 modular samples (MODEL §5): train / validation / test.
PAPER_SPLIT = (14000 / 20730, 3000 / 20730, 3730 / 20730)
_PARAM_FIELDS = ParameterArrays.FIELDS


class DatasetError(PostureIdError):
    """A data-set directory or request is inconsistent."""


def file_sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 22), b""):
            digest.update(block)
    return digest.hexdigest()


@dataclass(frozen=True)
class DatasetConfig:
    """Everything that determines a data set's content (its identity).

    Attributes:
        trials: kept (stable) trials wanted. seed: root seed. shard_size: simulated trials
        per shard. sigma: σ of the parameter perturbation (MODEL §5). split: fractions of
        kept trials for train / validation / test (default: the paper's).
        amplitude_deg, cycles, states: the PRTS. sway_limit_deg, deadband_rad_s, dt:
        simulation options. body: URDF path (its SHA-256 is checked too).
    """

    trials: int
    body: str
    seed: int = 0
    shard_size: int = 256
    sigma: float = SIGMA
    split: tuple[float, float, float] = PAPER_SPLIT
    amplitude_deg: float = 1.0
    cycles: int = 2
    states: int = 242
    sway_limit_deg: float = 6.0
    deadband_rad_s: float = 0.0003
    dt: float = 0.002

    def __post_init__(self) -> None:
        if self.trials < 3:
            raise DatasetError(f"trials must be ≥ 3 (one per split), got {self.trials}")
        if self.shard_size < 1:
            raise DatasetError(f"shard_size must be ≥ 1, got {self.shard_size}")
        if len(self.split) != 3 or abs(sum(self.split) - 1.0) > 1e-9 or min(self.split) < 0:
            raise DatasetError(f"split must be three fractions summing to 1, got {self.split}")
        object.__setattr__(self, "split", tuple(float(f) for f in self.split))

    def options(self) -> SimulationOptions:
        return SimulationOptions(dt=self.dt, sway_limit_deg=self.sway_limit_deg,
                                 deadband_rad_s=self.deadband_rad_s, workers=1)

    def stimulus(self):
        return prts(amplitude_deg=self.amplitude_deg, cycles=self.cycles, states=self.states)

    def identity(self) -> dict:
        """The arguments that must match for a run to resume (the body by path and hash)."""
        data = asdict(self)
        data["split"] = list(self.split)
        data["body"] = str(Path(self.body).resolve())
        return data


def _shard_seed(seed: int, k: int) -> np.random.SeedSequence:
    return np.random.SeedSequence([seed, 0]).spawn(k + 1)[k]


def make_shard(config: DatasetConfig, k: int, body: Body | None = None) -> dict[str, np.ndarray]:
    """Simulate shard ``k`` and compute its features: a dict of arrays for ``np.savez``.

    Keys: parameter arrays (S, N) of all simulated trials, ``abort_time`` (S,) s (NaN when
    kept), ``max_sway_deg`` (S,), ``kept`` (S,) bool; for the K kept trials only:
    ``theta`` (K, 6051, N) float32 rad, ``alpha_bs`` (K, 6051) float32 rad,
    ``modular`` (K, N, 3, 51, 51) float32, ``monolithic`` (K, 2N−1, 51, 51) float32,
    ``targets`` (K, N, 5) normalised [K̃p, K̃i, K̃d, Δ̃, C].
    """
    body = body or load_body(config.body)
    rng = np.random.default_rng(_shard_seed(config.seed, k))
    params = sample_parameters(body, config.shard_size, rng, sigma=config.sigma)
    batch = simulate_batch(body, params, config.stimulus(), config.options())
    kept = batch.stable
    with np.errstate(invalid="ignore"):
        max_sway = np.degrees(np.nanmax(np.abs(batch.theta), axis=(1, 2)))
    max_sway = np.where(kept, max_sway, config.sway_limit_deg)
    theta = batch.theta[kept]
    spectra = stft(np.moveaxis(theta, 1, 2))  # (K, N, 51, 51)
    tilt_spectrum = stft(batch.tilt)
    targets = normalise_arrays(params, body.default_parameters())[kept]
    out = {f: getattr(params, f) for f in _PARAM_FIELDS}
    out.update(
        abort_time=batch.abort_time,
        max_sway_deg=max_sway,
        kept=kept,
        theta=theta.astype(np.float32),
        alpha_bs=batch.alpha[kept, :, 0].astype(np.float32),
        modular=modular_images(tilt_spectrum, spectra),
        monolithic=monolithic_images(spectra),
        targets=targets,
    )
    return out


def _make_shard_remote(config: DatasetConfig, k: int, urdf_text: str) -> dict[str, np.ndarray]:
    """:func:`make_shard` on a cluster worker, which may not see the body file: the URDF
    text travels with the task."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / Path(config.body).name
        path.write_text(urdf_text)
        return make_shard(config, k, load_body(path))


def _save_npz(path: Path, arrays: dict[str, np.ndarray]) -> None:
    atomic_write(path, lambda tmp: _savez_to(tmp, arrays))


def _savez_to(tmp: Path, arrays: dict[str, np.ndarray]) -> None:
    with open(tmp, "wb") as fh:
        np.savez(fh, **arrays)


def _shard_name(k: int) -> str:
    return f"shard-{k:05d}.npz"


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


@dataclass
class Dataset:
    """A data-set directory (read side). Use :meth:`open`."""

    path: Path
    manifest: dict = field(repr=False)

    @classmethod
    def open(cls, path: str | Path, verify: bool = True) -> Dataset:
        """Open a finished data set; with ``verify``, check every shard's SHA-256."""
        path = Path(path)
        manifest = _read_manifest(path)
        if manifest is None:
            raise DatasetError(f"{path}: not a data set (no manifest.json)")
        if not manifest.get("complete"):
            raise DatasetError(f"{path}: generation did not finish; run the same command again")
        data = cls(path, manifest)
        if verify:
            data.verify()
        return data

    def verify(self) -> None:
        for entry in self.manifest["shards"]:
            _check_shard(self.path, entry)

    @property
    def shards(self) -> list[dict]:
        return self.manifest["shards"]

    @property
    def n_segments(self) -> int:
        return self.manifest["body"]["n_segments"]

    def load_shard(self, k: int) -> dict[str, np.ndarray]:
        """Arrays of shard k; the kept-trial arrays cut to the trials the set uses."""
        entry = self.shards[k]
        with np.load(self.path / entry["file"], allow_pickle=False) as npz:
            arrays = {key: npz[key] for key in npz.files}
        used = entry["used"]
        for key in ("theta", "alpha_bs", "modular", "monolithic", "targets"):
            arrays[key] = arrays[key][:used]
        return arrays

    def iter_shards(self) -> Iterator[dict[str, np.ndarray]]:
        for k in range(len(self.shards)):
            yield self.load_shard(k)

    def split(self) -> dict[str, np.ndarray]:
        """Trial indices (into the kept, used trials in shard order) per set."""
        with np.load(self.path / "split.npz", allow_pickle=False) as npz:
            return {key: npz[key] for key in ("train", "validation", "test")}

    def stats(self) -> dict[str, np.ndarray]:
        with np.load(self.path / "stats.npz", allow_pickle=False) as npz:
            return {key: npz[key] for key in npz.files}


def _read_manifest(path: Path) -> dict | None:
    file = path / "manifest.json"
    if not file.exists():
        return None
    try:
        manifest = json.loads(file.read_text())
    except json.JSONDecodeError as exc:
        raise DatasetError(f"{file}: not valid JSON ({exc})") from None
    if manifest.get("format") != FORMAT:
        raise DatasetError(f"{file}: not a posture_id data-set manifest")
    return manifest


def _check_shard(path: Path, entry: dict) -> None:
    file = path / entry["file"]
    if not file.exists():
        raise DatasetError(f"{file}: shard listed in the manifest is missing")
    if file_sha256(file) != entry["sha256"]:
        raise DatasetError(
            f"{file}: shard is corrupt or truncated (SHA-256 differs from the manifest); "
            "delete it and run the same command again to regenerate it"
        )


def _write_manifest(path: Path, manifest: dict) -> None:
    atomic_write_text(path / "manifest.json", json.dumps(manifest, indent=2) + "\n")


def _new_manifest(config: DatasetConfig, body: Body, body_hash: str) -> dict:
    options = config.options()
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
        "options": {"dt": options.dt, "sample_rate_hz": options.sample_rate_hz,
                    "sway_limit_deg": options.sway_limit_deg,
                    "deadband_rad_s": options.deadband_rad_s},
        "defaults": body.default_parameters().to_dict(),
        "sampling": {
            "sigma": config.sigma,
            "rule": "p = p_default*|1 + X|, X ~ N(0, sigma^2) for kp, ki, kd, delay_s; "
                    "class +1/-1 with probability 1/2; passive terms at defaults",
            "seed": config.seed,
            "shard_seeds": "shard k: numpy.random.SeedSequence([seed, 0]).spawn(k + 1)[k]",
            "split_seed": "numpy.random.SeedSequence([seed, 1])",
        },
        "features": {
            "stft": "MATLAB spectrogram(x, 250, 135, 250, 50), first 51 bins",
            "modular": "(N, 3, 51, 51): |S_above|, |S_below|, wrapped phase difference",
            "monolithic": "(2N-1, 51, 51): |S| of each segment, neighbour phase differences",
            "targets": "(N, 5): kp, ki, kd, delay_s normalised (p - p0)/p0, class C",
        },
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
    manifest = _read_manifest(out) if out.exists() else None
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
        _check_shard(out, entry)
    return body, manifest


def generate_dataset(
    config: DatasetConfig,
    out: str | Path,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Dataset:
    """Generate (or finish) the data set ``config`` into ``out``.

    Args:
        workers: local threads making shards (default: all cores).
        scheduler: address of a Dask distributed scheduler; shards then run as tasks
            there and come back to be written here.
        progress: called with (kept trials so far, trials wanted) as shards complete.
    """
    out = Path(out)
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
        file = out / _shard_name(k)
        _save_npz(file, arrays)
        entries[k] = {"index": k, "file": file.name, "simulated": int(len(arrays["kept"])),
                      "kept": int(arrays["kept"].sum()), "sha256": file_sha256(file)}
        manifest["shards"] = [entries[i] for i in sorted(entries)]
        _write_manifest(out, manifest)
        if progress is not None:
            progress(min(kept_total(), config.trials), config.trials)

    _write_manifest(out, manifest)
    if progress is not None:
        progress(min(kept_total(), config.trials), config.trials)
    runner = _dask_runner(scheduler, config) if scheduler else _local_runner(workers, config, body)
    try:
        next_k = 0
        while needed_shards() is None:
            # estimate how many more shards the wave needs from the acceptance so far
            done = [e for e in entries.values()]
            rate = (sum(e["kept"] for e in done) / sum(e["simulated"] for e in done)
                    if done else 0.75)
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
        close = getattr(runner, "close", None)
        if close is not None:
            close()
    return _finish(config, out, manifest, entries, needed_shards())


class _local_runner:  # noqa: N801 - used like a function
    """Make shards in local threads (the kernel and the FFTs release the GIL).

    At most two shards per worker are in flight, and a shard's arrays are dropped as soon
    as they are written, so memory stays bounded whatever the size of the set.
    """

    def __init__(self, workers: int | None, config: DatasetConfig, body: Body) -> None:
        self.workers = workers or os.cpu_count() or 1
        self.pool = ThreadPoolExecutor(max_workers=self.workers)
        self.config = config
        self.body = body

    def __call__(self, ks: list[int]):
        todo = list(reversed(ks))
        in_flight: dict = {}
        while todo or in_flight:
            while todo and len(in_flight) < 2 * self.workers:
                k = todo.pop()
                in_flight[self.pool.submit(make_shard, self.config, k, self.body)] = k
            done, _ = wait(in_flight, return_when=FIRST_COMPLETED)
            for fut in done:
                k = in_flight.pop(fut)
                yield k, fut.result()

    def close(self) -> None:
        self.pool.shutdown(wait=True, cancel_futures=True)


class _dask_runner:  # noqa: N801 - used like a function
    """Make shards as tasks on a Dask distributed cluster; results are written here.

    Up to two shards per cluster thread are in flight; each is released once written.
    """

    def __init__(self, address: str, config: DatasetConfig) -> None:
        self.urdf_text = Path(config.body).read_text()
        try:
            from distributed import Client
        except ImportError:
            raise DatasetError("--scheduler needs dask.distributed (pip install "
                               "'dask[distributed]')") from None
        try:
            self.client = Client(address, timeout=30)
        except OSError as exc:
            raise DatasetError(f"cannot reach the Dask scheduler at {address} ({exc})") from None
        self.config = config

    def __call__(self, ks: list[int]):
        from distributed import as_completed

        slots = max(2 * sum(self.client.nthreads().values()), 1)
        todo = list(reversed(ks))
        in_flight: dict = {}
        queue = as_completed()
        while todo or in_flight:
            while todo and len(in_flight) < slots:
                k = todo.pop()
                fut = self.client.submit(_make_shard_remote, self.config, k, self.urdf_text,
                                         pure=False)
                in_flight[fut] = k
                queue.add(fut)
            fut = next(queue)
            k = in_flight.pop(fut)
            arrays = fut.result()
            fut.release()
            yield k, arrays

    def close(self) -> None:
        self.client.close()


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
    _save_npz(out / "split.npz", split)
    n = manifest["body"]["n_segments"]
    manifest["split"] = {
        "by": "trial",
        "file": "split.npz",
        **{name: {"trials": int(len(idx)), "modular_samples": int(len(idx) * n)}
           for name, idx in split.items()},
    }
    data = Dataset(out, manifest)
    _save_npz(out / "stats.npz", _statistics(data, split["train"]))
    manifest["stats"] = {"file": "stats.npz", "from": "train"}
    manifest["complete"] = True
    _write_manifest(out, manifest)
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
