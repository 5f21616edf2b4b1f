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
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, NoReturn

from posture_id.errors import PostureIdError

__all__ = [
    "Parser",
    "default_of",
    "positive_int",
    "non_negative_int",
    "positive_float",
    "nonzero_float",
    "non_negative_float",
    "check_output_file",
    "check_output_folder",
    "check_out_and_plot",
    "command_rate",
    "share",
    "say",
    "write_result",
]


class _StoredOnce(argparse._StoreAction):
    """A flag's value, refused when the flag is given again with another value (argparse
    keeps the last without a word: ``--height-m 1.8 --height-m 1.7``, or an old spelling
    beside the new one)."""

    def __call__(self, parser, namespace, values, option_string=None):
        if option_string is not None:
            given = namespace.__dict__.setdefault("_given_flags", {})
            if self.dest in given and given[self.dest] != values:
                parser.error(f"{self.option_strings[-1]} given twice, "
                             f"{_shown(given[self.dest])} and then {_shown(values)} (an old "
                             "spelling of it counts too): give it once")
            given[self.dest] = values
        super().__call__(parser, namespace, values, option_string)


def _shown(values) -> str:
    """A flag's value as typed."""
    if isinstance(values, list | tuple):
        return " ".join(str(v) for v in values)
    return str(values)


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line (``prog: error: message``), exit 2, and
    whose flags take one value each (a flag given twice with two values is refused)."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.register("action", None, _StoredOnce)
        self.register("action", "store", _StoredOnce)

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
#: A scale whose sign is a sense (a sensor's units per degree): any finite number but 0.
nonzero_float = _number(float, lambda x: x != 0, "a number other than 0")
#: A platform's command rate, Hz: a motion controller takes 1 Hz to 10 kHz (a higher
#: rate writes a file of millions of lines per minute, a lower one no tilt).
command_rate = _number(float, lambda x: 1 <= x <= 10_000, "a rate from 1 to 10000 Hz")
#: A share of something: more than none, less than all.
share = _number(float, lambda x: 0 < x < 1, "a share between 0 and 1")
#: An interval's nominal coverage: the calibrations hold 0.50 to 0.99.
interval_level = _number(float, lambda x: 0.5 <= x <= 0.99, "a level from 0.5 to 0.99")


def say(message: str) -> None:
    """A status line on stderr (results go to stdout)."""
    print(message, file=sys.stderr, flush=True)


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve() or (a.exists() and b.exists() and a.samefile(b))
    except OSError:
        return False


def _writable_place(path: Path, flag: str) -> None:
    """The nearest existing ancestor of ``path`` must be a writable folder."""
    ancestor = path.parent
    while not ancestor.exists():
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise PostureIdError(f"{path}: {flag}: {ancestor} is a file, not a folder")
    if not os.access(ancestor, os.W_OK | os.X_OK):
        raise PostureIdError(f"{path}: {flag}: the folder {ancestor} is not writable")


def check_output_file(path: Path | None, flag: str, inputs=(), outputs=()) -> None:
    """Refuse, before any work, an output file that cannot be written or would destroy
    something: a directory, under a file or an unwritable folder, an input of the same
    command, or the same path as another output. Missing folders are created later."""
    if path is None:
        return
    if path.is_dir():
        raise PostureIdError(f"{path}: {flag} is a folder; give a file name")
    _writable_place(path, flag)
    if path.exists() and not os.access(path, os.W_OK):
        raise PostureIdError(f"{path}: {flag}: the file exists and is not writable")
    for other in inputs:
        if other is not None and _same_file(path, Path(other)):
            raise PostureIdError(f"{path}: {flag} is also an input of this command; it would be "
                                 "overwritten: write the result elsewhere")
    for other in outputs:
        if other is not None and _same_file(path, Path(other)):
            raise PostureIdError(f"{path}: given as two different outputs; choose two names")


def check_out_and_plot(args: argparse.Namespace, inputs=()) -> None:
    """:func:`check_output_file` of a command's ``--out`` and ``--plot`` (``args.out``,
    ``args.plot``): neither one of ``inputs``, the plot not the result's own file."""
    check_output_file(args.out, "--out", inputs)
    check_output_file(args.plot, "--plot", inputs, outputs=(args.out,))


def check_output_folder(path: Path, flag: str, inputs=()) -> None:
    """Refuse an output folder that is a file, lies under a file or an unwritable folder,
    or is an input of the command."""
    if path.exists() and not path.is_dir():
        raise PostureIdError(f"{path}: {flag} is a file, not a folder")
    if not path.exists():
        _writable_place(path, flag)
    elif not os.access(path, os.W_OK | os.X_OK):
        raise PostureIdError(f"{path}: {flag}: the folder is not writable")
    for other in inputs:
        if other is not None and _same_file(path, Path(other)):
            raise PostureIdError(f"{path}: {flag} is also an input of this command")


def write_result(result, out: Path | None, plot: Path | None = None) -> None:
    """Write a result's JSON (none without ``out``) and its plot, say so on stderr, print
    its summary."""
    if out is not None:
        result.to_json(out)
        say(f"wrote {out}")
    if plot:
        result.plot(plot)
        say(f"wrote {plot}")
        if getattr(result, "plot_intervals", None) and result.intervals is not None:
            beside = plot.with_name(plot.stem + ".intervals" + plot.suffix)
            result.plot_intervals(beside)
            say(f"wrote {beside}")
    print(result.summary())


def is_cohort(recording: str) -> bool:
    """Whether a command's recording argument names a cohort: a folder or a glob pattern."""
    return Path(recording).is_dir() or any(c in recording for c in "*?[")
