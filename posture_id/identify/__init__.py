"""Identification of recordings: the CNN, least squares and the hybrid behind one entry
point (:func:`identify`). Uses :mod:`posture_id.learning` and :mod:`posture_id.fitting`;
only the command line sits above it."""

from posture_id.identify.core import Identifier, identify
from posture_id.identify.method import DEFAULT_METHOD, Method
from posture_id.identify.result import IdentificationResult, SegmentFit

__all__ = ["identify", "Identifier", "Method", "DEFAULT_METHOD", "IdentificationResult",
           "SegmentFit"]
