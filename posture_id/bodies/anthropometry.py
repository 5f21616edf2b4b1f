"""Bodies written as URDF: the default TIP (docs/model.md §1) and Winter's anthropometric tables.

Segments are straight, stacked upright along +z with their COMs on their axes; they are
written by :mod:`posture_id.bodies.urdf_writer` (joints about +y, rooted at a ``foot`` link).
"""

from __future__ import annotations

from dataclasses import dataclass

from posture_id.bodies.urdf_writer import LinkSpec
from posture_id.errors import BodyError

__all__ = [
    "SegmentSpec",
    "winter_body_file",
    "straight_links",
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
    """docs/model.md §1: shank 10 kg, thigh 10 kg, trunk 30 kg, 0.5 m each, COM mid, I = m·l²/12."""
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


#: m, the heights Winter's tables are used for (a person's, in metres).
HEIGHT_RANGE_M = (0.5, 2.5)
#: kg, the masses likewise.
MASS_RANGE_KG = (10.0, 300.0)


def winter_segments(height_m: float, mass_kg: float, n_segments: int = 3) -> list[SegmentSpec]:
    """Segments of a person from Winter's tables, feet excluded (they are the support).

    Args:
        height_m: body height, m (0.5 to 2.5). mass_kg: body mass, kg (10 to 300).
        n_segments: 3 (shank, thigh, trunk), 2 (leg, trunk) or 1 (body).
    """
    if not HEIGHT_RANGE_M[0] <= height_m <= HEIGHT_RANGE_M[1]:
        raise BodyError(f"height {height_m} m is outside 0.5–2.5 m")
    if not MASS_RANGE_KG[0] <= mass_kg <= MASS_RANGE_KG[1]:
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




def straight_links(segments: list[SegmentSpec]) -> list[LinkSpec]:
    """Straight segments stacked upright along z, as :class:`LinkSpec` for the writer."""
    links = []
    below = 0.0
    for seg in segments:
        i = seg.inertia
        links.append(
            LinkSpec(
                link=seg.link, joint=seg.joint, origin=(0.0, 0.0, below), mass=seg.mass,
                com=(0.0, 0.0, seg.com), inertia=((i, 0.0, 0.0), (0.0, i, 0.0), (0.0, 0.0, 0.0)),
                end=(0.0, 0.0, seg.length),
            )
        )
        below = seg.length
    return links


def winter_body_file(height_m: float, mass_kg: float, n_segments: int):
    """The URDF of the Winter body of ``height_m`` (m), ``mass_kg`` (kg) and ``n_segments``
    in the cache folder, written once: a subject's body from a trial's metadata.

    Returns:
        its path.
    """
    from posture_id.bodies.urdf_writer import write_chain_urdf
    from posture_id.cache import cache_folder

    name = f"winter_{height_m:.3g}m_{mass_kg:.4g}kg_{n_segments}seg"
    path = cache_folder("bodies") / f"{name}.urdf"
    if not path.is_file():
        write_chain_urdf(path, name, straight_links(winter_segments(height_m, mass_kg,
                                                                    n_segments)))
    return path
