"""``posture-id network cnn data generate|info``: training data sets."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.bodies.body import DEFAULT_URDF
from posture_id.cli.arguments import (
    check_output_folder,
    default_of,
    non_negative_float,
    non_negative_int,
    positive_int,
    say,
)
from posture_id.cli.progress import TerminalProgress
from posture_id.cli.simulate import (
    add_model_arguments,
    add_motor_noise_arguments,
    model_options,
)
from posture_id.cli.stimulus import add_stimulus_arguments, prts_arguments
from posture_id.learning.data.store import Dataset
from posture_id.learning.data.trial_config import DatasetConfig
from posture_id.learning.data.trial_generation import generate_dataset

__all__ = ["add_parser"]


def add_parser(sub, name: str = "data") -> None:
    data = sub.add_parser(name, help="training data: generate a data set, describe one")
    dsub = data.add_subparsers(dest="dataset_command", required=True)
    gen = dsub.add_parser("generate", help="simulate random trials into a data-set directory")
    gen.add_argument("--trials", type=positive_int, required=True,
                     help="kept (stable) trials wanted")
    gen.add_argument("--out", type=Path, required=True, help="data-set directory")
    gen.add_argument("--workers", type=positive_int, help="local threads (default: all cores)")
    gen.add_argument("--scheduler", help="Dask distributed scheduler address (tcp://host:port)")
    gen.add_argument("--body", type=Path, help="URDF (default: the TIP)")
    gen.add_argument("--seed", type=non_negative_int, default=default_of(DatasetConfig, "seed"),
                     help="root seed (default %(default)d)")
    gen.add_argument("--shard-size", type=positive_int,
                     default=default_of(DatasetConfig, "shard_size"),
                     help="simulated trials per shard (default %(default)d)")
    gen.add_argument("--sensor-noise-deg", type=non_negative_float,
                     default=default_of(DatasetConfig, "sensor_noise_deg"),
                     help="features from angles plus white noise of an SD drawn from "
                          "[0, this] per trial, degrees (default %(default)g: noise-free)")
    add_motor_noise_arguments(gen, "a level drawn from [0, DEG] per trial")
    add_stimulus_arguments(gen)
    add_model_arguments(gen)
    gen.add_argument("--quiet", action="store_true", help="no progress bar")
    gen.set_defaults(func=run_generate)
    info = dsub.add_parser("info", help="counts, rejection rate, splits, Fig. 2 and images")
    info.add_argument("dir", type=Path)
    info.add_argument("--figures", type=Path, help="where to write the PNGs (default: DIR)")
    info.add_argument("--no-verify", action="store_true", help="skip the shard SHA-256 check")
    info.set_defaults(func=run_info)


def run_generate(args: argparse.Namespace) -> int:
    check_output_folder(args.out, "--out", inputs=(args.body,))
    if args.scheduler:
        from posture_id.executors import check_scheduler_address

        check_scheduler_address(args.scheduler)
    config = DatasetConfig(
        trials=args.trials, body=str(args.body or DEFAULT_URDF), seed=args.seed,
        shard_size=args.shard_size, **prts_arguments(args), simulation=model_options(args),
        sensor_noise_deg=args.sensor_noise_deg, motor_noise_deg=args.motor_noise,
        motor_cutoff_hz=args.motor_cutoff_hz,
    )
    with TerminalProgress("kept trials", quiet=args.quiet) as progress:
        data = generate_dataset(config, args.out, workers=args.workers,
                                scheduler=args.scheduler, progress=progress)
    say(data.summary())
    return 0


def run_info(args: argparse.Namespace) -> int:
    if args.figures is not None:
        check_output_folder(args.figures, "--figures")
    data = Dataset.open(args.dir, verify=not args.no_verify)
    print(data.summary())
    overview, images = data.write_figures(args.figures)
    print(f"wrote {overview} and {images}")
    return 0
