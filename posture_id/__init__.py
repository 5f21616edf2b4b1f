"""posture_id: identify how a body keeps its balance: the parameters of its posture
controller (DEC, or the independent-channel model) from its sway on a tilting platform.

The public API; each name lives in the package of its stage (docs/development.md):

- **Identify a recording**: :func:`read_recording` (CSV or C3D), :func:`identify`,
  :class:`Identifier`, :class:`Method`, :class:`IdentificationResult`,
  :func:`prepare_trial`
- **Bodies**: :func:`load_body`, :class:`Body`, :data:`DEFAULT_URDF`, :func:`lump_robot`
  and :func:`preset_body` (a humanoid's whole-body URDF lumped to a chain)
- **DEC's parameters**: :class:`DecParameters`, :class:`ModuleParameters`,
  :class:`ParameterArrays`, :func:`default_parameters`, :func:`sample_parameters`
- **Simulation**: :func:`prts`, :func:`tilt_from_array`, :func:`tilt_from_csv`,
  :func:`simulate`, :func:`simulate_batch`, :class:`SimulationOptions`,
  :func:`simulate_reference` (Pinocchio, slow)
- **Recordings**: :class:`Recording`, :class:`RecordingColumns` (a lab's columns),
  :class:`TimeUnit`, :class:`MarkerMapping` and :class:`LabAxes` (a C3D trial's markers),
  :class:`ForcePlateColumns` and :func:`com_angle_from_cop` (a force plate's COP),
  :func:`recognise_periodic` (any periodic tilt in a tilt column)
- **Least squares** (CasADi): :func:`fit_recording`, :class:`FitOptions`,
  :class:`FitProblem`, :class:`FitResult`
- **The independent-channel model**: :func:`fit_ic`, :class:`IcFitOptions`,
  :class:`IcParameters`, :func:`simulate_ic`, :func:`compare_models` (DEC against IC),
  :func:`compare_amplitudes`
- **One subject, several trials; a study**: :func:`fit_joint`, :class:`JointFit`,
  :func:`read_manifest`, :func:`run_study`, :class:`StudyOptions`
- **FRFs and norms**: :func:`frequency_response`, :class:`FrfOptions`,
  :class:`FrequencyBands`, :data:`BAND_PRESETS`, :func:`read_frfs`, :class:`FrfSet`,
  :class:`Norm`, :func:`build_norm`, :func:`against_norm`, :func:`compare_groups`,
  :func:`compare_paired` (two conditions within subjects)
- **Training data**: :func:`generate_dataset`, :class:`DatasetConfig`, :class:`Dataset`

Everything but the first groups loads on first use, so that ``import posture_id`` does
not import torch, CasADi, Dask or example-robot-data.
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
from posture_id.recording import AngleUnit, Recording, RecordingColumns, TimeUnit
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
    "RecordingColumns",
    "AngleUnit",
    "TimeUnit",
    "ForcePlateColumns",
    "com_angle_from_cop",
    "recognise_periodic",
    "fit_joint",
    "JointFit",
    "read_manifest",
    "run_study",
    "StudyOptions",
    "compare_paired",
    "read_recording",
    "prepare_trial",
    "identify",
    "Identifier",
    "Method",
    "IdentificationResult",
    "MarkerMapping",
    "LabAxes",
    "fit_ic",
    "IcFitOptions",
    "IcParameters",
    "simulate_ic",
    "compare_models",
    "compare_amplitudes",
    "frequency_response",
    "FrfOptions",
    "FrequencyBands",
    "BAND_PRESETS",
    "read_frfs",
    "FrfSet",
    "Norm",
    "build_norm",
    "against_norm",
    "compare_groups",
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
    "ForcePlateColumns": "posture_id.force_plate.reading",
    "com_angle_from_cop": "posture_id.force_plate.cop",
    "recognise_periodic": "posture_id.simulation.periodic",
    "fit_joint": "posture_id.fitting.joint_conditions",
    "JointFit": "posture_id.fitting.joint_conditions",
    "read_manifest": "posture_id.manifest",
    "run_study": "posture_id.manifest",
    "StudyOptions": "posture_id.manifest",
    "compare_paired": "posture_id.norms.paired",
    "read_recording": "posture_id.trials.reading",
    "prepare_trial": "posture_id.trials",
    "Identifier": "posture_id.identify",
    "Method": "posture_id.identify",
    "IdentificationResult": "posture_id.identify",
    "MarkerMapping": "posture_id.motion_capture.mapping",
    "LabAxes": "posture_id.motion_capture.mapping",
    "fit_ic": "posture_id.fitting.frequency",
    "IcFitOptions": "posture_id.fitting.frequency",
    "IcParameters": "posture_id.models.ic",
    "simulate_ic": "posture_id.models.ic",
    "compare_models": "posture_id.comparison.models",
    "compare_amplitudes": "posture_id.comparison.models",
    "frequency_response": "posture_id.frf",
    "FrfOptions": "posture_id.frf",
    "FrequencyBands": "posture_id.frf.bands",
    "BAND_PRESETS": "posture_id.frf.bands",
    "read_frfs": "posture_id.norms.readers",
    "FrfSet": "posture_id.norms.norm",
    "Norm": "posture_id.norms.norm",
    "build_norm": "posture_id.norms.norm",
    "against_norm": "posture_id.norms.norm",
    "compare_groups": "posture_id.norms.groups",
    "simulate_reference": "posture_id.simulation.reference",
    "lump_robot": "posture_id.bodies.lumping",
    "preset_body": "posture_id.bodies.lumping",
    "generate_dataset": "posture_id.learning.data",
    "DatasetConfig": "posture_id.learning.data",
    "Dataset": "posture_id.learning.data",
    "fit_recording": "posture_id.fitting",
    "FitOptions": "posture_id.fitting",
    "FitProblem": "posture_id.fitting",
    "FitResult": "posture_id.fitting",
}


_lazy = lazy_getattr("posture_id", _LAZY)


def __getattr__(name: str) -> object:
    """A name of the API on first use; ``identify`` is the package of that name, callable as
    its function (Python binds the package's name here once it is imported, so the name is
    the same object every time)."""
    if name == "identify":
        import importlib

        return importlib.import_module("posture_id.identify")
    return _lazy(name)
