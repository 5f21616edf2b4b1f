"""Checks of a URDF's text that the URDF parser does not make (or makes only in its own
console output): every joint names defined links, the moving joints form one chain (a
whole humanoid's tree is sent to ``posture-id body --lump`` before its links are
checked), every inertial has a positive mass (or none and no inertia: a massless frame)
and a physically valid inertia (symmetric, positive semi-definite, each principal moment
at most the sum of the other two). Each problem is one line naming the file, link or
joint.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from posture_id.errors import BodyError

__all__ = ["check_urdf_text"]

_INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
#: Principal moments below this (kg·m²) count as zero.
_ZERO_INERTIA = 1e-12


def _lump_hint(path: Path) -> str:
    """What to do with a whole humanoid's URDF (a tree): the command that lumps it."""
    return (f"a whole humanoid: lump its legs and trunk into one first, `posture-id body "
            f"--lump {path} --segments 3 --ankle-joints L R --knee-joints L R "
            f"--hip-joints L R --out body.urdf`")


def _check_chain(path: Path, root) -> None:
    """A tree (links fixed to one another count as one, as the parser merges them) is
    refused before its links are checked: it is read only through ``posture-id body
    --lump``. The one check that the moving joints form a single chain."""
    group = {link.get("name"): link.get("name") for link in root.findall("link")}

    def top(name: str) -> str:
        while group.get(name, name) != name:
            name = group[name]
        return name

    joints = [(j.get("name"), j.get("type"), j.find("parent").get("link"),
               j.find("child").get("link")) for j in root.findall("joint")]
    for _name, kind, parent, child in joints:
        if kind == "fixed":
            group[top(child)] = top(parent)
    moving: dict[str, list[str]] = {}
    for name, kind, parent, _child in joints:
        if kind == "floating":
            raise BodyError(f"{path}: joint '{name}' is floating: the body must be a single "
                            f"serial chain standing on the support ({_lump_hint(path)})")
        if kind != "fixed":
            moving.setdefault(top(parent), []).append(name)
    for link, names in moving.items():
        if len(names) > 1:
            raise BodyError(f"{path}: joints {', '.join(repr(n) for n in names[:3])}"
                            f"{' …' if len(names) > 3 else ''} branch off link '{link}': the "
                            f"body must be a single serial chain, not a tree ({_lump_hint(path)})")


def check_urdf_text(path: Path) -> None:
    """Raise :class:`BodyError` for the first problem found in the URDF at ``path``."""
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise BodyError(f"{path}: not UTF-8 text (byte {exc.start})") from None
    except OSError as exc:
        raise BodyError(f"{path}: cannot be read ({exc.strerror})") from None
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise BodyError(f"{path}: not well-formed XML ({exc})") from None
    if root.tag != "robot":
        raise BodyError(f"{path}: the root element is <{root.tag}>, a URDF's is <robot>")
    links = {link.get("name") for link in root.findall("link")}
    for joint in root.findall("joint"):
        name = joint.get("name")
        for role in ("parent", "child"):
            element = joint.find(role)
            target = element.get("link") if element is not None else None
            if target is None:
                raise BodyError(f"{path}: joint '{name}' has no <{role} link=...>")
            if target not in links:
                raise BodyError(f"{path}: joint '{name}' names {role} link '{target}', which is "
                                f"not defined (links: {', '.join(sorted(links))})")
    _check_chain(path, root)
    for link in root.findall("link"):
        inertial = link.find("inertial")
        if inertial is not None:
            _check_inertial(path, link.get("name"), inertial)


def _number(path: Path, where: str, element, key: str) -> float:
    raw = element.get(key)
    try:
        value = float(raw)
    except (TypeError, ValueError):
        raise BodyError(f"{path}: {where}: {key}={raw!r} is not a number") from None
    if not math.isfinite(value):
        raise BodyError(f"{path}: {where}: {key}={raw} is not finite")
    return value


def _check_inertial(path: Path, link: str, inertial) -> None:
    where = f"link '{link}'"
    mass = inertial.find("mass")
    if mass is None:
        raise BodyError(f"{path}: {where}: <inertial> has no <mass>")
    value = _number(path, where + " <mass>", mass, "value")
    if value < 0:
        raise BodyError(f"{path}: {where}: mass must be > 0, got {mass.get('value')}")
    inertia = inertial.find("inertia")
    if inertia is None:
        raise BodyError(f"{path}: {where}: <inertial> has no <inertia> element (the parser "
                        "would take it as zero)")
    v = {k: _number(path, where + " <inertia>", inertia, k) for k in _INERTIA_KEYS}
    if value == 0:
        # a massless frame (a sensor's, a tool's) adds nothing to the link it is fixed to;
        # a moving link without mass is refused where the segments are built
        if any(abs(x) >= _ZERO_INERTIA for x in v.values()):
            raise BodyError(f"{path}: {where}: mass must be > 0, got {mass.get('value')} "
                            "with a non-zero inertia")
        return
    matrix = np.array([[v["ixx"], v["ixy"], v["ixz"]], [v["ixy"], v["iyy"], v["iyz"]],
                       [v["ixz"], v["iyz"], v["izz"]]])
    moments = np.linalg.eigvalsh(matrix)
    # moments below 1e-12 kg·m² are an exporter's rounding (±1e-20 about a frame)
    moments = np.where(np.abs(moments) < _ZERO_INERTIA, 0.0, moments)
    scale = max(float(np.abs(moments).max()), 1e-300)
    if moments.min() < -1e-9 * scale:
        raise BodyError(f"{path}: {where}: the inertia is not positive semi-definite "
                        f"(principal moments {', '.join(f'{m:.4g}' for m in moments)})")
    if moments.max() > moments.sum() - moments.max() + 1e-9 * scale:
        raise BodyError(f"{path}: {where}: the inertia breaks the triangle inequality (a "
                        f"principal moment exceeds the sum of the other two: "
                        f"{', '.join(f'{m:.4g}' for m in moments)}); no rigid body has it")
