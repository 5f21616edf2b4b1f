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


@dataclass(frozen=True)
class Rows:
    """Row offsets of the work array ``w`` (each row holds LANES values) for N segments."""

    n: int

    @property
    def theta(self) -> int:  # θ_j, rad
        return 0

    @property
    def omega(self) -> int:  # θ̇_j, rad/s
        return self.n

    @property
    def integral(self) -> int:  # ∫ε_j dt, rad·s
        return 2 * self.n

    @property
    def alpha(self) -> int:  # α_j,S, rad
        return 3 * self.n

    @property
    def alpha_dot(self) -> int:
        return 4 * self.n

    @property
    def tg(self) -> int:  # T_g,j = sin α_j,S
        return 5 * self.n

    @property
    def tg_dot(self) -> int:
        return 6 * self.n

    @property
    def cos(self) -> int:
        return 7 * self.n

    @property
    def sin(self) -> int:
        return 8 * self.n

    @property
    def lever(self) -> int:  # Im(e^{iθ_j} S_j), kg·m
        return 9 * self.n

    @property
    def tau(self) -> int:  # joint torque, N·m
        return 10 * self.n

    @property
    def servo(self) -> int:  # undelayed PID command
        return 11 * self.n

    @property
    def q(self) -> int:  # joint angle
        return 12 * self.n

    @property
    def qd(self) -> int:
        return 13 * self.n

    @property
    def acc(self) -> int:  # θ̈_j
        return 14 * self.n

    @property
    def mass(self) -> int:  # M (N×N rows), its LDLᵀ factors in place
        return 15 * self.n

    @property
    def estimate(self) -> int:  # α̂_FS, rad
        return 15 * self.n + self.n * self.n

    @property
    def estimate_rate(self) -> int:
        return self.estimate + 1

    @property
    def inside(self) -> int:  # 1.0 while every |θ_j| ≤ sway limit
        return self.estimate + 2

    @property
    def vsum(self) -> int:  # 4N rows: COM-above sums Σ_{j≥i} e^{iθ_j} S_j (re, im), rates
        return self.estimate + 3

    @property
    def pivot_inverse(self) -> int:  # 1/d_j of M = L·diag(d)·Lᵀ (N rows)
        return self.estimate + 3 + 4 * self.n

    @property
    def servo_before(self) -> int:  # the servo command of the step before (N rows)
        return self.estimate + 3 + 5 * self.n

    @property
    def count(self) -> int:
        return self.estimate + 3 + 6 * self.n


@dataclass(frozen=True)
class ParRows:
    """Row offsets of the parameter array ``par`` for N modules."""

    n: int

    kp = property(lambda self: 0)
    ki = property(lambda self: self.n)
    kd = property(lambda self: 2 * self.n)
    sign = property(lambda self: 3 * self.n)  # class C: +1 COM in space, −1 joint (or between)
    kpas = property(lambda self: 4 * self.n)
    bpas = property(lambda self: 5 * self.n)
    delay = property(lambda self: 6 * self.n)  # Δ/dt, steps (fractional)
    delay_ceil = property(lambda self: 7 * self.n)  # ⌈Δ/dt⌉
    delay_frac = property(lambda self: 8 * self.n)  # ⌈Δ/dt⌉ − Δ/dt
    alpha_ref = property(lambda self: 9 * self.n)  # α_i,S at the reference posture, rad
    hold = property(lambda self: 10 * self.n)  # servo command holding it at rest, N·m
    count = property(lambda self: 11 * self.n)
