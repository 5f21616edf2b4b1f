"""Intervals widened by what the recording's own noise does: a second calibration for
people-like sway, conditioned on the noise the recording itself shows.

The network's conformal intervals (:mod:`posture_id.learning.calibration`) hold
on the noise families it was calibrated on. On people-like sway of other shapes they may
not: on the honest verdict's people-like subjects two families had their true Kp inside
the 90 % intervals for 83 % of modules (``docs/results/widening/report.md``). What the
recording's own noise leaves of its stimulus-locked sway is measured on the recording
itself, from the scatter of its locked response between cycles
(:attr:`~posture_id.identify.noise_check.NoiseCheck.noise_relative`), so an interval can
widen with it.

The widening: on calibration subjects (people-like subjects of every noise family the
project simulates, drawn apart from any benchmark's, identified by the default method),
the score of each module's parameter is s = |p̃_true − p̃| / h, h the half-width of its
interval (normalised units); the recordings are split into :data:`BINS` bins of their noise
share at its quantiles, and each bin's factor per parameter is the split-conformal
quantile of its scores at the intervals' level, never below 1 (an interval is widened,
never narrowed). A people-like recording's half-widths are multiplied by its bin's
factors. **[decision]** Bins rather than a fitted trend: few calibration subjects, and a
bin's conformal quantile needs no form assumed.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from posture_id.errors import PostureIdError
from posture_id.fileio import atomic_write_text, json_text
from posture_id.uncertainty.conformal import conformal_quantile

__all__ = ["BINS", "WIDENING_FILE", "RecordingWidening", "fit_widening", "scores_of"]

#: Bins of the recording's noise share.
BINS = 2
#: The file beside a model's weights.
WIDENING_FILE = "widening.json"


def scores_of(estimate: np.ndarray, truth: np.ndarray, lower: np.ndarray,
              upper: np.ndarray) -> np.ndarray:
    """(..., 4) s = |truth − estimate| / h with h the interval's half-width on the side of
    the truth (an interval cut at p̃ = −1 is narrower below), all normalised."""
    estimate, truth = np.asarray(estimate, float), np.asarray(truth, float)
    above = truth >= estimate
    half = np.where(above, np.asarray(upper) - estimate, estimate - np.asarray(lower))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(half > 0, np.abs(truth - estimate) / half, np.inf)


@dataclass(frozen=True)
class RecordingWidening:
    """Factors (≥ 1) on the half-widths of people-like recordings, per bin of their noise
    share (the module doc).

    Attributes:
        level: the intervals' level the factors were calibrated at.
        edges: (BINS − 1,) noise-share bin edges.
        factors: (BINS, 4) per bin, Kp, Ki, Kd, Δ.
        counts: (BINS,) calibration modules per bin.
        weights_sha256: of the model calibrated.
        made_by: the command that made it.
    """

    level: float
    edges: tuple[float, ...]
    factors: tuple[tuple[float, ...], ...]
    counts: tuple[int, ...]
    weights_sha256: str
    made_by: str = ""

    def factor(self, noise_relative: float) -> np.ndarray:
        """(4,) the factors of a recording whose noise leaves ``noise_relative`` of its
        locked sway."""
        k = int(np.searchsorted(self.edges, noise_relative, side="right"))
        return np.asarray(self.factors[k], dtype=float)

    def to_dict(self) -> dict:
        return {"format": "posture_id-recording-widening", "level": self.level,
                "edges": list(self.edges), "factors": [list(f) for f in self.factors],
                "counts": list(self.counts), "weights_sha256": self.weights_sha256,
                "made_by": self.made_by}

    def save(self, folder: str | Path) -> Path:
        return atomic_write_text(Path(folder) / WIDENING_FILE, json_text(self.to_dict()))

    @classmethod
    def load(cls, folder: str | Path) -> RecordingWidening | None:
        """The widening beside a model (None when there is none)."""
        file = Path(folder) / WIDENING_FILE
        if not file.exists():
            return None
        try:
            data = json.loads(file.read_text(encoding="utf-8"))
            if data.get("format") != "posture_id-recording-widening":
                raise KeyError("format")
            out = cls(float(data["level"]), tuple(float(e) for e in data["edges"]),
                      tuple(tuple(float(v) for v in row) for row in data["factors"]),
                      tuple(int(c) for c in data["counts"]), str(data["weights_sha256"]),
                      str(data.get("made_by", "")))
        except (json.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
            raise PostureIdError(f"{file}: not a recording widening ({exc})") from None
        if (np.shape(out.factors) != (len(out.edges) + 1, 4) or len(out.counts)
                != len(out.factors) or not np.all(np.asarray(out.factors) >= 1.0)):
            raise PostureIdError(f"{file}: its factors are not (bins, 4) values ≥ 1")
        return out


def fit_widening(scores: np.ndarray, noise_relative: np.ndarray, level: float,
                 weights_sha256: str, made_by: str = "") -> RecordingWidening:
    """The widening from (M, 4) calibration ``scores`` (:func:`scores_of`) of M modules
    whose recordings' noise shares are ``noise_relative`` (M,), at ``level``."""
    scores = np.asarray(scores, dtype=float)
    share = np.asarray(noise_relative, dtype=float)
    if len(scores) < 10 * BINS:
        raise PostureIdError(f"{len(scores)} calibration modules are too few for "
                             f"{BINS} bins")
    edges = np.quantile(share, np.arange(1, BINS) / BINS)
    which = np.searchsorted(edges, share, side="right")
    factors, counts = [], []
    for k in range(BINS):
        chosen = scores[which == k]
        counts.append(len(chosen))
        q = conformal_quantile(chosen, level, capped=True)
        factors.append(tuple(float(v) for v in np.maximum(q, 1.0)))
    return RecordingWidening(level, tuple(float(e) for e in edges), tuple(factors),
                             tuple(counts), weights_sha256, made_by)
