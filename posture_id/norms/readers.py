"""FRFs of several subjects from what labs have: FRF JSONs (``posture-id frf``), a table
(CSV: one row per subject, columns ``<f>_re`` and ``<f>_im``, or ``<f>_gain`` and
``<f>_phase_deg``, f in Hz), or a MATLAB ``.mat`` file holding an N × F complex matrix
(``variable``, with the frequencies given)."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np

from posture_id.errors import PostureIdError
from posture_id.fileio import read_json
from posture_id.norms.norm import FrfSet

__all__ = ["read_frfs", "frf_from_json", "frf_json_channels", "is_frf_table"]

#: A CSV table's FRF column: ``<f>_re``, ``<f>_im``, ``<f>_gain`` or ``<f>_phase_deg``.
_FRF_COLUMN = re.compile(r"^((?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)_(re|im|gain|phase_deg)$")


def _frf_json(path: Path) -> dict:
    """An FRF JSON's object, or a refusal naming the file."""
    data = read_json(path, "an FRF file")
    if not isinstance(data, dict) or "frequencies_hz" not in data or \
            not isinstance(data.get("channels"), dict):
        raise PostureIdError(f"{path}: not an FRF file (posture-id frf writes "
                             "frequencies_hz and channels)")
    return data


def frf_json_channels(path: Path) -> tuple[str, ...]:
    """The names of an FRF JSON's channels (the file checked to be one, its channels not
    read)."""
    return tuple(_frf_json(path)["channels"])


def frf_from_json(path: Path, channels: tuple[str, ...] | None = None
                  ) -> tuple[np.ndarray, np.ndarray, tuple[str, ...], dict | None]:
    """(frequencies (F,), H (F, M), channels, its lab bands or None) of one FRF JSON.

    Raises:
        PostureIdError: naming the file (and the channel): not an FRF file, a channel it
            lacks, a channel without ``re`` and ``im`` (or ``gain`` and ``phase_deg``), a
            length other than the frequencies', values that are not finite numbers.
    """
    data = _frf_json(path)
    f = _finite_vector(data["frequencies_hz"], f"{path}: frequencies_hz")
    names = tuple(channels or data["channels"])
    columns = []
    for name in names:
        if name not in data["channels"]:
            raise PostureIdError(f"{path}: no channel {name!r} (it has "
                                 f"{', '.join(data['channels'])})")
        columns.append(_channel_response(data["channels"][name], len(f),
                                         f"{path}: channel {name!r}"))
    return f, np.stack(columns, axis=1), names, data.get("lab_bands")


def _finite_vector(values, where: str, length: int | None = None) -> np.ndarray:
    """``values`` as a (length,) float array, or a refusal naming ``where``."""
    try:
        v = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise PostureIdError(f"{where}: not a list of numbers") from None
    if v.ndim != 1:
        raise PostureIdError(f"{where}: not a list of numbers")
    if length is not None and len(v) != length:
        raise PostureIdError(f"{where}: {len(v)} values for {length} frequencies")
    bad = np.flatnonzero(~np.isfinite(v))
    if bad.size:
        raise PostureIdError(f"{where}: value {bad[0] + 1} is not finite ({v[bad[0]]})")
    return v


def _channel_response(channel, length: int, where: str) -> np.ndarray:
    """One FRF JSON channel's (F,) complex response: from ``re`` and ``im``, or from
    ``gain`` and ``phase_deg``; a channel with both pairs must have them agree."""
    if not isinstance(channel, dict):
        raise PostureIdError(f"{where}: not an object of re and im (or gain and phase_deg)")
    found = []
    for real, other in (("re", "im"), ("gain", "phase_deg")):
        if real in channel or other in channel:
            if real not in channel or other not in channel:
                missing = other if real in channel else real
                raise PostureIdError(f"{where}: has {real if real in channel else other} "
                                     f"but no {missing}: give re and im, or gain and "
                                     "phase_deg")
            a = _finite_vector(channel[real], f"{where}: {real}", length)
            b = _finite_vector(channel[other], f"{where}: {other}", length)
            found.append(a + 1j * b if real == "re" else a * np.exp(1j * np.radians(b)))
    if not found:
        raise PostureIdError(f"{where}: no re and im (nor gain and phase_deg)")
    if len(found) == 2:
        apart = np.abs(found[0] - found[1]) > 1e-6 * np.maximum(np.abs(found[0]), 1e-9)
        if apart.any():
            raise PostureIdError(f"{where}: gain and phase_deg disagree with re and im (value "
                                 f"{np.flatnonzero(apart)[0] + 1}): the file was edited; keep "
                                 "one pair")
    return found[0]


def is_frf_table(path: Path) -> bool:
    """Whether a CSV file is a table of FRFs (a header with ``<f>_re`` ... columns), not a
    recording; False for a file that cannot be read (its reader says why)."""
    try:
        with Path(path).open(encoding="utf-8-sig", newline="") as handle:
            header = next(csv.reader(handle), [])
    except (OSError, UnicodeDecodeError, csv.Error):
        return False
    return any(_FRF_COLUMN.match(c.strip()) for c in header)


def _read_table(path: Path) -> FrfSet:
    """A CSV table: one row per subject (``subject`` or ``name`` its name), the FRF in
    ``<f>_re`` and ``<f>_im`` or ``<f>_gain`` and ``<f>_phase_deg`` columns; a row whose
    number of fields is not the header's, or a value that is not a finite number, is
    refused by line."""
    with Path(path).open(encoding="utf-8-sig", newline="") as handle:
        rows = list(csv.reader(handle))
    while rows and not any(cell.strip() for cell in rows[-1]):
        rows.pop()
    if len(rows) < 2:
        raise PostureIdError(f"{path}: a header and no subjects")
    header = [c.strip() for c in rows[0]]
    found: dict[float, dict[str, int]] = {}
    for index, column in enumerate(header):
        match = _FRF_COLUMN.match(column)
        if match is None and re.match(r"^.+_(re|im|gain|phase_deg)$", column):
            raise PostureIdError(f"{path}: column {column!r}: "
                                 f"{column.rsplit('_', 2 if column.endswith('_deg') else 1)[0]!r}"
                                 " is not a frequency in Hz (<f>_re, e.g. 0.05_re)")
        if match:
            cells = found.setdefault(float(match.group(1)), {})
            if match.group(2) in cells:
                raise PostureIdError(f"{path}: columns {header[cells[match.group(2)]]} and "
                                     f"{column} are one frequency's {match.group(2)} twice")
            cells[match.group(2)] = index
    if not found:
        raise PostureIdError(f"{path}: no FRF columns (<f>_re and <f>_im, or <f>_gain and "
                             f"<f>_phase_deg; the header is {','.join(header)})")
    f = np.array(sorted(found))
    for freq in f:
        if not ({"re", "im"} <= found[freq].keys() or
                {"gain", "phase_deg"} <= found[freq].keys()):
            raise PostureIdError(f"{path}: {freq:g} Hz has {sorted(found[freq])}: give re "
                                 "and im, or gain and phase_deg")
    name_column = next((header.index(n) for n in ("subject", "name") if n in header), None)
    names, response = [], []
    for k, row in enumerate(rows[1:], 2):
        if len(row) != len(header):
            raise PostureIdError(f"{path}: line {k} has {len(row)} fields, the header "
                                 f"{len(header)}: a value missing or one too many shifts "
                                 "every column after it")
        values = []
        for freq in f:
            cols = found[freq]
            pair = ("re", "im") if "re" in cols else ("gain", "phase_deg")
            a, b = (_table_number(row[cols[key]], path, k, header[cols[key]]) for key in pair)
            values.append(a + 1j * b if pair[0] == "re" else a * np.exp(1j * np.radians(b)))
        names.append(row[name_column] if name_column is not None and row[name_column]
                     else f"row {k}")
        response.append(values)
    return FrfSet(f, np.asarray(response)[:, :, None], ("COM",), tuple(names))


def _table_number(cell: str, path: Path, line: int, column: str) -> float:
    try:
        value = float(cell)
    except ValueError:
        raise PostureIdError(f"{path}: line {line}, column {column}: {cell!r} is not a "
                             "number") from None
    if not np.isfinite(value):
        raise PostureIdError(f"{path}: line {line}, column {column}: {cell!r} is not finite")
    return value


def _read_mat(path: Path, variable: str | None, frequencies: list[float] | None) -> FrfSet:
    """An N × F complex matrix of a MATLAB file (v4 to v7, what scipy reads)."""
    from scipy.io import loadmat

    if variable is None or not frequencies:
        raise PostureIdError(f"{path}: a .mat file needs --variable NAME and --frequencies "
                             "F ... (its N × F complex matrix and the frequencies)")
    if path.is_dir():
        raise PostureIdError(f"{path}: is a folder, not a MATLAB file")
    with path.open("rb") as handle:
        head = handle.read(128)
    if head.startswith(b"MATLAB 7.3"):
        raise PostureIdError(f"{path}: a MATLAB v7.3 file (HDF5), which posture-id does not "
                             "read: save it as v7 in MATLAB (save(file, 'H', '-v7'))")
    try:
        data = loadmat(path)
    except Exception as exc:  # noqa: BLE001 - scipy raises many kinds for a bad file
        raise PostureIdError(f"{path}: not a MATLAB file that can be read (truncated or "
                             f"corrupt, or another format: {exc})") from None
    if variable not in data:
        raise PostureIdError(f"{path}: no variable {variable!r} (it has "
                             f"{', '.join(k for k in data if not k.startswith('__'))})")
    h = np.asarray(data[variable])
    if h.ndim != 2 or h.shape[1] != len(frequencies):
        raise PostureIdError(f"{path}: {variable} is {h.shape}; expected subjects × "
                             f"{len(frequencies)} frequencies")
    if not np.issubdtype(h.dtype, np.number):
        raise PostureIdError(f"{path}: {variable} holds {h.dtype}, not numbers")
    if not np.iscomplexobj(h):
        raise PostureIdError(f"{path}: {variable} holds real numbers; an FRF is complex "
                             "(gain·e^(i·phase)): give the complex matrix (gains alone have "
                             "no phase, and would be read with every phase 0)")
    bad = np.argwhere(~np.isfinite(h))
    if len(bad):
        raise PostureIdError(f"{path}: {variable}[{bad[0][0] + 1}, {bad[0][1] + 1}] (subject "
                             f"{bad[0][0] + 1}, {frequencies[bad[0][1]]:g} Hz) is not finite")
    return FrfSet(np.asarray(frequencies, float), h.astype(complex)[:, :, None], ("COM",),
                  tuple(f"{variable}[{i}]" for i in range(len(h))))


def read_frfs(paths: list[Path], channels: tuple[str, ...] | None = None,
              variable: str | None = None, frequencies: list[float] | None = None
              ) -> tuple[FrfSet, dict | None]:
    """The FRFs of ``paths``: FRF JSONs (one subject each), one CSV table, or one .mat;
    with the lab bands the JSONs were computed at (or None).

    Args:
        paths: the files: FRF JSONs (each once, at the same frequencies), or a single
            CSV table or ``.mat`` file.
        channels: the FRF JSONs' channels read (default: every channel of each file);
            a table or ``.mat`` file gives one channel, ``COM``.
        variable: the ``.mat`` file's N × F complex matrix (required for a ``.mat``).
        frequencies: the ``.mat`` matrix's F column frequencies, Hz (required for a
            ``.mat``).
    Returns:
        (:class:`FrfSet` (N subjects, F frequencies, M channels), the JSONs' lab bands or
        None).
    Raises:
        PostureIdError: naming the file: missing, given twice, of mixed kinds, at other
            frequencies than the first, or not readable as an FRF.
    """
    paths = [Path(p) for p in paths]
    seen: set[Path] = set()
    for p in paths:
        if not p.exists():
            raise PostureIdError(f"{p}: no such file")
        if p.resolve() in seen:
            raise PostureIdError(f"{p}: given twice; each member counts once")
        seen.add(p.resolve())
    suffixes = {p.suffix.lower() for p in paths}
    if suffixes <= {".csv"} and len(paths) == 1:
        return _read_table(paths[0]), None
    if suffixes <= {".mat"} and len(paths) == 1:
        return _read_mat(paths[0], variable, frequencies), None
    if suffixes != {".json"}:
        raise PostureIdError("give FRF JSONs (one per subject), one CSV table or one .mat "
                             f"file, not {', '.join(sorted(suffixes))} together")
    f0, names, bands, response = None, None, None, []
    for p in paths:
        f, h, names_here, bands_here = frf_from_json(p, channels)
        if f0 is None:
            f0, names, bands = f, names_here, bands_here
        elif f.shape != f0.shape or not np.allclose(f, f0, atol=1e-6):
            raise PostureIdError(f"{p}: its FRF is at other frequencies than {paths[0]}'s: "
                                 "compute every FRF at the same points (--band-preset)")
        response.append(h)
    return FrfSet(f0, np.stack(response), names, tuple(p.stem for p in paths)), bands
