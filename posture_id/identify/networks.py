"""Which network an identification uses: the bundled universal model unless told
otherwise (docs/universal.md)."""

from __future__ import annotations

from pathlib import Path

from posture_id.bodies.body import Body
from posture_id.learning.identifier import CnnIdentifier
from posture_id.learning.protocol import NetworkIdentifier
from posture_id.learning.universal.identifier import UniversalIdentifier, is_universal_model

__all__ = ["network_for", "Network"]

#: What an identification asks of a network (both networks implement it).
Network = NetworkIdentifier


def network_for(model: str | Path | Network | None, body: Body) -> Network:
    """A network already loaded, a model directory (a universal model or a per-body
    specialist made by ``posture-id train``), or None: the bundled universal model."""
    if isinstance(model, CnnIdentifier | UniversalIdentifier):
        return model
    if model is None:
        return UniversalIdentifier.bundled(body)
    if is_universal_model(model):
        return UniversalIdentifier.load(model, body)
    return CnnIdentifier.load(model, body)
