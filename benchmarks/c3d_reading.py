"""Reading a motion-capture trial: ezc3d (compiled, the project's reader) against the
pure-Python ``c3d`` package, and the whole marker route; the marker route's angle accuracy;
one trial's answer from its C3D and from its CSV.

Run:  .venv/bin/python benchmarks/c3d_reading.py [--seconds 120] [--markers 40] [--repeats 5]

Writes a trial as a lab's system would (the TIP's default sway on the 242-state PRTS,
``--seconds`` long, 100 Hz, ``--markers`` markers: the 10 the angles use and the rest of a
full set on the segments, 0.3 mm marker noise, a 1 kHz analog tilt channel and a force
channel), then times, in one run, medians of ``--repeats``: ezc3d's read of every marker
and channel, the ``c3d`` package's (when it is installed: ``pip install c3d``; not a
dependency), the project's read (``read_c3d``: ezc3d and the checks), and the whole route
to a recording (read, gaps, angles, tilt from the platform markers).

Accuracy: the same sway written with 0.3 mm marker noise for each lab layout (forward x
in mm, forward −y in m, a gap in a hip marker), read back: RMS of each derived angle
against the simulated one, beside the noise's own share (0.3 mm over the segment's length;
the tilt's markers are single, 0.4 m apart). Answer: a people-like trial (motor noise,
0.03° sensor noise in its CSV) identified by the default command from its CSV and from its
C3D: classes and Kp with the C3D answer's 90 % interval. Writes
docs/results/c3d_reading/report.md and rows.json.
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "results" / "c3d_reading"


def _median_s(run, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def _read_with_ezc3d(path: Path) -> None:
    import ezc3d

    c3d = ezc3d.c3d(str(path))
    np.asarray(c3d["data"]["points"]), np.asarray(c3d["data"]["analogs"])


def _read_with_c3d(path: Path) -> None:
    import c3d

    with path.open("rb") as handle:
        reader = c3d.Reader(handle)
        frames = [(points, analog) for _, points, analog in reader.read_frames()]
    np.stack([p for p, _ in frames]), np.concatenate([a for _, a in frames], axis=1)


def _accuracy(folder: Path, sway, body, mapping) -> list[dict]:
    """RMS of the derived angles against the simulated ones, per lab layout."""
    from dataclasses import replace

    from posture_id.motion_capture import (
        C3dWriteOptions,
        LabAxes,
        TiltChannel,
        marker_angles,
        read_c3d,
        write_c3d,
    )
    from posture_id.motion_capture.writer import TILT_CHANNEL

    lengths = np.asarray([s.length for s in body.segments])
    sway = sway.resampled(100.0)
    out = []
    for forward, unit in (("x", "mm"), ("-y", "m")):
        path = write_c3d(folder / f"accuracy_{unit}.c3d", sway, tuple(lengths),
                         C3dWriteOptions(axes=LabAxes(forward), unit=unit, marker_noise_mm=0.3,
                                         gaps=(("RKNE", 20.0, 0.15),), seed=11))
        layout = replace(mapping, axes=LabAxes(forward))
        by_markers = marker_angles(read_c3d(path), layout)
        by_channel = marker_angles(read_c3d(path), replace(layout, tilt=TiltChannel(
            TILT_CHANNEL, 2.0)))

        def rms(a, b):
            return np.degrees(np.sqrt(np.mean((a - b) ** 2, axis=0)))

        out.append({"layout": f"forward {forward}, {unit}, a 0.15 s gap",
                    "rms_deg": rms(by_markers.theta, sway.theta).tolist(),
                    "expected_deg": np.degrees(0.3e-3 / lengths).tolist(),
                    "tilt_markers_rms_deg": float(rms(by_markers.tilt, sway.tilt)),
                    "tilt_expected_deg": float(np.degrees(0.3e-3 * np.sqrt(2) / 0.4)),
                    "tilt_channel_rms_deg": float(rms(by_channel.tilt, sway.tilt))})
    return out


def _answers(folder: Path, body) -> list[dict]:
    """A people-like trial identified from its CSV and from its C3D (default command)."""
    from posture_id.cli import main as cli
    from posture_id.motion_capture import C3dWriteOptions, write_c3d
    from posture_id.simulation import simulate
    from posture_id.simulation.noise import MotorNoise

    trial = simulate(body, motor_noise=MotorNoise(0.05, seed=4)).to_recording()
    csv, c3d = folder / "answer.csv", folder / "answer.c3d"
    trial.resampled(100.0).with_sensor_noise(0.03, seed=5).to_csv(csv)
    write_c3d(c3d, trial, tuple(s.length for s in body.segments),
              C3dWriteOptions(marker_noise_mm=0.3, gaps=(("RHIP", 30.0, 0.12),), seed=6))
    cli(["identify", str(csv), "--out", str(folder / "csv.json")])
    cli(["identify", str(c3d), "--segment-markers", "shank=LANK+RANK,LKNE+RKNE",
         "thigh=LKNE+RKNE,LHIP+RHIP", "trunk=LHIP+RHIP,LSHO+RSHO", "--forward-axis", "x",
         "--tilt-markers", "PLATB,PLATF", "--out", str(folder / "c3d.json")])
    a = json.loads((folder / "csv.json").read_text())
    b = json.loads((folder / "c3d.json").read_text())
    rows = []
    for joint in body.joint_names:
        kp = b["intervals"]["modules"][joint]["kp"]
        rows.append({"joint": joint, "csv_kp": a["parameters"][joint]["kp"],
                     "csv_class": a["parameters"][joint]["controls"],
                     "c3d_kp": b["parameters"][joint]["kp"],
                     "c3d_class": b["parameters"][joint]["controls"],
                     "low": kp["lower_si"], "high": kp["upper_si"],
                     "inside": kp["lower_si"] <= a["parameters"][joint]["kp"] <= kp["upper_si"]})
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=120.0)
    parser.add_argument("--markers", type=int, default=40)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    from posture_id.bodies.body import load_body
    from posture_id.fileio import atomic_write_text, json_text
    from posture_id.motion_capture import (
        C3dWriteOptions,
        LabAxes,
        MarkerMapping,
        marker_angles,
        parse_segment_markers,
        parse_tilt_markers,
        read_c3d,
        write_c3d,
    )
    from posture_id.simulation import simulate
    from posture_id.simulation.stimulus import prts

    body = load_body()
    cycles = int(np.ceil(args.seconds / 60.5))
    sway = simulate(body, stimulus=prts(cycles=cycles)).to_recording()
    keep = sway.time <= args.seconds + 1e-9
    from dataclasses import replace

    sway = replace(sway, time=sway.time[keep], tilt=sway.tilt[keep], theta=sway.theta[keep])
    own = 2 * (body.n_segments + 1) + 2
    mapping = MarkerMapping(LabAxes("x"), parse_segment_markers(
        ["shank=LANK+RANK,LKNE+RKNE", "thigh=LKNE+RKNE,LHIP+RHIP", "trunk=LHIP+RHIP,LSHO+RSHO"]),
        tilt=parse_tilt_markers("PLATB,PLATF"))
    rows: dict = {"seconds": args.seconds, "markers": args.markers, "rate_hz": 100.0,
                  "repeats": args.repeats}
    with tempfile.TemporaryDirectory() as tmp:
        path = write_c3d(Path(tmp) / "trial.c3d", sway, tuple(s.length for s in body.segments),
                         C3dWriteOptions(marker_noise_mm=0.3, extra_markers=args.markers - own,
                                         gaps=(("LHIP", 30.0, 0.1),)))
        trial = read_c3d(path)
        rows["frames"], rows["file_bytes"] = trial.n_frames, path.stat().st_size
        assert len(trial.labels) == args.markers
        rows["ezc3d_s"] = _median_s(lambda: _read_with_ezc3d(path), args.repeats)
        try:
            import c3d  # noqa: F401
        except ImportError:
            rows["c3d_package_s"] = None
        else:
            rows["c3d_package_s"] = _median_s(lambda: _read_with_c3d(path), args.repeats)
        rows["read_c3d_s"] = _median_s(lambda: read_c3d(path), args.repeats)
        rows["route_s"] = _median_s(lambda: marker_angles(read_c3d(path), mapping)
                                    .recording(body.segment_names), args.repeats)
        rows["accuracy"] = _accuracy(Path(tmp), sway, body, mapping)
        rows["answers"] = _answers(Path(tmp), body)
    OUT.mkdir(parents=True, exist_ok=True)
    atomic_write_text(OUT / "rows.json", json_text(rows))
    package = ("not installed" if rows["c3d_package_s"] is None
               else f"{rows['c3d_package_s']:.3f} s")
    ratio = ("" if rows["c3d_package_s"] is None
             else f" ({rows['c3d_package_s'] / rows['ezc3d_s']:.2g}× ezc3d's time)")
    report = f"""# Reading a C3D trial

Made by `.venv/bin/python benchmarks/c3d_reading.py --seconds {args.seconds:g} --markers \
{args.markers} --repeats {args.repeats}`: a {args.seconds:g} s trial at 100 Hz \
({rows['frames']} frames), {args.markers} markers, a 1 kHz tilt channel and a force channel \
({rows['file_bytes'] / 1e6:.1f} MB); medians of {args.repeats} reads, one run, this machine.

| reader | time |
|---|---|
| ezc3d (every marker and channel) | {rows['ezc3d_s']:.3f} s |
| the pure-Python `c3d` package (the same) | {package}{ratio} |
| `read_c3d` (ezc3d and the project's checks) | {rows['read_c3d_s']:.3f} s |
| the whole route to a recording (read, gaps, angles, tilt) | {rows['route_s']:.3f} s |
"""
    report += """
## The marker route's angles (0.3 mm marker noise)

| layout | shank | thigh | trunk | tilt (platform markers) | tilt (analog channel) |
|---|---|---|---|---|---|
"""
    for row in rows["accuracy"]:
        report += (f"| {row['layout']} | " + " | ".join(f"{v:.4f}°" for v in row["rms_deg"])
                   + f" | {row['tilt_markers_rms_deg']:.4f}° | "
                   f"{row['tilt_channel_rms_deg']:.1e}° |\n")
    noise = rows["accuracy"][0]
    report += ("| the noise's own share | " + " | ".join(f"{v:.4f}°" for v in
                                                          noise["expected_deg"])
               + f" | {noise['tilt_expected_deg']:.4f}° | 0 |\n")
    report += """
## One trial, two files, the default command

| joint | CSV: Kp, class | C3D: Kp, class | C3D's 90 % interval | CSV's Kp inside |
|---|---|---|---|---|
"""
    for row in rows["answers"]:
        report += (f"| {row['joint']} | {row['csv_kp']:.1f}, {row['csv_class']} | "
                   f"{row['c3d_kp']:.1f}, {row['c3d_class']} | [{row['low']:.1f}, "
                   f"{row['high']:.1f}] | {'yes' if row['inside'] else 'no'} |\n")
    atomic_write_text(OUT / "report.md", report)
    print(report)
    print(json.dumps(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
