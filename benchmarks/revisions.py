"""Another revision of this checkout beside it, for benchmarks that compare the two in one run.

:func:`checkout` puts revision REV into a temporary git worktree for the length of a
``with`` block; :data:`IMPORT_BEFORE` is Python code that makes a child process import
``posture_id`` from the tree named by ``$POSTURE_ID_BEFORE`` instead of this checkout's
editable install (its import hook removed first), with the same interpreter.
"""

from __future__ import annotations

import subprocess
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Prefix for ``python -c``: posture_id is imported from $POSTURE_ID_BEFORE (checked).
IMPORT_BEFORE = (
    "import os, sys; "
    "sys.meta_path[:] = [f for f in sys.meta_path "
    "if '__editable__' not in getattr(f, '__module__', '')]; "
    "sys.path.insert(0, os.environ['POSTURE_ID_BEFORE']); "
    "import posture_id; assert posture_id.__file__.startswith(sys.path[0]), posture_id.__file__; "
)


@contextmanager
def checkout(revision: str, folder: Path | None = None) -> Iterator[Path]:
    """A detached worktree of ``revision`` (in ``folder``, or a temporary one), removed on exit."""
    with tempfile.TemporaryDirectory() as tmp:
        tree = (folder or Path(tmp)) / "before"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(tree),
                        revision], check=True, capture_output=True)
        try:
            yield tree
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(tree)],
                           check=True, capture_output=True)
