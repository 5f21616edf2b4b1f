"""Hostile input to the command line, run and sorted: the harness of the project's
suites of bad input (``tests/test_hostile_*.py``, the cases of ``tests/hostile_cases*.py``)
and of their reports (``benchmarks/hostile_input.py``).

A :class:`Case` is a command line, the files it is run beside and its good answer declared
before it runs: the words its one-line refusal or its notice must hold, and whether the
right outcome is a refusal or an answer. :func:`run_case` runs it in a folder of its own,
in this process, and sorts what happened into one of

- **clear**: exit status 2 and one line that names the file or flag and the problem;
- **handled**: an answer (exit 0 or 1) with a notice that says what was done about it;
- **unclear**: exit status 2, but the line does not name the problem;
- **traceback**: an internal error (exit 3) or an exception that escaped;
- **silent**: an answer with no word about what was wrong;
- **data loss**: a file of the user's (or an input) changed, vanished, or a failed run
  left a new file behind;
- **hang**: still running after the case's time limit.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import re
import shutil
import signal
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["Case", "Outcome", "OUTCOMES", "build_files", "run_case", "before_after"]

OUTCOMES = ("clear", "handled", "unclear", "traceback", "silent", "data loss", "hang")


@dataclass(frozen=True)
class Case:
    """One bad input.

    name: unique, short. surface: the command or input it tries. argv: the command line;
    ``{name}`` fields are the shared material's paths (:func:`make_material`).
    files: ``{relative path: text}`` written into the case's folder first (a name ending
    in ``/`` is a folder; a text starting with ``@`` copies that material file).
    expect: words the line (clear) or the notice (handled) must hold, each of them.
    handled: the right outcome is an answer with a notice, not a refusal.
    kept: files the command may write (handled cases), relative to the case's folder.
    """

    name: str
    surface: str
    argv: tuple[str, ...]
    expect: tuple[str, ...]
    files: dict = field(default_factory=dict)
    handled: bool = False
    kept: tuple[str, ...] = ()
    limit_s: int = 120


@dataclass(frozen=True)
class Outcome:
    """What a case did: its outcome (one of :data:`OUTCOMES`), exit status (None: none
    came), the line that says it (the refusal, the notice) and how long it ran, s."""

    name: str
    surface: str
    outcome: str
    status: int | None
    line: str
    seconds: float

    def to_dict(self) -> dict:
        return {"name": self.name, "surface": self.surface, "outcome": self.outcome,
                "status": self.status, "line": self.line, "seconds": round(self.seconds, 2)}


class _Hang(BaseException):  # not caught by the CLI's handler of bugs
    pass


def _digest(folders: list[Path]) -> dict[str, str]:
    out = {}
    for folder in folders:
        for p in sorted(folder.rglob("*")):
            if p.is_file():
                out[str(p)] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


def build_files(folder: Path, files: dict, material: dict[str, str]) -> None:
    """Write ``files`` into ``folder``: text, bytes, ``@name`` (a copy of a material file
    or folder), or a tuple: ``("edit", name, f)`` the material JSON with ``f(data)``
    applied, ``("cut", name, n)`` its first n bytes, ``("text", name, f)`` ``f(text)``,
    ``("bytes", name, f)`` the bytes ``f(text)``."""
    for name, text in files.items():
        target = folder / name
        if name.endswith("/"):
            target.mkdir(parents=True, exist_ok=True)
            continue
        target.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(text, tuple):
            how, key, arg = text
            source = Path(material[key])
            if how == "edit":
                target.write_text(json.dumps(arg(json.loads(source.read_text("utf-8")))),
                                  encoding="utf-8")
            elif how == "cut":
                target.write_bytes(source.read_bytes()[:arg])
            elif how == "bytes":
                target.write_bytes(arg(source.read_text("utf-8")))
            else:
                target.write_text(arg(source.read_text("utf-8")), encoding="utf-8")
        elif isinstance(text, str) and text.startswith("@"):
            source = Path(material[text[1:]])
            if source.is_dir():
                shutil.copytree(source, target)
            else:
                shutil.copyfile(source, target)
        elif isinstance(text, bytes):
            target.write_bytes(text)
        else:
            target.write_text(text, encoding="utf-8")


def run_case(case: Case, material: dict[str, str], folder: Path, shipped: Iterable[str] = (),
             spelled: Callable[[list[str]], list[str]] | None = None,
             root: Path | None = None) -> Outcome:
    """Run ``case`` in ``folder`` (made empty here) and sort its outcome (the module doc).

    Args:
        case: the input and its good answer. material: ``{name: path}`` the case's
            ``{name}`` fields and ``@name`` files stand for; every entry but those in
            ``shipped`` (the project's own files) is watched for changes.
        folder: the case's own folder (the current directory while it runs).
        spelled: turns the command line into the spelling of the tree under test.
        root: paths inside it are written relative to it in the outcome's line.
    """
    from posture_id.cli import main

    shipped = set(shipped)

    if folder.exists():
        shutil.rmtree(folder)
    folder.mkdir(parents=True)
    build_files(folder, case.files, material)
    argv = [a.format(**material) for a in case.argv]
    argv = spelled(argv) if spelled is not None else argv
    watched = [folder] + [Path(p) for k, p in material.items()
                          if k not in shipped and Path(p).is_dir()]
    watched_files = [Path(p) for k, p in material.items()
                     if k not in shipped and Path(p).is_file()]
    before = _digest(watched)
    before.update({str(p): hashlib.sha256(p.read_bytes()).hexdigest() for p in watched_files})
    out, err = io.StringIO(), io.StringIO()
    start = time.perf_counter()
    status: int | None = None
    escaped = None
    here = Path.cwd()

    def alarm(signum, frame):
        raise _Hang

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(case.limit_s)
    try:
        os.chdir(folder)
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            status = main(argv)
    except _Hang:
        escaped = "hang"
    except BaseException as exc:  # noqa: BLE001 - an escaped exception is an outcome here
        escaped = f"{type(exc).__name__}: {exc}"
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
        os.chdir(here)
    seconds = time.perf_counter() - start
    after = _digest(watched)
    after.update({str(p): hashlib.sha256(p.read_bytes()).hexdigest() for p in watched_files
                  if p.exists()})
    err_text, out_text = err.getvalue(), out.getvalue()
    line = " ".join(err_text.strip().splitlines()[-1:]) if err_text.strip() else ""
    kept = {str(folder / k) for k in case.kept}

    def allowed(k: str) -> bool:  # a file the case may write, or one in a folder it may
        return any(k == p or k.startswith(p + os.sep) for p in kept)

    lost = [k for k, v in before.items() if after.get(k) != v and not allowed(k)]
    new = [k for k in after if k not in before and not allowed(k)]
    if escaped == "hang":
        kind = "hang"
    elif escaped is not None or status == 3 or "Traceback" in err_text:
        kind, line = "traceback", escaped or line
    elif lost or (status == 2 and new):
        kind = "data loss"
        line = f"{line} [changed or new: {', '.join(Path(p).name for p in (lost or new))}]"
    elif status == 2:  # a renamed flag's notice is not part of the refusal
        refusal = "".join(line for line in err_text.splitlines(keepends=True)
                          if not line.startswith("posture-id: note:"))
        one_line = refusal.count("\n") == 1 and re.match(r"posture-id( [a-z-]+)*: error: ",
                                                          refusal) is not None
        named = all(e in refusal for e in case.expect)
        kind = "clear" if one_line and named and not case.handled else "unclear"
    else:
        noticed = all(e in err_text + out_text for e in case.expect)
        kind = "handled" if case.handled and noticed else "silent"
        if kind == "handled":
            line = next((s for s in (err_text + out_text).splitlines()
                         if case.expect[0] in s), line)
    if root is not None:  # the report names no machine's folders
        line = line.replace(str(root) + os.sep, "")
    return Outcome(case.name, case.surface, kind, status, line.strip()[:400], seconds)


def before_after(before: list[dict], after: list[Outcome]) -> str:
    """A markdown table, per surface of the cases in ``before`` (``Outcome.to_dict()`` rows
    of a run on an earlier tree) and ``after``: the outcomes' counts, clear / handled /
    unclear / traceback / silent / data loss / hang, before and after."""
    was = {r["name"]: r["outcome"] for r in before}
    rows = [r for r in after if r.name in was]
    lines = ["| surface | cases | before | after |", "|---|---|---|---|"]
    for surface in [*sorted({r.surface for r in rows}), "all"]:
        mine = [r for r in rows if surface in ("all", r.surface)]
        cells = [" / ".join(str(sum(o == k for o in outcomes)) for k in OUTCOMES)
                 for outcomes in ([was[r.name] for r in mine], [r.outcome for r in mine])]
        label = f"**{surface}**" if surface == "all" else surface
        lines.append(f"| {label} | {len(mine)} | {cells[0]} | {cells[1]} |")
    return "\n".join(lines) + "\n"
