"""Bodies written as URDF: the default TIP (MODEL §1) and Winter's anthropometric tables.

The chain is written upright along +z, joints about +y (so a positive angle is a forward
lean towards +x), rooted at a ``foot`` link that stands on the platform. The top segment
gets a massless ``<name>_end`` frame so that its length can be read back.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from posture_id.errors import BodyError
from posture_id.io_utils import atomic_write_text

__all__ = [
    "SegmentSpec",
    "chain_urdf",
    "write_chain_urdf",
    "default_tip_segments",
    "winter_segments",
    "WINTER",
]


@dataclass(frozen=True)
class SegmentSpec:
    """One segment to write: straight, its COM on its long axis.

    Attributes:
        link: URDF link name. joint: name of the joint below it.
        length: m, joint to next joint. mass: kg.
        com: m, COM distance from the joint below along the segment.
        inertia: kg·m², about the COM, perpendicular to the segment.
    """

    link: str
    joint: str
    length: float
    mass: float
    com: float
    inertia: float


#: Winter (2009), Biomechanics and Motor Control of Human Movement, Table 4.1 and Fig. 4.1.
#: Per segment: mass fraction of body mass, length fraction of height, COM fraction of the
#: length from the *distal* (lower) joint, radius of gyration about the COM (fraction of
#: length). Both legs are one segment (masses doubled when the chain is built).
WINTER = {
    "shank": {"mass": 0.0465, "length": 0.246, "com_from_lower": 1 - 0.433, "gyration": 0.302},
    "thigh": {"mass": 0.100, "length": 0.245, "com_from_lower": 1 - 0.433, "gyration": 0.323},
    # head-arms-trunk, greater trochanter to glenohumeral joint; COM 0.626 from the hip.
    "trunk": {"mass": 0.678, "length": 0.818 - 0.530, "com_from_lower": 0.626, "gyration": 0.496},
}


def default_tip_segments() -> list[SegmentSpec]:
    """MODEL §1: shank 10 kg, thigh 10 kg, trunk 30 kg, 0.5 m each, COM mid, I = m·l²/12."""
    out = []
    for link, joint, mass in (("shank", "ankle", 10.0), ("thigh", "knee", 10.0),
                              ("trunk", "hip", 30.0)):
        out.append(SegmentSpec(link, joint, 0.5, mass, 0.25, mass * 0.5**2 / 12.0))
    return out


def _merge(parts: list[SegmentSpec], link: str, joint: str) -> SegmentSpec:
    """Rigidly join straight segments end to end (parallel-axis theorem)."""
    base = 0.0
    mass = sum(p.mass for p in parts)
    moment = 0.0
    coms = []
    for p in parts:
        coms.append(base + p.com)
        moment += p.mass * (base + p.com)
        base += p.length
    com = moment / mass
    pairs = zip(parts, coms, strict=True)
    inertia = sum(p.inertia + p.mass * (c - com) ** 2 for p, c in pairs)
    return SegmentSpec(link, joint, base, mass, com, inertia)


def winter_segments(height_m: float, mass_kg: float, n_segments: int = 3) -> list[SegmentSpec]:
    """Segments of a person from Winter's tables, feet excluded (they are the support).

    Args:
        height_m: body height, m (0.5 to 2.5). mass_kg: body mass, kg (10 to 300).
        n_segments: 3 (shank, thigh, trunk), 2 (leg, trunk) or 1 (body).
    """
    if not 0.5 <= height_m <= 2.5:
        raise BodyError(f"height {height_m} m is outside 0.5–2.5 m")
    if not 10.0 <= mass_kg <= 300.0:
        raise BodyError(f"mass {mass_kg} kg is outside 10–300 kg")
    parts = []
    for link, joint in (("shank", "ankle"), ("thigh", "knee"), ("trunk", "hip")):
        row = WINTER[link]
        legs = 1.0 if link == "trunk" else 2.0
        length = row["length"] * height_m
        mass = legs * row["mass"] * mass_kg
        parts.append(
            SegmentSpec(
                link, joint, length, mass, row["com_from_lower"] * length,
                mass * (row["gyration"] * length) ** 2,
            )
        )
    if n_segments == 3:
        return parts
    if n_segments == 2:
        return [_merge(parts[:2], "leg", "ankle"), parts[2]]
    if n_segments == 1:
        return [_merge(parts, "body", "ankle")]
    raise BodyError(f"segments must be 1, 2 or 3, got {n_segments}")




def chain_urdf(name: str, segments: list[SegmentSpec]) -> str:
    """URDF text of a foot-rooted planar chain of straight segments (see module doc)."""
    lines = ['<?xml version="1.0"?>', f'<robot name="{name}">', '  <link name="foot"/>']
    parent = "foot"
    offset = 0.0
    for seg in segments:
        i = seg.inertia
        lines += [
            f'  <joint name="{seg.joint}" type="revolute">',
            f'    <parent link="{parent}"/>',
            f'    <child link="{seg.link}"/>',
            f'    <origin xyz="0 0 {offset!r}" rpy="0 0 0"/>',
            '    <axis xyz="0 1 0"/>',
            '    <limit lower="-1.57" upper="1.57" effort="10000" velocity="10"/>',
            "  </joint>",
            f'  <link name="{seg.link}">',
            "    <inertial>",
            f'      <origin xyz="0 0 {seg.com!r}" rpy="0 0 0"/>',
            f'      <mass value="{seg.mass!r}"/>',
            f'      <inertia ixx="{i!r}" ixy="0" ixz="0" iyy="{i!r}" iyz="0" izz="0"/>',
            "    </inertial>",
            "    <visual>",
            f'      <origin xyz="0 0 {seg.length / 2!r}" rpy="0 0 0"/>',
            f'      <geometry><cylinder radius="0.04" length="{seg.length!r}"/></geometry>',
            "    </visual>",
            "  </link>",
        ]
        parent = seg.link
        offset = seg.length
    top = segments[-1]
    lines += [
        f'  <joint name="{top.link}_end_joint" type="fixed">',
        f'    <parent link="{top.link}"/>',
        f'    <child link="{top.link}_end"/>',
        f'    <origin xyz="0 0 {top.length!r}" rpy="0 0 0"/>',
        "  </joint>",
        f'  <link name="{top.link}_end"/>',
        "</robot>",
    ]
    return "\n".join(lines) + "\n"


def write_chain_urdf(path: str | Path, name: str, segments: list[SegmentSpec]) -> Path:
    """Write :func:`chain_urdf` atomically to ``path``."""
    return atomic_write_text(Path(path), chain_urdf(name, segments))
