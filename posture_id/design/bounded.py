"""The error of the least-squares fit held within its bounds, linearised.

Near the true parameters θ the weighted fit minimises ½ δᵀAδ − gᵀδ over the step
δ = θ̂ − θ, with A the weighted information and g = J̄ᵀW̄e the noise's pull,
g ~ N(0, B) (:mod:`.information`). Unbounded, δ̂ = A⁻¹g has the covariance A⁻¹BA⁻¹
that the design's widths come from. But the fit keeps every gain and delay within its
search range (:class:`~posture_id.fitting.options.FitOptions` ``gain_bounds`` and
``delay_bounds``): where the sway says little about a parameter, its error is capped
by that range, and so, through their correlation, are the errors of the parameters
estimated together with it. The RMS error a fit actually shows is therefore that of the
box-constrained quadratic's minimiser, which this module draws by Monte Carlo:

    δ̂ = argmin ½ δᵀAδ − gᵀδ   subject to   lower − θ ≤ δ ≤ upper − θ,

for ``draws`` independent g. Directions A does not see (eigenvalue below
:data:`~.information.RANK_TOLERANCE` of the largest, :func:`~.information.unit_diagonal`)
are left where the fit starts (δ = 0 there); a parameter with no information of its own
at all is reported with an unbounded error, as its width is.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import lsq_linear

from posture_id.design.information import Information, unit_diagonal
from posture_id.fitting.least_squares import search_bounds
from posture_id.fitting.options import FitOptions
from posture_id.fitting.unknowns import UnknownLayout

__all__ = ["bounded_errors", "fit_bounds"]

#: Ridge (share of the largest eigenvalue of the scaled A) that makes the constrained
#: minimiser unique along directions the sway does not see: the fit stays at its start.
RIDGE = 1e-10


def fit_bounds(n_modules: int) -> tuple[np.ndarray, np.ndarray]:
    """(4N,) lower and upper bounds of [K̃p×N, K̃i×N, K̃d×N, Δ̃×N]: the fit's own
    (:func:`~posture_id.fitting.least_squares.search_bounds` with the
    :class:`~posture_id.fitting.options.FitOptions` defaults)."""
    layout = UnknownLayout(n_modules)
    lower, upper = search_bounds(FitOptions(), layout)
    return lower[layout.gains_delays], upper[layout.gains_delays]


def bounded_errors(info: Information, truth: np.ndarray, lower: np.ndarray,
                   upper: np.ndarray, draws: int, rng: np.random.Generator) -> np.ndarray:
    """(draws, P) errors δ̂ of the linearised weighted fit held within ``lower`` ≤ θ + δ
    ≤ ``upper``, for true parameters ``truth`` (P,) (module docstring); ∞ in the
    columns of parameters with no information of their own."""
    a = 0.5 * (info.weighted + info.weighted.T)
    b = 0.5 * (info.spread + info.spread.T)
    own, scale, values, vectors, seen = unit_diagonal(a)
    out = np.zeros((draws, len(truth)))
    out[:, ~own] = np.inf
    if not own.any():
        return out
    scale = scale[own]  # x = δ / scale: every parameter's information 1
    b_s = b[np.ix_(own, own)] * np.outer(scale, scale)
    largest = float(values.max())
    # g ~ N(0, B): through B's own square root (B is positive semi-definite)
    b_values, b_vectors = np.linalg.eigh(b_s)
    root = b_vectors * np.sqrt(np.clip(b_values, 0.0, None))
    g = rng.standard_normal((draws, len(b_values))) @ root.T  # (draws, P_own)
    # unbounded: the minimum-norm minimiser (nothing moves along unseen directions)
    x = (g @ vectors[:, seen] / values[seen]) @ vectors[:, seen].T
    lo = (lower[own] - truth[own]) / scale
    hi = (upper[own] - truth[own]) / scale
    outside = np.any((x < lo) | (x > hi), axis=1)
    if outside.any():
        # ½‖Lx − c‖² = ½xᵀAx − gᵀx + const with L = √Λ Vᵀ (seen directions), c = Λ^-½ Vᵀg;
        # a small ridge keeps the minimiser unique where the sway sees nothing
        ridge = np.sqrt(RIDGE * largest)
        lhs = np.vstack([np.sqrt(values[seen])[:, None] * vectors[:, seen].T,
                         ridge * np.eye(len(lo))])
        inner_lo, inner_hi = np.minimum(lo, 0.0), np.maximum(hi, 0.0)
        for k in np.flatnonzero(outside):
            rhs = np.r_[(g[k] @ vectors[:, seen]) / np.sqrt(values[seen]), np.zeros(len(lo))]
            x[k] = lsq_linear(lhs, rhs, bounds=(inner_lo, inner_hi), method="bvls").x
    out[:, own] = x * scale
    return out
