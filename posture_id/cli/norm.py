"""``posture-id norm build | test | compare``: normative sets of FRFs, one subject or robot
against a norm, and two groups against each other (docs/norms.md)."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.cli.arguments import (
    check_output_file,
    non_negative_int,
    positive_float,
    positive_int,
    say,
    write_result,
)
from posture_id.cli.exit_status import answered
from posture_id.cli.markers import recording_body
from posture_id.cli.stimulus import (
    add_column_arguments,
    add_lab_stimulus_arguments,
    recording_and_stimulus,
)
from posture_id.errors import PostureIdError

__all__ = ["add_parser"]


def _sources(p: argparse.ArgumentParser) -> None:
    p.add_argument("--channel", nargs="+", help="FRF JSONs: the channels to use (default: "
                                                "all of the first file's)")
    p.add_argument("--variable", help=".mat: the N × F complex matrix")
    p.add_argument("--frequencies", type=positive_float, nargs="+", metavar="F",
                   help=".mat: its frequencies, Hz")
    p.add_argument("--rate-hz", type=positive_float, default=22.0,
                   help="the pseudo-impulse responses' sampling rate (default %(default)g)")
    p.add_argument("--bootstrap", type=positive_int, default=1000,
                   help="bootstrap resamples (default %(default)d)")
    p.add_argument("--level", type=positive_float, default=0.95,
                   help="the bands' level (default %(default)g)")
    p.add_argument("--seed", type=non_negative_int, default=0, help="seed (default 0)")


def add_parser(sub) -> None:
    norm = sub.add_parser("norm", help="normative sets of FRFs: build one, test a subject or "
                                       "robot against it, compare two groups")
    n = norm.add_subparsers(dest="norm_command", required=True)
    b = n.add_parser("build", help="a norm from its members' FRFs (FRF JSONs from posture-id "
                                   "frf --band-preset ..., a CSV table or a .mat)")
    b.add_argument("files", type=Path, nargs="+")
    b.add_argument("--out", type=Path, required=True, help="norm JSON to write")
    b.add_argument("--weights", type=positive_float, nargs="+",
                   help="frequency weights of the human-likeness score (default 1 each)")
    _sources(b)
    b.set_defaults(func=run_build)
    t = n.add_parser("test", help="a recording or an FRF JSON against a norm")
    t.add_argument("recording", type=Path, metavar="INPUT",
                   help="recording (CSV or C3D: its FRF is computed at the norm's points) "
                        "or FRF JSON")
    t.add_argument("--norm", type=Path, required=True, help="norm JSON (built or published)")
    t.add_argument("--out", type=Path, help="result JSON")
    t.add_argument("--plot", type=Path, help="Bode with the norm, PIR in its band (PNG)")
    t.add_argument("--body", type=Path, help="a recording's URDF (adds the body COM channel)")
    add_lab_stimulus_arguments(t, "tilt CSV (time_s,tilt_deg) the recording was made with")
    add_column_arguments(t)
    t.set_defaults(func=run_test)
    c = n.add_parser("compare", help="two groups of FRFs (the difference of their mean PIRs "
                                     "and a permutation test), or of identify results "
                                     "(parameter by parameter)")
    c.add_argument("--group", type=Path, nargs="+", action="append", required=True,
                   metavar="FILE", help="one group's files (give --group twice)")
    c.add_argument("--names", nargs=2, default=["A", "B"], help="the groups' names")
    c.add_argument("--permutations", type=positive_int, default=2000,
                   help="permutations (default %(default)d)")
    c.add_argument("--out", type=Path, required=True, help="comparison JSON")
    c.add_argument("--plot", type=Path, help="the difference with its band (PNG)")
    _sources(c)
    c.set_defaults(func=run_compare)


def run_build(args: argparse.Namespace) -> int:
    check_output_file(args.out, "--out", tuple(args.files))
    from posture_id.norms.norm import build_norm
    from posture_id.norms.readers import read_frfs

    frfs, bands = read_frfs(args.files, tuple(args.channel) if args.channel else None,
                            args.variable, args.frequencies)
    if args.weights is not None and len(args.weights) != len(frfs.frequencies_hz):
        raise PostureIdError(f"--weights: {len(args.weights)} given for "
                             f"{len(frfs.frequencies_hz)} frequencies")
    norm = build_norm(frfs, args.bootstrap, args.level, args.rate_hz, args.weights,
                      args.seed, bands)
    norm.to_json(args.out)
    say(f"wrote {args.out}: {len(frfs)} members, {len(frfs.frequencies_hz)} points, "
        f"channels {', '.join(frfs.channels)}; {100 * args.level:.0f} % prediction band "
        f"±{norm.prediction_constant:.2f} SD")
    return 0


def run_test(args: argparse.Namespace) -> int:
    inputs = (args.recording, args.norm, args.body, args.tilt)
    check_output_file(args.out, "--out", inputs)
    check_output_file(args.plot, "--plot", inputs, outputs=(args.out,))
    from posture_id.norms.norm import Norm, against_norm
    from posture_id.norms.readers import frf_from_json

    norm = Norm.from_json(args.norm)
    if args.recording.suffix.lower() == ".json":
        f, h, _, _ = frf_from_json(args.recording, norm.channels)
    else:
        f, h = _recording_frf(args, norm)
    result = against_norm(norm, f, h, args.recording.name)
    write_result(result, args.out, args.plot)
    return answered(result.inside_prediction_band is False)


def _recording_frf(args: argparse.Namespace, norm) -> tuple:
    """A recording's FRF at the norm's points, by the labs' convention."""
    from posture_id.frf.analysis import frequency_response
    from posture_id.frf.bands import FrequencyBands
    from posture_id.frf.response import FrfOptions
    from posture_id.trials import prepare_trial

    if norm.lab_bands is None:
        raise PostureIdError(f"{args.norm}: the norm does not say at which bands its FRFs "
                             "were computed; give the recording's FRF JSON (posture-id frf)")
    body = recording_body(args, None)
    recording, stimulus = recording_and_stimulus(args, body)
    options = FrfOptions.lab_convention(FrequencyBands.from_dict(norm.lab_bands))
    frf = frequency_response(prepare_trial(recording, stimulus, rate_hz=None), body, options)
    missing = [c for c in norm.channels if c not in frf.channels]
    if missing:
        raise PostureIdError(f"{args.recording}: no channel {', '.join(missing)} for the norm "
                             f"(the recording gives {', '.join(frf.channels)}; --body adds "
                             "the body COM)")
    columns = [frf.channels.index(c) for c in norm.channels]
    return frf.frequencies_hz, frf.response[:, columns]


def run_compare(args: argparse.Namespace) -> int:
    if len(args.group) != 2:
        raise PostureIdError(f"--group: give two groups (got {len(args.group)})")
    first = {p.resolve() for p in args.group[0]}
    shared = [p for p in args.group[1] if p.resolve() in first]
    if shared:
        raise PostureIdError(f"{shared[0]}: in both groups (--group ... --group ...); a "
                             "member belongs to one group")
    inputs = tuple(p for g in args.group for p in g)
    check_output_file(args.out, "--out", inputs)
    check_output_file(args.plot, "--plot", inputs, outputs=(args.out,))
    from posture_id.norms.groups import compare_groups
    from posture_id.norms.readers import read_frfs

    if all(_is_identified(p) for g in args.group for p in g):
        return _compare_identified(args)
    channels = tuple(args.channel) if args.channel else None
    a, _ = read_frfs(args.group[0], channels, args.variable, args.frequencies)
    b, _ = read_frfs(args.group[1], channels, args.variable, args.frequencies)
    _no_member_twice(a, b, args.group)
    result = compare_groups(a, b, tuple(args.names), args.permutations, args.bootstrap,
                            args.level, args.rate_hz, args.seed)
    write_result(result, args.out, args.plot)
    return 0


def _no_member_twice(a, b, groups: list[list[Path]]) -> None:
    """Refuse a member of the second group whose FRF is one of the first's (a copy under
    another name: the groups would share members, and the test assumes they do not)."""
    import numpy as np

    def label(frfs, k: int, files: list[Path]) -> str:
        return str(files[k]) if len(files) == len(frfs) else f"{frfs.names[k]} ({files[0]})"

    if a.response.shape[1:] != b.response.shape[1:]:
        return  # compare_groups says how they differ
    for j, hb in enumerate(b.response):
        for i, ha in enumerate(a.response):
            if np.array_equal(ha, hb):
                raise PostureIdError(
                    f"{label(b, j, groups[1])}: the same FRF as {label(a, i, groups[0])} "
                    "of the first group (a copy?); a member belongs to one group")


def _is_identified(path: Path) -> bool:
    """An identify result (parameters and intervals), not an FRF."""
    import json

    if path.suffix.lower() != ".json" or path.name.endswith(".frf.json"):
        return False
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return isinstance(data, dict) and "parameters" in data and "intervals" in data


def _compare_identified(args: argparse.Namespace) -> int:
    """Two groups of identify results, parameter by parameter."""
    from posture_id.norms.parameters import compare_parameters, read_identified

    result = compare_parameters(read_identified(args.group[0]), read_identified(args.group[1]),
                                tuple(args.names), args.permutations, args.bootstrap,
                                args.level, args.seed)
    write_result(result, args.out, args.plot)
    return 0
