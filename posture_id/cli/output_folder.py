"""Report folders that hold only what the program wrote (issue 46).

A command that writes a folder of files (``design --out``, a cohort's ``--out``,
``evaluate --out``, ``demo --out``, ``benchmark --out``, ``calibration --out``,
``universal table --out``) names, before any work, the files it will write there. A file
of those names that posture-id did not write (the user's own ``study/design.md``, a
``summary.csv`` of their own) makes the command refuse in one line; a file it wrote before
is overwritten (a run again). It knows its own files by the folder's ledger,
``.posture-id-files`` (each file it wrote there with its SHA-256, updated after every
run), or, for JSON results written before the ledger existed, by their
``"provenance": {"package": "posture_id"}``. A file the user edited after posture-id wrote
it is the user's. A run that fails leaves no new empty folder behind.
"""

from __future__ import annotations

import glob
from collections.abc import Iterable, Sequence
from pathlib import Path
from types import TracebackType

from posture_id.cli.arguments import check_output_folder
from posture_id.errors import PostureIdError
from posture_id.fileio import atomic_write_text, file_sha256, json_object, json_text

__all__ = ["LEDGER", "OutputFolder", "written_by_posture_id", "cohort_folder"]

#: The folder's record of the files posture-id wrote into it: {relative path: SHA-256}
#: (JSON, but not named *.json: a user's loop over the results' JSON does not meet it).
LEDGER = ".posture-id-files"


def _ledger(folder: Path) -> dict[str, str]:
    files = json_object(folder / LEDGER).get("files")
    return {str(k): str(v) for k, v in files.items()} if isinstance(files, dict) else {}


def written_by_posture_id(path: Path, folder: Path) -> bool:
    """Whether ``path`` (a file in ``folder``) is as posture-id wrote it."""
    if _ledger(folder).get(path.relative_to(folder).as_posix()) == file_sha256(path):
        return True
    if path.suffix != ".json":
        return False
    provenance = json_object(path).get("provenance")
    return isinstance(provenance, dict) and provenance.get("package") == "posture_id"


def _files(folder: Path) -> dict[str, tuple[int, int, int]]:
    """{relative path: (inode, size, mtime_ns)} of the files under ``folder``."""
    if not folder.is_dir():
        return {}
    out = {}
    for p in folder.rglob("*"):
        if p.is_file() and p.name != LEDGER:
            s = p.stat()
            out[p.relative_to(folder).as_posix()] = (s.st_ino, s.st_size, s.st_mtime_ns)
    return out


class OutputFolder:
    """``with OutputFolder(out, "--out", writes=("report.md", "*.png")):`` around a
    command's work.

    On entry (before any work): the folder checks of
    :func:`~posture_id.cli.arguments.check_output_folder`, then a refusal when a file
    matching ``writes`` (glob patterns relative to the folder) is there and posture-id did
    not write it. On a clean exit: the ledger records every file the command wrote. On an
    error: the files it did write are recorded too (a cohort's finished results are
    kept and resumed), and a folder it created and left empty is removed.
    """

    def __init__(self, path: Path, flag: str, writes: Sequence[str],
                 inputs: Iterable[object] = ()) -> None:
        self.path = Path(path)
        self.flag = flag
        self.writes = tuple(writes)
        self.inputs = tuple(inputs)

    def foreign_files(self) -> list[Path]:
        """The files matching ``writes`` that posture-id did not write."""
        if not self.path.is_dir():
            return []
        found = {p for pattern in self.writes for p in self.path.glob(pattern) if p.is_file()}
        return sorted(p for p in found if not written_by_posture_id(p, self.path))

    def __enter__(self) -> OutputFolder:
        check_output_folder(self.path, self.flag, inputs=self.inputs)
        foreign = self.foreign_files()
        if foreign:
            names = ", ".join(p.relative_to(self.path).as_posix() for p in foreign[:4])
            more = f" and {len(foreign) - 4} more" if len(foreign) > 4 else ""
            raise PostureIdError(
                f"{self.path}: {self.flag} holds {names}{more}, which posture-id did not "
                "write and would overwrite: give another folder, or move those files away")
        self._existed = self.path.exists()
        self._before = _files(self.path)
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 trace: TracebackType | None) -> None:
        if not self.path.is_dir():
            return
        now = _files(self.path)
        written = [name for name, stat in now.items() if self._before.get(name) != stat]
        if written:
            self._record(written)
        elif not self._existed and not any(self.path.iterdir()):
            self.path.rmdir()

    def _record(self, written: list[str]) -> None:
        files = {k: v for k, v in _ledger(self.path).items() if (self.path / k).is_file()}
        files.update({name: file_sha256(self.path / name) for name in written})
        atomic_write_text(self.path / LEDGER, json_text(
            {"about": "the files posture-id wrote here (it overwrites these, and no other)",
             "files": dict(sorted(files.items()))}))


def cohort_folder(args, recordings: list[Path], suffixes: Sequence[str] = (".json",)
                  ) -> OutputFolder:
    """A cohort's ``--out`` folder (``args.out``): ``<recording><suffix>`` for each of the
    ``recordings`` and each of ``suffixes``, and summary.csv. Its inputs: the recordings,
    ``--body``, ``--tilt`` and the recordings' folders (results beside the recordings would
    be read as recordings the next time)."""
    writes = (*(f"{glob.escape(p.stem)}{suffix}" for suffix in suffixes for p in recordings),
              "summary.csv")
    return OutputFolder(args.out, "--out", writes, inputs=(
        *recordings, args.body, args.tilt, *{p.parent for p in recordings}))
