"""How to identify a recording, and the one default everywhere."""

from __future__ import annotations

import enum

__all__ = ["Method", "DEFAULT_METHOD"]


class Method(enum.Enum):
    """How to identify (see :mod:`posture_id.identify.core`)."""

    CNN = "cnn"
    FIT = "fit"
    HYBRID = "hybrid"
    #: the network alone, then least squares from its answer (the hybrid) when its trust
    #: verdict is doubtful and the sway is not people-like (on the stimulus-locked sway
    #: when the recording is too noisy to check an answer that explains it as well as its
    #: noise allows); least squares from the body's defaults when the network cannot read
    #: the recording (a tilt that is not periodic, or less than one whole cycle of it) or
    #: identify the body (docs/universal.md)
    AUTO = "auto"


#: The one default method of :func:`~posture_id.identify.identify`,
#: :class:`~posture_id.identify.Identifier`, the command line and cohorts: the CNN alone
#: (milliseconds, calibrated intervals); the hybrid, least squares from the CNN's answer, on
#: request when seconds per recording are worth its precision (docs/identify.md).
DEFAULT_METHOD = Method.AUTO
