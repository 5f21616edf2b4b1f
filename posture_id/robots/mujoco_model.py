"""A posture_id body on its tilting platform as a MuJoCo model (MJCF written here).

The chain is taken from the body's Pinocchio model (what :func:`~posture_id.bodies.body.load_body`
read from the URDF; links joined by fixed joints already merged): every segment becomes a
MuJoCo body with the URDF joint's placement, a hinge about the joint's axis and the link's
mass, COM and 3×3 inertia tensor. MuJoCo's URDF importer is not used: the platform has to
be inserted under the chain, and the importer's defaults (inertia from geometry, joint
armature, contacts) would each have to be undone.

The MJCF's world, as the URDF's: gravity is the Pinocchio model's (−z, 9.81 m/s² for the
shipped bodies), the joints share the body's horizontal axis ``a`` (+y), forward is
``a × up`` (+x).

    world
    └── platform   hinge about ``a`` through the ankle (the stimulus's tilt α_FS, prescribed)
        └── segment 1 (shank)   hinge "ankle": q_1 = θ_1 − α_FS
            └── segment 2 (thigh)   hinge "knee": q_2 = θ_2 − θ_1
                └── ...

Decisions, each a field of :class:`MujocoOptions`:

- **the platform is prescribed kinematically.** Its hinge has an armature of
  ``platform_armature`` (1e10 kg·m²), so the torques the body exerts on it cannot
  accelerate it (|α̈_FS| < 1e-7 rad/s² at the TIP's ankle torques); before every step
  the simulator sets its angle and rate to the stimulus's exactly and shifts the ankle
  coordinate by the same amount the other way, so the body's state in space is unchanged
  (the ankle turns about a fixed axis: the platform reaches the body only through the
  ankle joint, docs/model.md §1). A PRTS's tilt is linear between knots on the step grid,
  so the platform moves exactly as prescribed within every step too.
- **inertia about the hinge axis is exact; the other principal moments are made
  positive.** A planar chain's dynamics use only aᵀ·I·a of each link; a slender rod's zero
  moment about its own long axis (the TIP's izz = 0), which MuJoCo refuses, is raised by
  ``inertia_floor`` in the plane normal to ``a``, which leaves aᵀ·I·a unchanged.
- **no contacts, no joint limits, no armature or friction on the chain's joints**: the
  feet are the platform, the joints are ideal hinges; passive stiffness and damping of the
  DEC modules are MuJoCo's own joint stiffness and damping (set per simulation,
  :mod:`posture_id.robots.mujoco_sim`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from posture_id.bodies.body import Body
from posture_id.robots.errors import RobotError, require_mujoco

__all__ = ["MujocoOptions", "DEFAULT_STEP_S", "ChainModel", "chain_mjcf", "INTEGRATORS",
           "PLATFORM", "SITE", "SEGMENT_SENSORS", "inertial", "mjcf_head", "compile_mjcf"]

#: MuJoCo integrators by the names :class:`MujocoOptions` accepts.
INTEGRATORS = ("rk4", "implicit", "implicitfast", "euler")
_MJCF_INTEGRATOR = {"rk4": "RK4", "implicit": "implicit", "implicitfast": "implicitfast",
                    "euler": "Euler"}
#: Name of the platform's body and hinge in the MJCF.
PLATFORM = "platform"
#: Suffix of the sites at the platform's and every segment's joint anchor, aligned with the
#: world at the zero posture: their orientation is the segment's turn in space.
SITE = "_frame"
#: The sensors of every segment, in the order of ``sensordata`` (3 values each, world frame):
#: angular velocity, the joint anchor's velocity and position, the COM of the subtree above
#: the joint and its velocity. The platform has one: its angular velocity, first.
SEGMENT_SENSORS = ("angvel", "anchorvel", "anchor", "com_above", "com_above_vel")


#: s, a chain's step when none is given.
DEFAULT_STEP_S = 0.001


@dataclass(frozen=True)
class MujocoOptions:
    """How MuJoCo steps the body on its platform.

    Attributes:
        timestep_s: MuJoCo's step, s; the DEC controller runs once per step. None (the
            default): :data:`DEFAULT_STEP_S` for a chain; for a whole body the largest of
            1, 1/2, 1/4 and 1/8 ms at which its step is stable
            (:func:`~posture_id.robots.whole_body.choose_step`).
        integrator: MuJoCo's integrator, one of :data:`INTEGRATORS` (default ``"rk4"``:
            4th-order Runge-Kutta; the controller's torques are held over its stages).
        platform_armature: kg·m², armature of the platform's hinge, large enough that the
            body's reaction cannot accelerate it (the tilt is prescribed; see the module).
        inertia_floor: kg·m², added to every link's inertia in the plane normal to the
            joint axis (not about it), so that a slender rod's zero moment becomes positive.
        solver_tolerance, solver_iterations: MuJoCo's constraint solver (the whole body's
            welds; a chain has no constraint). Its own default tolerance, 1e-8, leaves
            force errors that DEC's loop turns into sway: on TALOS about 0.01° of sway
            with the platform level, different at every step, where 1e-15 leaves 0.001°,
            the same at 1 and 0.25 ms (docs/robots.md, "The step").
    """

    timestep_s: float | None = None
    integrator: str = "rk4"
    platform_armature: float = 1e10
    inertia_floor: float = 1e-6
    solver_tolerance: float = 1e-15
    solver_iterations: int = 1000

    def __post_init__(self) -> None:
        if self.timestep_s is not None and not (
                math.isfinite(self.timestep_s) and 0 < self.timestep_s <= 0.01):
            raise RobotError(f"MuJoCo timestep_s must be in (0, 0.01] s, got {self.timestep_s}")
        if not (math.isfinite(self.solver_tolerance) and self.solver_tolerance > 0):
            raise RobotError("MuJoCo solver_tolerance must be > 0, got "
                             f"{self.solver_tolerance}")
        if self.solver_iterations < 1:
            raise RobotError("MuJoCo solver_iterations must be ≥ 1, got "
                             f"{self.solver_iterations}")
        if self.integrator not in INTEGRATORS:
            raise RobotError(f"MuJoCo integrator must be one of {', '.join(INTEGRATORS)}, got "
                             f"'{self.integrator}'")
        if not (math.isfinite(self.platform_armature) and self.platform_armature >= 1e6):
            raise RobotError("MuJoCo platform_armature must be ≥ 1e6 kg·m² (the tilt is "
                             f"prescribed), got {self.platform_armature}")
        if not (math.isfinite(self.inertia_floor) and self.inertia_floor > 0):
            raise RobotError(f"MuJoCo inertia_floor must be > 0 kg·m², got {self.inertia_floor}")

    @property
    def step_s(self) -> float:
        """The step, s: ``timestep_s``, or :data:`DEFAULT_STEP_S` when it is None."""
        return DEFAULT_STEP_S if self.timestep_s is None else self.timestep_s


def _vec(v) -> str:
    return " ".join(f"{float(x):.17g}" for x in v)


def _quat(rotation: np.ndarray) -> np.ndarray:
    """(w, x, y, z) unit quaternion of a 3×3 rotation matrix."""
    r = np.asarray(rotation, dtype=float)
    w = math.sqrt(max(0.0, 1.0 + r[0, 0] + r[1, 1] + r[2, 2])) / 2.0
    x = math.copysign(math.sqrt(max(0.0, 1.0 + r[0, 0] - r[1, 1] - r[2, 2])) / 2.0,
                      r[2, 1] - r[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1.0 - r[0, 0] + r[1, 1] - r[2, 2])) / 2.0,
                      r[0, 2] - r[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1.0 - r[0, 0] - r[1, 1] + r[2, 2])) / 2.0,
                      r[1, 0] - r[0, 1])
    q = np.array([w, x, y, z])
    return q / np.linalg.norm(q)


def inertial(com, mass: float, tensor: np.ndarray) -> str:
    """An MJCF ``<inertial>``: COM (3,) m in the body's frame, mass kg, inertia tensor
    (3, 3) kg·m² about the COM."""
    t = tensor
    return (f'<inertial pos="{_vec(com)}" mass="{mass:.17g}" '
            f'fullinertia="{_vec((t[0, 0], t[1, 1], t[2, 2], t[0, 1], t[0, 2], t[1, 2]))}"/>')


def mjcf_head(name: str, options: MujocoOptions, gravity: np.ndarray, at: np.ndarray,
              axis: np.ndarray, solver: str = "") -> list[str]:
    """The first lines of an MJCF of a body on the platform, to the platform's inertial:
    the model ``name``, MuJoCo's step, integrator and ``gravity`` (3,) m/s² (``solver``:
    more ``<option>`` attributes), contacts off, the platform's body at ``at`` (3,) m and
    its hinge about ``axis`` (3,) with ``options.platform_armature``."""
    return [
        f'<mujoco model="{name}">',
        '  <compiler angle="radian" inertiafromgeom="false" autolimits="true"/>',
        f'  <option timestep="{options.step_s:.17g}" '
        f'integrator="{_MJCF_INTEGRATOR[options.integrator]}" gravity="{_vec(gravity)}"'
        f'{solver}>',
        '    <flag contact="disable"/>',
        '  </option>',
        '  <worldbody>',
        f'    <body name="{PLATFORM}" pos="{_vec(at)}">',
        f'      <joint name="{PLATFORM}" type="hinge" axis="{_vec(axis)}" '
        f'armature="{options.platform_armature:.17g}"/>',
        # on the axis: the platform's own weight exerts no torque about it
        '      <inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.1"/>',
    ]


def compile_mjcf(xml: str, refused: str):
    """The ``mujoco.MjModel`` of the MJCF text ``xml``.

    Raises:
        MissingExtraError: MuJoCo is not installed.
        RobotError: MuJoCo refuses the model: ``refused``, then its message in one line.
    """
    mujoco = require_mujoco()
    try:
        return mujoco.MjModel.from_xml_string(xml)
    except ValueError as exc:
        msg = " ".join(str(exc).split())
        raise RobotError(f"{refused} ({msg})") from None


def chain_mjcf(body: Body, options: MujocoOptions | None = None,
               kpas: np.ndarray | None = None, bpas: np.ndarray | None = None) -> str:
    """The MJCF text of ``body`` standing on its platform (see the module).

    Args:
        body: a posture_id chain (N segments); its Pinocchio model gives the placements,
            masses, COMs and inertia tensors.
        options: timestep, integrator, platform armature, inertia floor.
        kpas, bpas: (N,) passive stiffness N·m/rad and damping N·m·s/rad of the joints
            (MuJoCo's joint ``stiffness`` about q = 0 and ``damping``); default 0.
    Returns:
        The MJCF document (str).
    """
    import pinocchio as pin

    options = options or MujocoOptions()
    model = body.model
    n = body.n_segments
    kpas = np.zeros(n) if kpas is None else np.asarray(kpas, dtype=float)
    bpas = np.zeros(n) if bpas is None else np.asarray(bpas, dtype=float)
    if kpas.shape != (n,) or bpas.shape != (n,):
        raise RobotError(f"passive stiffness and damping need {n} values each (one per joint "
                         f"of '{body.name}'), got {kpas.shape} and {bpas.shape}")
    data = model.createData()
    q0 = pin.neutral(model)
    pin.forwardKinematics(model, data, q0)
    axis = np.asarray(body.axis, dtype=float)
    gravity = np.asarray(model.gravity.linear, dtype=float)
    ankle = np.asarray(data.oMi[1].translation, dtype=float)
    up = -gravity / np.linalg.norm(gravity)
    fwd = np.cross(axis, up)
    size = max(s.length for s in body.segments)
    half = 0.3 * size * (np.abs(fwd) + np.abs(axis)) + 0.01 * np.abs(up)  # box half-sizes, m
    lines = [
        *mjcf_head(f"{body.name} on a tilting platform", options, gravity, ankle, axis),
        f'      <geom type="box" size="{_vec(half)}" pos="{_vec(-0.01 * up)}" '
        'contype="0" conaffinity="0" rgba="0.6 0.6 0.6 1"/>',
        f'      <site name="{PLATFORM}{SITE}"/>',
    ]
    indent = "      "
    sensors = [f'    <frameangvel name="{PLATFORM}_angvel" objtype="site" '
               f'objname="{PLATFORM}{SITE}"/>']
    for j in range(1, n + 1):
        seg = body.segments[j - 1]
        placement = model.jointPlacements[j]
        pos = np.zeros(3) if j == 1 else np.asarray(placement.translation, dtype=float)
        rot = np.asarray(placement.rotation, dtype=float)
        world_rot = np.asarray(data.oMi[j].rotation, dtype=float)
        local_axis = world_rot.T @ axis
        inertia = model.inertias[j]
        tensor = np.asarray(inertia.inertia, dtype=float)
        tensor = tensor + options.inertia_floor * (np.eye(3) - np.outer(local_axis, local_axis))
        com = np.asarray(inertia.lever, dtype=float)
        lines += [
            f'{indent}<body name="{seg.name}" pos="{_vec(pos)}" quat="{_vec(_quat(rot))}">',
            f'{indent}  <joint name="{seg.joint}" type="hinge" axis="{_vec(local_axis)}" '
            f'stiffness="{kpas[j - 1]:.17g}" damping="{bpas[j - 1]:.17g}"/>',
            f'{indent}  {inertial(com, float(inertia.mass), tensor)}',
            f'{indent}  <geom type="capsule" fromto="0 0 0 {_vec(2.0 * com)}" size="0.03" '
            'contype="0" conaffinity="0"/>',
            # at the joint's anchor, aligned with the world at the zero posture
            f'{indent}  <site name="{seg.name}{SITE}" quat="{_vec(_quat(world_rot.T))}"/>',
        ]
        sensors += [
            f'    <frameangvel name="{seg.name}_angvel" objtype="site" '
            f'objname="{seg.name}{SITE}"/>',
            f'    <framelinvel name="{seg.name}_anchorvel" objtype="site" '
            f'objname="{seg.name}{SITE}"/>',
            f'    <framepos name="{seg.name}_anchor" objtype="site" objname="{seg.name}{SITE}"/>',
            f'    <subtreecom name="{seg.name}_com_above" body="{seg.name}"/>',
            f'    <subtreelinvel name="{seg.name}_com_above_vel" body="{seg.name}"/>',
        ]
        indent += "  "
    for _ in range(n):
        indent = indent[:-2]
        lines.append(f"{indent}</body>")
    lines += ["    </body>", "  </worldbody>", "  <sensor>", *sensors, "  </sensor>",
              "</mujoco>"]
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class ChainModel:
    """A compiled MuJoCo model of a body on its platform, and where its parts are.

    Attributes:
        body: the posture_id body it was built from.
        options: the MuJoCo options it was built with.
        xml: the MJCF text.
        model: the compiled ``mujoco.MjModel``.
        platform_qpos, platform_dof: addresses of the platform hinge in qpos and qvel.
        segment_bodies: (N,) MuJoCo body ids of the segments, support upward.
        joint_qpos, joint_dofs: (N,) addresses of the segments' hinges in qpos and qvel.
        joint_ids: (N,) MuJoCo joint ids of the segments' hinges.
        platform_site: MuJoCo site id of the platform's frame.
        segment_sites: (N,) MuJoCo site ids of the segments' frames (at their joints'
            anchors, aligned with the world at the zero posture: a segment's angle in space
            is the angle its site's frame has turned about the axis).
        sensor_adr: (N, 5) addresses in ``sensordata`` of each segment's
            :data:`SEGMENT_SENSORS`; platform_sensor: that of the platform's angular velocity.
        axis, up, fwd: (3,) the joint axis, up and forward in the world.
    """

    body: Body
    options: MujocoOptions
    xml: str = field(repr=False)
    model: object = field(repr=False)
    platform_qpos: int
    platform_dof: int
    segment_bodies: np.ndarray
    joint_qpos: np.ndarray
    joint_dofs: np.ndarray
    joint_ids: np.ndarray
    platform_site: int
    segment_sites: np.ndarray
    sensor_adr: np.ndarray = field(repr=False)
    platform_sensor: int
    axis: np.ndarray = field(repr=False)
    up: np.ndarray = field(repr=False)
    fwd: np.ndarray = field(repr=False)

    @classmethod
    def build(cls, body: Body, options: MujocoOptions | None = None,
              kpas: np.ndarray | None = None, bpas: np.ndarray | None = None) -> ChainModel:
        """Write the MJCF of ``body`` (:func:`chain_mjcf`), compile it and locate its parts.

        Raises:
            MissingExtraError: MuJoCo is not installed.
            RobotError: MuJoCo refuses the model (one line: its message).
        """
        mujoco = require_mujoco()
        options = options or MujocoOptions()
        xml = chain_mjcf(body, options, kpas, bpas)
        model = compile_mjcf(xml, f"{body.urdf_path}: MuJoCo refuses the model")
        obj = mujoco.mjtObj

        def ids(kind, names) -> np.ndarray:
            return np.array([mujoco.mj_name2id(model, kind, name) for name in names])

        platform = mujoco.mj_name2id(model, obj.mjOBJ_JOINT, PLATFORM)
        bodies = ids(obj.mjOBJ_BODY, body.segment_names)
        joints = ids(obj.mjOBJ_JOINT, body.joint_names)
        sites = ids(obj.mjOBJ_SITE, [s.name + SITE for s in body.segments])
        sensor_adr = np.array([model.sensor_adr[ids(obj.mjOBJ_SENSOR, [
            f"{s.name}_{what}" for what in SEGMENT_SENSORS])] for s in body.segments])
        axis = np.asarray(body.axis, dtype=float)
        gravity = np.asarray(model.opt.gravity, dtype=float)
        up = -gravity / np.linalg.norm(gravity)
        fwd = np.cross(axis, up)
        return cls(
            body=body, options=options, xml=xml, model=model,
            platform_qpos=int(model.jnt_qposadr[platform]),
            platform_dof=int(model.jnt_dofadr[platform]),
            segment_bodies=bodies,
            joint_qpos=model.jnt_qposadr[joints].astype(int),
            joint_dofs=model.jnt_dofadr[joints].astype(int),
            joint_ids=joints,
            platform_site=mujoco.mj_name2id(model, obj.mjOBJ_SITE, PLATFORM + SITE),
            segment_sites=sites,
            sensor_adr=sensor_adr,
            platform_sensor=int(model.sensor_adr[mujoco.mj_name2id(
                model, obj.mjOBJ_SENSOR, f"{PLATFORM}_angvel")]),
            axis=axis, up=up, fwd=fwd,
        )
