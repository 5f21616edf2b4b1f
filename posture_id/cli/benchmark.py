"""``posture-id network cnn benchmark``: the CNN against the optimiser, into a report folder."""

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
from posture_id.cli.progress import TerminalProgress

__all__ = ["add_parser", "BENCHMARK_METHODS"]

#: studies.benchmark.METHODS, named here without importing torch (a test keeps them equal).
BENCHMARK_METHODS = ("cnn", "paper-cnn", "fit", "hybrid", "auto")


def add_parser(sub, name: str = "benchmark") -> None:
    p = sub.add_parser(name, help="the networks against least squares, the hybrid and "
                                         "auto, on held-out recordings")
    p.add_argument("--body", type=Path, help="URDF (default: the TIP)")
    p.add_argument("--trials", type=positive_int, default=50,
                   help="held-out simulated recordings per noise level (default %(default)d)")
    p.add_argument("--sensor-noise-deg", type=non_negative_float, nargs="+",
                   default=[0.0, 0.01, 0.05],
                   help="sensor-noise levels, degrees (default %(default)s)")
    p.add_argument("--seed", type=non_negative_int, default=0, help="seed (default 0)")
    p.add_argument("--workers", type=positive_int, help="processes (default: all cores)")
    p.add_argument("--methods", nargs="+", choices=BENCHMARK_METHODS,
                   help="methods compared (default: all: the universal network alone, the "
                        "paper's spectrogram CNN (for a body with a shipped specialist), "
                        "least squares from the defaults, the hybrid, auto)")
    p.add_argument("--people-like", action="store_true",
                   help="also the same subjects with motor noise leaving 15–40 %% of their "
                        "body COM sway stimulus-locked (0.05° sensor noise)")
    p.add_argument("--out", type=Path, required=True,
                   help="report folder; an interrupted run goes on from its journal there")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    check_output_folder(args.out, "--out")
    from posture_id.studies.benchmark import JOURNAL, run_benchmark

    body = load_body(args.body or DEFAULT_URDF)
    journal = args.out / JOURNAL
    with TerminalProgress("identifications", prefix="posture-id network cnn benchmark") as progress:
        result = run_benchmark(body, args.trials, tuple(args.sensor_noise_deg), args.seed,
                               args.workers,
                               None if args.methods is None else tuple(args.methods),
                               progress=progress, journal=journal,
                               people_like=args.people_like)
    paths = result.write(args.out)
    journal.unlink()  # its rows are in the report's JSON now
    print(result.to_markdown())
    say("wrote " + ", ".join(str(p) for p in paths))
    return 0
