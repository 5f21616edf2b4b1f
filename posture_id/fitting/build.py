"""Compile CasADi functions to C with the system compiler, cached; fall back to CasADi's VM.

The generated C source is hashed with the compiler command; the shared library is kept
in the ``casadi/`` folder of the cache (:mod:`posture_id.cache`) under that hash, so a
second fit of as many segments loads it at once (or from the prebuilt folder the set-up
filled). Without a compiler,
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
from dataclasses import dataclass
from pathlib import Path

import casadi as ca

from posture_id.cache import cache_folder, prebuilt_file
from posture_id.fileio import atomic_write_text
from posture_id.fitting.options import Compilation

__all__ = ["compile_functions", "Backend"]

#: gcc's flags. -Og, not -O1: the 3-segment model (one block of 1000 samples and its
#: derivatives) compiles in 7 s instead of 27 s, and the compiled code runs as fast on a
#: 121 s recording (0.062 s against 0.060 s a simulation, 2.03 s against 1.96 s a
#: Jacobian chunk; -O0 compiles in 3 s but runs 2.5x slower). Measured side by side by
#: benchmarks/compile_flags.py (docs/results/compile_flags.json).
_FLAGS = ["-Og", "-fPIC", "-shared", "-march=native"]


@dataclass(frozen=True)
class Backend:
    """How compiled functions run.

    Attributes:
        compiled: True for C compiled by the system compiler, False for CasADi's VM.
        cached: the compiled library came from the cache (no compilation this time).
        reason: why the VM runs them ("" when compiled).
    """

    compiled: bool
    cached: bool = False
    reason: str = ""

    def __str__(self) -> str:
        if self.compiled:
            return "compiled (cached)" if self.cached else "compiled"
        return f"vm: {self.reason}"


def compile_functions(name: str, key: bytes, build: Callable[[], list[ca.Function]],
                      notify=None, mode: Compilation = Compilation.AUTO
                      ) -> tuple[list[ca.Function], Backend]:
    """Compiled CasADi functions, from the cache when possible, and how they run.

    Args:
        name: base name of the generated file.
        key: bytes that determine the functions completely (model, sizes, code version);
            with the compiler flags they name the cached library, so a cached library is
            loaded without building the (slow) symbolic functions at all.
        build: makes the functions (needed on a cache miss or for the VM).
        notify: called with a one-line message before a (slow) compilation.
        mode: AUTO (compile if a compiler exists), NEVER (VM), ALWAYS (fail if the
            compiler is missing or fails).
    Returns:
        (functions, :class:`Backend`).
    """
    if mode is Compilation.NEVER:
        return build(), Backend(False, reason="compilation disabled")
    compiler = os.environ.get("CC") or shutil.which("gcc") or shutil.which("cc")
    if compiler is None:
        if mode is Compilation.ALWAYS:
            raise RuntimeError("no C compiler found (set CC)")
        return build(), Backend(False, reason="no C compiler found")
    digest = hashlib.sha256(key + ca.__version__.encode() + " ".join(_FLAGS).encode())
    library = cache_folder("casadi") / f"{name}-{digest.hexdigest()[:24]}.so"
    prebuilt = prebuilt_file("casadi", library.name)
    if not library.exists() and prebuilt is not None:
        library = prebuilt  # compiled at set-up
    names_file = library.with_suffix(".names")
    if library.exists() and names_file.exists():
        names = names_file.read_text().split()
        return [ca.external(n, str(library)) for n in names], Backend(True, cached=True)
    functions = build()
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
            if mode is Compilation.ALWAYS:
                raise
            detail = getattr(exc, "stderr", "") or str(exc)
            return functions, Backend(False, reason=f"compilation failed "
                                                    f"({detail.strip()[:200]})")
        os.replace(partial, library)
    atomic_write_text(names_file, " ".join(f.name() for f in functions))
    return [ca.external(f.name(), str(library)) for f in functions], Backend(True)
