"""Source of the compiled simulator for one number of segments N (numba).

Not imported as it is: :func:`posture_id.simulation.kernel.kernels` writes a copy with
``N`` set (the line marked below) into the cache folder and imports that, so every
segment loop unrolls, every row offset is a compile-time constant, the lane loops
vectorise (AVX2/AVX-512), and numba's on-disk cache of the copy makes a new process start
warm. Equations: :mod:`posture_id.simulation.kernel`; layout:
:mod:`posture_id.simulation.kernel_layout`.
"""

import math

import numpy as np
from numba import njit

from posture_id.simulation.fastmath import atan2_poly_r, cos_poly, sin_poly
from posture_id.simulation.kernel_layout import LANES, ParRows, Rows

N = 3  # SEGMENTS: replaced in every generated copy

L = LANES
R = Rows(N)
P = ParRows(N)
TH, OM, INT, AL, ALD = R.theta, R.omega, R.integral, R.alpha, R.alpha_dot
TG, TGD, COS, SIN, LEV = R.tg, R.tg_dot, R.cos, R.sin, R.lever
TAU, SERVO, Q, QD, ACC, MASS = R.tau, R.servo, R.q, R.qd, R.acc, R.mass
SPREV = R.servo_before
EST, ESTR, INSIDE = R.estimate, R.estimate_rate, R.inside
VRE, VIM, VDRE, VDIM = R.vsum, R.vsum + N, R.vsum + 2 * N, R.vsum + 3 * N
PIVINV = R.pivot_inverse
KP, KI, KD, SIGN, KPAS, BPAS = P.kp, P.ki, P.kd, P.sign, P.kpas, P.bpas
DLY, DCEIL, DFRAC = P.delay, P.delay_ceil, P.delay_frac
AREF, HOLD = P.alpha_ref, P.hold



@njit(cache=True, error_model="numpy", inline="always")
def kinematics(w, s_re, s_im, sway_limit):
    """COM-above angles, gravity terms and the sway-limit flag from θ, θ̇ (all lanes).

    s_re, s_im: (N,) gravity levers S (kg·m); sway_limit: rad.
    Three passes over the lanes, each with short dependency chains (the simulator is
    bound by their latency): sin and cos of every θ_j; the COM-above sums from the top
    down; then every segment's angle, rate and gravity term.
    """
    for lane in range(L):
        w[INSIDE * L + lane] = 1.0
    for i in range(N):
        for lane in range(L):
            th = w[(TH + i) * L + lane]
            w[(COS + i) * L + lane] = cos_poly(th)
            w[(SIN + i) * L + lane] = sin_poly(th)
            if not abs(th) <= sway_limit:
                w[INSIDE * L + lane] = 0.0
    # running sums Σ_{j≥i} e^{iθ_j} S_j (re, im) and their rates, from the top down
    for top_down in range(N):
        i = N - 1 - top_down
        sr = s_re[i]
        si = s_im[i]
        for lane in range(L):
            c = w[(COS + i) * L + lane]
            s = w[(SIN + i) * L + lane]
            e_re = c * sr - s * si
            e_im = s * sr + c * si
            w[(LEV + i) * L + lane] = e_im
            om = w[(OM + i) * L + lane]
            if top_down == 0:
                v_re = e_re
                v_im = e_im
                vd_re = -om * e_im
                vd_im = om * e_re
            else:
                v_re = w[(VRE + i + 1) * L + lane] + e_re
                v_im = w[(VIM + i + 1) * L + lane] + e_im
                vd_re = w[(VDRE + i + 1) * L + lane] - om * e_im
                vd_im = w[(VDIM + i + 1) * L + lane] + om * e_re
            w[(VRE + i) * L + lane] = v_re
            w[(VIM + i) * L + lane] = v_im
            w[(VDRE + i) * L + lane] = vd_re
            w[(VDIM + i) * L + lane] = vd_im
    for i in range(N):
        for lane in range(L):
            v_re = w[(VRE + i) * L + lane]
            v_im = w[(VIM + i) * L + lane]
            vd_re = w[(VDRE + i) * L + lane]
            vd_im = w[(VDIM + i) * L + lane]
            r = math.sqrt(v_re * v_re + v_im * v_im)
            inv_r = 1.0 / r
            rate = (vd_im * v_re - vd_re * v_im) * (inv_r * inv_r)
            w[(AL + i) * L + lane] = atan2_poly_r(v_im, v_re, r)
            w[(ALD + i) * L + lane] = rate
            w[(TG + i) * L + lane] = v_im * inv_r
            w[(TGD + i) * L + lane] = v_re * inv_r * rate

@njit(cache=True, error_model="numpy", inline="always")
def dec_torques(n, w, par, buf, tilt, tilt_vel, dt, deadband_rad_s):
    """DEC joint torques at step n (docs/model.md §2) into the τ rows; advances ∫ε, α̂_FS and
    the delay buffers. tilt, tilt_vel: α_FS (rad) and rate at t = n·dt.

    buf: (N·B·L,) ring buffers of B (a power of two) servo commands per module.
    """
    n_buf = buf.shape[0] // (N * L)
    mask = n_buf - 1
    # phase 1 (vectorised): servo command, integral and tilt-estimate updates
    for lane in range(L):
        ankle_rate = w[OM * L + lane] - tilt_vel  # proprioceptive q̇_1
        v = w[OM * L + lane] - ankle_rate  # vestibular θ̇_1 − q̇_1
        est_rate = max(v - deadband_rad_s, 0.0) + min(v + deadband_rad_s, 0.0)
        beta = w[EST * L + lane]
        beta_rate = est_rate
        below = tilt
        below_rate = tilt_vel
        for i in range(N):
            th = w[(TH + i) * L + lane]
            om = w[(OM + i) * L + lane]
            q = th - below
            qd = om - below_rate
            # class C = ±1 selects COM in space or joint angle; a value between
            # (the fit's relaxed class) mixes them linearly
            mix = 0.5 + 0.5 * par[(SIGN + i) * L + lane]
            # COM in space relative to the reference posture's (0 for a straight chain)
            x = (mix * (w[(AL + i) * L + lane] - par[(AREF + i) * L + lane] - below + beta)
                 + (1.0 - mix) * q)
            xd = mix * (w[(ALD + i) * L + lane] - below_rate + beta_rate) + (1.0 - mix) * qd
            integ = w[(INT + i) * L + lane]
            # the servo command holding the reference posture at rest is part of it at
            # every step (the integrator's state of a subject who has stood there)
            w[(SERVO + i) * L + lane] = (
                par[(KP + i) * L + lane] * x
                + par[(KD + i) * L + lane] * xd
                + par[(KI + i) * L + lane] * integ
                + par[(HOLD + i) * L + lane]
            )
            w[(INT + i) * L + lane] = integ + dt * x
            w[(Q + i) * L + lane] = q
            w[(QD + i) * L + lane] = qd
            beta += q
            beta_rate += qd
            below = th
            below_rate = om
        w[ESTR * L + lane] = est_rate
        w[EST * L + lane] += dt * est_rate
    # phase 2: store the command already interpolated for its reader (vectorised):
    # slot m holds u(m−1) + frac·(u(m) − u(m−1)), the servo command Δ/dt steps before
    # step m + ⌈Δ/dt⌉ − 1, so a lane reads one slot ...
    slot = n & mask
    for i in range(N):
        row = i * n_buf + slot
        for lane in range(L):
            u_now = w[(SERVO + i) * L + lane]
            u_before = w[(SPREV + i) * L + lane]
            buf[row * L + lane] = u_before + par[(DFRAC + i) * L + lane] * (u_now - u_before)
            w[(SPREV + i) * L + lane] = u_now
    # ... (scalar: one gather per lane); before the first command is Δ old, the servo sent
    # what held the reference posture at rest
    for i in range(N):
        base = i * n_buf * L
        for lane in range(L):
            k = n + 1 - int(par[(DCEIL + i) * L + lane])
            delayed = buf[base + (k & mask) * L + lane]
            w[(TAU + i) * L + lane] = (delayed if n >= par[(DLY + i) * L + lane]
                                       else par[(HOLD + i) * L + lane])
    # phase 3 (vectorised): τ = −servo(t − Δ) − PD on T_g (undelayed) − passive
    for lane in range(L):
        for i in range(N):
            kp = par[(KP + i) * L + lane]
            kd = par[(KD + i) * L + lane]
            w[(TAU + i) * L + lane] = (
                -w[(TAU + i) * L + lane]
                - kp * w[(TG + i) * L + lane]
                - kd * w[(TGD + i) * L + lane]
                - par[(KPAS + i) * L + lane] * w[(Q + i) * L + lane]
                - par[(BPAS + i) * L + lane] * w[(QD + i) * L + lane]
            )

@njit(cache=True, error_model="numpy", inline="always")
def dynamics(w, d_re, d_im, inertia, gravity, dt):
    """θ̈ from M θ̈ = Q − c − G (LDLᵀ), then one semi-implicit Euler step.

    d_re, d_im: (N, N) coupling D (kg·m²); inertia: (N,) kg·m²; gravity: m/s²; dt: s.
    M's diagonal is constant.
    """
    # right-hand side Q − G in the θ̈ rows, M's lower triangle, Coriolis/centrifugal terms
    for j in range(N):
        for lane in range(L):
            rhs = w[(TAU + j) * L + lane] + gravity * w[(LEV + j) * L + lane]
            if j + 1 < N:
                rhs -= w[(TAU + j + 1) * L + lane]
            w[(ACC + j) * L + lane] = rhs
    for j in range(N):
        for k in range(j):
            dr = d_re[j, k]
            di = d_im[j, k]
            for lane in range(L):
                cj = w[(COS + j) * L + lane]
                sj = w[(SIN + j) * L + lane]
                ck = w[(COS + k) * L + lane]
                sk = w[(SIN + k) * L + lane]
                e_re = cj * ck + sj * sk
                e_im = sj * ck - cj * sk
                w[(MASS + j * N + k) * L + lane] = dr * e_re - di * e_im
                cor = dr * e_im + di * e_re
                ok = w[(OM + k) * L + lane]
                oj = w[(OM + j) * L + lane]
                w[(ACC + j) * L + lane] -= ok * ok * cor
                w[(ACC + k) * L + lane] += oj * oj * cor
    # M = L·diag(d)·Lᵀ, L unit lower triangular (in place of M's lower triangle), the
    # pivots d in M's diagonal rows, 1/d in the PIVINV rows; then L y = b, Lᵀ θ̈ = y / d.
    # The segment loops run over all of range(N) with a condition (never range(j)), so
    # LLVM unrolls them whole and the lane loop vectorises.
    for lane in range(L):
        for j in range(N):
            s = d_re[j, j] + inertia[j]
            for k in range(N):
                if k < j:
                    l_jk = w[(MASS + j * N + k) * L + lane]
                    s -= l_jk * l_jk * w[(MASS + k * N + k) * L + lane]
            w[(MASS + j * N + j) * L + lane] = s
            inv = 1.0 / s
            w[(PIVINV + j) * L + lane] = inv
            for i in range(N):
                if i > j:
                    s = w[(MASS + i * N + j) * L + lane]
                    for k in range(N):
                        if k < j:
                            s -= (w[(MASS + i * N + k) * L + lane]
                                  * w[(MASS + j * N + k) * L + lane]
                                  * w[(MASS + k * N + k) * L + lane])
                    w[(MASS + i * N + j) * L + lane] = s * inv
    for lane in range(L):
        for i in range(N):
            s = w[(ACC + i) * L + lane]
            for k in range(N):
                if k < i:
                    s -= w[(MASS + i * N + k) * L + lane] * w[(ACC + k) * L + lane]
            w[(ACC + i) * L + lane] = s
        for back in range(N):
            i = N - 1 - back
            s = w[(ACC + i) * L + lane] * w[(PIVINV + i) * L + lane]
            for k in range(N):
                if k > i:
                    s -= w[(MASS + k * N + i) * L + lane] * w[(ACC + k) * L + lane]
            w[(ACC + i) * L + lane] = s
    for j in range(N):
        for lane in range(L):
            om = w[(OM + j) * L + lane] + dt * w[(ACC + j) * L + lane]
            w[(OM + j) * L + lane] = om
            w[(TH + j) * L + lane] += dt * om

@njit(cache=True, nogil=True, error_model="numpy")
def simulate_block(w, par, buf, d_re, d_im, inertia, s_re, s_im, gravity, tilt, tilt_vel,
                   n_steps, dt, sample_every, sway_limit, deadband_rad_s, out_theta,
                   out_alpha, abort_step, first, count, motor, motor_on):
    """Simulate trials ``first .. first+count−1`` of a batch as one block of L lanes.

    w, par, buf: the block's work, parameter and buffer arrays (lanes ≥ count are
    padding). tilt, tilt_vel: (n_steps + 1,) α_FS (rad) and rate on the step grid.
    out_theta, out_alpha: (B, S, N) θ and α_S at every ``sample_every``-th step (rad),
    NaN from an abort on. abort_step: (B,) int64, the step of the abort or −1.
    motor: (n_steps·N·L,) motor-noise torques (N·m) added to the joint torques of every
    step, step-major then joint then lane; read only when ``motor_on``.
    Releases the GIL: blocks run in parallel threads.
    """
    alive = np.zeros(L, dtype=np.bool_)
    alive[:count] = True
    n_alive = count
    for lane in range(count):
        abort_step[first + lane] = -1
    for step in range(n_steps + 1):
        kinematics(w, s_re, s_im, sway_limit)
        parked = False
        for lane in range(L):
            if w[INSIDE * L + lane] > 0.0:
                continue
            if alive[lane]:
                alive[lane] = False
                n_alive -= 1
                if lane < count:
                    k0 = (step + sample_every - 1) // sample_every
                    abort_step[first + lane] = step
                    out_theta[first + lane, k0:] = np.nan
                    out_alpha[first + lane, k0:] = np.nan
            # a lane past the limit is parked upright at rest: its numbers stay benign
            parked = True
            w[EST * L + lane] = 0.0
            for j in range(N):
                w[(TH + j) * L + lane] = 0.0
                w[(OM + j) * L + lane] = 0.0
                w[(INT + j) * L + lane] = 0.0
                w[(SPREV + j) * L + lane] = 0.0
            for p in range(lane, buf.shape[0], L):
                buf[p] = 0.0
        if n_alive == 0:
            return
        if parked:
            kinematics(w, s_re, s_im, sway_limit)
        if step % sample_every == 0:
            k = step // sample_every
            for lane in range(count):
                if alive[lane]:
                    for j in range(N):
                        out_theta[first + lane, k, j] = w[(TH + j) * L + lane]
                        out_alpha[first + lane, k, j] = w[(AL + j) * L + lane]
        if step == n_steps:
            return
        dec_torques(step, w, par, buf, tilt[step], tilt_vel[step], dt, deadband_rad_s)
        if motor_on:
            base = step * N * L
            for i in range(N):
                for lane in range(L):
                    w[(TAU + i) * L + lane] += motor[base + i * L + lane]
        dynamics(w, d_re, d_im, inertia, gravity, dt)
