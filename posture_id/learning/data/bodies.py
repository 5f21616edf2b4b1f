"""Drawn bodies as :class:`~posture_id.bodies.body.Body` objects (through a URDF, as a
user's body would come)."""

from __future__ import annotations

import tempfile
from dataclasses import replace
from functools import lru_cache
from pathlib import Path

import numpy as np

from posture_id.bodies.anthropometry import straight_links, winter_segments
from posture_id.bodies.body import DEFAULT_URDF, Body, load_body
from posture_id.bodies.urdf_writer import LinkSpec, chain_urdf
from posture_id.learning.data.scope import BodyDraw

__all__ = ["body_urdf", "build_body"]


@lru_cache(maxsize=8)
def _preset(name: str, segments: int):
    from posture_id.bodies.lumping import preset_body

    return preset_body(name, segments)


def _jittered_links(links: list[LinkSpec], factors: tuple[tuple[float, float], ...]
                    ) -> list[LinkSpec]:
    """Links with segment i's mass scaled by a_i and its length by b_i: its COM and far
    end by b_i, the next joint (its origin) with it, its inertia by a_i·b_i²."""
    out = []
    below = 1.0
    for link, (a, b) in zip(links, factors, strict=True):
        out.append(replace(link, origin=tuple(np.asarray(link.origin) * below),
                           mass=link.mass * a, com=tuple(np.asarray(link.com) * b),
                           inertia=tuple(map(tuple, np.asarray(link.inertia) * a * b**2)),
                           end=tuple(np.asarray(link.end) * b)))
        below = b
    return out


def body_urdf(draw: BodyDraw) -> str:
    """The URDF text of a drawn body."""
    if draw.kind == "tip":
        return Path(DEFAULT_URDF).read_text()
    if draw.kind != "winter":
        lumped = _preset(draw.kind, draw.segments)
        if not draw.factors:
            return lumped.urdf()
        return chain_urdf(lumped.name, _jittered_links(lumped.links, draw.factors),
                          foot=lumped.foot, comment=f"{lumped.origin}; segments jittered")
    links = straight_links(winter_segments(draw.height_m, draw.mass_kg, draw.segments))
    return chain_urdf(f"winter_{draw.segments}seg", _jittered_links(links, draw.factors))


def build_body(draw: BodyDraw) -> Body:
    """Load a drawn body (its URDF written to a temporary file)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "body.urdf"
        path.write_text(body_urdf(draw))
        return load_body(path)
