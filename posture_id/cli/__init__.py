"""Command line: ``posture-id identify | fit | compare | frf | norm | study | body |
simulate | stimulus | design | robot | network | demo``, one module per command (the
``network`` family's jobs in the modules :mod:`.network` names).

Every user error is printed as one line ``posture-id: error: ...`` (exit status 2), never
a traceback: argument errors by :class:`~.arguments.Parser`, input errors as
:class:`~posture_id.errors.PostureIdError`. Anything else is a bug: one line saying so
(exit status 3), the traceback with ``posture-id --debug``. Output paths are checked
before any work starts (:func:`~.arguments.check_output_file`).
"""

from __future__ import annotations

import argparse
import os
import sys

from posture_id.cli import (
    body,
    compare,
    demo,
    design,
    fit,
    frf,
    identify,
    network,
    norm,
    platform_command,
    robot,
    simulate,
    study,
)
from posture_id.cli.arguments import Parser
from posture_id.cli.exit_status import BUG, EPILOG, INTERRUPTED, REFUSED
from posture_id.cli.renamed import normalised
from posture_id.errors import PostureIdError, bug_line

__all__ = ["main", "build_parser", "COMMAND_GROUPS"]


#: The commands by task, as the top-level help lists them.
COMMAND_GROUPS = (
    ("identify and analyse a recording",
     ("identify", "fit", "compare", "frf", "norm", "study")),
    ("build bodies, stimuli and studies",
     ("body", "simulate", "stimulus", "design", "robot")),
    ("train and evaluate networks", ("network",)),
    ("try it", ("demo",)),
)
EXAMPLES = """examples:
  posture-id demo --out demo                      the bundled example, end to end
  posture-id identify trial.csv --out result.json --plot result.png
  posture-id identify trial.c3d --segment-markers leg=LANK+RANK,LHIP+RHIP \\
      trunk=LHIP+RHIP,LSHO+RSHO --tilt-channel platform_angle --forward-axis -y
  posture-id identify recordings/ --out results/  a cohort: one JSON each, summary.csv
  posture-id compare trial.csv --out compare.json DEC against the IC model
  posture-id body --from-robot talos --out talos.urdf   a humanoid lumped to a chain

`posture-id COMMAND --help` for a command's flags."""


def build_parser() -> Parser:
    parser = Parser(prog="posture-id", formatter_class=argparse.RawDescriptionHelpFormatter,
                    usage="posture-id [--debug] COMMAND ...",
                    description="Identify how a body keeps its balance: the parameters of its "
                                "posture controller\n(DEC, or the independent-channel model) "
                                "from its sway on a tilting platform.",
                    epilog=EXAMPLES)
    parser.add_argument("--debug", action="store_true",
                        help="show the traceback of an unexpected error (a bug)")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser,
                                metavar="COMMAND", title="commands", prog="posture-id")
    for command in (identify, fit, compare, frf, norm, study, body, simulate, platform_command,
                    design, robot, network, demo):
        command.add_parser(sub)
    for command_parser in sub.choices.values():  # one meaning per exit status, said by all
        command_parser.epilog = EPILOG
    helps = {a.dest: a.help for a in sub._choices_actions}  # each in COMMAND_GROUPS (tested)
    sub.help = argparse.SUPPRESS  # the grouped list below replaces argparse's own
    parser.description += "\n" + "".join(
        f"\n{title}:\n" + "".join(f"  {name:<12} {helps[name]}\n" for name in names)
        for title, names in COMMAND_GROUPS)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run one command; returns the exit status (2 for any user error)."""
    try:
        args = build_parser().parse_args(normalised(sys.argv[1:] if argv is None
                                                    else list(argv)))
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
        print(f"posture-id: {bug_line(exc)}. Run again with --debug for the traceback.",
              file=sys.stderr)
        return BUG
