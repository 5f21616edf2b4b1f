"""Is a recording like anything the universal network was trained on? A typicality score of
its inputs against the training distribution's.

A network answers whatever it is given; far from every input it was trained on, its answer
is an extrapolation that no calibration covers. Simulation-based inference tests such
misspecification by asking how typical the observed summary statistics are under the
simulator; here the summaries are the network's own inputs (:mod:`~.features.module_frfs`: the
stimulus-locked harmonics' features of each module and the body's and stimulus's
descriptors), standardised by the model's own standardisation.

The reference (:class:`TypicalityReference`, made by :func:`fit_reference` from a
universal set's held-out splits, the distribution the model was trained on):

- the mean and a shrunk covariance (Ledoit and Wolf's shrinkage towards a multiple of
  the identity: the inputs' dimension is in the hundreds) of the module inputs of the
  ``calibration`` split; a module's squared Mahalanobis distance D² from them;
- a recording's score: the largest D² of its modules;
- the same score of every recording of the ``validation`` split (sorted): a new
  recording's tail probability p = (1 + #{reference scores ≥ its score}) / (1 + M).

A recording with p below :data:`ATYPICAL_P` (its score beyond every one of the
reference's recordings, when M ≥ 1000) is *atypical*: the trust verdict doubts it, with
the score named (:mod:`posture_id.identify.verdict`). ``posture-id network universal typicality``
writes the reference beside a model (``typicality.safetensors``), bound to its weights.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from posture_id.errors import PostureIdError
from posture_id.fileio import Result, atomic_write
from posture_id.plotting import plot_shares

__all__ = ["TypicalityReference", "Typicality", "TypicalityReport", "fit_reference",
           "recording_scores", "shrunk_covariance", "ATYPICAL_P",
           "TYPICALITY_FILE"]

#: A recording whose tail probability is below this is atypical (doubted).
ATYPICAL_P = 1e-3
#: The reference's file in a model's folder.
TYPICALITY_FILE = "typicality.safetensors"


def shrunk_covariance(x: np.ndarray) -> tuple[np.ndarray, float]:
    """Ledoit–Wolf covariance of rows ``x`` (M, D), centred: (1 − δ)·S + δ·μI with S the
    sample covariance, μ = tr(S)/D and δ the shrinkage that minimises the expected
    Frobenius loss (Ledoit & Wolf 2004, their estimates of its parts); (D, D) and δ."""
    m, d = x.shape
    if m < 2:
        raise PostureIdError(f"a covariance needs at least 2 samples, got {m}")
    s = x.T @ x / m
    mu = float(np.trace(s)) / d
    dist = float(np.sum((s - mu * np.eye(d)) ** 2))  # d² = ‖S − μI‖²
    # b̄² = 1/M² Σ_k ‖x_k x_kᵀ − S‖² = (Σ_k ‖x_k‖⁴ − M ‖S‖²) / M²
    spread = (float(np.sum(np.sum(x**2, axis=1) ** 2)) - m * float(np.sum(s**2))) / m**2
    delta = 0.0 if dist == 0 else min(1.0, max(0.0, spread / dist))
    return (1 - delta) * s + delta * mu * np.eye(d), delta


def recording_scores(d2: np.ndarray, recording: np.ndarray) -> np.ndarray:
    """The largest module D² of each recording: ``d2`` (M,) per module, ``recording`` (M,)
    the recording each module belongs to; (R,) in the order of first appearance."""
    _, first, inverse = np.unique(recording, return_index=True, return_inverse=True)
    out = np.full(len(first), -np.inf)
    np.maximum.at(out, inverse, d2)
    return out[np.argsort(first)]


@dataclass(frozen=True)
class Typicality:
    """One recording's typicality: its score (the largest module D²), the tail
    probability p of that score among the reference's recordings, how many those were,
    and whether it is atypical (p < :data:`ATYPICAL_P`)."""

    score: float
    p: float
    reference_recordings: int

    @property
    def atypical(self) -> bool:
        return self.p < ATYPICAL_P

    def sentence(self) -> str:
        return (f"its inputs are unlike any the network was trained on: typicality score "
                f"{self.score:.0f} (the largest module's squared Mahalanobis distance), "
                f"reached by a share p = {self.p:.1g} of {self.reference_recordings} "
                "training-like recordings")

    def to_dict(self) -> dict:
        return {"score": self.score, "p": self.p, "atypical": self.atypical,
                "reference_recordings": self.reference_recordings}


@dataclass(frozen=True)
class TypicalityReference:
    """The training distribution's inputs (module docstring).

    Attributes:
        mean: (D,) of the standardised inputs. whitening: (D, D) W with D² = ‖W(x − mean)‖².
        scores: (M,) sorted scores of the reference recordings. shrinkage: δ.
        weights_sha256: the model whose standardisation and inputs these are.
        source: what made it (sets, splits, counts).
    """

    mean: np.ndarray
    whitening: np.ndarray
    scores: np.ndarray
    shrinkage: float
    weights_sha256: str
    source: dict

    def d2(self, standardised: np.ndarray) -> np.ndarray:
        """(M,) squared Mahalanobis distances of standardised module inputs (M, D)."""
        z = (np.asarray(standardised, dtype=np.float64) - self.mean) @ self.whitening.T
        return np.sum(z * z, axis=1)

    def tail(self, score: float) -> float:
        """p of a recording's score among the reference recordings (+1 smoothed)."""
        m = len(self.scores)
        above = m - int(np.searchsorted(self.scores, score, side="left"))
        return (1 + above) / (1 + m)

    def of(self, standardised: np.ndarray) -> Typicality:
        """The typicality of one recording's standardised module inputs (N, D)."""
        score = float(self.d2(standardised).max())
        return Typicality(score, self.tail(score), len(self.scores))

    def save(self, folder: str | Path) -> Path:
        from safetensors.numpy import save

        path = Path(folder) / TYPICALITY_FILE
        meta = {"format": "posture_id-typicality", "weights_sha256": self.weights_sha256,
                "shrinkage": repr(self.shrinkage), "source": json.dumps(self.source)}
        data = save({name: np.ascontiguousarray(value, dtype=np.float64) for name, value in
                     (("mean", self.mean), ("whitening", self.whitening),
                      ("scores", self.scores))}, metadata=meta)
        return atomic_write(path, lambda tmp: tmp.write_bytes(data))

    @classmethod
    def load(cls, folder: str | Path) -> TypicalityReference | None:
        """The reference in a model's folder, or None when it has none; a damaged one is
        refused in one line."""
        from safetensors import SafetensorError, safe_open

        path = Path(folder) / TYPICALITY_FILE
        if not path.exists():
            return None
        try:
            with safe_open(str(path), framework="numpy") as f:
                meta = f.metadata() or {}
                arrays = {k: f.get_tensor(k) for k in ("mean", "whitening", "scores")}
            if meta.get("format") != "posture_id-typicality":
                raise ValueError("not a typicality reference")
            return cls(arrays["mean"].astype(np.float64), arrays["whitening"].astype(np.float64),
                       np.sort(arrays["scores"].astype(np.float64)), float(meta["shrinkage"]),
                       meta["weights_sha256"], json.loads(meta["source"]))
        except (SafetensorError, OSError, ValueError, KeyError) as exc:
            raise PostureIdError(f"{path}: not a readable typicality reference ({exc}); "
                                 "make it again with 'posture-id network universal "
                                 "typicality'") from exc


def fit_reference(fit_inputs: np.ndarray, score_inputs: np.ndarray,
                  score_recordings: np.ndarray, weights_sha256: str, source: dict
                  ) -> TypicalityReference:
    """A reference from standardised module inputs: the mean and shrunk covariance of
    ``fit_inputs`` (M₁, D); the reference scores of the recordings of ``score_inputs``
    (M₂, D), whose recording each module belongs to is ``score_recordings`` (M₂,)."""
    x = np.asarray(fit_inputs, dtype=np.float64)
    mean = x.mean(axis=0)
    cov, delta = shrunk_covariance(x - mean)
    values, vectors = np.linalg.eigh(cov)
    whitening = np.ascontiguousarray(
        (vectors / np.sqrt(np.maximum(values, 1e-12 * values.max()))).T)
    reference = TypicalityReference(mean, whitening, np.zeros(0), delta, weights_sha256,
                                    source)
    scores = recording_scores(reference.d2(score_inputs), np.asarray(score_recordings))
    return TypicalityReference(mean, whitening, np.sort(scores), delta, weights_sha256,
                               {**source, "reference_recordings": int(len(scores))})


@dataclass(frozen=True)
class TypicalityReport(Result):
    """A reference made from sets, and how often it calls the sets' own held-out test
    recordings atypical (its false alarms: about :data:`ATYPICAL_P` if the reference is
    right), overall and by regime."""

    reference: TypicalityReference
    test_recordings: int
    false_alarms: dict[str, tuple[int, int]]

    def to_dict(self) -> dict:
        return {"shrinkage": self.reference.shrinkage, "source": self.reference.source,
                "atypical_p": ATYPICAL_P, "test_recordings": self.test_recordings,
                "false_alarms": {k: {"atypical": a, "recordings": n}
                                 for k, (a, n) in self.false_alarms.items()}}

    def markdown(self) -> str:
        lines = ["# Typicality reference", "",
                 f"Fitted on {self.reference.source['fit_modules']} module inputs of the "
                 "calibration split (Ledoit–Wolf shrinkage "
                 f"{self.reference.shrinkage:.3f}); reference scores of "
                 f"{self.reference.source['reference_recordings']} recordings of the "
                 f"validation split. Held-out test recordings called atypical (p < "
                 f"{ATYPICAL_P:g}):", "", "| recordings | atypical | share |", "|---|---|---|"]
        for key, (atypical, count) in self.false_alarms.items():
            lines.append(f"| {key} ({count}) | {atypical} | {atypical / max(count, 1):.2%} |")
        return "\n".join(lines)

    def summary(self) -> str:
        return self.markdown()

    def plot(self, path=None, ax=None):
        """The test recordings called atypical, per regime, against the share expected."""
        labels = list(self.false_alarms)
        shares = [100 * a / max(n, 1) for a, n in self.false_alarms.values()]
        return plot_shares(labels, shares, 100 * ATYPICAL_P,
                           "test recordings called atypical, %", "expected share", path, ax)
