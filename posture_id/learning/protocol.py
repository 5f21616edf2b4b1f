"""What an identification asks of a network: the one protocol the paper's spectrogram CNN
(:class:`~posture_id.learning.identifier.CnnIdentifier`) and the universal network
(:class:`~posture_id.learning.universal.identifier.UniversalIdentifier`) implement."""

from __future__ import annotations

from typing import Protocol, runtime_checkable

__all__ = ["NetworkIdentifier"]


@runtime_checkable
class NetworkIdentifier(Protocol):
    """A trained network that identifies DEC on a body's prepared trials.

    Attributes:
        body: the body it identifies. model: the loaded weights and sidecar.
        calibration: its intervals' and class probabilities' calibration, or None.
        notices: what loading it had to say (one line each).
    """

    body: object
    model: object
    notices: tuple[str, ...]

    @property
    def calibration(self): ...

    @property
    def trained_on_this_body(self) -> bool:
        """Whether it was trained on this very body (its hybrid's calibration applies)."""

    @property
    def reads_people_like(self) -> bool:
        """Whether it was trained on people-like sway (the verdict's people-like rules)."""

    def identify(self, trial, level: float):
        """The network's answer on a prepared trial: parameters, class probabilities and
        intervals at ``level``."""

    def for_body(self, body) -> NetworkIdentifier:
        """This kind of network for another body: the universal network itself (nothing
        read again), a specialist the bundled one of that body."""
