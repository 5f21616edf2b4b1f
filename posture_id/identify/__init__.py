"""Identification of recordings: the CNN, least squares and the hybrid behind one entry
point (:func:`identify`). Uses :mod:`posture_id.learning` and :mod:`posture_id.fitting`;
only the command line sits above it.

``posture_id.identify`` names both this package and the function: once the package is
imported, Python binds the name on :mod:`posture_id` to the package, so the package is
callable and calling it is calling :func:`identify` (``posture_id.identify(recording)``
works either way).
"""

import inspect
import sys
import types

from posture_id.identify.core import Identifier, identify
from posture_id.identify.method import DEFAULT_METHOD, Method
from posture_id.identify.result import IdentificationResult, SegmentFit

__all__ = ["identify", "Identifier", "Method", "DEFAULT_METHOD", "IdentificationResult",
           "SegmentFit"]


class _CallablePackage(types.ModuleType):
    """This package, callable as :func:`identify`."""

    def __call__(self, *args, **kwargs) -> IdentificationResult:
        return identify(*args, **kwargs)

    __call__.__doc__ = identify.__doc__
    __call__.__signature__ = inspect.signature(identify).replace(parameters=[
        inspect.Parameter("self", inspect.Parameter.POSITIONAL_ONLY),
        *inspect.signature(identify).parameters.values()])


sys.modules[__name__].__class__ = _CallablePackage
