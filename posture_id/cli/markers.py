"""The flags that read a motion-capture trial (C3D), or the marker or tracker positions of a
text table: which markers make each segment, the platform's tilt, the lab's axes, the
positions' unit, and how long a gap may be filled."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.bodies.body import load_body
from posture_id.cli.arguments import non_negative_float, nonzero_float, say
from posture_id.errors import PostureIdError
from posture_id.motion_capture.mapping import (
    AXES,
    DEFAULT_MAX_GAP_S,
    LabAxes,
    MarkerMapping,
    TiltChannel,
    parse_com_markers,
    parse_segment_markers,
    parse_tilt_markers,
)

__all__ = ["add_marker_arguments", "mapping_from_args", "marker_flags_given",
           "write_marker_plot"]

#: The marker flags and their defaults (a flag is given when its value differs).
_MARKER_FLAGS = {"segment_markers": None, "com_markers": None, "tilt_markers": None,
                 "tilt_channel": None, "tilt_scale": None, "forward_axis": None,
                 "vertical_axis": "z", "max_gap_s": DEFAULT_MAX_GAP_S,
                 "position_units": None}


def add_marker_arguments(parser: argparse.ArgumentParser) -> None:
    """--segment-markers, --com-markers, --tilt-markers, --tilt-channel, --tilt-scale,
    --forward-axis, --vertical-axis, --max-gap-s."""
    group = parser.add_argument_group(
        "a motion-capture trial (C3D), or marker or tracker positions in a CSV",
        "the angles from markers: segment angles in space from the vertical, positive "
        "forward; the tilt positive when the platform's front edge goes down; in a CSV a "
        "point NAME is its columns NAME_x, NAME_y, NAME_z, its tilt the --tilt-column "
        "(docs/motion_capture.md)")
    group.add_argument("--segment-markers", nargs="+", metavar="SEGMENT=LOWER,UPPER",
                       help="each segment's lower and upper point, support upward (e.g. "
                            "leg=ANK,HIP trunk=HIP,SHO); a point may average markers: "
                            "LGTR+RGTR")
    group.add_argument("--com-markers", nargs="+", metavar="POINT",
                       help="a 1-segment body's COM: the support point, then the weighted "
                            "points whose mean is the COM (e.g. LANK+RANK LGTR+RGTR:0.6 "
                            "LSHO+RSHO:0.4)")
    group.add_argument("--tilt-markers", metavar="BACK,FRONT",
                       help="the platform's tilt from two markers on it, behind and in front "
                            "of the ankles (level at the trial's start)")
    group.add_argument("--tilt-channel", metavar="NAME",
                       help="the platform's tilt from an analog channel (its angle sensor), "
                            "resampled to the marker rate")
    group.add_argument("--tilt-scale", type=nonzero_float, metavar="DEG_PER_UNIT",
                       help="--tilt-channel's degrees per unit, positive for the front edge "
                            "down (default 1: the channel is in degrees)")
    group.add_argument("--forward-axis", choices=AXES,
                       help="the file's axis the subject faces (needed for C3D; a negative "
                            "one as --forward-axis=-y)")
    group.add_argument("--vertical-axis", choices=AXES, default="z",
                       help="the file's upward axis (default %(default)s)")
    group.add_argument("--position-units", choices=("m", "cm", "mm"),
                       help="a CSV's position columns' unit where their headers state none "
                            "(default m)")
    group.add_argument("--max-gap-s", type=non_negative_float, default=DEFAULT_MAX_GAP_S,
                       help="the longest gap of an occluded marker filled (cubic spline), s; "
                            "a longer one is refused (default %(default)g)")


def marker_flags_given(args: argparse.Namespace) -> list[str]:
    """The marker flags given, spelled as flags."""
    return [f"--{name.replace('_', '-')}" for name, default in _MARKER_FLAGS.items()
            if getattr(args, name, default) != default]


def mapping_from_args(args: argparse.Namespace, table: bool = False) -> MarkerMapping | None:
    """The mapping the marker flags give, or None when none is given; ``table``: for the
    positions in a CSV (its time and tilt columns named by the CSV flags), else a C3D's.

    Raises:
        PostureIdError: both or neither of --segment-markers and --com-markers, both tilt
            sources, --tilt-scale without --tilt-channel, no --forward-axis; for a C3D a
            CSV's column flags, for a CSV a C3D's analog channel.
    """
    given = marker_flags_given(args)
    if not given:
        return None
    columns = [flag for flag, on in (
        ("--angle-columns", getattr(args, "angle_columns", None)),
        ("--time-column", getattr(args, "time_column", "time_s") != "time_s"),
        ("--tilt-column", getattr(args, "tilt_column", "tilt_deg") != "tilt_deg"),
        ("--units", getattr(args, "units", None) is not None),
        ("--sample-rate-hz", getattr(args, "sample_rate_hz", None) is not None),
        ("--cop-column", getattr(args, "cop_column", None))) if on]
    if table:
        beside = [f for f in columns if f in ("--angle-columns", "--cop-column")]
        if beside:
            raise PostureIdError(f"{', '.join(beside)} and the marker flags "
                                 f"({', '.join(given)}) are two sources of the sway: give one")
        if args.tilt_channel or args.tilt_scale is not None:
            where = getattr(args, "recording", None)
            raise PostureIdError(f"{str(where) + ': ' if where else ''}--tilt-channel and "
                                 "--tilt-scale read a C3D's analog channel; a CSV's tilt is "
                                 "its --tilt-column (or --tilt-markers BACK,FRONT)")
    elif columns or getattr(args, "position_units", None) is not None:
        columns += ["--position-units"] if getattr(args, "position_units", None) else []
        raise PostureIdError(f"{', '.join(columns)} read a CSV file's columns, and the "
                             f"marker flags ({', '.join(given)}) a C3D trial: give the ones "
                             "for the file (a C3D's tilt: --tilt-markers or --tilt-channel)")
    if args.tilt_markers and args.tilt_channel:
        raise PostureIdError("--tilt-markers and --tilt-channel are two sources of the "
                             "platform's tilt: give one")
    if args.tilt_scale is not None and not args.tilt_channel:
        raise PostureIdError("--tilt-scale goes with --tilt-channel (an analog channel's "
                             "degrees per unit)")
    what = "a CSV's marker positions" if table else "a C3D trial"
    if not (args.segment_markers or args.com_markers):
        raise PostureIdError(f"{', '.join(given)} read {what}: name its markers too "
                             "(--segment-markers SEGMENT=LOWER,UPPER ..., or --com-markers)")
    if args.forward_axis is None:
        raise PostureIdError(f"{what} needs --forward-axis: the file's axis the subject "
                             f"faces ({', '.join(AXES)}); angles are signed by it")
    tilt = None
    if args.tilt_markers:
        tilt = parse_tilt_markers(args.tilt_markers)
    elif args.tilt_channel:
        tilt = TiltChannel(args.tilt_channel,
                           1.0 if args.tilt_scale is None else args.tilt_scale)
    return MarkerMapping(
        axes=LabAxes(args.forward_axis, args.vertical_axis),
        segments=parse_segment_markers(args.segment_markers or ()),
        com=parse_com_markers(args.com_markers) if args.com_markers else None,
        tilt=tilt, max_gap_s=args.max_gap_s)


def write_marker_plot(recording_path: Path, mapping: MarkerMapping, plot: Path) -> Path:
    """The marker check beside ``plot`` (``NAME.markers.png``): raw traces and the angles
    derived from them."""
    from posture_id.motion_capture import marker_angles, read_c3d

    beside = plot.with_name(plot.stem + ".markers" + plot.suffix)
    marker_angles(read_c3d(recording_path), mapping).plot(beside)
    say(f"wrote {beside}")
    return beside


def trial_subject(path: Path) -> tuple[float, float]:
    """(height m, mass kg) from a C3D trial's metadata, or a one-line refusal naming the
    parameters looked for."""
    from posture_id.motion_capture.c3d_file import (
        HEIGHT_PARAMETERS,
        MASS_PARAMETERS,
        read_c3d,
    )

    trial = read_c3d(path)
    if trial.height_m is None or trial.mass_kg is None:
        looked = ", ".join(f"{g}:{p}" for g, p in HEIGHT_PARAMETERS + MASS_PARAMETERS)
        raise PostureIdError(f"{path}: the file does not give the subject's height and mass "
                             f"(looked for {looked}): give --height-m and --mass-kg")
    return trial.height_m, trial.mass_kg


def _force_plate_body(args: argparse.Namespace):
    """A force plate's recording is the body-COM sway of the subject's body (``--body``,
    required) taken as one segment (said on stderr when the body has more)."""
    from posture_id.bodies.one_segment import one_segment_body

    if args.body is None and getattr(args, "height_m", None) is not None:
        return _plate_weighed_body(args)
    if args.body is None:
        raise PostureIdError("--cop-column: the COP is turned into the body's sway through the "
                             "subject's body: give it (--body URDF; posture-id body --height-m "
                             "H --mass-kg M --segments 1 writes one; or --height-m H with the "
                             "plate's --load-columns)")
    body = load_body(args.body)
    single = one_segment_body(body)
    if single is not body:
        say(f"{args.body}: the force plate gives the body COM alone: the body as one segment "
            f"(its mass, COM height and inertia about the ankle; {single.urdf_path})")
    return single


def _plate_weighed_body(args: argparse.Namespace):
    """``--height-m H --load-columns ...``: the one-segment Winter body of the subject's
    height and the mass the trial's own load columns give (said on stderr)."""
    from posture_id.bodies.anthropometry import winter_body_file
    from posture_id.cli.plate_mass import load_columns_from_args
    from posture_id.force_plate.load import standing_mass

    load = load_columns_from_args(args)
    if load is None:
        raise PostureIdError("--height-m makes the subject's body with the mass the plate "
                             "weighs: name its load columns (--load-columns NAME ...)")
    tilt = None if str(args.tilt_column).lower() == "none" else args.tilt_column
    mass = standing_mass(args.recording, load, tilt)
    say(mass.notice)
    say(f"{args.recording}: the subject's body: Winter's tables for {args.height_m:.3g} m and "
        f"{mass.mass_kg:.4g} kg, one segment (the force plate gives the body COM)")
    return load_body(winter_body_file(args.height_m, mass.mass_kg, 1))


def recording_body(args: argparse.Namespace, default: Path | None):
    """The body a command reads ``args.recording`` for: ``--body``; else, for a C3D trial
    whose metadata give the subject's height and mass, their Winter body with as many
    segments as the markers name (said on stderr); else ``default`` (None: no body)."""
    from posture_id.motion_capture import is_c3d, marker_angles, read_c3d
    from posture_id.trials.subjects import subject_urdf

    if getattr(args, "cop_column", None):
        return _force_plate_body(args)
    if args.body is not None:
        return load_body(args.body)
    mapping = (mapping_from_args(args)
               if is_c3d(getattr(args, "recording", "") or "") else None)
    urdf = None if mapping is None else subject_urdf(Path(args.recording), None, None,
                                                     mapping)
    if urdf is not None:  # the file gives the subject's height and mass
        trial = read_c3d(args.recording)  # kept from subject_urdf's read
        marker_angles(trial, mapping)  # a trial its markers cannot be read from: refused first
        say(f"{args.recording}: the subject's body from the file's metadata: Winter's "
            f"tables for {trial.height_m:.3g} m and {trial.mass_kg:.4g} kg, "
            f"{mapping.n_segments} segment(s) (--body URDF gives another)")
        return load_body(urdf)
    return None if default is None else load_body(default)
