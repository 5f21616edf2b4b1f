"""Training sets: sharded, seeded, resumable sets of simulated trials, made locally or on a
Dask cluster; a network's features are computed from the sway they store.

Two kinds share the shard store (:mod:`.store`: manifest, shards named by SHA-256, atomic
writes): the paper's sets of one body under one PRTS (:mod:`.trial_config`, what a set
is; :mod:`.trial_shards`, one shard simulated; :mod:`.trial_generation`, making or
finishing a set; :mod:`.runners`, local threads or Dask), and the universal network's
sets of drawn bodies and stimuli (:mod:`.drawn`, with :mod:`.scope` and :mod:`.bodies`).
"""

from posture_id.learning.data.store import Dataset
from posture_id.learning.data.trial_config import PAPER_SPLIT, DatasetConfig, DatasetError
from posture_id.learning.data.trial_generation import generate_dataset

__all__ = ["DatasetConfig", "DatasetError", "PAPER_SPLIT", "Dataset", "generate_dataset"]
