"""Stimulus: the PRTS against its known properties, and user tilt profiles."""

from __future__ import annotations

import numpy as np
import pytest

from posture_id.errors import StimulusError
from posture_id.simulation.stimulus import prts, prts_symbols, tilt_from_array, tilt_from_csv


def test_first_symbols_match_model():
    assert list(prts_symbols(242)[:10]) == [-1, 0, 0, -1, 1, 1, -1, -1, 1, 0]


@pytest.mark.parametrize("states", [242, 80])
def test_prts_is_maximal_length_with_antisymmetric_halves(states):
    s = prts_symbols(states).astype(int)
    assert len(s) == states
    # the register visits every non-zero state once: no shorter period
    doubled = np.tile(s, 2)
    for period in range(1, states):
        if states % period == 0:
            assert not np.array_equal(doubled[period : period + states], s), period
    half = states // 2
    np.testing.assert_array_equal(s[half:], -s[:half])
    # balanced: equal numbers of +1 and -1
    assert (s == 1).sum() == (s == -1).sum()


def test_prts_power_only_at_odd_harmonics():
    s = prts_symbols(242).astype(float)
    spectrum = np.abs(np.fft.rfft(s)) ** 2
    even, odd = spectrum[0::2], spectrum[1::2]
    assert even.max() < 1e-18 * odd.max() + 1e-20
    assert np.all(odd > 0)


def test_prts_position_returns_to_zero_and_has_the_amplitude():
    stim = prts(amplitude_deg=2.0, cycles=3)
    assert stim.duration == pytest.approx(3 * 60.5)
    cycle_knots = np.arange(0, len(stim.times), 242)
    np.testing.assert_allclose(stim.angles[cycle_knots], 0.0, atol=1e-15)
    one = stim.angles[:243]
    assert np.ptp(one) == pytest.approx(np.radians(2.0), rel=1e-12)
    # peak-to-peak spans 17 state steps, as docs/model.md §4 says
    steps = np.concatenate([[0], np.cumsum(prts_symbols(242))])
    assert np.ptp(steps) == 17


def test_prts_velocity_is_the_sequence_on_the_step_grid():
    stim = prts(amplitude_deg=1.0, cycles=1)
    dt = 0.002
    angle, velocity = stim.on_grid(dt, 30250)
    rate = np.radians(1.0) / 17 / 0.25  # rad/s per unit symbol
    symbols = prts_symbols(242)
    per_state = 125  # steps of 2 ms per 0.25 s state
    np.testing.assert_allclose(velocity[:-1], np.repeat(symbols, per_state) * rate, rtol=1e-12)
    np.testing.assert_allclose(np.diff(angle), velocity[:-1] * dt, atol=1e-15)


def test_eighty_state_prts_duration():
    assert prts(states=80, cycles=1).duration == pytest.approx(20.0)


def test_tilt_csv_round_trip_and_errors(tmp_path):
    good = tmp_path / "tilt.csv"
    good.write_text("time_s,tilt_deg\n0,0\n1,0.5\n2,0\n")
    stim = tilt_from_csv(good)
    assert stim.duration == 2.0
    assert stim.angle(0.5) == pytest.approx(np.radians(0.25))
    assert stim.velocity(0.5) == pytest.approx(np.radians(0.5))

    nan = tmp_path / "nan.csv"
    nan.write_text("time_s,tilt_deg\n0,0\n1,nan\n2,0\n")
    with pytest.raises(StimulusError) as err:
        tilt_from_csv(nan)
    assert str(nan) in str(err.value) and "line 3" in str(err.value)

    missing = tmp_path / "missing.csv"
    missing.write_text("t,tilt_deg\n0,0\n")
    with pytest.raises(StimulusError, match="column 'time_s' is missing"):
        tilt_from_csv(missing)

    back = tmp_path / "back.csv"
    back.write_text("time_s,tilt_deg\n0,0\n1,0\n1,0\n")
    with pytest.raises(StimulusError, match="does not increase"):
        tilt_from_csv(back)


def test_tilt_from_array_rejects_nan():
    with pytest.raises(StimulusError, match="not a finite number"):
        tilt_from_array([0, 1, 2], [0, np.nan, 0])


def test_recognise_prts_from_50hz_samples():
    from posture_id.simulation.stimulus import recognise_prts

    t = np.arange(6051) * 0.02
    stim = prts(amplitude_deg=1.5)
    found = recognise_prts(t, stim.angle(t))
    assert found is not None
    np.testing.assert_allclose(found.angles, stim.angles, rtol=1e-9, atol=1e-15)
    negated = recognise_prts(t, -stim.angle(t))
    np.testing.assert_allclose(negated.angles, -stim.angles, rtol=1e-9, atol=1e-15)
    assert recognise_prts(t, np.sin(t)) is None
