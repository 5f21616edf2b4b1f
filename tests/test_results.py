"""Results say what made them, print their own summary, and plot without touching the
user's matplotlib state."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np

from posture_id import __version__, simulate
from posture_id.simulation import SimulationOptions


def test_simulation_result_has_provenance_and_a_summary(tip, tmp_path):
    options = SimulationOptions(sway_limit_deg=10.0)
    result = simulate(tip, options=options)
    data = json.loads(json.dumps(result.to_dict()))
    assert data["provenance"]["version"] == __version__
    assert data["provenance"]["options"]["sway_limit_deg"] == 10.0
    assert data["provenance"]["body"]["sha256"] == tip.sha256
    assert len(tip.sha256) == 64
    assert "stable" in result.summary() and "6051 samples" in result.summary()
    recording = result.to_recording()
    np.testing.assert_array_equal(recording.theta, result.theta)
    assert recording.segments == tip.segment_names


def test_plots_leave_the_backend_alone_and_draw_into_given_axes(tip):
    code = """
import matplotlib
matplotlib.use("svg")
from matplotlib.figure import Figure
from posture_id import load_body, simulate
result = simulate(load_body())
fig = result.plot()
assert matplotlib.get_backend() == "svg", matplotlib.get_backend()
import matplotlib.pyplot as plt
assert plt.get_fignums() == [], plt.get_fignums()   # nothing left open in pyplot
mine = Figure()
axes = mine.subplots(2, 1)
assert result.plot(ax=axes) is mine
assert len(axes[1].lines) == 4                        # three segments and the body COM
print("ok")
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


def _every_result_class() -> list[type]:
    import importlib
    import pkgutil

    import posture_id
    from posture_id.fileio import Result

    for info in pkgutil.walk_packages(posture_id.__path__, "posture_id."):
        if not info.name.endswith("__main__"):  # the console entry runs on import
            importlib.import_module(info.name)
    found, todo = [], [Result]
    while todo:
        for sub in todo.pop().__subclasses__():
            found.append(sub)
            todo.append(sub)
    return found


def test_every_result_belongs_to_one_family():
    """Every result class has to_dict(), to_json(), summary() and plot(path=None,
    ax=None) of its own; none takes a folder where the others take a file."""
    import inspect

    from posture_id.fileio import Result

    classes = _every_result_class()
    names = {c.__name__ for c in classes}
    assert {"SimulationResult", "BatchResult", "FitResult", "FrequencyResponse",
            "IdentificationResult", "CnnIdentification", "CohortResult", "TrainingResult",
            "EvaluationReport", "BenchmarkReport", "CalibrationReport"} <= names, names
    for cls in classes:
        for method in ("to_dict", "summary", "plot"):
            assert getattr(cls, method) is not getattr(Result, method), (cls, method)
        parameters = list(inspect.signature(cls.plot).parameters.values())[1:3]
        assert [(p.name, p.default) for p in parameters] == [("path", None), ("ax", None)], cls
