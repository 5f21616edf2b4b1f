"""``posture-id network cnn calibrate``: calibrate a model's intervals and check their coverage."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.cli.arguments import (
    non_negative_float,
    non_negative_int,
    positive_int,
    say,
)
from posture_id.cli.output_folder import OutputFolder
from posture_id.cli.progress import TerminalProgress

__all__ = ["add_parser"]


def add_parser(sub, name: str = "calibrate") -> None:
    p = sub.add_parser(
        name,
        help="calibrate a model's intervals and class probabilities; check their coverage",
        description="Calibrates the CNN's intervals (conformal) and class probabilities "
                    "(temperature) on the data set's validation split and checks their "
                    "coverage on the test split; with --fits, least squares too. The "
                    "calibration (calibration.json) and its report go into --out; --install "
                    "also puts the calibration beside the model (docs/uncertainty.md).")
    p.add_argument("model", type=Path, help="model directory")
    p.add_argument("dataset", type=Path, help="the data set the model was trained on")
    p.add_argument("--out", type=Path, required=True,
                   help="report folder (calibration_report.md/.json, PNGs); an interrupted "
                        "least-squares run goes on from its journal there")
    p.add_argument("--sensor-noise-deg", type=non_negative_float, nargs="+",
                   help="sensor-noise levels checked, degrees (default: 0 and the data "
                        "set's training noise)")
    p.add_argument("--calibration-noise-deg", type=non_negative_float, nargs="+",
                   help="sensor-noise levels calibrated at (default: 5 from 0 to the data "
                        "set's training noise)")
    p.add_argument("--fits", type=non_negative_int, default=0,
                   help="test trials per checked level refined by least squares (default 0: "
                        "none; about 5 s each per core)")
    p.add_argument("--workers", type=positive_int, help="processes (default: all cores)")
    p.add_argument("--install", action="store_true",
                   help="also write calibration.json into the model directory, where "
                        "identify reads it")
    p.set_defaults(func=run)


#: What ``calibration`` writes into its --out folder (its journal is its own).
CALIBRATION_FILES = ("calibration.json", "calibration_report.json", "calibration_report.md",
                     "coverage.png", "reliability.png", "identifiability.png")


def run(args: argparse.Namespace) -> int:
    with OutputFolder(args.out, "--out", CALIBRATION_FILES, inputs=(args.model, args.dataset)):
        return _calibration(args)


def _calibration(args: argparse.Namespace) -> int:
    from posture_id.studies.calibration import install_calibration, run_calibration

    with TerminalProgress(prefix="posture-id network cnn calibrate") as progress:
        report = run_calibration(
            args.model, args.dataset, args.out,
            tuple(args.sensor_noise_deg) if args.sensor_noise_deg else None,
            tuple(sorted(args.calibration_noise_deg)) if args.calibration_noise_deg else None,
            args.fits, args.workers, progress)
    print(report.to_markdown())
    say(f"wrote the calibration and its report in {args.out}")
    if args.install:
        say(f"installed {install_calibration(report)}")
    return 0
