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

__all__ = ["read_frfs", "frf_from_json"]


def frf_from_json(path: Path, channels: tuple[str, ...] | None = None
                  ) -> tuple[np.ndarray, np.ndarray, tuple[str, ...], dict | None]:
    """(frequencies (F,), H (F, M), channels, its lab bands or None) of one FRF JSON."""
    data = read_json(path, "an FRF file")
    if not isinstance(data, dict) or "frequencies_hz" not in data or "channels" not in data:
        raise PostureIdError(f"{path}: not an FRF file (posture-id frf writes "
                             "frequencies_hz and channels)")
    f = np.asarray(data["frequencies_hz"], dtype=float)
    names = tuple(channels or data["channels"])
    columns = []
    for name in names:
        if name not in data["channels"]:
            raise PostureIdError(f"{path}: no channel {name!r} (it has "
                                 f"{', '.join(data['channels'])})")
        c = data["channels"][name]
        if "re" in c:
            columns.append(np.asarray(c["re"], float) + 1j * np.asarray(c["im"], float))
        else:
            columns.append(np.asarray(c["gain"], float)
                           * np.exp(1j * np.radians(np.asarray(c["phase_deg"], float))))
    return f, np.stack(columns, axis=1), names, data.get("lab_bands")


def _read_table(path: Path) -> FrfSet:
    with Path(path).open(encoding="utf-8-sig", newline="") as handle:
        rows = list(csv.DictReader(handle))
    if not rows:
        raise PostureIdError(f"{path}: a header and no subjects")
    header = list(rows[0])
    pattern = re.compile(r"^([0-9.]+)_(re|im|gain|phase_deg)$")
    found: dict[float, dict[str, str]] = {}
    for column in header:
        match = pattern.match(column.strip())
        if match:
            found.setdefault(float(match.group(1)), {})[match.group(2)] = column
    if not found:
        raise PostureIdError(f"{path}: no FRF columns (<f>_re and <f>_im, or <f>_gain and "
                             f"<f>_phase_deg; the header is {','.join(header)})")
    f = np.array(sorted(found))
    names, response = [], []
    for k, row in enumerate(rows, 2):
        values = []
        for freq in f:
            cols = found[freq]
            try:
                if {"re", "im"} <= cols.keys():
                    values.append(float(row[cols["re"]]) + 1j * float(row[cols["im"]]))
                elif {"gain", "phase_deg"} <= cols.keys():
                    values.append(float(row[cols["gain"]]) * np.exp(
                        1j * np.radians(float(row[cols["phase_deg"]]))))
                else:
                    raise PostureIdError(f"{path}: {freq:g} Hz has {sorted(cols)}: give re "
                                         "and im, or gain and phase_deg")
            except (TypeError, ValueError):
                raise PostureIdError(f"{path}: line {k}: a value at {freq:g} Hz is not a "
                                     "number") from None
        names.append(row.get("subject") or row.get("name") or f"row {k}")
        response.append(values)
    return FrfSet(f, np.asarray(response)[:, :, None], ("COM",), tuple(names))


def _read_mat(path: Path, variable: str | None, frequencies: list[float] | None) -> FrfSet:
    from scipy.io import loadmat

    if variable is None or not frequencies:
        raise PostureIdError(f"{path}: a .mat file needs --variable NAME and --frequencies "
                             "F ... (its N × F complex matrix and the frequencies)")
    try:
        data = loadmat(path)
    except (ValueError, OSError) as exc:
        raise PostureIdError(f"{path}: not a MATLAB file scipy reads ({exc})") from None
    if variable not in data:
        raise PostureIdError(f"{path}: no variable {variable!r} (it has "
                             f"{', '.join(k for k in data if not k.startswith('__'))})")
    h = np.asarray(data[variable])
    if h.ndim != 2 or h.shape[1] != len(frequencies):
        raise PostureIdError(f"{path}: {variable} is {h.shape}; expected subjects × "
                             f"{len(frequencies)} frequencies")
    return FrfSet(np.asarray(frequencies, float), h.astype(complex)[:, :, None], ("COM",),
                  tuple(f"{variable}[{i}]" for i in range(len(h))))


def read_frfs(paths: list[Path], channels: tuple[str, ...] | None = None,
              variable: str | None = None, frequencies: list[float] | None = None
              ) -> tuple[FrfSet, dict | None]:
    """The FRFs of ``paths``: FRF JSONs (one subject each), one CSV table, or one .mat;
    with the lab bands the JSONs were computed at (or None)."""
    paths = [Path(p) for p in paths]
    for p in paths:
        if not p.exists():
            raise PostureIdError(f"{p}: no such file")
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
