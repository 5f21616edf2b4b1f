"""The IC model's body and its closed-loop frequency response (docs/model.md §8).

The body is one rigid inverted pendulum about the ankle, its joints locked upright:
J = 1ᵀ·M(0)·1 (the whole chain turning as one about the ankle; M the mass matrix in the
segments' angles in space) and m·g·h, the ankle's (Pinocchio). With
N(s) = Kp + Kd·s + Ki/s, D(s) = e^{−sΔ}, P(s) = Kpas + Bpas·s and
F(s) = (G/m·g·h)/(τ_f·s + 1), the tilt-to-COM-sway response is

    H(s) = (P + W·N·D) / ((J·s² − m·g·h)·(1 − F·N·D) + P + N·D).

:func:`closed_loop` gives H and its derivatives with respect to every parameter
(analytic: the fit's exact Jacobian); :func:`is_stable` decides the closed loop's
stability from its characteristic equation with the delay as a Padé approximant.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from posture_id.models.ic.parameters import IcParameters

__all__ = ["IcPlant", "closed_loop", "is_stable", "PARAMETER_ORDER", "rightmost_pole"]

#: The order of the derivatives :func:`closed_loop` returns.
PARAMETER_ORDER = ("kp", "kd", "ki", "delay_s", "w", "torque_feedback_gain",
                   "torque_feedback_time_s", "kpas", "bpas")
#: Order of the Padé approximant of e^{−sΔ} in :func:`is_stable`.
PADE_ORDER = 10


@dataclass(frozen=True)
class IcPlant:
    """The body as the IC model sees it. inertia: J, kg·m² about the ankle axis.
    mgh: N·m/rad, total mass × g × COM height."""

    inertia: float
    mgh: float

    @classmethod
    def of(cls, body) -> IcPlant:
        """J = 1ᵀ·M(θ = 0)·1 from the body's mass matrix (the chain turning as one),
        m·g·h of the ankle (Pinocchio)."""
        mass_matrix = np.real(body.coupling) + np.diag(body.inertias)
        return cls(float(mass_matrix.sum()), float(body.mgh[0]))


def closed_loop(params: IcParameters, plant: IcPlant, s: np.ndarray,
                gradient: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """H(s) (shape of ``s``, complex; rad of COM sway per rad of tilt); with
    ``gradient``, also dH/dp (9, ...) in :data:`PARAMETER_ORDER` (SI units)."""
    s = np.asarray(s, dtype=complex)
    p = params
    n = p.kp + p.kd * s + p.ki / s
    d = np.exp(-s * p.delay_s)
    passive = p.kpas + p.bpas * s
    low_pass = p.torque_feedback_time_s * s + 1.0
    f = (p.torque_feedback_gain / plant.mgh) / low_pass
    body = plant.inertia * s ** 2 - plant.mgh
    nd = n * d
    numerator = passive + p.w * nd
    denominator = body * (1.0 - f * nd) + passive + nd
    h = numerator / denominator
    if not gradient:
        return h
    # derivatives of the numerator and denominator through N·D, P and F
    d_nd = {"kp": d, "kd": s * d, "ki": d / s, "delay_s": -s * nd}
    grads = []
    for name in PARAMETER_ORDER:
        if name in d_nd:
            dn, dd = p.w * d_nd[name], body * (-f * d_nd[name]) + d_nd[name]
        elif name == "w":
            dn, dd = nd, 0.0
        elif name == "torque_feedback_gain":
            dn, dd = 0.0, body * (-nd / (plant.mgh * low_pass))
        elif name == "torque_feedback_time_s":
            dn, dd = 0.0, body * (nd * f * s / low_pass)
        elif name == "kpas":
            dn, dd = 1.0, 1.0
        else:  # bpas
            dn, dd = s, s
        grads.append((dn * denominator - numerator * dd) / denominator ** 2)
    return h, np.stack(np.broadcast_arrays(*grads))


def _pade(delay_s: float, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Numerator and denominator coefficients (highest power first) of the [order/order]
    Padé approximant of e^{−sΔ}."""
    from math import factorial

    k = np.arange(order + 1)
    c = np.array([factorial(2 * order - j) * factorial(order)
                  / (factorial(2 * order) * factorial(j) * factorial(order - j)) for j in k])
    num = c * (-delay_s) ** k
    den = c * delay_s ** k
    return num[::-1], den[::-1]


def rightmost_pole(params: IcParameters, plant: IcPlant, order: int = PADE_ORDER) -> float:
    """The largest real part of the closed loop's poles, 1/s (the delay as a Padé
    approximant of ``order``): the closed loop is stable when it is < 0."""
    p = params
    pn, pd = _pade(p.delay_s, order) if p.delay_s > 0 else (np.array([1.0]), np.array([1.0]))
    # N = nn/nd_, F = fn/fd, D = pn/pd
    if p.ki:
        nn, nd_ = np.array([p.kd, p.kp, p.ki]), np.array([1.0, 0.0])
    else:
        nn, nd_ = np.array([p.kd, p.kp]), np.array([1.0])
    g = p.torque_feedback_gain / plant.mgh
    fn, fd = (np.array([g]), np.array([p.torque_feedback_time_s, 1.0])) if g else (
        np.array([0.0]), np.array([1.0]))
    body = np.array([plant.inertia, 0.0, -plant.mgh])
    passive = np.array([p.bpas, p.kpas])
    mul = np.polymul
    # body·(fd·nd_·pd − fn·nn·pn) + passive·fd·nd_·pd + nn·fd·pn = 0
    common = mul(mul(fd, nd_), pd)
    characteristic = np.polyadd(
        mul(body, np.polysub(common, mul(mul(fn, nn), pn))),
        np.polyadd(mul(passive, common), mul(mul(nn, fd), pn)))
    characteristic = np.trim_zeros(characteristic, "f")
    roots = np.roots(characteristic)
    return float(roots.real.max()) if len(roots) else -np.inf


def is_stable(params: IcParameters, plant: IcPlant) -> bool:
    """Whether the closed loop settles (every pole in the left half plane)."""
    return rightmost_pole(params, plant) < -1e-6
