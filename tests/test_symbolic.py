"""CasADi model: symbolic dynamics against Pinocchio, symbolic rollout against the fast
simulator."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest
from conftest import random_parameters

from posture_id.dec import ParameterArrays
from posture_id.fitting.symbolic import (
    SymbolicModel,
    body_constants,
    buffer_sizes,
    chain_dynamics,
    delay_weights,
    rollout_function,
    rollout_steps,
    step_inputs,
)
from posture_id.simulation import SimulationOptions, prts, simulate, simulate_batch


def test_symbolic_dynamics_match_pinocchio(any_body):
    body = any_body
    n = body.n_segments
    f = chain_dynamics(body)
    rng = np.random.default_rng(2)
    lower = np.tril(np.ones((n, n)))
    model, data = body.model, body.model.createData()
    for _ in range(20):
        q = rng.uniform(-0.4, 0.4, n)
        v = rng.uniform(-2, 2, n)
        tau = rng.uniform(-300, 300, n)
        acc, mass, grav = (np.array(x) for x in f(lower @ q, lower @ v, tau))
        m_pin = pin.crba(model, data, q)
        m_pin = np.triu(m_pin) + np.triu(m_pin, 1).T
        np.testing.assert_allclose(lower.T @ mass @ lower, m_pin, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(lower.T @ grav.ravel(),
                                   pin.computeGeneralizedGravity(model, data, q),
                                   rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(acc.ravel(), lower @ pin.aba(model, data, q, v, tau),
                                   rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("body_name", ["tip", "winter", "winter2", "talos_bent"])
def test_symbolic_rollout_equals_fast_simulator(request, body_name):
    body = request.getfixturevalue(body_name)
    params = random_parameters(body, np.random.default_rng(5))
    options = SimulationOptions()
    stim = prts(amplitude_deg=2.0)  # the full 121 s trial
    fast = simulate(body, params, stim, options)
    n_steps = options.n_steps(stim)
    n_samples = n_steps // options.sample_every + 1
    delay = options.delay_steps(params.array("delay_s"))
    sizes = buffer_sizes(delay + 3)
    model = SymbolicModel(body.n_segments, tuple(sizes), options.dt, options.deadband_rad_s)
    rollout = rollout_function(model, n_samples, options.sample_every)
    tilt, tilt_vel = stim.on_grid(options.dt, n_steps)
    u = step_inputs(tilt, tilt_vel, rollout_steps(n_samples, options.sample_every))
    p = np.concatenate([params.array(f) for f in ("kp", "ki", "kd")]
                       + [delay, params.array("sign"), params.array("kpas"),
                          params.array("bpas")])
    d = ca.SX.sym("d", body.n_segments)
    weights = ca.Function("w", [d], [delay_weights(d, sizes)])(delay)
    theta = np.array(rollout(u, p, weights, body_constants(body))).T
    assert np.abs(fast.theta).max() > 1e-3
    np.testing.assert_allclose(theta, fast.theta, rtol=0, atol=1e-8)


def _rollout_theta(body, params: ParameterArrays, stim, options, smooth: float) -> np.ndarray:
    """(S, N) rad: the CasADi rollout of one trial (relaxed classes allowed)."""
    n_steps = options.n_steps(stim)
    n_samples = n_steps // options.sample_every + 1
    delay = options.delay_steps(params.delay_s[0])
    sizes = buffer_sizes(delay + 3)
    model = SymbolicModel(body.n_segments, tuple(sizes), options.dt, options.deadband_rad_s,
                          smooth=smooth)
    rollout = rollout_function(model, n_samples, options.sample_every)
    tilt, tilt_vel = stim.on_grid(options.dt, n_steps)
    u = step_inputs(tilt, tilt_vel, rollout_steps(n_samples, options.sample_every))
    p = np.concatenate([params.kp[0], params.ki[0], params.kd[0], delay, params.sign[0],
                        params.kpas[0], params.bpas[0]])
    d = ca.SX.sym("d", body.n_segments)
    weights = ca.Function("w", [d], [delay_weights(d, sizes)])(delay)
    return np.array(rollout(u, p, weights, body_constants(body))).T


def test_relaxed_classes_and_smoothed_deadband_match_the_compiled_kernel(tip):
    """What the fit relies on: its warm start (the compiled kernel) and its exact stages
    (CasADi) are the same model for classes strictly between −1 and 1, and smoothing the
    dead-band (softplus, width 1e-5 rad/s) moves the sway by a negligible amount: the
    PRTS's tilt rate is piecewise constant, never near the ±0.0003 rad/s threshold."""
    params = random_parameters(tip, np.random.default_rng(8)).arrays()
    relaxed = np.array([[0.6, -0.3, 0.2]])
    params = ParameterArrays(**{f: getattr(params, f) for f in ParameterArrays.FIELDS
                                if f != "sign"}, sign=relaxed)
    options = SimulationOptions()
    stim = prts(amplitude_deg=2.0)
    fast = simulate_batch(tip, params, stim, options).theta[0]
    assert np.all(np.isfinite(fast)) and np.abs(fast).max() > 1e-3
    exact = _rollout_theta(tip, params, stim, options, smooth=0.0)
    np.testing.assert_allclose(exact, fast, rtol=0, atol=1e-8)
    smoothed = _rollout_theta(tip, params, stim, options, smooth=1e-5)
    np.testing.assert_allclose(smoothed, fast, rtol=0, atol=1e-8)
    # and the relaxed class is really a mixture: the sway differs from both pure classes
    for pure in (1.0, -1.0):
        other = ParameterArrays(**{f: getattr(params, f) for f in ParameterArrays.FIELDS
                                   if f != "sign"}, sign=np.full((1, 3), pure))
        assert np.abs(simulate_batch(tip, other, stim, options).theta[0] - fast).max() > 1e-4


def test_bodies_with_as_many_segments_share_one_compiled_model(winter, tmp_path):
    """The body's constants are inputs of the compiled code: a second 3-segment body (a
    Winter subject of another height and mass) runs on the same compiled model as the
    first, and each simulates its own body exactly as the fast simulator does."""
    from posture_id.bodies.anthropometry import straight_links, winter_segments
    from posture_id.bodies.body import load_body
    from posture_id.bodies.urdf_writer import write_chain_urdf
    from posture_id.dec.parameters import normalise
    from posture_id.fitting import Compilation, FitOptions
    from posture_id.fitting.problem import FitProblem
    from posture_id.fitting.unknowns import passive_normalised, q_from_targets

    path = tmp_path / "short_heavy.urdf"
    write_chain_urdf(path, "short_heavy", straight_links(winter_segments(1.55, 95.0, 3)))
    other = load_body(path)
    assert other.n_segments == winter.n_segments
    assert not np.allclose(body_constants(other), body_constants(winter))
    options = SimulationOptions()
    stim = prts(amplitude_deg=2.0, cycles=1, states=80, state_s=0.1)
    n_samples = options.n_steps(stim) // options.sample_every + 1
    fit_options = FitOptions(compilation=Compilation.NEVER)
    messages: list[str] = []
    problems = [FitProblem.get(b, n_samples, fit_options, notify=messages.append)
                for b in (winter, other)]
    assert problems[0].model is problems[1].model
    assert problems[0] is not problems[1]
    for body, problem in zip((winter, other), problems, strict=True):
        params = random_parameters(body, np.random.default_rng(11))
        q = q_from_targets(normalise(params, problem.defaults),
                           passive_normalised(params, problem.defaults))
        n_steps = options.n_steps(stim)
        tilt, tilt_vel = stim.on_grid(options.dt, problem.n_steps_u)
        u = step_inputs(tilt, tilt_vel, problem.n_steps_u)
        fast = simulate(body, params, stim, options)
        assert n_steps // options.sample_every + 1 == len(fast.time)
        np.testing.assert_allclose(problem.simulate(q, u), fast.theta, rtol=0, atol=1e-8)
