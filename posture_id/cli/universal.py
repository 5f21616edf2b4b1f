"""``posture-id network universal data | train | check | ensemble | typicality | table``: the
universal identifier's training set, training, calibration and check, ensembles of models
trained apart, its typicality reference, and its table over body families and stimuli
(docs/universal.md)."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from posture_id.cli.arguments import (
    check_output_folder,
    non_negative_float,
    non_negative_int,
    positive_float,
    positive_int,
    say,
)
from posture_id.cli.output_folder import OutputFolder
from posture_id.cli.progress import TerminalProgress
from posture_id.errors import PostureIdError
from posture_id.simulation.noise_families import NoiseFamily

__all__ = ["add_parser"]


def add_parser(sub, name: str = "universal") -> None:
    p = sub.add_parser(name, help="the universal identifier: its training set, training, "
                       "calibration and tables")
    u = p.add_subparsers(dest="universal_command", required=True, parser_class=type(p))
    d = u.add_parser("data", help="simulate the training set (resumable)")
    d.add_argument("--out", type=Path, required=True, help="set directory")
    d.add_argument("--shards", type=positive_int, required=True,
                   help="shards: each one drawn body and PRTS")
    d.add_argument("--trials", type=positive_int,
                   help="parameter sets per shard (default: UniversalDataConfig's, 64)")
    d.add_argument("--seed", type=non_negative_int, default=0, help="root seed (default 0)")
    d.add_argument("--clean-share", type=non_negative_float,
                   help="share of trials without motor noise (default: the scope's, 0.25)")
    d.add_argument("--locked-share", type=positive_float, nargs=2, metavar=("LOW", "HIGH"),
                   help="range of the locked share of the other trials' body COM sway "
                        "(default: the scope's, 0.1 1)")
    d.add_argument("--proportion-jitter", type=non_negative_float,
                   help="each Winter segment's mass and length scaled by a factor within "
                        "± this (default: the scope's, 0.15)")
    d.add_argument("--tip-share", type=non_negative_float,
                   help="share of shards on the default TIP (default: the scope's, 0.1)")
    d.add_argument("--preset-share", type=non_negative_float,
                   help="share of shards on lumped humanoids (default: the scope's, 0.15)")
    d.add_argument("--preset-jitter", type=non_negative_float,
                   help="each lumped humanoid segment's mass and length scaled by a factor "
                        "within ± this (default: the scope's, 0: the robots as lumped)")
    d.add_argument("--amplitude-deg", type=positive_float, nargs=2, metavar=("LOW", "HIGH"),
                   help="range of the PRTS's peak-to-peak tilt, degrees, drawn log-uniform "
                        "(default: the scope's, 0.5 4); a set trained beside the default "
                        "one may draw over any range that overlaps it")
    d.add_argument("--noise-families", nargs="+", metavar="FAMILY",
                   choices=[f.value for f in NoiseFamily],
                   help="each trial with motor noise draws its torque noise's shape from "
                        "one of these families (posture_id.simulation.noise_families; "
                        "default: the low-pass of 0.2 Hz for all)")
    d.add_argument("--workers", type=positive_int, help="processes (default: all cores)")
    d.add_argument("--quiet", action="store_true", help="no progress bar")
    d.set_defaults(func=run_data)

    t = u.add_parser("train", help="train the universal network on a set (resumable)")
    t.add_argument("data", type=Path, nargs="+",
                   help="set directories (posture-id network universal data), trained on together")
    t.add_argument("--out", type=Path, required=True, help="model directory")
    t.add_argument("--epochs", type=positive_int,
                   help="at most this many epochs (default: UniversalTrainingConfig's, 60)")
    t.add_argument("--learning-rate", type=positive_float,
                   help="peak learning rate (default: UniversalTrainingConfig's, 2e-3)")
    t.add_argument("--dropout", type=non_negative_float,
                   help="dropout after each hidden layer (default: UniversalNetworkConfig's)")
    t.add_argument("--weight-decay", type=non_negative_float,
                   help="AdamW's weight decay (default: UniversalTrainingConfig's)")
    t.add_argument("--hidden", type=positive_int, nargs="+", metavar="WIDTH",
                   help="hidden widths of each perceptron (default: UniversalNetworkConfig's, "
                        "512 512 256)")
    t.add_argument("--members", type=positive_int, default=1,
                   help="perceptrons trained together as an ensemble (default 1)")
    t.add_argument("--point-loss", choices=("squared", "absolute"),
                   help="the estimates' loss: squared error (the posterior mean; default) or "
                        "absolute error (the posterior median)")
    t.add_argument("--fresh-motor-noise", action="store_true",
                   help="turn each training trial's motor noise to a new draw every epoch "
                        "(each harmonic's noise by a random phase), as the bundled model "
                        "was trained (`make universal-model`); off by default")
    t.add_argument("--motor-noise-tilt", type=non_negative_float, default=0.0, metavar="SLOPE",
                   help="every epoch, tilt each training trial's motor-noise spectrum by a PSD "
                        "slope drawn in ±SLOPE (torque noise of shapes no simulation made; "
                        "default 0: as simulated)")
    t.add_argument("--init", type=Path, metavar="MODEL_DIR",
                   help="start from this universal model (its weights and standardisation: "
                        "fine-tuning; its network settings are kept)")
    t.add_argument("--exclude-families", nargs="+", metavar="FAMILY", default=(),
                   choices=[f.value for f in NoiseFamily],
                   help="leave the trials of these noise families out (to report on them "
                        "as noise the network never saw)")
    t.add_argument("--keep-clean", type=non_negative_float, default=0.0, metavar="WEIGHT",
                   help="with --init: keep the outputs on clean trials (no motor noise) those "
                        "of the model started from, with this weight against the truth's "
                        "loss (learning other noise without unlearning clean sway; default 0)")
    t.add_argument("--seed", type=non_negative_int, default=0, help="seed (default 0)")
    t.add_argument("--threads", type=positive_int, help="torch threads (default: all cores)")
    t.add_argument("--quiet", action="store_true", help="no progress bar")
    t.set_defaults(func=run_train)

    c = u.add_parser("calibrate", help="calibrate a model on its set's calibration split (the "
                     "recording-difficulty trend on its validation split) and check it on "
                     "the test split")
    c.add_argument("model", type=Path, help="model directory")
    c.add_argument("data", type=Path, nargs="+", help="the sets it was trained on")
    c.set_defaults(func=run_check)

    e = u.add_parser("ensemble", help="one model of several trained apart (their members "
                     "averaged); calibrate it with check, give it a typicality reference")
    e.add_argument("models", type=Path, nargs="+", help="model directories (two or more; "
                   "the last one's scope and sets are the ensemble's: list the widest last)")
    e.add_argument("--out", type=Path, required=True, help="model directory to write")
    e.add_argument("--by-noise", action="store_true",
                   help="gate the models by the recording's noise instead of averaging "
                   "them: the first answers white noise (a sensor's) or nearly none, the "
                   "others noise shaped by the body (motor noise, drift), mixed between "
                   "(docs/universal.md, 'One model, two networks, chosen by the noise')")
    e.set_defaults(func=run_ensemble)

    y = u.add_parser("typicality", help="the typicality reference of a model (its inputs "
                     "on the calibration and validation splits of the sets it was trained "
                     "on), written beside it; its false alarms on the test split")
    y.add_argument("model", type=Path, help="model directory")
    y.add_argument("data", type=Path, nargs="+", help="the sets it was trained on (or sets "
                   "drawn from the same distribution)")
    y.set_defaults(func=run_typicality)

    b = u.add_parser("table", help="the table over body families, stimuli and sway")
    b.add_argument("model", type=Path, nargs="?", help="model directory (default: bundled)")
    b.add_argument("--out", type=Path, required=True, help="report folder")
    b.add_argument("--trials", type=positive_int, default=64,
                   help="trials per cell (default %(default)d)")
    b.add_argument("--workers", type=positive_int, help="processes (default: all cores)")
    b.add_argument("--cache", type=Path, help="folder that keeps the simulated cells: a run "
                   "again with the same trials reads them (resumes; scores another model on "
                   "the same trials; a folder of cells made with other trials, seed or bodies "
                   "per cell is refused, not overwritten); delete it after changing the "
                   "simulator")
    b.add_argument("--seed", type=non_negative_int, help="draw the trials from this seed "
                   "(default: the documented table's): the same table on other trials")
    b.add_argument("--bodies-per-cell", type=positive_int,
                   help="Winter bodies a cell's trials are spread over (default: the "
                   "documented table's, 64)")
    b.add_argument("--quiet", action="store_true", help="no progress bar")
    b.set_defaults(func=run_table)


def _given(args: argparse.Namespace, *names: str, **values) -> dict:
    """The options given (not None): ``args``' attributes ``names``, then ``values``; the
    defaults of what they configure stand for the rest."""
    return {k: v for k, v in ({n: getattr(args, n) for n in names} | values).items()
            if v is not None}


def run_data(args: argparse.Namespace) -> int:
    check_output_folder(args.out, "--out")
    from posture_id.learning.data.drawn import UniversalDataConfig, generate_universal
    from posture_id.learning.data.scope import ScopeError, UniversalScope

    given = {"trials": args.trials} if args.trials else {}
    scope = _given(args, "clean_share", "locked_share", "proportion_jitter", "tip_share",
                   "preset_share", "preset_jitter", "amplitude_deg", "noise_families")
    try:
        given["scope"] = UniversalScope(**{k: tuple(v) if isinstance(v, list) else v
                                           for k, v in scope.items()})
    except ScopeError as exc:  # named by the flags the user gave, not the scope's fields
        text = str(exc).removeprefix("scope ")
        raise PostureIdError(re.sub(r"\b(" + "|".join(scope) + r")\b",
                                    lambda m: "--" + m.group(1).replace("_", "-"),
                                    text)) from None
    config = UniversalDataConfig(shards=args.shards, seed=args.seed, **given)
    with TerminalProgress("shard", prefix="posture-id network universal data",
                          quiet=args.quiet) as progress:
        data = generate_universal(config, args.out, args.workers, progress)
    counts = data.manifest["counts"]
    say(f"wrote {args.out}: {counts['shards']} shards, {counts['kept']} of "
        f"{counts['simulated']} trials kept")
    return 0


def run_train(args: argparse.Namespace) -> int:
    check_output_folder(args.out, "--out", inputs=tuple(args.data))
    from posture_id.learning.universal_network import UniversalNetworkConfig
    from posture_id.learning.universal_training import UniversalTrainingConfig, train_universal

    if args.init is not None and (args.hidden or args.dropout is not None or args.members != 1):
        raise PostureIdError("--init keeps its model's network: --hidden, --dropout and "
                             "--members go with a network trained from the start")
    if args.keep_clean and args.init is None:
        raise PostureIdError("--keep-clean keeps the outputs of the model fine-tuned from: "
                             "give it with --init MODEL_DIR")
    if args.init is not None and not (args.init / "model.json").is_file():
        raise PostureIdError(f"{args.init}: --init is not a universal model (no model.json)")
    given = _given(args, "epochs", "weight_decay", "point_loss",
                   max_learning_rate=args.learning_rate,
                   init=None if args.init is None else str(args.init))
    config = UniversalTrainingConfig(seed=args.seed, threads=args.threads,
                                     fresh_motor_noise=args.fresh_motor_noise,
                                     motor_noise_tilt=args.motor_noise_tilt,
                                     exclude_families=tuple(args.exclude_families),
                                     keep_clean=args.keep_clean, **given)
    shape = _given(args, "dropout", hidden=tuple(args.hidden) if args.hidden else None)
    network = UniversalNetworkConfig(members=args.members, **shape)
    with TerminalProgress("epoch", prefix="posture-id network universal train",
                          quiet=args.quiet) as progress:
        train_universal(args.data, args.out, config, network, progress=progress)
    say(f"wrote {args.out / 'model.safetensors'} and model.json")
    return 0


def run_check(args: argparse.Namespace) -> int:
    from posture_id.studies.universal_check import calibrate_model

    report = calibrate_model(args.model, args.data)
    print(report.markdown())
    say(f"wrote {args.model / 'calibration.json'}, check.json and check.md")
    return 0


def run_ensemble(args: argparse.Namespace) -> int:
    check_output_folder(args.out, "--out", inputs=tuple(args.models))
    from posture_id.learning.universal_model import UniversalModel, ensemble_of

    model = ensemble_of([UniversalModel.load(folder) for folder in args.models],
                        by_noise=args.by_noise)
    model.save(args.out)
    gated = (f", {model.gate.white_members} of them for white noise"
             if model.gate is not None else "")
    say(f"wrote {args.out / 'model.safetensors'} and model.json "
        f"({model.network.config.members} members{gated}); calibrate it: posture-id network "
        f"universal calibrate {args.out} DATA_DIR...")
    return 0


def run_typicality(args: argparse.Namespace) -> int:
    from posture_id.learning.typicality import TYPICALITY_FILE
    from posture_id.studies.universal_check import reference_from_sets

    report = reference_from_sets(args.model, args.data)
    print(report.markdown())
    say(f"wrote {args.model / TYPICALITY_FILE}, typicality.json and typicality.md")
    return 0


#: What ``universal table`` writes into its --out folder.
TABLE_FILES = ("table.json", "table.md", "table.png")


def run_table(args: argparse.Namespace) -> int:
    with OutputFolder(args.out, "--out", TABLE_FILES, inputs=(args.model, args.cache)):
        return _table(args)


def _table(args: argparse.Namespace) -> int:
    from posture_id.learning.universal_identifier import BUNDLED_DIR
    from posture_id.studies.universal_table import family_table

    if args.cache is not None:
        check_output_folder(args.cache, "--cache")
    with TerminalProgress("cell", prefix="posture-id network universal table",
                          quiet=args.quiet) as progress:
        # the seed and bodies per cell where given; family_table's defaults otherwise
        given = _given(args, "seed", "bodies_per_cell")
        table = family_table(args.model or BUNDLED_DIR, args.out, args.trials, args.workers,
                             args.cache, progress, **given)
    print(table.markdown())
    say(f"wrote {args.out / 'table.md'}, table.json and table.png")
    return 0
