"""Training data: sharded, seeded, resumable data sets of simulated trials and their
spectrogram features (docs/model.md §5–6), made locally or on a Dask cluster.

Modules: :mod:`.config` (what a set is), :mod:`.shards` (one shard: simulate and
featurise), :mod:`.features` (STFT and images), :mod:`.runners` (local threads, Dask),
:mod:`.store` (the directory on disk), :mod:`.generation` (making or finishing a set).
"""

from posture_id.datasets.config import PAPER_SPLIT, DatasetConfig, DatasetError
from posture_id.datasets.features import modular_images, monolithic_images, stft
from posture_id.datasets.generation import generate_dataset
from posture_id.datasets.store import Dataset

__all__ = [
    "DatasetConfig",
    "DatasetError",
    "PAPER_SPLIT",
    "Dataset",
    "generate_dataset",
    "stft",
    "modular_images",
    "monolithic_images",
]
