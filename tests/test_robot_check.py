"""The robot checks without their optional extra: importing ``posture_id.robots`` does not
import MuJoCo, and using it without MuJoCo stops with one line naming the extra."""

from __future__ import annotations

import subprocess
import sys

import pytest

from posture_id.errors import PostureIdError
from posture_id.robots import ROBOTS_EXTRA, MissingExtraError, simulate_mujoco


def test_importing_the_robot_checks_does_not_import_mujoco():
    code = ("import sys, posture_id.robots, posture_id.cli; "
            "print('mujoco' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"


def test_without_mujoco_one_line_names_the_extra(monkeypatch, tip):
    monkeypatch.setitem(sys.modules, "mujoco", None)  # import mujoco → ImportError
    with pytest.raises(MissingExtraError) as err:
        simulate_mujoco(tip)
    message = str(err.value)
    assert isinstance(err.value, PostureIdError)
    assert "\n" not in message and ROBOTS_EXTRA in message
    assert ROBOTS_EXTRA == "pip install posture_id[robots]"
