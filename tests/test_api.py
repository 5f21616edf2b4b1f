"""The public API: every exported name resolves; the layers stay one-way on import."""

from __future__ import annotations

import subprocess
import sys

import posture_id


def test_every_exported_name_resolves():
    for name in posture_id.__all__:
        assert getattr(posture_id, name) is not None, name


def test_import_does_not_load_casadi_torch_or_matplotlib():
    code = ("import sys, posture_id; "
            "print(sorted(m for m in ('casadi', 'torch', 'matplotlib', 'distributed') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"
