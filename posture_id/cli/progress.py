"""Progress on the terminal: counted work as a tqdm bar, messages as lines on stderr."""

from __future__ import annotations

import sys

from tqdm import tqdm

from posture_id.progress import ProgressUpdate

__all__ = ["TerminalProgress"]


class TerminalProgress:
    """A :data:`posture_id.progress.Progress` callback for the terminal; use as a context
    manager so the bar is closed. A count that goes back (the next epoch) starts a new bar.

    Args:
        description: the bar's label. prefix: put before every message line.
        quiet: no bar (messages are still printed).
    """

    def __init__(self, description: str = "", prefix: str = "posture-id",
                 quiet: bool = False) -> None:
        self.description = description
        self.prefix = prefix
        self.quiet = quiet
        self.bar: tqdm | None = None

    def __call__(self, update: ProgressUpdate) -> None:
        if update.message:
            print(f"{self.prefix}: {update.message}", file=sys.stderr, flush=True)
        if update.total is None or self.quiet:
            return
        if self.bar is not None and (update.done < self.bar.n or update.total != self.bar.total):
            self.bar.close()  # a new pass (the next epoch): a new bar
            self.bar = None
        if self.bar is None:
            self.bar = tqdm(total=update.total, unit=update.unit, desc=self.description,
                            file=sys.stderr)
        self.bar.update(update.done - self.bar.n)

    def __enter__(self) -> TerminalProgress:
        return self

    def __exit__(self, *exc) -> None:
        if self.bar is not None:
            self.bar.close()
