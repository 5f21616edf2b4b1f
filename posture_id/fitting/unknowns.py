"""The fit's vector of unknowns and the (N, 5) targets of MODEL §3: one conversion.

q (5N,) is field-major: K̃p of every module (support upward), then K̃i, K̃d, Δ̃ and
last the class values c; targets (N, 5) hold [K̃p, K̃i, K̃d, Δ̃, C] per module. The
continuous part is q[:4N]; the classes are q[4N:].
"""

from __future__ import annotations

import numpy as np

__all__ = ["q_from_targets", "targets_from_q", "targets_from_qs"]


def q_from_targets(targets: np.ndarray) -> np.ndarray:
    """(N, 5) targets → (5N,) q."""
    return np.asarray(targets, dtype=float).T.ravel().copy()


def targets_from_q(q: np.ndarray) -> np.ndarray:
    """(5N,) q → (N, 5) targets."""
    return targets_from_qs(np.asarray(q)[None])[0]


def targets_from_qs(qs: np.ndarray) -> np.ndarray:
    """(B, 5N) unknown vectors → (B, N, 5) targets."""
    qs = np.asarray(qs, dtype=float)
    return qs.reshape(len(qs), 5, -1).transpose(0, 2, 1)
