"""What a network is and how it is trained: frozen, typed configuration.

:class:`NetworkConfig` fixes the architecture (it is written into every checkpoint and a
checkpoint is refused by code whose architecture differs); :class:`TrainingConfig` the
optimiser, schedule, batches, early stopping and seed.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field

from posture_id.errors import LearningError
from posture_id.frf.features import FRF_FEATURE_DEFINITION
from posture_id.learning.features.spectrograms import FEATURE_DEFINITION

__all__ = [
    "LearningError",
    "Layout",
    "ClassOutput",
    "NetworkConfig",
    "SgdMomentum",
    "AdamWOneCycle",
    "Optimiser",
    "TrainingConfig",
]

#: The sidecar format of the paper CNN's models (:mod:`.checkpoint`).
MODEL_FORMAT = "posture_id-model"


class Layout(enum.Enum):
    """What a network sees. docs/model.md §5–6: spectrograms, one sample per module (3 channels in,
    5 targets out) or one per trial (2N − 1 channels in, 5N targets out). FRF: one sample
    per trial of FRF features (:mod:`posture_id.frf.features`: 3N channels, one row of F
    excited frequencies; 5N targets out)."""

    MODULAR = "modular"
    MONOLITHIC = "monolithic"
    FRF = "frf"


class ClassOutput(enum.Enum):
    """How the class C is predicted.

    REGRESSION: the paper's: C is one more regression target (MSE), read by its sign.
    LOGIT: a logit per module trained with binary cross-entropy beside the MSE of the
    continuous targets; positive logit = COM in space.
    """

    REGRESSION = "regression"
    LOGIT = "logit"


@dataclass(frozen=True)
class NetworkConfig:
    """The CNN: ``len(widths)`` blocks of (3×3 convolution, batch normalisation, ReLU, 2×2
    max pooling), then global average pooling and a head of fully connected layers.

    Attributes:
        layout: modular, monolithic or frf. in_channels: 3 (modular), 2N − 1 (monolithic)
            or 3N (frf).
        modules: modules predicted per sample: 1 (modular) or N (monolithic, frf).
        widths: channels of each block (the paper's figure shows 5 blocks).
        head: widths of the hidden fully connected layers of the head.
        class_output: :class:`ClassOutput`.
        image_size: pixels of the square input image (51, docs/model.md §6); for frf, F, the
            frequencies of the one-row input.
    """

    layout: Layout
    in_channels: int
    modules: int
    widths: tuple[int, ...] = (32, 48, 64, 96, 128)
    head: tuple[int, ...] = (128,)
    class_output: ClassOutput = ClassOutput.LOGIT
    image_size: int = 51

    def __post_init__(self) -> None:
        if not isinstance(self.layout, Layout):
            raise LearningError(f"layout must be a Layout, got {self.layout!r}")
        if not isinstance(self.class_output, ClassOutput):
            raise LearningError(f"class_output must be a ClassOutput, got {self.class_output!r}")
        for name in ("in_channels", "modules", "image_size"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise LearningError(f"{name} must be a positive integer, got {value!r}")
        if not self.widths or any(w < 1 for w in self.widths):
            raise LearningError(f"widths must be positive integers, got {self.widths!r}")
        if any(h < 1 for h in self.head):
            raise LearningError(f"head widths must be positive integers, got {self.head!r}")
        object.__setattr__(self, "widths", tuple(int(w) for w in self.widths))
        object.__setattr__(self, "head", tuple(int(h) for h in self.head))

    @property
    def outputs(self) -> int:
        """Network outputs: 5 per module ([K̃p, K̃i, K̃d, Δ̃] and the class or its logit)."""
        return 5 * self.modules

    @classmethod
    def for_body(cls, layout: Layout, n_segments: int, **kwargs) -> NetworkConfig:
        """The configuration of ``layout`` for a body of ``n_segments``."""
        if layout is Layout.MODULAR:
            return cls(layout, 3, 1, **kwargs)
        if layout is Layout.FRF:
            return cls(layout, 3 * n_segments, n_segments, **kwargs)
        return cls(layout, 2 * n_segments - 1, n_segments, **kwargs)

    @property
    def feature_definition(self) -> dict:
        """What the inputs are (written into checkpoints; a model whose definition differs
        from this code's is refused)."""
        return FRF_FEATURE_DEFINITION if self.layout is Layout.FRF else FEATURE_DEFINITION


@dataclass(frozen=True)
class SgdMomentum:
    """The paper's optimiser: SGD with momentum, learning rate divided by 10 at 50 % and
    75 % of the epochs."""

    learning_rate: float = 0.01
    momentum: float = 0.9
    weight_decay: float = 1e-4


@dataclass(frozen=True)
class AdamWOneCycle:
    """AdamW with a one-cycle schedule (warm-up to ``max_learning_rate``, cosine decay)."""

    max_learning_rate: float = 3e-3
    weight_decay: float = 1e-4


Optimiser = SgdMomentum | AdamWOneCycle


@dataclass(frozen=True)
class TrainingConfig:
    """How to train.

    Attributes:
        optimiser: :class:`SgdMomentum` (the paper's) or :class:`AdamWOneCycle` (faster).
        epochs: at most this many passes over the training split.
        batch_size: samples per step.
        patience: stop when the validation loss has not improved for this many epochs.
        seed: seeds the initial weights and the order of the samples (one stream per
            epoch, so a resumed run continues exactly).
        threads: torch threads (default: all cores).
        buffer_shards: shards held in memory at once; the samples of a buffer are
            shuffled together. 0 holds the whole training split (it must fit in memory).
    """

    optimiser: Optimiser = field(default_factory=AdamWOneCycle)
    epochs: int = 30
    batch_size: int = 128
    patience: int = 8
    seed: int = 0
    threads: int | None = None
    buffer_shards: int = 0

    def __post_init__(self) -> None:
        if not isinstance(self.optimiser, SgdMomentum | AdamWOneCycle):
            raise LearningError(f"optimiser must be SgdMomentum() or AdamWOneCycle(), got "
                                f"{self.optimiser!r}")
        for name in ("epochs", "batch_size", "patience"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise LearningError(f"{name} must be an integer ≥ 1, got {value!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise LearningError(f"seed must be an integer ≥ 0, got {self.seed!r}")
        if self.threads is not None and self.threads < 1:
            raise LearningError(f"threads must be ≥ 1, got {self.threads}")
        if self.buffer_shards < 0:
            raise LearningError(f"buffer_shards must be ≥ 0, got {self.buffer_shards}")
        rate = getattr(self.optimiser, "learning_rate", None) or getattr(
            self.optimiser, "max_learning_rate", None)
        if not (math.isfinite(rate) and rate > 0):
            raise LearningError(f"the learning rate must be > 0, got {rate}")
