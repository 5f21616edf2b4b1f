"""Do two groups differ, and where? (``posture-id norm compare``)

Each group's members' pseudo-impulse responses (:class:`~posture_id.norms.norm.FrfSet`,
the channels concatenated into one supervector). The difference of the group means, with
a bootstrap confidence band (each group resampled with replacement, ``bootstrap`` times;
the pointwise ``level`` interval of the resampled differences) and where that band leaves
zero; and a permutation test of the distance between the group means,
T = Σ_t (mean_A(t) − mean_B(t))² over the supervector (for several channels the
PERMANOVA statistic of Euclidean distances, up to a constant): the members' labels
shuffled ``permutations`` times, p = (1 + #{T_perm ≥ T}) / (1 + permutations).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from posture_id.errors import PostureIdError
from posture_id.fileio import Result
from posture_id.norms.norm import FrfSet

__all__ = ["GroupComparison", "compare_groups"]


@dataclass(frozen=True)
class GroupComparison(Result):
    """Group A against group B.

    Attributes:
        names: the two groups' names. sizes: their members. p_value: of the permutation
        test. statistic: T. t: (S,) s. channels: (M,). difference: (M, S) mean_A − mean_B
        PIR. low, high: (M, S) its confidence band. leaves_zero: per channel, the spans
        of t (s) where the band excludes zero.
    """

    names: tuple[str, str]
    sizes: tuple[int, int]
    p_value: float
    statistic: float
    permutations: int
    level: float
    t: np.ndarray = field(repr=False)
    channels: tuple[str, ...] = ()
    difference: np.ndarray = field(default=None, repr=False)
    low: np.ndarray = field(default=None, repr=False)
    high: np.ndarray = field(default=None, repr=False)

    @property
    def leaves_zero(self) -> dict[str, list[tuple[float, float]]]:
        out = {}
        dt = float(self.t[1] - self.t[0]) if len(self.t) > 1 else 0.0
        for m, name in enumerate(self.channels):
            outside = (self.low[m] > 0) | (self.high[m] < 0)
            spans, start = [], None
            for k, out_k in enumerate(outside):
                if out_k and start is None:
                    start = k
                if not out_k and start is not None:
                    spans.append((float(self.t[start]), float(self.t[k - 1] + dt)))
                    start = None
            if start is not None:
                spans.append((float(self.t[start]), float(self.t[-1] + dt)))
            out[name] = spans
        return out

    def to_dict(self) -> dict:
        from posture_id.provenance import provenance

        return {"groups": list(self.names), "sizes": list(self.sizes),
                "p_value": self.p_value, "statistic": self.statistic,
                "permutations": self.permutations, "level": self.level,
                "leaves_zero_s": {k: [list(s) for s in v] for k, v in self.leaves_zero.items()},
                "pir": {"t": self.t.tolist(),
                        "difference": {c: self.difference[m].tolist()
                                       for m, c in enumerate(self.channels)},
                        "low": {c: self.low[m].tolist() for m, c in enumerate(self.channels)},
                        "high": {c: self.high[m].tolist()
                                 for m, c in enumerate(self.channels)}},
                "provenance": provenance()}

    def summary(self) -> str:
        a, b = self.names
        lines = [f"{a} ({self.sizes[0]}) against {b} ({self.sizes[1]}): p = "
                 f"{self.p_value:.4f} (permutation test of the distance between the group "
                 f"means, {self.permutations} permutations)"]
        for name, spans in self.leaves_zero.items():
            where = ", ".join(f"{lo:.2f}–{hi:.2f} s" for lo, hi in spans) or "nowhere"
            lines.append(f"  {name}: the {100 * self.level:.0f} % band of the difference "
                         f"leaves zero {where}")
        return "\n".join(lines)

    def plot(self, path=None, ax=None):
        from posture_id.plotting import plot_group_difference

        return plot_group_difference(self, path=path, ax=ax)


def compare_groups(a: FrfSet, b: FrfSet, names: tuple[str, str] = ("A", "B"),
                   permutations: int = 2000, bootstrap: int = 1000, level: float = 0.95,
                   rate_hz: float = 22.0, seed: int = 0) -> GroupComparison:
    """Group ``a`` against group ``b`` (the module doc).

    Args:
        a: group A's members' FRFs (:class:`FrfSet`, at least 2 members).
        b: group B's, at the same frequencies and channels as ``a``'s.
        names: the two groups' names, A's first.
        permutations: the label shuffles of the permutation test.
        bootstrap: the resamples of each group for the difference's confidence band.
        level: the band's pointwise coverage (default 0.95).
        rate_hz: the PIRs' sample rate, Hz (above twice the highest frequency).
        seed: seeds the permutations and the resamples.
    Returns:
        :class:`GroupComparison`: the p-value, the mean PIR difference (M, S) with its band,
        and where the band leaves zero.
    Raises:
        PostureIdError: a group of fewer than 2 members, or groups at different frequencies
            or with different channels.
    """
    if len(a) < 2 or len(b) < 2:
        raise PostureIdError(f"comparing groups needs at least 2 members each, got "
                             f"{len(a)} and {len(b)}")
    if a.frequencies_hz.shape != b.frequencies_hz.shape or not np.allclose(
            a.frequencies_hz, b.frequencies_hz, atol=1e-6):
        raise PostureIdError("the two groups' FRFs are at different frequencies")
    if tuple(a.channels) != tuple(b.channels):
        raise PostureIdError(f"the groups' channels differ: {a.channels} and {b.channels}")
    t, xa = a.pirs(rate_hz)
    _, xb = b.pirs(rate_hz)
    rng = np.random.default_rng(seed)
    both = np.vstack([xa, xb])
    n = len(xa)

    def statistic(x: np.ndarray, first: np.ndarray) -> float:
        return float(np.sum((x[first].mean(axis=0) - x[~first].mean(axis=0)) ** 2))

    labels = np.zeros(len(both), dtype=bool)
    labels[:n] = True
    observed = statistic(both, labels)
    exceed = 0
    for _ in range(permutations):
        exceed += statistic(both, rng.permutation(labels)) >= observed
    p_value = (1 + exceed) / (1 + permutations)
    diffs = np.stack([xa[rng.integers(0, len(xa), len(xa))].mean(axis=0)
                      - xb[rng.integers(0, len(xb), len(xb))].mean(axis=0)
                      for _ in range(bootstrap)])
    m = len(a.channels)
    low = np.quantile(diffs, (1 - level) / 2, axis=0).reshape(m, -1)
    high = np.quantile(diffs, (1 + level) / 2, axis=0).reshape(m, -1)
    difference = (xa.mean(axis=0) - xb.mean(axis=0)).reshape(m, -1)
    return GroupComparison(tuple(names), (len(a), len(b)), float(p_value), observed,
                           permutations, level, t, tuple(a.channels), difference, low, high)
