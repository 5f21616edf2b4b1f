"""The loop every network trains by: epochs from where a run stands, each checkpointed so
that a killed run resumes, early stopping after ``patience`` epochs without a better
validation loss, progress through the project's progress reporting, and torch computing
with the threads the caller names (restored after)."""

from __future__ import annotations

from typing import Any

from posture_id.learning.threads import torch_threads
from posture_id.progress import Progress

__all__ = ["EpochTrainer"]


class EpochTrainer:
    """A training run (the CNN's :class:`~posture_id.learning.training.Trainer`, the
    universal network's :class:`~posture_id.learning.universal.training.UniversalTrainer`).

    Subclasses set ``epochs``, ``patience``, ``threads``, ``history`` (one row per epoch
    run, resumed ones included) and ``best`` ((validation loss, epoch), epoch 0: none
    yet), and implement :meth:`run_epoch`, :meth:`checkpoint`, :meth:`said` and
    :meth:`finish`.
    """

    epochs: int
    patience: int
    threads: int | None
    history: list[dict]
    best: tuple[float, int]

    def should_stop(self, epoch: int) -> bool:
        """Early stopping: no better validation loss for ``patience`` epochs."""
        return self.best[1] > 0 and epoch - self.best[1] > self.patience

    def run_epoch(self, epoch: int, progress: Progress | None = None) -> dict:
        """Epoch ``epoch`` (1-based): its row (``train_loss``, ``validation_loss``,
        ``seconds``, ...)."""
        raise NotImplementedError

    def checkpoint(self, row: dict) -> bool:
        """Keep the epoch (its row in ``history``, the state to resume from, the best
        weights); whether it is the best so far."""
        raise NotImplementedError

    def said(self, progress: Progress | None, epoch: int, row: dict, improved: bool) -> None:
        """Report the epoch."""
        raise NotImplementedError

    def finish(self, stopped_early: bool) -> Any:
        """The run's result, once its epochs are done."""
        raise NotImplementedError

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
