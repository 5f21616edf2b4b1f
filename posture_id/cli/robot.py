"""``posture-id robot check``: a body's DEC in MuJoCo against the lumped model posture_id
simulates (docs/robots.md): a humanoid preset's whole body, or a chain URDF."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.cli.arguments import positive_float, say
from posture_id.cli.exit_status import answered
from posture_id.cli.output_folder import OutputFolder
from posture_id.cli.simulate import add_model_arguments, model_options
from posture_id.cli.stimulus import add_lab_stimulus_arguments, stimulus_from_args
from posture_id.errors import PostureIdError
from posture_id.robots.whole_body import HeldJoints, WholeBodyOptions

__all__ = ["add_parser", "run_check", "CHECK_FILES"]

#: What ``robot check --out DIR`` writes.
CHECK_FILES = ("check.json", "check.png")


def add_parser(sub) -> None:
    robot = sub.add_parser("robot", help="check a robot's DEC in MuJoCo (optional extra: "
                                         "pip install posture_id[robots])")
    rsub = robot.add_subparsers(dest="robot_command", required=True, metavar="SUBCOMMAND")
    check = rsub.add_parser(
        "check", help="a humanoid's whole body (or a chain) in MuJoCo against the lumped "
                      "model posture_id simulates: FRFs, variance explained, falls")
    check.add_argument("--body", required=True, metavar="URDF_OR_PRESET",
                       help="a preset (talos, g1, human: its whole body in MuJoCo against "
                            "its lumped chain) or a chain URDF (the chain in MuJoCo against "
                            "the compiled simulator)")
    check.add_argument("--segments", type=int, choices=(1, 2, 3),
                       help="segments a preset is lumped to (default 3; a chain URDF has "
                            "its own)")
    check.add_argument("--params", type=Path,
                       help="DEC parameter JSON of the (lumped) chain (default: its defaults)")
    add_lab_stimulus_arguments(check, "tilt CSV (time_s,tilt_deg) instead of the PRTS")
    add_model_arguments(check)
    check.add_argument("--timestep-ms", type=positive_float, default=None,
                       help="MuJoCo's step, ms (default: 1 for a chain; for a whole body "
                            "the largest of 1, 0.5, 0.25, 0.125 at which its step is "
                            "stable)")
    check.add_argument("--held", choices=[h.value for h in HeldJoints],
                       help="how a preset's joints the lumping treats as rigid are held: "
                            f"stiff PD servos, or welded rigid (default "
                            f"{HeldJoints.SERVOS.value}; a chain has none)")
    check.add_argument("--servo-stiffness", type=positive_float, metavar="FACTOR",
                       help="a held joint's servo stiffness over the m·g·h of the mass it "
                            f"carries (default {WholeBodyOptions().stiffness_factor:g}; with "
                            "--held servos)")
    check.add_argument("--out", type=Path, required=True,
                       help="folder to write check.json and check.png into")
    check.set_defaults(func=run_check)


def _whole_body_flags(args: argparse.Namespace, preset: bool) -> WholeBodyOptions:
    """How a preset's whole body is held, from --held and --servo-stiffness; refused where
    they do nothing (a chain URDF holds no joints; welded joints have no servo), as is
    --segments on a chain (it has its own)."""
    if not preset:
        given = [flag for flag, value in (("--held", args.held),
                                          ("--servo-stiffness", args.servo_stiffness),
                                          ("--segments", args.segments)) if value is not None]
        if given:
            raise PostureIdError(f"{', '.join(given)}: a preset's whole body only; the chain "
                                 f"URDF {args.body} is simulated as it is (its own segments, "
                                 "no joints held)")
        return WholeBodyOptions()
    held = HeldJoints(args.held or HeldJoints.SERVOS.value)
    if held is HeldJoints.RIGID and args.servo_stiffness is not None:
        raise PostureIdError("--servo-stiffness sets the held joints' servos, and --held rigid "
                             "welds them: give one")
    if args.servo_stiffness is None:
        return WholeBodyOptions(held=held)
    return WholeBodyOptions(held=held, stiffness_factor=args.servo_stiffness)


def run_check(args: argparse.Namespace) -> int:
    from posture_id.robots.errors import RobotError, require_mujoco

    require_mujoco()  # before anything else: one line naming the extra
    from posture_id.bodies.body import load_body
    from posture_id.bodies.lumping import PRESETS
    from posture_id.dec.parameters import DecParameters
    from posture_id.robots.check import CheckOptions, robot_check
    from posture_id.robots.mujoco_model import MujocoOptions
    from posture_id.robots.whole_body import WholeBodySpec, lumped_body
    from posture_id.simulation.stimulus import prts

    inputs = tuple(p for p in (args.params, args.tilt, args.protocol) if p is not None)
    if args.body not in PRESETS and not Path(args.body).is_file():
        raise RobotError(f"--body: '{args.body}' is neither a preset ({', '.join(PRESETS)}) "
                         "nor a URDF file")
    whole = _whole_body_flags(args, args.body in PRESETS)
    segments = args.segments or 3
    with OutputFolder(args.out, "--out", CHECK_FILES, inputs=inputs):
        if args.body in PRESETS:
            target = WholeBodySpec.preset(args.body)
            chain = lumped_body(target, segments) if args.params else None
        else:
            target = chain = load_body(Path(args.body))
        params = DecParameters.from_json(args.params, chain) if args.params else None
        stimulus = stimulus_from_args(args, default=prts())
        step = None if args.timestep_ms is None else args.timestep_ms / 1000
        result = robot_check(target, stimulus, params, CheckOptions(segments=segments),
                             simulation_options=model_options(args),
                             mujoco_options=MujocoOptions(timestep_s=step),
                             whole_body_options=whole)
        args.out.mkdir(parents=True, exist_ok=True)
        result.to_json(args.out / "check.json")
        result.plot(args.out / "check.png")
    print(result.summary())
    say(f"wrote {args.out / 'check.json'} and {args.out / 'check.png'}")
    return answered(not result.stays_up)
