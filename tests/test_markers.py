"""The rule of tests/conftest.py: a ``slow`` mark says what makes its test slow."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

CONFTEST = Path(__file__).with_name("conftest.py")

GIVEN = '''import pytest


@pytest.mark.slow("trains a network")
def test_marked_with_its_reason():
    pass


@pytest.mark.parametrize("n", [1, pytest.param(2, marks=pytest.mark.slow("a big n"))])
def test_one_case_marked(n):
    pass
'''

BARE = '''import pytest


@pytest.mark.slow
def test_marked_bare():
    pass
'''


def _collect(folder: Path, name: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q",
                           "-p", "no:cacheprovider", name], cwd=folder, capture_output=True,
                          text=True, timeout=60)


def test_a_slow_mark_without_its_reason_is_refused(tmp_path):
    shutil.copy(CONFTEST, tmp_path / "conftest.py")
    (tmp_path / "pytest.ini").write_text("[pytest]\nmarkers =\n    slow(reason): slow\n")
    (tmp_path / "test_given.py").write_text(GIVEN)
    (tmp_path / "test_bare.py").write_text(BARE)
    given = _collect(tmp_path, "test_given.py")
    assert given.returncode == 0, given.stdout + given.stderr
    assert "3 tests collected" in given.stdout
    bare = _collect(tmp_path, "test_bare.py")
    assert bare.returncode == 4, bare.stdout + bare.stderr  # pytest's usage error
    assert "test_bare.py::test_marked_bare: a slow mark says what makes the test slow" in (
        bare.stderr)
