"""Numeric text tables as labs write them: the one reader behind every numeric file
posture_id takes (tilt profiles, recordings, a lab's exports).

A file is read as it is. Detected, in this order:

- the encoding: UTF-8 (a byte-order mark allowed), UTF-16 with its byte-order mark or
  without one (told by the NUL byte of every character pair), else
  Windows Latin-1 (cp1252; ISO Latin-1 where cp1252 cannot decode), said in a notice;
- blank lines and comment lines (starting with ``#`` or ``%``) anywhere: skipped;
- the delimiter, from the last lines (the data, not a title): tab, then ``;``, then ``,``,
  the first that splits most of them into two or more fields (a file of one column:
  ``,``);
- the header: the last line without a number above the first row of numbers as wide as
  the data; lines above it (a title, an export's metadata) are skipped, said in a notice;
- the decimal mark: ``.``, or ``,`` when the delimiter is not a comma and the numbers use
  it; a file whose numbers use both is refused;
- a trailing delimiter at the end of each line (an empty last field): dropped;
- each column's unit, when its header name ends with one in brackets: ``Time [ms]``,
  ``Neigung [°]``, ``COP AP (mm)`` (round brackets for the units of :data:`UNIT_ALIASES`
  only, since ``COP (AP)`` names a column). A column is looked up by its whole header name
  or by its name without the unit.

The numbers are parsed by numpy once the structure is known; only a file that fails there
is read again cell by cell, to name the first bad cell.
"""

from __future__ import annotations

import codecs
import csv
import io
import math
import re
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from posture_id.errors import PostureIdError

__all__ = ["TextTable", "read_text_table", "decode_text", "split_unit", "UNIT_ALIASES"]

#: Unit spellings read from a header (lower case) → the unit's one spelling.
UNIT_ALIASES = {
    "s": "s", "sec": "s", "ms": "ms", "msec": "ms",
    "deg": "deg", "°": "deg", "degree": "deg", "degrees": "deg", "rad": "rad",
    "mm": "mm", "cm": "cm", "m": "m", "n": "N",
}
#: Delimiters tried, in this order (a tab or ``;`` file may also hold decimal commas).
DELIMITERS = ("\t", ";", ",")
#: Lines starting (after blanks) with one of these are comments.
COMMENT_STARTS = ("#", "%")
#: How many of the last lines the delimiter is detected from.
SAMPLE_LINES = 200

_SQUARE = re.compile(r"^(?P<name>.*?\S)\s*\[\s*(?P<unit>[^\[\]]*?)\s*\]$")
_ROUND = re.compile(r"^(?P<name>.*?\S)\s*\(\s*(?P<unit>[^()]*?)\s*\)$")
_DECIMAL_COMMA = re.compile(r",\d|\d,")
_DECIMAL_POINT = re.compile(r"\.\d|\d\.")
_NAMES = {"\t": "tab", ";": "';'", ",": "','"}


def split_unit(name: str) -> tuple[str, str | None]:
    """A header name and the unit it states: ``"COP AP [mm]"`` → ``("COP AP", "mm")``,
    ``"Neigung [°]"`` → ``("Neigung", "deg")``, ``"Fz (N)"`` → ``("Fz", "N")``; a name
    without one → ``(name, None)``. Square brackets always hold a unit (a known one in its
    one spelling, :data:`UNIT_ALIASES`; another as written); round ones only a known unit."""
    name = name.strip()
    square = _SQUARE.match(name)
    if square and square["unit"]:
        unit = square["unit"]
        return square["name"], UNIT_ALIASES.get(unit.lower(), unit)
    round_ = _ROUND.match(name)
    if round_ and round_["unit"].lower() in UNIT_ALIASES:
        return round_["name"], UNIT_ALIASES[round_["unit"].lower()]
    return name, None


@dataclass(frozen=True, eq=False)
class TextTable:
    """A numeric text table, read as it is (:func:`read_text_table`).

    Attributes:
        path: the file.
        header: (C,) the header's names as written (spaces around stripped, inside kept).
        names_without_units: (C,) the same without a stated unit (``"COP AP"``).
        units: (C,) each column's unit as its header states it (``"ms"``, ``"deg"``,
            ``"mm"``, ...; :data:`UNIT_ALIASES`), None where it states none.
        values: (rows, C) float64, every cell a finite number.
        notices: what was detected that a reader may want to know (an encoding other than
            UTF-8, lines skipped above the header, decimal commas, trailing delimiters).
        delimiter: ``"\\t"``, ``";"`` or ``","``. decimal: ``"."`` or ``","``.
        encoding: ``"utf-8"``, ``"utf-8-sig"``, ``"utf-16"``, ``"cp1252"`` or
            ``"latin-1"``.
        header_line: the header's line, 1-based as in the file.
        first_data_line: the first data row's line, 1-based as in the file.
        row_lines: (rows,) int, each data row's line, 1-based as in the file.
        error: the exception class a failed look-up raises.
        what: what the file is, for messages ("recording", "tilt file").
    """

    path: Path
    header: tuple[str, ...]
    names_without_units: tuple[str, ...]
    units: tuple[str | None, ...]
    values: np.ndarray
    notices: tuple[str, ...] = ()
    delimiter: str = ","
    decimal: str = "."
    encoding: str = "utf-8"
    header_line: int = 1
    first_data_line: int = 2
    row_lines: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64),
                                  repr=False)
    error: type[Exception] = field(default=PostureIdError, repr=False)
    what: str = "table"

    @property
    def n_rows(self) -> int:
        """How many data rows."""
        return int(self.values.shape[0])

    def find(self, name: str) -> int | None:
        """The index of the column ``name`` names (its whole header name, else its name
        without the unit), None when none does.

        Raises:
            error: ``name`` names two columns.
        """
        name = name.strip()
        for names in (self.header, self.names_without_units):
            hits = [k for k, n in enumerate(names) if n == name]
            if len(hits) == 1:
                return hits[0]
            if len(hits) > 1:
                raise self.error(
                    f"{self.path}: column {name!r} is named twice (columns "
                    f"{', '.join(repr(self.header[k]) for k in hits)}): name one by its "
                    "whole header name")
        return None

    def index(self, name: str) -> int:
        """The index of column ``name`` (its whole header name or its name without the
        unit). Raises ``error`` naming the file and listing the header when missing."""
        self.require([name])
        found = self.find(name)
        assert found is not None
        return found

    def has(self, name: str) -> bool:
        """True when ``name`` names a column (either spelling)."""
        return self.find(name) is not None

    def require(self, names: Iterable[str]) -> None:
        """Raise ``error`` naming every one of ``names`` that names no column, with the
        file and its header."""
        missing = [n for n in names if self.find(n) is None]
        if missing:
            raise self.error(f"{self.path}: no column {', '.join(repr(n) for n in missing)} "
                             f"(the header is {','.join(self.header)})")

    def column(self, name: str) -> np.ndarray:
        """(rows,) float64, the values of column ``name`` (either spelling)."""
        return self.values[:, self.index(name)]

    def unit_of(self, name: str) -> str | None:
        """The unit column ``name``'s header states (``"ms"``, ``"deg"``, ``"mm"``...;
        :data:`UNIT_ALIASES`), None when it states none."""
        return self.units[self.index(name)]

    def stated_unit(self, name: str, allowed: Iterable[str], given: str | None,
                    flag: str, what: str, kind: str) -> str | None:
        """The unit column ``name``'s header states (None: none), checked: one of
        ``allowed`` (``what`` the column must be: "time column must be in s or ms"), and
        the ``kind`` of unit ("time") ``given`` by the caller (None: none; its ``flag``
        named) not contradicting it. Raises ``error`` naming the file, the column and
        both units."""
        stated = self.unit_of(name)
        if stated is None:
            return None
        whole = self.header[self.index(name)]
        if stated not in set(allowed):
            raise self.error(f"{self.path}: column {whole!r} is in {stated} by its header; "
                             f"the {what}")
        if given is not None and given != stated:
            raise self.error(
                f"{self.path}: column {whole!r} is in {stated} by its header, but the {kind} "
                f"unit given is {given} ({flag} {given}): leave the unit out or correct the "
                "header")
        return stated

    def line_of(self, row: int) -> int:
        """The file's line (1-based) of data row ``row`` (0-based)."""
        return int(self.row_lines[row])


def read_text_table(path: str | Path, error: type[Exception] = PostureIdError,
                    what: str = "table") -> TextTable:
    """Read a numeric text table as a lab wrote it (the module's doc says what is
    detected and how).

    Args:
        path: the file. error: the exception class to raise (a ``PostureIdError``).
        what: what the file should be, for messages ("tilt file", "recording").
    Returns:
        :class:`TextTable`.
    Raises:
        error: one line naming the file, the line (1-based, as in the file) and column
            where there is one, and the problem: no such file, a folder, binary data, an
            empty file, a header without data, no header, an ambiguous decimal mark, a row
            with another number of fields than the header, a cell that is not a finite
            number.
    """
    path = Path(path)
    text, encoding, notices = decode_text(path, error, what)
    text = text.replace("\r\n", "\n").replace("\r", "\n")
    lines = text.split("\n")
    content = _content_lines(text, len(lines))
    if not content:
        raise error(f"{path}: empty file, expected a {what}")
    delimiter, width = _delimiter(lines, content)
    split = _Splitter(lines, delimiter)
    head = _header_position(content, split, width, path, error)
    header_k = content[head]
    data = content[head + 1:]
    names = split.cells(header_k)
    if len(names) > 1 and not names[-1].strip() and width != len(names):
        names = names[:-1]  # a trailing delimiter
    header = tuple(n.strip() for n in names)
    if head > 0:
        first = lines[content[0]].strip()
        shown = first if len(first) <= 60 else first[:57] + "..."
        span = (f"line {content[0] + 1}" if head == 1
                else f"lines {content[0] + 1}-{content[head - 1] + 1}")
        notices.append(f"{path}: {span} above the header (line {header_k + 1}) skipped: "
                       f"{shown!r}")
    if not data:
        raise error(f"{path}: a header and no data rows"
                    + (f" (the header is line {header_k + 1})" if header_k else ""))
    block = "\n".join(lines[k] for k in data)
    decimal = _decimal(delimiter, block, data, split, header, path, error)
    if decimal == ",":
        notices.append(f"{path}: decimal commas")
    fast = _fast_values(block, delimiter, decimal, len(header), len(data))
    values, trailing = fast if fast is not None else _slow_values(
        data, split, header, decimal, header_k, path, error)
    if trailing:
        notices.append(f"{path}: a trailing {_NAMES[delimiter]} at the end of the lines "
                       "(an empty last field) left out")
    split_names = [split_unit(n) for n in header]
    return TextTable(
        path=path, header=header,
        names_without_units=tuple(n for n, _ in split_names),
        units=tuple(u for _, u in split_names),
        values=values, notices=tuple(notices), delimiter=delimiter, decimal=decimal,
        encoding=encoding, header_line=header_k + 1, first_data_line=data[0] + 1,
        row_lines=np.asarray(data, dtype=np.int64) + 1, error=error, what=what)


_SKIPPED = re.compile(r"^[^\S\n]*(?:[#%][^\n]*)?$", re.MULTILINE)


def _content_lines(text: str, n_lines: int) -> list[int]:
    """The indices of the lines of ``text`` (split at "\\n") that are neither blank nor
    comments (found by one regular-expression scan: most files have few)."""
    skipped = []
    line, position = 0, 0
    for match in _SKIPPED.finditer(text):
        line += text.count("\n", position, match.start())
        position = match.start()
        skipped.append(line)
    if not skipped:
        return list(range(n_lines))
    keep = np.ones(n_lines, dtype=bool)
    keep[skipped] = False
    return np.flatnonzero(keep).tolist()


def _utf16_without_mark(raw: bytes) -> tuple[str, str] | None:
    """(codec, its name) when ``raw`` reads as UTF-16 text with no byte-order mark: an even
    number of bytes, and one byte of nearly every pair NUL (ASCII and Latin text), the
    other of nearly none; else None (binary data)."""
    if len(raw) < 4 or len(raw) % 2:
        return None
    even, odd = raw[0::2], raw[1::2]
    zeros_even, zeros_odd = even.count(0) / len(even), odd.count(0) / len(odd)
    if zeros_odd > 0.9 and zeros_even < 0.05:
        return "utf-16-le", "little-endian"
    if zeros_even > 0.9 and zeros_odd < 0.05:
        return "utf-16-be", "big-endian"
    return None


def decode_text(path: Path, error: type[Exception], what: str) -> tuple[str, str, list[str]]:
    """A text file's text, its encoding and the notice of one other than UTF-8 (the
    module doc), for every file a user brings (tables, manifests).

    Raises:
        ``error``: naming the file: missing, a folder, unreadable, binary data.
    """
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise error(f"{path}: no such {what}") from None
    except IsADirectoryError:
        raise error(f"{path}: is a folder, expected a {what} (a text table: CSV, "
                    "tab- or ';'-separated)") from None
    except OSError as exc:
        raise error(f"{path}: cannot be read ({exc.strerror})") from None
    if raw.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        try:
            return raw.decode("utf-16"), "utf-16", [f"{path}: read as UTF-16"]
        except UnicodeDecodeError as exc:
            raise error(f"{path}: not UTF-16 text after its byte-order mark (byte "
                        f"{exc.start})") from None
    nul = raw.find(b"\x00")
    if nul >= 0:
        order = _utf16_without_mark(raw)
        if order is None:
            raise error(f"{path}: binary data (byte {nul} is NUL), not a {what} (text)")
        codec, said = order
        try:
            return raw.decode(codec), codec, [
                f"{path}: read as UTF-16 ({said}, no byte-order mark)"]
        except UnicodeDecodeError as exc:
            raise error(f"{path}: neither text nor UTF-16 {said} (byte {exc.start})") from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        for encoding, said in (("cp1252", "Windows Latin-1 (cp1252)"),
                               ("latin-1", "Latin-1 (ISO 8859-1)")):
            try:
                return raw.decode(encoding), encoding, [
                    f"{path}: not UTF-8 (byte {exc.start}); read as {said}"]
            except UnicodeDecodeError:
                continue
        raise AssertionError("Latin-1 decodes every byte") from None
    return text, "utf-8-sig" if raw.startswith(codecs.BOM_UTF8) else "utf-8", []


def _field_count(line: str, delimiter: str) -> int:
    """Fields of ``line`` split at ``delimiter``, a trailing delimiter not counted."""
    count = line.count(delimiter) + 1
    if count > 1 and line.rstrip(" ").endswith(delimiter):
        count -= 1
    return count


def _delimiter(lines: list[str], content: list[int]) -> tuple[str, int]:
    """The delimiter and the data's width (fields), from the last lines."""
    sample = [lines[k] for k in content[-SAMPLE_LINES:]]
    fallback = None
    for delimiter in DELIMITERS:
        counts = Counter(_field_count(line, delimiter) for line in sample)
        freq, width = max((f, w) for w, f in counts.items())
        if width >= 2 and 2 * freq >= len(sample):
            return delimiter, width
        if fallback is None and delimiter == ",":
            fallback = (delimiter, width)
    assert fallback is not None
    return fallback


class _Splitter:
    """Lines split into cells at one delimiter (CSV quoting honoured), each once."""

    def __init__(self, lines: list[str], delimiter: str) -> None:
        self.lines = lines
        self.delimiter = delimiter
        self._cells: dict[int, list[str]] = {}

    def cells(self, k: int) -> list[str]:
        """The cells of line ``k`` (0-based), as written."""
        if k not in self._cells:
            line = self.lines[k]
            if '"' in line:
                try:
                    row = next(csv.reader([line], delimiter=self.delimiter))
                except (csv.Error, StopIteration):
                    row = line.split(self.delimiter)
            else:
                row = line.split(self.delimiter)
            self._cells[k] = row or [""]
        return self._cells[k]

    def kind(self, k: int) -> str:
        """"numeric" (every cell a number, either decimal mark), "text" (no cell a
        number) or "mixed"."""
        cells = self.cells(k)
        if len(cells) > 1 and not cells[-1].strip():
            cells = cells[:-1]
        numbers = sum(_number_like(c) for c in cells)
        if numbers == len(cells):
            return "numeric"
        if numbers == 0 and any(c.strip() for c in cells):
            return "text"
        return "mixed"

    def width(self, k: int) -> int:
        """Fields of line ``k``, a trailing empty one not counted."""
        cells = self.cells(k)
        return len(cells) - 1 if len(cells) > 1 and not cells[-1].strip() else len(cells)


def _number_like(cell: str) -> bool:
    cell = cell.strip()
    if not cell:
        return False
    for candidate in (cell, cell.replace(",", ".")):
        try:
            float(candidate)
            return True
        except ValueError:
            continue
    return False


def _header_position(content: list[int], split: _Splitter, width: int, path: Path,
                     error: type[Exception]) -> int:
    """The index in ``content`` of the header: the last line without a number above the
    first row of numbers as wide as the data (before it: a title, metadata)."""
    start = None
    first_other = None
    for i, k in enumerate(content):
        kind = split.kind(k)
        if kind != "text" and first_other is None:
            first_other = i
        if kind == "numeric" and split.width(k) == width:
            start = i
            break
    if start is None and first_other is None:  # no number anywhere: the header alone
        return next((i for i, k in enumerate(content) if split.width(k) == width), 0)
    start = first_other if start is None else start
    for i in range(start - 1, -1, -1):
        if split.kind(content[i]) == "text":
            return i
    if start == 0:
        raise error(f"{path}: line {content[0] + 1} holds numbers where the header should "
                    "be: name the columns in a header line above the data")
    return 0


def _decimal(delimiter: str, block: str, data: list[int], split: _Splitter,
             header: tuple[str, ...], path: Path, error: type[Exception]) -> str:
    """``","`` when the numbers use decimal commas (not with a comma delimiter), else
    ``"."``; refused when they use both."""
    if delimiter == ",":
        return "."
    comma = _DECIMAL_COMMA.search(block) if "," in block else None
    if comma is None:
        return "."
    point = _DECIMAL_POINT.search(block) if "." in block else None
    if point is None:
        return ","

    def where(match: re.Match) -> str:
        row = block.count("\n", 0, match.start())
        line_start = block.rfind("\n", 0, match.start()) + 1
        column = block.count(delimiter, line_start, match.start())
        cell = split.cells(data[row])[column] if column < len(split.cells(data[row])) else ""
        name = header[column] if column < len(header) else f"#{column + 1}"
        return f"line {data[row] + 1}, column '{name}' ({cell.strip()!r})"

    raise error(f"{path}: both decimal commas ({where(comma)}) and decimal points "
                f"({where(point)}): the decimal mark is ambiguous; save the file with one")


def _fast_values(block: str, delimiter: str, decimal: str, n_columns: int,
                 n_rows: int) -> tuple[np.ndarray, bool] | None:
    """The values parsed by numpy, (n_rows, n_columns), and whether every line ended with
    the delimiter (an empty last field, left out); None when anything is not plainly well
    formed (the slow reader then names the problem, or reads what numpy would not)."""
    if '"' in block:
        return None
    if decimal == ",":
        block = block.replace(",", ".")
    first = block[:block.find("\n")] if "\n" in block else block
    trailing = first.endswith(delimiter)
    if trailing:  # every line must end with the delimiter, else the slow reader decides
        ends = block.count(delimiter + "\n") + block.endswith(delimiter)
        if ends != n_rows:
            return None
        block = block.replace(delimiter + "\n", "\n").removesuffix(delimiter)
    try:
        values = np.loadtxt(io.StringIO(block), delimiter=delimiter, comments=None,
                            dtype=np.float64, ndmin=2)
    except ValueError:
        return None
    if values.shape != (n_rows, n_columns) or not np.isfinite(values).all():
        return None
    return values, trailing


def _slow_values(data: list[int], split: _Splitter, header: tuple[str, ...], decimal: str,
                 header_k: int, path: Path, error: type[Exception]
                 ) -> tuple[np.ndarray, bool]:
    """The values cell by cell: the first bad row or cell raised, named by its line
    and column; also whether a trailing delimiter was left out."""
    n = len(header)
    values = np.empty((len(data), n))
    trailing = False
    said_header = "the header" if header_k == 0 else f"the header (line {header_k + 1})"
    for r, k in enumerate(data):
        cells = split.cells(k)
        if len(cells) == n + 1 and not cells[-1].strip():
            cells = cells[:-1]
            trailing = True
        if len(cells) != n:
            raise error(f"{path}: line {k + 1}: {len(cells)} fields, {said_header} has {n}")
        for c, cell in enumerate(cells):
            try:
                x = float(cell.replace(",", ".") if decimal == "," else cell)
            except ValueError:
                raise error(f"{path}: line {k + 1}, column '{header[c]}': not a number "
                            f"({cell!r})") from None
            if not math.isfinite(x):
                raise error(f"{path}: line {k + 1}, column '{header[c]}': {cell.strip()} is "
                            "not a finite number")
            values[r, c] = x
    return values, trailing
