"""Vectorisable elementary functions for the compiled simulator.

LLVM cannot vectorise calls to libm's sin, cos and atan2, so the hot loop uses these
polynomial forms instead, evaluated by Estrin's scheme (pairs of terms, then pairs of
pairs, with u², u⁴, u⁸): the simulator is bound by the latency of these chains, which
Estrin's scheme shortens from one multiply-add per term (Horner) to about log₂ of the
number of terms. They are accurate to a few ulp on the ranges the simulator
uses them on (checked against numpy in ``tests/test_fastmath.py``):

- :func:`sin_poly`, :func:`cos_poly`: |x| ≤ π/4 (segment angles; the sway limit is capped
  at 45°, and a lane past the limit is discarded before its angles are used);
- :func:`atan2_poly`: |atan2(y, x)| ≤ π/2, i.e. x ≥ 0 (COM-above angles: the COM stands
  above its joint); three half-angle reductions, then the Taylor series of atan.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = ["sin_poly", "cos_poly", "atan2_poly", "atan2_poly_r", "POLY_MAX_ANGLE"]

#: Largest |x| (rad) for which sin_poly/cos_poly are accurate to ~1e-16.
POLY_MAX_ANGLE = math.pi / 4


@njit(cache=True, inline="always", error_model="numpy")
def sin_poly(x: float) -> float:
    """sin x for |x| ≤ π/4: Taylor series to x¹⁷ (truncation < 1e-19)."""
    u = x * x
    u2 = u * u
    u4 = u2 * u2
    p01 = (1.0 / 6.0 - u * (1.0 / 120.0)) + (1.0 / 5040.0 - u * (1.0 / 362880.0)) * u2
    p23 = ((1.0 / 39916800.0 - u * (1.0 / 6227020800.0))
           + (1.0 / 1307674368000.0 - u * (1.0 / 355687428096000.0)) * u2)
    return x - x * u * (p01 + p23 * u4)


@njit(cache=True, inline="always", error_model="numpy")
def cos_poly(x: float) -> float:
    """cos x for |x| ≤ π/4: Taylor series to x¹⁸ (truncation < 1e-20)."""
    u = x * x
    u2 = u * u
    u4 = u2 * u2
    p01 = (0.5 - u * (1.0 / 24.0)) + (1.0 / 720.0 - u * (1.0 / 40320.0)) * u2
    p23 = ((1.0 / 3628800.0 - u * (1.0 / 479001600.0))
           + (1.0 / 87178291200.0 - u * (1.0 / 20922789888000.0)) * u2)
    return 1.0 - u * ((p01 + p23 * u4) + (1.0 / 6402373705728000.0 * u4) * u4)


@njit(cache=True, inline="always", error_model="numpy")
def atan2_poly(y: float, x: float) -> float:
    """atan2(y, x) for x ≥ 0; see :func:`atan2_poly_r`."""
    return atan2_poly_r(y, x, math.sqrt(x * x + y * y))


@njit(cache=True, inline="always", error_model="numpy")
def atan2_poly_r(y: float, x: float, r: float) -> float:
    """atan2(y, x) for x ≥ 0 given r = √(x² + y²), by three half-angle steps and a series.

    atan2(y, x) = 2·atan2(y, x + r); after three steps |t| = |y/x| ≤ tan(π/16) and the
    series of atan to t²¹ is below 1e-17. Passing r saves a square root when the caller
    has it already.
    """
    y2 = y * y
    x = x + r
    x = x + math.sqrt(x * x + y2)
    x = x + math.sqrt(x * x + y2)
    t = y / x
    u = t * t
    u2 = u * u
    u4 = u2 * u2
    u8 = u4 * u4
    p0 = ((1.0 - u * (1.0 / 3.0)) + (1.0 / 5.0 - u * (1.0 / 7.0)) * u2
          + ((1.0 / 9.0 - u * (1.0 / 11.0)) + (1.0 / 13.0 - u * (1.0 / 15.0)) * u2) * u4)
    p1 = (1.0 / 17.0 - u * (1.0 / 19.0)) + (1.0 / 21.0) * u2
    return 8.0 * t * (p0 + p1 * u8)
