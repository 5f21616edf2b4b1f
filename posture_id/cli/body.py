"""``posture-id body``: describe a body (URDF), or write one (Winter, default TIP, lumped)."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.bodies.anthropometry import (
    default_tip_segments,
    straight_links,
    winter_segments,
)
from posture_id.bodies.body import DEFAULT_URDF, load_body
from posture_id.bodies.lumping import PRESETS, lump_robot, preset_body
from posture_id.bodies.urdf_writer import write_chain_urdf
from posture_id.cli.arguments import check_output_file, positive_float, say
from posture_id.cli.plate_mass import add_load_arguments, load_columns_from_args
from posture_id.dec.parameters import default_parameters
from posture_id.errors import PostureIdError
from posture_id.fileio import json_text

__all__ = ["add_parser", "run"]


def add_parser(sub) -> None:
    body = sub.add_parser("body", help="describe a body (URDF) or write one")
    body.add_argument("urdf", nargs="?", type=Path, help="URDF file (default: the TIP)")
    body.add_argument("--json", action="store_true", help="print JSON instead of a table")
    mode = body.add_mutually_exclusive_group()
    mode.add_argument("--height-m", type=positive_float,
                      help="write a Winter body: height, m (with --mass-kg)")
    mode.add_argument("--default-tip", action="store_true",
                      help="write the default triple inverted pendulum of docs/model.md §1")
    mode.add_argument("--from-robot", choices=sorted(PRESETS),
                      help="lump a humanoid shipped by example-robot-data")
    mode.add_argument("--lump", type=Path, metavar="URDF",
                      help="lump a whole-body URDF (floating base, two legs) into a chain")
    mode.add_argument("--from-trial", type=Path, metavar="C3D",
                      help="write the Winter body of the subject a motion-capture trial's "
                           "metadata describe (height and mass)")
    body.add_argument("--mass-kg", type=positive_float, help="write a Winter body: mass, kg")
    body.add_argument("--mass-from", type=Path, metavar="TRIAL",
                      help="write a Winter body: the mass a force plate's trial weighs (its "
                           "--load-columns while the platform rests level), in place of "
                           "--mass-kg")
    body.add_argument("--tilt-column", metavar="NAME",
                      help="--mass-from: the trial's tilt column, to weigh where the platform "
                           "rests level (default: every sample)")
    add_load_arguments(body, "with --mass-from: the columns that weigh the subject")
    body.add_argument("--segments", type=int, default=3, choices=(1, 2, 3),
                      help="written body: 3 shank+thigh+trunk, 2 leg+trunk, 1 whole body")
    body.add_argument("--ankle-joints", nargs=2, metavar=("LEFT", "RIGHT"),
                      help="--lump: ankle pitch joints")
    body.add_argument("--knee-joints", nargs=2, metavar=("LEFT", "RIGHT"),
                      help="--lump: knee joints (needed for 3 segments)")
    body.add_argument("--hip-joints", nargs=2, metavar=("LEFT", "RIGHT"),
                      help="--lump: hip pitch joints")
    body.add_argument("--srdf", type=Path, help="--lump: SRDF holding the reference posture")
    body.add_argument("--posture", help="--lump: name of the posture in the SRDF")
    body.add_argument("--out", type=Path, help="where to write the generated URDF")
    body.set_defaults(func=run)


def _write(args: argparse.Namespace) -> Path | None:
    """Write the body the flags ask for; its path, or None when only describing."""
    if args.mass_kg is not None and args.height_m is None:
        raise PostureIdError("--mass-kg goes with --height-m (a Winter body)")
    _weighed(args)
    if args.from_trial is not None:
        from posture_id.cli.markers import trial_subject

        args.height_m, args.mass_kg = trial_subject(args.from_trial)
        say(f"{args.from_trial}: the subject is {args.height_m:.3g} m and {args.mass_kg:.4g} kg")
    writing = args.height_m is not None or args.default_tip or args.from_robot or args.lump
    lump_only = [f"--{f.replace('_', '-')}" for f in ("ankle_joints", "knee_joints",
                                                      "hip_joints", "srdf", "posture")
                 if getattr(args, f) is not None]
    if lump_only and not args.lump:
        raise PostureIdError(f"{', '.join(lump_only)} go with --lump (a whole-body URDF)")
    if args.default_tip and args.segments != 3:
        raise PostureIdError("--default-tip writes the 3-segment TIP of docs/model.md §1; "
                             "--segments goes with --height-m, --from-robot or --lump")
    if not writing:
        if args.out is not None:
            raise PostureIdError("--out writes a body: give --height-m and --mass-kg, "
                                 "--default-tip, --from-robot or --lump (describing a URDF "
                                 "writes nothing)")
        if args.segments != 3:
            raise PostureIdError("--segments goes with a body to write (--height-m, "
                                 "--from-robot or --lump); a URDF has its own")
        return None
    if args.out is None:
        raise PostureIdError("--out is required to write a body URDF")
    check_output_file(args.out, "--out", inputs=(args.urdf, args.lump, args.srdf,
                                                  args.from_trial, args.mass_from))
    if args.urdf is not None:
        raise PostureIdError("give either a URDF to describe or flags to write one, not both")
    if args.from_robot:
        lumped = preset_body(args.from_robot, args.segments)
    elif args.lump:
        for flag in ("ankle_joints", "hip_joints"):
            if getattr(args, flag) is None:
                raise PostureIdError(f"--lump needs --{flag.replace('_', '-')} LEFT RIGHT")
        if (args.srdf is None) != (args.posture is None):
            raise PostureIdError("--srdf and --posture go together")
        lumped = lump_robot(
            args.lump, ankle=tuple(args.ankle_joints), hip=tuple(args.hip_joints),
            knee=tuple(args.knee_joints) if args.knee_joints else None,
            srdf=(args.srdf, args.posture) if args.srdf is not None else None,
            segments=args.segments,
        )
    else:
        lumped = None
    if lumped is not None:
        path = lumped.write(args.out)
        say(f"wrote {path} ({lumped.origin})")
        return path
    if args.default_tip:
        segments, name = default_tip_segments(), "tip_default"
    else:
        if args.mass_kg is None:
            raise PostureIdError("--height-m goes with --mass-kg (a Winter body)")
        segments = winter_segments(args.height_m, args.mass_kg, args.segments)
        name = f"winter_{args.height_m:g}m_{args.mass_kg:g}kg_{args.segments}seg"
    path = write_chain_urdf(args.out, name, straight_links(segments))
    say(f"wrote {path}")
    if not args.default_tip:
        modelled = sum(s.mass for s in segments)
        say(f"it models {modelled:.2f} of the {args.mass_kg:g} kg: the feet "
            f"({args.mass_kg - modelled:.2f} kg, Winter's tables) are the support on the "
            "platform, not a segment that sways (docs/model.md)")
    return path


def _weighed(args: argparse.Namespace) -> None:
    """``--mass-from TRIAL``: the mass the trial's load columns give, as --mass-kg."""
    load = load_columns_from_args(args)
    if args.mass_from is None:
        given = [f for f, v in (("--load-columns", load), ("--tilt-column", args.tilt_column))
                 if v is not None]
        if given:
            raise PostureIdError(f"{', '.join(given)} go with --mass-from TRIAL (the subject "
                                 "weighed by a force plate)")
        return
    if args.height_m is None:
        raise PostureIdError("--mass-from goes with --height-m (a Winter body)")
    if args.mass_kg is not None:
        raise PostureIdError("--mass-kg and --mass-from are two masses: give one")
    if load is None:
        raise PostureIdError(f"--mass-from {args.mass_from}: name the plate's load columns "
                             "(--load-columns NAME ...: its load cells, or its vertical force)")
    from posture_id.force_plate.load import standing_mass

    mass = standing_mass(args.mass_from, load, args.tilt_column)
    say(mass.notice)
    args.mass_kg = mass.mass_kg


def run(args: argparse.Namespace) -> int:
    urdf = _write(args) or args.urdf or DEFAULT_URDF
    body = load_body(urdf)
    params = default_parameters(body)
    if args.json:
        print(json_text({**body.to_dict(), "default_parameters": params.to_dict()}), end="")
    else:
        print(body.summary() + "\n\ndefault parameters (docs/model.md §3):\n" + params.summary())
    return 0
