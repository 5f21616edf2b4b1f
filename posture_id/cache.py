"""Where posture_id keeps compiled code between processes.

``$POSTURE_ID_CACHE`` when set, else the platform's user cache folder for posture_id
(platformdirs: ``~/.cache/posture_id`` on Linux); when that folder cannot be
written, a private temporary folder for this process (slower: nothing is reused).
Subfolders: ``kernels/`` (the generated simulator modules and numba's cache of them) and
``casadi/`` (the fit's compiled C libraries).
"""

from __future__ import annotations

import os
import tempfile
from functools import cache
from pathlib import Path

__all__ = ["cache_root", "cache_folder"]


def cache_root() -> Path:
    """The configured cache folder (it may not exist yet)."""
    root = os.environ.get("POSTURE_ID_CACHE")
    if root:
        return Path(root)
    from platformdirs import user_cache_dir

    return Path(user_cache_dir("posture_id", appauthor=False))


def cache_folder(name: str) -> Path:
    """``cache_root()/name``, created; a private temporary folder when it is not writable."""
    return _writable(cache_root() / name)


@cache
def _writable(folder: Path) -> Path:
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / f".probe-{os.getpid()}"
        probe.touch()
        probe.unlink()
        return folder
    except OSError:
        return Path(tempfile.mkdtemp(prefix=f"posture_id_{folder.name}_"))
