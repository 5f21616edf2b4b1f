"""Command line: ``posture-id body | simulate | fit | frf | dataset | train | evaluate |
calibration | identify | demo | benchmark | universal | design | stimulus | compare | norm``,
one module per command.

Every user error is printed as one line ``posture-id: error: ...`` (exit status 2), never
a traceback: argument errors by :class:`~.arguments.Parser`, input errors as
:class:`~posture_id.errors.PostureIdError`. Anything else is a bug: one line saying so
(exit status 3), the traceback with ``posture-id --debug``. Output paths are checked
before any work starts (:func:`~.arguments.check_output_file`).
"""

from __future__ import annotations

import os
import sys

from posture_id.cli import (
    benchmark,
    body,
    calibration,
    compare,
    dataset,
    demo,
    design,
    evaluate,
    fit,
    frf,
    identify,
    norm,
    platform_command,
    simulate,
    train,
    universal,
)
from posture_id.cli.arguments import Parser
from posture_id.cli.exit_status import BUG, EPILOG, INTERRUPTED, REFUSED
from posture_id.errors import PostureIdError

__all__ = ["main", "build_parser"]


def build_parser() -> Parser:
    parser = Parser(prog="posture-id",
                    description="Identify DEC posture-control parameters from body sway.")
    parser.add_argument("--debug", action="store_true",
                        help="show the traceback of an unexpected error (a bug)")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    for command in (body, simulate, fit, frf, dataset, train, evaluate, calibration, identify,
                    demo, benchmark, universal, design, platform_command, compare,
                    norm):
        command.add_parser(sub)
    for command_parser in sub.choices.values():  # one meaning per exit status, said by all
        command_parser.epilog = EPILOG
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run one command; returns the exit status (2 for any user error)."""
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as stop:  # --help (0) or an argument error (2), already printed
        return stop.code if isinstance(stop.code, int) else 0
    try:
        return args.func(args)
    except PostureIdError as exc:
        print(f"posture-id: error: {exc}", file=sys.stderr)
        return REFUSED
    except BrokenPipeError:  # `posture-id body | head`: the reader left, nothing to say
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # no second error when Python flushes stdout
        return 0
    except KeyboardInterrupt:
        print("posture-id: interrupted (finished work is kept; run the same command again "
              "to continue where it resumes)", file=sys.stderr)
        return INTERRUPTED
    except Exception as exc:  # noqa: BLE001 - the one place that turns a bug into one line
        if args.debug:
            raise
        detail = " ".join(str(exc).split())[:300]
        print(f"posture-id: internal error (a bug; please report it): {type(exc).__name__}: "
              f"{detail}. Run again with --debug for the traceback.", file=sys.stderr)
        return BUG
