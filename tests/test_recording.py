"""Recording CSV: round trip and clear errors."""

from __future__ import annotations

import numpy as np
import pytest

from posture_id.errors import RecordingError
from posture_id.recording import Recording
from posture_id.simulation import prts, simulate


def test_round_trip(tmp_path, tip):
    result = simulate(tip, stimulus=prts(states=80, cycles=1))
    path = tmp_path / "r.csv"
    result.to_csv(path)
    assert path.read_text().splitlines()[0] == "time_s,tilt_deg,shank_deg,thigh_deg,trunk_deg"
    rec = Recording.from_csv(path, tip.segment_names)
    np.testing.assert_allclose(rec.theta, result.theta, atol=1e-13)
    np.testing.assert_allclose(rec.tilt, result.tilt, atol=1e-13)
    np.testing.assert_allclose(rec.time, result.time, atol=1e-9)


@pytest.mark.parametrize(
    "text, fragment",
    [
        ("time,tilt_deg,shank_deg\n0,0,0\n", "header must start"),
        ("time_s,tilt_deg,shank_deg\n0,0,0\n0.02,0,nan\n", "line 3, column 'shank_deg'"),
        ("time_s,tilt_deg,shank_deg\n0,0,0\n0.02,0\n", "line 3: 2 fields"),
        ("time_s,tilt_deg,shank_deg,hip_deg\n0,0,0,0\n0.02,0,0,0\n", "do not match"),
    ],
)
def test_bad_recordings(tmp_path, tip, text, fragment):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(RecordingError) as err:
        Recording.from_csv(path, tip.segment_names if "hip_deg" in text else None)
    assert fragment in str(err.value) and str(path) in str(err.value)
