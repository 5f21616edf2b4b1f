"""``posture-id benchmark``: the CNN against the optimiser, into a report folder."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.bodies.body import DEFAULT_URDF, load_body
from posture_id.cli.arguments import (
    check_output_folder,
    non_negative_float,
    non_negative_int,
    positive_int,
    say,
)
from posture_id.cli.identify import METHODS
from posture_id.cli.progress import TerminalProgress

__all__ = ["add_parser"]


def add_parser(sub) -> None:
    p = sub.add_parser("benchmark", help="CNN versus least squares versus the hybrid")
    p.add_argument("--body", type=Path, help="URDF (default: the TIP)")
    p.add_argument("--trials", type=positive_int, default=50,
                   help="held-out simulated recordings per noise level (default %(default)d)")
    p.add_argument("--sensor-noise-deg", type=non_negative_float, nargs="+",
                   default=[0.0, 0.01, 0.05],
                   help="sensor-noise levels, degrees (default %(default)s)")
    p.add_argument("--seed", type=non_negative_int, default=0, help="seed (default 0)")
    p.add_argument("--workers", type=positive_int, help="processes (default: all cores)")
    p.add_argument("--methods", nargs="+", choices=METHODS, default=list(METHODS),
                   help="methods compared (default: all: cnn fit hybrid)")
    p.add_argument("--out", type=Path, required=True,
                   help="report folder; an interrupted run goes on from its journal there")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    check_output_folder(args.out, "--out")
    from posture_id.identify import Method
    from posture_id.studies.benchmark import JOURNAL, run_benchmark

    body = load_body(args.body or DEFAULT_URDF)
    journal = args.out / JOURNAL
    with TerminalProgress("identifications", prefix="posture-id benchmark") as progress:
        result = run_benchmark(body, args.trials, tuple(args.sensor_noise_deg), args.seed,
                               args.workers, tuple(Method(m) for m in args.methods),
                               progress=progress, journal=journal)
    paths = result.write(args.out)
    journal.unlink()  # its rows are in the report's JSON now
    print(result.to_markdown())
    say("wrote " + ", ".join(str(p) for p in paths))
    return 0
