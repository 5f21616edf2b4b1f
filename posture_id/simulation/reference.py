"""Slow reference simulation: the same DEC controller, the plant stepped by Pinocchio.

Everything the fast kernel derives from its own planar equations is taken from Pinocchio
here instead: segment angles from the joint configuration, COM-above angles and their
rates from subtree centres of mass and their Jacobians, accelerations from the
articulated-body algorithm (``pinocchio.aba``). The controller is the compiled
:func:`posture_id.simulation.kernel.Kernels.dec_torques` (lane 0), so a difference between the two
paths can only come from the plant. One Python iteration per 2 ms step: kept for
validation and for the speed comparison in ``benchmarks/simulation.py``.

Pinocchio's coordinates are the joint angles with the foot fixed to the world:
q_pin = (θ_1, q_2, …, q_N); the platform rotates about the ankle axis, which never
moves, so the tilt reaches the body only through q_1 = θ_1 − α_FS in the torques.
"""

from __future__ import annotations

import math

import numpy as np

from posture_id.bodies.body import Body
from posture_id.dec.parameters import DecParameters, default_parameters
from posture_id.simulation.batch import block_arrays, check_joints
from posture_id.simulation.kernel import LANES, kernels
from posture_id.simulation.noise import MotorNoise, motor_noise_torques, per_trial
from posture_id.simulation.options import SimulationOptions
from posture_id.simulation.results import SimulationResult
from posture_id.simulation.stimulus import TiltProfile, prts

__all__ = ["simulate_reference", "com_above_angles"]


def com_above_angles(body: Body, q: np.ndarray, v: np.ndarray, data=None):
    """COM-above angles α_i,S (N,) rad and rates (N,) rad/s from Pinocchio.

    Args:
        q, v: (N,) Pinocchio configuration (θ_1, q_2, …) rad and its velocity rad/s.
    """
    import pinocchio as pin

    model = body.model
    data = data or model.createData()
    axis = np.asarray(body.axis)
    up = -np.asarray(model.gravity.linear) / body.gravity
    fwd = np.cross(axis, up)
    pin.forwardKinematics(model, data, q, v)
    pin.computeJointJacobians(model, data, q)
    alpha = np.empty(body.n_segments)
    rate = np.empty(body.n_segments)
    for i in range(body.n_segments):
        jid = i + 1
        jac_com = pin.jacobianSubtreeCenterOfMass(model, data, q, jid)
        com = data.com[jid]  # world frame after jacobianSubtreeCenterOfMass
        origin = data.oMi[jid].translation
        jac_origin = pin.getJointJacobian(model, data, jid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        lever = com - origin
        lever_rate = (np.asarray(jac_com) - np.asarray(jac_origin)[:3]) @ v
        x, y = float(up @ lever), float(fwd @ lever)
        xd, yd = float(up @ lever_rate), float(fwd @ lever_rate)
        alpha[i] = math.atan2(y, x)
        rate[i] = (x * yd - y * xd) / (x * x + y * y)
    return alpha, rate


def simulate_reference(
    body: Body,
    params: DecParameters | None = None,
    stimulus: TiltProfile | None = None,
    options: SimulationOptions | None = None,
    motor_noise: MotorNoise | None = None,
) -> SimulationResult:
    """Simulate one trial with Pinocchio's forward dynamics (slow; for validation); the
    motor noise, when given, is the same torque sequence the fast simulator adds.

    Args:
        body: the chain (N segments), its Pinocchio model stepped.
        params: every module's DEC parameters, SI units (default: the body's defaults).
        stimulus: the platform tilt (default: PRTS, 242 states, 2 cycles, 1° p-p).
        options: step, sampling, sway limit, dead-band (default :class:`SimulationOptions`).
        motor_noise: low-pass torque noise at every joint (:class:`MotorNoise`), or None:
            none.
    Returns:
        :class:`SimulationResult`, as :func:`~posture_id.simulation.batch.simulate` gives.
    Raises:
        SimulationError: parameters whose modules are not the body's joints (in order).
    """
    import pinocchio as pin

    options = options or SimulationOptions()
    stimulus = stimulus or prts()
    params = params or default_parameters(body)
    check_joints(body, params)
    n = body.n_segments
    model = body.model
    data = model.createData()
    k = kernels(n)
    rows = k.rows
    n_steps = options.n_steps(stimulus)
    every = options.sample_every
    tilt, tilt_vel = stimulus.on_grid(options.dt, n_steps)
    par, buf = block_arrays(k, body, params.arrays(), options, 0, 1)
    w = np.zeros(rows.count * LANES)
    limit = math.radians(options.sway_limit_deg)
    motor = (None if motor_noise is None else motor_noise_torques(
        per_trial([motor_noise], 1), n_steps, options.dt, body.mgh, 1)[:, :, 0])

    q = np.zeros(n)
    v = np.zeros(n)
    n_samples = n_steps // every + 1
    theta_out = np.full((n_samples, n), np.nan)
    alpha_out = np.full((n_samples, n), np.nan)
    abort_time = None

    def lane0(row: int) -> slice:
        return slice(row * LANES, (row + n) * LANES, LANES)

    for step in range(n_steps + 1):
        theta = np.cumsum(q)
        omega = np.cumsum(v)
        if np.any(np.abs(theta) > limit):
            abort_time = step * options.dt
            break
        alpha, alpha_rate = com_above_angles(body, q, v, data)
        if step % every == 0:
            theta_out[step // every] = theta
            alpha_out[step // every] = alpha
        if step == n_steps:
            break
        w[lane0(rows.theta)] = theta
        w[lane0(rows.omega)] = omega
        w[lane0(rows.alpha)] = alpha
        w[lane0(rows.alpha_dot)] = alpha_rate
        w[lane0(rows.tg)] = np.sin(alpha)
        w[lane0(rows.tg_dot)] = np.cos(alpha) * alpha_rate
        k.dec_torques(step, w, par, buf, tilt[step], tilt_vel[step], options.dt,
                      options.deadband_rad_s)
        tau = w[lane0(rows.tau)].copy()
        if motor is not None:
            tau += motor[step]
        acc = pin.aba(model, data, q, v, tau)
        v = v + options.dt * np.asarray(acc)
        q = q + options.dt * v

    return SimulationResult.on_body(options, tilt, body, params, stimulus.description,
                                    theta=theta_out, alpha=alpha_out, abort_time=abort_time)
