"""Bodies: URDF chains through Pinocchio, anthropometric and lumped humanoid bodies.

The bottom of the model stack: nothing here knows about the controller, the simulator or
identification. :func:`load_body` is the entry point; :mod:`.anthropometry` and
:mod:`.urdf_writer` make new chains, :mod:`.lumping` reduces whole-body humanoids.
"""

from posture_id.bodies.body import (
    BUNDLED_URDFS,
    DEFAULT_URDF,
    TWO_SEGMENT_URDF,
    Body,
    Segment,
    load_body,
)

__all__ = ["DEFAULT_URDF", "TWO_SEGMENT_URDF", "BUNDLED_URDFS", "Body", "Segment", "load_body",
           "lump_robot", "preset_body"]


def __getattr__(name: str):
    # lumping reads example-robot-data's files: load it on first use only
    if name in ("lump_robot", "preset_body"):
        from posture_id.bodies import lumping

        return getattr(lumping, name)
    raise AttributeError(f"module 'posture_id.bodies' has no attribute '{name}'")
