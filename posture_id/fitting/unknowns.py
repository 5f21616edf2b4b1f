"""The fit's vector of unknowns and the (N, 5) targets of docs/model.md §3: one conversion.

q (7N,) is field-major: K̃p of every module (support upward), then K̃i, K̃d, Δ̃, the class
values c, and last the passive stiffness and damping K̃pas, B̃pas (normalised like the
gains: p/p_default − 1; they stay at the defaults unless ``FitOptions.fit_passive``).
Targets (N, 5) hold [K̃p, K̃i, K̃d, Δ̃, C] per module. The continuous part is q[:4N], the
classes q[4N:5N], the passive terms q[5N:].
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from posture_id.dec.parameters import DecParameters, ParameterArrays, denormalise_arrays

__all__ = ["PER_MODULE", "class_names", "UnknownLayout", "q_from_targets", "targets_from_q",
           "targets_from_qs", "passive_from_qs", "passive_normalised", "parameters_from_qs"]

#: Unknowns per module in q.
PER_MODULE = 7


def class_names(signs) -> str:
    """"com/joint/com" from class values (≥ 0 is COM in space)."""
    return "/".join("com" if s >= 0 else "joint" for s in signs)


def q_from_targets(targets: np.ndarray, passive: np.ndarray | None = None) -> np.ndarray:
    """(N, 5) targets and (N, 2) normalised passive terms (default 0) → (7N,) q."""
    targets = np.asarray(targets, dtype=float)
    passive = np.zeros((len(targets), 2)) if passive is None else np.asarray(passive, float)
    return np.concatenate([targets.T.ravel(), passive.T.ravel()])


def targets_from_q(q: np.ndarray) -> np.ndarray:
    """(7N,) q → (N, 5) targets."""
    return targets_from_qs(np.asarray(q)[None])[0]


def targets_from_qs(qs: np.ndarray) -> np.ndarray:
    """(B, 7N) unknown vectors → (B, N, 5) targets."""
    qs = np.asarray(qs, dtype=float)
    return qs.reshape(len(qs), PER_MODULE, -1)[:, :5].transpose(0, 2, 1)


def passive_from_qs(qs: np.ndarray) -> np.ndarray:
    """(B, 7N) unknown vectors → (B, N, 2) normalised [K̃pas, B̃pas]."""
    qs = np.asarray(qs, dtype=float)
    return qs.reshape(len(qs), PER_MODULE, -1)[:, 5:].transpose(0, 2, 1)


def parameters_from_qs(qs: np.ndarray, defaults: DecParameters) -> ParameterArrays:
    """(B, 7N) unknown vectors → the parameters they stand for, passive terms included
    (classes as they are: ±1, or a relaxed value in between)."""
    params = denormalise_arrays(targets_from_qs(qs), defaults)
    passive = passive_from_qs(qs)
    return replace(params, kpas=params.kpas * (1 + passive[..., 0]),
                   bpas=params.bpas * (1 + passive[..., 1]))


def passive_normalised(params, defaults) -> np.ndarray:
    """(N, 2) [K̃pas, B̃pas] of :class:`~posture_id.dec.parameters.DecParameters`."""
    return np.column_stack([params.array(f) / defaults.array(f) - 1 for f in ("kpas", "bpas")])


@dataclass(frozen=True)
class UnknownLayout:
    """Where each kind of unknown sits in q (7N,) for a body of ``n`` modules."""

    n: int

    @property
    def gains_delays(self) -> slice:
        """K̃p, K̃i, K̃d of every module, then Δ̃: q[:4N]."""
        return slice(0, 4 * self.n)

    @property
    def classes(self) -> slice:
        """The class values c: q[4N:5N]."""
        return slice(4 * self.n, 5 * self.n)

    @property
    def passive(self) -> slice:
        """K̃pas then B̃pas of every module: q[5N:7N]."""
        return slice(5 * self.n, 7 * self.n)

    @property
    def size(self) -> int:
        return PER_MODULE * self.n

    def _indices(self, part: slice) -> list[int]:
        return list(range(part.start, part.stop))

    def continuous(self, fit_passive: bool) -> list[int]:
        """Indices fitted with the classes fixed: gains, delays (and passive terms)."""
        return self._indices(self.gains_delays) + (self._indices(self.passive)
                                                  if fit_passive else [])

    def everything(self, fit_passive: bool) -> list[int]:
        """Indices fitted with the classes relaxed: the continuous ones and the classes."""
        return self._indices(self.gains_delays) + self._indices(self.classes) + (
            self._indices(self.passive) if fit_passive else [])

    def per_unknown(self, gains_delays: float, classes: float, passive: float) -> np.ndarray:
        """(7N,) with one value for each kind of unknown (bounds, prior SDs)."""
        out = np.empty(self.size)
        out[self.gains_delays], out[self.classes], out[self.passive] = (
            gains_delays, classes, passive)
        return out
