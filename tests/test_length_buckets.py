"""Recordings of other lengths share one compiled fit model (issue 44): lengths within a
bucket of 500 samples (10 s at 50 Hz) run on the same compiled code, and the model's
first samples are the recording's."""

from __future__ import annotations

import numpy as np
import pytest

from posture_id.fitting import problem as problem_module
from posture_id.fitting.options import FitOptions
from posture_id.fitting.problem import BUCKET_SAMPLES, FitProblem, bucket_samples
from posture_id.fitting.symbolic import step_inputs
from posture_id.fitting.unknowns import q_from_targets
from posture_id.recording import Recording
from posture_id.simulation import prts, simulate
from posture_id.trials import prepare_trial


def test_buckets_round_up_to_whole_buckets():
    assert bucket_samples(1) == BUCKET_SAMPLES
    assert bucket_samples(6051) == bucket_samples(6001) == 6500
    assert bucket_samples(6500) == 6500 and bucket_samples(6501) == 7000


@pytest.mark.slow
def test_five_lengths_fit_on_one_compiled_model(tip, monkeypatch):
    """A lab's five trials of 121.0–124.6 s (the same 242-state PRTS, level stretches of
    different lengths after it) are fitted on one compiled model; each fit's simulated
    sway has the recording's length and matches the compiled simulator's own."""
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
    for extra in (0, 20, 50, 110, 180):  # samples after the last cycle
        n = len(base.time) + extra
        time = np.arange(n) / base.sample_rate_hz
        theta = np.vstack([base.theta, np.repeat(base.theta[-1:], extra, axis=0)])
        recording = Recording(time, stimulus.angle(time), theta, base.segments)
        trial = prepare_trial(recording, stimulus)
        problem = FitProblem.get(tip, len(trial.recording.time), options)
        tilt, velocity = stimulus.on_grid(options.simulation.dt, problem.n_steps_u)
        u = step_inputs(tilt, velocity, problem.n_steps_u)
        # the defaults (q = 0) with the default classes: com, joint, com
        classes = np.array([[0, 0, 0, 0, 1], [0, 0, 0, 0, -1], [0, 0, 0, 0, 1]])
        q = q_from_targets(classes.astype(float), np.zeros((tip.n_segments, 2)))
        sway = problem.simulate(q, u)
        assert sway.shape == (n, tip.n_segments)
        np.testing.assert_allclose(sway[: len(base.time)], base.theta, atol=1e-6)
        jac = problem.jacobian(q, u, [0, 1])
        assert jac.shape == (n * tip.n_segments, 2)
    assert len(set(keys)) == 1 and keys[0].n_samples == bucket_samples(6051)
