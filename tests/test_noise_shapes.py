"""Noise of other shapes than the project's own: torque noise with other spectra, shared
between joints or changing its level; coloured sensor noise and drift; the families drawn
from them. Each against the analytic answer it was asked for."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import welch

from posture_id.errors import SimulationError
from posture_id.simulation import prts, simulate
from posture_id.simulation.measurement import MeasurementNoise
from posture_id.simulation.noise import MotorNoise, MotorShape
from posture_id.simulation.noise_families import NoiseFamily, draw_noise
from posture_id.simulation.subjects import people_like

DT = 0.002


def test_the_default_shape_is_the_exact_low_pass_draw_of_before():
    """The default MotorShape takes the Ornstein-Uhlenbeck path: the same numbers."""
    explicit = MotorNoise(1.0, 0.2, 5, MotorShape()).unit_noise(5000, 3, DT)
    plain = MotorNoise(1.0, 0.2, 5).unit_noise(5000, 3, DT)
    np.testing.assert_array_equal(explicit, plain)
    assert MotorShape().ornstein_uhlenbeck and not MotorShape(slope=1.0).ornstein_uhlenbeck


@pytest.mark.parametrize("shape", [
    MotorShape(slope=1.0),
    MotorShape(slope=1.5, second_cutoff_hz=2.0, second_slope=4.0),
])
def test_a_shaped_noise_has_the_spectrum_asked_for(shape):
    noise = MotorNoise(1.0, 0.3, seed=9, shape=shape)
    eta = noise.unit_noise(1_000_000, 2, DT)
    f, measured = welch(eta, fs=1 / DT, nperseg=8192, axis=0)
    analytic = shape.psd(f, noise.cutoff_hz)
    band = (f > 0.05) & (f < 20)
    ratio = measured[band].mean(axis=1) / analytic[band]
    ratio /= np.median(ratio)  # the analytic PSD is unnormalised: its shape is checked
    assert np.all(np.abs(ratio - 1) < 0.25)
    assert eta.std(axis=0) == pytest.approx([1.0, 1.0], rel=0.05)  # unit variance
    # the log-log slope is the one asked for (across the second corner, or above the first)
    pick = (f > 0.5) & (f < 4) if shape.second_cutoff_hz else (f > 2) & (f < 8)
    slope = np.polyfit(np.log(f[pick]), np.log(measured[pick].mean(axis=1)), 1)[0]
    expected = np.polyfit(np.log(f[pick]), np.log(analytic[pick]), 1)[0]
    assert slope == pytest.approx(expected, abs=0.15)


def test_shared_noise_has_the_asked_correlation_between_joints():
    eta = MotorNoise(1.0, 0.5, seed=2, shape=MotorShape(joint_correlation=0.7)
                     ).unit_noise(400_000, 3, DT)
    corr = np.corrcoef(eta.T)
    np.testing.assert_allclose(corr[np.triu_indices(3, 1)], 0.7, atol=0.05)
    np.testing.assert_allclose(eta.std(axis=0), 1.0, rtol=0.06)


def test_a_changing_level_goes_from_one_to_the_ratio():
    shape = MotorShape(level_ratio=2.5, change_at=0.4)
    eta = MotorNoise(1.0, 2.0, seed=4, shape=shape).unit_noise(200_000, 2, DT)
    start, end = eta[:60_000].std(), eta[-60_000:].std()
    assert start == pytest.approx(1.0, rel=0.06)
    assert end == pytest.approx(2.5, rel=0.06)
    t = np.array([0.0, 160.0, 400.0])
    np.testing.assert_allclose(shape.level(t, 400.0), [1.0, 1.75, 2.5], rtol=1e-6)


def test_coloured_sensor_noise_has_its_slope_and_sd():
    time = np.arange(200_000) * 0.02
    noise = MeasurementNoise(sd_deg=0.05, colour_slope=1.5).draw(time, 2, seed=1)
    f, measured = welch(noise, fs=50.0, nperseg=16384, axis=0)
    pick = (f > 0.1) & (f < 5)
    slope = np.polyfit(np.log(f[pick]), np.log(measured[pick].mean(axis=1)), 1)[0]
    assert slope == pytest.approx(-1.5, abs=0.1)  # well above the flat corner (0.01 Hz)
    assert noise.std(axis=0) == pytest.approx([0.05, 0.05], rel=0.1)
    white = MeasurementNoise(sd_deg=0.05).draw(time, 1, seed=1)
    assert np.abs(np.corrcoef(white[:-1, 0], white[1:, 0])[0, 1]) < 0.01


def test_drift_is_an_offset_a_trend_a_random_walk_and_steps():
    time = np.arange(6001) * 0.02  # 120 s
    trend = MeasurementNoise(offset_deg=0.3, trend_deg=0.2).draw(time, 3, seed=2)
    np.testing.assert_allclose(np.abs(trend[0]), 0.3, atol=1e-12)
    np.testing.assert_allclose(np.abs(trend[-1] - trend[0]), 0.2, atol=1e-12)
    walks = np.stack([MeasurementNoise(random_walk_deg=0.5).draw(time, 50, seed=s)
                      for s in range(20)])
    at_60 = walks[:, 3000].ravel()  # a random walk: SD 0.5° after 60 s, √2 of it at 120 s
    assert at_60.std() == pytest.approx(0.5, rel=0.1)
    assert walks[:, -1].std() == pytest.approx(0.5 * np.sqrt(2), rel=0.1)
    steps = MeasurementNoise(steps=2, step_deg=0.1).draw(time, 1, seed=3)[:, 0]
    jumps = np.flatnonzero(np.abs(np.diff(steps)) > 1e-12)
    assert 1 <= len(jumps) <= 2 and np.all(np.abs(np.diff(steps)[jumps]) == pytest.approx(0.1))


@pytest.mark.parametrize("bad", [dict(slope=-1), dict(joint_correlation=1.0),
                                 dict(level_ratio=0.0), dict(second_cutoff_hz=0.0),
                                 dict(change_at=2.0)])
def test_a_bad_shape_is_refused(bad):
    with pytest.raises(SimulationError, match=next(iter(bad))):
        MotorShape(**bad)


def test_bad_measurement_noise_is_refused():
    with pytest.raises(SimulationError, match="colour_slope"):
        MeasurementNoise(colour_slope=5)
    with pytest.raises(SimulationError, match="steps"):
        MeasurementNoise(steps=-1)


@pytest.mark.parametrize("family", list(NoiseFamily))
def test_every_family_makes_a_people_like_subject_with_the_asked_share(tip, family):
    from posture_id.dec.parameters import default_parameters

    draw = draw_noise(family, np.random.default_rng(3))
    assert draw.family is family and draw.to_dict()["family"] == family.value
    subject = people_like(tip, default_parameters(tip), prts(), 0.3, seed=8,
                          sensor_noise_deg=draw.sensor_noise_deg, cutoff_hz=draw.cutoff_hz,
                          shape=draw.shape, measurement=draw.measurement)
    assert subject.motor_noise.shape == draw.shape
    # the level is set for the asked share from the noise's own variance; one draw's
    # covariance with the locked response moves the realised share a little: reported
    assert subject.locked_share == pytest.approx(0.3, abs=0.1)
    noisy = simulate(tip, default_parameters(tip), prts(), motor_noise=subject.motor_noise)
    assert subject.locked_share == pytest.approx(
        np.var(subject.locked.alpha[:, 0]) / np.var(noisy.alpha[:, 0]), rel=1e-9)
