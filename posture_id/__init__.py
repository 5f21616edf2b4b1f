"""posture_id: identify DEC posture-control parameters from body sway on a tilting support.

Public API (see docs/):

- bodies: :func:`load_body`, :class:`Body`, :data:`DEFAULT_URDF`
- parameters: :class:`DecParameters`, :class:`ModuleParameters`, :class:`ParameterArrays`
- stimulus: :func:`prts`, :func:`tilt_from_array`, :func:`tilt_from_csv`
- simulation: :func:`simulate`, :func:`simulate_batch`, :class:`SimulationOptions`,
  :func:`simulate_reference` (Pinocchio, slow)
- recordings: :class:`Recording`
"""

from posture_id.body import DEFAULT_URDF, Body, load_body
from posture_id.errors import PostureIdError
from posture_id.parameters import DecParameters, ModuleParameters, ParameterArrays
from posture_id.recording import Recording
from posture_id.simulation import (
    BatchResult,
    SimulationOptions,
    SimulationResult,
    simulate,
    simulate_batch,
)
from posture_id.stimulus import TiltProfile, prts, tilt_from_array, tilt_from_csv

__version__ = "0.1.0"

__all__ = [
    "DEFAULT_URDF",
    "Body",
    "load_body",
    "PostureIdError",
    "DecParameters",
    "ModuleParameters",
    "ParameterArrays",
    "Recording",
    "BatchResult",
    "SimulationOptions",
    "SimulationResult",
    "simulate",
    "simulate_batch",
    "simulate_reference",
    "TiltProfile",
    "prts",
    "tilt_from_array",
    "tilt_from_csv",
    "__version__",
]


def simulate_reference(*args, **kwargs):
    """Pinocchio reference simulation; see :func:`posture_id.reference.simulate_reference`."""
    from posture_id.reference import simulate_reference as _ref

    return _ref(*args, **kwargs)
