"""Drawn bodies as :class:`~posture_id.bodies.body.Body` objects (through a URDF, as a
user's body would come)."""

from __future__ import annotations

import tempfile
from dataclasses import replace
from functools import lru_cache
from pathlib import Path

from posture_id.bodies.anthropometry import straight_links, winter_segments
from posture_id.bodies.body import DEFAULT_URDF, Body, load_body
from posture_id.bodies.urdf_writer import chain_urdf
from posture_id.learning.universal.scope import BodyDraw

__all__ = ["body_urdf", "build_body"]


@lru_cache(maxsize=8)
def _preset_urdf(name: str, segments: int) -> str:
    from posture_id.bodies.lumping import preset_body

    return preset_body(name, segments).urdf()


def body_urdf(draw: BodyDraw) -> str:
    """The URDF text of a drawn body."""
    if draw.kind == "tip":
        return Path(DEFAULT_URDF).read_text()
    if draw.kind != "winter":
        return _preset_urdf(draw.kind, draw.segments)
    specs = winter_segments(draw.height_m, draw.mass_kg, draw.segments)
    jittered = []
    for spec, (mass_factor, length_factor) in zip(specs, draw.factors, strict=True):
        jittered.append(replace(spec, mass=spec.mass * mass_factor,
                                length=spec.length * length_factor,
                                com=spec.com * length_factor,
                                inertia=spec.inertia * mass_factor * length_factor**2))
    return chain_urdf(f"winter_{draw.segments}seg", straight_links(jittered))


def build_body(draw: BodyDraw) -> Body:
    """Load a drawn body (its URDF written to a temporary file)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "body.urdf"
        path.write_text(body_urdf(draw))
        return load_body(path)
