"""The entrance every recording passes once: :func:`prepare_trial` → :class:`PreparedTrial`."""

from posture_id.trials.prepared import MIN_ANY_TILT_S, PreparedTrial, prepare_trial

__all__ = ["PreparedTrial", "prepare_trial", "MIN_ANY_TILT_S"]
