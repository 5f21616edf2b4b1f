"""``posture-id network cnn train``: train a CNN identifier on a data set."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.cli.arguments import (
    check_output_folder,
    default_of,
    non_negative_int,
    positive_float,
    positive_int,
    say,
)
from posture_id.cli.progress import TerminalProgress
from posture_id.learning.config import (
    AdamWOneCycle,
    ClassOutput,
    Layout,
    NetworkConfig,
    SgdMomentum,
    TrainingConfig,
)
from posture_id.learning.data.store import Dataset

__all__ = ["add_parser"]


def add_parser(sub, name: str = "train") -> None:
    p = sub.add_parser(name, help="train a CNN identifier on a data set")
    p.add_argument("dataset", type=Path,
                   help="data-set directory (posture-id network cnn data generate)")
    p.add_argument("--layout", choices=[x.value for x in Layout], default="modular",
                   help="spectrograms, one sample per module (default) or one per trial; "
                        "or FRF features, one per trial (posture_id.frf.features)")
    p.add_argument("--out", type=Path, required=True, help="model directory (resumed if it "
                   "holds a run with the same arguments)")
    p.add_argument("--optimiser", choices=("adamw", "sgd"), default="adamw",
                   help="AdamW with a one-cycle schedule (default) or the paper's SGD with "
                        "momentum")
    p.add_argument("--learning-rate", type=positive_float,
                   help="peak (AdamW) or initial (SGD) learning rate (default: "
                        f"{default_of(AdamWOneCycle, 'max_learning_rate')} / "
                        f"{default_of(SgdMomentum, 'learning_rate')})")
    p.add_argument("--epochs", type=positive_int, default=default_of(TrainingConfig, "epochs"),
                   help="at most this many epochs (default %(default)d)")
    p.add_argument("--batch-size", type=positive_int,
                   default=default_of(TrainingConfig, "batch_size"),
                   help="samples per step (default %(default)d)")
    p.add_argument("--patience", type=positive_int,
                   default=default_of(TrainingConfig, "patience"),
                   help="early stopping: epochs without a better validation loss "
                        "(default %(default)d)")
    p.add_argument("--seed", type=non_negative_int, default=default_of(TrainingConfig, "seed"),
                   help="seed of the initial weights and the sample order (default %(default)d)")
    p.add_argument("--threads", type=positive_int, help="torch threads (default: all cores)")
    p.add_argument("--buffer-shards", type=non_negative_int,
                   default=default_of(TrainingConfig, "buffer_shards"),
                   help="0: hold the training split in memory (default); K: stream K shards "
                        "at a time (larger-than-memory sets)")
    p.add_argument("--class-output", choices=[x.value for x in ClassOutput],
                   default=default_of(NetworkConfig, "class_output").value,
                   help="logit: the class as a logit with cross-entropy (default); "
                        "regression: the paper's, one more MSE target read by its sign")
    p.add_argument("--widths", type=positive_int, nargs="+",
                   default=list(default_of(NetworkConfig, "widths")),
                   help="channels of each convolution block (default %(default)s)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    check_output_folder(args.out, "--out", inputs=(args.dataset,))
    # torch loads here, not when the parser is built: other commands start without it
    from posture_id.learning.training import train

    data = Dataset.open(args.dataset, verify=False)
    layout = Layout(args.layout)
    network = NetworkConfig.for_body(layout, data.n_segments, widths=tuple(args.widths),
                                     class_output=ClassOutput(args.class_output))
    kind, rate = ((SgdMomentum, "learning_rate") if args.optimiser == "sgd"
                  else (AdamWOneCycle, "max_learning_rate"))
    optimiser = kind(**({rate: args.learning_rate} if args.learning_rate else {}))
    training = TrainingConfig(optimiser=optimiser, epochs=args.epochs,
                              batch_size=args.batch_size, patience=args.patience,
                              seed=args.seed, threads=args.threads,
                              buffer_shards=args.buffer_shards)
    with TerminalProgress("epoch", prefix="posture-id network cnn train",
                          quiet=args.quiet) as progress:
        result = train(args.dataset, args.out, network, training, progress)
    result.plot(args.out / "loss.png")
    say(result.summary())
    say(f"wrote {args.out / 'model.safetensors'}, model.json, log.jsonl and loss.png")
    return 0
