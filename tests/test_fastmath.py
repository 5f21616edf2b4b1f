"""The kernel's vectorisable sin, cos and atan2 against numpy on their ranges."""

from __future__ import annotations

import numpy as np
from numba import njit

from posture_id.simulation.fastmath import POLY_MAX_ANGLE, atan2_poly, cos_poly, sin_poly


@njit
def _apply(x, y):
    out = np.empty((3, x.size))
    for i in range(x.size):
        out[0, i] = sin_poly(x[i])
        out[1, i] = cos_poly(x[i])
        out[2, i] = atan2_poly(y[i], np.abs(x[i]) + 1e-12)
    return out


def test_polynomials_match_numpy():
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.uniform(-POLY_MAX_ANGLE, POLY_MAX_ANGLE, 20000),
                        [0.0, POLY_MAX_ANGLE, -POLY_MAX_ANGLE, 1e-300]])
    y = rng.uniform(-3, 3, x.size) * np.abs(x)  # COM angles up to ±72°
    out = _apply(x, y)
    np.testing.assert_allclose(out[0], np.sin(x), rtol=0, atol=4e-16)
    np.testing.assert_allclose(out[1], np.cos(x), rtol=0, atol=4e-16)
    np.testing.assert_allclose(out[2], np.arctan2(y, np.abs(x) + 1e-12), rtol=0, atol=1e-15)


def test_atan2_up_to_ninety_degrees():
    angle = np.linspace(-np.pi / 2 + 1e-9, np.pi / 2 - 1e-9, 1001)
    out = _apply(np.cos(angle) - 1e-12, np.sin(angle))
    np.testing.assert_allclose(out[2], angle, rtol=0, atol=2e-15)
