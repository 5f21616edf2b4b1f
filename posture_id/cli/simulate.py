"""``posture-id simulate``: one trial of a DEC-controlled body on the tilting platform."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from posture_id.bodies.body import DEFAULT_URDF, load_body
from posture_id.cli.arguments import (
    check_out_and_plot,
    check_output_file,
    default_of,
    non_negative_float,
    non_negative_int,
    positive_float,
    say,
)
from posture_id.cli.exit_status import answered
from posture_id.cli.stimulus import add_lab_stimulus_arguments, stimulus_from_args
from posture_id.dec.parameters import DecParameters
from posture_id.errors import PostureIdError
from posture_id.motion_capture.mapping import AXES
from posture_id.simulation.batch import simulate
from posture_id.simulation.noise import DEFAULT_CUTOFF_HZ, MotorNoise
from posture_id.simulation.options import SimulationOptions
from posture_id.simulation.stimulus import prts

__all__ = ["add_parser", "run", "add_model_arguments", "model_options",
           "add_motor_noise_arguments"]


def add_model_arguments(parser: argparse.ArgumentParser) -> None:
    """--sway-limit-deg and --deadband-rad-s with the SimulationOptions defaults."""
    parser.add_argument("--sway-limit-deg", type=positive_float,
                        default=default_of(SimulationOptions, "sway_limit_deg"),
                        help="abort a trial when a segment leaves ±this angle "
                             "(default %(default)g)")
    parser.add_argument("--deadband-rad-s", type=non_negative_float,
                        default=default_of(SimulationOptions, "deadband_rad_s"),
                        help="tilt-estimator dead-band θ, rad/s (default %(default)g)")


def model_options(args: argparse.Namespace) -> SimulationOptions:
    return SimulationOptions(sway_limit_deg=args.sway_limit_deg,
                             deadband_rad_s=args.deadband_rad_s)


def add_motor_noise_arguments(parser: argparse.ArgumentParser, what: str) -> None:
    """--motor-noise DEG and --motor-cutoff-hz (low-pass torque noise at every joint)."""
    parser.add_argument("--motor-noise", type=non_negative_float, default=0.0, metavar="DEG",
                        help=f"low-pass torque noise at every joint, its SD the gravity torque "
                             f"m·g·h of a lean of {what} (default 0: none)")
    parser.add_argument("--motor-cutoff-hz", type=positive_float, default=DEFAULT_CUTOFF_HZ,
                        help="corner frequency of the motor noise's first-order low-pass "
                             "(default %(default)g Hz)")


def add_parser(sub) -> None:
    sim = sub.add_parser("simulate", help="simulate a DEC-controlled body on the tilting platform")
    sim.add_argument("--body", type=Path, help="URDF (default: the TIP)")
    sim.add_argument("--model", choices=("dec", "ic"), default="dec",
                     help="the controller: dec (default) or ic, the independent-channel model "
                          "(docs/model.md §8; every segment at the body COM angle)")
    sim.add_argument("--params", type=Path,
                     help="parameter JSON (default: the body's defaults; with --model ic an "
                          "IC parameter file, \"model\": \"ic\")")
    add_lab_stimulus_arguments(sim, "tilt CSV (time_s,tilt_deg) instead of the PRTS")
    add_model_arguments(sim)
    sim.add_argument("--sensor-noise-deg", type=non_negative_float, default=0.0,
                     help="white sensor noise added to the segment angles, degrees (SD)")
    add_motor_noise_arguments(sim, "this many degrees")
    sim.add_argument("--seed", type=non_negative_int, default=0,
                     help="seed of the sensor and motor noise (default %(default)d)")
    sim.add_argument("--out", type=Path, required=True,
                     help="recording to write: CSV, or a motion-capture trial (NAME.c3d: "
                          "markers at the body's joints, platform markers, an analog tilt "
                          "channel)")
    sim.add_argument("--plot", type=Path, help="plot of tilt and sway to write (PNG)")
    sim.add_argument("--force-plate-out", type=Path, metavar="CSV",
                     help="also write the trial as a force plate under the feet records it: "
                          "time_s,tilt_deg,cop_mm,fz_n (the COP from the ankle torque and the "
                          "support's reaction, forward along the plate from the point under "
                          "the ankle; the normal force)")
    sim.add_argument("--cop-noise-mm", type=non_negative_float, default=0.0,
                     help="white noise on the written COP, mm (SD; default 0)")
    add_c3d_writing_arguments(sim)
    sim.set_defaults(func=run)


def add_c3d_writing_arguments(parser: argparse.ArgumentParser) -> None:
    """The flags of a C3D trial written by ``simulate --out NAME.c3d``."""
    group = parser.add_argument_group("a C3D trial (--out NAME.c3d)")
    group.add_argument("--c3d-forward-axis", choices=AXES[:2] + AXES[3:5],
                       help="the axis the subject faces in the file (default x; a negative "
                            "one as --c3d-forward-axis=-y)")
    group.add_argument("--c3d-unit", choices=("mm", "m"), help="POINT:UNITS (default mm)")
    group.add_argument("--frame-rate-hz", type=positive_float,
                       help="marker frames per second (default 100)")
    group.add_argument("--analog-per-frame", type=non_negative_int,
                       help="analog samples per frame of the tilt channel (default 10; 0: "
                            "no analog channels)")
    group.add_argument("--marker-noise-mm", type=non_negative_float,
                       help="white noise on every marker coordinate, mm (SD; default 0)")
    group.add_argument("--marker-gap", nargs=3, action="append",
                       metavar=("MARKER", "START_S", "DURATION_S"),
                       help="frames where MARKER is not seen (may repeat)")
    group.add_argument("--height-m", type=positive_float,
                       help="the subject's height in the file's metadata, m")
    group.add_argument("--mass-kg", type=positive_float,
                       help="the subject's mass in the file's metadata, kg")


_C3D_FLAGS = ("c3d_forward_axis", "c3d_unit", "frame_rate_hz", "analog_per_frame",
              "marker_noise_mm", "marker_gap", "height_m", "mass_kg")


def _c3d_options(args: argparse.Namespace, end_s: float):
    """The C3D trial's writing options the flags ask for (None: ``--out`` is a CSV),
    checked before anything is simulated; ``end_s``: the trial's length, s."""
    from posture_id.motion_capture import is_c3d

    given = [f"--{f.replace('_', '-')}" for f in _C3D_FLAGS if getattr(args, f) is not None]
    if not is_c3d(args.out):
        if given:
            raise PostureIdError(f"{', '.join(given)} write a C3D trial: give --out NAME.c3d")
        return None
    from posture_id.motion_capture import C3dWriteOptions, LabAxes

    _check_subject(args)
    gaps = [_marker_gap(marker, start, duration, end_s)
            for marker, start, duration in args.marker_gap or ()]
    defaults = C3dWriteOptions()
    return C3dWriteOptions(
        axes=LabAxes(args.c3d_forward_axis or "x"), unit=args.c3d_unit or defaults.unit,
        rate_hz=args.frame_rate_hz or defaults.rate_hz,
        marker_noise_mm=args.marker_noise_mm or 0.0, gaps=tuple(gaps),
        analog_per_frame=(defaults.analog_per_frame if args.analog_per_frame is None
                          else args.analog_per_frame),
        height_m=args.height_m, mass_kg=args.mass_kg, seed=args.seed)


def _write_recording(args: argparse.Namespace, recording, body, c3d) -> None:
    """``--out``: CSV, or a C3D trial written with ``c3d`` (:func:`_c3d_options`); and
    ``--force-plate-out``: the force plate's columns of the noise-free motion."""
    if args.force_plate_out is not None:
        from posture_id.force_plate.writing import write_force_plate_csv

        write_force_plate_csv(args.force_plate_out, body, recording, args.cop_noise_mm,
                              args.seed)
        say(f"wrote {args.force_plate_out} (the force plate's COP and normal force)")
    if args.sensor_noise_deg > 0:  # on the angles as markers see them; the plate's own
        recording = recording.with_sensor_noise(args.sensor_noise_deg, args.seed)
    if c3d is None:
        recording.to_csv(args.out)
        return
    from posture_id.motion_capture import write_c3d

    write_c3d(args.out, recording, tuple(s.length for s in body.segments), c3d)


def _check_subject(args: argparse.Namespace) -> None:
    """Refuse a height or mass in other units than the flags' (175 for 1.75 m)."""
    from posture_id.bodies.anthropometry import HEIGHT_RANGE_M, MASS_RANGE_KG

    for flag, value, (low, high), unit in (
            ("--height-m", args.height_m, HEIGHT_RANGE_M, "metres"),
            ("--mass-kg", args.mass_kg, MASS_RANGE_KG, "kg")):
        if value is not None and not low <= value <= high:
            raise PostureIdError(f"{flag} {value:g}: a person's is {low:g}–{high:g} "
                                 f"{unit}; is it in other units?")


def _marker_gap(marker: str, start: str, duration: str, end_s: float
                ) -> tuple[str, float, float]:
    """One --marker-gap's (marker, start s, duration s), refused unless it lies within
    the trial's 0..``end_s`` and lasts some time."""
    where = f"--marker-gap {marker} {start} {duration}"
    try:
        start_s, duration_s = float(start), float(duration)
    except ValueError:
        raise PostureIdError(f"{where}: START_S and DURATION_S must be numbers of "
                             "seconds") from None
    if not (np.isfinite(duration_s) and duration_s > 0):
        raise PostureIdError(f"{where}: DURATION_S must be > 0 s (a gap lasts some time)")
    if not (np.isfinite(start_s) and 0 <= start_s < end_s):
        raise PostureIdError(f"{where}: START_S must be within the trial, 0 to {end_s:g} s "
                             f"({'after it ends' if start_s >= end_s else 'before it starts'})")
    return marker, start_s, duration_s


def run(args: argparse.Namespace) -> int:
    inputs = (args.body, args.params, args.tilt)
    check_out_and_plot(args, inputs)
    check_output_file(args.force_plate_out, "--force-plate-out", inputs,
                      outputs=(args.out, args.plot))
    if args.cop_noise_mm and args.force_plate_out is None:
        raise PostureIdError("--cop-noise-mm goes with --force-plate-out")
    body = load_body(args.body or DEFAULT_URDF)
    stimulus = stimulus_from_args(args, default=prts())
    c3d = _c3d_options(args, stimulus.duration)
    options = model_options(args)
    if args.model == "ic":
        return _simulate_ic(args, body, stimulus, options, c3d)
    params = DecParameters.from_json(args.params, body) if args.params else None
    motor = (MotorNoise(args.motor_noise, args.motor_cutoff_hz, args.seed)
             if args.motor_noise > 0 else None)
    result = simulate(body, params, stimulus, options, motor_noise=motor)
    recording = result.to_recording()
    _write_recording(args, recording, body, c3d)
    say(f"wrote {args.out} ({len(result.time)} samples at {options.sample_rate_hz:g} Hz)")
    if args.plot:
        result.plot(args.plot)
        say(f"wrote {args.plot}")
    if not result.stable:
        say(f"posture-id: warning: the body left the ±{options.sway_limit_deg:g}° sway limit "
            f"at t = {result.abort_time:.3f} s; the recording stops there")
    return answered(not result.stable)


def _simulate_ic(args: argparse.Namespace, body, stimulus, options, c3d) -> int:
    """``--model ic``: the IC model's recording (docs/model.md §8)."""
    from posture_id.models.ic import IcParameters, IcPlant, default_ic_parameters, simulate_ic

    if args.deadband_rad_s != default_of(SimulationOptions, "deadband_rad_s"):
        raise PostureIdError("--deadband-rad-s is DEC's tilt estimator; the IC model has none")
    params = (IcParameters.from_json(args.params) if args.params
              else default_ic_parameters(IcPlant.of(body).mgh))
    recording = simulate_ic(body, params, stimulus, options, args.motor_noise,
                            args.motor_cutoff_hz, args.seed)
    _write_recording(args, recording, body, c3d)
    say(f"wrote {args.out} ({len(recording.time)} samples at {options.sample_rate_hz:g} Hz; "
        f"{params.summary()})")
    if args.plot:
        from posture_id.plotting import plot_batch

        alpha = body.com_angles(recording.theta)[:, 0]
        plot_batch(recording.time, recording.tilt, alpha[None],
                   np.array([np.all(np.isfinite(alpha))]), "IC model", path=args.plot)
        say(f"wrote {args.plot}")
    fell = not np.all(np.isfinite(recording.theta))
    if fell:
        say(f"posture-id: warning: the body left the ±{options.sway_limit_deg:g}° sway limit; "
            "the recording stops there")
    return answered(fell)
