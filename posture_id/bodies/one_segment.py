"""A body as one rigid segment about the ankle: what a body-COM recording (a force plate's,
a COM marker's) is the sway of."""

from __future__ import annotations

import numpy as np

from posture_id.bodies.anthropometry import SegmentSpec, straight_links
from posture_id.bodies.body import Body, load_body

__all__ = ["one_segment_body", "ONE_SEGMENT", "ONE_JOINT"]

#: The segment and joint names of a one-segment body.
ONE_SEGMENT, ONE_JOINT = "body", "ankle"


def one_segment_body(body: Body) -> Body:
    """``body`` rigid and upright as one segment: the same mass, ankle-to-COM height and
    moment of inertia about the ankle axis (hence the same m·g·h), its length the
    body's; written once to the cache folder (named by the body's SHA-256) and loaded.
    A one-segment body is itself."""
    if body.n_segments == 1:
        return body
    from posture_id.bodies.urdf_writer import write_chain_urdf
    from posture_id.cache import cache_folder

    ones = np.ones(body.n_segments)
    about_ankle = float(ones @ (np.real(body.coupling) + np.diag(body.inertias)) @ ones)
    mass = body.total_mass
    height = float(body.com_height_above[0])
    length = float(sum(s.length for s in body.segments))
    name = f"{body.name}_one_segment"
    path = cache_folder("bodies") / f"{name}_{body.sha256[:16]}.urdf"
    if not path.is_file():
        segment = SegmentSpec(ONE_SEGMENT, ONE_JOINT, length, mass, height,
                              about_ankle - mass * height**2)
        write_chain_urdf(path, name, straight_links([segment]))
    return load_body(path)
