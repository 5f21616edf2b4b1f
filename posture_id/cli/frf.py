"""``posture-id frf``: frequency-response functions of a recording relative to its tilt."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.cli.arguments import (
    check_out_and_plot,
    default_of,
    non_negative_int,
    positive_float,
    say,
    write_result,
)
from posture_id.cli.markers import recording_body
from posture_id.cli.plate_mass import add_load_arguments
from posture_id.cli.stimulus import (
    add_recording_arguments,
    prepared_trial,
)
from posture_id.errors import PostureIdError
from posture_id.frf import FrfOptions, frequency_response
from posture_id.frf.bands import BAND_PRESETS, parse_bands

__all__ = ["add_parser", "run"]


def add_parser(sub) -> None:
    p = sub.add_parser("frf", help="frequency-response functions (gain, phase, coherence) "
                                   "of the sway relative to the tilt")
    p.add_argument("recording", type=Path, help="recording CSV (time_s,tilt_deg,<seg>_deg...)")
    p.add_argument("--body", type=Path,
                   help="URDF whose segments the recording's columns must be; adds the body "
                        "COM (default: none, every angle column as it is, e.g. a COM-only "
                        "recording)")
    p.add_argument("--height-m", type=positive_float,
                   help="a force plate's trial: the subject's height, m; the body is Winter's "
                        "one segment of that height and the mass the plate weighs "
                        "(--load-columns), in place of --body")
    p.add_argument("--out", type=Path, required=True, help="FRF JSON to write")
    p.add_argument("--plot", type=Path, help="gain, phase and coherence against frequency (PNG)")
    p.add_argument("--period-s", type=positive_float,
                   help="one cycle of a periodic tilt that is not a PRTS, s (default: from the "
                        "named or recognised PRTS)")
    p.add_argument("--skip-cycles", type=non_negative_int,
                   default=default_of(FrfOptions, "skip_cycles"),
                   help="whole cycles left out at the start (default %(default)d)")
    p.add_argument("--drift-order", type=non_negative_int,
                   default=default_of(FrfOptions, "drift_order"),
                   help="order of the polynomial drift removed (default %(default)d)")
    p.add_argument("--bands", type=non_negative_int, default=default_of(FrfOptions, "bands"),
                   help="average the excited frequencies into this many log-spaced bands "
                        "(default %(default)d: none)")
    p.add_argument("--max-frequency-hz", type=positive_float,
                   default=default_of(FrfOptions, "max_frequency_hz"),
                   help="highest frequency kept (default %(default)g Hz)")
    lab = p.add_argument_group("a lab's FRF points", "the spectra averaged over bands of "
                               "stimulated harmonics, reported at fixed frequencies (docs/frf.md)")
    lab.add_argument("--band-preset", choices=sorted(BAND_PRESETS),
                     help="named points: peterka11, Peterka 2002's 11 points 0.05–2.2 Hz")
    lab.add_argument("--band-harmonics", metavar="BANDS",
                     help="bands as ordinals of the stimulated harmonics, e.g. "
                          "\"1;2;3-4;4-5\" (overlap allowed)")
    lab.add_argument("--band-ranges-hz", metavar="BANDS",
                     help="bands as frequency ranges, e.g. \"0.2-0.4;0.4-0.8\"")
    lab.add_argument("--lab-convention", action="store_true",
                     help="the labs' convention: the first cycle left out, no drift removed "
                          "(with a lab's bands; --skip-cycles and --drift-order then apply "
                          "only when given)")
    add_recording_arguments(p, "tilt CSV (time_s,tilt_deg) the recording was made with; "
                               "give --period-s with it")
    add_load_arguments(p, "with --height-m and --cop-column: the mass of the subject's body "
                          "from the trial's own load (docs/force_plates.md)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    check_out_and_plot(args, (args.recording, args.body, args.tilt))
    if (args.height_m is not None or args.load_columns) and not args.cop_column:
        raise PostureIdError("--height-m and --load-columns weigh the subject on a force "
                             "plate: they go with --cop-column")
    if args.load_columns and args.height_m is None:
        raise PostureIdError("--load-columns weighs the subject for the body --height-m makes: "
                             "give the height too (or --body URDF, without them)")
    body = recording_body(args, None)
    trial = prepared_trial(args, body, rate_hz=None, checked=False)
    options = _options(args)
    result = frequency_response(trial, body, options, args.period_s)
    for notice in trial.notices:  # what was found on the way in (a refusal says its own)
        say(notice)
    write_result(result, args.out, args.plot)
    return 0


def _options(args: argparse.Namespace) -> FrfOptions:
    """FrfOptions from the flags: log-spaced bands, or a lab's points (one way only)."""
    given = [flag for flag, value in (("--band-preset", args.band_preset),
                                      ("--band-harmonics", args.band_harmonics),
                                      ("--band-ranges-hz", args.band_ranges_hz)) if value]
    if len(given) > 1 or (given and args.bands):
        raise PostureIdError(f"{', '.join(given + (['--bands'] if args.bands else []))}: "
                             "one way of averaging into bands at a time")
    if args.lab_convention and not given:
        raise PostureIdError("--lab-convention goes with a lab's bands (--band-preset, "
                             "--band-harmonics or --band-ranges-hz)")
    if not given:
        return FrfOptions(skip_cycles=args.skip_cycles, drift_order=args.drift_order,
                          bands=args.bands, max_frequency_hz=args.max_frequency_hz)
    if args.band_preset:
        bands = BAND_PRESETS[args.band_preset]
    elif args.band_harmonics:
        bands = parse_bands(args.band_harmonics, "harmonics")
    else:
        bands = parse_bands(args.band_ranges_hz, "ranges")
    skip, drift = args.skip_cycles, args.drift_order
    if args.lab_convention:
        skip = skip if skip != default_of(FrfOptions, "skip_cycles") else 1
        drift = drift if drift != default_of(FrfOptions, "drift_order") else 0
    return FrfOptions(skip_cycles=skip, drift_order=drift, lab_bands=bands,
                      max_frequency_hz=args.max_frequency_hz)
