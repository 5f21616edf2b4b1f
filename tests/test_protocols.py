"""Stimulus protocols: JSON round trip, errors that name the field, the tilt each one
makes (against known spectra), and the command line that plays them."""

from __future__ import annotations

import json

import numpy as np
import pytest

from posture_id.cli import main
from posture_id.errors import StimulusError
from posture_id.simulation.protocols import (
    MultisineProtocol,
    PrtsProtocol,
    SumOfSinesProtocol,
    TwoAmplitudeProtocol,
    protocol_from_dict,
    read_protocol,
    write_protocol,
)
from posture_id.simulation.stimulus import prts, tilt_from_csv

PROTOCOLS = [PrtsProtocol(), PrtsProtocol(80, 0.3, 3.0, 4, 2),
             MultisineProtocol(20.0, (1, 3, 7, 15), 2.0, (1, 0.5, 0.5, 0.25), cycles=3),
             SumOfSinesProtocol((0.05, 0.1, 0.4), (1.0, 0.5, 0.2), (0.0, 1.0, 2.0), 2),
             TwoAmplitudeProtocol(PrtsProtocol(80, 0.25, 1.0, 4), (1.0, 4.0))]


@pytest.mark.parametrize("protocol", PROTOCOLS, ids=lambda p: p.kind)
def test_protocols_round_trip_through_json(protocol, tmp_path):
    again = protocol_from_dict(json.loads(json.dumps(protocol.to_dict())))
    assert again == protocol
    assert read_protocol(write_protocol(protocol, tmp_path / "p.json")) == protocol


def test_a_prts_protocol_is_the_prts():
    p = PrtsProtocol(80, 0.3, 3.0, 4)
    ref = prts(3.0, 4, 80, 0.3)
    np.testing.assert_array_equal(p.profile().times, ref.times)
    np.testing.assert_array_equal(p.profile().angles, ref.angles)
    assert p.period_s == pytest.approx(24.0) and p.recording_minutes == pytest.approx(1.6)
    assert p.peak_to_peak_deg == pytest.approx(3.0)


def _amplitudes(profile, period_s, rate=200.0):
    """Amplitude (degrees) of every harmonic of one cycle of the tilt."""
    n = int(round(period_s * rate))
    x = np.degrees(profile.angle(np.arange(n) / rate))
    return 2 * np.abs(np.fft.rfft(x)[1:]) / n


def test_a_multisine_excites_its_harmonics_only_at_its_peak_to_peak():
    p = MultisineProtocol(20.0, (1, 3, 7, 15), 2.0, (1, 0.5, 0.5, 0.25), cycles=3)
    profile = p.profile()
    assert np.ptp(np.degrees(profile.angles)) == pytest.approx(2.0, rel=1e-3)
    amp = _amplitudes(profile, 20.0)
    chosen = np.array([1, 3, 7, 15]) - 1
    others = np.delete(amp[:60], chosen)
    assert others.max() < 1e-3 * amp[chosen].max()
    np.testing.assert_allclose(amp[chosen] / amp[chosen][0], [1, 0.5, 0.5, 0.25], rtol=1e-3)
    assert profile.period_s == 20.0 and profile.duration == pytest.approx(60.0)


def test_a_sum_of_sines_has_the_least_common_period_and_its_amplitudes():
    p = SumOfSinesProtocol((0.05, 0.1, 0.4), (1.0, 0.5, 0.2), (0.0, 1.0, 2.0), 2)
    assert p.period_s == pytest.approx(20.0)
    amp = _amplitudes(p.profile(), 20.0)
    np.testing.assert_allclose(amp[[0, 1, 7]], [1.0, 0.5, 0.2], rtol=1e-3)
    assert SumOfSinesProtocol((0.3, 0.5), (1, 1)).period_s == pytest.approx(10.0)


def test_two_amplitudes_are_two_recordings():
    p = PROTOCOLS[-1]
    assert [r.amplitude_deg for r in p.recordings] == [1.0, 4.0]
    assert p.recording_minutes == pytest.approx(2 * 80 / 60)
    with pytest.raises(StimulusError, match="two recordings"):
        p.profile()


@pytest.mark.parametrize("data, message", [
    ({"kind": "chirp"}, "field 'kind' must be one of"),
    ({"kind": "prts", "states": 100}, "states must be one of"),
    ({"kind": "prts", "colour": "red"}, r"unknown field\(s\) \['colour'\]"),
    ({"kind": "prts", "cycles": 0}, "cycles must be a whole number"),
    ({"kind": "prts", "states": 80, "state_s": 0.2013}, "whole number of 0.02 s"),
    ({"kind": "multisine", "harmonics": [1, 1]}, "distinct"),
    ({"kind": "multisine", "harmonics": [1, 2], "phases_rad": [0]}, "phases_rad must be 2"),
    ({"kind": "sum_of_sines", "frequencies_hz": [0.1, 0.2], "amplitudes_deg": [1]},
     "one amplitude each"),
    ({"kind": "sum_of_sines", "frequencies_hz": [0.1, 0.0031], "amplitudes_deg": [1, 1]},
     "over 300 s|no period"),
    ({"kind": "two_amplitudes", "base": {"kind": "prts"}, "amplitudes_deg": [2, 2]},
     "two different amplitudes"),
    ({"kind": "two_amplitudes", "base": {"kind": "prts", "amplitude_deg": -1}},
     "base: protocol amplitude_deg"),
])
def test_bad_protocols_are_refused_with_the_field_named(data, message, tmp_path):
    file = tmp_path / "bad.json"
    file.write_text(json.dumps(data))
    with pytest.raises(StimulusError, match=message) as caught:
        read_protocol(file)
    assert str(file) in str(caught.value)


def test_stimulus_command_writes_the_platform_file(tmp_path, capsys):
    protocol = write_protocol(PROTOCOLS[-1], tmp_path / "two.json")
    out = tmp_path / "command.csv"
    assert main(["stimulus", str(protocol), "--out", str(out)]) == 2
    assert "--part 1..2" in capsys.readouterr().err
    assert main(["stimulus", str(protocol), "--out", str(out), "--part", "2",
                 "--rate-hz", "50"]) == 0
    back = tilt_from_csv(out)
    expected = PROTOCOLS[-1].recordings[1].profile()
    t = np.arange(0, 80, 0.02)
    np.testing.assert_allclose(back.angle(t), expected.angle(t), atol=1e-7)
    assert back.duration == pytest.approx(80.0)


def test_simulate_plays_a_protocol_file(tmp_path):
    from posture_id.recording import Recording

    protocol = SumOfSinesProtocol((0.1, 0.3), (0.5, 0.25), cycles=2)
    file = write_protocol(protocol, tmp_path / "sines.json")
    out = tmp_path / "rec.csv"
    assert main(["simulate", "--protocol", str(file), "--out", str(out)]) == 0
    rec = Recording.read(out)
    np.testing.assert_allclose(np.degrees(rec.tilt), np.degrees(protocol.profile().angle(
        rec.time)), atol=1e-5)
    assert main(["simulate", "--protocol", str(file), "--states", "80", "--out",
                 str(out)]) == 2
