"""Compiling CasADi functions: cache, fallbacks."""

from __future__ import annotations

import casadi as ca
import pytest

from posture_id.fitting.build import compile_functions
from posture_id.fitting.options import Compilation


def _square():
    x = ca.SX.sym("x")
    return [ca.Function("square", [x], [x * x])]


def test_compile_then_load_from_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("POSTURE_ID_CACHE", str(tmp_path))
    messages = []
    (f,), backend = compile_functions("t", b"key", _square, notify=messages.append)
    assert str(backend) == "compiled" and float(f(3)) == 9.0 and messages
    built = []

    def build():
        built.append(1)
        return _square()

    (g,), backend = compile_functions("t", b"key", build)
    assert str(backend) == "compiled (cached)" and float(g(4)) == 16.0
    assert not built  # a cached library needs no symbolic build
    (_,), backend = compile_functions("t", b"other key", _square)
    assert str(backend) == "compiled"


def test_virtual_machine_fallbacks(tmp_path, monkeypatch):
    (f,), backend = compile_functions("t", b"key", _square, mode=Compilation.NEVER)
    assert str(backend).startswith("vm") and float(f(2)) == 4.0
    monkeypatch.setenv("POSTURE_ID_CACHE", str(tmp_path))
    monkeypatch.setenv("CC", str(tmp_path / "no-such-compiler"))
    (f,), backend = compile_functions("t", b"key2", _square)
    assert str(backend).startswith("vm: compilation failed") and float(f(5)) == 25.0
    with pytest.raises(OSError):
        compile_functions("t", b"key3", _square, mode=Compilation.ALWAYS)


def test_unwritable_cache_compiles_privately(monkeypatch):
    monkeypatch.setenv("POSTURE_ID_CACHE", "/proc/not-writable")
    (f,), backend = compile_functions("t", b"key", _square)
    assert str(backend) == "compiled" and float(f(6)) == 36.0


def test_a_prebuilt_library_serves_an_empty_cache(tmp_path, monkeypatch):
    """What the set-up compiled (the prebuilt folder) is loaded when the cache has nothing;
    switched off, the function is compiled into the cache."""
    monkeypatch.setenv("POSTURE_ID_CACHE", str(tmp_path / "setup"))
    compile_functions("t", b"prebuilt key", _square)  # the set-up's compile
    monkeypatch.setenv("POSTURE_ID_PREBUILT", str(tmp_path / "setup"))
    monkeypatch.setenv("POSTURE_ID_CACHE", str(tmp_path / "new"))
    built = []

    def build():
        built.append(1)
        return _square()

    (f,), backend = compile_functions("t", b"prebuilt key", build)
    assert str(backend) == "compiled (cached)" and not built and float(f(3)) == 9.0
    assert not list((tmp_path / "new" / "casadi").glob("*.so"))
    monkeypatch.setenv("POSTURE_ID_PREBUILT", "none")
    (_,), backend = compile_functions("t", b"prebuilt key", build)
    assert str(backend) == "compiled" and built
