"""``posture-id design``: predict which protocol identifies which parameter, before
anyone stands on the platform (docs/design.md)."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.cli.arguments import (
    non_negative_float,
    non_negative_int,
    positive_float,
    positive_int,
    say,
    share,
)
from posture_id.cli.output_folder import OutputFolder
from posture_id.cli.progress import TerminalProgress
from posture_id.errors import PostureIdError

__all__ = ["add_parser"]


def add_parser(sub) -> None:
    p = sub.add_parser("design", help="predict, per candidate protocol, how well each "
                       "module's Kp, Ki, Kd, delay and class will be identified; rank them")
    p.add_argument("--body", type=Path, help="URDF (default: the TIP)")
    p.add_argument("--model", choices=("dec", "ic"), default="dec",
                   help="the model to be fitted: dec (default) or ic (the independent-channel "
                        "model: its Kp, Kd, delay and W; docs/ic.md)")
    p.add_argument("--protocol", type=Path, nargs="+", metavar="FILE",
                   help="candidate protocol files (JSON; default: ten built-in candidates, "
                        "today's PRTS first)")
    p.add_argument("--sensor-noise-deg", type=non_negative_float, default=0.05,
                   help="white sensor noise SD, degrees (default %(default)g)")
    motor = p.add_mutually_exclusive_group()
    motor.add_argument("--locked-share", type=share,
                       help="motor noise leaving this share of the body COM sway locked "
                            "(people: 0.15–0.4; default: no motor noise)")
    motor.add_argument("--motor-sd-deg", type=non_negative_float,
                       help="motor noise of this level, degrees (MotorNoise's σ)")
    p.add_argument("--goal", nargs="+", choices=("kp", "ki", "kd", "delay_s"),
                   help="rank by these parameters of every module (default: all four)")
    p.add_argument("--max-minutes", type=positive_float,
                   help="recording time in all, minutes")
    p.add_argument("--max-peak-to-peak-deg", type=positive_float,
                   help="largest peak-to-peak tilt, degrees")
    p.add_argument("--max-velocity-deg-s", type=positive_float,
                   help="largest tilt velocity, degrees per second")
    p.add_argument("--residual", choices=("locked", "raw"), default="locked",
                   help="the fit planned for: locked (default; for people's sway) or raw")
    p.add_argument("--draws", type=positive_int, default=8,
                   help="subjects drawn from the prior (default %(default)d)")
    p.add_argument("--seed", type=non_negative_int, default=0, help="seed (default 0)")
    p.add_argument("--out", type=Path, required=True,
                   help="report folder: design.md, design.json, design.png, protocols/, "
                        "recommended.json")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


#: What ``design`` writes into its --out folder (DesignResult.write).
DESIGN_FILES = ("design.md", "design.json", "design.png", "protocols/*.json",
                "recommended.json")


def run(args: argparse.Namespace) -> int:
    with OutputFolder(args.out, "--out", DESIGN_FILES,
                      inputs=tuple(args.protocol or ()) + (args.body,)):
        return _design(args)


def _design(args: argparse.Namespace) -> int:
    """The candidates' predicted widths (``--model ic``: the IC fit's), ranked, written
    to ``--out``."""
    from posture_id.bodies.body import DEFAULT_URDF, load_body
    from posture_id.design.candidates import default_candidates
    from posture_id.simulation.protocols import read_protocol

    if args.model == "ic":  # DEC's flags refused, and a design without noise
        given = [flag for flag, on in (("--goal", args.goal), ("--max-minutes", args.max_minutes),
                                       ("--max-peak-to-peak-deg", args.max_peak_to_peak_deg),
                                       ("--max-velocity-deg-s", args.max_velocity_deg_s),
                                       ("--motor-sd-deg", args.motor_sd_deg),
                                       ("--residual", args.residual != "locked")) if on]
        if given:
            raise PostureIdError(f"{', '.join(given)}: DEC's design only; --model ic ranks every "
                                 "candidate by Kp, Kd, delay and W (with --sensor-noise-deg and "
                                 "--locked-share)")
        if args.sensor_noise_deg == 0 and args.locked_share is None:
            raise PostureIdError("--sensor-noise-deg 0 and no motor noise (--locked-share): a "
                                 "recording without noise pins every parameter exactly, and no "
                                 "protocol is better than another; give the noise the recordings "
                                 "will have")
    body = load_body(args.body or DEFAULT_URDF)
    protocols = ([read_protocol(f) for f in args.protocol] if args.protocol
                 else default_candidates())
    if args.model == "ic":
        from posture_id.design.ic import design_ic

        with TerminalProgress("subject", prefix="posture-id design",
                              quiet=args.quiet) as progress:
            result = design_ic(body, protocols, args.sensor_noise_deg, args.locked_share,
                               args.draws, args.seed, progress=progress)
    else:
        from posture_id.design.goal import PARAMETERS, DesignGoal
        from posture_id.design.noise import SwayNoise
        from posture_id.design.predict import DesignOptions
        from posture_id.design.report import design

        noise = SwayNoise(args.sensor_noise_deg, args.locked_share, args.motor_sd_deg)
        goal = DesignGoal(tuple(args.goal or PARAMETERS), args.max_minutes,
                          args.max_peak_to_peak_deg, args.max_velocity_deg_s)
        options = DesignOptions(draws=args.draws, seed=args.seed, residual=args.residual)
        with TerminalProgress("recording", prefix="posture-id design",
                              quiet=args.quiet) as progress:
            result = design(body, protocols, noise, goal, options, progress)
    result.write(args.out)
    print(result.markdown())
    say(f"wrote {args.out / 'design.md'}, design.json, design.png and the protocols "
        f"({result.seconds:.0f} s)")
    return 0
