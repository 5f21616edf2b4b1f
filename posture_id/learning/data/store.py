"""A data-set directory on disk: manifest, shards, split and statistics (read and write).

    manifest.json        what made it (body and its hash, stimulus, options, defaults,
                         sampling, seed, split, counts, package version) and its shards
    shard-00000.npz ...  simulated trials (nothing pickled), written atomically
    split.npz            trial indices of the train / validation / test sets
    stats.npz            standardisation statistics from the training set only
"""

from __future__ import annotations

import json
import zipfile
from collections.abc import Iterator
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from posture_id.fileio import atomic_write, atomic_write_text, file_sha256, json_text
from posture_id.learning.data.trial_config import DatasetError
from posture_id.plotting import plot_dataset_overview, plot_images
from posture_id.simulation.stimulus import TiltProfile, prts

__all__ = ["Dataset", "FORMAT", "FORMAT_VERSION", "SET_KEYS", "read_manifest", "write_manifest",
           "check_shard", "save_npz", "shard_name", "stimulus_of", "with_sensor_noise"]

FORMAT = "posture_id-dataset"
#: 2: the simulation options are nested under "simulation" in the configuration.
FORMAT_VERSION = 2
#: Arrays every shard holds.
SHARD_ARRAYS = ("kp", "ki", "kd", "delay_s", "sign", "kpas", "bpas", "abort_time",
                "max_sway_deg", "kept", "theta", "alpha_bs", "modular", "monolithic", "targets")
#: Keys every set's manifest has, with their types.
SET_KEYS = {"config": dict, "shards": list, "complete": bool}
#: Keys every paper data set's manifest has (a finished one has more: counts, split).
_MANIFEST_KEYS = {**SET_KEYS, "body": dict, "stimulus": dict, "options": dict}
_SHARD_KEYS = {"index": int, "file": str, "simulated": int, "kept": int, "sha256": str}


def stimulus_of(entry: dict) -> TiltProfile:
    """The PRTS of a data-set manifest's (or a model sidecar's) ``"stimulus"`` entry."""
    return prts(entry["amplitude_deg"], entry["cycles"], entry["states"])


def with_sensor_noise(theta: np.ndarray, sd_deg, seed) -> np.ndarray:
    """Trials' segment angles ``theta`` (T, S, N) rad plus white sensor noise of SD
    ``sd_deg`` (°, one for all or (T,) one per trial), drawn from
    ``np.random.default_rng(seed)`` (a seed sequence, or a generator drawn on)."""
    rng = np.random.default_rng(seed)
    return theta + np.reshape(np.radians(sd_deg), (-1, 1, 1)) * rng.standard_normal(theta.shape)


@dataclass
class Dataset:
    """A data-set directory (read side). Use :meth:`open`."""

    path: Path
    manifest: dict = field(repr=False)

    @classmethod
    def open(cls, path: str | Path, verify: bool = True) -> Dataset:
        """Open a finished data set; with ``verify``, check every shard's SHA-256."""
        path = Path(path)
        manifest = read_manifest(path)
        if manifest is None:
            raise DatasetError(f"{path}: not a data set (no manifest.json)")
        if not manifest.get("complete"):
            raise DatasetError(f"{path}: generation did not finish; run the same command again")
        file = path / "manifest.json"
        for key in ("counts", "split"):
            if not isinstance(manifest.get(key), dict):
                raise DatasetError(f"{file}: a finished manifest has a '{key}' object")
        if not all(isinstance(e.get("used"), int) for e in manifest["shards"]):
            raise DatasetError(f"{file}: every shard entry of a finished set has 'used'")
        data = cls(path, manifest)
        if verify:
            data.verify()
        return data

    def verify(self) -> None:
        """Check that every shard the manifest lists exists with its SHA-256.

        Raises:
            DatasetError: naming a shard that is missing, corrupt or truncated.
        """
        for entry in self.manifest["shards"]:
            check_shard(self.path, entry)

    @property
    def shards(self) -> list[dict]:
        """The manifest's shard entries, in order (file, counts, SHA-256, trials used)."""
        return self.manifest["shards"]

    @property
    def n_segments(self) -> int:
        """N, the segments of the body the set was simulated for."""
        return self.manifest["body"]["n_segments"]

    @cached_property
    def stimulus(self) -> TiltProfile:
        """The PRTS the set's trials were simulated under (:func:`stimulus_of`; made once
        a set: :meth:`tilt` asks for it shard after shard)."""
        return stimulus_of(self.manifest["stimulus"])

    @property
    def rate_hz(self) -> float:
        """The sample rate of the stored sway, Hz."""
        return float(self.manifest["options"]["sample_rate_hz"])

    def tilt(self, samples: int) -> np.ndarray:
        """(samples,) the stimulus's tilt at the stored sway's first sample times, rad."""
        return self.stimulus.angle(np.arange(samples) / self.rate_hz)

    def load_shard(self, k: int, keys: tuple[str, ...] | None = None
                   ) -> dict[str, np.ndarray]:
        """Arrays of shard k; the kept-trial arrays cut to the trials the set uses.
        ``keys``: read only these (the images are most of a shard's bytes)."""
        entry = self.shards[k]
        file = self.path / entry["file"]
        try:
            with np.load(file, allow_pickle=False) as npz:
                arrays = {key: npz[key] for key in npz.files if keys is None or key in keys}
        except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
            raise DatasetError(f"{file}: cannot be read ({type(exc).__name__}: {exc}); check "
                               "the set without --no-verify") from None
        missing = [key for key in (SHARD_ARRAYS if keys is None else keys)
                   if key not in arrays and key not in ("sensor_noise_deg", "motor_noise_deg")]
        if missing:
            raise DatasetError(f"{file}: shard lacks {', '.join(missing)}")
        used = entry["used"]
        # sets made before sensor noise existed are noise-free
        for key in ("sensor_noise_deg", "motor_noise_deg"):
            if keys is None or key in keys:
                arrays.setdefault(key, np.zeros(used))
        for key in ("theta", "alpha_bs", "modular", "monolithic", "targets", "sensor_noise_deg",
                    "motor_noise_deg"):
            if key in arrays:
                arrays[key] = arrays[key][:used]
        return arrays

    def split_local(self, split: str) -> list[np.ndarray]:
        """Per shard, the indices among its used trials of the ``split``'s trials, in
        data-set order."""
        indices = self.split()[split]
        used = np.array([entry["used"] for entry in self.shards])
        offsets = np.concatenate([[0], np.cumsum(used)])
        return [indices[(indices >= offsets[k]) & (indices < offsets[k + 1])] - offsets[k]
                for k in range(len(used))]

    def iter_shards(self) -> Iterator[dict[str, np.ndarray]]:
        """Every shard's arrays (:meth:`load_shard`), one shard at a time, in order."""
        for k in range(len(self.shards)):
            yield self.load_shard(k)

    def split(self) -> dict[str, np.ndarray]:
        """Trial indices (into the kept, used trials in shard order) per set."""
        with np.load(self.path / "split.npz", allow_pickle=False) as npz:
            return {key: npz[key] for key in ("train", "validation", "test")}

    def stats(self) -> dict[str, np.ndarray]:
        """The standardisation statistics (``stats.npz``): means and standard deviations of
        the images and the targets, from the training set only."""
        with np.load(self.path / "stats.npz", allow_pickle=False) as npz:
            return {key: npz[key] for key in npz.files}

    def to_dict(self) -> dict:
        """The manifest (configuration, provenance, counts, split, shards)."""
        return dict(self.manifest)

    def summary(self) -> str:
        """One line: trials used, kept and rejected, shards, body and split."""
        m = self.manifest
        c = m["counts"]
        s = m["split"]
        return (
            f"{self.path}: {c['used']} trials used ({c['kept']} kept of {c['simulated']} "
            f"simulated, {c['rejection_rate']:.1%} rejected) in {len(m['shards'])} shards; body "
            f"{m['body']['name']} ({m['body']['n_segments']} segments); split by trial: "
            + ", ".join(f"{k} {s[k]['trials']} trials = {s[k]['modular_samples']} modular "
                        "samples" for k in ("train", "validation", "test"))
        )

    def overview(self) -> dict[str, np.ndarray]:
        """What the paper's Fig. 2 shows, gathered over all shards.

        Returns: ``kp_normalised`` (K, N) K̃p of the used trials; ``max_sway_deg`` (S,) and
        ``kept`` (S,) bool of every simulated trial; ``modular`` (N, 3, 51, 51) and
        ``monolithic`` (2N−1, 51, 51) images of the first used trial.
        """
        kp, sway, kept = [], [], []
        first: dict[str, np.ndarray] = {}
        for arrays in self.iter_shards():
            kp.append(arrays["targets"][:, :, 0])
            sway.append(arrays["max_sway_deg"])
            kept.append(arrays["kept"])
            if not first and len(arrays["targets"]):
                first = {"modular": arrays["modular"][0], "monolithic": arrays["monolithic"][0]}
        return {"kp_normalised": np.concatenate(kp), "max_sway_deg": np.concatenate(sway),
                "kept": np.concatenate(kept), **first}

    def plot(self, path=None, ax=None, overview: dict | None = None):
        """The sampled K̃p and every simulated trial's largest sway, kept or rejected
        (Fig. 2 analogue); ``overview``: :meth:`overview`, when already gathered."""
        data = overview or self.overview()
        return plot_dataset_overview(data["kp_normalised"], self.manifest["body"]["joints"],
                                     data["max_sway_deg"], data["kept"],
                                     self.manifest["options"]["sway_limit_deg"], path=path,
                                     ax=ax)

    def plot_images(self, path=None, ax=None, overview: dict | None = None):
        """The first used trial's modular and monolithic images."""
        data = overview or self.overview()
        return plot_images(data["modular"], data["monolithic"],
                           self.manifest["body"]["joints"], path=path, ax=ax)

    def write_figures(self, folder: str | Path | None = None) -> tuple[Path, Path]:
        """``dataset_overview.png`` and ``dataset_images.png`` into ``folder`` (default:
        the data-set directory)."""
        folder = Path(folder) if folder is not None else self.path
        overview = folder / "dataset_overview.png"
        images = folder / "dataset_images.png"
        data = self.overview()
        self.plot(overview, overview=data)
        self.plot_images(images, overview=data)
        return overview, images


def read_manifest(path: Path, format: str = FORMAT, version: int | None = FORMAT_VERSION,
                  what: str = "a posture_id data-set manifest", keys: dict = _MANIFEST_KEYS
                  ) -> dict | None:
    """The manifest of the set in ``path`` (None when it has none), checked: JSON, of
    ``format`` (``what`` names it in the refusal) and ``version`` (None: unversioned), with
    ``keys`` of their types and shard entries of a set's.

    Raises:
        DatasetError: naming the file and what is wrong with it.
    """
    file = path / "manifest.json"
    if not file.exists():
        return None
    try:
        manifest = json.loads(file.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise DatasetError(f"{file}: not valid JSON ({exc})") from None
    except OSError as exc:
        raise DatasetError(f"{file}: cannot be read ({exc.strerror})") from None
    if not isinstance(manifest, dict) or manifest.get("format") != format:
        raise DatasetError(f"{file}: not {what}")
    if version is not None and manifest.get("format_version") != version:
        raise DatasetError(
            f"{file}: data-set format version {manifest.get('format_version')!r}; this "
            f"posture_id reads version {version}: generate the set again"
        )
    for key, kind in keys.items():
        if key not in manifest:
            raise DatasetError(f"{file}: the manifest is missing '{key}'")
        if not isinstance(manifest[key], kind):
            raise DatasetError(f"{file}: '{key}' must be a {kind.__name__}, got "
                               f"{type(manifest[key]).__name__}")
    for k, entry in enumerate(manifest["shards"]):
        if not isinstance(entry, dict) or not all(
                isinstance(entry.get(f), t) for f, t in _SHARD_KEYS.items()):
            raise DatasetError(f"{file}: shard entry {k} is not an object with "
                               + ", ".join(f"{f} ({t.__name__})" for f, t in _SHARD_KEYS.items()))
    return manifest


def check_shard(path: Path, entry: dict) -> None:
    file = path / entry["file"]
    if not file.exists():
        raise DatasetError(f"{file}: shard listed in the manifest is missing")
    if file_sha256(file) != entry["sha256"]:
        raise DatasetError(
            f"{file}: shard is corrupt or truncated (SHA-256 differs from the manifest); "
            "delete it and run the same command again to regenerate it"
        )


def write_manifest(path: Path, manifest: dict) -> None:
    atomic_write_text(path / "manifest.json", json_text(manifest))


def save_npz(path: Path, arrays: dict[str, np.ndarray]) -> None:
    atomic_write(path, lambda tmp: _savez_to(tmp, arrays))


def _savez_to(tmp: Path, arrays: dict[str, np.ndarray]) -> None:
    with open(tmp, "wb") as fh:
        np.savez(fh, **arrays)


def shard_name(k: int) -> str:
    return f"shard-{k:05d}.npz"
