"""One reader for every recording a user brings: a CSV file (the standard header, or a
lab's own columns) or a motion-capture trial (C3D: its markers turned into angles)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from posture_id.bodies.body import Body
from posture_id.errors import RecordingError
from posture_id.force_plate.reading import ForcePlateColumns, read_force_plate
from posture_id.motion_capture import is_c3d
from posture_id.motion_capture.mapping import MarkerMapping
from posture_id.motion_capture.marker_table import MarkerColumns, read_marker_table
from posture_id.recording import Recording, RecordingColumns

__all__ = ["read_recording", "RecordingLayout", "RECORDING_SUFFIXES"]

#: How a file's contents are read: a lab's columns (CSV), a force plate's columns (the COP
#: turned into the body-COM sway), a marker mapping (C3D), a CSV's marker or tracker
#: positions, or None (the standard CSV header).
RecordingLayout = RecordingColumns | ForcePlateColumns | MarkerMapping | MarkerColumns | None
#: The suffixes a cohort's folder is searched for.
RECORDING_SUFFIXES = (".csv", ".c3d")


def read_recording(path: str | Path, segments: tuple[str, ...] | None = None,
                   tilt_of: Callable[[np.ndarray], np.ndarray] | None = None,
                   layout: RecordingLayout = None, body: Body | None = None) -> Recording:
    """The recording in ``path`` for a body of ``segments`` (link names, in order).

    Args:
        path: The recording's file: a CSV (or a lab's text export) or a C3D.
        segments: The body's segment names, in order: a CSV's angle columns must be these
            (None: whichever its header names).
        tilt_of: the named stimulus's tilt (rad) at given times (s): fills in a file
            without a tilt (no tilt column; no platform markers or channel).
        layout: a CSV's columns, a force plate's, or a C3D's :class:`MarkerMapping`
            (required for C3D).
        body: the subject's body, which a force plate's COP is turned into sway through
            (the recording is then that of the body as one segment).

    Raises:
        RecordingError: naming the file and the problem (a C3D without a marker mapping,
            a marker mapping for a CSV, and whatever its reader refuses).
    """
    if is_c3d(path):
        if isinstance(layout, MarkerColumns):
            layout = layout.mapping  # a C3D has its own rate, units and channels
        if not isinstance(layout, MarkerMapping):
            raise RecordingError(
                f"{path}: a C3D file: name the markers of each segment (--segment-markers "
                "SEGMENT=LOWER,UPPER ...; or --com-markers for a 1-segment body) and the "
                "axis the subject faces (--forward-axis); docs/motion_capture.md")
        from posture_id.motion_capture.angles import marker_angles
        from posture_id.motion_capture.c3d_file import read_c3d

        return marker_angles(read_c3d(path), layout).recording(segments, tilt_of)
    if isinstance(layout, ForcePlateColumns):
        if body is None:
            raise RecordingError(f"{path}: the COP is turned into the body's sway through "
                                 "the subject's body: give it (--body URDF; posture-id body "
                                 "--height-m H --mass-kg M --segments 1 writes one)")
        return read_force_plate(path, layout, body, tilt_of)
    if isinstance(layout, MarkerColumns):
        return read_marker_table(path, layout, segments, tilt_of)
    if isinstance(layout, MarkerMapping):
        raise RecordingError(f"{path}: the marker flags (--segment-markers, --com-markers, "
                             "--tilt-markers, --tilt-channel, --forward-axis) read a C3D "
                             "file (.c3d); this is not one")
    return Recording.read(path, segments, tilt_of, layout)
