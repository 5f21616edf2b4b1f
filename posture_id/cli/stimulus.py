"""Stimulus flags shared by the commands: the PRTS as docs/model.md §4 defines it, as a lab ran
it (state duration, lead-in, starting state, sign, platform lag), or a tilt file; and the
column flags that read a lab's recording as it is."""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

from posture_id.cli.arguments import (
    default_of,
    non_negative_float,
    positive_float,
    positive_int,
    say,
)
from posture_id.cli.markers import add_marker_arguments, mapping_from_args, write_marker_plot
from posture_id.errors import PostureIdError
from posture_id.force_plate.cop import CopUnit
from posture_id.force_plate.reading import ForcePlateColumns
from posture_id.motion_capture import is_c3d
from posture_id.motion_capture.mapping import MarkerMapping
from posture_id.motion_capture.marker_table import LengthUnit, MarkerColumns
from posture_id.recording import AngleUnit, Recording, RecordingColumns, TimeUnit
from posture_id.simulation.protocols import Protocol, read_protocol
from posture_id.simulation.stimulus import (
    PRTS_REGISTERS,
    PRTS_STATE_S,
    TiltProfile,
    prts,
    read_tilt_file,
)
from posture_id.trials import PreparedTrial, prepare_trial
from posture_id.trials.reading import RecordingLayout, read_recording

__all__ = ["add_stimulus_arguments", "add_lab_stimulus_arguments", "prts_arguments",
           "protocol_profile",
           "stimulus_from_args", "recording_and_stimulus", "prepared_trial", "add_column_arguments",
           "add_recording_arguments",
           "columns_from_args"]

_PRTS_FLAGS = {"amplitude_deg": "--amplitude-deg", "cycles": "--cycles", "states": "--states"}
_LAB_FLAGS = {"state_s": "--state-s", "onset_s": "--onset-s", "start_state": "--start-state",
              "sign": "--sign", "lag_s": "--lag-s"}


def add_stimulus_arguments(parser: argparse.ArgumentParser) -> None:
    """--amplitude-deg, --cycles, --states (defaults: the PRTS's, filled in by
    :func:`prts_arguments`, so that a flag given next to ``--tilt`` can be told apart)."""
    parser.add_argument("--amplitude-deg", type=positive_float,
                        help=f"PRTS peak-to-peak tilt, degrees (default "
                             f"{default_of(prts, 'amplitude_deg'):g})")
    parser.add_argument("--cycles", type=positive_int,
                        help=f"PRTS cycles (default {default_of(prts, 'cycles')})")
    parser.add_argument("--states", type=int, choices=sorted(PRTS_REGISTERS, reverse=True),
                        help=f"PRTS length (default {default_of(prts, 'states')} states, "
                             "60.5 s a cycle)")


def add_lab_stimulus_arguments(parser: argparse.ArgumentParser, tilt_help: str) -> None:
    """The PRTS flags, those describing how a lab ran it, and ``--tilt FILE``."""
    add_stimulus_arguments(parser)
    parser.add_argument("--state-s", type=positive_float,
                        help=f"PRTS state duration, s (default {PRTS_STATE_S:g})")
    parser.add_argument("--onset-s", type=non_negative_float,
                        help="level platform before the sequence starts, s (default 0)")
    parser.add_argument("--start-state", type=non_negative_float,
                        help="the sequence starts this many states into its cycle, "
                             "fractional for a start part-way through a state (default 0)")
    parser.add_argument("--sign", choices=("+1", "-1"),
                        help="-1 when the platform's positive tilt is the other way")
    parser.add_argument("--lag-s", type=non_negative_float,
                        help="the platform follows its command this late, s (default 0)")
    parser.add_argument("--tilt", type=Path, help=tilt_help)
    parser.add_argument("--protocol", type=Path, metavar="FILE",
                        help="the stimulus as a protocol file (JSON: posture-id design "
                             "writes them); replaces the PRTS flags")
    parser.add_argument("--part", type=positive_int,
                        help="which recording of a two-amplitude protocol (1 or 2)")


def prts_arguments(args: argparse.Namespace) -> dict:
    """The PRTS keyword arguments the flags ask for, defaults filled in."""
    out = {k: getattr(args, k) if getattr(args, k) is not None else default_of(prts, k)
           for k in _PRTS_FLAGS}
    out.update({k: getattr(args, k) for k in _LAB_FLAGS if getattr(args, k, None) is not None})
    if "sign" in out:
        out["sign"] = int(out["sign"])
    return out


def stimulus_from_args(args: argparse.Namespace, default: TiltProfile | None
                       ) -> TiltProfile | None:
    """The stimulus the flags name: a tilt file, a PRTS (when any PRTS flag is given), or
    ``default``. A PRTS flag next to ``--tilt`` is refused."""
    given = [flag for key, flag in {**_PRTS_FLAGS, **_LAB_FLAGS}.items()
             if getattr(args, key, None) is not None]
    if getattr(args, "protocol", None):
        if given or getattr(args, "tilt", None):
            raise PostureIdError(f"--protocol replaces the PRTS and --tilt: "
                                 f"{', '.join(given or ['--tilt'])} do not apply")
        return protocol_profile(read_protocol(args.protocol), getattr(args, "part", None),
                                args.protocol)
    if getattr(args, "part", None) is not None:
        raise PostureIdError("--part goes with --protocol")
    if getattr(args, "tilt", None):
        if given:
            raise PostureIdError(f"--tilt replaces the PRTS: {', '.join(given)} do not apply")
        profile, notices = read_tilt_file(args.tilt)
        for notice in notices:  # its encoding, title lines skipped, decimal commas
            say(notice)
        return profile
    if given:
        return prts(**prts_arguments(args))
    return default


def protocol_profile(protocol: Protocol, part: int | None, where) -> TiltProfile:
    """The tilt of one recording of a protocol: the protocol's own, or recording ``part``
    (1-based) of a two-amplitude protocol, which needs it."""
    recordings = protocol.recordings
    if len(recordings) > 1 and part is None:
        raise PostureIdError(f"{where}: {protocol.label()} is {len(recordings)} recordings; "
                             f"name one with --part 1..{len(recordings)}")
    if part is not None and not 1 <= part <= len(recordings):
        raise PostureIdError(f"{where}: --part must be within 1..{len(recordings)}, got {part}")
    return recordings[(part or 1) - 1].profile()


def _units_given(args: argparse.Namespace) -> str | None:
    """``--units`` as given, None when it was not (the header's unit, else deg)."""
    units = getattr(args, "units", None)
    return None if units is None else str(units)


def add_column_arguments(parser: argparse.ArgumentParser) -> None:
    """Flags that read a lab's file as it is: which column is what, and in which unit."""
    group = parser.add_argument_group(
        "a lab's columns", "read the file as it is: comma, tab or ';' separated, decimal "
        "commas, title lines, units in the header such as 'Time [ms]' (default: "
        "time_s,tilt_deg,<segment>_deg); a column is named by its header name with or "
        "without its unit")
    group.add_argument("--angle-columns", nargs="+", metavar="COLUMN",
                       help="the sway columns, one per body segment, support upward (a "
                            "body-COM column with a 1-segment body); the other column flags "
                            "apply with it")
    group.add_argument("--time-column", default="time_s",
                       help="the time column (default %(default)s)")
    group.add_argument("--time-units", choices=[u.value for u in TimeUnit],
                       help="unit of the time column (default: the header's, else s)")
    group.add_argument("--tilt-column", default="tilt_deg",
                       help="the platform-tilt column, or 'none' (the tilt is then the named "
                            "stimulus's; default %(default)s)")
    group.add_argument("--units", choices=[u.value for u in AngleUnit],
                       help="unit of the tilt and angle columns (default: the header's, "
                            "else deg)")
    group.add_argument("--sample-rate-hz", type=positive_float,
                       help="the true sampling rate: overrides a wrong time column")
    plate = parser.add_argument_group(
        "a force plate's file", "the COP turned into the body-COM sway through the subject's "
        "body (--body), which is then taken as one segment (docs/force_plates.md)")
    plate.add_argument("--cop-column", metavar="NAME",
                       help="the COP column, forward along the plate (in place of "
                            "--angle-columns)")
    plate.add_argument("--cop-units", choices=[u.value for u in CopUnit],
                       help="unit of the COP column (default: the header's, else mm)")
    plate.add_argument("--force-column", metavar="NAME",
                       help="the plate's normal force, N (default: the static load "
                            "m·g·cos(tilt))")
    plate.add_argument("--ankle-height-m", type=non_negative_float,
                       help="the ankle axis above the plate's surface, m (default 0)")
    plate.add_argument("--cop-sign", choices=("+1", "-1"),
                       help="-1 when the plate's COP axis points backward")
    add_marker_arguments(parser)


def add_recording_arguments(parser: argparse.ArgumentParser, tilt_help: str =
                            "tilt CSV (time_s,tilt_deg) the recording was made with") -> None:
    """The flags of a command that reads a recording: how its stimulus ran
    (:func:`add_lab_stimulus_arguments`, ``tilt_help`` the help of ``--tilt``) and which
    of its columns is what (:func:`add_column_arguments`)."""
    add_lab_stimulus_arguments(parser, tilt_help)
    add_column_arguments(parser)


def _force_plate_flags(args: argparse.Namespace) -> list[str]:
    """The force-plate flags given besides --cop-column."""
    return [flag for flag, key in (("--cop-units", "cop_units"),
                                   ("--force-column", "force_column"),
                                   ("--ankle-height-m", "ankle_height_m"),
                                   ("--cop-sign", "cop_sign"))
            if getattr(args, key, None) is not None]


def _positions_table(recording: str | None) -> bool:
    """Whether the marker flags read a CSV's positions: the recording is not a C3D file,
    nor a folder holding one (a cohort of C3D trials)."""
    if not recording:
        return False
    path = Path(recording)
    if path.is_dir():
        return not any(is_c3d(p) for p in path.iterdir())
    return not is_c3d(path)


def columns_from_args(args: argparse.Namespace) -> RecordingLayout:
    """How the flags say the file is read: a lab's columns, a C3D's marker mapping, or
    None for the standard header."""
    units = _units_given(args)
    time_units = getattr(args, "time_units", None)
    table = _positions_table(getattr(args, "recording", None))
    mapping = mapping_from_args(args, table=table)
    if mapping is not None and table:
        columns = _lab_columns(args, units, time_units, ())
        if mapping.tilt is not None:  # the platform's markers give the tilt
            columns = replace(columns, tilt=None)
        return MarkerColumns(mapping, columns, None if args.position_units is None
                             else LengthUnit(args.position_units))
    if mapping is not None:
        if time_units is not None:
            raise PostureIdError("--time-units reads a CSV file's time column; a C3D trial "
                                 "has its own rate")
        return mapping
    plate = _force_plate_flags(args)
    if getattr(args, "cop_column", None):
        if getattr(args, "angle_columns", None):
            raise PostureIdError("--cop-column and --angle-columns are two sources of the "
                                 "sway: give one")
        return ForcePlateColumns(
            cop=args.cop_column, time=args.time_column, tilt=_tilt_column(args),
            force=args.force_column, unit=None if units is None else AngleUnit(units),
            time_unit=None if time_units is None else TimeUnit(time_units),
            sample_rate_hz=args.sample_rate_hz,
            cop_unit=None if args.cop_units is None else CopUnit(args.cop_units),
            ankle_height_m=args.ankle_height_m or 0.0,
            cop_sign=int(args.cop_sign or "+1"))
    if plate:
        raise PostureIdError(f"{', '.join(plate)} go with --cop-column (a force plate's COP)")
    if not getattr(args, "angle_columns", None):
        flags = [flag for flag, on in (
            ("--sample-rate-hz", getattr(args, "sample_rate_hz", None) is not None),
            ("--units", units not in (None, AngleUnit.DEGREES.value)),
            ("--time-units", time_units not in (None, TimeUnit.SECONDS.value))) if on]
        if flags:
            raise PostureIdError(f"{' and '.join(flags)} go{'es' if len(flags) == 1 else ''} "
                                 "with --angle-columns (name the file's columns)")
        if getattr(args, "time_column", "time_s") != "time_s" or \
                getattr(args, "tilt_column", "tilt_deg") != "tilt_deg":
            raise PostureIdError("--time-column and --tilt-column go with --angle-columns "
                                 "(name the file's columns)")
        return None
    return _lab_columns(args, units, time_units, tuple(args.angle_columns))


def _tilt_column(args: argparse.Namespace) -> str | None:
    """--tilt-column, or None for ``none`` (the file has no tilt column)."""
    return None if args.tilt_column.lower() == "none" else args.tilt_column


def _lab_columns(args: argparse.Namespace, units: str | None, time_units: str | None,
                 angles: tuple[str, ...]) -> RecordingColumns:
    """A lab's file's time, tilt and ``angles`` columns and their units, as the flags
    name them."""
    return RecordingColumns(time=args.time_column, tilt=_tilt_column(args), angles=angles,
                            unit=None if units is None else AngleUnit(units),
                            time_unit=None if time_units is None else TimeUnit(time_units),
                            sample_rate_hz=args.sample_rate_hz)


def recording_and_stimulus(args: argparse.Namespace, body) -> tuple[Recording,
                                                                    TiltProfile | None]:
    """The recording ``args.recording`` for ``body`` (None: any angle columns) and the
    stimulus the flags name (its tilt fills in a recording without a tilt column)."""
    stimulus = stimulus_from_args(args, default=None)
    layout = columns_from_args(args)
    recording = read_recording(args.recording, None if body is None else body.segment_names,
                               None if stimulus is None else stimulus.angle, layout, body)
    if isinstance(layout, MarkerMapping) and getattr(args, "plot", None):  # a C3D's
        write_marker_plot(Path(args.recording), layout, Path(args.plot))
    return recording, stimulus


def prepared_trial(args: argparse.Namespace, body, rate_hz: float | None = 50.0,
                   checked: bool = True) -> PreparedTrial:
    """``args.recording`` read for ``body`` with its stimulus (:func:`recording_and_stimulus`),
    with ``checked`` its columns checked to be the body's segments, prepared at ``rate_hz``
    Hz (None: the recording's own rate, as the FRF takes it)."""
    recording, stimulus = recording_and_stimulus(args, body)
    if checked:
        recording.check_segments(body.segment_names)
    return prepare_trial(recording, stimulus, rate_hz)
