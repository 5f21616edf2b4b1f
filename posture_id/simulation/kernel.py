"""Compiled planar-chain dynamics and the DEC controller, batched over trials (numba).

Equations of motion in segment-in-space angles θ (N,) (derivation in docs/model.md):

    M(θ) θ̈ + c(θ, θ̇) + G(θ) = Q,   Q_j = τ_j − τ_{j+1}
    M_jk = Re(D_jk E_jk) + δ_jk I_j,   c_j = Σ_k θ̇_k² Im(D_jk E_jk),   E_jk = e^{i(θ_j − θ_k)}
    G_j = −g Im(e^{iθ_j} S_j)

with the body's constant coupling D (N, N) and gravity levers S (N,) (see
:class:`posture_id.bodies.body.Body`). The COM above joint i is Σ_{j≥i} e^{iθ_j} S_j / m_above,i.

Time stepping (docs/model.md §2 **[decision]**): step dt, controller from the state at the start
of the step, semi-implicit Euler (velocities first, then angles).

Layout (:mod:`.kernel_layout`): trials run in blocks of LANES; every per-trial quantity
is a row of LANES values in one flat work array. The source (:mod:`.kernel_source`) is
written once per number of segments N with N a constant, so loops over segments unroll,
every row offset is a constant and the loops over lanes vectorise (AVX2/AVX-512);
elementary functions come from :mod:`.fastmath` for the same reason. Delay-buffer reads
(a different delay per lane) happen in a short scalar phase.

Warm start: the copy for N lives in the cache folder (:mod:`posture_id.cache`) under a name
that hashes its source, the sources it inlines and numba's version; numba caches its
machine code beside it, so a new process loads the compiled simulator instead of
compiling it (about 4 s per N, once per machine). A copy the set-up compiled into the
prebuilt folder (:func:`posture_id.cache.prebuilt_file`) serves when the cache has none.
"""

from __future__ import annotations

import hashlib
import importlib.util
import sys
import threading
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numba

from posture_id.cache import cache_folder, prebuilt_file
from posture_id.fileio import atomic_write_text
from posture_id.simulation.kernel_layout import LANES, ParRows, Rows, buffer_length

__all__ = ["LANES", "Rows", "ParRows", "Kernels", "kernels", "buffer_length", "kernel_source"]

_HERE = Path(__file__).resolve().parent
_SOURCES = ("kernel_source.py", "kernel_layout.py", "fastmath.py")
_N_LINE = "N = 3  # SEGMENTS: replaced in every generated copy"
_LOCK = threading.Lock()


@dataclass(frozen=True)
class Kernels:
    """The compiled functions for one N (see :func:`kernels`)."""

    n: int
    rows: Rows
    par_rows: ParRows
    kinematics: object
    dec_torques: object
    dynamics: object
    simulate_block: object


def kernel_source(n: int) -> tuple[str, str]:
    """(module name, source text) of the simulator for ``n`` segments."""
    if not (isinstance(n, int) and n >= 1):
        raise ValueError(f"the number of segments must be a positive integer, got {n!r}")
    template = (_HERE / "kernel_source.py").read_text(encoding="utf-8")
    if template.count(_N_LINE) != 1:
        raise RuntimeError("kernel_source.py lost its 'N = 3' marker line")
    text = template.replace(_N_LINE, f"N = {n}  # generated for {n} segments")
    digest = hashlib.sha256(text.encode())
    for name in _SOURCES[1:]:
        digest.update((_HERE / name).read_bytes())
    digest.update(numba.__version__.encode())
    return f"posture_id_kernel_n{n}_{digest.hexdigest()[:16]}", text


@cache
def kernels(n: int) -> Kernels:
    """The compiled simulation functions for N segments: loaded from the cache folder when
    a previous process compiled them, else compiled (and cached) now."""
    with _LOCK:
        name, text = kernel_source(n)
        path = cache_folder("kernels") / f"{name}.py"
        prebuilt = prebuilt_file("kernels", f"{name}.py")
        if not path.exists() and prebuilt is not None:
            path = prebuilt  # compiled at set-up (numba's cache beside it)
        elif not path.exists() or path.read_text(encoding="utf-8") != text:
            atomic_write_text(path, text)
        if not any((path.parent / "__pycache__").glob(f"{name}.*.nbi")):
            # numba compiles on the first call: say so, once per machine and N
            print(f"posture-id: compiling the simulator for {n} segment(s) (once; cached "
                  f"in {path.parent})", file=sys.stderr, flush=True)
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return Kernels(n, module.R, module.P, module.kinematics, module.dec_torques,
                   module.dynamics, module.simulate_block)
