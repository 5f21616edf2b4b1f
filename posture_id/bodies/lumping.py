"""Whole-body URDF → the sagittal, foot-rooted chain posture_id simulates.

A humanoid's or a person's URDF has a floating base at the pelvis, two legs, arms and a
head. Given the joints that act as ankle, knee and hip pitch on both legs and a reference
posture, :func:`lump_robot` groups the model's links (Pinocchio bodies) into

- the support: everything beyond the ankle pitch joints (both feet);
- shank: between ankle and knee joints, both legs together;
- thigh: between knee and hip joints, both legs together;
- trunk: everything else (pelvis, torso, arms, head, hip yaw/roll links above the hip
  pitch joints);

(2 segments: leg = shank + thigh, the knee locked; 1 segment: all above the ankles), and
writes each group's mass, COM and inertia tensor, computed by Pinocchio at the reference
posture, as one link of a planar chain. The lumped joints sit at the midpoint of the left
and right joints. The sagittal plane is the world x–z plane of the reference posture:
x forward, z up (gravity −z), the pitch axis y.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from posture_id.bodies.urdf_writer import LinkSpec, chain_urdf
from posture_id.errors import BodyError
from posture_id.fileio import atomic_write_text

__all__ = ["RobotPreset", "PRESETS", "robots_dir", "lump_robot", "LumpedBody", "preset_body",
           "load_posture", "world_inertia"]

_PITCH_TOL = 1e-6


@dataclass(frozen=True)
class RobotPreset:
    """A humanoid shipped by example-robot-data and how to read its sagittal chain.

    Attributes:
        urdf: path below the example-robot-data ``robots`` folder.
        ankle, knee, hip: (left, right) names of the pitch joints.
        srdf: optional (path below ``robots``, configuration name) of the reference posture;
            the neutral configuration otherwise.
        base_rpy: roll, pitch, yaw (rad) of the floating base in the reference posture
            (turns a model drawn y-up to z-up).
    """

    urdf: str
    ankle: tuple[str, str]
    knee: tuple[str, str]
    hip: tuple[str, str]
    srdf: tuple[str, str] | None = None
    base_rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    note: str = ""


PRESETS: dict[str, RobotPreset] = {
    "talos": RobotPreset(
        urdf="talos_data/robots/talos_reduced.urdf",
        ankle=("leg_left_5_joint", "leg_right_5_joint"),
        knee=("leg_left_4_joint", "leg_right_4_joint"),
        hip=("leg_left_3_joint", "leg_right_3_joint"),
        srdf=("talos_data/srdf/talos.srdf", "half_sitting"),
        note="PAL Robotics TALOS, standing in its 'half_sitting' configuration",
    ),
    "g1": RobotPreset(
        urdf="g1_description/urdf/g1_29dof_rev_1_0.urdf",
        ankle=("left_ankle_pitch_joint", "right_ankle_pitch_joint"),
        knee=("left_knee_joint", "right_knee_joint"),
        hip=("left_hip_pitch_joint", "right_hip_pitch_joint"),
        note="Unitree G1 (29 DoF), zero configuration",
    ),
    "human": RobotPreset(
        urdf="human_description/robots/human.urdf",
        ankle=("left_ankle_Z", "right_ankle_Z"),
        knee=("left_knee_Z", "right_knee_Z"),
        hip=("left_hip_Z", "right_hip_Z"),
        base_rpy=(np.pi / 2, 0.0, 0.0),
        note="example-robot-data human model (drawn y-up, turned z-up), zero configuration",
    ),
}


def robots_dir() -> Path:
    """The ``robots`` folder of example-robot-data (it ships files, no Python module)."""
    from importlib import metadata

    try:
        dist = metadata.distribution("example-robot-data")
    except metadata.PackageNotFoundError:
        raise BodyError(
            "example-robot-data is not installed (pip install example-robot-data)"
        ) from None
    path = Path(dist.locate_file("cmeel.prefix/share/example-robot-data/robots"))
    if not path.is_dir():
        raise BodyError(f"example-robot-data has no robots folder at {path}")
    return path


@dataclass(frozen=True)
class LumpedBody:
    """The lumped chain and where it came from.

    Attributes:
        name: robot name. links: segments, support upward. foot: (mass, com, inertia) of
        the support. joints: (3,) world positions of the lumped joints (m).
        origin: a line saying which model and posture it was lumped from.
    """

    name: str
    links: list[LinkSpec]
    foot: tuple
    joint_points: np.ndarray = field(repr=False)
    origin: str = ""

    def urdf(self) -> str:
        return chain_urdf(self.name, self.links, foot=self.foot, comment=self.origin)

    def write(self, path: str | Path) -> Path:
        """Write the lumped URDF atomically."""
        return atomic_write_text(Path(path), self.urdf())


def _joint_id(model, name: str, role: str, urdf: Path) -> int:
    if model.existJointName(name):
        return model.getJointId(name)
    close = difflib.get_close_matches(name, list(model.names), n=3)
    hint = f" (did you mean {', '.join(close)}?)" if close else ""
    raise BodyError(f"{urdf}: {role} joint '{name}' is not in the model{hint}")


def world_inertia(model, data, j: int) -> tuple[float, np.ndarray, np.ndarray]:
    """The body of Pinocchio joint ``j`` placed by ``data``'s forward kinematics: mass
    (kg), COM (3,) m and inertia tensor about the COM (3, 3) kg·m², world axes."""
    inertia, placement = model.inertias[j], data.oMi[j]
    rot = np.asarray(placement.rotation)
    return (float(inertia.mass), np.asarray(placement.act(np.asarray(inertia.lever))),
            rot @ np.asarray(inertia.inertia) @ rot.T)


def _group_inertia(model, data, ids) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass (kg), COM (3,) m and inertia tensor about the COM (3, 3) kg·m², world axes."""
    parts = [world_inertia(model, data, j) for j in ids if model.inertias[j].mass != 0.0]
    mass = sum(m for m, _, _ in parts)
    if mass == 0.0:
        raise BodyError("a lumped segment has no mass: check the joint names")
    com = sum(m * c for m, c, _ in parts) / mass
    tensor = np.zeros((3, 3))
    for m, c, inertia in parts:
        d = c - com
        tensor += inertia + m * (float(d @ d) * np.eye(3) - np.outer(d, d))
    return mass, com, tensor


#: Left and right joints of a pair must sit within this of each other's mirror image, m.
MIRROR_TOL_M = 0.05


def _check_pairs(urdf: Path, model, data, ids: dict[str, tuple[int, int]]) -> None:
    """Every joint once; each left/right pair apart sideways and mirrored (same height and
    fore-aft position within :data:`MIRROR_TOL_M`)."""
    seen: dict[int, str] = {}
    for role, (left, right) in ids.items():
        if left == right:
            raise BodyError(f"{urdf}: the left and right {role} joints are the same joint "
                            f"'{model.names[left]}'")
        for j in (left, right):
            if j in seen:
                raise BodyError(f"{urdf}: joint '{model.names[j]}' is given as both the "
                                f"{seen[j]} and the {role}")
            seen[j] = role
        a, b = data.oMi[left].translation, data.oMi[right].translation
        if abs(a[1] - b[1]) < 0.02 or abs(a[0] - b[0]) > MIRROR_TOL_M or \
                abs(a[2] - b[2]) > MIRROR_TOL_M:
            raise BodyError(
                f"{urdf}: {role} joints '{model.names[left]}' and '{model.names[right]}' are "
                f"not a mirrored left/right pair (at x, y, z = {_fmt3(a)} and {_fmt3(b)} m)")


def _fmt3(v) -> str:
    return "(" + ", ".join(f"{x:.3f}" for x in v) + ")"


def load_posture(
    urdf: str | Path,
    srdf: tuple[str | Path, str] | None = None,
    base_rpy: tuple[float, float, float] = (0.0, 0.0, 0.0),
    posture: np.ndarray | None = None,
) -> tuple[object, np.ndarray, str]:
    """A whole-body URDF with a free-flyer base, in the posture it is lumped at.

    Args:
        urdf: the whole-body URDF.
        srdf: (SRDF file, configuration name) to read the posture from.
        base_rpy: base orientation applied on top of the posture (rad).
        posture: (nq,) configuration (position, quaternion x y z w, joints); overrides
            ``srdf``.
    Returns:
        (Pinocchio model, (nq,) configuration, a label saying which posture it is).
    Raises:
        BodyError: a missing or unreadable URDF or SRDF, an unknown configuration, a
            posture of the wrong size (one line).
    """
    import pinocchio as pin

    urdf = Path(urdf)
    if not urdf.is_file():
        raise BodyError(f"{urdf}: no such URDF file")
    try:
        model = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer())
    except Exception as exc:
        raise BodyError(f"{urdf}: cannot be read as URDF ({' '.join(str(exc).split())})") from None
    q = pin.neutral(model)
    label = "zero configuration"
    if srdf is not None:
        srdf_path, config = Path(srdf[0]), srdf[1]
        try:
            pin.loadReferenceConfigurations(model, str(srdf_path), False)
        except Exception as exc:
            raise BodyError(f"{srdf_path}: cannot read reference configurations ({exc})") from None
        if config not in model.referenceConfigurations:
            known = ", ".join(model.referenceConfigurations.keys())
            raise BodyError(f"{srdf_path}: no configuration '{config}' (has: {known})")
        q = np.array(model.referenceConfigurations[config])
        label = f"'{config}' from {srdf_path.name}"
    if posture is not None:
        posture = np.asarray(posture, dtype=float)
        if posture.shape != (model.nq,):
            raise BodyError(
                f"{urdf}: posture has {posture.size} values; this model with a free-flyer "
                f"base needs nq = {model.nq} (x y z, quaternion x y z w, {model.nq - 7} joints)"
            )
        q = posture.copy()
        label = "given posture"
    if any(base_rpy):
        rot = pin.rpy.rpyToMatrix(*base_rpy) @ pin.Quaternion(q[6], *q[3:6]).matrix()
        quat = pin.Quaternion(rot)
        q[3:7] = [quat.x, quat.y, quat.z, quat.w]
    return model, q, label


def lump_robot(
    urdf: str | Path,
    ankle: tuple[str, str],
    hip: tuple[str, str],
    knee: tuple[str, str] | None = None,
    posture: np.ndarray | None = None,
    srdf: tuple[str | Path, str] | None = None,
    base_rpy: tuple[float, float, float] = (0.0, 0.0, 0.0),
    segments: int = 3,
    name: str | None = None,
) -> LumpedBody:
    """Lump a whole-body URDF (floating base) into a 1-, 2- or 3-segment sagittal chain.

    Args:
        urdf: the whole-body URDF.
        ankle: (left, right) ankle pitch-joint names.
        hip: (left, right) hip pitch-joint names.
        knee: (left, right) knee pitch-joint names; needed for 3 segments.
        posture: (nq,) configuration of the model with a free-flyer base (position,
            quaternion x y z w, joints); default neutral, or ``srdf``.
        srdf: (SRDF file, configuration name) to read the posture from.
        base_rpy: base orientation applied on top of the posture (rad).
        segments: 3 (shank, thigh, trunk), 2 (leg, trunk: knee locked) or 1 (body).
        name: the stem of the lumped body's name (``<name>_<N>seg``; None: the URDF's
            robot name).
    """
    import pinocchio as pin

    urdf = Path(urdf)
    if not urdf.is_file():
        raise BodyError(f"{urdf}: no such URDF file")
    if segments not in (1, 2, 3):
        raise BodyError(f"segments must be 1, 2 or 3, got {segments}")
    if segments == 3 and knee is None:
        raise BodyError("a 3-segment body needs the knee joints")
    model, q, label = load_posture(urdf, srdf=srdf, base_rpy=base_rpy, posture=posture)

    data = model.createData()
    pin.forwardKinematics(model, data, q)
    pin.computeJointJacobians(model, data, q)
    lateral = np.array([0.0, 1.0, 0.0])
    roles = {"ankle": ankle, "hip": hip}
    if knee is not None:
        roles["knee"] = knee
    ids: dict[str, tuple[int, int]] = {}
    for role, pair in roles.items():
        if len(pair) != 2:
            raise BodyError(f"{urdf}: give two {role} joints (left, right), got {pair}")
        ids[role] = tuple(_joint_id(model, n, role, urdf) for n in pair)  # type: ignore[assignment]
        for joint_name, j in zip(pair, ids[role], strict=True):
            if model.joints[j].nv != 1:
                raise BodyError(f"{urdf}: {role} joint '{joint_name}' is not a revolute joint")
            jac = np.asarray(pin.getJointJacobian(model, data, j, pin.ReferenceFrame.WORLD))
            axis = jac[3:, model.joints[j].idx_v]
            if abs(abs(float(axis @ lateral)) - 1.0) > _PITCH_TOL:
                raise BodyError(
                    f"{urdf}: {role} joint '{joint_name}' does not pitch: its axis "
                    f"({', '.join(f'{a:.3g}' for a in axis)}) is not the lateral axis y "
                    f"in the {label}"
                )
    _check_pairs(urdf, model, data, ids)
    subtree = {j: set(model.subtrees[j]) for pair in ids.values() for j in pair}
    for side in (0, 1):
        chain = [ids["hip"][side], *([ids["knee"][side]] if knee else []), ids["ankle"][side]]
        for upper, lower in zip(chain, chain[1:], strict=False):
            if lower not in subtree[upper] or lower == upper:
                raise BodyError(
                    f"{urdf}: joint '{model.names[lower]}' is not below '{model.names[upper]}' "
                    "on the same leg: check the order ankle, knee, hip and left, right"
                )

    def both(role: str) -> set[int]:
        return subtree[ids[role][0]] | subtree[ids[role][1]]

    everything = set(range(model.njoints))
    feet = both("ankle")
    if segments == 3:
        groups = [
            ("shank", "ankle", both("knee") - feet),
            ("thigh", "knee", both("hip") - both("knee")),
            ("trunk", "hip", everything - both("hip")),
        ]
    elif segments == 2:
        groups = [("leg", "ankle", both("hip") - feet), ("trunk", "hip", everything - both("hip"))]
    else:
        groups = [("body", "ankle", everything - feet)]

    def midpoint(role: str) -> np.ndarray:
        left, right = ids[role]
        return (data.oMi[left].translation + data.oMi[right].translation) / 2.0

    points = [midpoint(role) for _, role, _ in groups]
    ankle_point = points[0]
    links = []
    for k, (link, role, members) in enumerate(groups):
        mass, com, tensor = _group_inertia(model, data, sorted(members))
        origin = points[k] - (points[k - 1] if k else ankle_point)
        if k + 1 < len(groups):
            end = points[k + 1] - points[k]
        else:
            tops = [data.oMi[j].translation for j in members]
            top = max(tops, key=lambda p: p[2])
            end = top - points[k]
            if end[2] <= com[2] - points[k][2]:
                end = 2.0 * (com - points[k])
        links.append(
            LinkSpec(
                link=link, joint=role, origin=tuple(origin), mass=mass,
                com=tuple(com - points[k]), inertia=tuple(map(tuple, tensor)), end=tuple(end),
            )
        )
    foot_mass, foot_com, foot_tensor = _group_inertia(model, data, sorted(feet))
    robot = name or model.name
    return LumpedBody(
        name=f"{robot}_{segments}seg",
        links=links,
        foot=(foot_mass, tuple(foot_com - ankle_point), foot_tensor),
        joint_points=np.array(points),
        origin=(
            f"lumped by posture-id from {urdf.name} at the {label}: {segments} segments, "
            f"joints {', '.join(f'{r}={p[0]}/{p[1]}' for r, p in roles.items())}"
        ),
    )


def preset_body(name: str, segments: int = 3) -> LumpedBody:
    """Lump one of :data:`PRESETS` (``talos``, ``g1``, ``human``).

    Args:
        name: the preset's name; it also names the lumped body (``<name>_<segments>seg``).
        segments: 3 (shank, thigh, trunk), 2 (leg, trunk: knee locked) or 1 (body).
    Returns:
        :class:`LumpedBody`, lumped at the preset's posture (its SRDF configuration, or
        the zero configuration).
    Raises:
        BodyError: an unknown preset, a segment count other than 1, 2 or 3, or a robot
            model that cannot be read.
    """
    if name not in PRESETS:
        raise BodyError(f"unknown robot '{name}' (presets: {', '.join(PRESETS)})")
    preset = PRESETS[name]
    root = robots_dir()
    srdf = (root / preset.srdf[0], preset.srdf[1]) if preset.srdf else None
    return lump_robot(
        root / preset.urdf, ankle=preset.ankle, knee=preset.knee if segments == 3 else None,
        hip=preset.hip, srdf=srdf, base_rpy=preset.base_rpy, segments=segments, name=name,
    )
