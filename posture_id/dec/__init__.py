"""The DEC controller's parameters: defaults (docs/model.md §3), normalisation, the JSON format and
the docs/model.md §5 prior. Depends only on :mod:`posture_id.bodies` (for m·g·h)."""

from posture_id.dec.parameters import (
    DecParameters,
    ModuleParameters,
    ParameterArrays,
    default_parameters,
    denormalise,
    denormalise_arrays,
    normalise,
    normalise_arrays,
)
from posture_id.dec.prior import SIGMA, sample_parameters

__all__ = [
    "DecParameters",
    "ModuleParameters",
    "ParameterArrays",
    "default_parameters",
    "normalise",
    "denormalise",
    "normalise_arrays",
    "denormalise_arrays",
    "SIGMA",
    "sample_parameters",
]
