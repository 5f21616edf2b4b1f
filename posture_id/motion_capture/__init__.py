"""Motion capture: a lab's C3D trial, its markers and channels turned into sagittal segment
angles, a body COM angle and the platform's tilt (docs/model.md §1's angles), and C3D trials
written from simulated sway for the project's own tests and example.

The names load on first use: the command line's parsers import the mapping alone.
"""

from pathlib import Path

from posture_id._lazy import lazy_getattr

_WHERE = {
    "MarkerAngles": "posture_id.motion_capture.angles",
    "marker_angles": "posture_id.motion_capture.angles",
    "MotionCaptureTrial": "posture_id.motion_capture.c3d_file",
    "read_c3d": "posture_id.motion_capture.c3d_file",
    "C3dWriteOptions": "posture_id.motion_capture.writer",
    "write_c3d": "posture_id.motion_capture.writer",
    **{name: "posture_id.motion_capture.mapping" for name in (
        "ComMarkers", "LabAxes", "MarkerMapping", "MarkerPoint", "SegmentMarkers",
        "TiltChannel", "TiltMarkers", "parse_com_markers", "parse_segment_markers",
        "parse_tilt_markers")},
}

__all__ = [*_WHERE, "is_c3d"]
__getattr__ = lazy_getattr(__name__, _WHERE)


def is_c3d(path: str | Path) -> bool:
    """Whether ``path`` names a C3D file (by its suffix, any case)."""
    return Path(path).suffix.lower() == ".c3d"
