"""``posture-id frf``: frequency-response functions of a recording relative to its tilt."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.bodies.body import load_body
from posture_id.cli.arguments import (
    check_output_file,
    default_of,
    non_negative_int,
    positive_float,
    write_result,
)
from posture_id.cli.stimulus import (
    add_column_arguments,
    add_lab_stimulus_arguments,
    recording_and_stimulus,
)
from posture_id.frf import FrfOptions, frequency_response
from posture_id.trials import prepare_trial

__all__ = ["add_parser", "run"]


def add_parser(sub) -> None:
    p = sub.add_parser("frf", help="frequency-response functions (gain, phase, coherence) "
                                   "of the sway relative to the tilt")
    p.add_argument("recording", type=Path, help="recording CSV (time_s,tilt_deg,<seg>_deg...)")
    p.add_argument("--body", type=Path,
                   help="URDF whose segments the recording's columns must be; adds the body "
                        "COM (default: none, every angle column as it is, e.g. a COM-only "
                        "recording)")
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
    add_lab_stimulus_arguments(p, "tilt CSV (time_s,tilt_deg) the recording was made with; "
                                  "give --period-s with it")
    add_column_arguments(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    inputs = (args.recording, args.body, args.tilt)
    check_output_file(args.out, "--out", inputs)
    check_output_file(args.plot, "--plot", inputs, outputs=(args.out,))
    body = load_body(args.body) if args.body else None
    recording, stimulus = recording_and_stimulus(args, body)
    options = FrfOptions(skip_cycles=args.skip_cycles, drift_order=args.drift_order,
                         bands=args.bands, max_frequency_hz=args.max_frequency_hz)
    result = frequency_response(prepare_trial(recording, stimulus, rate_hz=None), body,
                                options, args.period_s)
    write_result(result, args.out, args.plot)
    return 0
