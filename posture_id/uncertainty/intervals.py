"""Intervals of every module's Kp, Ki, Kd and Δ, with what they say in words."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from posture_id.dec.parameters import TARGET_FIELDS
from posture_id.plotting import plot_intervals
from posture_id.uncertainty.identifiability import Determination, determination, prior_interval

__all__ = ["ParameterIntervals", "LABELS"]

#: How parameters are named in sentences.
LABELS = {"kp": "Kp", "ki": "Ki", "kd": "Kd", "delay_s": "delay"}


@dataclass(frozen=True)
class ParameterIntervals:
    """Intervals at one level for N modules × [Kp, Ki, Kd, Δ].

    Attributes:
        level: nominal coverage (0.9 = 90 %). method: how they were made (one line).
        lower, upper: (N, 4) normalised p̃ = p/p_default − 1 (never below −1).
        lower_si, upper_si: (N, 4) the same in SI units (N·m/rad, N·m/(rad·s), N·m·s/rad, s).
        ratio: (N, 4) width against the prior's at the same level.
        noise_deg: the recording's estimated sensor noise, °. joints: module names.
        imprecise: (N, 4) bool, or None: least squares' flags of parameters determined to
            worse than ±``precision`` of their value (its 95 % Gauss-Newton interval,
            ``FitResult.poorly_determined``); the sentences say them too, so that the
            words and the flags of one result agree.
        precision: the relative precision those flags were judged by (0.05 = ±5 %).
    """

    level: float
    method: str
    lower: np.ndarray
    upper: np.ndarray
    lower_si: np.ndarray
    upper_si: np.ndarray
    ratio: np.ndarray
    noise_deg: float
    joints: tuple[str, ...]
    imprecise: np.ndarray | None = None
    precision: float = 0.05

    @classmethod
    def around(cls, estimate: np.ndarray, half_width: np.ndarray, defaults: np.ndarray,
               level: float, method: str, noise_deg: float, joints: tuple[str, ...],
               imprecise: np.ndarray | None = None, precision: float = 0.05
               ) -> ParameterIntervals:
        """estimate ± half_width (both (N, 4) normalised), cut at p̃ = −1; ``defaults``
        (N, 4) the SI defaults p_default."""
        lower = np.maximum(estimate - half_width, -1.0)
        upper = estimate + half_width
        ratio, _ = determination(upper - lower, level)
        return cls(level, method, lower, upper, defaults * (1 + lower), defaults * (1 + upper),
                   ratio, float(noise_deg), tuple(joints),
                   None if imprecise is None else np.asarray(imprecise, bool), precision)

    def widened(self, estimate: np.ndarray, factor: np.ndarray, defaults: np.ndarray,
                why: str) -> ParameterIntervals:
        """Each side's half-width about ``estimate`` ((N, 4) normalised) times ``factor``
        ((4,) or (N, 4), ≥ 1), cut at p̃ = −1; ``defaults`` (N, 4) the SI defaults;
        ``why`` is added to :attr:`method`."""
        estimate = np.asarray(estimate, dtype=float)
        factor = np.broadcast_to(np.asarray(factor, dtype=float), estimate.shape)
        lower = np.maximum(estimate - factor * (estimate - self.lower), -1.0)
        upper = estimate + factor * (self.upper - estimate)
        ratio, _ = determination(upper - lower, self.level)
        return replace(self, method=f"{self.method}; {why}", lower=lower, upper=upper,
                       lower_si=defaults * (1 + lower), upper_si=defaults * (1 + upper),
                       ratio=ratio)

    @property
    def words(self) -> np.ndarray:
        """(N, 4) :class:`Determination`."""
        return determination(self.upper - self.lower, self.level)[1]

    def sentences(self) -> list[str]:
        """One sentence per module for what the recording leaves undetermined or only
        partly determined, e.g. "the knee's Ki is not determined by this recording", and,
        with least squares' flags, what is determined against the prior but to worse than
        ±``precision`` of its value."""
        out = []
        words = self.words
        for i, (j, row) in enumerate(zip(self.joints, words, strict=True)):
            for kind in (Determination.NOT, Determination.PARTLY):
                names = [LABELS[f] for f, w in zip(TARGET_FIELDS, row, strict=True) if w is kind]
                if names:
                    verb = "is" if len(names) == 1 else "are"
                    out.append(f"the {j}'s {' and '.join(names)} {verb} {kind.value} by this "
                               "recording")
            if self.imprecise is not None:
                names = [LABELS[f] for k, f in enumerate(TARGET_FIELDS)
                         if self.imprecise[i, k] and row[k] is Determination.WELL]
                if names:
                    verb = "is" if len(names) == 1 else "are"
                    out.append(f"the {j}'s {' and '.join(names)} {verb} determined to worse "
                               f"than ±{100 * self.precision:g} % of the value (poorly "
                               "determined, 95 % Gauss-Newton interval)")
        return out

    def table(self) -> list[str]:
        """Printable lines: each module's intervals in SI units, then the sentences."""
        lines = [f"{100 * self.level:g} % intervals ({self.method}; sensor noise about "
                 f"{self.noise_deg:.3f}°):",
                 f"{'module':<10}" + "".join(f"{LABELS[f]:>22}" for f in TARGET_FIELDS)]
        for i, j in enumerate(self.joints):
            cells = [f"[{self.lower_si[i, k]:.4g}, {self.upper_si[i, k]:.4g}]"
                     for k in range(len(TARGET_FIELDS))]
            lines.append(f"{j:<10}" + "".join(f"{c:>22}" for c in cells))
        return lines + [s[0].upper() + s[1:] + "." for s in self.sentences()]

    def plot(self, estimate: np.ndarray, path=None, ax=None):
        """Each parameter's interval around ``estimate`` ((N, 4) normalised), the prior's
        interval shaded (:func:`posture_id.plotting.plot_intervals`)."""
        return plot_intervals(self.joints, estimate, self.lower, self.upper,
                              [[w.value for w in row] for row in self.words],
                              prior_interval(self.level), self.level, self.method, path, ax)

    def to_dict(self) -> dict:
        words = self.words
        return {"level": self.level, "method": self.method, "noise_deg": self.noise_deg,
                "modules": {j: {f: {"lower": float(self.lower[i, k]),
                                    "upper": float(self.upper[i, k]),
                                    "lower_si": float(self.lower_si[i, k]),
                                    "upper_si": float(self.upper_si[i, k]),
                                    "width_to_prior": float(self.ratio[i, k]),
                                    "determination": words[i, k].value}
                                for k, f in enumerate(TARGET_FIELDS)}
                            for i, j in enumerate(self.joints)},
                "in_words": self.sentences()}
