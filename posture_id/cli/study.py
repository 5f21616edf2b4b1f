"""``posture-id study MANIFEST --out DIR``: a whole study from its manifest (every trial's
FRF, each subject's joint fit, summary.csv, paired tests between the conditions)."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.cli.arguments import (
    check_output_file,
    default_of,
    non_negative_int,
    positive_float,
    positive_int,
    say,
)
from posture_id.cli.exit_status import answered
from posture_id.cli.output_folder import LEDGER, OutputFolder, written_by_posture_id
from posture_id.cli.plate_mass import add_load_arguments, load_columns_from_args
from posture_id.cli.progress import TerminalProgress
from posture_id.cli.stimulus import add_column_arguments, columns_from_args
from posture_id.errors import PostureIdError
from posture_id.force_plate.reading import ForcePlateColumns
from posture_id.frf.response import FrfOptions

__all__ = ["add_parser", "run"]


def add_parser(sub) -> None:
    p = sub.add_parser("study", help="a whole study from its manifest (CSV: subject, condition, "
                                     "file, and the body or height_m and mass_kg): every "
                                     "trial's FRF, each subject's joint fit, paired tests "
                                     "between the conditions")
    p.add_argument("manifest", type=Path, help="the manifest CSV (files relative to it)")
    p.add_argument("--out", type=Path, required=True,
                   help="results folder: frf/, fits/, paired/, summary.csv (a row per "
                        "subject, the conditions as columns), trials.csv, study.json; an "
                        "empty folder, or this study's own: a study started again goes on "
                        "where it stopped (a file posture-id did not write is never "
                        "overwritten)")
    p.add_argument("--model", choices=("ic", "dec", "none"), default="ic",
                   help="the model fitted to each subject's trials (default %(default)s; "
                        "none: FRFs only)")
    p.add_argument("--per-condition", nargs="+", metavar="NAME", default=None,
                   help="the parameters that take one value per condition (default: w for "
                        "ic, none for dec; dec: e.g. ankle.kp)")
    p.add_argument("--segments", type=positive_int, default=1,
                   help="segments of the Winter body of a subject given by height and mass "
                        "(default %(default)d)")
    p.add_argument("--skip-cycles", type=non_negative_int,
                   default=default_of(FrfOptions, "skip_cycles"),
                   help="whole cycles left out at the start of each trial's FRF (default "
                        "%(default)d)")
    p.add_argument("--max-frequency-hz", type=positive_float,
                   default=default_of(FrfOptions, "max_frequency_hz"),
                   help="highest FRF frequency kept (default %(default)g Hz)")
    p.add_argument("--permutations", type=positive_int, default=2000,
                   help="of the paired tests (default %(default)d)")
    p.add_argument("--workers", type=positive_int,
                   help="local processes (default: every core)")
    p.add_argument("--scheduler", help="a Dask distributed scheduler (tcp://host:port)")
    p.add_argument("--plot", type=Path,
                   help="the per-condition parameters and FRF gains of every subject (PNG)")
    add_column_arguments(p)
    add_load_arguments(p, "the mass of a subject whose rows give a height and no mass: the "
                          "median of what the plate weighs in its trials")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from posture_id.manifest import StudyOptions, read_manifest, run_study

    check_output_file(args.plot, "--plot", (args.manifest,))
    if args.out.exists() and not args.out.is_dir():
        raise PostureIdError(f"{args.out}: --out is a file; give a folder")
    manifest = read_manifest(args.manifest)
    folder = OutputFolder(args.out, "--out", STUDY_FILES, inputs=(args.manifest,))
    model = None if args.model == "none" else args.model
    per_condition = args.per_condition
    if per_condition is None:
        per_condition = ["w"] if model == "ic" else []
    if model is None and args.per_condition:
        raise PostureIdError("--per-condition goes with a model (--model ic or dec)")
    if args.scheduler and args.workers is not None:
        raise PostureIdError("--workers sets the local processes, and --scheduler runs the "
                             "study on the cluster's workers: give one")
    if args.segments != 1 and all(t.body is not None for t in manifest.trials):
        raise PostureIdError(f"--segments {args.segments}: every row of {args.manifest} names "
                             "its body's URDF, which has its own segments; --segments makes "
                             "the Winter body of a row given by height_m and mass_kg")
    layout = columns_from_args(args)
    if isinstance(layout, ForcePlateColumns) and args.segments != 1:
        raise PostureIdError(f"--segments {args.segments}: a force plate's COP is the sway of "
                             "the body as one segment, whatever its URDF; leave --segments "
                             "out")
    if args.scheduler:
        from posture_id.executors import check_scheduler_address

        check_scheduler_address(args.scheduler)
    load = load_columns_from_args(args)
    if load is not None and all(t.body is not None or t.mass_kg is not None
                                for t in manifest.trials):
        raise PostureIdError(f"--load-columns weighs a subject whose rows give a height and no "
                             f"mass, and every row of {args.manifest} gives its mass or body")
    options = StudyOptions(layout=layout, model=model, load=load,
                           per_condition=tuple(per_condition), segments=args.segments,
                           frf=FrfOptions(skip_cycles=args.skip_cycles,
                                          max_frequency_hz=args.max_frequency_hz),
                           permutations=args.permutations, workers=args.workers,
                           scheduler=args.scheduler)
    with folder:
        replaced = _study_folder(args.out)
        with TerminalProgress("study") as progress:
            result = run_study(manifest, args.out, options, progress)
    for notice in result.notices:  # the manifest's, then the study's (a refusal says its own)
        say(notice)
    for notice in result.trial_notices:
        say(notice)
    if replaced:
        say(f"{args.out}: this study's own folder: the run replaces {replaced} (made again "
            "from every trial); FRFs and fits whose trials and options still hold are kept")
    print(result.summary())
    if args.plot:
        result.plot(args.plot)
        say(f"wrote {args.plot}")
    return answered(result.answered_doubtfully)


#: What ``study --out DIR`` writes (glob patterns in the folder).
STUDY_FILES = ("summary.csv", "trials.csv", "study.json", "frf/*.json", "fits/*.json",
               "paired/*.json")


def _study_folder(out: Path) -> str:
    """Refuse an ``--out`` that holds files and is not a study's own (an empty folder, or
    one whose study.json posture-id wrote); for a study's own, the files the run replaces
    (to say so), else ""."""
    if not out.is_dir():
        return ""
    present = sorted(p.relative_to(out).as_posix() for p in out.rglob("*")
                     if p.is_file() and p.name != LEDGER)
    if not present:
        return ""
    study = out / "study.json"
    if not (study.is_file() and written_by_posture_id(study, out)):
        listed = ", ".join(present[:4]) + (f" and {len(present) - 4} more"
                                           if len(present) > 4 else "")
        raise PostureIdError(f"{out}: --out holds {listed}, not a study's own results: give "
                             "an empty folder, or the folder of this study's earlier run")
    remade = [name for name in ("summary.csv", "trials.csv", "study.json")
              if (out / name).is_file()]
    if (out / "paired").is_dir():
        remade.append("paired/")
    return ", ".join(remade)
