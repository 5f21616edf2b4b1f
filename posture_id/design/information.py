"""The information a recording's stimulus-locked harmonics carry about the parameters,
and the covariance of the least-squares estimate made from them.

The locked fit (:class:`~posture_id.frf.locked.LockedProjection`) compares, at every
compared harmonic k and channel m, the complex cycle-averaged DFT of the simulated and
recorded sway, each weighted by the noise level there (the SD of its real and of its
imaginary part). Near the true parameters the residual is linear: r_k = J_k δ + e_k, with
J_k (M, P) complex (the Jacobian of the harmonics) and e_k circular complex noise of
covariance Σ_k = E[e_k e_kᴴ] (M, M), independent between harmonics (the cycle average's
noise is nearly white across harmonics). In real form z_k = [Re r_k; Im r_k]:

    J̄_k = [Re J_k; Im J_k],  C̄_k = ½ [[Re Σ_k, −Im Σ_k], [Im Σ_k, Re Σ_k]],
    W̄_k = diag(1/σ²),  σ²_m = ½ Σ_k,mm (the fit's weights: one channel at a time),

    A = Σ_k J̄_kᵀ W̄_k J̄_k,   B = Σ_k J̄_kᵀ W̄_k C̄_k W̄_k J̄_k,
    cov(δ̂) = A⁻¹ B A⁻¹  (the weighted fit's covariance, the "sandwich"),
    F = Σ_k J̄_kᵀ C̄_k⁻¹ J̄_k  (the Fisher information: the best any fit can do).

With one channel, or noise uncorrelated between channels, A = B = F. Recordings add:
A and B of every recording (and repetition) are summed before the covariance is formed.
A direction of the parameters the harmonics do not see (A singular there) has an
unbounded variance: :func:`covariance` says ∞ for every parameter it involves.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Information", "harmonic_information", "covariance", "real_blocks",
           "unit_diagonal"]

#: An eigenvalue of A below this share of the largest is no information.
RANK_TOLERANCE = 1e-13


def real_blocks(jacobian: np.ndarray, noise: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(K, 2M, P) real Jacobian blocks J̄_k and (K, 2M, 2M) real noise covariances C̄_k of
    complex ``jacobian`` (K, M, P) and circular noise covariances ``noise`` (K, M, M)."""
    jr = np.concatenate([jacobian.real, jacobian.imag], axis=1)
    top = np.concatenate([noise.real, -noise.imag], axis=2)
    bottom = np.concatenate([noise.imag, noise.real], axis=2)
    return jr, 0.5 * np.concatenate([top, bottom], axis=1)


@dataclass(frozen=True)
class Information:
    """What one or more recordings' harmonics say about P parameters.

    Attributes:
        weighted: (P, P) A = J̄ᵀW̄J̄ of the weighted fit.
        spread: (P, P) B = J̄ᵀW̄C̄W̄J̄.
        fisher: (P, P) F = J̄ᵀC̄⁻¹J̄.
    """

    weighted: np.ndarray
    spread: np.ndarray
    fisher: np.ndarray

    def __add__(self, other: Information) -> Information:
        return Information(self.weighted + other.weighted, self.spread + other.spread,
                           self.fisher + other.fisher)

    def __mul__(self, times: float) -> Information:
        """The information of ``times`` independent repetitions."""
        return Information(self.weighted * times, self.spread * times, self.fisher * times)

    __rmul__ = __mul__

    def fit_covariance(self) -> np.ndarray:
        """(P, P) the weighted least-squares estimate's covariance A⁻¹BA⁻¹."""
        return covariance(self.weighted, self.spread)

    def bound(self) -> np.ndarray:
        """(P, P) the Cramér–Rao bound F⁻¹."""
        return covariance(self.fisher)

    def marginal(self, keep: np.ndarray) -> Information:
        """The information about the parameters ``keep`` (indices or mask) when the
        others are known (held at their true values in the fit)."""
        k = np.flatnonzero(keep) if np.asarray(keep).dtype == bool else np.asarray(keep)
        return Information(self.weighted[np.ix_(k, k)], self.spread[np.ix_(k, k)],
                           self.fisher[np.ix_(k, k)])


def harmonic_information(jacobian: np.ndarray, noise: np.ndarray,
                         weighted: bool = True) -> Information:
    """:class:`Information` of harmonics with complex Jacobian ``jacobian`` (K, M, P) and
    circular noise covariances ``noise`` (K, M, M) (module docstring). ``weighted``
    False: the fit weighs every harmonic and channel alike (W̄ = I, the raw fit's
    least squares on every sample, by Parseval, in steady state)."""
    jacobian = np.asarray(jacobian, dtype=complex)
    noise = np.asarray(noise, dtype=complex)
    if jacobian.ndim != 3 or noise.shape != (jacobian.shape[0],) + (jacobian.shape[1],) * 2:
        raise ValueError(f"jacobian (K, M, P) and noise (K, M, M) do not match: "
                         f"{jacobian.shape}, {noise.shape}")
    jr, cr = real_blocks(jacobian, noise)
    variance = np.einsum("kii->ki", cr)  # (K, 2M): ½ Σ_mm for Re and for Im
    if np.any(variance <= 0):
        raise ValueError("every harmonic's noise variance must be > 0")
    wj = jr / variance[:, :, None] if weighted else jr
    weighted = np.einsum("kip,kiq->pq", jr, wj)
    spread = np.einsum("kip,kij,kjq->pq", wj, cr, wj)
    fisher = np.einsum("kip,kiq->pq", jr, np.linalg.solve(cr, jr))
    return Information(weighted, spread, fisher)


def unit_diagonal(a: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                         np.ndarray]:
    """The symmetric information ``a`` (P, P) scaled to unit diagonal (its parameters'
    units and sizes differ by many orders) and decomposed: ``own`` (P,) the parameters with
    information of their own; ``scale`` (P,) 1/√a_ii for them (0 for the others);
    ``values``, ``vectors`` the eigen-decomposition of the scaled a over ``own``;
    ``seen`` the eigenvalues above :data:`RANK_TOLERANCE` of the largest."""
    diag = np.diag(a).copy()
    top = max(float(diag.max(initial=0.0)), 0.0)
    own = diag > 1e-300 + 1e-14 * top
    scale = np.where(own, 1.0 / np.sqrt(np.where(own, diag, 1.0)), 0.0)
    scaled = a * np.outer(scale, scale)
    values, vectors = np.linalg.eigh(scaled[np.ix_(own, own)])
    largest = float(values.max(initial=0.0))
    seen = values > RANK_TOLERANCE * largest if largest > 0 else np.zeros(len(values), bool)
    return own, scale, values, vectors, seen


def covariance(information: np.ndarray, spread: np.ndarray | None = None) -> np.ndarray:
    """(P, P) A⁻¹ (or A⁻¹BA⁻¹ with ``spread`` B); ∞ on the rows and columns of parameters
    that a direction A does not see involves. A is first scaled to unit diagonal (its
    parameters' units and sizes differ by many orders); a parameter with no information
    of its own, or in a direction whose eigenvalue of the scaled A is below
    :data:`RANK_TOLERANCE` of the largest, is not seen."""
    a = 0.5 * (information + information.T)
    own, scale, values, vectors, seen = unit_diagonal(a)
    inverse = np.zeros_like(a)
    inverse[np.ix_(own, own)] = (vectors[:, seen] / values[seen]) @ vectors[:, seen].T
    inverse *= np.outer(scale, scale)
    out = inverse if spread is None else inverse @ spread @ inverse
    blind = ~own
    blind[own] = np.any(np.abs(vectors[:, ~seen]) > 1e-6, axis=1)
    out = np.array(out, dtype=float)
    out[blind, :] = np.inf
    out[:, blind] = np.inf
    return out
