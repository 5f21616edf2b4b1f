"""Least-squares identification with CasADi: the only layer that imports CasADi.

Modules: :mod:`.symbolic` (the plant and DEC in CasADi), :mod:`.build` (C generation and
its cache), :mod:`.problem` (the compiled problem you can hold and reuse),
:mod:`.evaluators` (residuals, Jacobians, one stage), :mod:`.options`, :mod:`.result`,
:mod:`.prepare` (recordings in) and :mod:`.least_squares` (:func:`fit_recording`).
"""

from posture_id.fitting.least_squares import fit_recording
from posture_id.fitting.options import (
    Compilation,
    ExhaustiveClasses,
    FitError,
    FitOptions,
    FixedClasses,
    RelaxedClasses,
)
from posture_id.fitting.prepare import prepare_recording
from posture_id.fitting.problem import FitProblem
from posture_id.fitting.result import FitResult, StageResult

__all__ = [
    "fit_recording",
    "FitOptions",
    "FitError",
    "Compilation",
    "RelaxedClasses",
    "ExhaustiveClasses",
    "FixedClasses",
    "FitProblem",
    "FitResult",
    "StageResult",
    "prepare_recording",
]
