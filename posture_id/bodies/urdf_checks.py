"""Checks of a URDF's text that the URDF parser does not make (or makes only in its own
console output): every joint names defined links, every inertial has a positive mass and
a physically valid inertia (symmetric, positive semi-definite, each principal moment at
most the sum of the other two). Each problem is one line naming the file, link or joint.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from posture_id.errors import BodyError

__all__ = ["check_urdf_text"]

_INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


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
    if _number(path, where + " <mass>", mass, "value") <= 0:
        raise BodyError(f"{path}: {where}: mass must be > 0, got {mass.get('value')}")
    inertia = inertial.find("inertia")
    if inertia is None:
        raise BodyError(f"{path}: {where}: <inertial> has no <inertia> element (the parser "
                        "would take it as zero)")
    v = {k: _number(path, where + " <inertia>", inertia, k) for k in _INERTIA_KEYS}
    matrix = np.array([[v["ixx"], v["ixy"], v["ixz"]], [v["ixy"], v["iyy"], v["iyz"]],
                       [v["ixz"], v["iyz"], v["izz"]]])
    moments = np.linalg.eigvalsh(matrix)
    scale = max(float(np.abs(moments).max()), 1e-300)
    if moments.min() < -1e-9 * scale:
        raise BodyError(f"{path}: {where}: the inertia is not positive semi-definite "
                        f"(principal moments {', '.join(f'{m:.4g}' for m in moments)})")
    if moments.max() > moments.sum() - moments.max() + 1e-9 * scale:
        raise BodyError(f"{path}: {where}: the inertia breaks the triangle inequality (a "
                        f"principal moment exceeds the sum of the other two: "
                        f"{', '.join(f'{m:.4g}' for m in moments)}); no rigid body has it")
