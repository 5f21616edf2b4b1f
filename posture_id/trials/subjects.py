"""Which body a recording's subject has: their own URDF beside the cohort, or the one a
motion-capture trial's metadata give."""

from __future__ import annotations

from pathlib import Path

from posture_id.bodies.anthropometry import winter_body_file
from posture_id.errors import PostureIdError
from posture_id.motion_capture import is_c3d
from posture_id.motion_capture.mapping import MarkerMapping

__all__ = ["subject_urdf"]


def subject_urdf(recording: Path, bodies: Path | None, default: Path | None,
                 trial_bodies: MarkerMapping | None = None) -> Path | None:
    """A recording's subject's URDF: ``bodies``/<recording stem>.urdf when there is one;
    else, with ``trial_bodies`` (the cohort's marker mapping) for a C3D trial whose metadata
    give the subject's height and mass, their Winter body of the mapping's segments;
    ``default`` otherwise."""
    own = None if bodies is None else Path(bodies) / f"{recording.stem}.urdf"
    if own is not None and own.is_file():
        return own
    if trial_bodies is not None and is_c3d(recording):
        from posture_id.motion_capture.c3d_file import read_c3d

        try:
            trial = read_c3d(recording)
        except PostureIdError:
            return default  # reading the recording refuses it, with the reason, later
        if trial.height_m is not None and trial.mass_kg is not None:
            return winter_body_file(trial.height_m, trial.mass_kg, trial_bodies.n_segments)
    return default
