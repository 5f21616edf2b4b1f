"""Motor noise: the low-pass torque noise has the variance and spectrum it was asked for,
reaches the body through the joint torques exactly as in Pinocchio's reference, and is
seeded per trial."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import welch

from posture_id.dec.parameters import ParameterArrays, default_parameters
from posture_id.errors import SimulationError
from posture_id.simulation import TiltProfile, prts, simulate, simulate_batch
from posture_id.simulation.noise import MotorNoise, motor_noise_torques, per_trial
from posture_id.simulation.reference import simulate_reference

DT = 0.002


@pytest.mark.parametrize("cutoff_hz, tolerance", [(5.0, 0.03), (0.2, 0.10)])
def test_torque_sd_is_mgh_times_level(tip, cutoff_hz, tolerance):
    noise = MotorNoise(0.5, cutoff_hz, seed=3)
    trials = per_trial([MotorNoise(0.5, cutoff_hz, seed=s) for s in range(4)], 4)
    torques = motor_noise_torques(trials, 400_000, DT, tip.mgh, 4)  # (steps, N, lanes)
    sd = torques.std(axis=(0, 2))
    expected = tip.mgh * np.radians(noise.sd_deg)
    np.testing.assert_allclose(sd, expected, rtol=tolerance)
    # independent joints: correlations near zero
    flat = torques.transpose(1, 0, 2).reshape(3, -1)
    corr = np.corrcoef(flat)
    assert np.abs(corr[np.triu_indices(3, 1)]).max() < 0.05


def test_spectrum_is_the_first_order_low_pass():
    noise = MotorNoise(1.0, cutoff_hz=2.0, seed=7)
    eta = noise.unit_noise(2_000_000, 1, DT)[:, 0]
    f, measured = welch(eta, fs=1 / DT, nperseg=8192)
    analytic = noise.unit_psd(f, DT)
    band = (f > 0.1) & (f < 40)
    ratio = measured[band] / analytic[band]
    # Welch with ~500 averages: each bin within ±25 %, the bins on average within 2 %
    assert np.all(np.abs(ratio - 1) < 0.25)
    assert abs(ratio.mean() - 1) < 0.02
    # and it is low-pass, not white: a decade above the corner the power has fallen ~100×
    assert analytic[np.argmin(abs(f - 20))] < analytic[np.argmin(abs(f - 0.2))] / 50
    assert np.trapezoid(analytic, f) == pytest.approx(1.0, rel=0.02)  # unit variance


def test_stationary_from_the_first_step():
    noise = MotorNoise(1.0, cutoff_hz=0.05)
    first = np.array([noise.unit_noise(3, 1, DT, seed=s)[0, 0] for s in range(4000)])
    assert first.std() == pytest.approx(1.0, rel=0.05)


def test_kernel_adds_the_same_torque_as_the_pinocchio_reference(tip):
    params = default_parameters(tip)
    stim = TiltProfile(prts().times[:21], prts().angles[:21], "first 5 s")
    noise = MotorNoise(0.5, seed=11)
    fast = simulate(tip, params, stim, motor_noise=noise)
    ref = simulate_reference(tip, params, stim, motor_noise=noise)
    quiet = simulate(tip, params, stim)
    assert np.abs(fast.theta - quiet.theta).max() > 1e-4  # the noise moved the body
    np.testing.assert_allclose(fast.theta, ref.theta, rtol=0, atol=1e-12)


def test_each_trial_has_its_own_noise_whatever_its_batch(tip):
    params = default_parameters(tip)
    arrays = params.arrays()
    two = ParameterArrays(**{f: np.repeat(getattr(arrays, f), 2, axis=0)
                             for f in ParameterArrays.FIELDS})
    a, b = MotorNoise(0.3, seed=1), MotorNoise(0.3, seed=2)
    batch = simulate_batch(tip, two, motor_noise=[a, b])
    alone = simulate(tip, params, motor_noise=b)
    np.testing.assert_array_equal(batch.theta[1], alone.theta)
    assert not np.allclose(batch.theta[0], batch.theta[1])
    # one MotorNoise for a batch: trial b seeded by [seed, b], so trials differ
    shared = simulate_batch(tip, two, motor_noise=MotorNoise(0.3, seed=1))
    assert not np.allclose(shared.theta[0], shared.theta[1])


def test_zero_level_is_noise_free_and_sway_grows_linearly(tip):
    quiet = simulate(tip)
    zero = simulate(tip, motor_noise=MotorNoise(0.0))
    np.testing.assert_array_equal(quiet.theta, zero.theta)
    small = simulate(tip, motor_noise=MotorNoise(0.1, seed=4)).theta - quiet.theta
    double = simulate(tip, motor_noise=MotorNoise(0.2, seed=4)).theta - quiet.theta
    # the body is nearly linear at these angles: twice the noise, twice the extra sway
    assert np.linalg.norm(double - 2 * small) < 0.05 * np.linalg.norm(double)


@pytest.mark.parametrize("kwargs", [{"sd_deg": -0.1}, {"sd_deg": float("nan")},
                                    {"sd_deg": 0.1, "cutoff_hz": 0.0},
                                    {"sd_deg": 0.1, "seed": -1}])
def test_bad_motor_noise_is_refused(kwargs):
    with pytest.raises(SimulationError, match="motor noise"):
        MotorNoise(**kwargs)


def test_a_list_of_the_wrong_length_is_refused(tip):
    with pytest.raises(SimulationError, match="2 motor noises given for 1 trials"):
        simulate_batch(tip, default_parameters(tip).arrays(),
                       motor_noise=[MotorNoise(0.1), MotorNoise(0.1)])


def test_cli_simulate_with_motor_noise_is_the_api_trial(tip, tmp_path):
    from posture_id.cli import main
    from posture_id.recording import Recording

    out = tmp_path / "noisy.csv"
    assert main(["simulate", "--motor-noise", "0.3", "--motor-cutoff-hz", "0.5", "--seed", "9",
                 "--out", str(out)]) == 0
    recorded = Recording.from_csv(out, tip.segment_names)
    api = simulate(tip, motor_noise=MotorNoise(0.3, 0.5, seed=9))
    np.testing.assert_allclose(recorded.theta, api.theta, atol=1e-9)
    assert not np.allclose(recorded.theta, simulate(tip).theta, atol=1e-5)


@pytest.mark.parametrize("share", [0.1, 0.3])
def test_people_like_subject_has_the_asked_locked_share(tip, share):
    from posture_id.simulation.subjects import people_like

    subject = people_like(tip, default_parameters(tip), prts(states=80, cycles=6), share, 3)
    assert subject.locked_share == pytest.approx(share, rel=0.1)
    assert subject.motor_noise.sd_deg > 0
    # the recording is the noisy sway plus sensor noise; the locked response is noise-free
    assert np.std(subject.recording.theta - subject.locked.theta) > 0
    np.testing.assert_allclose(subject.locked.theta, simulate(
        tip, default_parameters(tip), prts(states=80, cycles=6)).theta)


def test_a_kept_unit_noise_is_the_fresh_draw_of_its_seed():
    """Trials simulated at several levels of one noise draw it once (the kept unit noise);
    what is kept is exactly the fresh draw of its seed, for every kind of seed."""
    import math

    from posture_id.simulation.noise import _unit_noise

    mgh = np.array([700.0, 300.0])
    trials = [(MotorNoise(0.3, 0.2, 7), np.random.SeedSequence([7, 3])),
              (MotorNoise(0.5, 0.3, 2**61 + 5), np.random.SeedSequence([2**61 + 5, 11])),
              (MotorNoise(0.2), np.random.SeedSequence(12345678901234567890)),
              (MotorNoise(0.2), np.random.SeedSequence(5).spawn(2)[1])]
    _unit_noise.cache_clear()
    first = motor_noise_torques(trials, 500, 0.002, mgh, 5)
    again = motor_noise_torques(trials, 500, 0.002, mgh, 5)
    assert _unit_noise.cache_info().hits == len(trials)
    for lane, (noise, seed) in enumerate(trials):
        fresh = noise.unit_noise(500, 2, 0.002, seed) * (mgh * math.radians(noise.sd_deg))
        assert np.array_equal(first[:, :, lane], fresh)
        assert np.array_equal(again[:, :, lane], fresh)
    assert not first[:, :, 4].any()  # the lane past the trials stays zero
    kept = _unit_noise(0.2, 7, (), 4, 10, 1, 0.002)
    assert not kept.flags.writeable
