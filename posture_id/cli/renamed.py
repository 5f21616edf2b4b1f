"""One name per idea across the commands: old spellings of renamed flags still work, each
with a one-line notice of its new name, and a negative axis is taken as typed.

The command line is read once, before parsing (:func:`normalised`): a renamed flag
(``--noise-deg``, alone or as ``--noise-deg=0.05``) is replaced by its new name for its
command; ``identify --model DIR`` (a network's folder: one that exists, or a path) becomes
``--network DIR``, as
``--model`` names the model (``dec`` or ``ic``) in every command; and an axis flag
followed by ``-x``, ``-y`` or ``-z`` (which argparse would take for a flag) is joined to it
as ``--forward-axis=-y``.
"""

from __future__ import annotations

import os
import sys

__all__ = ["RENAMED", "AXIS_FLAGS", "MOVED_COMMANDS", "normalised"]

#: Commands that moved into the ``network`` family: old command → its new words.
MOVED_COMMANDS: dict[str, tuple[str, ...]] = {
    "universal": ("network", "universal"),
    "dataset": ("network", "cnn", "data"),
    "train": ("network", "cnn", "train"),
    "evaluate": ("network", "cnn", "evaluate"),
    "calibration": ("network", "cnn", "calibrate"),
    "benchmark": ("network", "cnn", "benchmark"),
}
#: Jobs of the old ``universal`` command renamed in the family.
_MOVED_UNIVERSAL_JOBS = {"check": "calibrate"}

#: (command, old spelling): new spelling.
RENAMED: dict[tuple[str, str], str] = {
    ("simulate", "--noise-deg"): "--sensor-noise-deg",
    ("benchmark", "--noise-deg"): "--sensor-noise-deg",
    ("calibrate", "--noise-deg"): "--sensor-noise-deg",
    ("identify", "--frf-preset"): "--band-preset",
    ("body", "--height"): "--height-m",
    ("body", "--mass"): "--mass-kg",
    ("simulate", "--subject-height-m"): "--height-m",
    ("simulate", "--subject-mass-kg"): "--mass-kg",
}
#: The flags whose value may be a negative axis.
AXIS_FLAGS = ("--forward-axis", "--vertical-axis", "--c3d-forward-axis")
_NEGATIVE_AXES = ("-x", "-y", "-z")
_MODEL_NAMES = ("dec", "ic")


def _a_folder(value: str) -> bool:
    """Whether ``--model``'s value names a network's folder (one that exists, or a path),
    not a model (``dec``, ``ic``, or a misspelling argparse then names)."""
    return value not in _MODEL_NAMES and (os.path.isdir(value) or "/" in value
                                          or os.sep in value)


def _notice(old: str, new: str) -> None:
    print(f"posture-id: note: {old} is now {new} (the old spelling still works)",
          file=sys.stderr)


def _moved(argv: list[str]) -> list[str]:
    """``argv`` with a command that moved into the ``network`` family in its new words (a
    notice on stderr)."""
    at = next((k for k, a in enumerate(argv) if not a.startswith("-")), None)
    if at is None or argv[at] not in MOVED_COMMANDS:
        return argv
    old = [argv[at]]
    new = list(MOVED_COMMANDS[argv[at]])
    rest = argv[at + 1:]
    if argv[at] == "universal" and rest and rest[0] in _MOVED_UNIVERSAL_JOBS:
        old.append(rest[0])
        new.append(_MOVED_UNIVERSAL_JOBS[rest[0]])
        rest = rest[1:]
    _notice("posture-id " + " ".join(old), "posture-id " + " ".join(new))
    return argv[:at] + new + rest


def _job(argv: list[str]) -> str | None:
    """The command a flag belongs to: the first word, or a network family's job."""
    words = [a for a in argv if not a.startswith("-")]
    if words[:1] == ["network"]:
        return words[2] if len(words) > 2 else None
    return words[0] if words else None


def normalised(argv: list[str]) -> list[str]:
    """``argv`` with a moved command and renamed flags in their new spelling (a notice each
    on stderr), identify's network folder under ``--network`` and negative axes joined to
    their flag."""
    argv = _moved(argv)
    command = _job(argv)
    out: list[str] = []
    k = 0
    while k < len(argv):
        token = argv[k]
        flag, equals, value = token.partition("=")
        if flag in AXIS_FLAGS and not equals and k + 1 < len(argv) \
                and argv[k + 1] in _NEGATIVE_AXES:
            out.append(f"{flag}={argv[k + 1]}")
            k += 2
            continue
        new = RENAMED.get((command, flag))
        if new is not None:
            _notice(flag, new)
            out.append(new + equals + value)
        elif command == "identify" and flag == "--model" and _a_folder(
                value if equals else (argv[k + 1] if k + 1 < len(argv) else "")):
            _notice("--model DIR", "--network DIR")  # a network's folder, as it once was
            out.append("--network" + equals + value)
        else:
            out.append(token)
        k += 1
    return out
