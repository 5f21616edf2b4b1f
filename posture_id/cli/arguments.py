"""Argument parsing shared by every command: one-line errors and checked numeric types.

Every numeric flag has a type below, so ``0``, ``-1``, ``nan`` or a word where they make
no sense stop the command with one line and exit status 2 before any work starts.
Defaults come from the configuration dataclasses (:func:`default_of`), never repeated.
"""

from __future__ import annotations

import argparse
import dataclasses
import inspect
import math
import sys
from collections.abc import Callable
from typing import Any, NoReturn

__all__ = [
    "Parser",
    "default_of",
    "positive_int",
    "non_negative_int",
    "positive_float",
    "non_negative_float",
]


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line (``prog: error: message``), exit 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


def default_of(owner: Any, name: str) -> Any:
    """The default of field ``name`` of a dataclass, or of parameter ``name`` of a function."""
    if dataclasses.is_dataclass(owner):
        f = owner.__dataclass_fields__[name]
        if f.default is not dataclasses.MISSING:
            return f.default
        return f.default_factory()  # type: ignore[misc]
    return inspect.signature(owner).parameters[name].default


def _number(kind: type, test: Callable[[float], bool], wanted: str):
    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {wanted}, got {text!r}") from None
        if not (math.isfinite(value) and test(value)):
            raise argparse.ArgumentTypeError(f"must be {wanted}, got {text!r}")
        return value

    parse.__name__ = wanted  # argparse names the type in some messages
    return parse


positive_int = _number(int, lambda x: x >= 1, "an integer ≥ 1")
non_negative_int = _number(int, lambda x: x >= 0, "an integer ≥ 0")
positive_float = _number(float, lambda x: x > 0, "a number > 0")
non_negative_float = _number(float, lambda x: x >= 0, "a number ≥ 0")


def say(message: str) -> None:
    """A status line on stderr (results go to stdout)."""
    print(message, file=sys.stderr, flush=True)
