"""Which network an identification uses: the bundled universal model unless told
otherwise (docs/universal.md)."""

from __future__ import annotations

from pathlib import Path

from posture_id.bodies.body import Body
from posture_id.learning.identifier import NetworkIdentifier
from posture_id.learning.universal_identifier import UniversalIdentifier

__all__ = ["network_for", "Network"]

#: What an identification asks of a network (every architecture's identifier is one).
Network = NetworkIdentifier


def network_for(model: str | Path | Network | None, body: Body) -> Network:
    """A network already loaded, a model directory (of any registered architecture: the
    universal model, a per-body specialist made by ``posture-id network cnn train``, ...), or None:
    the bundled universal model."""
    if model is None:
        return UniversalIdentifier.bundled(body)
    return NetworkIdentifier.resolve(model, body)
