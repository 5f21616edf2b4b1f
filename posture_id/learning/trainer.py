"""The loop every network trains by, and the one layout of its state on disk.

Epochs run from where a run stands, each checkpointed so that a killed run resumes;
early stopping ends a run after ``patience`` epochs without a better validation loss;
progress goes through the project's progress reporting; torch computes with the threads
the caller names (restored after).

While (and after) it trains, a model directory holds::

    training/state.json               what was asked (must match to resume), the history,
                                      the best epoch, the optimiser's and schedule's state
    training/epoch-NNNN.safetensors   the network's weights and the optimiser's tensors
                                      after the last epoch (and what else a run keeps)
    log.jsonl                         one line per epoch: losses, learning rate, time

Each file is written atomically; the same command started again on the directory
continues from its last finished epoch, and a directory trained with other arguments, or
one that is not empty and holds no state, is refused in one line.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import torch
from safetensors.torch import load_file, save_file

from posture_id.errors import LearningError
from posture_id.fileio import Result, atomic_write, atomic_write_text, json_text
from posture_id.learning.model_files import network_tensors, prefixed
from posture_id.learning.threads import torch_threads
from posture_id.plotting import plot_loss_curves
from posture_id.progress import Progress

__all__ = ["EpochTrainer", "TrainingResult", "STATE", "read_state"]

STATE = "training/state.json"


def _optimiser_tensors(optimiser) -> tuple[dict[str, torch.Tensor], dict]:
    """Optimiser state as safetensors tensors plus JSON (param groups, scalars)."""
    state = optimiser.state_dict()
    tensors, scalars = {}, {}
    for index, entries in state["state"].items():
        for key, value in entries.items():
            if torch.is_tensor(value):
                tensors[f"optimiser.{index}.{key}"] = value.detach().cpu().contiguous()
            else:
                scalars[f"{index}.{key}"] = value
    return tensors, {"param_groups": state["param_groups"], "scalars": scalars}


def _restore_optimiser(optimiser, tensors: dict[str, torch.Tensor], data: dict) -> None:
    state: dict = {}
    for name, value in prefixed(tensors, "optimiser.").items():
        index, key = name.split(".", 1)
        state.setdefault(int(index), {})[key] = value
    for name, value in data["scalars"].items():
        index, key = name.split(".", 1)
        state.setdefault(int(index), {})[key] = value
    groups = [{k: tuple(v) if k == "betas" else v for k, v in group.items()}
              for group in data["param_groups"]]
    optimiser.load_state_dict({"state": state, "param_groups": groups})


def read_state(out: Path, identity: dict) -> dict | None:
    """The state to resume from in model directory ``out``, None for a fresh start.

    Raises:
        LearningError: ``out`` is a file, is not empty and holds no state, was trained
            with other arguments than ``identity`` (naming those that differ), or has lost
            its last epoch's tensors.
    """
    path = out / STATE
    if not path.exists():
        if out.exists() and not out.is_dir():
            raise LearningError(f"{out}: exists and is not a directory")
        if out.exists() and any(out.iterdir()):
            raise LearningError(f"{out}: exists, is not empty and holds no training state; "
                                "choose another directory")
        return None
    try:
        state = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise LearningError(f"{path}: not valid JSON ({exc})") from None
    ours = json.loads(json_text(identity))
    if state.get("identity") != ours:
        theirs = state.get("identity", {})
        diff = [k for k in ours if theirs.get(k) != ours[k]]
        raise LearningError(f"{out}: was trained with other arguments ({', '.join(diff)} "
                            "differ); choose another directory or repeat them")
    if not (out / state["weights"]).is_file():
        raise LearningError(f"{out / state['weights']}: the last epoch's state is missing")
    return state


@dataclass(frozen=True)
class TrainingResult(Result):
    """How a training run went.

    Attributes:
        model_dir: where the best model is. epochs_run: epochs finished in all.
        best_epoch: the epoch of the best validation loss (1-based). best_validation_loss.
        stopped_early: early stopping ended it. wall_time_s: this call's time, s.
        history: one dict per epoch (epoch, train_loss, validation_loss, learning_rate,
        seconds). model: the trained model, when the trainer hands it over (the
        universal network's :class:`~posture_id.learning.universal_model.UniversalModel`).
    """

    model_dir: Path
    epochs_run: int
    best_epoch: int
    best_validation_loss: float
    stopped_early: bool
    wall_time_s: float
    history: tuple[dict, ...] = field(repr=False)
    provenance: dict = field(default_factory=dict, repr=False)
    model: Any = field(default=None, repr=False, compare=False)

    def to_dict(self) -> dict:
        return {"model_dir": str(self.model_dir), "epochs_run": self.epochs_run,
                "best_epoch": self.best_epoch,
                "best_validation_loss": self.best_validation_loss,
                "stopped_early": self.stopped_early, "wall_time_s": self.wall_time_s,
                "history": list(self.history), "provenance": self.provenance}

    def summary(self) -> str:
        how = "stopped early" if self.stopped_early else "all epochs"
        return (f"{self.model_dir}: {self.epochs_run} epochs ({how}), best validation loss "
                f"{self.best_validation_loss:.4f} at epoch {self.best_epoch}, "
                f"{self.wall_time_s:.0f} s")

    def plot(self, path=None, ax=None):
        """Training and validation loss per epoch."""
        return plot_loss_curves(self.history, path=path, ax=ax)


class EpochTrainer:
    """A training run (the paper CNN's :class:`~posture_id.learning.training.Trainer`,
    the universal network's
    :class:`~posture_id.learning.universal_training.UniversalTrainer`).

    Subclasses set ``out`` (the model directory), ``identity`` (what must match to
    resume), ``net``, ``optimiser``, ``schedule``, ``epochs``, ``patience``, ``threads``,
    ``history`` (one row per epoch run, resumed ones included), ``best`` ((validation
    loss, epoch), epoch 0: none yet) and ``started`` (its ``time.perf_counter()``), and
    implement :meth:`run_epoch`, :meth:`keep_best`, :meth:`said` and :meth:`finish`
    (which returns :meth:`result`); a run that keeps
    more than the network and the optimiser (the best weights, say) names it in
    :meth:`state_tensors` and takes it back in :meth:`restore_state_tensors`.
    """

    out: Path
    identity: dict
    net: torch.nn.Module
    optimiser: torch.optim.Optimizer
    schedule: Any
    epochs: int
    patience: int
    threads: int | None
    history: list[dict]
    best: tuple[float, int]
    started: float

    def state_tensors(self) -> dict[str, torch.Tensor]:
        """Tensors the state keeps besides the network's and the optimiser's (none)."""
        return {}

    def restore_state_tensors(self, tensors: dict[str, torch.Tensor]) -> None:
        """Take back what :meth:`state_tensors` kept, from a state's tensors."""

    def resume(self) -> bool:
        """Load the last epoch's state from the model directory, if there is one (True)."""
        state = read_state(self.out, self.identity)
        if state is None:
            return False
        tensors = load_file(str(self.out / state["weights"]))
        self.net.load_state_dict(prefixed(tensors, "network."))
        _restore_optimiser(self.optimiser, tensors, state["optimiser"])
        self.schedule.load_state_dict(state["schedule"])
        self.history = state["history"]
        self.best = (state["best_validation_loss"], state["best_epoch"])
        self.restore_state_tensors(tensors)
        return True

    def write_state(self) -> None:
        """Write the state after the last epoch (the files of the module doc), then remove
        the epoch before's tensors."""
        out = self.out
        weights = f"training/epoch-{len(self.history):04d}.safetensors"
        tensors = network_tensors(self.net)
        optimiser_tensors, optimiser_json = _optimiser_tensors(self.optimiser)
        tensors.update(optimiser_tensors)
        tensors.update(self.state_tensors())
        atomic_write(out / weights, lambda tmp: save_file(tensors, str(tmp)))
        state = {"identity": self.identity, "weights": weights, "optimiser": optimiser_json,
                 "schedule": self.schedule.state_dict(), "history": self.history,
                 "best_validation_loss": self.best[0], "best_epoch": self.best[1]}
        atomic_write_text(out / STATE, json_text(state))
        atomic_write_text(out / "log.jsonl",
                          "".join(json.dumps(r) + "\n" for r in self.history))
        for old in (out / "training").glob("epoch-*.safetensors"):
            if old.name != Path(weights).name:
                old.unlink()

    def should_stop(self, epoch: int) -> bool:
        """Early stopping: no better validation loss for ``patience`` epochs."""
        return self.best[1] > 0 and epoch - self.best[1] > self.patience

    def run_epoch(self, epoch: int, progress: Progress | None = None) -> dict:
        """Epoch ``epoch`` (1-based): its row (``train_loss``, ``validation_loss``,
        ``seconds``, ...)."""
        raise NotImplementedError

    def checkpoint(self, row: dict) -> bool:
        """Keep the epoch: its row in ``history``, the network when its validation loss is
        the best so far (:meth:`keep_best`), and the state to resume from; whether it is
        the best so far."""
        self.history.append(row)
        improved = row["validation_loss"] < self.best[0]
        if improved:
            self.best = (row["validation_loss"], row["epoch"])
            self.keep_best()
        self.write_state()
        return improved

    def keep_best(self) -> None:
        """Keep the network of the best epoch so far (``best``)."""
        raise NotImplementedError

    def said(self, progress: Progress | None, epoch: int, row: dict, improved: bool) -> None:
        """Report the epoch."""
        raise NotImplementedError

    def finish(self, stopped_early: bool) -> Any:
        """The run's result, once its epochs are done."""
        raise NotImplementedError

    def result(self, stopped_early: bool, made_by: dict, model: Any = None) -> TrainingResult:
        """The :class:`TrainingResult` of the epochs run (``made_by``: its provenance;
        ``model``: the trained model, when the trainer hands it over), timed from
        ``started``."""
        return TrainingResult(self.out, len(self.history), self.best[1], self.best[0],
                              stopped_early, time.perf_counter() - self.started,
                              tuple(self.history), made_by, model=model)

    def run(self, progress: Progress | None = None) -> Any:
        """Epochs from where the run stands to the configured number, or until early
        stopping; then :meth:`finish`."""
        with torch_threads(self.threads):
            stopped_early = False
            for epoch in range(len(self.history) + 1, self.epochs + 1):
                if self.should_stop(epoch):
                    stopped_early = True
                    break
                row = self.run_epoch(epoch, progress)
                self.said(progress, epoch, row, self.checkpoint(row))
            else:
                stopped_early = len(self.history) < self.epochs
            return self.finish(stopped_early)
