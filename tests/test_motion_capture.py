"""C3D trials: markers to the angles of docs/model.md §1, checked on trials the project writes from
simulated sway (known segment lengths, marker noise, gaps, both forward axes, mm and m, an
analog tilt channel); the refusals; the same answer as the trial's CSV."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from posture_id.cli import main
from posture_id.errors import RecordingError
from posture_id.motion_capture import (
    C3dWriteOptions,
    LabAxes,
    MarkerMapping,
    TiltChannel,
    is_c3d,
    marker_angles,
    parse_com_markers,
    parse_segment_markers,
    parse_tilt_markers,
    read_c3d,
    write_c3d,
)
from posture_id.motion_capture.gaps import fill_gaps
from posture_id.motion_capture.writer import TILT_CHANNEL
from posture_id.simulation import simulate
from posture_id.simulation.stimulus import prts
from posture_id.trials.reading import read_recording

TIP_MARKERS = ["shank=LANK+RANK,LKNE+RKNE", "thigh=LKNE+RKNE,LHIP+RHIP",
               "trunk=LHIP+RHIP,LSHO+RSHO"]
NOISE_MM = 0.3


@pytest.fixture(scope="module")
def sway(tip):
    """A TIP trial on one 60.5 s cycle of the 242-state PRTS, at 100 Hz."""
    return simulate(tip, stimulus=prts(cycles=1)).to_recording().resampled(100.0)


def _lengths(body) -> tuple[float, ...]:
    return tuple(s.length for s in body.segments)


def _mapping(forward: str, tilt=None, max_gap_s: float = 0.2) -> MarkerMapping:
    return MarkerMapping(LabAxes(forward), parse_segment_markers(TIP_MARKERS), tilt=tilt,
                         max_gap_s=max_gap_s)


def _rms_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.degrees(np.sqrt(np.mean((a - b) ** 2, axis=0)))


@pytest.mark.parametrize(("forward", "unit"), [("x", "mm"), ("-y", "m"), ("y", "mm")])
def test_angles_from_markers_match_the_simulation_to_the_marker_noise(sway, tip, tmp_path,
                                                                      forward, unit):
    path = write_c3d(tmp_path / "trial.c3d", sway, _lengths(tip),
                     C3dWriteOptions(axes=LabAxes(forward), unit=unit,
                                     marker_noise_mm=NOISE_MM, seed=3))
    assert read_c3d(path).unit == unit
    rec = read_recording(path, tip.segment_names, None,
                         _mapping(forward, parse_tilt_markers("PLATB,PLATF")))
    # each segment's ends average two markers: the angle's noise is NOISE_MM / length
    expected = np.degrees(1e-3 * NOISE_MM / np.asarray(_lengths(tip)))
    rms = _rms_deg(rec.theta, sway.theta)
    assert np.all(rms < 1.25 * expected) and np.all(rms > 0.75 * expected)
    # the platform markers (one each, 0.4 m apart) give the tilt to their own noise
    assert _rms_deg(rec.tilt, sway.tilt) < 2.0 * math.degrees(1e-3 * NOISE_MM * 2 ** 0.5 / 0.4)
    assert rec.source["forward_axis"] == forward and rec.source["point_unit"] == unit


def test_the_analog_tilt_channel_is_the_tilt(sway, tip, tmp_path):
    path = write_c3d(tmp_path / "trial.c3d", sway, _lengths(tip),
                     C3dWriteOptions(deg_per_volt=2.5))
    rec = read_recording(path, tip.segment_names, None,
                         _mapping("x", TiltChannel(TILT_CHANNEL, 2.5)))
    assert _rms_deg(rec.tilt, sway.tilt) < 1e-5
    assert rec.tilt_recorded and rec.source["tilt_channel"] == TILT_CHANNEL
    # the scale's sign is the sense: a channel read with the wrong sign is the negated tilt
    wrong = read_recording(path, tip.segment_names, None,
                           _mapping("x", TiltChannel(TILT_CHANNEL, -2.5)))
    assert np.allclose(wrong.tilt, -rec.tilt)


def test_forward_lean_is_positive_and_front_down_tilt_is_positive(tip, tmp_path):
    """Signs checked on a made-up posture: every segment leaning 2° forward, the platform
    tilted 1° front-down (docs/model.md §1)."""
    from posture_id.recording import Recording

    t = np.arange(50) / 100.0
    posture = Recording(t, np.radians(np.clip((t - 0.2) * 10, 0.0, 1.0)),  # level, then 1°
                        np.radians(np.full((50, 3), 2.0)), tip.segment_names)
    for forward in ("x", "-x", "y", "-y"):
        path = write_c3d(tmp_path / f"{forward}.c3d", posture, _lengths(tip),
                         C3dWriteOptions(axes=LabAxes(forward)))
        angles = marker_angles(read_c3d(path), _mapping(forward,
                                                        parse_tilt_markers("PLATB,PLATF")))
        assert np.allclose(np.degrees(angles.theta), 2.0, atol=1e-4)
        assert np.degrees(angles.tilt[-1]) == pytest.approx(1.0, abs=1e-4)


def test_a_gap_is_filled_by_the_spline_and_named_in_the_provenance(sway, tip, tmp_path):
    path = write_c3d(tmp_path / "gap.c3d", sway, _lengths(tip),
                     C3dWriteOptions(gaps=(("LHIP", 20.0, 0.15), ("RSHO", 0.0, 0.05))))
    rec = read_recording(path, tip.segment_names, None,
                         _mapping("x", TiltChannel(TILT_CHANNEL, 2.0)))
    inside = (sway.time >= 20.0) & (sway.time < 20.15)
    # a spline through the neighbouring frames: well below a tenth of the sway there
    assert np.max(np.abs(np.degrees(rec.theta - sway.theta)[inside])) < 0.01
    gaps = {g["marker"]: g["frames"] for g in rec.source["gaps_filled"]}
    assert gaps == {"LHIP": [2001, 2015], "RSHO": [1, 5]}


def test_the_fill_rule_against_a_known_curve():
    """A cubic is filled exactly by the spline; a straight line at the ends is held."""
    t = np.arange(100) / 100.0
    track = np.stack([t**3, t**2, t], axis=1)
    holed = track.copy()
    holed[40:55] = np.nan
    filled, gaps = fill_gaps(holed, 100.0, 0.2, "M", "file.c3d")
    assert np.allclose(filled, track, atol=1e-12) and gaps[0].frames == 15
    with pytest.raises(RecordingError, match=r"file\.c3d: marker 'M' is missing in frames "
                                             r"41–55 \(0\.40–0\.54 s, 0\.15 s\), longer"):
        fill_gaps(holed, 100.0, 0.1, "M", "file.c3d")


def test_com_markers_give_the_body_com_angle_of_a_one_segment_body(tmp_path):
    from posture_id.bodies.anthropometry import straight_links, winter_segments
    from posture_id.bodies.body import load_body
    from posture_id.bodies.urdf_writer import write_chain_urdf

    urdf = write_chain_urdf(tmp_path / "one.urdf", "one",
                            straight_links(winter_segments(1.7, 65.0, 1)))
    body = load_body(urdf)
    sway = simulate(body, stimulus=prts(cycles=1)).to_recording().resampled(100.0)
    path = write_c3d(tmp_path / "com.c3d", sway, _lengths(body),
                     C3dWriteOptions(marker_noise_mm=NOISE_MM, height_m=1.7, mass_kg=65.0))
    mapping = MarkerMapping(LabAxes("x"), com=parse_com_markers(
        ["LANK+RANK", "LHIP+RHIP:0.6", "LSHO+RSHO:0.4"]), tilt=TiltChannel(TILT_CHANNEL, 2.0))
    rec = read_recording(path, body.segment_names, None, mapping)
    assert _rms_deg(rec.theta, sway.theta)[0] < 0.03
    trial = read_c3d(path)
    assert trial.height_m == pytest.approx(1.7) and trial.mass_kg == pytest.approx(65.0)


def _write_default(tmp_path, sway, tip, **options):
    return write_c3d(tmp_path / "trial.c3d", sway, _lengths(tip), C3dWriteOptions(**options))


def _identify(path, *flags) -> int:
    return main(["identify", str(path), "--method", "cnn", *flags])


def _markers(*extra):
    return ["--segment-markers", *TIP_MARKERS, "--forward-axis", "x", *extra]


def test_refusals_are_one_line_naming_the_file(sway, tip, tmp_path, capsys):
    path = _write_default(tmp_path, sway, tip, gaps=(("LKNE", 10.0, 1.0),))

    def refused(*args) -> str:
        assert main(list(args)) == 2
        err = capsys.readouterr().err.strip()
        assert "Traceback" not in err and len(err.splitlines()) == 1
        return err

    # a missing marker, listed with the file's
    err = refused("identify", str(path), "--segment-markers", "shank=LANK,KNEE",
                  "thigh=LKNE,LHIP", "trunk=LHIP,LSHO", "--forward-axis", "x",
                  "--tilt-channel", TILT_CHANNEL)
    assert str(path) in err and "no marker 'KNEE'" in err and "LKNE, RKNE" in err
    # a gap longer than the fill limit
    err = refused("identify", str(path), *_markers("--tilt-markers", "PLATB,PLATF"))
    assert "marker 'LKNE' is missing in frames 1001–1100" in err and str(path) in err
    # no platform: no tilt markers, no channel, no stimulus named
    err = refused("identify", str(path), *_markers("--max-gap-s", "2"))
    assert str(path) in err and "no platform tilt" in err
    # an analog channel the file lacks
    err = refused("identify", str(path), *_markers("--max-gap-s", "2", "--tilt-channel",
                                                  "angle"))
    assert "no analog channel 'angle'" in err and TILT_CHANNEL in err
    # no forward axis; both tilt sources; marker flags on a CSV; a C3D without them
    assert "--forward-axis" in refused("identify", str(path), "--segment-markers",
                                       *TIP_MARKERS)
    assert "give one" in refused("identify", str(path), *_markers(
        "--tilt-markers", "PLATB,PLATF", "--tilt-channel", TILT_CHANNEL))
    csv = tmp_path / "trial.csv"
    sway.to_csv(csv)
    # a CSV given the marker flags is read for its positions: this one has none
    assert "no coordinate columns for point" in refused("identify", str(csv), *_markers())
    assert "name the markers" in refused("identify", str(path))
    # a corrupt file, a truncated one, a CSV named .c3d
    garbage = tmp_path / "garbage.c3d"
    garbage.write_bytes(np.random.default_rng(0).bytes(4096))
    assert "not a C3D file" in refused("identify", str(garbage), *_markers())
    truncated = tmp_path / "truncated.c3d"
    truncated.write_bytes(path.read_bytes()[:3000])
    assert "cannot be read" in refused("identify", str(truncated), *_markers())
    renamed = tmp_path / "renamed.c3d"
    renamed.write_bytes(csv.read_bytes())
    assert "not a C3D file" in refused("identify", str(renamed), *_markers())


def test_a_two_d_file_and_wrong_axes_are_refused(sway, tip, tmp_path, capsys):
    import ezc3d

    path = _write_default(tmp_path, sway, tip)
    c3d = ezc3d.c3d(str(path))
    points = c3d["data"]["points"]
    points[2] = 0.0  # every marker at height 0: a 2-D file of x and y
    points[2, :, ::7] = 0.0
    c3d["data"]["points"] = points
    flat = tmp_path / "flat.c3d"
    c3d.write(str(flat))
    assert _identify(flat, *_markers("--tilt-channel", TILT_CHANNEL)) == 2
    err = capsys.readouterr().err
    assert "no z coordinate" in err and "2-D" in err and str(flat) in err
    # the vertical axis named wrongly: segments out of the plane, or upside down
    assert _identify(path, *_markers("--tilt-channel", TILT_CHANNEL, "--vertical-axis",
                                     "y")) == 2
    assert "lies mostly outside the plane" in capsys.readouterr().err
    assert _identify(path, *_markers("--tilt-channel", TILT_CHANNEL,
                                     "--vertical-axis=-z")) == 2
    assert "leans 180°" in capsys.readouterr().err
    # the forward axis named wrongly: the platform's line points sideways
    assert _identify(path, "--segment-markers", *TIP_MARKERS, "--forward-axis", "y",
                     "--tilt-markers", "PLATB,PLATF") == 2
    assert "points 90° away from --forward-axis y" in capsys.readouterr().err
    # ... and without platform markers: the segments sway across it, not along it
    assert _identify(path, "--segment-markers", *TIP_MARKERS, "--forward-axis=-y",
                     "--tilt-channel", TILT_CHANNEL) == 2
    err = capsys.readouterr().err
    assert "sway along x, and not at all along --forward-axis -y" in err
    assert "--forward-axis x" in err and err.count("\n") == 1


@pytest.mark.slow("the default command twice, 3 segments")
def test_the_c3d_and_the_csv_of_one_trial_give_the_same_answer(tip, tmp_path):
    """One people-like trial (motor noise) through the default command twice: as the CSV
    of its angles and as its C3D (0.3 mm marker noise, a gap, the platform markers)."""
    from posture_id.simulation.noise import MotorNoise

    trial = simulate(tip, motor_noise=MotorNoise(0.05, seed=4)).to_recording()
    csv, c3d = tmp_path / "trial.csv", tmp_path / "trial.c3d"
    trial.resampled(100.0).with_sensor_noise(0.03, seed=5).to_csv(csv)
    write_c3d(c3d, trial, _lengths(tip), C3dWriteOptions(
        marker_noise_mm=NOISE_MM, gaps=(("RHIP", 30.0, 0.12),), seed=6))
    assert main(["identify", str(csv), "--out", str(tmp_path / "csv.json")]) in (0, 1)
    assert main(["identify", str(c3d), *_markers("--tilt-markers", "PLATB,PLATF"),
                 "--out", str(tmp_path / "c3d.json")]) in (0, 1)
    a = json.loads((tmp_path / "csv.json").read_text())
    b = json.loads((tmp_path / "c3d.json").read_text())
    for joint in tip.joint_names:
        assert a["parameters"][joint]["controls"] == b["parameters"][joint]["controls"]
        kp = b["intervals"]["modules"][joint]["kp"]
        assert kp["lower_si"] <= a["parameters"][joint]["kp"] <= kp["upper_si"]
    source = b["provenance"]["recording_source"]
    assert source["tilt_markers"] == "PLATB,PLATF" and source["segment_markers"] == TIP_MARKERS


def test_the_subjects_body_comes_from_the_files_metadata(sway, tip, tmp_path, capsys):
    path = _write_default(tmp_path, sway, tip, height_m=1.62, mass_kg=58.0)
    out = tmp_path / "r.json"
    assert _identify(path, *_markers("--tilt-channel", TILT_CHANNEL, "--tilt-scale", "2"),
                     "--out", str(out)) in (0, 1)
    assert "Winter's tables for 1.62 m and 58 kg, 3 segment(s)" in capsys.readouterr().err
    body = json.loads(out.read_text())["provenance"]["body"]
    assert body["name"].startswith("winter_1.62m_58kg_3seg")
    # --body wins
    assert _identify(path, *_markers("--tilt-channel", TILT_CHANNEL, "--tilt-scale", "2"),
                     "--body", str(tip.urdf_path), "--out", str(out)) in (0, 1)
    assert json.loads(out.read_text())["provenance"]["body"]["name"] == tip.name
    # and posture-id body builds it from the trial alone
    urdf = tmp_path / "subject.urdf"
    assert main(["body", "--from-trial", str(path), "--segments", "2", "--out",
                 str(urdf)]) == 0
    assert "winter_1.62m_58kg_2seg" in urdf.read_text()


def test_a_cohort_of_c3d_files_locally_and_on_dask(sway, tip, tmp_path):
    distributed = pytest.importorskip("distributed")
    folder = tmp_path / "trials"
    subjects = ((1.62, 58.0), (1.85, 90.0))
    for k, (height, mass) in enumerate(subjects):
        write_c3d(folder / f"s{k}.c3d", sway, _lengths(tip),
                  C3dWriteOptions(marker_noise_mm=NOISE_MM, seed=k, height_m=height,
                                  mass_kg=mass))
    flags = [*_markers("--tilt-channel", TILT_CHANNEL, "--tilt-scale", "2"),
             "--method", "cnn"]
    local, remote = tmp_path / "local", tmp_path / "remote"
    status = main(["identify", str(folder), "--out", str(local), *flags])
    assert status in (0, 1) and sorted(p.name for p in local.glob("*.json")) == [
        "s0.json", "s1.json"]
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        assert main(["identify", str(folder), "--out", str(remote), *flags, "--scheduler",
                     cluster.scheduler_address]) == status
    for k, (height, mass) in enumerate(subjects):  # each subject's body, from their file
        a = json.loads((local / f"s{k}.json").read_text())
        b = json.loads((remote / f"s{k}.json").read_text())
        assert a["parameters"] == b["parameters"]
        assert a["provenance"]["body"]["name"] == f"winter_{height:g}m_{mass:g}kg_3seg"


def test_plot_shows_the_markers_beside_the_angles(sway, tip, tmp_path):
    path = _write_default(tmp_path, sway, tip, gaps=(("LSHO", 5.0, 0.1),))
    plot = tmp_path / "check.png"
    assert _identify(path, *_markers("--tilt-markers", "PLATB,PLATF"), "--plot",
                     str(plot)) in (0, 1)
    assert (tmp_path / "check.markers.png").stat().st_size > 10_000


def test_simulate_writes_a_c3d_trial_and_its_flags_need_one(tmp_path, capsys):
    out = tmp_path / "sim.c3d"
    assert main(["simulate", "--out", str(out), "--cycles", "1", "--marker-noise-mm", "0.3",
                 "--c3d-forward-axis=-y", "--c3d-unit", "m", "--height-m", "1.8",
                 "--mass-kg", "75", "--marker-gap", "LHIP", "3", "0.1"]) == 0
    trial = read_c3d(out)
    assert is_c3d(out) and trial.unit == "m" and trial.height_m == pytest.approx(1.8)
    assert np.isnan(trial.marker("LHIP")[300:310]).all()
    assert main(["simulate", "--out", str(tmp_path / "x.csv"), "--c3d-unit", "m"]) == 2
    assert "give --out NAME.c3d" in capsys.readouterr().err


def test_frf_and_fit_read_a_c3d_trial(sway, tip, tmp_path):
    """The other commands that read a recording take the marker flags too (one reader)."""
    path = _write_default(tmp_path, sway, tip, marker_noise_mm=NOISE_MM)
    flags = _markers("--tilt-channel", TILT_CHANNEL, "--tilt-scale", "2", "--body",
                     str(tip.urdf_path))
    one_cycle = ["--drift-order", "0"]  # the sway is one cycle long
    assert main(["frf", str(path), *flags, *one_cycle, "--out", str(tmp_path / "frf.json")]) == 0
    frf = json.loads((tmp_path / "frf.json").read_text())
    assert frf["provenance"]["recording_source"]["tilt_channel"] == TILT_CHANNEL
    csv = tmp_path / "same.csv"
    sway.to_csv(csv)
    assert main(["frf", str(csv), "--body", str(tip.urdf_path), *one_cycle, "--out",
                 str(tmp_path / "csv.json")]) == 0
    same = json.loads((tmp_path / "csv.json").read_text())
    # below 0.5 Hz the sway's harmonics stand well above the marker noise (0.03°; one
    # cycle averages nothing away): gains within 5 %
    low = np.asarray(frf["frequencies_hz"]) < 0.5
    for channel in ("shank", "trunk", "body COM"):
        gain = np.asarray(frf["channels"][channel]["gain"])[low]
        reference = np.asarray(same["channels"][channel]["gain"])[low]
        assert np.median(np.abs(gain / reference - 1)) < 0.05, channel
    assert main(["fit", str(path), *flags, "--model", "ic", "--out",
                 str(tmp_path / "ic.json")]) in (0, 1)


def test_the_example_trial_sways_along_its_forward_axis_not_across_it():
    """The numbers docs/motion_capture.md gives for the forward-axis check: the shipped C3D
    trial's segments sway under 0.1× as much across its forward axis (-y) as along it, and
    over 10× as much along it as across x, the lateral axis named forward."""
    from posture_id.motion_capture import marker_angles, read_c3d
    from posture_id.motion_capture.angles import SWAY_ACROSS_RATIO, sway_across
    from posture_id.motion_capture.mapping import (
        LabAxes,
        MarkerMapping,
        parse_segment_markers,
    )

    trial = read_c3d(Path(__file__).resolve().parents[1]
                     / "posture_id/studies/examples/straight_leg_subject.c3d")
    segments = parse_segment_markers(["leg=LANK+RANK,LHIP+RHIP", "trunk=LHIP+RHIP,LSHO+RSHO"])
    read = marker_angles(trial, MarkerMapping(axes=LabAxes("-y"), segments=segments))
    vectors = [read.points[str(s.upper)] - read.points[str(s.lower)] for s in segments]
    right, _ = sway_across(vectors, LabAxes("-y"), trial.rate_hz)
    wrong, _ = sway_across(vectors, LabAxes("x"), trial.rate_hz)
    assert right < 0.1 and wrong > 10 and wrong > SWAY_ACROSS_RATIO
