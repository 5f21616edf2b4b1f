"""A body of the same build, larger or smaller: every length × b, the masses kept.

What another person's body does to a sway model: gains scale with m·g·h (so a mass that is
not the subject's is invisible in the sway), while the inertia about each joint scales
with b² against m·g·h with b, so the body's time scale √(J/mgh) goes with √b. The
identifier's check for another person's body (:mod:`posture_id.identify.alternatives`)
asks whether a larger or smaller copy explains the sway better.
"""

from __future__ import annotations

import tempfile
from functools import lru_cache
from pathlib import Path

import numpy as np

from posture_id.bodies.body import Body, load_body
from posture_id.bodies.urdf_writer import LinkSpec, chain_urdf

__all__ = ["scaled_body"]


@lru_cache(maxsize=32)
def scaled_body(body: Body, factor: float) -> Body:
    """``body`` with every length (joint origins, COMs, segment lengths) × ``factor``, its
    masses kept and each inertia about its COM × factor² (written as a planar URDF and
    loaded; kept, so that a cohort on one body writes and loads each size once)."""
    links = []
    segments = body.segments
    for k, seg in enumerate(segments):
        forward, up = (np.asarray(v, dtype=float) * factor for v in (seg.com, seg.joint_origin))
        if k + 1 < len(segments):
            end = np.asarray(segments[k + 1].joint_origin, dtype=float) * factor
        else:
            end = np.array([0.0, seg.length * factor])
        i = seg.inertia * factor**2
        links.append(LinkSpec(
            link=seg.name, joint=seg.joint, origin=(float(up[0]), 0.0, float(up[1])),
            mass=seg.mass, com=(float(forward[0]), 0.0, float(forward[1])),
            inertia=((i, 0.0, 0.0), (0.0, i, 0.0), (0.0, 0.0, i)),
            end=(float(end[0]), 0.0, float(end[1]))))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "scaled.urdf"
        path.write_text(chain_urdf(f"{body.name}_x{factor:g}", links))
        return load_body(path)
