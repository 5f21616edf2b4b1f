"""Layer contracts (pyproject.toml, import-linter): kept by the code, and able to fail.

The second group copies the package, adds one forbidden import and checks that the
contract named for it breaks: a contract that cannot fail would prove nothing.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LINT = Path(sys.executable).with_name("lint-imports")


def _lint(cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([str(LINT), "--no-cache"], cwd=cwd, capture_output=True, text=True,
                          env={"PYTHONPATH": str(cwd), "PATH": "/usr/bin:/bin"})


def test_the_package_keeps_every_contract():
    result = _lint(ROOT)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "4 kept, 0 broken" in result.stdout


@pytest.mark.parametrize(("module", "line", "broken"), [
    ("simulation/leak.py", "import torch", "torch is imported only by the learning layer"),
    ("datasets/leak.py", "import casadi", "CasADi is imported only by the fitting layer"),
    ("learning/leak.py", "import casadi", "CasADi is imported only by the fitting layer"),
    ("fitting/leak.py", "import matplotlib.pyplot",
     "matplotlib is imported only by posture_id.plotting"),
    ("bodies/leak.py", "def f():\n    from posture_id.simulation import simulate\n",
     "Stages are layered"),
    ("fitting/leak.py", "from posture_id.learning import __doc__", "Stages are layered"),
])
def test_a_forbidden_import_breaks_its_contract(tmp_path, module, line, broken):
    shutil.copytree(ROOT / "posture_id", tmp_path / "posture_id",
                    ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    (tmp_path / "posture_id" / module).write_text(line + "\n")
    result = _lint(tmp_path)
    assert result.returncode != 0
    verdicts = [ln for ln in result.stdout.splitlines() if ln.startswith(broken)]
    assert verdicts and verdicts[0].endswith("BROKEN"), result.stdout
    assert "1 broken" in result.stdout, result.stdout  # only the contract named for it
