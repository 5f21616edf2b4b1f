"""A humanoid's whole body on the tilting platform in MuJoCo, DEC at its lumped joints.

The whole-body URDF (a preset of :data:`~posture_id.bodies.lumping.PRESETS`, or any URDF
with named ankle, knee and hip pitch joints) is read by Pinocchio with a free-flyer base
and put in the posture it is lumped at (:func:`reference_configuration`: the SRDF
configuration or the zero one, the base turned by ``base_rpy``, as
:func:`~posture_id.bodies.lumping.lump_robot` does). The MJCF is written from the
Pinocchio model's bodies (links joined by fixed joints merged; meshes are not needed):
one MuJoCo body per Pinocchio joint, placed where the reference posture puts it, so that
MuJoCo's zero configuration *is* the lumped posture; its mass, COM and inertia tensor;
a hinge about the joint's axis.

    world
    ├── platform   hinge about the lateral axis through the lumped ankle (prescribed)
    └── pelvis     free joint (the URDF's root)
        ├── legs ... feet   each foot welded to the platform (equality constraint)
        └── torso, arms, head

Decisions (each stated in docs/robots.md):

- **the feet are welded to the platform, the base is free.** The two legs close a loop
  through the platform, so no tree rooted at the feet avoids a loop closure; the URDF's
  own tree is kept (pelvis at its root, a free joint) and the last body of each foot is
  held to the platform by a MuJoCo ``weld`` equality, stiff (``WholeBodyOptions
  .weld_timeconst_s``, 2 ms; impedance 0.99-0.999: the sole moves less than a
  hundred micrometres under the body's weight).
- **DEC acts at the lumped joints**: the lumped ankle torque is shared equally by the two
  ankle pitch joints, knees and hips likewise; their passive stiffness and damping are
  half the module's each (two springs in parallel). DEC's sensors read the whole body as
  the lumped model defines it (:class:`WholeBodySensors`).
- **every other joint is a stiff PD servo** about the lumped posture, with the static
  torque of that posture fed forward (:func:`static_torques`); its stiffness
  K = ``stiffness_factor`` (100) × m·g·h of the mass the joint carries (:func:`servo_gains`),
  critically damped. A joint that moves less than ``locked_below_kg`` is locked, and so
  are the feet's own joints beyond the ankle pitch (an ankle's roll joint): the feet are
  the support, welded to the platform, as the lumping makes them. Where a servo is past
  what RK4 integrates at the step on the joint's own inertia in MuJoCo's tree, an armature
  is added to that joint (``WholeBodyOptions.max_step_rate``; a 2-segment lumping's knee).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from posture_id.bodies.lumping import world_inertia
from posture_id.errors import BodyError
from posture_id.robots.errors import RobotError, require_mujoco
from posture_id.robots.mujoco_model import _quat, _vec

__all__ = ["WholeBodySpec", "WholeBodyOptions", "HeldJoints", "ServoGain", "WholeBodyModel",
           "WholeBodySensors", "reference_configuration", "servo_gains", "ROLES",
           "simulate_whole_body", "lumped_body", "static_torques"]

#: The lumped joints of an N-segment lumping, support upward (posture_id.bodies.lumping).
ROLES = {1: ("ankle",), 2: ("ankle", "hip"), 3: ("ankle", "knee", "hip")}
PLATFORM = "platform"


@dataclass(frozen=True)
class WholeBodySpec:
    """A whole-body URDF and how it is read as a sagittal chain (as the lumping reads it).

    Attributes:
        urdf: the whole-body URDF (free-flyer base).
        ankle, knee, hip: (left, right) names of the pitch joints.
        srdf: optional (SRDF file, configuration name) of the reference posture.
        base_rpy: roll, pitch, yaw (rad) of the base on top of the posture.
        name: the robot's name (a preset's name).
    """

    urdf: Path
    ankle: tuple[str, str]
    knee: tuple[str, str]
    hip: tuple[str, str]
    srdf: tuple[Path, str] | None = None
    base_rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    name: str = "robot"

    @classmethod
    def preset(cls, name: str) -> WholeBodySpec:
        """One of :data:`~posture_id.bodies.lumping.PRESETS` (``talos``, ``g1``, ``human``)."""
        from posture_id.bodies.lumping import PRESETS, robots_dir

        if name not in PRESETS:
            raise BodyError(f"unknown robot '{name}' (presets: {', '.join(PRESETS)})")
        preset = PRESETS[name]
        root = robots_dir()
        srdf = (root / preset.srdf[0], preset.srdf[1]) if preset.srdf else None
        return cls(urdf=root / preset.urdf, ankle=preset.ankle, knee=preset.knee,
                   hip=preset.hip, srdf=srdf, base_rpy=tuple(preset.base_rpy), name=name)

    def pitch_joints(self, segments: int) -> list[tuple[str, str]]:
        """The (left, right) pitch joints of the lumped joints of ``segments`` segments."""
        return [getattr(self, role) for role in ROLES[segments]]


class HeldJoints(enum.Enum):
    """How the joints the lumping treats as rigid are held in MuJoCo."""

    #: a stiff PD servo each (:func:`servo_gains`): a robot's joint controllers
    SERVOS = "servos"
    #: welded: the held joints are not joints at all, exactly as the lumping assumes
    RIGID = "rigid"


@dataclass(frozen=True)
class WholeBodyOptions:
    """How the whole body is held together in MuJoCo.

    Attributes:
        held: :class:`HeldJoints` (default servos): servos, or welded rigid (the lumping's
            own assumption, no servo to integrate: it tells what the servos' compliance
            adds from what the rest of the lumping leaves out).
        stiffness_factor: a held joint's stiffness over the m·g·h of the mass it carries.
        damping_ratio: of each held joint's servo (1: critically damped, with the
            inertia it carries about its axis).
        min_lever_m: m, the lever in m·g·h is at least this (a yaw joint's mass sits on
            its axis; its stiffness would be zero).
        locked_below_kg: a joint that carries less mass than this is locked (kg).
        weld_timeconst_s: s, time constant of the feet's welds to the platform
            (MuJoCo's ``solref``; at least twice the step).
        mass_floor_kg: a massless link (a URDF's intermediate link of a 3-DoF joint) gets
            this mass, with a ``1e-3 × mass`` m² inertia (kg).
        max_step_rate: a held joint's servo must satisfy B·dt/I ≤ this and √(K/I)·dt ≤
            this, I its own inertia in MuJoCo's mass matrix (its subtree's, about its axis,
            at the reference posture) and dt the step: where it does not, an armature (a
            motor's reflected rotor inertia, kg·m²) is added to the joint until it does.
            Without it a stiff servo on a light subtree (a knee held in a 2-segment
            lumping: its shank and foot; a wrist) is at the edge of RK4's stability at 1 ms
            and rings or diverges.
    """

    held: HeldJoints = HeldJoints.SERVOS
    stiffness_factor: float = 100.0
    damping_ratio: float = 1.0
    min_lever_m: float = 0.05
    locked_below_kg: float = 1e-3
    weld_timeconst_s: float = 0.002
    mass_floor_kg: float = 1e-4
    max_step_rate: float = 1.0

    def __post_init__(self) -> None:
        try:
            object.__setattr__(self, "held", HeldJoints(self.held))
        except ValueError:
            raise RobotError(f"WholeBodyOptions.held must be one of "
                             f"{', '.join(h.value for h in HeldJoints)}, got {self.held!r}"
                             ) from None
        for name in ("stiffness_factor", "damping_ratio", "min_lever_m", "weld_timeconst_s",
                     "mass_floor_kg", "locked_below_kg", "max_step_rate"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise RobotError(f"WholeBodyOptions.{name} must be > 0, got {value}")


def reference_configuration(spec: WholeBodySpec):
    """(Pinocchio model with a free-flyer base, (nq,) configuration): the whole body in
    the posture the lumping uses (SRDF configuration or zero; the base turned by
    ``base_rpy``)."""
    from posture_id.bodies.lumping import load_posture

    urdf = Path(spec.urdf)
    model, q, _label = load_posture(urdf, srdf=spec.srdf, base_rpy=spec.base_rpy)
    for pair in (spec.ankle, spec.knee, spec.hip):
        for name in pair:
            if not model.existJointName(name):
                raise BodyError(f"{urdf}: joint '{name}' is not in the model")
    return model, q


@dataclass(frozen=True)
class ServoGain:
    """The PD servo holding one joint the lumping treats as rigid.

    Attributes:
        joint: URDF joint name. mass_kg: the mass it carries (half the body above it for
        a leg's joint: two legs share it). lever_m: distance of that mass's COM from the
        joint's axis (at least ``min_lever_m``). stiffness: N·m/rad. inertia: kg·m² about
        its axis. damping: N·m·s/rad. feedforward: N·m, the static torque of the posture.
        locked: a joint of the feet (beyond the ankle pitch: the support, welded to the
        platform), or one that carries too little mass to be a joint: locked (rigid).
        armature: kg·m², added to the joint in MuJoCo so that its servo is stable at the
        step (``WholeBodyOptions.max_step_rate``; 0 where it already is).
    """

    joint: str
    mass_kg: float
    lever_m: float
    stiffness: float
    inertia: float
    damping: float
    feedforward: float = 0.0
    locked: bool = False
    armature: float = 0.0

    def to_dict(self) -> dict:
        return {"joint": self.joint, "mass_kg": self.mass_kg, "lever_m": self.lever_m,
                "stiffness_nm_rad": self.stiffness, "damping_nms_rad": self.damping,
                "inertia_kgm2": self.inertia, "feedforward_nm": self.feedforward,
                "locked": self.locked, "armature_kgm2": self.armature}


def _joint_axes(model, data, q) -> dict[int, np.ndarray]:
    """World axis (3,) of every 1-DoF revolute joint at ``q`` (others absent)."""
    import pinocchio as pin

    pin.computeJointJacobians(model, data, q)
    axes = {}
    for j in range(2, model.njoints):
        joint = model.joints[j]
        if joint.nv != 1:
            continue
        jac = np.asarray(pin.getJointJacobian(model, data, j, pin.ReferenceFrame.WORLD))
        col = jac[:, joint.idx_v]
        if np.linalg.norm(col[3:]) > 0.5:  # revolute: unit angular part
            axes[j] = col[3:] / np.linalg.norm(col[3:])
    return axes


def servo_gains(model, data, q, dec_joints: set[int], ankles: tuple[int, int],
                options: WholeBodyOptions) -> dict[int, ServoGain]:
    """The PD servo of every joint that is not one of DEC's (``dec_joints``), by
    Pinocchio joint id.

    The mass a joint carries: for a joint on a leg (between the pelvis and a foot, the
    feet's own joints included) half of everything on the pelvis's side of it (the two
    legs share the body's weight); for any other joint (waist, arms, head) its subtree.
    K = ``stiffness_factor`` · m · g · max(lever, ``min_lever_m``); B = 2ζ·√(K·I), I the
    carried mass's moment of inertia about the joint's axis (the same share).
    """
    parts = {j: world_inertia(model, data, j) for j in range(1, model.njoints)}
    axes = _joint_axes(model, data, q)
    g = float(np.linalg.norm(model.gravity.linear))
    everything = set(range(1, model.njoints))
    feet = set(model.subtrees[ankles[0]]) | set(model.subtrees[ankles[1]])
    gains = {}
    for j in range(2, model.njoints):
        if j in dec_joints:
            continue
        name = model.names[j]
        if j not in axes:
            raise RobotError(f"joint '{name}' is not a 1-DoF revolute joint: the whole-body "
                             "check holds revolute joints only")
        subtree = set(model.subtrees[j])
        on_leg = j in feet or ankles[0] in subtree or ankles[1] in subtree
        members, share = ((everything - subtree, 0.5) if on_leg else (subtree, 1.0))
        axis = axes[j]
        anchor = np.asarray(data.oMi[j].translation)
        mass, first, inertia = 0.0, np.zeros(3), 0.0
        for b in members:
            m, c, tensor = parts[b]
            r = c - anchor
            r_perp = r - (r @ axis) * axis
            mass += m
            first += m * c
            inertia += float(axis @ tensor @ axis) + m * float(r_perp @ r_perp)
        mass *= share
        inertia *= share
        if (j in feet or mass < options.locked_below_kg  # the feet are the support
                or options.held is HeldJoints.RIGID):
            gains[j] = ServoGain(name, mass, 0.0, 0.0, inertia, 0.0, locked=True)
            continue
        r = first * share / mass - anchor
        lever = max(float(np.linalg.norm(r - (r @ axis) * axis)), options.min_lever_m)
        stiffness = options.stiffness_factor * mass * g * lever
        damping = 2.0 * options.damping_ratio * math.sqrt(stiffness * inertia)
        gains[j] = ServoGain(name, mass, lever, stiffness, inertia, damping)
    return gains


@dataclass(frozen=True)
class WholeBodyModel:
    """The compiled MuJoCo model of a whole body on its platform and where its parts are.

    Attributes:
        spec: the whole body. segments: the lumped segment count (1-3). xml: the MJCF.
        model: ``mujoco.MjModel``. platform_qpos, platform_dof: the platform's hinge.
        dec_dofs: (N, 2) qvel addresses of each lumped joint's left and right pitch joint;
        dec_qpos: (N, 2) their qpos addresses; dec_sign: (N, 2) ±1, the sign that turns
        the hinge's angle and torque into the lumped joint's (the hinge's child is the
        foot's side, its axis ±y).
        gains: the held joints' servos (:class:`ServoGain`), by joint name.
        total_mass: kg of the robot (the feet included).
        axis, up, fwd: (3,) world axes.
        held_dofs: qvel addresses of the held joints (their PD is MuJoCo's joint stiffness
        and damping; their static torques, :func:`static_torques`, are applied as constant
        forces).
        step_choice: :class:`~posture_id.robots.stability.StepChoice` when the step was
            chosen (``MujocoOptions.timestep_s`` None), else None.
    """

    spec: WholeBodySpec
    segments: int
    xml: str = field(repr=False)
    model: object = field(repr=False)
    platform_qpos: int
    platform_dof: int
    dec_qpos: np.ndarray
    dec_dofs: np.ndarray
    dec_sign: np.ndarray
    gains: dict = field(repr=False)
    total_mass: float
    axis: np.ndarray = field(repr=False)
    up: np.ndarray = field(repr=False)
    fwd: np.ndarray = field(repr=False)
    held_dofs: np.ndarray = field(repr=False)
    ankle_point: np.ndarray = field(repr=False)
    step_choice: object = None

    @classmethod
    def build(cls, spec: WholeBodySpec, segments: int = 3, kpas=None, bpas=None,
              mujoco_options=None, options: WholeBodyOptions | None = None
              ) -> WholeBodyModel:
        """Write the MJCF of ``spec`` standing on the platform (see the module), compile it
        and compute the held joints' servos and static torques.

        Args:
            spec: the whole body. segments: 1, 2 or 3 lumped segments.
            kpas, bpas: (N,) the DEC modules' passive stiffness N·m/rad and damping
                N·m·s/rad (half of each on either side's pitch joint); default 0.
            mujoco_options: :class:`~posture_id.robots.mujoco_model.MujocoOptions`.
            options: :class:`WholeBodyOptions`.
        """
        import pinocchio as pin

        from posture_id.robots.mujoco_model import MujocoOptions, compile_mjcf, inertial, mjcf_head

        mujoco = require_mujoco()
        if segments not in ROLES:
            raise RobotError(f"segments must be 1, 2 or 3, got {segments}")
        mujoco_options = mujoco_options or MujocoOptions()
        options = options or WholeBodyOptions()
        n = segments
        kpas = np.zeros(n) if kpas is None else np.asarray(kpas, dtype=float)
        bpas = np.zeros(n) if bpas is None else np.asarray(bpas, dtype=float)
        model, q = reference_configuration(spec)
        data = model.createData()
        pin.forwardKinematics(model, data, q)
        pairs = spec.pitch_joints(segments)
        ids = [tuple(model.getJointId(name) for name in pair) for pair in pairs]
        dec = {j for pair in ids for j in pair}
        ankles = ids[0]
        gains = servo_gains(model, data, q, dec, ankles, options)
        axes = _joint_axes(model, data, q)
        lateral = np.array([0.0, 1.0, 0.0])
        gravity = np.asarray(model.gravity.linear, dtype=float)
        up = -gravity / np.linalg.norm(gravity)
        fwd = np.cross(lateral, up)
        ankle_point = (np.asarray(data.oMi[ankles[0]].translation)
                       + np.asarray(data.oMi[ankles[1]].translation)) / 2.0
        feet = set(model.subtrees[ankles[0]]) | set(model.subtrees[ankles[1]])
        children: dict[int, list[int]] = {j: [] for j in range(model.njoints)}
        for j in range(1, model.njoints):
            children[int(model.parents[j])].append(j)
        soles = [j for j in feet if not children[j]]
        passive = {}
        for k, pair in enumerate(ids):
            for j in pair:
                passive[j] = (kpas[k] / 2.0, bpas[k] / 2.0)

        size = 0.3
        step = mujoco_options.step_s
        weld_tc = max(options.weld_timeconst_s, 2.0 * step)
        lines = [
            *mjcf_head(f"{spec.name} whole body on a tilting platform", mujoco_options,
                       gravity, ankle_point, lateral,
                       f' jacobian="dense" tolerance="{mujoco_options.solver_tolerance:.17g}"'
                       f' iterations="{mujoco_options.solver_iterations}"'),
            f'      <geom type="box" size="{size} {size} 0.005" pos="0 0 -0.08" '
            'contype="0" conaffinity="0" rgba="0.6 0.6 0.6 1"/>',
            '    </body>',
        ]
        floor = mujoco_options.inertia_floor

        def emit(j: int, indent: str) -> None:
            name = model.names[j]
            parent = int(model.parents[j])
            rot = np.asarray(data.oMi[j].rotation)
            pos = np.asarray(data.oMi[j].translation)
            if parent == 0:
                rel_pos, rel_rot = pos, rot
            else:
                prot = np.asarray(data.oMi[parent].rotation)
                rel_pos = prot.T @ (pos - np.asarray(data.oMi[parent].translation))
                rel_rot = prot.T @ rot
            inertia = model.inertias[j]
            mass = float(inertia.mass)
            tensor = np.asarray(inertia.inertia, dtype=float)
            if mass < options.mass_floor_kg:
                mass = options.mass_floor_kg
                tensor = np.eye(3) * 1e-3 * mass
            tensor = tensor + floor * np.eye(3)
            lines.append(f'{indent}<body name="{name}" pos="{_vec(rel_pos)}" '
                         f'quat="{_vec(_quat(rel_rot))}">')
            if parent == 0:
                lines.append(f'{indent}  <freejoint name="{name}"/>')
            else:
                gain = gains.get(j)
                if j in dec:
                    stiff, damp = passive[j]
                elif gain is not None and not gain.locked:
                    stiff, damp = gain.stiffness, gain.damping
                else:
                    stiff = damp = None
                if stiff is not None:
                    local_axis = rot.T @ axes[j]
                    lines.append(f'{indent}  <joint name="{name}" type="hinge" '
                                 f'axis="{_vec(local_axis)}" stiffness="{stiff:.17g}" '
                                 f'damping="{damp:.17g}"/>')
            lines.append(f'{indent}  {inertial(inertia.lever, mass, tensor)}')
            lines.append(f'{indent}  <site name="{name}_anchor"/>')
            lines.append(f'{indent}  <site name="{name}_frame" quat="{_vec(_quat(rot.T))}"/>')
            for child in children[j]:
                emit(child, indent + "  ")
            lines.append(f"{indent}</body>")

        for root in children[0]:
            emit(root, "    ")
        lines.append("  </worldbody>")
        lines.append("  <equality>")
        for j in sorted(soles):
            lines.append(f'    <weld body1="{PLATFORM}" body2="{model.names[j]}" '
                         f'solref="{weld_tc:.17g} 1" solimp="0.99 0.999 0.001"/>')
        lines.append("  </equality>")
        root_name = model.names[children[0][0]]
        sensors = [f'    <subtreecom name="total_com" body="{root_name}"/>',
                   f'    <subtreelinvel name="total_vel" body="{root_name}"/>']
        for pair in ids:
            for j in pair:
                name = model.names[j]
                above = model.names[int(model.parents[j])]
                sensors += [
                    f'    <subtreecom name="{name}_below_com" body="{name}"/>',
                    f'    <subtreelinvel name="{name}_below_vel" body="{name}"/>',
                    f'    <framepos name="{name}_anchor" objtype="site" '
                    f'objname="{name}_anchor"/>',
                    f'    <framelinvel name="{name}_anchorvel" objtype="site" '
                    f'objname="{name}_anchor"/>',
                    f'    <frameangvel name="{name}_angvel" objtype="site" '
                    f'objname="{above}_frame"/>',
                ]
        lines += ["  <sensor>", *sensors, "  </sensor>", "</mujoco>"]
        xml = "\n".join(lines) + "\n"
        mj = compile_mjcf(xml, f"{spec.urdf}: MuJoCo refuses the whole-body model")
        obj = mujoco.mjtObj
        jid = [[mujoco.mj_name2id(mj, obj.mjOBJ_JOINT, model.names[j]) for j in pair]
               for pair in ids]
        sign = np.array([[-float(axes[j] @ lateral) for j in pair] for pair in ids])
        if np.any(np.abs(np.abs(sign) - 1.0) > 1e-6):
            raise RobotError(f"{spec.urdf}: a lumped joint's pitch axis is not the lateral "
                             "axis y in the reference posture")
        held = [(mujoco.mj_name2id(mj, obj.mjOBJ_JOINT, g.joint), g)
                for g in gains.values() if not g.locked]
        held = _stabilise(mujoco, mj, held, step, options.max_step_rate)
        by_name = {g.joint: g for _, g in held}
        gains = {j: by_name.get(g.joint, g) for j, g in gains.items()}
        platform = mujoco.mj_name2id(mj, obj.mjOBJ_JOINT, PLATFORM)
        built = cls(
            spec=spec, segments=segments, xml=xml, model=mj,
            platform_qpos=int(mj.jnt_qposadr[platform]),
            platform_dof=int(mj.jnt_dofadr[platform]),
            dec_qpos=np.array([[mj.jnt_qposadr[i] for i in pair] for pair in jid], dtype=int),
            dec_dofs=np.array([[mj.jnt_dofadr[i] for i in pair] for pair in jid], dtype=int),
            dec_sign=np.sign(sign),
            gains={g.joint: g for g in gains.values()},
            total_mass=float(sum(model.inertias[j].mass for j in range(1, model.njoints))),
            axis=lateral, up=up, fwd=fwd,
            held_dofs=np.array([mj.jnt_dofadr[i] for i, _ in held], dtype=int),
            ankle_point=ankle_point,
        )
        return built


def _stabilise(mujoco, mj, held: list, dt: float, rate: float) -> list:
    """Add to each held joint the armature (kg·m²) that brings B·dt/I and √(K/I)·dt to at
    most ``rate`` (I: the joint's diagonal of the mass matrix at the reference posture);
    returns ``held`` with each :class:`ServoGain`'s ``armature`` set."""
    data = mujoco.MjData(mj)
    mujoco.mj_forward(mj, data)
    full = np.zeros((mj.nv, mj.nv))
    mujoco.mj_fullM(mj, data, full)
    out = []
    for i, gain in held:
        dof = int(mj.jnt_dofadr[i])
        need = max(gain.damping * dt / rate, gain.stiffness * (dt / rate) ** 2)
        extra = max(0.0, need - float(full[dof, dof]))
        mj.dof_armature[dof] += extra
        out.append((i, replace(gain, armature=extra)))
    return out


class WholeBodySensors:
    """DEC's sensors read from the whole body, as the lumped model defines them.

    For lumped joint k (its left and right pitch joints):

    - the segment angle in space θ_k and rate: the turn about the lateral axis of the link
      just above the joint (the pitch joint's parent: the shank above the ankle, the thigh
      above the knee, the hip's roll link above the hip), left and right averaged;
    - the joint angle q_k and rate: the pitch hinges' (sign-corrected), averaged;
    - the COM above the joint: the whole robot's COM less the subtrees below the two pitch
      joints (their feet's side), by MuJoCo's subtree COMs, velocities and masses; the
      anchor: the midpoint of the two joints' anchors; α_k the angle of the line from the
      anchor to that COM from the vertical, α̇_k its rate;
    - the platform's angle and rate: its hinge's.

    Call after ``mj_forward``. Returns the tuple :class:`~posture_id.robots.mujoco_sim
    .ChainSensors` returns (θ, θ̇, α, α̇ lists of N floats, platform angle, rate) and the
    (N,) lists q, q̇.
    """

    def __init__(self, body: WholeBodyModel, data) -> None:
        mujoco = require_mujoco()
        m = body.model
        self.data = data
        self.n = body.segments
        obj = mujoco.mjtObj

        def adr(name: str) -> int:
            return int(m.sensor_adr[mujoco.mj_name2id(m, obj.mjOBJ_SENSOR, name)])

        pairs = body.spec.pitch_joints(body.segments)
        self.total = (adr("total_com"), adr("total_vel"))
        self.mass = float(m.body_subtreemass[
            mujoco.mj_name2id(m, obj.mjOBJ_BODY, _root_name(m))])
        self.joints = []
        for pair in pairs:
            sides = []
            for name in pair:
                bid = mujoco.mj_name2id(m, obj.mjOBJ_BODY, name)
                parent = int(m.body_parentid[bid])
                frame = mujoco.mj_name2id(m, obj.mjOBJ_SITE,
                                          mujoco.mj_id2name(m, obj.mjOBJ_BODY, parent)
                                          + "_frame")
                sides.append((float(m.body_subtreemass[bid]), adr(f"{name}_below_com"),
                              adr(f"{name}_below_vel"), adr(f"{name}_anchor"),
                              adr(f"{name}_anchorvel"), adr(f"{name}_angvel"), frame))
            self.joints.append(sides)
        self.dec_qpos = body.dec_qpos.tolist()
        self.dec_dofs = body.dec_dofs.tolist()
        self.sign = body.dec_sign.tolist()
        self.pq, self.pd = body.platform_qpos, body.platform_dof
        self.up, self.fwd, self.axis = body.up, body.fwd, body.axis

    def _above(self, sides: list, total: int, below: int, at: int) -> tuple[np.ndarray, float]:
        """(3,) the COM above a lumped joint (its two ``sides``) less its anchor, m (or its
        rate, m/s, from the velocity sensors), and the mass above it, kg: ``total`` is the
        whole robot's sensor, ``below`` and ``at`` index each side's tuple at the sensors of
        the subtree below the joint and of the joint's anchor."""
        sd = self.data.sensordata
        first, mass, point = sd[total:total + 3] * self.mass, self.mass, np.zeros(3)
        for side in sides:
            first = first - side[0] * sd[side[below]:side[below] + 3]
            mass -= side[0]
            point += 0.5 * sd[side[at]:side[at] + 3]
        return first / mass - point, mass

    def __call__(self):
        d = self.data
        sd = d.sensordata
        xmat = d.site_xmat
        up, fwd, axis = self.up, self.fwd, self.axis
        a_c, a_v = self.total
        qpos, qvel = d.qpos, d.qvel
        theta, omega, alpha, alpha_rate, q, qd = [], [], [], [], [], []
        for k, sides in enumerate(self.joints):
            lever, _ = self._above(sides, a_c, 1, 3)
            rate, _ = self._above(sides, a_v, 2, 4)
            th = om = 0.0
            for *_, w, frame in sides:
                r_up = xmat[frame].reshape(3, 3) @ up
                th += 0.5 * math.atan2(float(fwd @ r_up), float(up @ r_up))
                om += 0.5 * float(sd[w:w + 3] @ axis)
            x, y = float(lever @ up), float(lever @ fwd)
            xd, yd = float(rate @ up), float(rate @ fwd)
            alpha.append(math.atan2(y, x))
            alpha_rate.append((x * yd - y * xd) / (x * x + y * y))
            theta.append(th)
            omega.append(om)
            (ql, qr), (dl, dr), (sl, sr) = self.dec_qpos[k], self.dec_dofs[k], self.sign[k]
            q.append(0.5 * (sl * qpos[ql] + sr * qpos[qr]))
            qd.append(0.5 * (sl * qvel[dl] + sr * qvel[dr]))
        return (theta, omega, alpha, alpha_rate, float(qpos[self.pq]), float(qvel[self.pd]),
                q, qd)

    def gravity_torques(self, gravity: np.ndarray) -> list[float]:
        """(N,) N·m: gravity's torque about the lateral axis on the mass above each lumped
        joint, about its anchor (call after ``mj_forward``)."""
        out = []
        for sides in self.joints:
            lever, mass = self._above(sides, self.total[0], 1, 3)
            out.append(float(self.axis @ np.cross(lever, mass * gravity)))
        return out


def _root_name(m) -> str:
    mujoco = require_mujoco()
    for b in range(1, m.nbody):
        if m.body_parentid[b] == 0 and m.body_jntnum[b] and \
                m.jnt_type[m.body_jntadr[b]] == mujoco.mjtJoint.mjJNT_FREE:
            return mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b)
    raise RobotError("the whole-body model has no free-floating root")


def static_torques(body: WholeBodyModel, data, dec_totals: list[float]) -> np.ndarray:
    """(H,) N·m: the held joints' torques that keep the whole body in its reference
    posture at rest, given DEC's total torque of each lumped joint (``dec_totals``, shared
    equally by the two sides): the feet's weld forces λ satisfy the base's and the DEC
    joints' equilibrium, and of those λ the one that needs the least held torque (2-norm)
    is taken. Call after ``mj_forward`` at the reference posture (qpos0, at rest)."""
    mujoco = require_mujoco()
    m = body.model
    rows = np.flatnonzero(np.asarray(data.efc_type) == mujoco.mjtConstraint.mjCNSTR_EQUALITY)
    jac = np.asarray(data.efc_J).reshape(data.nefc, m.nv)[rows]  # (E, nv)
    bias = np.array(data.qfrc_bias)
    root = [int(m.jnt_dofadr[j]) + i for j in range(m.njnt)
            if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE for i in range(6)]
    dec_rows, dec_tau = [], []
    for k, total in enumerate(dec_totals):
        for side in (0, 1):
            dec_rows.append(int(body.dec_dofs[k, side]))
            dec_tau.append(body.dec_sign[k, side] * total / 2.0)
    a = np.vstack([jac[:, root].T, jac[:, dec_rows].T])  # (6 + 2N, E)
    b = np.concatenate([bias[root], bias[dec_rows] - np.array(dec_tau)])
    lam0, *_ = np.linalg.lstsq(a, b, rcond=None)
    _, s, vt = np.linalg.svd(a)
    rank = int(np.sum(s > 1e-9 * s[0]))
    null = vt[rank:].T
    held = body.held_dofs
    jh = jac[:, held].T  # (H, E)
    residual = bias[held] - jh @ lam0
    if null.shape[1]:
        z, *_ = np.linalg.lstsq(jh @ null, residual, rcond=None)
        lam = lam0 + null @ z
    else:
        lam = lam0
    return bias[held] - jh @ lam


def simulate_whole_body(
    spec: WholeBodySpec,
    segments: int = 3,
    params=None,
    stimulus=None,
    options=None,
    mujoco_options=None,
    whole_body_options: WholeBodyOptions | None = None,
    lumped=None,
):
    """One trial of DEC balancing the whole body on its platform, stepped by MuJoCo.

    The controller is :func:`~posture_id.robots.mujoco_sim.simulate_mujoco`'s (docs/model.md
    §2: the same delay line, dead-band tilt estimator, gravity term and passive stiffness
    and damping), its sensors :class:`WholeBodySensors`, its torque per lumped joint
    shared equally by the two pitch joints; the held joints are servoed to the reference
    posture (:func:`servo_gains`, :func:`static_torques`).

    Args:
        spec: the whole body. segments: 1-3, as it is lumped.
        params: the lumped body's DEC parameters (joints ``ankle``/``knee``/``hip`` as
            lumped; default: the lumped body's defaults).
        stimulus: the platform tilt (default: the 121 s PRTS, 1° p-p).
        options: :class:`~posture_id.simulation.options.SimulationOptions` (sampling,
            sway limit, dead-band; MuJoCo's step replaces its ``dt``).
        mujoco_options: :class:`~posture_id.robots.mujoco_model.MujocoOptions`.
        whole_body_options: :class:`WholeBodyOptions`.
        lumped: the lumped :class:`~posture_id.bodies.body.Body` (default: lumped here
            from ``spec``, for the default parameters and the segments' names).
    Returns:
        (:class:`~posture_id.simulation.results.SimulationResult` of the lumped segments'
        angles θ (S, N) rad and COM-above angles α (S, N) rad of the whole body, at the
        sampling rate; the fall's time or None, :class:`WholeBodyModel`).
    """
    from posture_id.robots.mujoco_model import MujocoOptions
    from posture_id.robots.mujoco_sim import checked_parameters, run_dec_loop, stepped_options
    from posture_id.robots.stability import choose_step
    from posture_id.simulation.options import SimulationOptions
    from posture_id.simulation.stimulus import prts

    mujoco = require_mujoco()
    mujoco_options = mujoco_options or MujocoOptions()
    base = options or SimulationOptions()
    stimulus = stimulus or prts()
    if lumped is None:
        lumped = lumped_body(spec, segments)
    params = checked_parameters(params, lumped, "the lumped")
    kpas, bpas = params.array("kpas"), params.array("bpas")
    if mujoco_options.timestep_s is None:
        built = []  # the last one built is the step chosen (choose_step stops there)

        def build(step: float):
            built.append(WholeBodyModel.build(spec, segments, kpas, bpas, replace(
                mujoco_options, timestep_s=step), whole_body_options))
            return built[-1].model

        step_choice = choose_step(build)
        mujoco_options = replace(mujoco_options, timestep_s=step_choice.step_s)
        body = replace(built[-1], step_choice=step_choice)
    else:
        body = WholeBodyModel.build(spec, segments, kpas, bpas, mujoco_options,
                                    whole_body_options)
    options = stepped_options(base, mujoco_options)
    m = body.model
    d = mujoco.MjData(m)
    sense = WholeBodySensors(body, d)
    mujoco.mj_forward(m, d)
    gravity = np.asarray(m.opt.gravity, dtype=float)
    grav = sense.gravity_torques(gravity)  # gravity's torque on the mass above each joint
    feedforward = static_torques(body, d, [-g for g in grav])
    d.qfrc_applied[body.held_dofs] = feedforward
    # each held joint's servo reports the static torque it is given (held_dofs follow the
    # unlocked servos in their order)
    gains = dict(body.gains)
    held = [name for name, g in gains.items() if not g.locked]
    for name, torque in zip(held, feedforward, strict=True):
        gains[name] = replace(gains[name], feedforward=float(torque))
    body = replace(body, gains=gains)
    dofs = body.dec_dofs.tolist()
    signs = (0.5 * body.dec_sign).tolist()
    pq, pd = body.platform_qpos, body.platform_dof

    qpos, qvel, applied = d.qpos, d.qvel, d.qfrc_applied

    def prescribe(angle: float, rate: float) -> None:
        qpos[pq] = angle
        qvel[pd] = rate

    def apply(torques: list) -> None:
        for i in range(segments):  # shared by the left and right joint of the lumped one
            left, right = dofs[i]
            sl, sr = signs[i]
            applied[left] = sl * torques[i]
            applied[right] = sr * torques[i]

    return run_dec_loop(mujoco, m, d, stimulus, options, lumped, params, grav, prescribe,
                        sense, apply, f"{spec.name} whole body in MuJoCo {mujoco.__version__} "
                        f"{mujoco_options.integrator} {options.dt * 1000:g} ms"), body


def lumped_body(spec: WholeBodySpec, segments: int = 3):
    """The :class:`~posture_id.bodies.body.Body` ``spec`` lumps into (``segments``
    segments), through a temporary URDF (:func:`~posture_id.bodies.lumping.lump_robot`)."""
    import tempfile

    from posture_id.bodies.body import load_body
    from posture_id.bodies.lumping import lump_robot

    lumped = lump_robot(spec.urdf, ankle=spec.ankle, knee=spec.knee if segments == 3 else None,
                        hip=spec.hip, srdf=spec.srdf, base_rpy=spec.base_rpy,
                        segments=segments, name=spec.name)
    with tempfile.TemporaryDirectory() as folder:
        return load_body(lumped.write(Path(folder) / f"{lumped.name}.urdf"))
