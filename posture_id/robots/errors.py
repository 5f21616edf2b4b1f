"""Errors of the robot checks: one line each, :class:`~posture_id.errors.PostureIdError`s."""

from __future__ import annotations

from posture_id.errors import PostureIdError

__all__ = ["RobotError", "MissingExtraError", "ROBOTS_EXTRA", "require_mujoco"]

#: How to install what the robot checks need (the ``robots`` extra of pyproject.toml).
ROBOTS_EXTRA = "pip install posture_id[robots]"


class RobotError(PostureIdError):
    """A robot check cannot be built or run as asked (options, body, stimulus)."""


class MissingExtraError(RobotError):
    """An optional package the robot checks need is not installed."""


def require_mujoco():
    """The ``mujoco`` module, or :class:`MissingExtraError` naming the extra to install."""
    try:
        import mujoco
    except ImportError:
        raise MissingExtraError(
            f"the robot checks need MuJoCo, which is not installed: {ROBOTS_EXTRA}"
        ) from None
    return mujoco
