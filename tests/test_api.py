"""The public API: every exported name resolves; the layers stay one-way on import."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import posture_id


def test_every_exported_name_is_the_object_it_names():
    """Each name resolves (lazily or not) to the class or function of that name in its
    stage's package; the two constants are what they say."""
    for name in posture_id.__all__:
        obj = getattr(posture_id, name)
        if name == "__version__":
            assert re.fullmatch(r"\d+\.\d+\.\d+\S*", obj), obj
        elif name == "DEFAULT_URDF":
            assert Path(obj).is_file() and Path(obj).suffix == ".urdf"
        else:
            assert obj.__name__ == name, (name, obj)
            assert obj.__module__.startswith("posture_id."), (name, obj.__module__)


def test_the_command_line_imports_nothing_heavy():
    """Importing the command line (every command's parser) leaves scipy.signal, .stats and
    .fft, torch and CasADi to the commands that need them: `posture-id simulate` starts
    fast."""
    heavy = ("scipy.signal", "scipy.stats", "scipy.fft", "torch", "casadi", "matplotlib",
             "distributed")
    code = f"import sys, posture_id.cli; print(sorted(m for m in {heavy} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"


def test_import_does_not_load_casadi_torch_or_matplotlib():
    code = ("import sys, posture_id; "
            "print(sorted(m for m in ('casadi', 'torch', 'matplotlib', 'distributed') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"
