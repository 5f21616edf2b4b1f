"""The tutorials run as they are written (jupytext "percent" scripts in docs/tutorials/),
each in a folder of its own."""

from __future__ import annotations

import runpy
from pathlib import Path

import pytest

TUTORIALS = sorted((Path(__file__).parents[1] / "docs" / "tutorials").glob("*.py"))


def test_there_are_tutorials():
    assert [t.name for t in TUTORIALS] == ["c3d_trial.py", "cohort.py",
                                            "force_plate_study.py", "ic_model.py",
                                            "lab_recording.py", "norms.py", "python_api.py",
                                            "robot.py"]


@pytest.mark.slow("a tutorial end to end")
@pytest.mark.parametrize("tutorial", TUTORIALS, ids=[t.stem for t in TUTORIALS])
def test_a_tutorial_runs(tutorial, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    runpy.run_path(str(tutorial), run_name="__main__")  # its own asserts check its answers
    assert any(tmp_path.iterdir())  # it wrote its result
