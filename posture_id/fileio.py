"""Files: atomic writes (a file is either absent or complete, never half written), SHA-256,
JSON, and the one reader of numeric text tables (:mod:`posture_id.text_table`)."""

from __future__ import annotations

import dataclasses
import enum
import hashlib
import json
import math
import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from posture_id.errors import PostureIdError
from posture_id.text_table import TextTable, read_text_table

__all__ = ["atomic_write", "atomic_write_text", "file_sha256", "read_numeric_csv",
           "read_text_table", "TextTable",
           "jsonable", "json_text", "json_object", "Result", "JsonFile", "read_json",
           "check_time_column", "PLAUSIBLE_INTERVAL_S"]


def atomic_write(path: Path, write: Callable[[Path], None]) -> Path:
    """Call ``write(tmp)`` on a temporary file beside ``path``, then rename it over ``path``.

    The parent directory is created if needed. If ``write`` raises, ``path`` is untouched.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        write(tmp_path)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp_path, 0o666 & ~umask)  # mkstemp makes 0600; give the usual mode
        os.replace(tmp_path, path)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()
    return path


def atomic_write_text(path: Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    return atomic_write(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))


def file_sha256(path: Path) -> str:
    """Hex SHA-256 of a file's bytes (read in 4 MiB blocks)."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 22), b""):
            digest.update(block)
    return digest.hexdigest()


def read_numeric_csv(path: str | Path, error: type[Exception], what: str
                     ) -> tuple[list[str], np.ndarray]:
    """Read a numeric text table: the one reader for every numeric file posture_id takes
    (tilt profiles, recordings); :func:`posture_id.text_table.read_text_table` with the
    header and values alone.

    Rules: UTF-8 (a byte-order mark is ignored), else Windows Latin-1; comma, tab or ``;``
    separated, decimal commas with the latter two; blank and comment (``#``, ``%``) lines
    skipped, title lines above the header too; every row has as many fields as the header
    (a trailing delimiter left out); every cell is a finite number; at least one data row.

    Args:
        path: the file. error: the exception class to raise (a ``PostureIdError``).
        what: what the file should be, for messages ("tilt file", "recording").
    Returns:
        (header names stripped of spaces around them, values (rows, columns) float64).
    Raises:
        error: one line naming the file, the line and column, and the problem.
    """
    table = read_text_table(path, error, what)
    return list(table.header), table.values


#: Sample intervals a recording or tilt file can plausibly have, s (1 Hz to 10 kHz).
PLAUSIBLE_INTERVAL_S = (1e-4, 1.0)


def check_time_column(path: Path, time_s: np.ndarray, error: type[Exception],
                      column: str = "time_s", unit: str = "s", flag: str | None = None,
                      lines: np.ndarray | None = None) -> None:
    """Refuse a time column that does not increase or whose unit is not the one it was read
    in (by its median sample interval: milliseconds read as seconds give intervals of 10 or
    20 "seconds").

    Args:
        time_s: (S,) the column in seconds (converted from ``unit``).
        column: its name in the file. unit: ``"s"`` or ``"ms"``, the unit it was read in.
        flag: the flag that gives its unit (``"--time-units"``), named in the advice; None
            where there is none (the standard ``time_s`` column, or a unit the header states).
        lines: (S,) the file's line of each sample (1-based), to name; default: the row
            after a one-line header.
    """
    steps = np.diff(time_s)
    if len(steps) == 0:
        raise error(f"{path}: fewer than two samples")
    bad = np.flatnonzero(steps <= 0)
    if bad.size:
        where = f"row {bad[0] + 2}" if lines is None else f"line {lines[bad[0] + 1]}"
        raise error(f"{path}: {where}: {column} does not increase "
                    f"({time_s[bad[0]]:g} then {time_s[bad[0] + 1]:g})")
    median = float(np.median(steps))
    low, high = PLAUSIBLE_INTERVAL_S
    said = (f"{path}: column '{column}': the median sample interval is {median:g} s "
            f"({1 / median:.3g} Hz)")
    if median > high and unit == "s":
        raise error(f"{said}; is the time in milliseconds? "
                    + (f"give {flag} ms" if flag else f"{column} is in seconds"))
    if median < low and unit == "ms":
        raise error(f"{said} read as milliseconds; is the time in seconds? "
                    + (f"give {flag} s" if flag else "its header says ms"))
    if median > high or median < low:
        raise error(f"{said}; {column} is in {'seconds' if unit == 's' else 'milliseconds'}")


def jsonable(value: Any) -> Any:
    """``value`` as JSON-ready data: dataclasses as dicts (with a ``"type"``), enums by
    value, tuples and arrays as lists, paths as strings, non-finite floats as None."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = {f.name: jsonable(getattr(value, f.name)) for f in dataclasses.fields(value)
                  if f.repr}
        return {"type": type(value).__name__, **fields}
    if isinstance(value, enum.Enum):
        return jsonable(value.value)
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if hasattr(value, "tolist") and getattr(value, "ndim", 0) > 0:  # numpy arrays
        return jsonable(value.tolist())
    if hasattr(value, "item") and callable(value.item):  # numpy scalars
        return jsonable(value.item())
    return value


def json_text(data: Any) -> str:
    """Strict JSON (no NaN or Infinity: non-finite numbers become null), indented."""
    return json.dumps(jsonable(data), indent=2, allow_nan=False) + "\n"



def read_json(path: str | Path, what: str, error: type[Exception] = PostureIdError):
    """The JSON value in ``path`` (UTF-8, a byte-order mark allowed); ``error`` naming the
    file and the problem for a folder, a missing file, other text or invalid JSON. ``what``:
    what the file should be ("a norm file", ...)."""
    path = Path(path)
    if path.is_dir():
        raise error(f"{path}: is a folder, not {what} (JSON)")
    try:
        return json.loads(path.read_text(encoding="utf-8-sig"))
    except FileNotFoundError:
        raise error(f"{path}: no such file ({what})") from None
    except UnicodeDecodeError as exc:
        raise error(f"{path}: not UTF-8 text (byte {exc.start})") from None
    except json.JSONDecodeError as exc:
        raise error(f"{path}: not valid JSON ({exc})") from None


def json_object(path: Path) -> dict:
    """The object a JSON file holds; {} for a file that cannot be read, is not JSON or
    holds something else (for files posture-id wrote itself: a ledger, a result; a user's
    file is read with :func:`read_json`, which says what is wrong)."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


class JsonFile:
    """``to_json()`` of whatever has a ``to_dict()``: strict JSON, written atomically."""

    def to_dict(self) -> dict:  # pragma: no cover - every user defines it
        raise NotImplementedError

    def to_json(self, path: str | Path | None = None) -> str:
        """Strict JSON (:func:`json_text`) of ``to_dict()``; written atomically to ``path``
        when given."""
        text = json_text(self.to_dict())
        if path is not None:
            atomic_write_text(Path(path), text)
        return text


class Result(JsonFile):
    """The result family: every result of posture_id (a simulation, a fit, an
    identification, an FRF, a cohort, a training run, an evaluation, a benchmark, a
    calibration) has ``to_dict()`` (JSON-ready, strings for enums), ``to_json()`` (strict
    JSON, written atomically), ``summary()`` (printable text) and ``plot(path=None,
    ax=None)`` (its principal figure: saved to ``path``, drawn into ``ax`` when given;
    reports with several figures write the rest with ``write(folder)``)."""

    def to_dict(self) -> dict:  # pragma: no cover - every result defines it
        raise NotImplementedError

    def summary(self) -> str:  # pragma: no cover - every result defines it
        raise NotImplementedError

    def plot(self, path: str | Path | None = None, ax=None):  # pragma: no cover
        raise NotImplementedError

