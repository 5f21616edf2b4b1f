"""Training a CNN identifier on a data set: seeded, resumable, with early stopping.

A model directory while training holds ``model.safetensors`` and ``model.json``, the best
network so far (see :mod:`.checkpoint`), beside the state every trainer keeps
(:mod:`.trainer`).

Every epoch draws its sample order from ``SeedSequence([seed, epoch])``, and the state
after each epoch is saved atomically, so a run killed at any point and started again with
the same arguments continues from its last finished epoch and, on one thread, ends with
the same weights as an uninterrupted run.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import torch
import torch.nn.functional as F  # noqa: N812 - torch's convention

from posture_id.fileio import (
    file_sha256,
    jsonable,
)
from posture_id.frf.features import frf_width
from posture_id.learning.checkpoint import save_model
from posture_id.learning.config import (
    AdamWOneCycle,
    ClassOutput,
    Layout,
    LearningError,
    NetworkConfig,
    SgdMomentum,
    TrainingConfig,
)
from posture_id.learning.data.store import Dataset
from posture_id.learning.network import IdentifierNetwork
from posture_id.learning.samples import SplitSamples, Standardiser
from posture_id.learning.trainer import EpochTrainer, TrainingResult
from posture_id.progress import Progress, report
from posture_id.provenance import provenance

__all__ = ["train", "Trainer", "TrainingResult", "Objective"]

class Objective:
    """The loss of a network configuration on standardised targets.

    REGRESSION: MSE over all 5M outputs (the paper). LOGIT: MSE over the 4M continuous
    outputs plus the binary cross-entropy of each module's class logit.
    """

    def __init__(self, config: NetworkConfig, standardiser: Standardiser) -> None:
        self.config = config
        m = config.modules
        mean = torch.as_tensor(standardiser.target_mean.reshape(m, 5)[:, 4], dtype=torch.float32)
        std = torch.as_tensor(standardiser.target_std.reshape(m, 5)[:, 4], dtype=torch.float32)
        #: a standardised class value above this is C = +1 (COM in space)
        self.class_threshold = -mean / std

    def __call__(self, outputs: torch.Tensor, targets: torch.Tensor) -> torch.Tensor:
        if self.config.class_output is ClassOutput.REGRESSION:
            return F.mse_loss(outputs, targets)
        out = outputs.view(len(outputs), self.config.modules, 5)
        tgt = targets.view(len(targets), self.config.modules, 5)
        labels = (tgt[..., 4] > self.class_threshold).float()
        return (F.mse_loss(out[..., :4], tgt[..., :4])
                + F.binary_cross_entropy_with_logits(out[..., 4], labels))


def _optimiser(network: IdentifierNetwork, training: TrainingConfig, steps_per_epoch: int):
    """(optimiser, scheduler, step the scheduler per batch?)."""
    opt = training.optimiser
    if isinstance(opt, SgdMomentum):
        optimiser = torch.optim.SGD(network.parameters(), lr=opt.learning_rate,
                                    momentum=opt.momentum, weight_decay=opt.weight_decay)
        drops = (round(0.5 * training.epochs), round(0.75 * training.epochs))
        schedule = torch.optim.lr_scheduler.LambdaLR(
            optimiser, lambda epoch: 0.1 ** sum(epoch >= d for d in drops))
        return optimiser, schedule, False
    assert isinstance(opt, AdamWOneCycle)
    optimiser = torch.optim.AdamW(network.parameters(), lr=opt.max_learning_rate,
                                  weight_decay=opt.weight_decay)
    schedule = torch.optim.lr_scheduler.OneCycleLR(
        optimiser, max_lr=opt.max_learning_rate,
        total_steps=max(training.epochs * steps_per_epoch, 2))
    return optimiser, schedule, True


def _identity(data: Dataset, network: NetworkConfig, training: TrainingConfig) -> dict:
    """What must match for a run to resume."""
    return jsonable({"dataset_manifest_sha256": file_sha256(data.path / "manifest.json"),
                     "network": network, "training": training})


def train(dataset: str | Path, out: str | Path, network: NetworkConfig | None = None,
          training: TrainingConfig | None = None, progress: Progress | None = None
          ) -> TrainingResult:
    """Train (or finish training) a CNN identifier on a data set: a :class:`Trainer`
    configured, resumed and run to the end.

    Args:
        dataset: a finished data-set directory. out: the model directory.
        network: the architecture (default: modular, for the set's body).
        training: optimiser, epochs, batches, early stopping, seed, threads.
        progress: told the samples done in each epoch and a line per epoch.
    """
    trainer = Trainer(dataset, out, network, training)
    trainer.resume()
    return trainer.run(progress)


class Trainer(EpochTrainer):
    """One training run of the CNN, in steps (in the manner of sbi's trainers):

    1. **configure** (the constructor): the data set, the network (an FRF network's input
       width follows the stimulus), its standardiser, loss, samples and optimiser;
    2. :meth:`resume` from the model directory's state (refusing one made with other
       arguments);
    3. :meth:`run`: :meth:`run_epoch` while :meth:`should_stop` does not say stop, each
       epoch :meth:`checkpoint`-ed (the best model, and the state to resume from).

    Attributes:
        data, out, network_config, training: what it trains on, where, and how.
        net, objective, optimiser, schedule: the torch side. history: one row per epoch
        (epoch, train_loss, validation_loss, learning_rate, seconds). best: (validation
        loss, epoch) of the best epoch so far (epoch 0: none yet).
    """

    def __init__(self, dataset: str | Path, out: str | Path,
                 network: NetworkConfig | None = None,
                 training: TrainingConfig | None = None) -> None:
        self.started = time.perf_counter()
        self.training = training = training or TrainingConfig()
        self.data = data = Dataset.open(dataset)
        self.network_config = self._network(network)
        self.out = Path(out)
        self.identity = _identity(data, self.network_config, training)
        self.epochs, self.patience = training.epochs, training.patience
        self.threads = training.threads
        torch.manual_seed(training.seed)
        self.net = IdentifierNetwork(self.network_config).to(memory_format=torch.channels_last)
        self.standardiser = Standardiser.from_dataset(data, self.network_config.layout)
        self.objective = Objective(self.network_config, self.standardiser)
        self.train_set = SplitSamples(data, "train", self.network_config.layout,
                                      self.standardiser, training.buffer_shards)
        self.validation_set = SplitSamples(data, "validation", self.network_config.layout,
                                           self.standardiser, training.buffer_shards)
        steps = math.ceil(len(self.train_set) / training.batch_size)
        self.optimiser, self.schedule, self.per_batch = _optimiser(self.net, training, steps)
        self.history: list[dict] = []
        self.best: tuple[float, int] = (math.inf, 0)
        self.sidecar = _sidecar(data, training)

    def _network(self, network: NetworkConfig | None) -> NetworkConfig:
        """The architecture, checked against the data set's body (and, for the FRF
        layout, sized to its stimulus)."""
        data = self.data
        config = network or NetworkConfig.for_body(Layout.MODULAR, data.n_segments)
        if config.layout is Layout.FRF:  # the input's width follows the stimulus
            stimulus, rate = data.stimulus, data.rate_hz
            tilt = data.tilt(int(round(stimulus.duration * rate)) + 1)
            config = replace(config, image_size=frf_width(
                tilt, rate, stimulus.period_s, stimulus.periodic_from_s))
        expected = NetworkConfig.for_body(config.layout, data.n_segments)
        if (config.in_channels, config.modules) != (expected.in_channels, expected.modules):
            raise LearningError(
                f"a {config.layout.value} network for this {data.n_segments}-segment "
                f"data set takes {expected.in_channels} channels and {expected.modules} "
                f"modules, not {config.in_channels} and {config.modules}")
        return config

    def run_epoch(self, epoch: int, progress: Progress | None = None) -> dict:
        """One pass over the training split (batches shuffled by the seed and the epoch),
        then the validation loss; the epoch's row."""
        began = time.perf_counter()
        rng = np.random.default_rng(np.random.SeedSequence([self.training.seed, epoch]))
        self.net.train()
        total, done = 0.0, 0
        for images, targets in self.train_set.batches(self.training.batch_size, rng):
            loss = self.objective(self.net(images), targets)
            self.optimiser.zero_grad(set_to_none=True)
            loss.backward()
            self.optimiser.step()
            if self.per_batch:
                self.schedule.step()
            total += float(loss.detach()) * len(images)
            done += len(images)
            report(progress, done, len(self.train_set), "sample")
        if not self.per_batch:
            self.schedule.step()
        validation = evaluate_loss(self.net, self.objective, self.validation_set)
        return {"epoch": epoch, "train_loss": total / done, "validation_loss": validation,
                "learning_rate": self.optimiser.param_groups[0]["lr"],
                "seconds": time.perf_counter() - began}

    def keep_best(self) -> None:
        """Write the model of the best epoch so far into the model directory."""
        validation, epoch = self.best
        save_model(self.out, self.net, self.standardiser,
                   {**self.sidecar, "training": {**self.sidecar["training"],
                                                 "best_epoch": epoch,
                                                 "best_validation_loss": validation,
                                                 "epochs_run": epoch}})

    def said(self, progress: Progress | None, epoch: int, row: dict, improved: bool) -> None:
        report(progress, len(self.train_set), len(self.train_set), "sample",
               f"epoch {epoch}/{self.epochs}: train loss {row['train_loss']:.4f}, "
               f"validation {row['validation_loss']:.4f}{' (best)' if improved else ''}, "
               f"{row['seconds']:.0f} s")

    def finish(self, stopped_early: bool) -> TrainingResult:
        return self.result(stopped_early, provenance(self.training, dataset=str(self.data.path)))


def evaluate_loss(net: IdentifierNetwork, objective: Objective, samples: SplitSamples,
                  batch_size: int = 512) -> float:
    """Mean loss over a split (eval mode, no gradients)."""
    net.eval()
    total, count = 0.0, 0
    with torch.no_grad():
        for images, targets in samples.batches(batch_size):
            total += float(objective(net(images), targets)) * len(images)
            count += len(images)
    return total / count


def _sidecar(data: Dataset, training: TrainingConfig) -> dict:
    m = data.manifest
    return {
        "body": m["body"],
        "stimulus": m["stimulus"],
        "simulation": m["options"],
        "defaults": m["defaults"],
        "dataset": {"path": str(data.path.resolve()),
                    "manifest_sha256": file_sha256(data.path / "manifest.json"),
                    "trials": m["counts"]["used"], "split": m["split"]},
        "training": {"config": jsonable(training)},
    }
