"""The DEC controller law of MODEL §2, compiled, shared by every simulation path.

One call computes the joint torques of all N modules at step n from the sensed state and
advances the controller's own states (tilt estimate, integrals, delay buffers) by one step.
The fast simulator calls it from compiled code; the Pinocchio reference path calls the
same function from Python, so the two differ only in how the plant is stepped.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = ["dec_torques", "deadband", "buffer_length"]

_DELAY_TOL = 1e-9


def buffer_length(max_delay_steps: float) -> int:
    """Ring-buffer length that holds every servo command a delay of that many steps reads."""
    return int(math.floor(max_delay_steps)) + 2


@njit(cache=True)
def deadband(v: float, threshold: float) -> float:
    """f_θ(v): 0 inside ±threshold, v ∓ threshold outside (rad/s)."""
    if v > threshold:
        return v - threshold
    if v < -threshold:
        return v + threshold
    return 0.0


@njit(cache=True)
def dec_torques(
    n, dt, theta, omega, tilt, tilt_vel, alpha_s, alpha_s_dot, tg, tg_dot,
    kp, ki, kd, delay_steps, sign, kpas, bpas, deadband_rad_s,
    integral, estimate, buffer, tau,
):
    """Joint torques of all DEC modules at step n; advances the controller states.

    Args:
        n: step index (t = n·dt). dt: s.
        theta, omega: (N,) segment angles in space (rad) and their rates (rad/s).
        tilt, tilt_vel: α_FS (rad) and its rate (rad/s) at t.
        alpha_s, alpha_s_dot: (N,) COM-above angles in space α_i,S (rad) and rates.
        tg, tg_dot: (N,) gravity angle-equivalents sin(α_i,S) and their rates (1/s).
        kp, ki, kd: (N,) gains (N·m/rad, N·m/(rad·s), N·m·s/rad).
        delay_steps: (N,) Δ_i / dt, fractional (interpolated, never rounded).
        sign: (N,) class C_i (+1 COM in space, −1 joint angle).
        kpas, bpas: (N,) passive stiffness and damping.
        deadband_rad_s: θ of the tilt estimator's dead-band.
        integral: (N,) ∫ε dt, advanced in place. estimate: (1,) α̂_FS, advanced in place.
        buffer: (N, L) ring buffer of servo commands, written in place.
        tau: (N,) output joint torques, N·m.
    """
    n_mod = theta.shape[0]
    length = buffer.shape[1]
    # estimator input: vestibular trunk-derived shank rate minus proprioceptive ankle rate
    ankle_rate = omega[0] - tilt_vel
    est_rate = deadband(omega[0] - ankle_rate, deadband_rad_s)
    beta = estimate[0]
    beta_rate = est_rate
    below = tilt
    below_rate = tilt_vel
    for i in range(n_mod):
        q = theta[i] - below
        qd = omega[i] - below_rate
        if sign[i] > 0:
            x = alpha_s[i] - below + beta
            xd = alpha_s_dot[i] - below_rate + beta_rate
        else:
            x = q
            xd = qd
        servo = kp[i] * x + kd[i] * xd + ki[i] * integral[i]
        buffer[i, n % length] = servo
        lag = n - delay_steps[i]
        if lag < -_DELAY_TOL:
            delayed = 0.0
        else:
            if lag < 0.0:
                lag = 0.0
            k = int(math.floor(lag))
            frac = lag - k
            delayed = buffer[i, k % length]
            if frac > 0.0:
                delayed += frac * (buffer[i, (k + 1) % length] - delayed)
        tau[i] = (
            -delayed
            - kp[i] * tg[i]
            - kd[i] * tg_dot[i]
            - kpas[i] * q
            - bpas[i] * qd
        )
        integral[i] += dt * x
        beta += q
        beta_rate += qd
        below = theta[i]
        below_rate = omega[i]
    estimate[0] += dt * est_rate
