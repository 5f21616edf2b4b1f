"""Least-squares identification with CasADi: the only layer that imports CasADi.

Modules: :mod:`.symbolic` (the plant and DEC in CasADi), :mod:`.build` (C generation and
its cache), :mod:`.problem` (the compiled problem you can hold and reuse),
:mod:`.evaluators` (residuals, Jacobians, one stage), :mod:`.options`, :mod:`.result`,
:mod:`.least_squares` (:func:`fit_recording`).
"""

from posture_id._lazy import lazy_getattr

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
]

# Names load on first use: the options (imported by the command line and by identify) must
# not pull in CasADi.
_WHERE = {
    "fit_recording": "least_squares", "FitOptions": "options", "FitError": "options",
    "Compilation": "options", "RelaxedClasses": "options", "ExhaustiveClasses": "options",
    "FixedClasses": "options", "FitProblem": "problem", "FitResult": "result",
    "StageResult": "result",
}


__getattr__ = lazy_getattr("posture_id.fitting",
                           {k: f"posture_id.fitting.{v}" for k, v in _WHERE.items()})
