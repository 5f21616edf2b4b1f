"""A study manifest: one CSV row per trial, naming its subject, condition and file, and the
subject's body (a URDF, or the height and mass its Winter body is made from).

    subject,condition,file,height_m,mass_kg
    S01,eyes_open,S01_eo_0.1Hz.txt,1.77,70.4
    S01,eyes_closed,S01_ec_0.1Hz.txt,1.77,70.4

Files and URDFs are relative to the manifest's folder (or absolute). The columns are found
by name in any order (a ``body`` column, or ``height_m`` and ``mass_kg``; a row with a
height and no mass is weighed by the plate's load columns); comma,
semicolon or tab separated; UTF-8, UTF-16 or Windows Latin-1 (said). A row with both a body
and a height and mass uses the body (said). Every refusal is one line naming the
manifest, the line and the column.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

from posture_id.errors import PostureIdError

__all__ = ["TrialEntry", "StudyManifest", "read_manifest", "REQUIRED_COLUMNS"]

#: The columns every manifest has.
REQUIRED_COLUMNS = ("subject", "condition", "file")
#: The delimiters by name.
_NAMES = {",": "comma", ";": "semicolon", "\t": "tab"}
#: A person's height (m) and mass (kg).
_HEIGHT_M, _MASS_KG = (1.0, 2.5), (20.0, 250.0)


@dataclass(frozen=True)
class TrialEntry:
    """One trial of the manifest.

    Attributes:
        subject, condition: as written. file: the trial's file (resolved).
        line: its line in the manifest. body: the subject's URDF (resolved), or None.
        height_m, mass_kg: the subject's, for a Winter body (None with a URDF; a mass of
            None: the force plate weighs the subject, ``StudyOptions.load``).
    """

    subject: str
    condition: str
    file: Path
    line: int
    body: Path | None = None
    height_m: float | None = None
    mass_kg: float | None = None

    @property
    def key(self) -> str:
        """A name unique in the study, safe as a file name: subject and file stem."""
        stem = self.file.name.rsplit(".", 1)[0]
        return "".join(c if c.isalnum() or c in "-_" else "_" for c in
                       f"{self.subject}__{stem}")


@dataclass(frozen=True)
class StudyManifest:
    """The trials of a study (in the manifest's order), where it was read from and what
    its reading noticed (an encoding, a row's body chosen over its height and mass)."""

    path: Path
    trials: tuple[TrialEntry, ...]
    notices: tuple[str, ...] = ()

    @property
    def subjects(self) -> tuple[str, ...]:
        """In order of first appearance."""
        return tuple(dict.fromkeys(t.subject for t in self.trials))

    @property
    def conditions(self) -> tuple[str, ...]:
        """In order of first appearance."""
        return tuple(dict.fromkeys(t.condition for t in self.trials))

    def of(self, subject: str) -> tuple[TrialEntry, ...]:
        return tuple(t for t in self.trials if t.subject == subject)


def _text(path: Path) -> tuple[str, list[str]]:
    """The manifest's text and the notice of its encoding (one other than UTF-8)."""
    from posture_id.text_table import decode_text

    if not path.exists():
        raise PostureIdError(f"{path}: no such manifest")
    if path.is_dir():
        raise PostureIdError(f"{path}: is a folder, expected a manifest (CSV)")
    text, _, notices = decode_text(path, PostureIdError, "manifest (CSV)")
    return text, notices


def _number(path: Path, line: int, column: str, cell: str, span: tuple[float, float],
            unit: str) -> float:
    try:
        value = float(cell.replace(",", "."))
    except ValueError:
        raise PostureIdError(f"{path}: line {line}, column '{column}': not a number "
                             f"({cell!r})") from None
    low, high = span
    if not (math.isfinite(value) and low <= value <= high):
        raise PostureIdError(f"{path}: line {line}, column '{column}': {cell} is not a "
                             f"person's ({low:g}–{high:g} {unit}); is it in other units?")
    return value


def read_manifest(path: str | Path) -> StudyManifest:
    """Read and check a study manifest (the module doc).

    Args:
        path: the manifest CSV; the files and URDFs it names are relative to its folder.

    Raises:
        PostureIdError: one line naming the manifest, the line and the column: a column
            missing, an empty cell, a file or URDF that does not exist, a height or mass
            that is not a person's, a subject whose body differs between its rows, the
            same file twice, two subjects or conditions that differ only in case, no
            trials.
    """
    path = Path(path)
    text, notices = _text(path)
    lines = [line for line in text.splitlines() if line.strip() and not line.startswith("#")]
    if not lines:
        raise PostureIdError(f"{path}: an empty manifest (a header "
                             f"{','.join(REQUIRED_COLUMNS)},... and one row per trial)")
    delimiter = max((",", ";", "\t"), key=lambda d: lines[0].count(d))
    rows = list(csv.reader(io.StringIO(text), delimiter=delimiter))
    numbered = [(n, r) for n, r in enumerate(rows, start=1)
                if any(c.strip() for c in r) and not r[0].startswith("#")]
    header = [h.strip().lower() for h in numbered[0][1]]
    twice = sorted({h for h in header if h and header.count(h) > 1})
    if twice:
        raise PostureIdError(f"{path}: line {numbered[0][0]}: column "
                             f"{', '.join(repr(h) for h in twice)} appears twice in the header "
                             "(one column each)")
    missing = [c for c in REQUIRED_COLUMNS if c not in header]
    has_body = "body" in header
    has_size = "height_m" in header  # a mass_kg column, or the plate weighs the subject
    has_mass = "mass_kg" in header
    if missing or not (has_body or has_size):
        wanted = missing + ([] if has_body or has_size else ["body (or height_m and mass_kg)"])
        raise PostureIdError(f"{path}: no column {', '.join(wanted)} (the header is "
                             f"{delimiter.join(numbered[0][1])})")
    folder = path.parent
    trials, bodies, files, both = [], {}, {}, []
    spelled: dict[str, dict[str, tuple[str, int]]] = {"subject": {}, "condition": {}}
    for line, row in numbered[1:]:
        extra = row[len(header):]
        if len(row) < len(header) or any(c.strip() for c in extra):
            raise PostureIdError(f"{path}: line {line}: {len(row)} fields, the header has "
                                 f"{len(header)} (a {_NAMES.get(delimiter, delimiter)} "
                                 "inside a cell? quote it)")
        cell = {h: row[k].strip() for k, h in enumerate(header)}
        for column in REQUIRED_COLUMNS:
            if not cell[column]:
                raise PostureIdError(f"{path}: line {line}, column '{column}': empty")
        file = (folder / cell["file"]).resolve()
        if not file.is_file():
            raise PostureIdError(f"{path}: line {line}, column 'file': no such file "
                                 f"{cell['file']} (relative to {folder})")
        if file in files:
            raise PostureIdError(f"{path}: line {line}, column 'file': {cell['file']} is "
                                 f"already the trial of line {files[file]}")
        files[file] = line
        body = height = mass = None
        if has_body and cell["body"]:
            body = (folder / cell["body"]).resolve()
            if not body.is_file():
                raise PostureIdError(f"{path}: line {line}, column 'body': no such URDF "
                                     f"{cell['body']} (relative to {folder})")
            if has_size and (cell["height_m"] or cell.get("mass_kg")):
                both.append(line)
        elif has_size:
            height = _number(path, line, "height_m", cell["height_m"], _HEIGHT_M, "m")
            mass = (_number(path, line, "mass_kg", cell["mass_kg"], _MASS_KG, "kg")
                    if has_mass and cell["mass_kg"] else None)  # None: the plate weighs
        else:
            raise PostureIdError(f"{path}: line {line}, column 'body': empty (give the "
                                 "subject's URDF, or height_m and mass_kg columns)")
        for column in spelled:  # one spelling of each name: 'closed' is not 'Closed'
            name = cell[column]
            first_name, first_line = spelled[column].setdefault(name.casefold(), (name, line))
            if first_name != name:
                raise PostureIdError(
                    f"{path}: line {line}, column '{column}': {name!r} and {first_name!r} "
                    f"(line {first_line}) differ only in case: write one {column} the same "
                    "way in every row (or name two apart)")
        subject = cell["subject"]
        identity = (body, height, mass)
        first = bodies.setdefault(subject, (identity, line))
        if first[0] != identity:
            raise PostureIdError(f"{path}: line {line}: subject {subject}'s body differs from "
                                 f"line {first[1]}'s (one body per subject)")
        trials.append(TrialEntry(subject, cell["condition"], file, line, body, height, mass))
    if not trials:
        raise PostureIdError(f"{path}: a header and no trials")
    if both:
        lines_said = ", ".join(map(str, both[:5])) + (" ..." if len(both) > 5 else "")
        notices.append(f"{path}: line {lines_said}: both a "
                       "body and height_m and mass_kg: the body URDF is used, the height "
                       "and mass are ignored")
    return StudyManifest(path, tuple(trials), tuple(notices))
