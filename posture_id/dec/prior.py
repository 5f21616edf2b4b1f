"""Random DEC parameters around a body's defaults (docs/model.md §5).

Per trial and module: X ~ N(0, σ²) with σ = 0.5 **[decision: read as a standard
deviation]**, p = p_default·|1 + X| for Kp, Ki, Kd and Δ independently; the class is
±1 with probability ½ each; passive terms stay at their defaults.
"""

from __future__ import annotations

import numpy as np

from posture_id.bodies.body import Body
from posture_id.dec.parameters import ParameterArrays, default_parameters

__all__ = ["sample_parameters", "relative_factors", "SIGMA"]

#: Standard deviation of the relative perturbation X (docs/model.md §5).
SIGMA = 0.5


def relative_factors(rng: np.random.Generator, shape, sigma: float = SIGMA) -> np.ndarray:
    """|1 + X|, X ~ N(0, σ²), of the given shape: p / p_default under the prior.

    The normalised value p̃ of docs/model.md §3 is this minus one.
    """
    return np.abs(1.0 + sigma * rng.standard_normal(shape))


def sample_parameters(body: Body, n_trials: int, rng: np.random.Generator,
                      sigma: float = SIGMA) -> ParameterArrays:
    """(n_trials, N) random parameters for ``body`` drawn from ``rng`` (see module doc).

    Args:
        body: the body whose defaults are perturbed (N = its segments).
        n_trials: B, the number of parameter sets drawn.
        rng: the random generator drawn from.
        sigma: σ, the standard deviation of the relative perturbation X (default
            :data:`SIGMA`).
    Returns:
        :class:`ParameterArrays` (n_trials, N), SI units; passive terms at the defaults.
    """
    defaults = default_parameters(body)
    shape = (n_trials, body.n_segments)

    def perturbed(field: str) -> np.ndarray:
        return defaults.array(field) * relative_factors(rng, shape, sigma)

    kp, ki, kd, delay = (perturbed(f) for f in ("kp", "ki", "kd", "delay_s"))
    sign = np.where(rng.random(shape) < 0.5, 1.0, -1.0)
    return ParameterArrays(
        kp=kp, ki=ki, kd=kd, delay_s=delay, sign=sign,
        kpas=np.broadcast_to(defaults.array("kpas"), shape),
        bpas=np.broadcast_to(defaults.array("bpas"), shape),
    )
