"""Marker and tracker positions in a CSV: a virtual-reality lab's export, as such a lab
writes it (about 90 Hz, time stamps that jitter by under a millisecond, tracker positions
in metres, y up and z forward), read through the C3D route's checks and identified as it
is. The files are made here from simulated sway."""

from __future__ import annotations

import json

import numpy as np
import pytest

from posture_id.bodies.anthropometry import straight_links, winter_segments
from posture_id.bodies.body import load_body
from posture_id.bodies.urdf_writer import write_chain_urdf
from posture_id.cli import main
from posture_id.dec.parameters import default_parameters
from posture_id.errors import RecordingError
from posture_id.motion_capture.mapping import LabAxes, MarkerMapping, parse_com_markers
from posture_id.motion_capture.marker_table import LengthUnit, MarkerColumns
from posture_id.recording import RecordingColumns
from posture_id.simulation.batch import simulate
from posture_id.simulation.noise import MotorNoise
from posture_id.simulation.options import SimulationOptions
from posture_id.simulation.stimulus import prts
from posture_id.trials.reading import read_recording

RATE_HZ, JITTER_S = 90.0, 0.0004
#: m along the body line from the foot tracker: the hip and the shoulder trackers.
HIP_M, SHOULDER_M = 0.95, 1.45
COM = ["--com-markers", "foot", "hip:0.6", "shoulder:0.4", "--forward-axis", "z",
       "--vertical-axis", "y", "--time-column", "time", "--tilt-column", "platform_pitch"]


def _write_export(path, time, tilt_deg, theta, scale=1.0, header_unit="",
                  seed=3) -> None:
    """A VR export: time, platform pitch (deg), foot, hip and shoulder trackers (x lateral,
    y up, z forward), each tracker with 0.3 mm of noise; ``scale`` the positions' unit per
    metre."""
    rng = np.random.default_rng(seed)
    foot = np.array([0.02, 0.08, 0.0])
    line = np.column_stack([np.zeros_like(theta), np.cos(theta), np.sin(theta)])
    trackers = {"foot": np.tile(foot, (len(time), 1)),
                "hip": foot + HIP_M * line, "shoulder": foot + SHOULDER_M * line}
    names = ["time", "platform_pitch"]
    columns = [time, tilt_deg]
    for name, xyz in trackers.items():
        xyz = xyz + 0.0003 * rng.standard_normal(xyz.shape)
        for k, axis in enumerate("xyz"):
            names.append(f"{name}_{axis}{header_unit}")
            columns.append(xyz[:, k] * scale)
    rows = np.column_stack(columns)
    path.write_text(",".join(names) + "\n" + "".join(
        f"{row[0]:.6f}," + ",".join(f"{v:.7g}" for v in row[1:]) + "\n" for row in rows))


@pytest.fixture(scope="module")
def vr_lab(tmp_path_factory):
    """(folder, body, theta on the even grid): one simulated subject written twice, with
    a headset's jittered clock and evenly sampled."""
    folder = tmp_path_factory.mktemp("vr")
    urdf = write_chain_urdf(folder / "subject.urdf", "subject",
                            straight_links(winter_segments(1.75, 70.0, 1)))
    body = load_body(urdf)
    truth = default_parameters(body)
    stimulus = prts(1.0, cycles=3, states=80, onset_s=3.0, start_state=20)
    stimulus = stimulus.spanning(stimulus.duration + 3.0)
    sway = simulate(body, truth, stimulus, SimulationOptions(sample_rate_hz=500.0),
                    MotorNoise(0.03, seed=8))
    n = int(sway.time[-1] * RATE_HZ)
    even = np.arange(n) / RATE_HZ
    jitter = np.random.default_rng(5).uniform(-JITTER_S, JITTER_S, n)
    jitter[0] = jitter[-1] = 0.0
    for name, time in (("even", even), ("vr", even + jitter)):
        theta = np.interp(time, sway.time, sway.theta[:, 0])
        _write_export(folder / f"{name}.csv", time, np.degrees(stimulus.angle(time)), theta)
    return folder, body, np.interp(even, sway.time, sway.theta[:, 0])


def _rms_deg(error_rad: np.ndarray) -> float:
    return float(np.degrees(np.sqrt(np.mean(error_rad**2))))


def _layout(**kwargs) -> MarkerColumns:
    mapping = MarkerMapping(axes=LabAxes("z", "y"),
                            com=parse_com_markers(["foot", "hip:0.6", "shoulder:0.4"]))
    return MarkerColumns(mapping, RecordingColumns(time="time", tilt="platform_pitch"),
                         **kwargs)


def test_a_vr_export_gives_the_com_angle_on_its_even_clock(vr_lab):
    folder, body, theta = vr_lab
    recording = read_recording(folder / "vr.csv", body.segment_names, None, _layout())
    assert recording.evenly_sampled()
    assert recording.sample_rate_hz == pytest.approx(RATE_HZ, rel=1e-4)
    assert any("jitter" in n and "resampled" in n for n in recording.notices)
    # the trackers' 0.3 mm over a metre, and the jitter's interpolation, and no more
    assert _rms_deg(recording.theta[:, 0] - theta[: len(recording.time)]) < 0.03
    assert recording.tilt_recorded and recording.source["format"] == "marker table"


def test_positions_in_another_unit_are_read_or_refused_naming_the_unit(vr_lab, tmp_path):
    folder, body, theta = vr_lab
    time = np.arange(len(theta)) / RATE_HZ
    tilt = np.zeros_like(time)
    _write_export(tmp_path / "mm.csv", time, tilt, theta, scale=1000.0)
    with pytest.raises(RecordingError, match=r"mm\.csv.*not a standing person's.*"
                                             r"--position-units mm"):
        read_recording(tmp_path / "mm.csv", body.segment_names, None, _layout())
    read = read_recording(tmp_path / "mm.csv", body.segment_names, None,
                          _layout(position_unit=LengthUnit.MILLIMETRES))
    assert _rms_deg(read.theta[:, 0] - theta) < 0.03
    _write_export(tmp_path / "cm.csv", time, tilt, theta, scale=100.0, header_unit=" [cm]")
    read = read_recording(tmp_path / "cm.csv", body.segment_names, None, _layout())
    assert _rms_deg(read.theta[:, 0] - theta) < 0.03
    with pytest.raises(RecordingError, match=r"in cm by their headers.*--position-units m"):
        read_recording(tmp_path / "cm.csv", body.segment_names, None,
                       _layout(position_unit=LengthUnit.METRES))


def test_a_missing_coordinate_column_and_a_wrong_axis_are_refused(vr_lab, tmp_path):
    folder, body, _ = vr_lab
    text = (folder / "even.csv").read_text()
    (tmp_path / "no_z.csv").write_text(text.replace("shoulder_z", "shoulder_w"))
    with pytest.raises(RecordingError, match=r"no coordinate columns for point 'shoulder' "
                                             r"\(z\)"):
        read_recording(tmp_path / "no_z.csv", body.segment_names, None, _layout())
    across = MarkerColumns(MarkerMapping(axes=LabAxes("x", "y"), com=parse_com_markers(
        ["foot", "hip:0.6", "shoulder:0.4"])), RecordingColumns(time="time",
                                                              tilt="platform_pitch"))
    with pytest.raises(RecordingError, match=r"sway .* along z.*--forward-axis z"):
        read_recording(folder / "even.csv", body.segment_names, None, across)


def test_the_command_line_reads_tracker_columns_and_refuses_what_does_not_go(
        vr_lab, capsys):
    folder, body, _ = vr_lab
    out = folder / "frf.json"
    assert main(["frf", str(folder / "vr.csv"), *COM, "--body", str(body.urdf_path),
                 "--out", str(out)]) == 0, capsys.readouterr().err
    assert "jitter" in capsys.readouterr().err
    for extra, message in ((["--tilt-channel", "pitch"], "a CSV's tilt is its --tilt-column"),
                           (["--angle-columns", "hip_z"], "two sources of the sway")):
        assert main(["frf", str(folder / "vr.csv"), *COM, *extra, "--body",
                     str(body.urdf_path), "--out", str(folder / "x.json")]) == 2
        assert message in capsys.readouterr().err


@pytest.mark.slow("the default command twice, 1 segment")
def test_a_vr_export_is_identified_as_it_is_within_2_percent_of_it_evenly_sampled(
        vr_lab, capsys):
    folder, body, _ = vr_lab
    answers = {}
    for name in ("vr", "even"):
        out = folder / f"{name}.json"
        assert main(["identify", str(folder / f"{name}.csv"), *COM, "--body",
                     str(body.urdf_path), "--out", str(out)]) in (0, 1), \
            capsys.readouterr().err
        answers[name] = json.loads(out.read_text())["parameters"][body.joint_names[0]]
    for field in ("kp", "ki", "kd", "delay_s"):
        assert answers["vr"][field] == pytest.approx(answers["even"][field], rel=0.02), field


def test_a_rate_given_a_hair_off_the_clock_is_refused_with_the_rate_the_states_say(
        vr_lab, tmp_path, capsys):
    """The headset's clock runs at 89.53 Hz; the lab gives --sample-rate-hz 90: the PRTS's
    0.25 s states then last 0.2487 s, a cycle no whole number of samples (before: "a
    stimulus cycle of 19.896 s is not a whole number of samples", and nothing to do about
    it). The time stamps alone are read right."""
    folder, body, _ = vr_lab
    rate = 89.53
    stimulus = prts(1.0, cycles=3, states=80, onset_s=3.0, start_state=20)
    time = np.arange(int(66.0 * rate)) / rate
    sway = simulate(body, default_parameters(body), stimulus.spanning(66.0),
                    SimulationOptions(sample_rate_hz=500.0))
    _write_export(tmp_path / "slow.csv", time, np.degrees(stimulus.angle(time)),
                  np.interp(time, sway.time, sway.theta[:, 0]))
    args = ["frf", str(tmp_path / "slow.csv"), *COM, "--body", str(body.urdf_path), "--out",
            str(tmp_path / "slow.json")]
    assert main([*args, "--sample-rate-hz", "90"]) == 2
    err = capsys.readouterr().err
    assert "states last 0.2487 s" in err and "--sample-rate-hz 89.53" in err, err
    assert main(args) == 0, capsys.readouterr().err


def test_a_tracker_that_lost_tracking_is_a_gap_filled_or_refused(vr_lab, tmp_path):
    """A tracker writes (0, 0, 0) while it has lost tracking: a short stretch is filled
    as a C3D's gap is, a long one refused with its frames."""
    folder, body, theta = vr_lab
    lines = (folder / "even.csv").read_text().splitlines()
    header = lines[0].split(",")
    hip = [header.index(f"hip_{a}") for a in "xyz"]

    def lost(rows: range, name: str):
        edited = [lines[0]]
        for k, line in enumerate(lines[1:]):
            cells = line.split(",")
            if k in rows:
                for j in hip:
                    cells[j] = "0"
            edited.append(",".join(cells))
        (tmp_path / name).write_text("\n".join(edited) + "\n")
        return tmp_path / name

    short = read_recording(lost(range(900, 909), "short.csv"), body.segment_names, None,
                           _layout())
    assert _rms_deg(short.theta[:, 0] - theta[: len(short.time)]) < 0.03
    with pytest.raises(RecordingError, match=r"long\.csv.*'hip'.*frames 901"):
        read_recording(lost(range(900, 990), "long.csv"), body.segment_names, None,
                       _layout())
