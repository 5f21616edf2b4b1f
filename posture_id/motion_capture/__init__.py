"""Motion capture: a lab's C3D trial, its markers and channels turned into sagittal segment
angles, a body COM angle and the platform's tilt (MODEL §1's angles), and C3D trials
written from simulated sway for the project's own tests and example."""

from posture_id.motion_capture.angles import MarkerAngles, marker_angles
from posture_id.motion_capture.c3d_file import MotionCaptureTrial, read_c3d
from posture_id.motion_capture.mapping import (
    ComMarkers,
    LabAxes,
    MarkerMapping,
    MarkerPoint,
    SegmentMarkers,
    TiltChannel,
    TiltMarkers,
    parse_com_markers,
    parse_segment_markers,
    parse_tilt_markers,
)
from posture_id.motion_capture.writer import C3dWriteOptions, write_c3d

__all__ = ["MarkerAngles", "marker_angles", "MotionCaptureTrial", "read_c3d", "ComMarkers",
           "LabAxes", "MarkerMapping", "MarkerPoint", "SegmentMarkers", "TiltChannel",
           "TiltMarkers", "parse_com_markers", "parse_segment_markers", "parse_tilt_markers",
           "C3dWriteOptions", "write_c3d", "is_c3d"]


def is_c3d(path) -> bool:
    """Whether ``path`` names a C3D file (by its suffix, any case)."""
    from pathlib import Path

    return Path(path).suffix.lower() == ".c3d"
