"""posture_id: identify DEC posture-control parameters from body sway on a tilting support.

The public API; each name lives in the package of its stage (see docs/development.md):

- :mod:`posture_id.bodies`: :func:`load_body`, :class:`Body`, :data:`DEFAULT_URDF`,
  :func:`lump_robot`, :func:`preset_body`
- :mod:`posture_id.dec`: :class:`DecParameters`, :class:`ModuleParameters`,
  :class:`ParameterArrays`, :func:`default_parameters`, :func:`sample_parameters`
- :mod:`posture_id.simulation`: :func:`prts`, :func:`tilt_from_array`,
  :func:`tilt_from_csv`, :func:`simulate`, :func:`simulate_batch`,
  :class:`SimulationOptions`, :func:`simulate_reference` (Pinocchio, slow)
- :class:`Recording` (recordings as CSV)
- :mod:`posture_id.datasets`: :func:`generate_dataset`, :class:`DatasetConfig`,
  :class:`Dataset`
- :mod:`posture_id.fitting` (CasADi): :func:`fit_recording`, :class:`FitOptions`,
  :class:`FitProblem`, :class:`FitResult`

The last two groups, the lumping and the reference path load on first use, so that
``import posture_id`` does not import CasADi, Dask or example-robot-data.
"""

from posture_id._lazy import lazy_getattr
from posture_id._version import __version__
from posture_id.bodies import DEFAULT_URDF, Body, load_body
from posture_id.dec import (
    DecParameters,
    ModuleParameters,
    ParameterArrays,
    default_parameters,
    sample_parameters,
)
from posture_id.errors import PostureIdError
from posture_id.recording import Recording
from posture_id.simulation import (
    BatchResult,
    SimulationOptions,
    SimulationResult,
    TiltProfile,
    prts,
    simulate,
    simulate_batch,
    tilt_from_array,
    tilt_from_csv,
)

__all__ = [
    "DEFAULT_URDF",
    "Body",
    "load_body",
    "PostureIdError",
    "DecParameters",
    "ModuleParameters",
    "ParameterArrays",
    "default_parameters",
    "sample_parameters",
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
    "FitProblem",
    "FitResult",
    "__version__",
]

_LAZY = {
    "simulate_reference": "posture_id.simulation.reference",
    "lump_robot": "posture_id.bodies.lumping",
    "preset_body": "posture_id.bodies.lumping",
    "generate_dataset": "posture_id.datasets",
    "DatasetConfig": "posture_id.datasets",
    "Dataset": "posture_id.datasets",
    "fit_recording": "posture_id.fitting",
    "FitOptions": "posture_id.fitting",
    "FitProblem": "posture_id.fitting",
    "FitResult": "posture_id.fitting",
}


__getattr__ = lazy_getattr("posture_id", _LAZY)
