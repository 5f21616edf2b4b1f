"""Compile CasADi functions to C with the system compiler, cached; fall back to CasADi's VM.

The generated C source is hashed with the compiler command; the shared library is kept
in ``$POSTURE_ID_CACHE`` (default ``~/.cache/posture_id/casadi``) under that hash, so a
second fit of the same body and recording length loads it at once. Without a compiler,
or if compiling fails, the functions run in CasADi's virtual machine (slower) and the
caller is told why.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from collections.abc import Callable
from pathlib import Path

import casadi as ca

__all__ = ["compile_functions", "cache_dir"]

_FLAGS = ["-O1", "-fPIC", "-shared", "-march=native"]


def cache_dir() -> Path:
    root = os.environ.get("POSTURE_ID_CACHE")
    return Path(root) if root else Path.home() / ".cache" / "posture_id" / "casadi"


def compile_functions(name: str, key: bytes, build: Callable[[], list[ca.Function]],
                      notify=None, mode: str = "auto") -> tuple[list[ca.Function], str]:
    """Compiled CasADi functions, from the cache when possible, and how they run.

    Args:
        name: base name of the generated file.
        key: bytes that determine the functions completely (model, sizes, code version);
            with the compiler flags they name the cached library, so a cached library is
            loaded without building the (slow) symbolic functions at all.
        build: makes the functions (needed on a cache miss or for the VM).
        notify: called with a one-line message before a (slow) compilation.
        mode: "auto" (compile if a compiler exists), "never" (VM), "always" (fail if the
            compiler is missing or fails).
    Returns:
        (functions, backend), backend is "compiled (cached)", "compiled" or "vm: reason".
    """
    if mode == "never":
        return build(), "vm: compilation disabled"
    compiler = os.environ.get("CC") or shutil.which("gcc") or shutil.which("cc")
    if compiler is None:
        if mode == "always":
            raise RuntimeError("no C compiler found (set CC)")
        return build(), "vm: no C compiler found"
    digest = hashlib.sha256(key + ca.__version__.encode() + " ".join(_FLAGS).encode())
    library = cache_dir() / f"{name}-{digest.hexdigest()[:24]}.so"
    names_file = library.with_suffix(".names")
    if library.exists() and names_file.exists():
        names = names_file.read_text().split()
        return [ca.external(n, str(library)) for n in names], "compiled (cached)"
    functions = build()
    try:
        library.parent.mkdir(parents=True, exist_ok=True)
        probe = library.parent / f".probe-{os.getpid()}"
        probe.touch()
        probe.unlink()
    except OSError:  # an unwritable cache: compile into a private folder for this process
        library = Path(tempfile.mkdtemp(prefix="posture_id_casadi_")) / library.name
        names_file = library.with_suffix(".names")
    if notify is not None:
        notify(f"compiling the CasADi model with {Path(compiler).name} "
               f"(once; cached in {library.parent})")
    with tempfile.TemporaryDirectory() as tmp:
        gen = ca.CodeGenerator(f"{name}.c")
        for f in functions:
            gen.add(f)
        gen.generate(tmp + os.sep)
        source = Path(tmp) / f"{name}.c"
        partial = library.with_suffix(f".{os.getpid()}.tmp")
        try:
            subprocess.run([compiler, *_FLAGS, str(source), "-o", str(partial), "-lm"],
                           check=True, capture_output=True, text=True)
        except (subprocess.CalledProcessError, OSError) as exc:
            partial.unlink(missing_ok=True)
            if mode == "always":
                raise
            detail = getattr(exc, "stderr", "") or str(exc)
            return functions, f"vm: compilation failed ({detail.strip()[:200]})"
        os.replace(partial, library)
    names_file.write_text(" ".join(f.name() for f in functions))
    return [ca.external(f.name(), str(library)) for f in functions], "compiled"
