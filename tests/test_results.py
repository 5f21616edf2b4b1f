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
