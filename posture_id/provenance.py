"""What made a result: package version, options and the body's identity.

Every result's ``to_dict()`` carries ``"provenance": provenance(options, body)`` so that a
JSON file says which code, which settings and which URDF produced it.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from pathlib import Path
from typing import Any

from posture_id._version import __version__

__all__ = ["provenance", "body_identity", "jsonable"]


def jsonable(value: Any) -> Any:
    """``value`` as JSON-ready data: dataclasses as dicts (with a ``"type"``), enums by
    value, tuples as lists, paths as strings, non-finite floats as None."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = {f.name: jsonable(getattr(value, f.name)) for f in dataclasses.fields(value)
                  if f.repr}
        return {"type": type(value).__name__, **fields}
    if isinstance(value, enum.Enum):
        return jsonable(value.value)
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if hasattr(value, "item") and callable(value.item):  # numpy scalars
        return jsonable(value.item())
    return value


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
