"""Marker or tracker positions in a text table (a virtual-reality lab's export, a motion
tracker's CSV): each point's three coordinate columns read as a motion-capture trial, so
that the angles come from the same route as a C3D's (:func:`~.angles.marker_angles`: the
segments' and the body COM's angles, the forward axis and the upright checks, gaps).

A point ``HIP`` is the three columns its name spells with an axis: ``HIP_x``, ``HIP.x``,
``HIP x``, ``HIP:x``, ``HIP-x`` or ``HIPx`` (any case, a unit in the header allowed:
``HIP_x [m]``). The positions are in the unit the headers state (``m``, ``cm``, ``mm``),
else the one given, else metres; a unit that no standing person's segments fit is refused
with the unit that fits. Time stamps that jitter (a headset's clock) are resampled onto
their even clock first (:func:`~posture_id.recording.on_even_time`), said in a notice. The
platform's tilt is the table's tilt column (an angle), or two platform points
(``--tilt-markers``), or the named stimulus's. A point at exactly (0, 0, 0), what a tracker
writes when it loses tracking, is missing there, and its gap is filled (or refused) as a
C3D's is.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from posture_id.errors import RecordingError
from posture_id.motion_capture.c3d_file import METRES_PER_UNIT, MotionCaptureTrial
from posture_id.motion_capture.mapping import MarkerMapping, TiltChannel, TiltMarkers
from posture_id.recording import Recording, RecordingColumns, lab_columns, on_even_time
from posture_id.text_table import TextTable, read_text_table

__all__ = ["LengthUnit", "MarkerColumns", "read_marker_table", "AXIS_SEPARATORS",
           "SEGMENT_LENGTH_M"]


class LengthUnit(enum.Enum):
    """A position column's unit."""

    METRES = "m"
    CENTIMETRES = "cm"
    MILLIMETRES = "mm"


#: What may stand between a point's name and its axis in a column's name.
AXIS_SEPARATORS = ("_", ".", " ", ":", "-", "")
#: m, the median length a point pair (a segment, the support to the COM) may have in a
#: standing person: a unit that puts it outside is not the positions' unit.
SEGMENT_LENGTH_M = (0.05, 2.5)


@dataclass(frozen=True)
class MarkerColumns:
    """How a text table's marker or tracker positions are read.

    Attributes:
        mapping: the points of each segment (or of the body COM), the lab's axes and any
            platform points (:class:`~.mapping.MarkerMapping`; a tilt channel is not a
            table's: its tilt is ``columns.tilt``).
        columns: the time column, its unit, a sample rate that replaces it, and the tilt
            column (an angle, in ``columns.unit``), None without one; no angle columns.
        position_unit: of the position columns whose headers state none (default metres).
    """

    mapping: MarkerMapping
    columns: RecordingColumns
    position_unit: LengthUnit | None = None

    def __post_init__(self) -> None:
        if self.columns.angles:
            raise RecordingError("marker positions give the angles: name no angle columns "
                                 "(--angle-columns) beside them")
        if isinstance(self.mapping.tilt, TiltChannel):
            raise RecordingError("--tilt-channel reads a C3D's analog channel; a table's "
                                 "tilt is its --tilt-column")
        if self.mapping.tilt is not None and self.columns.tilt is not None:
            raise RecordingError("--tilt-markers and --tilt-column are two sources of the "
                                 "platform's tilt: give one (--tilt-column none)")


def _axis_column(table: TextTable, marker: str, axis: str) -> int | None:
    """The index of ``marker``'s ``axis`` column, None when none spells it; two refused."""
    wanted = {f"{marker}{sep}{axis}".lower() for sep in AXIS_SEPARATORS}
    hits = [k for k, name in enumerate(table.names_without_units)
            if name.strip().lower() in wanted]
    if len(hits) > 1:
        raise RecordingError(
            f"{table.path}: point {marker!r} has {len(hits)} {axis} columns "
            f"({', '.join(repr(table.header[k]) for k in hits)}): rename one")
    return hits[0] if hits else None


def _positions(table: TextTable, markers: tuple[str, ...], unit: LengthUnit | None
               ) -> tuple[np.ndarray, str, bool]:
    """(F, M, 3) m, the markers' positions, the unit read, and whether the headers state
    it."""
    indices, missing = {}, []
    for marker in markers:
        found = [_axis_column(table, marker, axis) for axis in "xyz"]
        if any(k is None for k in found):
            absent = [a for a, k in zip("xyz", found, strict=True) if k is None]
            missing.append(f"{marker!r} ({', '.join(absent)})")
        indices[marker] = found
    if missing:
        raise RecordingError(
            f"{table.path}: no coordinate columns for point {', '.join(missing)}: a point "
            f"NAME is read from columns NAME_x, NAME_y, NAME_z (or NAME.x, 'NAME x', ...); "
            f"the header is {','.join(table.header)}")
    stated = {table.units[k] for found in indices.values() for k in found} - {None}
    lengths = stated - set(METRES_PER_UNIT)
    if lengths:
        raise RecordingError(f"{table.path}: position columns in {', '.join(sorted(lengths))} "
                             f"by their headers; positions must be in "
                             f"{', '.join(METRES_PER_UNIT)}")
    if len(stated) > 1:
        raise RecordingError(f"{table.path}: the position columns' headers state "
                             f"{' and '.join(sorted(stated))}: one unit for every position")
    if stated and unit is not None and unit.value not in stated:
        raise RecordingError(f"{table.path}: the position columns are in {stated.pop()} by "
                             f"their headers, but --position-units {unit.value} is given: "
                             "leave it out or correct the header")
    from_header = bool(stated)
    name = stated.pop() if stated else (unit.value if unit is not None else "m")
    scale = METRES_PER_UNIT[name]
    points = np.stack([np.column_stack([table.values[:, k] for k in indices[m]])
                       for m in markers], axis=1) * scale
    points[np.all(points == 0.0, axis=2)] = np.nan  # a tracker that lost tracking
    return points, name, from_header


def _check_unit(path: Path, trial: MotionCaptureTrial, mapping: MarkerMapping,
                unit: str, stated: bool) -> None:
    """Refuse positions whose unit no standing person fits: the median length of a
    segment (or from the support to the COM points) outside :data:`SEGMENT_LENGTH_M`."""
    pairs = [(s.lower, s.upper, f"segment {s.segment!r}") for s in mapping.segments]
    if mapping.com is not None:
        pairs += [(mapping.com.support, p, f"--com-markers {mapping.com.support}→{p}")
                  for p in mapping.com.points]
    low, high = SEGMENT_LENGTH_M
    for lower, upper, label in pairs:
        a = np.mean([trial.marker(m) for m in lower.markers], axis=0)
        b = np.mean([trial.marker(m) for m in upper.markers], axis=0)
        length = float(np.nanmedian(np.linalg.norm(b - a, axis=1)))
        if not math.isfinite(length) or low <= length <= high:
            continue
        in_file = length / METRES_PER_UNIT[unit]  # the length in the file's own numbers
        fits = [u for u, per in METRES_PER_UNIT.items() if low <= in_file * per <= high]
        how = "by the headers" if stated else "as given (default m)"
        hint = (f"; in {fits[0]} it is {in_file * METRES_PER_UNIT[fits[0]]:.3g} m "
                f"(--position-units {fits[0]})" if fits and not stated else "")
        raise RecordingError(
            f"{path}: {label} is {length:.3g} m long with the positions in {unit} {how}, "
            f"not a standing person's ({low:g}–{high:g} m){hint}")


def read_marker_table(path: str | Path, layout: MarkerColumns,
                      segments: tuple[str, ...] | None = None,
                      tilt_of=None) -> Recording:
    """The recording a table of marker or tracker positions gives (module docstring) for a
    body of ``segments`` (default the mapping's names); ``tilt_of``: the named stimulus's
    tilt (rad) at given times (s), for a table without a tilt.

    Raises:
        RecordingError: naming the file and the column or point: a missing coordinate
            column, positions in a unit no person fits, time that jitters beyond a clock's
            or has a gap (the line named), and whatever the marker route refuses (a
            segment that is not upright, a forward axis across the subject).
    """
    from posture_id.motion_capture.angles import marker_angles

    path = Path(path)
    mapping, columns = layout.mapping, layout.columns
    table = on_even_time(read_text_table(path, RecordingError, "recording"), columns)
    from_markers = isinstance(mapping.tilt, TiltMarkers)  # else the column, or tilt_of
    time, tilt, _, notices = lab_columns(
        table, columns, (lambda t: np.zeros_like(t)) if from_markers else tilt_of)
    points, unit, stated = _positions(table, mapping.markers, layout.position_unit)
    rate = (len(time) - 1) / float(time[-1] - time[0]) if len(time) > 1 else 0.0
    trial = MotionCaptureTrial(path=path, labels=mapping.markers, points=points,
                               rate_hz=rate, first_frame=1, unit=unit, analog_labels=(),
                               analogs=np.zeros((0, 0)), analog_rate_hz=0.0)
    _check_unit(path, trial, mapping, unit, stated)
    angles = marker_angles(trial, mapping)
    recording = angles.recording(segments, lambda _: tilt)
    source = {**angles.source(), "format": "marker table", "point_unit": unit,
              "time_column": columns.time, "tilt_column": columns.tilt}
    return replace(recording, time=time, source=source, notices=notices,
                   tilt_recorded=from_markers or columns.tilt is not None)
