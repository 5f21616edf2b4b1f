"""Standard errors that follow the residual's structure, not only its size.

The Gauss-Newton covariance σ²(JᵀJ)⁻¹ assumes every residual independent with one SD σ.
A locked fit's residual is the weighted stimulus-locked harmonics of every channel
(:class:`~posture_id.frf.locked.LockedProjection`): each channel's harmonic is divided by
its own noise level, so the SDs are one, but the noise of one harmonic is shared by the
channels (a torque noise moves every segment at once, in step or against it) and a misfit
at one harmonic shows in its real and its imaginary part together. Neither is in σ²(JᵀJ)⁻¹.

The cluster-robust ("sandwich") covariance reads them from the residual itself: with the
rows grouped by harmonic (G groups, each harmonic's real and imaginary part of every
channel), the data part J_d and the prior's rows J_p (the same Gaussian prior terms the
fit added; none without a prior),

    H = J_dᵀJ_d + J_pᵀJ_p,   M = Σ_g (J_gᵀ r_g)(J_gᵀ r_g)ᵀ · c + J_pᵀJ_p,
    Cov = H⁻¹ M H⁻¹,   c = G/(G − 1) · (n − 1)/(n − p)

(n data rows, p unknowns; c the usual small-sample correction). With independent
residuals of SD one it is H⁻¹, the Gauss-Newton covariance. The fit's standard errors are
the larger of the two for each unknown: an interval never narrower than the white-noise
one, wider where the recording's noise is shared between channels or the misfit is
concentrated at a few harmonics.
"""

from __future__ import annotations

import numpy as np

__all__ = ["cluster_robust_covariance"]


def cluster_robust_covariance(jacobian: np.ndarray, residual: np.ndarray,
                              clusters: np.ndarray) -> np.ndarray | None:
    """(p, p) cluster-robust covariance of the unknowns, or None when it cannot be formed
    (fewer than two groups, as many rows as unknowns, or a singular Hessian).

    Args:
        jacobian: (R, p) of the whole residual; its last R − n rows are the prior's.
        residual: (R,) at the optimum, the prior's rows last.
        clusters: (n,) the group of each data row (the first n rows), integers ≥ 0.
    """
    jacobian = np.asarray(jacobian, dtype=float)
    residual = np.asarray(residual, dtype=float)
    clusters = np.asarray(clusters)
    n, p = len(clusters), jacobian.shape[1]
    groups = np.unique(clusters)
    if len(groups) < 2 or n <= p:
        return None
    data, prior = jacobian[:n], jacobian[n:]
    information = prior.T @ prior
    hessian = data.T @ data + information
    scores = np.zeros((int(clusters.max()) + 1, p))
    np.add.at(scores, clusters, data * residual[:n, None])
    scores = scores[groups]
    correction = len(groups) / (len(groups) - 1) * (n - 1) / (n - p)
    meat = correction * scores.T @ scores + information
    try:
        inverse = np.linalg.inv(hessian)
    except np.linalg.LinAlgError:
        return None
    if not np.all(np.isfinite(inverse)):
        return None
    return inverse @ meat @ inverse
