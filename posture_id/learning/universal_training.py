"""Training the universal network on a universal set (:mod:`~.data.drawn`).

Every epoch makes the training split's module samples afresh (:func:`.samples.
make_samples`: new sensor noise and drift on the stored sway), so the network never sees
the same noisy recording twice. Loss per module sample: the mean squared error of the
four standardised continuous targets, plus half the Gaussian negative log-likelihood of
their errors under the network's own SD (the mean detached: the SD learns the size of
the error without pulling the estimate), plus the binary cross-entropy of the class
logit. AdamW with a one-cycle schedule; the weights of the epoch with the lowest
validation loss (MSE + cross-entropy, fixed noise) are kept; training stops early after
``patience`` epochs without improvement. All cores are used (torch threads); a GPU when
torch finds one.

The run is resumable: after each epoch the state (weights, optimiser, best weights,
history) is written in the layout every trainer keeps (:mod:`posture_id.learning.trainer`);
the same command continues from there.
"""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Literal, get_args

import numpy as np
import torch

from posture_id.errors import LearningError
from posture_id.learning.data.drawn import merged_scope, open_sets
from posture_id.learning.model_files import prefixed
from posture_id.learning.trainer import EpochTrainer, TrainingResult
from posture_id.learning.universal_model import UniversalModel
from posture_id.learning.universal_network import (
    OUTPUTS,
    UniversalNetworkConfig,
)
from posture_id.learning.universal_samples import Samples, make_samples, split_shards
from posture_id.progress import Progress, report
from posture_id.provenance import provenance

__all__ = ["UniversalTrainingConfig", "UniversalTrainer",
           "train_universal", "VALIDATION_SEED", "POINT_LOSSES"]

#: Seed of the validation split's noise (fixed, so epochs are compared alike).
VALIDATION_SEED = 0x56414C
#: The point losses :class:`UniversalTrainingConfig` knows.
PointLoss = Literal["squared", "absolute"]
POINT_LOSSES: tuple[str, ...] = get_args(PointLoss)


@dataclass(frozen=True)
class UniversalTrainingConfig:
    """How to train: epochs (at most), batch size, AdamW's peak learning rate and weight
    decay, early-stopping patience, seed, torch threads (default: all cores), and the
    point loss of the four parameters' estimates: 'squared' (their mean squared error:
    the estimate learns the posterior mean) or 'absolute' (their mean absolute error: the
    posterior median), in training and in the validation loss that picks the epoch.
    ``fresh_motor_noise``: every epoch turns each training trial's motor noise to a new
    draw (:func:`~.universal_samples.rotate_motor_noise`), as it draws its sensor noise and drift
    afresh; the validation split keeps the simulated noise. ``motor_noise_tilt``: every
    epoch (the first included) also tilts each training trial's motor-noise spectrum by a
    slope drawn in ±this (:func:`~.universal_samples.tilt_motor_noise`; 0: the simulated shape).
    ``init``: a universal model's
    folder to start from (its weights and its standardisation: fine-tuning; the network
    settings are then its own). ``exclude_families``: noise families
    (:mod:`posture_id.simulation.noise_families`) whose trials are left out of the
    training and validation splits (to report on them as noise never seen).
    ``keep_clean``: with ``init``, the weight of a term that keeps the fine-tuned network's
    outputs on clean training trials (no motor noise) those of the model it starts from
    (:func:`_gap`, per training sample, clean or not): learning other noise
    without unlearning clean sway, which the model started from learnt on more trials
    (learning without forgetting; 0: the truth alone)."""

    epochs: int = 60
    batch_size: int = 512
    max_learning_rate: float = 2e-3
    weight_decay: float = 1e-3
    patience: int = 12
    seed: int = 0
    threads: int | None = None
    point_loss: PointLoss = "squared"
    fresh_motor_noise: bool = False
    motor_noise_tilt: float = 0.0
    init: str | None = None
    exclude_families: tuple[str, ...] = ()
    keep_clean: float = 0.0

    def __post_init__(self) -> None:
        if not (self.keep_clean >= 0 and math.isfinite(self.keep_clean)):
            raise LearningError(f"keep_clean must be a finite weight ≥ 0, got {self.keep_clean!r}")
        if self.keep_clean and self.init is None:
            raise LearningError("keep_clean keeps the outputs of the model fine-tuned from: it "
                             "needs init")
        if self.point_loss not in POINT_LOSSES:
            raise LearningError(f"point_loss must be one of {', '.join(POINT_LOSSES)}, "
                             f"got {self.point_loss!r}")


def _device() -> torch.device:
    return torch.device("cuda" if torch.cuda.is_available() else "cpu")


def _loss(out: torch.Tensor, target: torch.Tensor, point_loss: PointLoss = "squared"
          ) -> tuple[torch.Tensor, torch.Tensor]:
    """(training loss, validation loss) of a batch: ``out`` (K, B, 9) of K members,
    ``target`` (B, 5) standardised continuous targets then the class (±1). The training
    loss is the members' mean of their own; the validation loss is that of what is
    deployed, the members' mean estimate and logit (for one member, the same thing).
    ``point_loss`` (:data:`POINT_LOSSES`): the estimates' squared or absolute error."""
    mean, log_sd, logit = out[..., :4], out[..., 4:8].clamp(-8, 6), out[..., 8]
    label = (target[:, 4] > 0).float()
    err = target[:, :4] - mean
    point = torch.square if point_loss == "squared" else torch.abs
    nll = (log_sd + 0.5 * (err.detach() ** 2) * torch.exp(-2 * log_sd)).mean()
    bce = torch.nn.functional.binary_cross_entropy_with_logits(logit, label.expand_as(logit))
    deployed = point(target[:, :4] - mean.mean(0)).mean() \
        + torch.nn.functional.binary_cross_entropy_with_logits(logit.mean(0), label)
    return point(err).mean() + 0.5 * nll + bce, deployed


#: Realised locked share from which a trial counts as clean (no motor noise), as
#: :mod:`~posture_id.studies.universal_check` groups them.
CLEAN_LOCKED_SHARE = 0.995


def _kept_outputs(teacher: torch.nn.Module | None, samples: Samples, x: torch.Tensor
                  ) -> tuple[torch.Tensor, torch.Tensor] | None:
    """What ``keep_clean`` holds: (the clean samples' mask (M,), the teacher's outputs
    (M, 9), its members averaged, on the clean samples; zeros elsewhere); None without a
    teacher."""
    if teacher is None:
        return None
    clean = torch.from_numpy(samples.locked_share >= CLEAN_LOCKED_SHARE)
    rows = torch.nonzero(clean).ravel()
    out = torch.zeros(len(x), OUTPUTS)
    with torch.no_grad():
        for i in range(0, len(rows), 8192):
            out[rows[i:i + 8192]] = teacher(x[rows[i:i + 8192]]).mean(0)
    return clean, out


def _gap(out: torch.Tensor, teacher: torch.Tensor) -> torch.Tensor:
    """The mean squared difference of ``out`` (K, B, 9) from the teacher's (B, 9): the
    eight estimates and log SDs as they are, the class as a probability (a logit of 12
    and one of 9 say the same)."""
    probability = torch.sigmoid(out[..., 8]) - torch.sigmoid(teacher[:, 8])
    return (((out[..., :8] - teacher[:, :8]).square().sum(-1) + probability.square())
            / OUTPUTS).mean()


def _targets(samples: Samples, mean: np.ndarray, std: np.ndarray) -> torch.Tensor:
    t = samples.targets.astype(np.float64).copy()
    t[:, :4] = (t[:, :4] - mean) / std
    return torch.from_numpy(t.astype(np.float32))


def train_universal(data_path: str | Path | Sequence[str | Path], out: str | Path,
                    config: UniversalTrainingConfig | None = None,
                    network: UniversalNetworkConfig | None = None,
                    progress: Progress | None = None) -> UniversalModel:
    """Train on the set at ``data_path`` (or the sets, together: :func:`~.data.drawn.open_sets`);
    the best model is written to ``out`` and returned (a :class:`UniversalTrainer` run to
    its end; progress and a line per epoch through ``progress``)."""
    trainer = UniversalTrainer(data_path, out, config, network, progress)
    trainer.resume()
    return trainer.run(progress).model


class UniversalTrainer(EpochTrainer):
    """One training run of the universal network (the module doc): configured and resumed
    by the constructor, run by :meth:`~posture_id.learning.trainer.EpochTrainer.run`.

    Attributes:
        config, network_config: how it trains and what. data, scope: the sets and their
        merged scope. model: the network with its standardisation. history, best: as
        :class:`~posture_id.learning.trainer.EpochTrainer`'s.
    """

    def __init__(self, data_path: str | Path | Sequence[str | Path], out: str | Path,
                 config: UniversalTrainingConfig | None = None,
                 network: UniversalNetworkConfig | None = None,
                 progress: Progress | None = None) -> None:
        self.started = time.perf_counter()
        self.config = config = config or UniversalTrainingConfig()
        self.progress = progress
        network_config = network or UniversalNetworkConfig()
        self.epochs, self.patience, self.threads = config.epochs, config.patience, config.threads
        self.out = out = Path(out)
        self.device = device = _device()
        self.data = data = open_sets(data_path)
        self.scope = scope = merged_scope(data)
        t0 = time.perf_counter()
        left_out = config.exclude_families
        self.train_shards = split_shards(data, "train", scope, left_out)
        validation = make_samples(split_shards(data, "validation", scope, left_out), scope,
                                  np.random.default_rng(VALIDATION_SEED))
        self.first = first = make_samples(self.train_shards, scope,
                                          np.random.default_rng([config.seed, 0]),
                                          config.fresh_motor_noise, config.motor_noise_tilt)
        report(progress, 0, config.epochs, "epoch",
               f"loaded {len(self.train_shards)} training shards ({len(first)} module "
               f"samples), {len(validation)} validation samples in "
               f"{time.perf_counter() - t0:.0f} s")
        torch.manual_seed(config.seed)
        self.base = None
        if config.init is not None:  # fine-tuning: its network and standardisation
            self.base = base = UniversalModel.load(config.init)
            self.teacher = copy.deepcopy(base.network).eval() if config.keep_clean else None
            net = base.network.to(device)
            net.train()
            network_config = net.config
            input_mean, input_std = base.input_mean, base.input_std
            target_mean, target_std = base.target_mean, base.target_std
        else:
            self.teacher = None
            input_mean = first.inputs.mean(axis=0, dtype=np.float64)
            input_std = np.maximum(first.inputs.std(axis=0, dtype=np.float64), 1e-6)
            target_mean = first.targets[:, :4].mean(axis=0)
            target_std = first.targets[:, :4].std(axis=0)
            net = network_config.build().to(device)
        self.net, self.network_config = net, network_config
        self.model = UniversalModel(net, input_mean, input_std, target_mean, target_std)
        self.steps = math.ceil(len(first) / config.batch_size)
        self.optimiser = torch.optim.AdamW(net.parameters(), lr=config.max_learning_rate,
                                           weight_decay=config.weight_decay)
        self.schedule = torch.optim.lr_scheduler.OneCycleLR(
            self.optimiser, max_lr=config.max_learning_rate,
            total_steps=config.epochs * self.steps + 1)
        self.identity = {"training": asdict(config), "sets": _run_identity(data, network_config)}
        self.best_state: dict | None = None
        self.history: list[dict] = []
        self.best: tuple[float, int] = (math.inf, 0)
        self.x_val = self.model.standardise(validation.inputs).to(device)
        self.t_val = _targets(validation, target_mean, target_std).to(device)

    def run_epoch(self, epoch: int, progress: Progress | None = None) -> dict:
        """Epoch ``epoch`` (1-based) on the training split's samples made afresh (its
        noise drawn from the seed and the epoch), then the validation loss."""
        config, net, index = self.config, self.net, epoch - 1
        started = time.perf_counter()
        samples = self.first if index == 0 else make_samples(
            self.train_shards, self.scope, np.random.default_rng([config.seed, index]),
            config.fresh_motor_noise, config.motor_noise_tilt)
        x = self.model.standardise(samples.inputs)
        t = _targets(samples, self.model.target_mean, self.model.target_std)
        kept = _kept_outputs(self.teacher, samples, x)
        order = torch.from_numpy(np.random.default_rng([config.seed, 1, index])
                                 .permutation(len(x)))
        torch.manual_seed(config.seed * 100003 + index)  # dropout: the same on a resumed run
        net.train()
        total = 0.0
        for i in range(self.steps):
            pick = order[i * config.batch_size : (i + 1) * config.batch_size]
            if not len(pick):
                continue
            outputs = net(x[pick].to(self.device))
            loss, _ = _loss(outputs, t[pick].to(self.device), config.point_loss)
            if kept is not None:
                clean = kept[0][pick].to(self.device)
                teacher_out = kept[1][pick].to(self.device)
                if clean.any():
                    loss = loss + config.keep_clean * clean.float().mean() * _gap(
                        outputs[:, clean], teacher_out[clean])
            self.optimiser.zero_grad(set_to_none=True)
            loss.backward()
            self.optimiser.step()
            self.schedule.step()
            total += loss.item() * len(pick)
        net.eval()
        x_val, t_val = self.x_val, self.t_val
        with torch.no_grad():
            val = float(np.mean([_loss(net(x_val[i:i + 8192]), t_val[i:i + 8192],
                                       config.point_loss)[1].item()
                                 for i in range(0, len(x_val), 8192)]))
        return {"epoch": epoch, "train_loss": total / len(x), "validation_loss": val,
                "seconds": time.perf_counter() - started}

    def keep_best(self) -> None:
        """Keep a copy of the weights (written to ``out`` when the run ends)."""
        self.best_state = {k: v.detach().cpu().clone() for k, v in self.net.state_dict().items()}

    def state_tensors(self) -> dict:
        """The best epoch's weights (written to ``out`` when the run ends)."""
        return {f"best.{k}": v.contiguous() for k, v in (self.best_state or {}).items()}

    def restore_state_tensors(self, tensors: dict) -> None:
        self.best_state = prefixed(tensors, "best.") or None

    def said(self, progress: Progress | None, epoch: int, row: dict, improved: bool) -> None:
        report(progress, epoch, self.epochs, "epoch",
               f"epoch {epoch}/{self.epochs}: train {row['train_loss']:.4f}, validation "
               f"{row['validation_loss']:.4f}{' (best)' if improved else ''}, "
               f"{row['seconds']:.0f} s")

    def finish(self, stopped_early: bool) -> TrainingResult:
        """The best epoch's weights, with the sidecar, written to ``out``; the state to
        resume from removed."""
        config, history, data = self.config, self.history, self.data
        if stopped_early:
            report(self.progress, len(history), self.epochs, "epoch",
                   f"no improvement for {self.patience} epochs: stopping")
        self.net.load_state_dict(self.best_state)
        self.net.cpu()
        model = self.model
        model.sidecar = {
            "scope": self.scope.to_dict(),
            "dataset": {"path": str(data[0].path.resolve()),
                        "config": data[0].manifest["config"],
                        "counts": data[0].manifest.get("counts")},
            "datasets": [{"path": str(d.path.resolve()), "config": d.manifest["config"],
                          "counts": d.manifest.get("counts")} for d in data],
            "training": {**asdict(config), "history": history,
                         "best_epoch": self.best[1],
                         "device": str(self.device), "train_samples": len(self.first)},
            "ranges": _ranges(self.first, None if self.base is None
                              else self.base.sidecar["ranges"]),
        }
        if self.base is not None:
            model.sidecar["fine_tuned_from"] = {
                "path": str(Path(config.init).resolve()),
                "weights_sha256": self.base.sidecar["weights_sha256"],
                "training": self.base.sidecar.get("training")}
        model.save(self.out)
        return self.result(stopped_early, provenance(config, datasets=[str(d.path) for d in data]),
                           model)


def _ranges(samples: Samples, before: dict | None = None) -> dict:
    """Per input column, the 0.5 % and 99.5 % points of the training inputs' descriptors
    (what a recording is checked against); with ``before`` (a fine-tuned model's start's),
    the span of both."""
    from posture_id.learning.features.module_frfs import DESCRIPTORS

    desc = samples.inputs[:, -DESCRIPTORS:]
    out = {"descriptors_low": np.percentile(desc, 0.5, axis=0).tolist(),
           "descriptors_high": np.percentile(desc, 99.5, axis=0).tolist(),
           "noise_ratio_high": float(np.percentile(samples.noise_ratio, 99.5))}
    if before is None:
        return out
    return {"descriptors_low": np.minimum(out["descriptors_low"],
                                          before["descriptors_low"]).tolist(),
            "descriptors_high": np.maximum(out["descriptors_high"],
                                           before["descriptors_high"]).tolist(),
            "noise_ratio_high": max(out["noise_ratio_high"], before["noise_ratio_high"])}


def _run_identity(data, network: UniversalNetworkConfig) -> list[dict]:
    """What a resumed run must share with the interrupted one besides its training
    configuration: each set's path, configuration and shard count, in order, then the
    network's configuration."""
    return [{"path": str(d.path.resolve()), "config": d.manifest["config"],
             "shards": len(d.manifest["shards"])} for d in data] + [{"network": network.to_dict()}]
