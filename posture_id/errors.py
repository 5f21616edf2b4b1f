"""User-facing errors.

Every error a user can cause (a bad URDF, parameter file, tilt profile or recording) is
raised as a :class:`PostureIdError` whose message is one line naming the file, the field
and the problem. The command line prints that line and exits with status 2, never a
traceback.
"""

from __future__ import annotations

__all__ = [
    "PostureIdError",
    "BodyError",
    "ParameterError",
    "StimulusError",
    "RecordingError",
    "SimulationError",
    "LearningError",
    "bug_line",
]


def bug_line(exc: BaseException) -> str:
    """One line saying an unexpected exception is a bug: its type and message, the
    message's white space folded and cut at 300 characters."""
    detail = " ".join(str(exc).split())[:300]
    return f"internal error (a bug; please report it): {type(exc).__name__}: {detail}"


class PostureIdError(Exception):
    """Base class of every error caused by user input."""


class BodyError(PostureIdError):
    """The URDF does not describe a valid sagittal chain."""


class ParameterError(PostureIdError):
    """A DEC parameter set or its JSON file is invalid."""


class StimulusError(PostureIdError):
    """A tilt profile (array or CSV) is invalid."""


class RecordingError(PostureIdError):
    """A sway recording (CSV) is invalid."""


class SimulationError(PostureIdError):
    """A simulation request is inconsistent (options, shapes)."""


class LearningError(PostureIdError):
    """A network, its training set, training request, model directory, checkpoint or
    calibration is inconsistent (every learning stage's errors are of this type)."""
