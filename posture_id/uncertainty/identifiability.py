"""How much a recording narrows a parameter: its interval's width against the prior's.

The prior is docs/model.md §5's: p̃ = |1 + X| − 1 with X ~ N(0, σ²), σ = 0.5, the distribution the
identifiers were trained and calibrated on. Its central interval at a level is taken from
the folded normal |1 + X| (its quantiles by bisection of its distribution function,
written with the standard library's normal: scipy.stats would cost half a second of every
identification's start-up). A parameter whose interval is
nearly as wide as the prior's was not determined by the recording: the answer is mostly
the prior's typical value.

**[decision]** Words by the ratio r = interval width / prior width at the same level:
r < 0.25 "well determined", r < 0.75 "partly determined", otherwise "not determined".
"""

from __future__ import annotations

import enum
from functools import lru_cache
from statistics import NormalDist

import numpy as np

from posture_id.dec.prior import SIGMA

__all__ = ["Determination", "determination", "prior_interval", "WELL", "PARTLY"]

#: Ratio thresholds of the words (see the module doc).
WELL, PARTLY = 0.25, 0.75


class Determination(enum.Enum):
    """How well a recording determines a parameter."""

    WELL = "well determined"
    PARTLY = "partly determined"
    NOT = "not determined"


@lru_cache(maxsize=64)
def prior_interval(level: float, sigma: float = SIGMA) -> tuple[float, float]:
    """Central interval of the prior's p̃ = |1 + X| − 1 at ``level`` (cached)."""
    low, high = (folded_normal_quantile(q, 1.0, sigma)
                 for q in ((1 - level) / 2, (1 + level) / 2))
    return low - 1.0, high - 1.0


def folded_normal_quantile(q: float, mean: float, sigma: float) -> float:
    """The ``q`` quantile of |Z|, Z ~ N(mean, σ²): the y ≥ 0 where
    Φ((y − mean)/σ) − Φ((−y − mean)/σ) = q, by bisection to the last bit."""
    normal = NormalDist(mean, sigma)
    low, high = 0.0, abs(mean) + 40.0 * sigma
    for _ in range(200):
        middle = 0.5 * (low + high)
        if middle in (low, high):
            break
        if normal.cdf(middle) - normal.cdf(-middle) < q:
            low = middle
        else:
            high = middle
    return 0.5 * (low + high)


def determination(width: np.ndarray, level: float, sigma: float = SIGMA
                  ) -> tuple[np.ndarray, np.ndarray]:
    """(ratio to the prior's width, :class:`Determination` per element) of interval
    widths (normalised units) at ``level``."""
    low, high = prior_interval(level, sigma)
    ratio = np.asarray(width, dtype=float) / (high - low)
    words = np.where(ratio < WELL, Determination.WELL,
                     np.where(ratio < PARTLY, Determination.PARTLY, Determination.NOT))
    return ratio, words
