"""Split conformal intervals, conditioned on the recording's sensor noise.

On calibration trials (never trained on) the score of each module m and parameter p is
s = |p̃_true − p̃_estimated| / σ(x), with σ(x) = 1 for the CNN (:attr:`Normaliser.ABSOLUTE`)
and the Gauss-Newton standard error for least squares (:attr:`Normaliser.STANDARD_ERROR`).
For a level 1 − α the half-width is the ⌈(n + 1)(1 − α)⌉-th smallest of the n scores
(:func:`conformal_quantile`): for a new trial exchangeable with the calibration ones, the
interval estimate ± half-width·σ(x) holds the truth with probability at least 1 − α and at
most 1 − α + 1/(n + 1) (Vovk et al. 2005; Lei et al. 2018).

Exchangeability fails across noise levels (the CNN's errors grow with the sensor noise),
so the quantiles are taken separately at several sensor-noise levels, each calibration
level labelled with the median *estimated* noise of its trials
(:func:`~posture_id.uncertainty.noise.sensor_noise_deg`), and a recording gets the
half-widths linearly interpolated at its own estimated noise (**[decision]**: a Mondrian
split by noise, with geometric interpolation between the calibrated levels; a recording
noisier than the noisiest level gets that level's widths and a notice).

Quantiles are stored on :data:`LEVEL_GRID` (50 % to 99 % in steps of 1 %); a level
between grid points takes the next higher one (conservative).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

from posture_id.errors import PostureIdError

__all__ = ["LEVEL_GRID", "Normaliser", "ConformalCalibration", "conformal_quantile"]

#: The nominal levels a calibration stores (0.50, 0.51, …, 0.99).
LEVEL_GRID = np.round(np.arange(50, 100) / 100, 2)


class Normaliser(enum.Enum):
    """What a score is divided by (see the module doc)."""

    ABSOLUTE = "absolute"
    STANDARD_ERROR = "standard error"


def conformal_quantile(scores: np.ndarray, level: float, capped: bool = False) -> np.ndarray:
    """The split-conformal quantile of (n, ...) ``scores`` along axis 0 at ``level``: the
    ⌈(n + 1)·level⌉-th smallest; when that rank exceeds n (too few scores for the level)
    +inf, or with ``capped`` the largest score. Non-finite scores count as +inf."""
    if not 0 < level < 1:
        raise ValueError(f"a level must be in (0, 1), got {level}")
    scores = np.where(np.isfinite(scores), scores, np.inf)
    n = scores.shape[0]
    rank = math.ceil((n + 1) * level - 1e-9)
    if rank > n and not capped:
        return np.full(scores.shape[1:], np.inf)
    return np.sort(scores, axis=0)[min(rank, n) - 1]


@dataclass(frozen=True)
class ConformalCalibration:
    """Half-width scales of N modules × P parameters at several noise levels.

    Attributes:
        normaliser: :class:`Normaliser`.
        noise_deg: (L,) increasing median estimated sensor noise of each calibration level, °.
        nominal_noise_deg: (L,) the noise SD the calibration trials were given, °.
        levels: (K,) nominal coverage levels (:data:`LEVEL_GRID`).
        scales: (L, K, N, P) conformal quantiles of the scores.
        trials: calibration trials per noise level.
    """

    normaliser: Normaliser
    noise_deg: np.ndarray
    nominal_noise_deg: np.ndarray
    levels: np.ndarray
    scales: np.ndarray
    trials: int

    @classmethod
    def from_scores(cls, normaliser: Normaliser, scores: np.ndarray, noise_deg: np.ndarray,
                    nominal_noise_deg: np.ndarray) -> ConformalCalibration:
        """From (L, n, N, P) scores of n calibration trials at each of L noise levels."""
        order = np.argsort(noise_deg)
        scales = np.stack([np.stack([conformal_quantile(s, lv) for lv in LEVEL_GRID])
                           for s in np.asarray(scores)[order]])
        return cls(normaliser, np.asarray(noise_deg, float)[order],
                   np.asarray(nominal_noise_deg, float)[order], LEVEL_GRID.copy(), scales,
                   int(np.asarray(scores).shape[1]))

    def scale(self, level: float, noise_deg: float) -> np.ndarray:
        """(N, P) half-width scale at ``level`` for a recording of estimated sensor noise
        ``noise_deg`` (interpolated between calibrated noise levels, held beyond them)."""
        k = int(np.searchsorted(self.levels, level - 1e-9))
        if not 0 < level < 1 or k == len(self.levels):
            raise PostureIdError(f"interval level {level:g} is outside the calibrated "
                                 f"{self.levels[0]:g}–{self.levels[-1]:g}")
        table = self.scales[:, k]
        if len(self.noise_deg) == 1:
            return table[0]
        x = float(np.clip(noise_deg, self.noise_deg[0], self.noise_deg[-1]))
        j = int(np.clip(np.searchsorted(self.noise_deg, x) - 1, 0, len(self.noise_deg) - 2))
        w = (x - self.noise_deg[j]) / (self.noise_deg[j + 1] - self.noise_deg[j])
        if w <= 0 or w >= 1:
            return table[j + 1] if w >= 1 else table[j]
        low, high = table[j], table[j + 1]
        with np.errstate(invalid="ignore", divide="ignore"):
            # geometric: scales differ by orders of magnitude between a noise-free level
            # and a noisy one, and a trial just above the former must keep its scale
            mixed = np.where((low > 0) & (high > 0), low ** (1 - w) * high ** w,
                             (1 - w) * low + w * high)
        # an infinite scale (too few calibration trials for the level) stays infinite
        return np.where(np.isinf(low) | np.isinf(high), np.inf, mixed)

    def beyond(self, noise_deg: float) -> bool:
        """True when ``noise_deg`` is above the noisiest calibrated level (by 20 %)."""
        return noise_deg > 1.2 * self.noise_deg[-1] + 1e-6

    def to_dict(self) -> dict:
        return {"normaliser": self.normaliser.value, "noise_deg": self.noise_deg.tolist(),
                "nominal_noise_deg": self.nominal_noise_deg.tolist(),
                "levels": self.levels.tolist(), "trials": self.trials,
                "scales": np.where(np.isfinite(self.scales), self.scales, -1.0).round(6).tolist()}

    @classmethod
    def from_dict(cls, data: dict, name: str) -> ConformalCalibration:
        try:
            scales = np.asarray(data["scales"], dtype=float)
            out = cls(Normaliser(data["normaliser"]), np.asarray(data["noise_deg"], float),
                      np.asarray(data["nominal_noise_deg"], float),
                      np.asarray(data["levels"], float), np.where(scales < 0, np.inf, scales),
                      int(data["trials"]))
        except (KeyError, TypeError, ValueError) as error:
            raise PostureIdError(f"{name}: not a conformal calibration ({error})") from None
        if out.scales.ndim != 4 or out.scales.shape[:2] != (len(out.noise_deg), len(out.levels)):
            raise PostureIdError(f"{name}: calibration tables of inconsistent shapes "
                                 f"{out.scales.shape}")
        return out
