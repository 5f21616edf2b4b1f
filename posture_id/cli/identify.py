"""``posture-id identify``: DEC parameters of a recording from the CNN."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.bodies.body import DEFAULT_URDF, load_body
from posture_id.cli.arguments import check_output_file, say
from posture_id.recording import Recording

__all__ = ["add_parser"]


def add_parser(sub) -> None:
    p = sub.add_parser("identify", help="identify DEC parameters of a recording (CNN)")
    p.add_argument("recording", type=Path, help="recording CSV (time_s,tilt_deg,<seg>_deg...)")
    p.add_argument("--body", type=Path, help="URDF (default: the TIP)")
    p.add_argument("--model", type=Path,
                   help="model directory (default: the bundled model for the body)")
    p.add_argument("--out", type=Path, required=True,
                   help="result JSON; its \"parameters\" object is a parameter file")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    check_output_file(args.out, "--out", inputs=(args.recording, args.body, args.model))
    # torch loads here, not when the parser is built: other commands start without it
    from posture_id.learning.identifier import CnnIdentifier

    body = load_body(args.body or DEFAULT_URDF)
    identifier = (CnnIdentifier.load(args.model, body) if args.model
                  else CnnIdentifier.for_body(body))
    recording = Recording.from_csv(args.recording, body.segment_names)
    result = identifier.identify(recording, source=str(args.recording))
    result.to_json(args.out)
    say(f"wrote {args.out}")
    print(result.summary())
    return 0
