"""MuJoCo as an oracle of the compiled simulator: the TIP on its platform under
DEC, stepped by an independent engine (its own kinematic tree, mass matrix, bias forces,
joint stiffness and damping, RK4 integrator; sensors read from its state), against
posture_id's compiled simulator (its own planar equations, 2 ms semi-implicit Euler).

Measured (``benchmarks/mujoco_oracle.py``, docs/results/mujoco_oracle/report.md): over the
default 121 s PRTS (242 states ×2, 1°, default DEC parameters), RMS of the difference over
RMS of the sway, shank / thigh / trunk:

- MuJoCo RK4 1 ms against the compiled simulator at its default 2 ms: 0.15 / 0.23 / 0.47 %
  (the issue's bound: 1 %);
- both step-halved towards one limit: against the compiled simulator at 0.125 ms, the
  compiled simulator's error is 0.15 / 0.21 / 0.47 % at 2 ms, 0.07 / 0.10 / 0.22 % at 1 ms;
  MuJoCo's 0.06 / 0.20 / 0.35 % at 2 ms, 0.03 / 0.10 / 0.17 % at 1 ms, 0.016 / 0.05 /
  0.08 % at 0.5 ms: both first order (the controller runs once per step and holds its
  torque: RK4's plant is not what limits MuJoCo), both halving towards the same limit;
- the two limits, each extrapolated from its last two steps (Richardson, first order),
  agree to 2e-6 / 3e-6 / 5e-6 of the sway;
- so the 0.15–0.47 % between MuJoCo at 1 ms and the compiled simulator at 2 ms is mostly
  the compiled simulator's own 2 ms step (0.15–0.47 % from the limit), not MuJoCo's
  (0.03–0.17 %), and not a difference of model.

The 1 % bound alone cannot see a delay 1 ms off (it moves the converged sway by 0.006 to
0.12 %), so the step-halving test also checks that MuJoCo's error halves with its step and
that the two extrapolated limits agree to 1e-4: a fixed 1 ms error in every delay breaks
it (put back, it failed: MuJoCo's error went from 0.07 / 0.20 / 0.38 % to 0.055 / 0.15 /
0.30 %, not halving). A delay read one step late is an error that vanishes with the step;
it converges with the rest and is caught by the delay line's own test (put back, that
test failed and the others passed).
"""

from __future__ import annotations

import numpy as np
import pytest

from posture_id.dec.parameters import default_parameters
from posture_id.robots.errors import RobotError
from posture_id.robots.mujoco_model import ChainModel, MujocoOptions
from posture_id.robots.mujoco_sim import ChainSensors, DelayLine, simulate_mujoco
from posture_id.simulation import SimulationOptions, TiltProfile, prts, simulate
from posture_id.simulation.reference import com_above_angles

mujoco = pytest.importorskip("mujoco")


def _relative_rms(x: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """(N,) RMS of x − reference over RMS of reference, per column."""
    return np.sqrt(np.mean((x - reference) ** 2, axis=0) / np.mean(reference**2, axis=0))


def _first(stimulus: TiltProfile, states: int) -> TiltProfile:
    return TiltProfile(stimulus.times[: states + 1], stimulus.angles[: states + 1],
                       f"first {states} states", period_s=stimulus.period_s)


@pytest.mark.parametrize("fixture", ["tip", "winter2", "talos_bent"])
def test_the_mujoco_chain_has_the_urdfs_dynamics(request, fixture):
    """MuJoCo's accelerations of the chain equal Pinocchio's (``aba``) at random states and
    torques: masses, COMs, inertias, placements and axes carried over; the platform's
    armature keeps it still while the body pushes on it."""
    import pinocchio as pin

    body = request.getfixturevalue(fixture)
    chain = ChainModel.build(body)
    model, data = chain.model, mujoco.MjData(chain.model)
    pdata = body.model.createData()
    rng = np.random.default_rng(3)
    for _ in range(4):
        data.qpos[:] = rng.normal(size=model.nq) * 0.2
        data.qvel[:] = rng.normal(size=model.nv) * 0.5
        tau = rng.normal(size=body.n_segments) * 30.0
        data.qfrc_applied[:] = 0.0
        data.qfrc_applied[chain.joint_dofs] = tau
        mujoco.mj_forward(model, data)
        assert abs(data.qacc[chain.platform_dof]) < 1e-6
        # Pinocchio's coordinates: (θ_1, q_2, ...), the foot fixed, the ankle axis still
        q = np.array(data.qpos[chain.joint_qpos])
        v = np.array(data.qvel[chain.joint_dofs])
        q[0] += data.qpos[chain.platform_qpos]
        v[0] += data.qvel[chain.platform_dof]
        expected = pin.aba(body.model, pdata, q, v, tau)
        got = np.array(data.qacc[chain.joint_dofs])
        got[0] += data.qacc[chain.platform_dof]
        np.testing.assert_allclose(got, expected, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("fixture", ["tip", "talos_bent"])
def test_sensors_read_from_mujoco_match_pinocchio(request, fixture):
    """Segment angles, COM-above angles and their rates from MuJoCo's sites and subtree
    COMs equal the Pinocchio reference's (posture_id.simulation.reference)."""
    body = request.getfixturevalue(fixture)
    chain = ChainModel.build(body)
    data = mujoco.MjData(chain.model)
    sense = ChainSensors(chain, data)
    rng = np.random.default_rng(5)
    for _ in range(4):
        data.qpos[:] = rng.normal(size=chain.model.nq) * 0.1
        data.qvel[:] = rng.normal(size=chain.model.nv) * 0.4
        mujoco.mj_forward(chain.model, data)
        theta, omega, alpha, alpha_rate, platform, platform_rate = sense()
        q = np.array(data.qpos[chain.joint_qpos])
        v = np.array(data.qvel[chain.joint_dofs])
        q[0] += data.qpos[chain.platform_qpos]
        v[0] += data.qvel[chain.platform_dof]
        np.testing.assert_allclose(theta, np.cumsum(q), atol=1e-12)
        np.testing.assert_allclose(omega, np.cumsum(v), atol=1e-12)
        ref_alpha, ref_rate = com_above_angles(body, q, v)
        np.testing.assert_allclose(alpha, ref_alpha, atol=1e-12)
        np.testing.assert_allclose(alpha_rate, ref_rate, atol=1e-10)
        assert platform == pytest.approx(data.qpos[chain.platform_qpos], abs=1e-12)
        assert platform_rate == pytest.approx(data.qvel[chain.platform_dof], abs=1e-12)


def test_the_delay_line_interpolates_and_holds_before_the_delay():
    line = DelayLine(np.array([2.5, 0.0, 1.0 + 1e-12]), hold=[7.0, 8.0, 9.0])
    out = [line.push_and_read([10.0 * k, k, -k]) for k in range(5)]
    assert [o[0] for o in out] == [7.0, 7.0, 7.0, 5.0, 15.0]  # u(k − 2.5), hold before
    assert [o[1] for o in out] == [0.0, 1.0, 2.0, 3.0, 4.0]  # no delay: the command itself
    assert [o[2] for o in out] == [9.0, 0.0, -1.0, -2.0, -3.0]  # 1 + 1e-12 snapped to 1


def test_bad_options_are_refused_in_one_line(tip):
    for bad in ({"timestep_s": 0.0}, {"integrator": "rk45"}, {"platform_armature": 10.0}):
        with pytest.raises(RobotError) as err:
            MujocoOptions(**bad)
        assert "\n" not in str(err.value)
    with pytest.raises(RobotError, match="not a multiple"):
        simulate_mujoco(tip, stimulus=_first(prts(), 4),
                        mujoco_options=MujocoOptions(timestep_s=0.003))


@pytest.mark.slow("MuJoCo at a 1 ms step")
def test_tip_in_mujoco_agrees_with_the_compiled_simulator_within_1_percent(tip):
    """The issue's criterion: the default 121 s PRTS, default DEC, MuJoCo RK4 at 1 ms against
    the compiled simulator at its default 2 ms: ≤ 1 % RMS of the sway per segment and for
    every COM-above angle (measured 0.15 / 0.23 / 0.47 %, the module docstring)."""
    compiled = simulate(tip)
    engine = simulate_mujoco(tip, mujoco_options=MujocoOptions(timestep_s=0.001,
                                                              integrator="rk4"))
    assert compiled.stable and engine.stable
    assert engine.theta.shape == compiled.theta.shape == (6051, 3)
    np.testing.assert_allclose(engine.time, compiled.time)
    np.testing.assert_allclose(engine.tilt, compiled.tilt, atol=1e-15)
    assert np.degrees(np.abs(engine.theta).max()) > 0.1  # the body swayed
    assert np.all(_relative_rms(engine.theta, compiled.theta) <= 0.01)
    assert np.all(_relative_rms(engine.alpha, compiled.alpha) <= 0.01)


@pytest.mark.slow("MuJoCo at 1 and 0.5 ms steps")
def test_step_halving_brings_both_engines_to_one_limit(tip):
    """On the PRTS's first 30 s: MuJoCo's difference from the converged compiled sway halves
    with its step (first order), and the two extrapolated limits agree to 1e-4 of the sway
    (measured 1e-6 to 5e-6), far below what a delay one step off gives."""
    stimulus = _first(prts(), 121)
    compiled = {dt: simulate(tip, stimulus=stimulus, options=SimulationOptions(dt=dt)).theta
                for dt in (0.002, 0.00025, 0.000125)}
    engine = {dt: simulate_mujoco(tip, stimulus=stimulus,
                                  mujoco_options=MujocoOptions(timestep_s=dt)).theta
              for dt in (0.001, 0.0005)}
    limit = compiled[0.000125]
    coarse = _relative_rms(engine[0.001], limit)
    fine = _relative_rms(engine[0.0005], limit)
    assert np.all((fine > 0.3 * coarse) & (fine < 0.7 * coarse)), (coarse, fine)
    # which side: the compiled simulator at 2 ms is further from the limit than MuJoCo at 1 ms
    assert np.all(_relative_rms(compiled[0.002], limit) > coarse)
    engine_limit = 2.0 * engine[0.0005] - engine[0.001]
    compiled_limit = 2.0 * compiled[0.000125] - compiled[0.00025]
    assert np.all(_relative_rms(engine_limit, compiled_limit) < 1e-4)


def test_a_fall_is_reported_with_its_time(tip):
    """Too little gain (Kp, Ki, Kpas × 0.3): both engines report the fall (a segment past
    6°) at the same time, within two samples; the sway after it is NaN."""
    params = default_parameters(tip)
    for joint in tip.joint_names:
        m = params[joint]
        params = params.replace(joint, kp=0.3 * m.kp, ki=0.3 * m.ki, kpas=0.3 * m.kpas)
    stimulus = _first(prts(), 40)
    engine = simulate_mujoco(tip, params, stimulus)
    compiled = simulate(tip, params, stimulus)
    assert not engine.stable and not compiled.stable
    assert engine.abort_time == pytest.approx(compiled.abort_time, abs=0.04)
    fallen = int(np.ceil(engine.abort_time / 0.02))
    assert np.all(np.isnan(engine.theta[fallen:])) and np.all(np.isfinite(engine.theta[:fallen]))
    assert "left the ±6° limit" in engine.summary()
