"""The body-sway errors of docs/model.md §7, in one place: E_id and E_rel."""

from __future__ import annotations

import numpy as np

__all__ = ["sway_errors"]


def sway_errors(reference: np.ndarray, simulated: np.ndarray,
                fell: np.ndarray | bool | None = None) -> tuple[np.ndarray, np.ndarray]:
    """E_id (degrees) and E_rel (fraction) of simulated against reference body sway α_BS.

    E_id = ‖α_ref − α_sim‖ / S (in degrees) and E_rel = ‖α_ref − α_sim‖ / ‖α_ref‖ over the
    S samples of each trial; both are ∞ where the simulation fell (``fell``, or a sway that
    is not finite).

    Args:
        reference, simulated: (..., S) rad, the same shape.
        fell: (...) bool, trials known to have fallen (default: none beyond non-finite).

    Returns:
        (e_id_deg, e_rel), each of shape (...) (0-d arrays for one trial: use ``float``).
    """
    reference = np.asarray(reference, dtype=float)
    diff = reference - np.asarray(simulated, dtype=float)
    fallen = ~np.all(np.isfinite(diff), axis=-1)
    if fell is not None:
        fallen = fallen | np.asarray(fell, dtype=bool)
    with np.errstate(invalid="ignore"):
        distance = np.linalg.norm(np.where(np.isfinite(diff), diff, 0.0), axis=-1)
        e_id = np.degrees(distance) / reference.shape[-1]
        e_rel = distance / np.linalg.norm(reference, axis=-1)
    return np.where(fallen, np.inf, e_id), np.where(fallen, np.inf, e_rel)
