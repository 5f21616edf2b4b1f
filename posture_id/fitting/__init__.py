"""Least-squares identification with CasADi: the only layer that imports CasADi.

Modules: :mod:`.symbolic` (the plant and DEC in CasADi), :mod:`.build` (C generation and
its cache), :mod:`.problem` (the compiled problem you can hold and reuse),
:mod:`.evaluators` (residuals, Jacobians, one stage), :mod:`.options`, :mod:`.result`,
:mod:`.prepare` (recordings in) and :mod:`.least_squares` (:func:`fit_recording`).
"""

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

# Names load on first use: the options (imported by the command line and by identify) must
# not pull in CasADi.
_WHERE = {
    "fit_recording": "least_squares", "FitOptions": "options", "FitError": "options",
    "Compilation": "options", "RelaxedClasses": "options", "ExhaustiveClasses": "options",
    "FixedClasses": "options", "FitProblem": "problem", "FitResult": "result",
    "StageResult": "result", "prepare_recording": "prepare",
}


def __getattr__(name: str):
    if name in _WHERE:
        import importlib

        return getattr(importlib.import_module(f"posture_id.fitting.{_WHERE[name]}"), name)
    raise AttributeError(f"module 'posture_id.fitting' has no attribute '{name}'")
