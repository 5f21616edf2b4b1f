"""DEC in MuJoCo's loop: the same controller as the compiled simulator, another engine.

The controller of docs/model.md §2 is written again here, from the document, in plain
Python (it does not call :func:`~posture_id.simulation.kernel_source.dec_torques`), and its
sensors read MuJoCo's state, not posture_id's planar equations:

- the segment angles in space θ_i and rates θ̇_i: each segment body's orientation
  (``xmat``) and angular velocity (``cvel``);
- the joint angles and rates q_i, q̇_i (proprioception): the hinges' ``qpos``, ``qvel``;
- the COM-above angle α_i,S and its rate: the line from the hinge's anchor (``xanchor``)
  to the COM of the subtree above it (``subtree_com``), its rate from the subtree COM's
  velocity (``subtree_linvel``) less the anchor's;
- the platform's tilt α_FS: the platform body's orientation; the tilt-rate estimate
  integrates the dead-band of θ̇_1 − q̇_1 (vestibular shank rate less the ankle's);
- the reference posture of a bent body: α_i,S and the holding torques (``qfrc_bias``) of
  MuJoCo's model at the zero configuration.

Each MuJoCo step (``MujocoOptions.timestep_s``, 1 ms by default) evaluates the controller
once, from the state at the step's start, and holds its torques over the step (over every
stage of RK4); the servo command goes through a delay line of past commands read Δ/dt
steps back, interpolated linearly (never rounded), the command that holds the reference
posture before t = Δ. Passive stiffness and damping are MuJoCo's joint stiffness and
damping, evaluated by its integrator. The plant is MuJoCo's: its kinematic tree, mass
matrix, bias forces and integrator.
"""

from __future__ import annotations

import math

import numpy as np

from posture_id.bodies.body import Body
from posture_id.dec.parameters import DecParameters, default_parameters
from posture_id.errors import SimulationError
from posture_id.robots.errors import RobotError, require_mujoco
from posture_id.robots.mujoco_model import ChainModel, MujocoOptions
from posture_id.simulation.options import SimulationOptions
from posture_id.simulation.results import SimulationResult
from posture_id.simulation.stimulus import TiltProfile, prts

__all__ = ["simulate_mujoco", "DelayLine", "DecController", "ChainSensors", "deadband",
           "run_dec_loop", "stepped_options", "checked_parameters"]


def deadband(rate: float, width: float) -> float:
    """f_θ(v) of docs/model.md §2: 0 inside ±width, the excess beyond it (rad/s)."""
    if rate > width:
        return rate - width
    if rate < -width:
        return rate + width
    return 0.0


class DelayLine:
    """Past servo commands of N modules, read Δ_i/dt steps back (linear interpolation).

    Args:
        delay_steps: (N,) Δ_i/dt, steps (any real ≥ 0; snapped to a whole step within
            1e-9 of one).
        hold: (N,) the command read before the first one Δ_i old exists (N·m).
    """

    def __init__(self, delay_steps, hold) -> None:
        steps = np.asarray(delay_steps, dtype=float)
        nearest = np.round(steps)
        delay = np.where(np.abs(steps - nearest) < 1e-9, nearest, steps)
        if not (np.all(np.isfinite(delay)) and np.all(delay >= 0)):
            raise RobotError(f"delays must be finite and ≥ 0 steps, got {steps.tolist()}")
        self.delay = delay.tolist()
        self.hold = [float(h) for h in hold]
        self.history: list[list[float]] = [[] for _ in self.delay]

    def push_and_read(self, command: list) -> list:
        """Store the N commands of the next step k (0, 1, ...) and return the commands of
        step k − Δ_i/dt, interpolated between its two neighbouring steps; ``hold`` while
        k < Δ_i/dt."""
        out = []
        for i, delay in enumerate(self.delay):
            history = self.history[i]
            history.append(command[i])
            back = len(history) - 1 - delay
            if back < 0:
                out.append(self.hold[i])
                continue
            first = math.floor(back)
            frac = back - first
            value = history[first]
            if frac > 0.0:
                value += frac * (history[first + 1] - value)
            out.append(value)
        return out


class DecController:
    """DEC's modules as docs/model.md §2 writes them, stepped in a MuJoCo loop: the
    support-tilt estimate (the shank's rate in space less the ankle's, through the
    dead-band, integrated), each module's servo on its controlled variable (the COM above
    it in space, or its joint), the integral of its error, the lumped delay
    (:class:`DelayLine`), and the undelayed gravity term.

    Args:
        params: the N modules' DEC parameters. alpha_ref: (N,) rad, the COM-above angles
        of the reference posture. hold: (N,) N·m, each servo's command at rest.
        dt: s, the step. deadband_rad_s: the tilt estimator's dead-band.
    """

    def __init__(self, params: DecParameters, alpha_ref, hold, dt: float,
                 deadband_rad_s: float) -> None:
        self.kp, self.ki, self.kd = (params.array(n).tolist() for n in ("kp", "ki", "kd"))
        self.mix = (0.5 + 0.5 * params.array("sign")).tolist()  # C = ±1: COM, joint
        self.alpha_ref = [float(a) for a in alpha_ref]
        self.dt, self.width = dt, deadband_rad_s
        self.delays = DelayLine(params.array("delay_s") / dt, hold)
        self.estimate = 0.0  # α̂_FS, rad
        self.integral = [0.0] * len(self.kp)  # ∫ε dt, rad·s

    def torques(self, q, qd, theta, omega, alpha, alpha_rate, platform_angle: float,
                platform_rate: float) -> list[float]:
        """(N,) N·m, each module's joint torque this step from the sensors: joint angles
        q and rates qd, segment angles θ and rates ω in space, COM-above angles α and
        rates (rad, rad/s), the platform's tilt and rate; the state advances one step."""
        kp, ki, kd, mix, integral, dt = (self.kp, self.ki, self.kd, self.mix, self.integral,
                                         self.dt)
        est_rate = deadband(omega[0] - qd[0], self.width)
        beta, beta_rate = self.estimate, est_rate  # β̂_0 = α̂_FS
        below, below_rate = platform_angle, platform_rate  # θ_0 = α_FS
        command = []
        for i in range(len(kp)):
            com = mix[i]
            x = com * (alpha[i] - self.alpha_ref[i] - below + beta) + (1.0 - com) * q[i]
            xd = com * (alpha_rate[i] - below_rate + beta_rate) + (1.0 - com) * qd[i]
            command.append(kp[i] * x + kd[i] * xd + ki[i] * integral[i]
                           + self.delays.hold[i])
            integral[i] += dt * x
            beta += q[i]
            beta_rate += qd[i]
            below, below_rate = theta[i], omega[i]
        self.estimate += dt * est_rate
        delayed = self.delays.push_and_read(command)
        # τ = −servo(t − Δ) − PD on the gravity term sin α_S (undelayed)
        return [-delayed[i] - kp[i] * math.sin(alpha[i])
                - kd[i] * math.cos(alpha[i]) * alpha_rate[i] for i in range(len(kp))]


class ChainSensors:
    """What DEC's sensors deliver, read from MuJoCo's state of a :class:`ChainModel`.

    Call it after ``mj_forward`` (or ``mj_step``'s forward pass) has updated ``data``.
    Returns θ (N,) rad, θ̇ (N,) rad/s (the segments' sites' turn and the segments'
    angular velocity about the axis), α_S (N,) rad and α̇_S (N,) rad/s (the line from each
    joint's anchor to the COM of the subtree above it, from the ``subtreecom``,
    ``subtreelinvel`` and anchor sensors), and the platform's angle α_FS rad and rate
    rad/s in space; lists of floats (the loop runs in plain Python, once per step).
    """

    def __init__(self, chain: ChainModel, data) -> None:
        self.data = data
        self.n = chain.body.n_segments
        self.sites = [chain.platform_site, *map(int, chain.segment_sites)]
        self.adr = chain.sensor_adr.tolist()
        self.platform_rate_adr = chain.platform_sensor
        self.axis, self.up, self.fwd = chain.axis.tolist(), chain.up.tolist(), chain.fwd.tolist()
        up, fwd = self.up, self.fwd
        # a frame's turn in space from its rotation matrix R (row-major, world from frame):
        # the angle of R·up from up towards forward, atan2(fwdᵀ·R·up, upᵀ·R·up)
        self.to_fwd, self.to_up = ([(3 * k + col, v[k] * up[col]) for k in range(3)
                                    for col in range(3) if v[k] * up[col] != 0.0]
                                   for v in (fwd, up))

    def _turn(self, rot: list) -> float:
        return math.atan2(sum(rot[k] * c for k, c in self.to_fwd),
                          sum(rot[k] * c for k, c in self.to_up))

    def __call__(self) -> tuple[list, list, list, list, float, float]:
        sd = self.data.sensordata.tolist()
        frames = self.data.site_xmat[self.sites].tolist()
        axis, up, fwd = self.axis, self.up, self.fwd
        theta, omega, alpha, alpha_rate = [], [], [], []
        for i in range(self.n):
            a_angvel, a_anchorvel, a_anchor, a_com, a_comvel = self.adr[i]
            theta.append(self._turn(frames[i + 1]))
            omega.append(_dot(sd[a_angvel:a_angvel + 3], axis))
            lever = [sd[a_com + k] - sd[a_anchor + k] for k in range(3)]
            rate = [sd[a_comvel + k] - sd[a_anchorvel + k] for k in range(3)]
            x, y = _dot(lever, up), _dot(lever, fwd)
            xd, yd = _dot(rate, up), _dot(rate, fwd)
            alpha.append(math.atan2(y, x))
            alpha_rate.append((x * yd - y * xd) / (x * x + y * y))
        a = self.platform_rate_adr
        return theta, omega, alpha, alpha_rate, self._turn(frames[0]), _dot(sd[a:a + 3], axis)


def _dot(v: list, w: list) -> float:
    return v[0] * w[0] + v[1] * w[1] + v[2] * w[2]


def stepped_options(base: SimulationOptions, mujoco_options: MujocoOptions
                    ) -> SimulationOptions:
    """``base`` (sampling rate, sway limit, dead-band) at MuJoCo's step.

    Raises:
        RobotError: a sample period that is not a multiple of the step."""
    dt = mujoco_options.step_s
    try:
        return SimulationOptions(dt=dt, sample_rate_hz=base.sample_rate_hz,
                                 sway_limit_deg=base.sway_limit_deg,
                                 deadband_rad_s=base.deadband_rad_s)
    except SimulationError as exc:  # the sample period is not a multiple of the step
        raise RobotError(f"MuJoCo timestep_s {dt:g} s: {exc}") from None


def checked_parameters(params: DecParameters | None, body: Body, what: str
                       ) -> DecParameters:
    """``params`` (default: ``body``'s defaults), refused unless they are for its joints
    (``what`` names the body in the refusal: "body", "the lumped")."""
    params = params or default_parameters(body)
    if params.joints != body.joint_names:
        raise RobotError(f"parameters are for joints {', '.join(params.joints)}; {what} "
                         f"'{body.name}' has {', '.join(body.joint_names)}")
    return params


def run_dec_loop(mujoco, m, d, stimulus: TiltProfile, options: SimulationOptions,
                 body: Body, params: DecParameters, holding: list, prescribe, sensors,
                 apply, description: str) -> SimulationResult:
    """Step MuJoCo's model ``m``/``d`` through ``stimulus`` on the step grid under a
    :class:`DecController` of ``params``: each step ``prescribe(angle, rate)`` sets the
    platform (rad, rad/s), ``sensors()`` gives (θ, ω, α, α̇, platform angle and rate, q,
    q̇) of the N modules, ``apply(torques)`` puts the N torques (N·m) on the joints.

    The reference posture (docs/model.md §2) is MuJoCo's state when this is called (call
    after ``mj_forward`` at rest): its COM-above angles, and ``holding`` (N,) N·m, the
    torques that hold it against gravity.

    Returns:
        The :class:`SimulationResult` for ``body`` (the chain, or the lumped body of a
        whole one): θ (S, N) rad, α (S, N) rad at the samples, NaN from a fall on, and
        the fall's time, s, or None; its description the stimulus's, then
        ``description``.
    """
    n_steps, every, dt = options.n_steps(stimulus), options.sample_every, options.dt
    tilt, tilt_vel = stimulus.on_grid(dt, n_steps)
    kp = params.array("kp").tolist()
    alpha_ref = sensors()[2]
    hold = [holding[i] - kp[i] * math.sin(alpha_ref[i]) for i in range(body.n_segments)]
    controller = DecController(params, alpha_ref, hold, dt, options.deadband_rad_s)
    limit = math.radians(options.sway_limit_deg)
    n_samples = n_steps // every + 1
    theta_out = np.full((n_samples, body.n_segments), np.nan)
    alpha_out = np.full((n_samples, body.n_segments), np.nan)
    abort_time = None
    tilt_list, tilt_vel_list = tilt.tolist(), tilt_vel.tolist()
    for step in range(n_steps + 1):
        prescribe(tilt_list[step], tilt_vel_list[step])
        mujoco.mj_forward(m, d)
        theta, omega, alpha, alpha_rate, platform_angle, platform_rate, q, qd = sensors()
        if not all(abs(th) <= limit for th in theta):  # NaN too: a diverged body fell
            abort_time = step * dt
            break
        if step % every == 0:
            theta_out[step // every] = theta
            alpha_out[step // every] = alpha
        if step == n_steps:
            break
        apply(controller.torques(q, qd, theta, omega, alpha, alpha_rate, platform_angle,
                                 platform_rate))
        mujoco.mj_step(m, d)
    return SimulationResult.on_body(options, tilt, body, params,
                                    f"{stimulus.description}; {description}",
                                    theta=theta_out, alpha=alpha_out, abort_time=abort_time)


def simulate_mujoco(
    body: Body,
    params: DecParameters | None = None,
    stimulus: TiltProfile | None = None,
    options: SimulationOptions | None = None,
    mujoco_options: MujocoOptions | None = None,
) -> SimulationResult:
    """Simulate one trial of DEC balancing ``body`` on its platform, stepped by MuJoCo.

    Args:
        body: the chain (N segments).
        params: every module's DEC parameters, SI units (default: the body's defaults).
        stimulus: the platform tilt (default: PRTS, 242 states, 2 cycles, 1° p-p).
        options: sampling rate, sway limit and dead-band (its ``dt`` is not used: MuJoCo
            steps at ``mujoco_options.timestep_s``).
        mujoco_options: MuJoCo's step, integrator and model options
            (:class:`MujocoOptions`: 1 ms RK4 by default).
    Returns:
        :class:`~posture_id.simulation.results.SimulationResult`, as
        :func:`posture_id.simulation.simulate` gives: time (S,) s, tilt (S,) rad, segment
        angles θ (S, N) rad (NaN from a fall on) and COM-above angles α (S, N) rad, at the
        sampling rate (50 Hz: 6051 samples for 121 s); ``abort_time`` the time a segment
        left the sway limit, or None; its ``options.dt`` is MuJoCo's step.
    Raises:
        MissingExtraError: MuJoCo is not installed.
        RobotError: parameters that are not the body's joints, a sample period that is not
            a multiple of MuJoCo's step.
    """
    mujoco = require_mujoco()
    mujoco_options = mujoco_options or MujocoOptions()
    base = options or SimulationOptions()
    stimulus = stimulus or prts()
    params = checked_parameters(params, body, "body")
    options = stepped_options(base, mujoco_options)
    n = body.n_segments
    chain = ChainModel.build(body, mujoco_options, params.array("kpas"), params.array("bpas"))
    m = chain.model
    d = mujoco.MjData(m)

    jq = [int(a) for a in chain.joint_qpos]
    jd = [int(a) for a in chain.joint_dofs]
    pq, pd = chain.platform_qpos, chain.platform_dof
    sense = ChainSensors(chain, d)

    # the reference posture (docs/model.md §2): MuJoCo's COM-above angles and holding
    # torques (its bias forces at rest) at the zero configuration
    mujoco.mj_forward(m, d)
    holding = [-float(d.qfrc_bias[jd[i]]) for i in range(n)]
    qpos, qvel, applied = d.qpos, d.qvel, d.qfrc_applied

    def prescribe(angle: float, rate: float) -> None:
        # the platform follows the stimulus exactly; the ankle coordinate takes the change
        # the other way, so the body's state in space is unchanged
        qpos[jq[0]] += qpos[pq] - angle
        qvel[jd[0]] += qvel[pd] - rate
        qpos[pq] = angle
        qvel[pd] = rate

    def sensors() -> tuple:
        # proprioception: the hinges' angles and rates
        return (*sense(), [float(qpos[a]) for a in jq], [float(qvel[a]) for a in jd])

    def apply(torques: list) -> None:
        for i in range(n):  # passive stiffness and damping: MuJoCo's own
            applied[jd[i]] = torques[i]

    return run_dec_loop(mujoco, m, d, stimulus, options, body, params, holding, prescribe,
                        sensors, apply, f"MuJoCo {mujoco.__version__} "
                        f"{mujoco_options.integrator} {options.dt * 1000:g} ms")
