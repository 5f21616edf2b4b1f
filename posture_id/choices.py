"""Typed choices that read as their value: a ``str`` enum whose ``str()`` is the value
(what a report, a CSV cell and a JSON string show)."""

from __future__ import annotations

import enum

__all__ = ["Choice"]


class Choice(str, enum.Enum):
    """A choice among named values (its members compare equal to their strings)."""

    def __str__(self) -> str:
        return self.value
