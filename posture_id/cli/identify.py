"""``posture-id identify``: DEC parameters of a recording (CNN, least squares or both)."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from posture_id.bodies.body import DEFAULT_URDF, load_body
from posture_id.cli.arguments import check_output_file, say
from posture_id.cli.progress import TerminalProgress
from posture_id.recording import Recording

__all__ = ["add_parser"]

METHODS = ("cnn", "fit", "hybrid")


def add_parser(sub) -> None:
    p = sub.add_parser("identify", help="identify DEC parameters of a recording")
    p.add_argument("recording", type=Path, help="recording CSV (time_s,tilt_deg,<seg>_deg...)")
    p.add_argument("--body", type=Path, help="URDF (default: the TIP)")
    p.add_argument("--model", type=Path,
                   help="model directory (default: the bundled model for the body)")
    p.add_argument("--method", choices=METHODS, default="cnn",
                   help="cnn: the network alone, milliseconds (default); fit: least squares "
                        "from the defaults; hybrid: least squares from the CNN's answer")
    p.add_argument("--out", type=Path, required=True,
                   help="result JSON; its \"parameters\" object is a parameter file")
    p.add_argument("--plot", type=Path, help="recorded versus re-simulated sway (PNG)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    inputs = (args.recording, args.body, args.model)
    check_output_file(args.out, "--out", inputs)
    check_output_file(args.plot, "--plot", inputs, outputs=(args.out,))
    # torch and CasADi load here, not when the parser is built: other commands start fast
    from posture_id.identify import Method, identify
    from posture_id.learning.identifier import CnnIdentifier

    body = load_body(args.body or DEFAULT_URDF)
    method = Method(args.method)
    model = None
    if method is not Method.FIT:
        model = (CnnIdentifier.load(args.model, body) if args.model
                 else CnnIdentifier.for_body(body))
    recording = Recording.from_csv(args.recording, body.segment_names)
    with TerminalProgress(prefix="posture-id identify", quiet=True) as progress:
        result = identify(recording, body, method, model, progress=progress,
                          source=str(args.recording))
    result.to_json(args.out)
    say(f"wrote {args.out}")
    if args.plot:
        result.plot(args.plot)
        say(f"wrote {args.plot}")
    print(result.summary())
    return 0 if np.isfinite(result.e_rel) else 1
