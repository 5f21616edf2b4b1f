"""The plant and the DEC controller in CasADi, built from any :class:`~posture_id.bodies.body.Body`.

The PyPI ``pin`` wheel has no ``pinocchio.casadi``, so the planar chain's dynamics are
written here from the body's masses, lengths, COMs and inertias, through the same
constants as the compiled simulator (coupling D and gravity levers S, docs/model.md):

    M_jk = Re(D_jk e^{i(θ_j−θ_k)}) + δ_jk I_j,  c_j = Σ_k θ̇_k² Im(D_jk e^{i(θ_j−θ_k)}),
    G_j = −g Im(e^{iθ_j} S_j),  M θ̈ = Q − c − G.

:func:`step_function` is one 2 ms step (controller from the state at the start of the
step, semi-implicit Euler), the same integrator as the fast simulator;
:func:`rollout_function` rolls it over a trial and returns the 50 Hz samples.

The delay buffer is a shift register of the last P servo commands per module (P covers
the largest delay allowed); the delayed command is Σ_k w_k u_{n−k} with hat weights
w_k = max(0, 1 − |Δ/dt − k|), i.e. linear interpolation, continuous in Δ. For the fit the
class C may be relaxed to c ∈ [−1, 1] (x = (1+c)/2·x_COM + (1−c)/2·x_joint; exact at ±1)
and the dead-band smoothed (softplus, width ``smooth``).

The body enters as a vector of constants (:func:`body_constants`: D, S, the inertias and g),
an input of every function like the parameters, so one compiled model serves every body
with the same number of segments: a cohort of subjects with their own anthropometric
bodies compiles once.

Only the :mod:`posture_id.fitting` package imports CasADi (a layer contract).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from posture_id.bodies.body import Body

__all__ = ["SymbolicModel", "BodyTerms", "body_constants", "n_body_constants",
           "chain_dynamics", "step_function", "rollout_function", "rollout_steps",
           "block_function", "BLOCK_SAMPLES",
           "delay_weights", "buffer_sizes", "step_inputs"]


def n_body_constants(n: int) -> int:
    """Length of :func:`body_constants` for an N-segment body: 2N² + 3N + 1."""
    return 2 * n * n + 3 * n + 1


def body_constants(body: Body) -> np.ndarray:
    """(2N² + 3N + 1,) the body's constants as the symbolic model takes them:
    [Re D (N·N, row-major), Im D (N·N), Re S (N), Im S (N), I (N), g]
    in kg·m², kg·m², kg·m, kg·m, kg·m², m/s² (D, S: docs/model.md)."""
    d = np.asarray(body.coupling)
    s = np.asarray(body.gravity_lever)
    return np.concatenate([d.real.ravel(), d.imag.ravel(), s.real, s.imag,
                           np.asarray(body.inertias, dtype=float), [float(body.gravity)]])


@dataclass(frozen=True)
class BodyTerms:
    """The body's constants split into named terms, numbers or CasADi expressions.

    Attributes:
        d_re, d_im: (N, N) nested lists, Re and Im of the coupling D (kg·m²).
        s_re, s_im: (N,) Re and Im of the gravity levers S (kg·m).
        inertia: (N,) kg·m². gravity: m/s².
    """

    d_re: list
    d_im: list
    s_re: list
    s_im: list
    inertia: list
    gravity: object

    @classmethod
    def of(cls, constants, n: int) -> BodyTerms:
        """Split a :func:`body_constants` vector (numeric array or CasADi symbol)."""
        c = [constants[i] for i in range(n_body_constants(n))]
        nn = n * n
        return cls([c[j * n : (j + 1) * n] for j in range(n)],
                   [c[nn + j * n : nn + (j + 1) * n] for j in range(n)],
                   c[2 * nn : 2 * nn + n], c[2 * nn + n : 2 * nn + 2 * n],
                   c[2 * nn + 2 * n : 2 * nn + 3 * n], c[2 * nn + 3 * n])


def _deadband(v, threshold: float, smooth: float):
    """f_θ(v); with ``smooth`` > 0 a softplus version, differentiable everywhere."""
    if smooth <= 0:
        return ca.fmax(v - threshold, 0) + ca.fmin(v + threshold, 0)

    def softplus(z):
        # w·log(1 + e^{z/w}) written so that e^{…} never overflows (it did past ~0.4°/s)
        return ca.fmax(z, 0) + smooth * ca.log1p(ca.exp(-ca.fabs(z) / smooth))

    return softplus(v - threshold) - softplus(-v - threshold)


def chain_dynamics(body: Body):
    """CasADi SX function (θ, θ̇, τ) → (θ̈, M, G): the planar chain in segment angles,
    with ``body``'s constants filled in (the same expression the step uses).

    θ, θ̇, τ: (N,) rad, rad/s, N·m (joint torques). M: (N, N), G: (N,) gravity term.
    """
    n = body.n_segments
    theta = ca.SX.sym("theta", n)
    omega = ca.SX.sym("omega", n)
    tau = ca.SX.sym("tau", n)
    constants = ca.SX.sym("body", n_body_constants(n))
    acc, mass, grav = _dynamics_expr(BodyTerms.of(constants, n), theta, omega, tau)
    general = ca.Function("chain", [theta, omega, tau, constants], [acc, mass, grav])
    out = general(theta, omega, tau, body_constants(body))
    return ca.Function("chain_dynamics", [theta, omega, tau], list(out),
                       ["theta", "omega", "tau"], ["acc", "M", "G"])


def _dynamics_expr(terms: BodyTerms, theta, omega, tau):
    n = theta.numel()
    d_re, d_im, g = terms.d_re, terms.d_im, terms.gravity
    cos = [ca.cos(theta[j]) for j in range(n)]
    sin = [ca.sin(theta[j]) for j in range(n)]
    mass = ca.SX.zeros(n, n)
    rhs = []
    for j in range(n):
        lever_im = sin[j] * terms.s_re[j] + cos[j] * terms.s_im[j]
        r = tau[j] + g * lever_im - (tau[j + 1] if j + 1 < n else 0)
        for k in range(n):
            e_re = cos[j] * cos[k] + sin[j] * sin[k]
            e_im = sin[j] * cos[k] - cos[j] * sin[k]
            mass[j, k] = d_re[j][k] * e_re - d_im[j][k] * e_im
            r -= omega[k] ** 2 * (d_re[j][k] * e_im + d_im[j][k] * e_re)
        mass[j, j] += terms.inertia[j]
        rhs.append(r)
    rhs = ca.vertcat(*rhs)
    grav = ca.vertcat(*[-g * (sin[j] * terms.s_re[j] + cos[j] * terms.s_im[j])
                        for j in range(n)])
    return ca.solve(mass, rhs), mass, grav


def step_inputs(tilt: np.ndarray, tilt_vel: np.ndarray, n_steps: int) -> np.ndarray:
    """(3, n_steps) rollout input [step index, α_FS, α̇_FS] from the tilt on the step grid
    (arrays of at least ``n_steps`` values are cut; shorter ones padded with the last
    angle at rest)."""
    u = np.zeros((3, n_steps))
    u[0] = np.arange(n_steps)
    m = min(n_steps, len(tilt))
    u[1, :m] = tilt[:m]
    u[1, m:] = tilt[m - 1]
    u[2, :m] = tilt_vel[:m]
    return u


def buffer_sizes(max_delay_steps: np.ndarray) -> list[int]:
    """Shift-register length per module for delays up to ``max_delay_steps`` (N,)."""
    return [int(math.floor(d)) + 2 for d in max_delay_steps]


def delay_weights(delay_steps, sizes: list[int]):
    """Hat weights (Σ P_i,) of every module's buffer for Δ/dt = ``delay_steps`` (N,)."""
    parts = []
    for i, size in enumerate(sizes):
        k = np.arange(size, dtype=float)
        parts.append(ca.fmax(0, 1 - ca.fabs(delay_steps[i] - k)))
    return ca.vertcat(*parts)


@dataclass(frozen=True)
class SymbolicModel:
    """Sizes and layout of the symbolic step for N-segment bodies.

    State x = [θ (N), θ̇ (N), ∫ε (N), α̂_FS (1), buffers (Σ P_i)]; step input
    u = [n, α_FS(t), α̇_FS(t)]; parameters p = [Kp, Ki, Kd, Δ/dt, c, Kpas, Bpas] (7N),
    buffer weights w (Σ P_i) from :func:`delay_weights` and the body's constants b
    (:func:`body_constants`).
    """

    n: int
    sizes: tuple[int, ...]
    dt: float
    deadband_rad_s: float
    smooth: float = 0.0

    @property
    def n_state(self) -> int:
        return 3 * self.n + 1 + sum(self.sizes)


def step_function(model: SymbolicModel) -> ca.Function:
    """One integration step: (x, u, p, w, b) → x_next (SX, see :class:`SymbolicModel`)."""
    n = model.n
    dt = model.dt
    x = ca.SX.sym("x", model.n_state)
    u = ca.SX.sym("u", 3)
    p = ca.SX.sym("p", 7 * n)
    w = ca.SX.sym("w", sum(model.sizes))
    b = ca.SX.sym("b", n_body_constants(n))
    terms = BodyTerms.of(b, n)
    theta, omega = x[0:n], x[n : 2 * n]
    integ, est = x[2 * n : 3 * n], x[3 * n]
    step_n, tilt, tilt_vel = u[0], u[1], u[2]
    kp, ki, kd = p[0:n], p[n : 2 * n], p[2 * n : 3 * n]
    delay, cls = p[3 * n : 4 * n], p[4 * n : 5 * n]
    kpas, bpas = p[5 * n : 6 * n], p[6 * n : 7 * n]

    # COM-above angles and rates from the running sum V_i = Σ_{j≥i} e^{iθ_j} S_j
    s_re, s_im = terms.s_re, terms.s_im
    # and, at the reference posture θ = 0 (docs/model.md), each module's COM-above angle and
    # the servo command that held it at rest before the trial (0 and 0 for a straight chain)
    alpha, alpha_dot, tg, tg_dot = [None] * n, [None] * n, [None] * n, [None] * n
    alpha_ref, hold = [None] * n, [None] * n
    v_re = v_im = vd_re = vd_im = v0_re = v0_im = 0
    for i in range(n - 1, -1, -1):
        c, sn = ca.cos(theta[i]), ca.sin(theta[i])
        e_re = c * s_re[i] - sn * s_im[i]
        e_im = sn * s_re[i] + c * s_im[i]
        v_re, v_im = v_re + e_re, v_im + e_im
        vd_re, vd_im = vd_re - omega[i] * e_im, vd_im + omega[i] * e_re
        r2 = v_re**2 + v_im**2
        r = ca.sqrt(r2)
        alpha[i] = ca.atan2(v_im, v_re)
        alpha_dot[i] = (vd_im * v_re - vd_re * v_im) / r2
        tg[i] = v_im / r
        tg_dot[i] = v_re / r * alpha_dot[i]
        v0_re, v0_im = v0_re + s_re[i], v0_im + s_im[i]
        alpha_ref[i] = ca.atan2(v0_im, v0_re)
        hold[i] = terms.gravity * v0_im - kp[i] * v0_im / ca.sqrt(v0_re**2 + v0_im**2)

    # DEC controller (docs/model.md §2), as in posture_id.simulation.kernel
    ankle_rate = omega[0] - tilt_vel
    est_rate = _deadband(omega[0] - ankle_rate, model.deadband_rad_s, model.smooth)
    beta, beta_rate = est, est_rate
    below, below_rate = tilt, tilt_vel
    tau, integ_next, buffers = [], [], []
    offset = 3 * n + 1
    w_offset = 0
    for i in range(n):
        q = theta[i] - below
        qd = omega[i] - below_rate
        x_com = alpha[i] - alpha_ref[i] - below + beta
        xd_com = alpha_dot[i] - below_rate + beta_rate
        mix = (1 + cls[i]) / 2
        xi = mix * x_com + (1 - mix) * q
        xdi = mix * xd_com + (1 - mix) * qd
        servo = kp[i] * xi + kd[i] * xdi + ki[i] * integ[i] + hold[i]
        size = model.sizes[i]
        old = x[offset : offset + size]
        buf = ca.vertcat(servo, old[: size - 1])
        elapsed = ca.if_else(step_n - delay[i] >= -1e-9, 1, 0)
        delayed = elapsed * ca.dot(w[w_offset : w_offset + size], buf) + (1 - elapsed) * hold[i]
        tau.append(-delayed - kp[i] * tg[i] - kd[i] * tg_dot[i] - kpas[i] * q - bpas[i] * qd)
        integ_next.append(integ[i] + dt * xi)
        buffers.append(buf)
        offset += size
        w_offset += size
        beta, beta_rate = beta + q, beta_rate + qd
        below, below_rate = theta[i], omega[i]
    acc, _, _ = _dynamics_expr(terms, theta, omega, ca.vertcat(*tau))
    omega_next = omega + dt * acc
    theta_next = theta + dt * omega_next
    x_next = ca.vertcat(theta_next, omega_next, *integ_next, est + dt * est_rate, *buffers)
    return ca.Function("dec_step", [x, u, p, w, b], [x_next], ["x", "u", "p", "w", "b"],
                       ["x_next"])


#: Samples per inner block of the rollout (CasADi builds long mapaccums slowly: nest them).
_INNER = 100


def rollout_steps(n_samples: int, sample_every: int) -> int:
    """Steps the rollout's input u must hold for ``n_samples`` samples: whole inner
    blocks, so pad the stimulus past the end (those samples are dropped)."""
    blocks = -(-(n_samples - 1) // _INNER)
    return blocks * _INNER * sample_every


#: Inner blocks of 100 samples in one block of the compiled fit model (which simulates a
#: recording block by block, so its length is not compiled in). CasADi's derivative of a
#: longer loop costs less per sample: one Jacobian chunk of a 121 s recording (11 columns)
#: took 2.16 s with blocks of 10 padded to whole blocks, 2.39 s with 5 and 2.35 s with 20,
#: against 1.8 s for the whole recording compiled as one loop (measured side by side
#: here). Running the rest in blocks of one instead of a padded block saved 7 % (2.01 s)
#: but the second function took the 3-segment compile from 11 s to 16 s: not kept.
BLOCK_INNER = 10
#: Samples of one block of the compiled fit model.
BLOCK_SAMPLES = _INNER * BLOCK_INNER


def block_function(model: SymbolicModel, sample_every: int,
                   inner_blocks: int = BLOCK_INNER) -> ca.Function:
    """(x0, u (3, inner_blocks·100·sample_every), p, w, b) → (x_end, θ (N, inner_blocks·100)):
    one block of the rollout, the step folded ``sample_every`` times per sample and
    accumulated over blocks of 100 samples, ``inner_blocks`` of them (CasADi
    ``fold``/``mapaccum``: loops); θ the segment angles at the end of each sample."""
    step = step_function(model)
    inner = step.fold(sample_every).mapaccum("block", _INNER)
    x0 = ca.MX.sym("x0", model.n_state)
    u_block = ca.MX.sym("u", 3, _INNER * sample_every)
    p = ca.MX.sym("p", 7 * model.n)
    w = ca.MX.sym("w", sum(model.sizes))
    b = ca.MX.sym("b", n_body_constants(model.n))
    states = inner(x0, u_block, p, w, b)
    block = ca.Function("block", [x0, u_block, p, w, b],
                        [states[:, -1], states[: model.n, :]])
    if inner_blocks == 1:
        return block
    chained = block.mapaccum("blocks", inner_blocks, [0], [0])
    u_all = ca.MX.sym("u", 3, inner_blocks * _INNER * sample_every)
    x_ends, theta = chained(x0, u_all, p, w, b)
    return ca.Function("block", [x0, u_all, p, w, b], [x_ends[:, -1], theta])


def rollout_function(model: SymbolicModel, n_samples: int, sample_every: int) -> ca.Function:
    """(u (3, rollout_steps), p (7N,), w, b) → θ samples (N, S) at t = 0, every·dt, …

    The step is folded ``sample_every`` times per sample, accumulated over blocks of 100
    samples, and the blocks accumulated over the trial (CasADi ``fold``/``mapaccum``:
    loops, not an unrolled graph). u holds [step index, α_FS, α̇_FS] per step.
    """
    block = block_function(model, sample_every, 1)
    p = ca.MX.sym("p", 7 * model.n)
    w = ca.MX.sym("w", sum(model.sizes))
    b = ca.MX.sym("b", n_body_constants(model.n))
    blocks = -(-(n_samples - 1) // _INNER)
    trial = block.mapaccum("trial", blocks, [0], [0])
    u = ca.MX.sym("u", 3, rollout_steps(n_samples, sample_every))
    _, theta = trial(ca.DM.zeros(model.n_state), u, p, w, b)
    theta = ca.horzcat(ca.DM.zeros(model.n, 1), theta[:, : n_samples - 1])
    return ca.Function("rollout", [u, p, w, b], [theta], ["u", "p", "w", "b"], ["theta"])
