"""Every numeric flag of every command, given 0, −1, nan and a word: either a valid value
or one line and exit status 2 before any work starts; never a traceback."""

from __future__ import annotations

import argparse

import pytest

from posture_id.cli import build_parser, main
from posture_id.cli.arguments import (
    interval_level,
    non_negative_float,
    non_negative_int,
    nonzero_float,
    positive_float,
    positive_int,
)

CHECKED = {positive_int: "≥ 1", positive_float: "> 0", non_negative_int: "≥ 0",
           non_negative_float: "≥ 0", interval_level: "from 0.5 to 0.99",
           nonzero_float: "other than 0"}
#: Values that satisfy what every required option asks for, to reach the flag under test.
REQUIRED = {"--out": "out.json", "--trials": "3", "--shards": "2", "--norm": "norm.json",
            "--group": "a.json", "--body": "talos"}


def _commands(parser: argparse.ArgumentParser, prefix=()):
    """(argv prefix, subparser) of every leaf command."""
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subs:
        yield prefix, parser
        return
    for name, sub in subs[0].choices.items():
        yield from _commands(sub, (*prefix, name))


def _numeric_flags():
    out = []
    for prefix, parser in _commands(build_parser()):
        for action in parser._actions:
            if action.type in (int, float) or action.type in CHECKED:
                out.append((prefix, parser, action))
    return out


FLAGS = _numeric_flags()


def _argv(prefix, parser, action, value: str) -> list[str]:
    argv = list(prefix)
    for other in parser._actions:
        if other.required and other is not action:
            if other.option_strings:
                argv += [other.option_strings[0], REQUIRED[other.option_strings[0]]]
            else:
                argv.append("recording.csv" if other.dest == "recording" else "x")
    values = [value] * (action.nargs if isinstance(action.nargs, int) else 1)
    return [*argv, action.option_strings[0], *values]


def test_the_flags_are_found():
    names = {a.option_strings[0] for _, _, a in FLAGS}
    assert {"--amplitude-deg", "--cycles", "--states", "--sway-limit-deg", "--deadband-rad-s",
            "--starts", "--seed", "--workers", "--shard-size", "--trials", "--height-m",
            "--mass-kg", "--segments", "--level", "--fits"} <= names


@pytest.mark.parametrize(("prefix", "parser", "action"), FLAGS,
                         ids=[f"{' '.join(p)} {a.option_strings[0]}" for p, _, a in FLAGS])
def test_numeric_flag_takes_only_valid_values(prefix, parser, action, capsys):
    # a flag is either checked by a type above or limited to a few choices
    assert action.type in CHECKED or action.choices, action.option_strings
    for value in ("0", "-1", "nan", "word"):
        argv = _argv(prefix, parser, action, value)
        accepted = ((action.type in (non_negative_int, non_negative_float) and value == "0")
                    or (action.type is nonzero_float and value == "-1"))  # a sign is a sense
        if accepted:
            args = build_parser().parse_args(argv)
            value = getattr(args, action.dest)
            assert value in (0, -1) or set(value) == {0}, (argv, value)
            continue
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "error: argument" in err, (argv, err)
        assert action.option_strings[0] in err
