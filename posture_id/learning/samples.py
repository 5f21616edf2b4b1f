"""Training samples from a data set: standardised images and targets, in batches.

Modular layout: one sample per (trial, module): image (3, 51, 51), targets (5,).
Monolithic: one per trial: image (2N − 1, 51, 51), targets (5N,) (module after module).
FRF: one per trial: FRF features (3N, 1, F) (:mod:`posture_id.frf.features`) computed here
from the stored sway plus the trial's sensor noise (seeded by the shard), targets (5N,).
Images are standardised pixel by pixel and channel by channel, targets element by
element, with the training split's statistics (docs/model.md §5–6; ``stats.npz`` of the set; for
FRF features, computed from the training split when training starts).

A split is held in memory when ``buffer_shards`` is 0; otherwise shards are read a few at
a time (in a seeded random order) and the samples of each group shuffled together, so a
data set larger than memory streams from disk.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import torch

from posture_id.dec.parameters import ParameterArrays
from posture_id.frf.features import frf_features
from posture_id.learning.config import Layout, LearningError
from posture_id.learning.data.store import Dataset, with_sensor_noise

__all__ = ["Standardiser", "SplitSamples", "frf_inputs"]

#: Second word of the seed of the sensor noise added to a shard's sway for FRF features.
FRF_NOISE_STREAM = 0x465246


def frf_inputs(data: Dataset, arrays: dict[str, np.ndarray], k: int) -> np.ndarray:
    """(K, 3N, 1, F) FRF features of every used trial of shard ``k`` (``arrays``): its
    stored sway plus white sensor noise of the trial's ``sensor_noise_deg``, drawn from
    ``SeedSequence([k, FRF_NOISE_STREAM])``."""
    stimulus = data.stimulus
    noisy = with_sensor_noise(arrays["theta"].astype(np.float64), arrays["sensor_noise_deg"],
                              np.random.SeedSequence([k, FRF_NOISE_STREAM]))
    return frf_features(data.tilt(noisy.shape[1]), noisy, data.rate_hz, stimulus.period_s,
                        stimulus.periodic_from_s)


@dataclass(frozen=True)
class Standardiser:
    """Training-split statistics of images (C, H, W) and targets (T,), float64."""

    image_mean: np.ndarray
    image_std: np.ndarray
    target_mean: np.ndarray
    target_std: np.ndarray

    @classmethod
    def from_dataset(cls, data: Dataset, layout: Layout) -> Standardiser:
        stats = data.stats()
        if layout is Layout.FRF:
            raw = cls(np.zeros(1), np.ones(1), np.zeros(1), np.ones(1))
            images, _ = SplitSamples(data, "train", layout, raw, buffer_shards=1).arrays()
            return cls(images.mean(axis=0, dtype=np.float64), images.std(axis=0, dtype=np.float64),
                       np.asarray(stats["monolithic_targets_mean"], dtype=np.float64),
                       np.asarray(stats["monolithic_targets_std"], dtype=np.float64))
        if layout is Layout.MODULAR:
            keys = ("modular_mean", "modular_std", "targets_mean", "targets_std")
        else:
            keys = ("monolithic_mean", "monolithic_std", "monolithic_targets_mean",
                    "monolithic_targets_std")
        return cls(*(np.asarray(stats[k], dtype=np.float64) for k in keys))

    def __post_init__(self) -> None:
        # a pixel or target that never varies in training carries no information: scale 1
        for name in ("image_std", "target_std"):
            std = np.asarray(getattr(self, name), dtype=np.float64)
            object.__setattr__(self, name, np.where(std > 1e-12, std, 1.0))

    def images(self, images: np.ndarray) -> np.ndarray:
        """(..., C, H, W) raw → standardised float32."""
        return ((images - self.image_mean) / self.image_std).astype(np.float32)

    def targets(self, targets: np.ndarray) -> np.ndarray:
        """(..., T) raw normalised targets → standardised float32."""
        return ((targets - self.target_mean) / self.target_std).astype(np.float32)

    def raw_targets(self, standardised: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`targets` (float64)."""
        return np.asarray(standardised, dtype=np.float64) * self.target_std + self.target_mean

    def to_tensors(self) -> dict[str, torch.Tensor]:
        return {f"standardiser.{k}": torch.from_numpy(np.ascontiguousarray(getattr(self, k)))
                for k in ("image_mean", "image_std", "target_mean", "target_std")}

    @classmethod
    def from_tensors(cls, tensors: dict[str, torch.Tensor]) -> Standardiser:
        return cls(*(tensors[f"standardiser.{k}"].numpy().astype(np.float64)
                     for k in ("image_mean", "image_std", "target_mean", "target_std")))


class SplitSamples:
    """The samples of one split of a data set.

    Args:
        data: the data set. split: "train", "validation" or "test". layout: modular or
        monolithic. standardiser: the statistics to apply. buffer_shards: 0 = hold the
        split in memory; k = stream k shards at a time.
    """

    def __init__(self, data: Dataset, split: str, layout: Layout, standardiser: Standardiser,
                 buffer_shards: int = 0) -> None:
        self.data = data
        self.layout = layout
        self.standardiser = standardiser
        self.buffer_shards = buffer_shards
        self.n_modules = data.n_segments
        #: per shard, the local indices of this split's trials in it
        self.local = data.split_local(split)
        self.trials = int(sum(len(local) for local in self.local))
        if self.trials == 0:
            raise LearningError(f"{data.path}: the {split} split holds no trials")
        self._memory: tuple[np.ndarray, np.ndarray] | None = None

    def __len__(self) -> int:
        """Samples: trials × N (modular) or trials (monolithic)."""
        return self.trials * (self.n_modules if self.layout is Layout.MODULAR else 1)

    def _load(self, shards: list[int]) -> tuple[np.ndarray, np.ndarray]:
        """Standardised (images, targets) of this split's trials in ``shards``, in order."""
        images, targets = [], []
        key = "modular" if self.layout is Layout.MODULAR else "monolithic"
        for k in shards:
            if not len(self.local[k]):
                continue
            arrays = self.data.load_shard(k)
            x = (frf_inputs(self.data, arrays, k) if self.layout is Layout.FRF
                 else arrays[key])[self.local[k]]
            t = arrays["targets"][self.local[k]]  # (K, N, 5)
            if self.layout is Layout.MODULAR:
                x = x.reshape(-1, *x.shape[2:])
                t = t.reshape(-1, 5)
            else:
                t = t.reshape(len(t), -1)
            images.append(self.standardiser.images(x))
            targets.append(self.standardiser.targets(t))
        if not images:
            return (np.empty((0, 1, 1, 1), np.float32), np.empty((0, 1), np.float32))
        return np.concatenate(images), np.concatenate(targets)

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """All (images, targets) of the split in data-set order (held after the first call
        when ``buffer_shards`` is 0)."""
        if self._memory is not None:
            return self._memory
        out = self._load(list(range(len(self.local))))
        if self.buffer_shards == 0:
            self._memory = out
        return out

    def trial_parameters(self) -> ParameterArrays:
        """(trials, N) parameter arrays of the split's trials, in data-set order."""
        parts = {f: [] for f in ParameterArrays.FIELDS}
        for k, local in enumerate(self.local):
            if not len(local):
                continue
            arrays = self.data.load_shard(k)
            kept = arrays["kept"]
            for f in ParameterArrays.FIELDS:
                parts[f].append(arrays[f][kept][local])
        return ParameterArrays(**{f: np.concatenate(v) for f, v in parts.items()})

    def batches(self, batch_size: int, rng: np.random.Generator | None = None
                ) -> Iterator[tuple[torch.Tensor, torch.Tensor]]:
        """(images (B, C, H, W) channels-last, targets (B, T)) float32 tensors.

        With ``rng`` the samples are shuffled (the whole split in memory, or each group of
        ``buffer_shards`` shards, taken in a shuffled order); without, in data-set order.
        """
        if self.buffer_shards == 0:
            groups = [None]
        else:
            order = (rng.permutation(len(self.local)) if rng is not None
                     else np.arange(len(self.local)))
            groups = [list(order[i : i + self.buffer_shards])
                      for i in range(0, len(order), self.buffer_shards)]
        for group in groups:
            images, targets = self.arrays() if group is None else self._load(group)
            order = rng.permutation(len(images)) if rng is not None else np.arange(len(images))
            for start in range(0, len(order), batch_size):
                pick = order[start : start + batch_size]
                x = torch.from_numpy(images[pick]).contiguous(memory_format=torch.channels_last)
                yield x, torch.from_numpy(targets[pick])
