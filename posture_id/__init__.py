"""posture_id: identify DEC posture-control parameters from body sway on a tilting support.

Public API (see docs/):

- bodies: :func:`load_body`, :class:`Body`, :data:`DEFAULT_URDF`
- parameters: :class:`DecParameters`, :class:`ModuleParameters`, :class:`ParameterArrays`
- stimulus: :func:`prts`, :func:`tilt_from_array`, :func:`tilt_from_csv`
- simulation: :func:`simulate`, :func:`simulate_batch`, :class:`SimulationOptions`,
  :func:`simulate_reference` (Pinocchio, slow)
- recordings: :class:`Recording`
- real bodies: :func:`lump_robot`, :func:`preset_body`
- training data: :func:`generate_dataset`, :class:`DatasetConfig`, :class:`Dataset`
- least squares (CasADi): :func:`fit_recording`, :class:`FitOptions`, :class:`FitResult`

The last three groups (and :func:`simulate_reference`) load on first use, so that
``import posture_id`` does not import CasADi, Dask or Pinocchio's slow path.
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
    "lump_robot",
    "preset_body",
    "generate_dataset",
    "DatasetConfig",
    "Dataset",
    "fit_recording",
    "FitOptions",
    "FitResult",
    "__version__",
]

_LAZY = {
    "simulate_reference": "posture_id.reference",
    "lump_robot": "posture_id.lumping",
    "preset_body": "posture_id.lumping",
    "generate_dataset": "posture_id.dataset",
    "DatasetConfig": "posture_id.dataset",
    "Dataset": "posture_id.dataset",
    "fit_recording": "posture_id.fit",
    "FitOptions": "posture_id.fit",
    "FitResult": "posture_id.fit",
}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'posture_id' has no attribute '{name}'")
