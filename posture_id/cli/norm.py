"""``posture-id norm build | test | compare``: normative sets of FRFs, one subject or robot
against a norm, and two groups against each other (docs/norms.md)."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.cli.arguments import (
    check_out_and_plot,
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
    add_recording_arguments,
    prepared_trial,
)
from posture_id.errors import PostureIdError
from posture_id.frf.bands import BAND_PRESETS

__all__ = ["add_parser", "norm_bands"]


def _mat_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--variable", help=".mat: the N × F complex matrix")
    p.add_argument("--frequencies", type=positive_float, nargs="+", metavar="F",
                   help=".mat: its frequencies, Hz")


#: The pseudo-impulse responses' rate, Hz, and the bootstrap's resamples, unless given.
DEFAULT_RATE_HZ, DEFAULT_BOOTSTRAP = 22.0, 1000


def _defaults_filled(args: argparse.Namespace) -> None:
    """--rate-hz and --bootstrap as given, else their defaults (None until here, so that
    a flag the command does not use can be told from its default)."""
    if args.rate_hz is None:
        args.rate_hz = DEFAULT_RATE_HZ
    if args.bootstrap is None:
        args.bootstrap = DEFAULT_BOOTSTRAP


def _sources(p: argparse.ArgumentParser) -> None:
    p.add_argument("--channel", nargs="+", help="FRF JSONs: the channels to use (default: "
                                                "all of the first file's)")
    _mat_arguments(p)
    p.add_argument("--rate-hz", type=positive_float,
                   help=f"the pseudo-impulse responses' sampling rate (default "
                        f"{DEFAULT_RATE_HZ:g})")
    p.add_argument("--bootstrap", type=positive_int,
                   help=f"bootstrap resamples (default {DEFAULT_BOOTSTRAP})")
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
    t = n.add_parser("test", help="a recording or FRFs (an FRF JSON, a CSV table or a .mat "
                                  "of several subjects) against a norm")
    t.add_argument("recording", type=Path, metavar="INPUT",
                   help="recording (CSV or C3D: its FRF is computed at the norm's points), "
                        "FRF JSON, CSV table of FRFs (one row per subject) or .mat "
                        "(--variable, --frequencies); a table or .mat tests each subject")
    t.add_argument("--norm", type=Path, required=True, help="norm JSON (built or published)")
    t.add_argument("--out", type=Path, help="result JSON")
    t.add_argument("--plot", type=Path, help="Bode with the norm, PIR in its band (PNG)")
    t.add_argument("--body", type=Path, help="a recording's URDF (adds the body COM channel)")
    t.add_argument("--band-preset", choices=sorted(BAND_PRESETS),
                   help="a recording against a norm that does not say its bands (a published "
                        "one): the named points' bands, reported at the norm's frequencies "
                        "(default: the preset whose points are the norm's frequencies)")
    t.add_argument("--channel", action="append", metavar="NAME",
                   help="the input's channel tested against the norm's (once per norm "
                        "channel, in its order; default: the norm's names, or for a "
                        "one-channel norm the input's only channel besides the body COM)")
    _mat_arguments(t)
    add_recording_arguments(t)
    t.set_defaults(func=run_test)
    c = n.add_parser("compare", help="two groups of FRFs (the difference of their mean PIRs "
                                     "and a permutation test), or of identify results "
                                     "(parameter by parameter); --paired: two conditions "
                                     "of the same subjects")
    c.add_argument("--group", type=Path, nargs="+", action="append", required=True,
                   metavar="FILE", help="one group's files (give --group twice); with "
                                        "--paired the i-th file (or table row) of each "
                                        "group is the same subject's")
    c.add_argument("--names", nargs=2, default=["A", "B"], help="the groups' names")
    c.add_argument("--paired", action="store_true",
                   help="the groups are two conditions of the same subjects, in the same "
                        "order: a sign-flip permutation test of the within-subject "
                        "differences, per frequency and for the whole FRF (or per "
                        "parameter), with t-based intervals of the mean gain ratio and "
                        "phase difference (--bootstrap unused; docs/norms.md)")
    c.add_argument("--permutations", type=positive_int, default=2000,
                   help="permutations (default %(default)d)")
    c.add_argument("--out", type=Path, required=True, help="comparison JSON")
    c.add_argument("--plot", type=Path, help="the difference with its band (PNG); with "
                                             "--paired the gain ratio and phase difference "
                                             "per frequency")
    _sources(c)
    c.set_defaults(func=run_compare)


def run_build(args: argparse.Namespace) -> int:
    _defaults_filled(args)
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
    check_out_and_plot(args, (args.recording, args.norm, args.body, args.tilt))
    from posture_id.norms.norm import Norm, NormTests, against_norm
    from posture_id.norms.readers import frf_from_json, frf_json_channels, read_frfs

    norm = Norm.from_json(args.norm)
    kind = _input_kind(args.recording)
    if kind != "recording" and args.band_preset:
        raise PostureIdError(f"--band-preset goes with a recording (its FRF is computed at "
                             f"those points); {args.recording} holds FRFs already")
    if kind == "json":
        names = _channels(frf_json_channels(args.recording), norm, args.channel,
                          args.recording, recording=False)
        f, h, _, _ = frf_from_json(args.recording, names)
        result = against_norm(norm, f, h, args.recording.name, names)
    elif kind == "recording":
        f, h, names = _recording_frf(args, norm)
        result = against_norm(norm, f, h, args.recording.name, names)
    else:
        frfs, _ = read_frfs([args.recording], None, args.variable, args.frequencies)
        if args.channel:
            raise PostureIdError(f"--channel: {args.recording} holds one FRF per subject, "
                                 "no named channels; leave --channel out")
        if len(norm.channels) != 1:
            raise PostureIdError(f"{args.recording}: one channel per subject; the norm has "
                                 f"{len(norm.channels)} ({', '.join(norm.channels)})")
        if not _at(frfs.frequencies_hz, norm.frequencies_hz, rtol=1e-5):  # against_norm's
            raise PostureIdError(f"{args.recording}: its FRFs are at "
                                 f"{_hz(frfs.frequencies_hz)} Hz, the norm's at "
                                 f"{_hz(norm.frequencies_hz)} Hz: give them at the norm's "
                                 "points")
        result = NormTests(args.recording.name, tuple(
            against_norm(norm, frfs.frequencies_hz, frfs.response[k], frfs.names[k])
            for k in range(len(frfs))))
    write_result(result, args.out, args.plot)
    return answered(result.inside_prediction_band is False)


def _input_kind(path: Path) -> str:
    """What ``norm test`` was given: "json" (an FRF JSON), "table" (a CSV table of FRFs),
    "mat", or "recording" (a CSV or C3D recording)."""
    from posture_id.norms.readers import is_frf_table

    if not path.exists():
        raise PostureIdError(f"{path}: no such file")
    if path.is_dir():
        raise PostureIdError(f"{path}: is a folder; give one recording or file of FRFs")
    suffix = path.suffix.lower()
    if suffix in (".json", ".mat"):
        return suffix[1:]
    return "table" if suffix == ".csv" and is_frf_table(path) else "recording"


def _channels(available: tuple[str, ...], norm, given: list[str] | None, where: Path,
              recording: bool) -> tuple[str, ...]:
    """The input's channels tested against the norm's (:func:`~posture_id.norms.norm.
    tested_channels`); one of another name than the norm's is said on stderr."""
    from posture_id.norms.norm import tested_channels

    hint = ("; --body adds the body COM" if recording and "body COM" not in available
            else "")
    names = tested_channels(norm, available, given, str(where), hint)
    if not given and names != tuple(norm.channels):
        say(f"{where}: its channel {names[0]!r} tested against the norm's "
            f"{norm.channels[0]!r} (--channel names another)")
    return names


def _recording_frf(args: argparse.Namespace, norm) -> tuple:
    """A recording's FRF at the norm's points, by the labs' convention: (frequencies,
    H (F, M), the recording's channels tested)."""
    import numpy as np

    from posture_id.frf.analysis import frequency_response
    from posture_id.frf.response import FrfOptions

    try:
        options = FrfOptions.lab_convention(norm_bands(args, norm))
    except PostureIdError:
        if norm.lab_bands is not None or args.band_preset:
            raise
        options = None  # a norm at the frequencies a stimulus drives (sinusoids): its own
    body = recording_body(args, None)
    trial = prepared_trial(args, body, rate_hz=None, checked=False)
    frf = frequency_response(trial, body, options)
    rows = np.arange(len(frf.frequencies_hz))
    if options is None:
        rows = [int(np.argmin(np.abs(frf.frequencies_hz - x))) for x in norm.frequencies_hz]
        if not _at(frf.frequencies_hz[rows], norm.frequencies_hz, rtol=1e-5):
            norm_bands(args, norm)  # says why: no bands, no preset, not the stimulus's own
    names = _channels(tuple(frf.channels), norm, args.channel, args.recording, recording=True)
    columns = [frf.channels.index(c) for c in names]
    return frf.frequencies_hz[rows], frf.response[np.ix_(rows, columns)], names


def norm_bands(args: argparse.Namespace, norm):
    """The bands a recording's FRF is computed at for ``norm``: a built norm's own
    (``lab_bands``); for one that does not say them, the preset whose points are its
    frequencies, or ``--band-preset``'s bands reported at its frequencies."""
    import dataclasses

    import numpy as np

    from posture_id.frf.bands import FrequencyBands

    f = np.asarray(norm.frequencies_hz, dtype=float)
    chosen = BAND_PRESETS[args.band_preset] if args.band_preset else None
    if norm.lab_bands is not None:
        bands = FrequencyBands.from_dict(norm.lab_bands)
        if chosen is not None and not _same_bands(bands, chosen):
            raise PostureIdError(f"--band-preset {args.band_preset}: {args.norm} was built "
                                 f"at other points ({bands.name}, "
                                 f"{_hz(bands.centres_hz or f)} Hz); leave --band-preset out "
                                 "(the norm's own bands are used)")
        return bands
    if chosen is None:
        chosen = next((p for p in BAND_PRESETS.values() if _at(p.centres_hz, f)), None)
        if chosen is None:
            raise PostureIdError(f"{args.norm}: the norm does not say at which bands its FRFs "
                                 f"were computed and its frequencies ({_hz(f)} Hz) are no "
                                 f"preset's points, nor frequencies the recording's stimulus "
                                 f"drives: give --band-preset "
                                 f"{'|'.join(sorted(BAND_PRESETS))} (its bands, reported at "
                                 "the norm's frequencies), or the recording's FRF JSON")
        return chosen
    if _at(chosen.centres_hz, f):
        return chosen
    if len(chosen) != len(f):
        raise PostureIdError(f"--band-preset {args.band_preset}: {len(chosen)} points, the "
                             f"norm {args.norm} has {len(f)} ({_hz(f)} Hz)")
    for k, (freq, (low, high)) in enumerate(zip(f, chosen._ranges(), strict=True)):
        if not low <= freq <= high:
            raise PostureIdError(f"--band-preset {args.band_preset}: the norm's point {k + 1} "
                                 f"({freq:g} Hz) lies outside its band {k + 1} "
                                 f"({low:g}–{high:g} Hz): {args.norm} was computed at "
                                 "other bands")
    return dataclasses.replace(chosen, centres_hz=tuple(float(x) for x in f),
                               name=f"{chosen.name} at the norm's frequencies")


def _at(centres, frequencies, rtol: float = 0.0) -> bool:
    """Whether ``centres`` (a preset's, or FRFs' frequencies) are ``frequencies`` (within
    1e-6 Hz, and ``rtol``)."""
    import numpy as np

    return (centres is not None and len(centres) == len(frequencies)
            and bool(np.allclose(centres, frequencies, rtol=rtol, atol=1e-6)))


def _same_bands(a, b) -> bool:
    """Whether two band sets take the same harmonics (or ranges) and report them at the
    same frequencies, whatever their names."""
    da, db = a.to_dict(), b.to_dict()
    ca, cb = da.pop("centres_hz"), db.pop("centres_hz")
    da.pop("name")
    db.pop("name")
    return da == db and (ca is None and cb is None or (ca is not None and cb is not None
                                                       and _at(ca, cb)))


def _hz(values) -> str:
    return ", ".join(f"{float(v):g}" for v in values)


def run_compare(args: argparse.Namespace) -> int:
    unused = [flag for flag, value in (("--bootstrap", args.bootstrap),
                                       ("--rate-hz", args.rate_hz)) if value is not None]
    if args.paired and unused:
        raise PostureIdError(f"{', '.join(unused)}: unused by --paired (a sign-flip "
                             "permutation test of the within-subject differences, with "
                             "t-based intervals: give --permutations), leave "
                             f"{'them' if len(unused) > 1 else 'it'} out")
    _defaults_filled(args)
    if args.names[0] == args.names[1]:
        raise PostureIdError(f"--names: the two groups are both called {args.names[0]!r}; "
                             "give each its own name")
    if len(args.group) != 2:
        raise PostureIdError(f"--group: give two groups (got {len(args.group)})")
    first = {p.resolve() for p in args.group[0]}
    shared = [p for p in args.group[1] if p.resolve() in first]
    if shared:
        raise PostureIdError(f"{shared[0]}: in both groups (--group ... --group ...); "
                             + ("with --paired a subject's two conditions are two files"
                                if args.paired else "a member belongs to one group"))
    check_out_and_plot(args, tuple(p for g in args.group for p in g))
    from posture_id.norms.groups import compare_groups
    from posture_id.norms.readers import read_frfs

    if all(_is_identified(p) for g in args.group for p in g):
        return _compare_identified(args)
    channels = tuple(args.channel) if args.channel else None
    a, _ = read_frfs(args.group[0], channels, args.variable, args.frequencies)
    b, _ = read_frfs(args.group[1], channels, args.variable, args.frequencies)
    if args.paired:
        from posture_id.norms.paired import compare_paired

        _same_subjects(len(a), len(b), args.names)
        _no_member_twice(a, b, args.group, paired=True)
        result = compare_paired(a, b, tuple(args.names), args.permutations, args.level,
                                args.seed)
    else:
        _no_member_twice(a, b, args.group)
        result = compare_groups(a, b, tuple(args.names), args.permutations, args.bootstrap,
                                args.level, args.rate_hz, args.seed)
    write_result(result, args.out, args.plot)
    return 0


def _same_subjects(count_a: int, count_b: int, names: list[str]) -> None:
    """--paired: refuse groups of other sizes (each subject is in both, in order)."""
    if count_a != count_b:
        raise PostureIdError(f"--paired: {names[0]} has {count_a} subjects, {names[1]} has "
                             f"{count_b}; the i-th of each group is one subject, in both "
                             "groups")


def _no_member_twice(a, b, groups: list[list[Path]], paired: bool = False) -> None:
    """Refuse a member of the second group whose FRF is one of the first's (a copy under
    another name: the groups would share members, and the test assumes they do not). With
    ``paired``, a subject's two conditions identical (a condition's file copied: its
    difference would be exactly zero, as no two recordings give) is named as such."""
    import numpy as np

    def label(frfs, k: int, files: list[Path]) -> str:
        return str(files[k]) if len(files) == len(frfs) else f"{frfs.names[k]} ({files[0]})"

    if a.response.shape[1:] != b.response.shape[1:]:
        return  # compare_groups says how they differ
    for j, hb in enumerate(b.response):
        for i, ha in enumerate(a.response):
            if not np.array_equal(ha, hb):
                continue
            if paired and i == j:
                raise PostureIdError(
                    f"{label(b, j, groups[1])}: the same FRF as its pair "
                    f"{label(a, i, groups[0])} (a copied file?); a subject's two conditions "
                    "are two recordings")
            raise PostureIdError(
                f"{label(b, j, groups[1])}: the same FRF as {label(a, i, groups[0])} "
                "of the first group (a copy?); "
                + ("a recording belongs to one subject and condition" if paired
                   else "a member belongs to one group"))


def _is_identified(path: Path) -> bool:
    """An identify result (parameters and intervals), not an FRF."""
    from posture_id.fileio import json_object

    if path.suffix.lower() != ".json" or path.name.endswith(".frf.json"):
        return False
    data = json_object(path)
    return "parameters" in data and "intervals" in data


def _compare_identified(args: argparse.Namespace) -> int:
    """Two groups of identify results, parameter by parameter (``--paired``: two conditions
    of the same subjects)."""
    from posture_id.norms.parameters import compare_parameters, read_identified

    a, b = read_identified(args.group[0]), read_identified(args.group[1])
    if args.paired:
        from posture_id.norms.paired import compare_paired_parameters

        _same_subjects(len(a.names), len(b.names), args.names)
        _no_result_twice(a, b, args.group)
        result = compare_paired_parameters(a, b, tuple(args.names), args.permutations,
                                           args.level, args.seed)
    else:
        result = compare_parameters(a, b, tuple(args.names), args.permutations,
                                    args.bootstrap, args.level, args.seed)
    write_result(result, args.out, args.plot)
    return 0


def _no_result_twice(a, b, groups: list[list[Path]]) -> None:
    """--paired on identify results: refuse a result of the second group whose every
    parameter is one of the first's (a copied file; for its own pair the difference would
    be exactly zero)."""
    import numpy as np

    if set(a.values) != set(b.values):
        return  # compare_paired_parameters says how they differ
    keys = list(a.values)
    va = np.stack([a.values[k] for k in keys], axis=1)
    vb = np.stack([b.values[k] for k in keys], axis=1)
    for j, row in enumerate(vb):
        for i in np.flatnonzero(np.all(va == row, axis=1)):
            what = "its pair" if i == j else "the first group's"
            raise PostureIdError(f"{groups[1][j]}: the same identified parameters as {what} "
                                 f"{groups[0][i]} (a copied file?); a subject's two "
                                 "conditions are two recordings")
