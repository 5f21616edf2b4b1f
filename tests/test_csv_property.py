"""The numeric CSV readers on random input: a clear error (a PostureIdError with one
line) or a valid result, never anything else (hypothesis)."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from posture_id.errors import PostureIdError
from posture_id.recording import Recording
from posture_id.simulation.stimulus import tilt_from_csv

SETTINGS = settings(max_examples=150, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])
HEADERS = st.sampled_from([
    ["time_s", "tilt_deg", "shank_deg"],
    ["time_s", "tilt_deg", "shank_deg", "thigh_deg"],
    ["time_s", "tilt_deg"],
    ["tilt_deg", "time_s"],
    ["time_s", "tilt", "x_deg"],
])
CELLS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True, width=64),
    st.integers(-10**6, 10**6),
    st.sampled_from(["", "nan", "1e999", "abc", " 3 ", "0x10", "1,5"]),
)


def _read_both(path: Path) -> None:
    for read in (lambda: Recording.from_csv(path), lambda: tilt_from_csv(path)):
        try:
            result = read()
        except PostureIdError as exc:
            message = str(exc)
            assert "\n" not in message and str(path) in message, message
            continue
        if isinstance(result, Recording):
            assert np.all(np.isfinite(result.theta)) and np.all(np.isfinite(result.tilt))
            assert np.all(np.diff(result.time) > 0) and result.time[0] == 0
            assert result.theta.shape == (len(result.time), len(result.segments))
        else:
            assert np.all(np.diff(result.times) > 0) and np.all(np.isfinite(result.angles))


@SETTINGS
@given(st.binary(max_size=3000))
def test_random_bytes(data):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "random.csv"
        path.write_bytes(data)
        _read_both(path)


@SETTINGS
@given(HEADERS, st.lists(st.lists(CELLS, min_size=1, max_size=5), max_size=40))
def test_random_numeric_tables(header, rows):
    text = ",".join(header) + "\n" + "".join(",".join(str(c) for c in row) + "\n"
                                             for row in rows)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "table.csv"
        path.write_text(text)
        _read_both(path)


@SETTINGS
@given(st.integers(2, 60), st.floats(1e-3, 0.5), st.integers(1, 3), st.randoms())
def test_plausible_tables_are_read(n, dt, segments, rnd):
    """Well-formed tables with a real rate and angles in degrees always read."""
    time = np.arange(n) * dt
    angles = np.array([[rnd.uniform(-5, 5) for _ in range(segments + 1)] for _ in range(n)])
    angles[0, 0] = 1.0  # not all below the radians threshold, tilt not constant
    angles[1, 0] = -1.0
    names = ["shank", "thigh", "trunk"][:segments]
    header = "time_s,tilt_deg," + ",".join(f"{s}_deg" for s in names)
    body = "".join(f"{float(t)!r}," + ",".join(repr(float(a)) for a in row) + "\n"
                   for t, row in zip(time, angles, strict=True))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "ok.csv"
        path.write_text(header + "\n" + body)
        rec = Recording.from_csv(path)
        np.testing.assert_allclose(np.degrees(rec.theta), angles[:, 1:], rtol=1e-12, atol=1e-12)
        tilt = tilt_from_csv(path)
        np.testing.assert_allclose(np.degrees(tilt.angles), angles[:, 0], rtol=1e-12, atol=1e-12)
