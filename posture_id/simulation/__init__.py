"""Simulation: the stimulus, the compiled batch simulator and the Pinocchio reference path.

:class:`SimulationOptions` is the one description of *what is modelled* (step, output
rate, sway limit, dead-band); the data-set and fit configurations embed it. Where to run
(threads) is an argument of :func:`simulate_batch`, not an option.
"""

from posture_id.simulation.batch import (
    BatchResult,
    SimulationResult,
    simulate,
    simulate_batch,
)
from posture_id.simulation.options import MAX_DELAY_S, MAX_SWAY_LIMIT_DEG, SimulationOptions
from posture_id.simulation.stimulus import (
    TiltProfile,
    prts,
    recognise_prts,
    tilt_from_array,
    tilt_from_csv,
)

__all__ = [
    "SimulationOptions",
    "SimulationResult",
    "BatchResult",
    "simulate",
    "simulate_batch",
    "simulate_reference",
    "MAX_DELAY_S",
    "MAX_SWAY_LIMIT_DEG",
    "TiltProfile",
    "prts",
    "recognise_prts",
    "tilt_from_array",
    "tilt_from_csv",
]


def __getattr__(name: str):
    if name == "simulate_reference":  # Pinocchio's slow path, for validation
        from posture_id.simulation.reference import simulate_reference

        return simulate_reference
    raise AttributeError(f"module 'posture_id.simulation' has no attribute '{name}'")
