"""What made a result: package version, options and the body's identity.

Every result's ``to_dict()`` carries ``"provenance": provenance(options, body)`` so that a
JSON file says which code, which settings and which URDF produced it.
"""

from __future__ import annotations

from typing import Any

from posture_id._version import __version__
from posture_id.fileio import jsonable

__all__ = ["provenance", "body_identity", "jsonable", "recording_identity"]


def provenance(options: Any = None, body: Any = None, **extra: Any) -> dict:
    """``{"package", "version", "options", "body": {name, urdf, sha256}, ...extra}``."""
    out: dict = {"package": "posture_id", "version": __version__}
    if options is not None:
        out["options"] = jsonable(options)
    if body is not None:
        out["body"] = body_identity(body)
    out.update({k: jsonable(v) for k, v in extra.items()})
    return out


def body_identity(body: Any) -> dict:
    """The body's name, URDF path, SHA-256 and segment and joint names."""
    return {"name": body.name, "urdf": str(body.urdf_path), "sha256": body.sha256,
            "segments": list(body.segment_names), "joints": list(body.joint_names)}


def recording_identity(name: str, source: dict | None = None) -> dict:
    """``{"recording": name}``, with ``"recording_source"`` (the markers, axes and channels
    its angles came from) when they were derived from a motion-capture file."""
    return {"recording": name, **({"recording_source": source} if source else {})}
