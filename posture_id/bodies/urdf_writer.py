"""Write a foot-rooted planar chain as URDF (the form :func:`~posture_id.bodies.load_body` reads).

All link frames are parallel to the world frame at the zero posture: x forward, y the
common joint axis (a positive angle leans forward), z up. The support link is ``foot``;
the top segment gets a massless ``<link>_end`` frame marking its far end.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from posture_id.fileio import atomic_write_text

__all__ = ["LinkSpec", "chain_urdf", "write_chain_urdf"]


@dataclass(frozen=True)
class LinkSpec:
    """One segment of the chain.

    Attributes:
        link: URDF link name. joint: name of the revolute joint below it.
        origin: (3,) m, its joint relative to the joint below (the foot frame for the first).
        mass: kg. com: (3,) m, COM relative to its joint.
        inertia: (3, 3) kg·m², inertia tensor about the COM (world-aligned axes).
        end: (3,) m, the segment's far end relative to its joint (written as a frame on the
            top segment; the next joint's origin otherwise).
    """

    link: str
    joint: str
    origin: tuple[float, float, float]
    mass: float
    com: tuple[float, float, float]
    inertia: tuple[tuple[float, float, float], ...]
    end: tuple[float, float, float]


def _num(x) -> str:
    """Shortest text that reads back as the same double."""
    return repr(float(x))


def _xyz(v) -> str:
    return " ".join(_num(x) for x in v)


def _inertial(mass: float, com, inertia) -> list[str]:
    i = np.asarray(inertia, dtype=float)
    return [
        "    <inertial>",
        f'      <origin xyz="{_xyz(com)}" rpy="0 0 0"/>',
        f'      <mass value="{_num(mass)}"/>',
        f'      <inertia ixx="{_num(i[0, 0])}" ixy="{_num(i[0, 1])}" ixz="{_num(i[0, 2])}" '
        f'iyy="{_num(i[1, 1])}" iyz="{_num(i[1, 2])}" izz="{_num(i[2, 2])}"/>',
        "    </inertial>",
    ]


def chain_urdf(name: str, links: list[LinkSpec], foot: tuple | None = None,
               comment: str = "") -> str:
    """URDF text of the chain.

    Args:
        name: robot name. links: the segments, support upward.
        foot: optional (mass, com (3,), inertia (3, 3)) of the support link (informative:
            the support does not move and is not simulated).
        comment: a line written at the top (e.g. where the body came from).
    """
    lines = ['<?xml version="1.0"?>']
    if comment:
        lines.append(f"<!-- {comment} -->")
    lines.append(f'<robot name="{name}">')
    if foot is None:
        lines.append('  <link name="foot"/>')
    else:
        lines += ['  <link name="foot">', *_inertial(*foot), "  </link>"]
    parent = "foot"
    for seg in links:
        length = float(np.linalg.norm(seg.end))
        mid = np.asarray(seg.end, dtype=float) / 2.0
        lines += [
            f'  <joint name="{seg.joint}" type="revolute">',
            f'    <parent link="{parent}"/>',
            f'    <child link="{seg.link}"/>',
            f'    <origin xyz="{_xyz(seg.origin)}" rpy="0 0 0"/>',
            '    <axis xyz="0 1 0"/>',
            '    <limit lower="-1.57" upper="1.57" effort="10000" velocity="10"/>',
            "  </joint>",
            f'  <link name="{seg.link}">',
            *_inertial(seg.mass, seg.com, seg.inertia),
            "    <visual>",
            f'      <origin xyz="{_xyz(mid)}" rpy="0 {_num(np.arctan2(mid[0], mid[2]))} 0"/>',
            f'      <geometry><cylinder radius="0.04" length="{_num(length)}"/></geometry>',
            "    </visual>",
            "  </link>",
        ]
        parent = seg.link
    top = links[-1]
    lines += [
        f'  <joint name="{top.link}_end_joint" type="fixed">',
        f'    <parent link="{top.link}"/>',
        f'    <child link="{top.link}_end"/>',
        f'    <origin xyz="{_xyz(top.end)}" rpy="0 0 0"/>',
        "  </joint>",
        f'  <link name="{top.link}_end"/>',
        "</robot>",
    ]
    return "\n".join(lines) + "\n"


def write_chain_urdf(path: str | Path, name: str, links: list[LinkSpec], **kwargs) -> Path:
    """Write :func:`chain_urdf` atomically to ``path``."""
    return atomic_write_text(Path(path), chain_urdf(name, links, **kwargs))
