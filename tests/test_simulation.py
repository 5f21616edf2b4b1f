"""Simulation: compiled kernel vs the Pinocchio reference, step halving, stability,
batches, aborts, delays."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import random_parameters

from posture_id.dec.parameters import ParameterArrays, default_parameters
from posture_id.errors import SimulationError
from posture_id.simulation import SimulationOptions, TiltProfile, prts, simulate, simulate_batch
from posture_id.simulation.reference import simulate_reference


def _first_seconds(stim: TiltProfile, seconds: float, gain: float = 1.0) -> TiltProfile:
    knots = int(round(seconds / 0.25)) + 1
    return TiltProfile(stim.times[:knots], stim.angles[:knots] * gain, f"first {seconds} s")


@pytest.mark.parametrize("body_name", ["tip", "winter", "winter2", "talos_bent"])
@pytest.mark.parametrize("seed", [0, 1])
def test_compiled_matches_pinocchio_reference_over_5s(request, body_name, seed):
    any_body = request.getfixturevalue(body_name)
    rng = np.random.default_rng(seed)
    params = default_parameters(any_body) if seed == 0 else random_parameters(any_body, rng)
    stim = _first_seconds(prts(amplitude_deg=4.0), 5.0)
    fast = simulate(any_body, params, stim)
    ref = simulate_reference(any_body, params, stim)
    assert fast.stable and ref.stable
    assert np.abs(fast.theta).max() > 1e-3  # the body actually moved
    np.testing.assert_allclose(fast.theta, ref.theta, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fast.alpha, ref.alpha, rtol=0, atol=1e-12)


def test_step_halving_changes_121s_sway_by_under_2_percent(tip):
    coarse = simulate(tip, options=SimulationOptions(dt=0.002))
    fine = simulate(tip, options=SimulationOptions(dt=0.001))
    assert coarse.theta.shape == fine.theta.shape == (6051, 3)
    for j in range(3):
        diff = coarse.theta[:, j] - fine.theta[:, j]
        rel = np.sqrt(np.mean(diff**2)) / np.sqrt(np.mean(fine.theta[:, j] ** 2))
        assert rel < 0.02, (j, rel)
    # and the difference is real: the integrator is first order, not exact
    assert not np.allclose(coarse.theta, fine.theta, atol=1e-9)


@pytest.mark.parametrize("fixture", ["tip", "winter", "winter2", "winter1"])
def test_default_parameters_are_stable(request, fixture):
    body = request.getfixturevalue(fixture)
    result = simulate(body)
    assert result.stable
    assert result.theta.shape == (6051, body.n_segments)
    assert np.all(np.isfinite(result.theta))
    assert 0.02 < np.degrees(np.abs(result.alpha[:, 0]).max()) < 2.0


def test_recording_samples_and_tilt(tip):
    result = simulate(tip)
    np.testing.assert_allclose(result.time[:3], [0, 0.02, 0.04])
    assert result.time[-1] == pytest.approx(121.0)
    assert np.all(result.theta[0] == 0.0)
    np.testing.assert_allclose(result.tilt, prts().angle(result.time), atol=1e-15)


def test_batch_equals_single_trials_and_is_worker_independent(tip):
    rng = np.random.default_rng(3)
    sets = [random_parameters(tip, rng, spread=0.5) for _ in range(37)]  # > one block
    arrays = ParameterArrays.from_parameters(sets)
    one = simulate_batch(tip, arrays, workers=1)
    two = simulate_batch(tip, arrays, workers=2)
    np.testing.assert_array_equal(one.theta, two.theta)
    np.testing.assert_array_equal(one.abort_time, two.abort_time)
    for b in (0, 17, 36):
        single = simulate(tip, sets[b])
        np.testing.assert_array_equal(single.theta, one.theta[b])
        assert (single.abort_time is None) == np.isnan(one.abort_time[b])


def test_unstable_trial_is_aborted_and_reported(tip):
    d = default_parameters(tip)
    weak = d.replace("ankle", kp=0.1 * d["ankle"].kp, ki=0.0, kpas=0.3 * d["ankle"].kpas)
    batch = simulate_batch(tip, ParameterArrays.from_parameters([d, weak, d]))
    assert list(batch.stable) == [True, False, True]
    t_abort = batch.abort_time[1]
    assert 0 < t_abort < 121
    k = int(np.ceil(t_abort / 0.02))
    assert np.all(np.isfinite(batch.theta[1, :k]))
    assert np.all(np.isnan(batch.theta[1, k:]))
    assert np.degrees(np.abs(batch.theta[1, :k]).max()) <= 6.0
    # neighbours in the same block are untouched by the abort
    np.testing.assert_array_equal(batch.theta[0], batch.theta[2])
    np.testing.assert_array_equal(batch.theta[0], simulate(tip, d).theta)
    trial = batch.trial(1)
    assert trial.abort_time == pytest.approx(t_abort)


def test_sway_limit_is_configurable(tip):
    d = default_parameters(tip)
    weak = d.replace("ankle", kp=0.1 * d["ankle"].kp, ki=0.0, kpas=0.3 * d["ankle"].kpas)
    at6 = simulate(tip, weak)
    at3 = simulate(tip, weak, options=SimulationOptions(sway_limit_deg=3.0))
    assert at3.abort_time < at6.abort_time


def test_delay_is_interpolated_not_rounded(tip):
    d = default_parameters(tip)
    runs = {
        delay: simulate(tip, d.replace("hip", delay_s=delay)).theta[:, 2]
        for delay in (0.120, 0.121, 0.122)
    }
    mid = runs[0.121]
    assert not np.allclose(mid, runs[0.120], atol=1e-12)
    assert not np.allclose(mid, runs[0.122], atol=1e-12)
    # half a step lies between its neighbours: closer to their mean than to either
    mean = (runs[0.120] + runs[0.122]) / 2
    assert np.abs(mid - mean).max() < 0.2 * np.abs(runs[0.120] - runs[0.122]).max()


def test_servo_is_silent_before_the_delay(tip):
    """With no passive, no gravity PD and a pure step tilt, nothing acts before Δ."""
    d = default_parameters(tip)
    p = d
    for j in tip.joint_names:
        p = p.replace(j, delay_s=0.5, kpas=0.0, bpas=0.0)
    step = TiltProfile(np.array([0.0, 0.002, 1.0]), np.radians([0.0, 0.5, 0.5]), "step")
    free = simulate(tip, p, step)  # gravity and the T_g PD act; the servo not before 0.5 s
    q = p.replace("ankle", controls="joint")  # a different servo variable
    other = simulate(tip, q, step)
    before = free.time < 0.5 - 1e-9
    np.testing.assert_array_equal(free.theta[before], other.theta[before])
    assert not np.allclose(free.theta[~before], other.theta[~before])


def test_bad_options_and_shapes(tip):
    with pytest.raises(SimulationError, match="sway_limit_deg"):
        SimulationOptions(sway_limit_deg=60)
    with pytest.raises(SimulationError, match="not a multiple of dt"):
        SimulationOptions(dt=0.003)
    # a stimulus that ends off the sample grid runs to the next sample, its tilt held
    off_grid = simulate(tip, stimulus=TiltProfile(np.array([0.0, 1.01]), np.array([0, 1e-3])))
    assert off_grid.time[-1] == pytest.approx(1.02) and off_grid.tilt[-1] == 1e-3
    with pytest.raises(SimulationError, match="modules"):
        arrays = ParameterArrays.from_parameters([default_parameters(tip)])
        simulate_batch(tip, ParameterArrays(**{k: v[:, :2] for k, v in arrays.__dict__.items()}))
