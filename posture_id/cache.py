"""Where posture_id keeps compiled code between processes.

``$POSTURE_ID_CACHE`` when set, else the platform's user cache folder for posture_id
(platformdirs: ``~/.cache/posture_id`` on Linux); when that folder cannot be
written, a private temporary folder for this process (slower: nothing is reused).
Subfolders: ``kernels/`` (the generated simulator modules and numba's cache of them) and
``casadi/`` (the fit's compiled C libraries).

Beside it, read first when it holds what is wanted: the **prebuilt** folder that the
project's set-up fills (``python -m posture_id.studies.prebuild``, run by ``make``'s install step:
the simulator for 1–3 segments and the fit's compiled models for them), so that the first
command on a new machine, or with a new cache folder, compiles nothing.
``$POSTURE_ID_PREBUILT`` moves it, or switches it off with ``none``.
"""

from __future__ import annotations

import os
import tempfile
from functools import cache
from pathlib import Path

__all__ = ["cache_root", "cache_folder", "prebuilt_root", "prebuilt_file"]

#: The prebuilt folder's default place: inside the package (an editable install's
#: checkout; ignored by git).
_PREBUILT = Path(__file__).resolve().parent / "_prebuilt"


def prebuilt_root() -> Path | None:
    """The prebuilt folder (it may not exist), or None when switched off."""
    root = os.environ.get("POSTURE_ID_PREBUILT")
    if root is not None and root.strip().lower() in ("none", "0", ""):
        return None
    return Path(root) if root else _PREBUILT


def prebuilt_file(name: str, file: str) -> Path | None:
    """``prebuilt_root()/name/file`` when it exists, else None."""
    root = prebuilt_root()
    path = None if root is None else root / name / file
    return path if path is not None and path.exists() else None


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
