"""Compiled planar-chain dynamics and the batched DEC simulation loop (numba).

Equations of motion in segment-in-space angles θ (N,) (derivation in docs/model.md):

    M(θ) θ̈ + c(θ, θ̇) + G(θ) = Q,   Q_j = τ_j − τ_{j+1}
    M_jk = Re(D_jk E_jk) + δ_jk I_j,   c_j = Σ_k θ̇_k² Im(D_jk E_jk),   E_jk = e^{i(θ_j − θ_k)}
    G_j = −g Im(e^{iθ_j} S_j)

with the body's constant coupling D (N, N) and gravity levers S (N,) (see
:class:`posture_id.body.Body`). The COM above joint i is Σ_{j≥i} e^{iθ_j} S_j / m_above,i.

Time stepping (MODEL §2 **[decision]**): step dt, controller from the state at the start
of the step, semi-implicit Euler (velocities first, then angles).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from posture_id.dec import dec_torques

__all__ = ["chain_kinematics", "chain_acceleration", "simulate_batch_kernel"]


@njit(cache=True)
def chain_kinematics(theta, omega, s_re, s_im, cos_t, sin_t, alpha_s, alpha_s_dot, tg, tg_dot,
                     lever_im):
    """Fill COM-above angles and gravity terms from the segment angles.

    Args:
        theta, omega: (N,) rad, rad/s.
        s_re, s_im: (N,) gravity levers S (kg·m), real and imaginary parts.
        cos_t, sin_t: (N,) outputs, cos θ and sin θ.
        alpha_s, alpha_s_dot: (N,) outputs, α_i,S (rad) and its rate (rad/s).
        tg, tg_dot: (N,) outputs, sin α_i,S and its rate (1/s).
        lever_im: (N,) output, Im(e^{iθ_j} S_j) (kg·m); G_j = −g·lever_im_j.
    """
    n = theta.shape[0]
    for j in range(n):
        cos_t[j] = math.cos(theta[j])
        sin_t[j] = math.sin(theta[j])
    v_re = 0.0
    v_im = 0.0
    vd_re = 0.0
    vd_im = 0.0
    for i in range(n - 1, -1, -1):
        e_re = cos_t[i] * s_re[i] - sin_t[i] * s_im[i]
        e_im = sin_t[i] * s_re[i] + cos_t[i] * s_im[i]
        lever_im[i] = e_im
        v_re += e_re
        v_im += e_im
        vd_re -= omega[i] * e_im
        vd_im += omega[i] * e_re
        r2 = v_re * v_re + v_im * v_im
        inv_r = 1.0 / math.sqrt(r2)
        rate = (vd_im * v_re - vd_re * v_im) / r2
        alpha_s[i] = math.atan2(v_im, v_re)
        alpha_s_dot[i] = rate
        tg[i] = v_im * inv_r
        tg_dot[i] = v_re * inv_r * rate


@njit(cache=True)
def chain_acceleration(cos_t, sin_t, omega, d_re, d_im, inertia, gravity, lever_im, tau,
                       mass, acc):
    """θ̈ (N,) rad/s² from the state and joint torques ``tau`` (N,) N·m.

    ``mass`` (N, N) is scratch; ``acc`` (N,) receives the result. Solves M θ̈ = Q − c − G by
    an in-place Cholesky factorisation (M is symmetric positive definite).
    """
    n = omega.shape[0]
    for j in range(n):
        rhs = tau[j] + gravity * lever_im[j]
        if j + 1 < n:
            rhs -= tau[j + 1]
        for k in range(n):
            e_re = cos_t[j] * cos_t[k] + sin_t[j] * sin_t[k]
            e_im = sin_t[j] * cos_t[k] - cos_t[j] * sin_t[k]
            mass[j, k] = d_re[j, k] * e_re - d_im[j, k] * e_im
            rhs -= omega[k] * omega[k] * (d_re[j, k] * e_im + d_im[j, k] * e_re)
        mass[j, j] += inertia[j]
        acc[j] = rhs
    # Cholesky: mass = L Lᵀ, L stored in the lower triangle
    for j in range(n):
        s = mass[j, j]
        for k in range(j):
            s -= mass[j, k] * mass[j, k]
        mass[j, j] = math.sqrt(s)
        for i in range(j + 1, n):
            s = mass[i, j]
            for k in range(j):
                s -= mass[i, k] * mass[j, k]
            mass[i, j] = s / mass[j, j]
    for i in range(n):
        s = acc[i]
        for k in range(i):
            s -= mass[i, k] * acc[k]
        acc[i] = s / mass[i, i]
    for i in range(n - 1, -1, -1):
        s = acc[i]
        for k in range(i + 1, n):
            s -= mass[k, i] * acc[k]
        acc[i] = s / mass[i, i]


@njit(cache=True)
def _simulate_trial(d_re, d_im, inertia, s_re, s_im, gravity, tilt, tilt_vel, n_steps, dt,
                    sample_every, sway_limit, deadband_rad_s, kp, ki, kd, delay_steps, sign,
                    kpas, bpas, buffer_len, out_theta, out_alpha):
    """Run one trial; fill ``out_theta``/``out_alpha`` (S, N); return the abort step or −1."""
    n = s_re.shape[0]
    theta = np.zeros(n)
    omega = np.zeros(n)
    cos_t = np.empty(n)
    sin_t = np.empty(n)
    alpha_s = np.empty(n)
    alpha_s_dot = np.empty(n)
    tg = np.empty(n)
    tg_dot = np.empty(n)
    lever_im = np.empty(n)
    tau = np.empty(n)
    acc = np.empty(n)
    mass = np.empty((n, n))
    integral = np.zeros(n)
    estimate = np.zeros(1)
    buffer = np.zeros((n, buffer_len))
    for step in range(n_steps + 1):
        chain_kinematics(theta, omega, s_re, s_im, cos_t, sin_t, alpha_s, alpha_s_dot, tg,
                         tg_dot, lever_im)
        fallen = False
        for j in range(n):
            if not abs(theta[j]) <= sway_limit:
                fallen = True
        if fallen:
            first = (step + sample_every - 1) // sample_every
            out_theta[first:, :] = np.nan
            out_alpha[first:, :] = np.nan
            return step
        if step % sample_every == 0:
            k = step // sample_every
            for j in range(n):
                out_theta[k, j] = theta[j]
                out_alpha[k, j] = alpha_s[j]
        if step == n_steps:
            break
        dec_torques(step, dt, theta, omega, tilt[step], tilt_vel[step], alpha_s, alpha_s_dot,
                    tg, tg_dot, kp, ki, kd, delay_steps, sign, kpas, bpas, deadband_rad_s,
                    integral, estimate, buffer, tau)
        chain_acceleration(cos_t, sin_t, omega, d_re, d_im, inertia, gravity, lever_im, tau,
                           mass, acc)
        for j in range(n):
            omega[j] += dt * acc[j]
            theta[j] += dt * omega[j]
    return -1


@njit(cache=True, nogil=True)
def simulate_batch_kernel(d_re, d_im, inertia, s_re, s_im, gravity, tilt, tilt_vel, n_steps,
                          dt, sample_every, sway_limit, deadband_rad_s, kp, ki, kd,
                          delay_steps, sign, kpas, bpas, buffer_len, out_theta, out_alpha,
                          abort_step, start, stop):
    """Simulate trials ``start..stop-1`` of a batch, releasing the GIL (threads run chunks).

    Parameter arrays are (B, N); outputs ``out_theta``/``out_alpha`` are (B, S, N) rad and
    ``abort_step`` (B,) int64 (−1 for a trial that stayed within ``sway_limit`` rad).
    """
    for b in range(start, stop):
        abort_step[b] = _simulate_trial(
            d_re, d_im, inertia, s_re, s_im, gravity, tilt, tilt_vel, n_steps, dt,
            sample_every, sway_limit, deadband_rad_s, kp[b], ki[b], kd[b], delay_steps[b],
            sign[b], kpas[b], bpas[b], buffer_len, out_theta[b], out_alpha[b],
        )
