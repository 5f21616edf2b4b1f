"""One resumable journal for every long study: JSON lines, a header line first.

A study appends each finished row as it goes (flushed and synced: a killed run loses at
most the row being written); a run started again with the same header reads the rows back
and redoes only what is missing. A journal of another set-up (another header) is refused.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from pathlib import Path

from posture_id.errors import PostureIdError
from posture_id.fileio import atomic_write_text, jsonable

__all__ = ["Journal"]


@dataclass(frozen=True)
class Journal:
    """The journal at ``path`` for the set-up ``header`` (a JSON-able dict: body, model,
    data set, seed...); ``key(row)`` says which piece of work a row is."""

    path: Path
    header: dict
    key: Callable[[dict], Hashable]

    def read(self) -> dict[Hashable, dict]:
        """The rows written so far, by key (empty when there is no journal). A torn last
        line (the row being written when the run stopped) is dropped from the file.

        Raises:
            PostureIdError: the journal was written for another set-up.
        """
        path = Path(self.path)
        if not path.exists():
            return {}
        lines = path.read_text(encoding="utf-8").splitlines()
        try:
            found = json.loads(lines[0]) if lines else None
        except json.JSONDecodeError:
            found = None
        if found != self.header:
            raise PostureIdError(f"{path}: a journal of another set-up (the body, model, data "
                                 "set, trials or seed differ); remove it or choose another "
                                 "--out")
        rows, kept = {}, [lines[0]]
        for line in lines[1:]:
            try:
                row = json.loads(line)
            except json.JSONDecodeError:
                continue  # the line being written when the run stopped
            kept.append(line)
            if "e_rel" in row:  # strict JSON has no infinity: a fallen re-simulation
                row["e_rel"] = math.inf if row["e_rel"] is None else row["e_rel"]
            rows[self.key(row)] = row
        if len(kept) < len(lines) or not path.read_bytes().endswith(b"\n"):
            atomic_write_text(path, "\n".join(kept) + "\n")  # the torn line out
        return rows

    def append(self, row: dict) -> None:
        """Add one finished row (the header first, when the journal is new), synced."""
        path = Path(self.path)
        path.parent.mkdir(parents=True, exist_ok=True)
        new = not path.exists() or path.stat().st_size == 0
        with path.open("a", encoding="utf-8") as f:
            if new:
                f.write(json.dumps(self.header) + "\n")
            f.write(json.dumps(jsonable(row), allow_nan=False) + "\n")
            f.flush()
            os.fsync(f.fileno())
