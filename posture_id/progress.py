"""Progress of long work: one callback shape for every stage.

A long function takes ``progress: Progress | None`` and calls it with a
:class:`ProgressUpdate` as work completes (not as it is dispatched). The command line
turns updates with a total into a progress bar and messages into lines on stderr.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

__all__ = ["ProgressUpdate", "Progress", "report"]


@dataclass(frozen=True)
class ProgressUpdate:
    """How far a piece of work is.

    Attributes:
        done: units finished so far (trials simulated, trials kept, iterations).
        total: units wanted, or None when unknown (an iterative fit).
        unit: what is counted ("trial", "iteration").
        message: a one-line status, or "".
    """

    done: int
    total: int | None
    unit: str
    message: str = ""


#: The callback type every long function accepts.
Progress = Callable[[ProgressUpdate], None]


def report(progress: Progress | None, done: int, total: int | None, unit: str,
           message: str = "") -> None:
    """Send one update to ``progress`` when there is one."""
    if progress is not None:
        progress(ProgressUpdate(done, total, unit, message))
