"""Memory layout of the compiled simulator: lanes, rows of the work and parameter arrays.

Trials run in blocks of :data:`LANES`; every per-trial quantity is a *row* of LANES values
in one flat work array ``w`` (rows listed in :class:`Rows`), parameters are rows of ``par``
(:class:`ParRows`), the delay buffers rows of ``buf`` (:func:`buffer_length`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["LANES", "Rows", "ParRows", "buffer_length"]

#: Trials per block: the SIMD width the lane loops are written for.
LANES = 32


def buffer_length(max_delay_steps: float) -> int:
    """Power-of-two ring-buffer length holding every servo command a delay of
    ``max_delay_steps`` steps reads (the current one included)."""
    need = int(math.floor(max_delay_steps)) + 2
    return 1 << (need - 1).bit_length()


def _rows(k: int) -> property:
    """The offset of the k-th group of N rows, k·N (one row per segment or module)."""
    return property(lambda self: k * self.n)


@dataclass(frozen=True)
class Rows:
    """Row offsets of the work array ``w`` (each row holds LANES values) for N segments."""

    n: int

    theta = _rows(0)  # θ_j, rad
    omega = _rows(1)  # θ̇_j, rad/s
    integral = _rows(2)  # ∫ε_j dt, rad·s
    alpha = _rows(3)  # α_j,S, rad
    alpha_dot = _rows(4)
    tg = _rows(5)  # T_g,j = sin α_j,S
    tg_dot = _rows(6)
    cos = _rows(7)
    sin = _rows(8)
    lever = _rows(9)  # Im(e^{iθ_j} S_j), kg·m
    tau = _rows(10)  # joint torque, N·m
    servo = _rows(11)  # undelayed PID command
    q = _rows(12)  # joint angle
    qd = _rows(13)
    acc = _rows(14)  # θ̈_j
    mass = _rows(15)  # M (N×N rows), its LDLᵀ factors in place
    estimate = property(lambda self: 15 * self.n + self.n * self.n)  # α̂_FS, rad
    estimate_rate = property(lambda self: self.estimate + 1)
    inside = property(lambda self: self.estimate + 2)  # 1.0 while every |θ_j| ≤ sway limit
    # 4N rows: COM-above sums Σ_{j≥i} e^{iθ_j} S_j (re, im), rates
    vsum = property(lambda self: self.estimate + 3)
    # 1/d_j of M = L·diag(d)·Lᵀ (N rows)
    pivot_inverse = property(lambda self: self.estimate + 3 + 4 * self.n)
    # the servo command of the step before (N rows)
    servo_before = property(lambda self: self.estimate + 3 + 5 * self.n)
    count = property(lambda self: self.estimate + 3 + 6 * self.n)


@dataclass(frozen=True)
class ParRows:
    """Row offsets of the parameter array ``par`` for N modules."""

    n: int

    kp = _rows(0)
    ki = _rows(1)
    kd = _rows(2)
    sign = _rows(3)  # class C: +1 COM in space, −1 joint (or between)
    kpas = _rows(4)
    bpas = _rows(5)
    delay = _rows(6)  # Δ/dt, steps (fractional)
    delay_ceil = _rows(7)  # ⌈Δ/dt⌉
    delay_frac = _rows(8)  # ⌈Δ/dt⌉ − Δ/dt
    alpha_ref = _rows(9)  # α_i,S at the reference posture, rad
    hold = _rows(10)  # servo command holding it at rest, N·m
    count = _rows(11)
