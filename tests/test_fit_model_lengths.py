"""Recordings of any length share one compiled fit model (issue 44): the compiled code
simulates one block of samples and a recording runs block after block, so its length is
not compiled in; the simulation and its Jacobian are the compiled simulator's and the
finite differences' whatever the length."""

from __future__ import annotations

import numpy as np
import pytest

from posture_id.fitting import problem as problem_module
from posture_id.fitting.options import FitOptions
from posture_id.fitting.problem import FitProblem
from posture_id.fitting.symbolic import BLOCK_SAMPLES, step_inputs
from posture_id.fitting.unknowns import q_from_targets
from posture_id.recording import Recording
from posture_id.simulation import prts, simulate
from posture_id.trials import prepare_trial


@pytest.mark.slow("Jacobians over five recording lengths, 3 segments")
def test_five_lengths_fit_on_one_compiled_model(tip, monkeypatch):
    """A lab's trials of 40 s to 124.6 s (the same 242-state PRTS, level stretches of
    different lengths after it; one shorter than a block, one a block and a sample) run
    on one compiled model; each simulated sway has the recording's length and matches
    the compiled simulator's own, and the Jacobian carried through the blocks matches
    central differences."""
    keys = []
    real_get = problem_module.CompiledModel.get.__func__

    def counting(cls, key, notify=None):
        keys.append(key)
        return real_get(cls, key, notify)

    monkeypatch.setattr(problem_module.CompiledModel, "get", classmethod(counting))
    monkeypatch.setattr(FitProblem, "_cache", problem_module._ProcessCache(16))
    stimulus = prts()
    base = simulate(tip, stimulus=stimulus).to_recording()
    options = FitOptions()
    classes = np.array([[0, 0, 0, 0, 1], [0, 0, 0, 0, -1], [0, 0, 0, 0, 1]])
    q = q_from_targets(classes.astype(float), np.zeros((tip.n_segments, 2)))
    for n in (BLOCK_SAMPLES // 2, BLOCK_SAMPLES + 1, 2001, 6051, 6051 + 180):
        time = np.arange(n) / base.sample_rate_hz
        keep = min(n, len(base.time))
        theta = np.vstack([base.theta[:keep], np.repeat(base.theta[keep - 1:keep],
                                                        n - keep, axis=0)])
        trial = prepare_trial(Recording(time, stimulus.angle(time), theta, base.segments),
                              stimulus if n > len(base.time) else None)
        problem = FitProblem.get(tip, len(trial.recording.time), options)
        tilt, velocity = stimulus.on_grid(options.simulation.dt, problem.n_steps_u)
        u = step_inputs(tilt, velocity, problem.n_steps_u)
        sway = problem.simulate(q, u)
        assert sway.shape == (n, tip.n_segments)
        np.testing.assert_allclose(sway[:keep], base.theta[:keep], atol=1e-6)
        jac = problem.jacobian(q, u, [0, 8])
        assert jac.shape == (n * tip.n_segments, 2)
        if n == 2001:  # the chain rule across blocks, against central differences
            for k, column in enumerate((0, 8)):
                step = np.zeros_like(q)
                step[column] = 1e-5
                diff = (problem.simulate(q + step, u) - problem.simulate(q - step, u)) / 2e-5
                np.testing.assert_allclose(jac[:, k], diff.ravel(), rtol=0,
                                           atol=1e-4 * np.abs(diff).max())
    assert len(set(keys)) == 1


@pytest.mark.slow("a whole cohort through the command line, compiling its model")
def test_a_cohort_of_five_lengths_compiles_once(winter1, tmp_path):
    """A cohort of five recordings of five lengths (20.0–28.0 s), fitted by the command line
    on an empty cache with no prebuilt models: one compiled library in the cache (a
    1-segment body: its model compiles in a few seconds; the length rule is the same)."""
    import os
    import subprocess
    import sys

    folder = tmp_path / "recordings"
    folder.mkdir()
    stimulus = prts(states=80, cycles=1)
    base = simulate(winter1, stimulus=stimulus.spanning(28.0)).to_recording()
    for k, seconds in enumerate((20.0, 22.0, 24.5, 26.0, 28.0)):
        keep = base.time <= seconds + 1e-9
        Recording(base.time[keep], base.tilt[keep], base.theta[keep],
                  base.segments).to_csv(folder / f"s{k}.csv")
    env = {**os.environ, "POSTURE_ID_CACHE": str(tmp_path / "cache"),
           "POSTURE_ID_PREBUILT": "none"}
    done = subprocess.run([sys.executable, "-m", "posture_id.cli", "identify", str(folder),
                           "--body", str(winter1.urdf_path), "--method", "fit", "--states",
                           "80", "--cycles", "1", "--out", str(tmp_path / "out")],
                          capture_output=True, text=True, env=env)
    assert done.returncode in (0, 1), done.stderr
    assert "5 identified" in done.stderr
    assert len(list((tmp_path / "cache" / "casadi").glob("*.so"))) == 1
