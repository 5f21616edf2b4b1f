"""Bodies: a planar serial chain read from any URDF through Pinocchio.

A :class:`Body` is a chain of N rigid segments standing on a support (the URDF root link,
the feet), joined by revolute joints about one common horizontal axis. Pinocchio loads
the URDF and supplies every inertial quantity; from them the body derives the constants
of its planar equations of motion (used by the compiled simulator) and the m·g·h of the
segments above each joint (used to scale the DEC gains, docs/model.md §1 and §3).

Conventions (docs/model.md §1): angles from the gravitational vertical, positive = forward lean,
i.e. a positive rotation about the common joint axis ``a``; "forward" is ``a × up``.
Points of the sagittal plane are written as complex numbers ``up + 1j * forward`` so that
a segment at angle θ maps a local vector ``v`` to ``exp(1j * θ) * v``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from posture_id.bodies.urdf_checks import check_urdf_text
from posture_id.errors import BodyError
from posture_id.fileio import file_sha256

__all__ = ["Segment", "Body", "load_body", "DEFAULT_URDF", "TWO_SEGMENT_URDF", "BUNDLED_URDFS"]

#: The default triple inverted pendulum shipped with the package (docs/model.md §1).
DEFAULT_URDF = Path(__file__).resolve().parent / "data" / "tip_default.urdf"
#: The straight-leg 2-segment body of the paper's human experiment: Winter, 1.75 m, 70 kg.
TWO_SEGMENT_URDF = DEFAULT_URDF.with_name("winter_1.75m_70kg_2seg.urdf")
#: The bodies shipped with the package, by name.
BUNDLED_URDFS = {"tip_default": DEFAULT_URDF, "winter_1.75m_70kg_2seg": TWO_SEGMENT_URDF}

_REVOLUTE = {
    "JointModelRX",
    "JointModelRY",
    "JointModelRZ",
    "JointModelRevoluteUnaligned",
}
_JOINT_KIND = {
    "JointModelPX": "prismatic",
    "JointModelPY": "prismatic",
    "JointModelPZ": "prismatic",
    "JointModelPrismaticUnaligned": "prismatic",
    "JointModelRUBX": "continuous (unbounded revolute)",
    "JointModelRUBY": "continuous (unbounded revolute)",
    "JointModelRUBZ": "continuous (unbounded revolute)",
    "JointModelRevoluteUnboundedUnaligned": "continuous (unbounded revolute)",
    "JointModelFreeFlyer": "floating",
    "JointModelPlanar": "planar",
    "JointModelSpherical": "spherical",
}
_AXIS_TOL = 1e-9


@dataclass(frozen=True)
class Segment:
    """One rigid segment of the chain, in its upright (zero-angle) posture.

    Attributes:
        name: URDF link name of the segment (e.g. ``"shank"``).
        joint: URDF name of the joint below it (e.g. ``"ankle"``).
        mass: kg (links merged by fixed joints included).
        length: m, from its joint to the next joint; for the top segment, to its farthest
            attached frame, or twice its COM distance when it has none.
        com: (2,) m, COM relative to its joint, as (forward, up).
        inertia: kg·m², moment of inertia about the COM around the joint axis.
        joint_origin: (2,) m, position of its joint relative to the joint below,
            as (forward, up); zeros for the lowest joint.
    """

    name: str
    joint: str
    mass: float
    length: float
    com: tuple[float, float]
    inertia: float
    joint_origin: tuple[float, float]


@dataclass(frozen=True)
class Body:
    """A planar chain of N segments on a tilting support, loaded from a URDF.

    Build it with :func:`load_body` (or :meth:`Body.from_urdf`). All quantities are SI.

    Attributes:
        name: robot name from the URDF.
        urdf_path: the file it was loaded from.
        segments: the N segments, from the support upward.
        axis: (3,) common joint axis in the URDF world frame.
        gravity: m/s², magnitude of gravity.
        sha256: SHA-256 of the URDF file's bytes (results carry it as the body's identity).
        model: the Pinocchio model (for the reference simulation and checks).
    """

    name: str
    urdf_path: Path
    segments: tuple[Segment, ...]
    axis: tuple[float, float, float]
    gravity: float
    sha256: str
    model: object = field(repr=False, compare=False)

    # ----------------------------------------------------------------- loading
    @classmethod
    def from_urdf(cls, path: str | Path) -> Body:
        """Load and validate a URDF; see :func:`load_body`."""
        return load_body(path)

    # ------------------------------------------------------------ descriptors
    @property
    def n_segments(self) -> int:
        """N, the number of segments (= joints = DEC modules)."""
        return len(self.segments)

    @property
    def segment_names(self) -> tuple[str, ...]:
        """URDF link names of the segments, from the support upward."""
        return tuple(s.name for s in self.segments)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """URDF joint names, from the support upward (one DEC module each)."""
        return tuple(s.joint for s in self.segments)

    @property
    def total_mass(self) -> float:
        """kg, mass of all segments (the support excluded)."""
        return float(sum(s.mass for s in self.segments))

    # ------------------------------------------------------- planar constants
    @cached_property
    def _complex_geometry(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(N,) complex next-joint vectors p, (N,) complex COM vectors r, (N,) masses."""
        n = self.n_segments
        p = np.zeros(n, dtype=complex)
        r = np.zeros(n, dtype=complex)
        m = np.array([s.mass for s in self.segments])
        for j, seg in enumerate(self.segments):
            r[j] = seg.com[1] + 1j * seg.com[0]
            if j + 1 < n:
                nxt = self.segments[j + 1].joint_origin
                p[j] = nxt[1] + 1j * nxt[0]
        return p, r, m

    @cached_property
    def coupling(self) -> np.ndarray:
        """(N, N) complex Hermitian D with M(θ)_jk = Re(D_jk e^{i(θ_j-θ_k)}) + δ_jk I_j.

        D_jk = Σ_i m_i a_ij conj(a_ik), with a_ij the lever of segment i's COM on
        segment j: p_j below i, r_i at i, 0 above (kg·m²).
        """
        p, r, m = self._complex_geometry
        n = self.n_segments
        lever = np.zeros((n, n), dtype=complex)  # lever[i, j] = a_ij
        for i in range(n):
            lever[i, :i] = p[:i]
            lever[i, i] = r[i]
        return np.einsum("i,ij,ik->jk", m, lever, lever.conj())

    @cached_property
    def gravity_lever(self) -> np.ndarray:
        """(N,) complex S_j = Σ_i m_i a_ij (kg·m): the potential is g·Re(Σ_j e^{iθ_j} S_j).

        Σ_{j≥i} e^{iθ_j} S_j is m_above,i times the vector from joint i to the COM of the
        segments from i upward.
        """
        p, r, m = self._complex_geometry
        n = self.n_segments
        s = np.zeros(n, dtype=complex)
        for j in range(n):
            s[j] = m[j] * r[j] + m[j + 1 :].sum() * p[j]
        return s

    @property
    def inertias(self) -> np.ndarray:
        """(N,) kg·m², segment inertias about their COMs around the joint axis."""
        return np.array([s.inertia for s in self.segments])

    # -------------------------------------------------- per-module quantities
    @property
    def mass_above(self) -> np.ndarray:
        """(N,) kg, mass of the segments from joint i upward."""
        m = np.array([s.mass for s in self.segments])
        return np.cumsum(m[::-1])[::-1]

    @property
    def lever_above(self) -> np.ndarray:
        """(N,) complex kg·m, Σ_{j≥i} S_j: m_above,i times the vector from joint i to the COM
        above it at θ = 0 (up + 1j·fwd)."""
        s = self.gravity_lever
        return np.cumsum(s[::-1])[::-1]

    @property
    def com_above(self) -> np.ndarray:
        """(N,) complex m, vector from joint i to the COM above it at upright (up + 1j·fwd)."""
        return self.lever_above / self.mass_above

    def com_angles(self, theta: np.ndarray) -> np.ndarray:
        """COM-above angles α_i,S (..., N) rad of segment angles θ (..., N) rad: the angle
        from the vertical of the line from joint i to the COM of the segments above it
        (α_1,S is the whole-body sway α_BS)."""
        vectors = np.exp(1j * np.asarray(theta)) * self.gravity_lever
        above = np.flip(np.cumsum(np.flip(vectors, axis=-1), axis=-1), axis=-1)
        return np.angle(above)

    @property
    def reference_com_angles(self) -> np.ndarray:
        """(N,) rad, α_i,S at the reference posture θ = 0 (the URDF's zero configuration):
        0 for a straight chain, the lean of each COM-above line for a bent one (docs/model.md,
        "The reference posture of a bent body")."""
        return np.angle(self.lever_above)

    @property
    def holding_torques(self) -> np.ndarray:
        """(N,) N·m, the joint torques τ_i that hold the reference posture θ = 0 at rest
        against gravity: −g·Im(Σ_{j≥i} S_j); 0 for a straight chain."""
        return -self.gravity * self.lever_above.imag

    @property
    def com_height_above(self) -> np.ndarray:
        """(N,) m, h_i: distance from joint i to the COM of the segments above, upright."""
        return np.abs(self.com_above)

    @cached_property
    def mgh(self) -> np.ndarray:
        """(N,) N·m/rad, m_above,i·g·h_i at upright, computed by Pinocchio (subtree COMs)."""
        import pinocchio as pin

        model = self.model
        data = model.createData()
        q0 = pin.neutral(model)
        pin.forwardKinematics(model, data, q0)
        pin.centerOfMass(model, data, q0, True)
        axis = np.asarray(self.axis)
        out = np.empty(self.n_segments)
        for i in range(self.n_segments):
            joint_id = i + 1
            # subtree COMs of joints ≥ 1 are expressed in the joint's own frame
            lever = np.asarray(data.oMi[joint_id].rotation) @ np.asarray(data.com[joint_id])
            in_plane = lever - axis * float(axis @ lever)
            out[i] = data.mass[joint_id] * self.gravity * np.linalg.norm(in_plane)
        return out

    def to_dict(self) -> dict:
        """A JSON-ready description: identity, segments and per-module m·g·h."""
        return {
            "name": self.name,
            "urdf": str(self.urdf_path),
            "sha256": self.sha256,
            "gravity_m_s2": self.gravity,
            "total_mass_kg": self.total_mass,
            "segments": [
                {
                    "name": s.name,
                    "joint": s.joint,
                    "mass_kg": s.mass,
                    "length_m": s.length,
                    "com_fwd_up_m": list(s.com),
                    "inertia_kg_m2": s.inertia,
                }
                for s in self.segments
            ],
            "modules": [
                {
                    "joint": j,
                    "mass_above_kg": float(ma),
                    "com_height_above_m": float(h),
                    "mgh_Nm_per_rad": float(v),
                }
                for j, ma, h, v in zip(
                    self.joint_names, self.mass_above, self.com_height_above, self.mgh, strict=True
                )
            ],
        }

    def summary(self) -> str:
        """A printable table: identity and one row per segment."""
        lines = [
            f"body '{self.name}' from {self.urdf_path}: {self.n_segments} segments, "
            f"{self.total_mass:.3f} kg, g = {self.gravity:g} m/s²",
            "",
            f"{'segment':<10}{'joint':<10}{'mass kg':>9}{'length m':>10}{'COM m':>8}"
            f"{'I kg·m²':>10}{'m·g·h':>10}",
        ]
        for s, mgh in zip(self.segments, self.mgh, strict=True):
            lines.append(
                f"{s.name:<10}{s.joint:<10}{s.mass:>9.3f}{s.length:>10.4f}"
                f"{(s.com[0] ** 2 + s.com[1] ** 2) ** 0.5:>8.4f}{s.inertia:>10.4f}{mgh:>10.3f}"
            )
        return "\n".join(lines)


def load_body(path: str | Path = DEFAULT_URDF) -> Body:
    """Load a URDF through Pinocchio and check it is a valid sagittal chain.

    Args:
        path: URDF file. Its root link is the support (feet on the tilting platform); the
            moving joints must form one serial chain of revolute joints about one common
            horizontal axis. Links attached by fixed joints are merged into their parent.

    Raises:
        BodyError: one line naming the file, the joint or link, and the problem.
    """
    import pinocchio as pin

    path = Path(path)
    if path.is_dir():
        raise BodyError(f"{path}: is a folder, expected a URDF file")
    if not path.is_file():
        raise BodyError(f"{path}: no such URDF file")
    check_urdf_text(path)
    try:
        model = pin.buildModelFromUrdf(str(path))
    except Exception as exc:  # pinocchio raises plain RuntimeError/ValueError
        msg = " ".join(str(exc).split())
        raise BodyError(f"{path}: cannot be read as URDF ({msg})") from None

    n = model.njoints - 1
    if n < 1:
        raise BodyError(f"{path}: no moving joint: a body needs at least one revolute joint")
    names = [model.names[j] for j in range(1, model.njoints)]

    for j in range(1, model.njoints):
        short = model.joints[j].shortname()
        if short not in _REVOLUTE:
            kind = _JOINT_KIND.get(short, short)
            raise BodyError(
                f"{path}: joint '{model.names[j]}' is {kind}; every joint of the chain "
                "must be revolute (fixed joints are merged)"
            )

    data = model.createData()
    q0 = pin.neutral(model)
    pin.forwardKinematics(model, data, q0)
    pin.updateFramePlacements(model, data)
    pin.computeJointJacobians(model, data, q0)

    g_vec = np.asarray(model.gravity.linear, dtype=float)
    g = float(np.linalg.norm(g_vec))
    if g == 0.0:
        raise BodyError(f"{path}: gravity is zero")
    up = -g_vec / g

    axes = []
    for j in range(1, model.njoints):
        jac = pin.getJointJacobian(model, data, j, pin.ReferenceFrame.WORLD)
        axis = np.asarray(jac, dtype=float).reshape(6, model.nv)[3:, j - 1]
        axis = axis / np.linalg.norm(axis)
        if abs(float(axis @ up)) > _AXIS_TOL:
            raise BodyError(
                f"{path}: joint '{model.names[j]}' axis {_fmt(axis)} is not horizontal: "
                "the chain must rotate in the sagittal plane"
            )
        if axes and float(axis @ axes[0]) < 1.0 - _AXIS_TOL:
            raise BodyError(
                f"{path}: joint '{model.names[j]}' axis {_fmt(axis)} is off the common axis "
                f"{_fmt(axes[0])} of '{model.names[1]}': all joints must share one axis "
                "(same direction)"
            )
        axes.append(axis)
    axis = axes[0]
    forward = np.cross(axis, up)

    def plane(v: np.ndarray) -> tuple[float, float]:
        return float(v @ forward), float(v @ up)

    link_of_joint = {}
    for frame in model.frames:
        if frame.type == pin.FrameType.BODY and frame.parentJoint not in link_of_joint:
            link_of_joint[frame.parentJoint] = frame.name

    segments = []
    for j in range(1, model.njoints):
        inertia = model.inertias[j]
        link = link_of_joint.get(j, model.names[j])
        if not inertia.mass > 0.0 or not np.isfinite(inertia.mass):
            raise BodyError(
                f"{path}: link '{link}' (after joint '{model.names[j]}') has no mass: "
                "every moving link needs an <inertial> with mass > 0"
            )
        o_mi = data.oMi[j]
        com_world = o_mi.act(np.asarray(inertia.lever))
        rot = np.asarray(o_mi.rotation)
        inertia_axis = float(axis @ rot @ np.asarray(inertia.inertia) @ rot.T @ axis)
        if inertia_axis < 0.0 or not np.isfinite(inertia_axis):
            raise BodyError(f"{path}: link '{link}' has a negative or invalid inertia")
        origin = o_mi.translation
        com = plane(com_world - origin)
        if j < n:
            length = float(np.linalg.norm(plane(data.oMi[j + 1].translation - origin)))
        else:
            reach = [
                float(np.linalg.norm(plane(data.oMf[f].translation - origin)))
                for f, frame in enumerate(model.frames)
                if frame.parentJoint == j
            ]
            com_dist = float(np.hypot(*com))
            length = max(reach) if reach and max(reach) > com_dist else 2.0 * com_dist
        below = data.oMi[j - 1].translation if j > 1 else origin
        segments.append(
            Segment(
                name=link,
                joint=model.names[j],
                mass=float(inertia.mass),
                length=length,
                com=com,
                inertia=inertia_axis,
                joint_origin=plane(origin - below),
            )
        )

    body = Body(
        name=model.name,
        urdf_path=path,
        segments=tuple(segments),
        axis=tuple(float(a) for a in axis),
        gravity=g,
        sha256=file_sha256(path),
        model=model,
    )
    for i, h in enumerate(body.com_above):
        if h.real <= 0.0:
            raise BodyError(
                f"{path}: the COM above joint '{names[i]}' is not above it at the zero "
                "posture: the chain must stand upright"
            )
    return body


def _fmt(v: np.ndarray) -> str:
    return "(" + ", ".join(f"{x:.3g}" for x in v) + ")"
