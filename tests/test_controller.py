"""The compiled DEC controller against docs/model.md §2 written out again in plain numpy.

The reference simulation reuses the compiled controller, so a sign error shared by both
would pass every other test. Here the oracle knows nothing of the kernel: it computes the
COM-above angles from the segments' geometry (joint positions and COMs in the plane, the
rates by central differences along θ̇), keeps its own integrals, tilt estimate and
history of servo commands, and applies docs/model.md §2 line by line. Each step gets a fresh
random state (θ, θ̇, α_FS, α̇_FS); the controller's memory carries over, so the delay
buffer, the interpolation of fractional delays, the integral and the dead-band estimator
are all exercised.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from posture_id.dec import ParameterArrays, default_parameters
from posture_id.simulation import SimulationOptions
from posture_id.simulation.batch import block_arrays
from posture_id.simulation.kernel import LANES, kernels

DT = 0.002


def com_above_angles(body, theta: np.ndarray) -> np.ndarray:
    """(N,) α_i,S from the segments' geometry: angle from the vertical of the line from
    joint i to the COM of segments i..N, positive forward (docs/model.md §1)."""
    n = body.n_segments
    joint = np.zeros(2)  # (forward, up) of joint i
    joints, coms = [], []
    for i, seg in enumerate(body.segments):
        if i > 0:
            joint = joint + _rotate(seg.joint_origin, theta[i - 1])
        joints.append(joint)
        coms.append(joint + _rotate(seg.com, theta[i]))
    masses = np.array([s.mass for s in body.segments])
    out = np.empty(n)
    for i in range(n):
        com = (masses[i:, None] * np.array(coms[i:])).sum(0) / masses[i:].sum()
        lever = com - joints[i]
        out[i] = math.atan2(lever[0], lever[1])
    return out


def _rotate(v, angle: float) -> np.ndarray:
    """A segment-fixed (forward, up) vector of a segment leaning ``angle`` forward."""
    fwd, up = v
    return np.array([fwd * math.cos(angle) + up * math.sin(angle),
                     -fwd * math.sin(angle) + up * math.cos(angle)])


def deadband(v: float, threshold: float) -> float:
    if v < -threshold:
        return v + threshold
    if v > threshold:
        return v - threshold
    return 0.0


class Oracle:
    """docs/model.md §2 for one trial: memory (∫ε, α̂_FS, servo history) and one step."""

    def __init__(self, body, p: dict, deadband_rad_s: float) -> None:
        self.body = body
        self.p = p  # per-module arrays: kp, ki, kd, delay_s, sign, kpas, bpas
        self.theta_db = deadband_rad_s
        n = body.n_segments
        self.integral = np.zeros(n)
        self.estimate = 0.0
        self.history: list[np.ndarray] = []  # servo command at steps 0, 1, …
        # the reference posture θ = 0: its COM-above angles from the geometry, and the
        # servo command that held it at rest before the trial, from Pinocchio's gravity
        # torques there (τ = −servo − Kp·sin α_ref at rest)
        self.alpha_ref = com_above_angles(body, np.zeros(n))
        hold_torques = pin.computeGeneralizedGravity(body.model, body.model.createData(),
                                                     np.zeros(n))
        self.hold = -np.asarray(hold_torques) - p["kp"] * np.sin(self.alpha_ref)

    def torques(self, step: int, theta, omega, tilt, tilt_vel) -> np.ndarray:
        body, p = self.body, self.p
        n = body.n_segments
        h = 1e-6
        alpha = com_above_angles(body, theta)
        alpha_dot = (com_above_angles(body, theta + h * omega)
                     - com_above_angles(body, theta - h * omega)) / (2 * h)
        below = np.concatenate([[tilt], theta[:-1]])  # θ_{i−1}, θ_0 = α_FS
        below_dot = np.concatenate([[tilt_vel], omega[:-1]])
        q = theta - below
        qd = omega - below_dot
        # tilt estimator: vestibular θ̇_1 minus proprioceptive q̇_1, through the dead-band
        est_rate = deadband(omega[0] - qd[0], self.theta_db)
        beta = self.estimate + np.concatenate([[0.0], np.cumsum(q)[:-1]])  # β̂_{i−1}
        beta_dot = est_rate + np.concatenate([[0.0], np.cumsum(qd)[:-1]])
        x_com = (alpha - self.alpha_ref - below) + beta
        xd_com = (alpha_dot - below_dot) + beta_dot
        x = np.where(p["sign"] > 0, x_com, q)
        xd = np.where(p["sign"] > 0, xd_com, qd)
        # the command that held the stance at rest stays in the servo: the integral of a
        # subject who has stood there (hold/Ki), written so that Ki = 0 is well defined
        servo = p["kp"] * x + p["kd"] * xd + p["ki"] * self.integral + self.hold
        self.history.append(servo)
        delayed = self.hold.copy()
        for i in range(n):
            d = p["delay_s"][i] / DT  # steps, fractional
            if step >= d - 1e-9:
                k = int(math.floor(d + 1e-9))
                f = d - k
                u0 = self.history[step - k][i]
                u1 = self.history[step - k - 1][i] if f > 1e-12 else u0
                delayed[i] = (1 - f) * u0 + f * u1
        tg = np.sin(alpha)
        tg_dot = np.cos(alpha) * alpha_dot
        tau = (-delayed - (p["kp"] * tg + p["kd"] * tg_dot)
               - (p["kpas"] * q + p["bpas"] * qd))
        self.integral = self.integral + DT * x
        self.estimate += DT * est_rate
        return tau


@pytest.mark.parametrize("fixture", ["tip", "winter2", "talos_bent"])
def test_compiled_controller_matches_model_written_in_numpy(request, fixture):
    body = request.getfixturevalue(fixture)
    n = body.n_segments
    rng = np.random.default_rng(7)
    defaults = default_parameters(body)
    shape = (LANES, n)

    def around(field: str) -> np.ndarray:
        return defaults.array(field) * rng.uniform(0.3, 2.0, shape)

    # delays from 0 (no delay) to 0.2 s, whole and fractional numbers of steps
    delay = np.round(rng.uniform(0.0, 0.2, shape) / DT * 4) / 4 * DT
    delay[0] = [0.0] * n
    delay[1] = [DT * 7] * n
    params = ParameterArrays(kp=around("kp"), ki=around("ki"), kd=around("kd"),
                             delay_s=delay, sign=rng.choice([-1.0, 1.0], shape),
                             kpas=around("kpas"), bpas=around("bpas"))
    deadband_rad_s = 0.003  # wide, so random tilt rates fall on both sides of it
    options = SimulationOptions(deadband_rad_s=deadband_rad_s)
    k = kernels(n)
    rows = k.rows
    par, buf = block_arrays(k, body, params, options, 0, LANES)
    w = np.zeros(rows.count * LANES)
    s_re = np.ascontiguousarray(body.gravity_lever.real)
    s_im = np.ascontiguousarray(body.gravity_lever.imag)
    oracles = [Oracle(body, {f: getattr(params, f)[lane] for f in ParameterArrays.FIELDS},
                      deadband_rad_s) for lane in range(LANES)]
    worst = 0.0
    for step in range(150):
        theta = rng.uniform(-0.15, 0.15, shape)
        omega = rng.uniform(-0.5, 0.5, shape)
        tilt = rng.uniform(-0.05, 0.05)
        tilt_vel = rng.uniform(-0.01, 0.01)
        w[rows.theta * LANES : (rows.theta + n) * LANES] = theta.T.ravel()
        w[rows.omega * LANES : (rows.omega + n) * LANES] = omega.T.ravel()
        k.kinematics(w, s_re, s_im, math.radians(45.0))
        k.dec_torques(step, w, par, buf, tilt, tilt_vel, DT, deadband_rad_s)
        compiled = w[rows.tau * LANES : (rows.tau + n) * LANES].reshape(n, LANES).T
        for lane, oracle in enumerate(oracles):
            expected = oracle.torques(step, theta[lane], omega[lane], tilt, tilt_vel)
            scale = np.abs(expected).max() + 1.0
            np.testing.assert_allclose(compiled[lane], expected, rtol=0, atol=1e-7 * scale,
                                       err_msg=f"step {step}, lane {lane}")
            worst = max(worst, float(np.abs(compiled[lane] - expected).max() / scale))
    assert worst > 0.0  # the two really are separate computations


def test_oracle_geometry_matches_the_body_upright(tip):
    """At the upright posture the COM above each joint is straight above it."""
    np.testing.assert_allclose(com_above_angles(tip, np.zeros(3)), 0.0, atol=1e-15)
    lean = com_above_angles(tip, np.full(3, 0.1))
    np.testing.assert_allclose(lean, 0.1, atol=1e-12)  # a rigid lean tilts every COM alike
