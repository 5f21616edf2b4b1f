"""``posture-id network cnn evaluate``: the paper's tables and figures for a trained model."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.cli.arguments import non_negative_int, say
from posture_id.cli.output_folder import OutputFolder
from posture_id.cli.progress import TerminalProgress
from posture_id.errors import PostureIdError

__all__ = ["add_parser"]


def add_parser(sub, name: str = "evaluate") -> None:
    p = sub.add_parser(name, help="evaluate a trained model on a data set")
    p.add_argument("model", type=Path, help="model directory")
    p.add_argument("dataset", type=Path, help="data-set directory")
    p.add_argument("--out", type=Path, required=True,
                   help="report directory (report.md, report.json, PNGs)")
    p.add_argument("--resimulate", type=non_negative_int, default=200,
                   help="test trials re-simulated for E_id and E_rel (default %(default)d)")
    p.add_argument("--universal", nargs="?", const="bundled", metavar="MODEL",
                   help="also score the universal model (default: the bundled one) on the "
                        "same test trials, side by side (universal_comparison.md)")
    p.set_defaults(func=run)


#: What ``evaluate`` writes into its --out folder.
EVALUATE_FILES = ("report.json", "report.md", "parameter_errors.png",
                  "identification_error.png", "universal_comparison.md",
                  "universal_comparison.json")


def run(args: argparse.Namespace) -> int:
    if args.universal not in (None, "bundled") and not (Path(args.universal)
                                                        / "model.json").is_file():
        raise PostureIdError(f"{args.universal}: --universal is not a universal model (no "
                             "model.json)")
    with OutputFolder(args.out, "--out", EVALUATE_FILES, inputs=(args.model, args.dataset)):
        return _evaluate(args)


def _evaluate(args: argparse.Namespace) -> int:
    # torch loads here, not when the parser is built: other commands start without it
    from posture_id.learning.evaluation import evaluate

    with TerminalProgress(prefix="posture-id network cnn evaluate") as progress:
        report = evaluate(args.model, args.dataset, resimulate=args.resimulate,
                          progress=progress)
    paths = report.write(args.out)
    print(report.summary())
    if args.universal:
        paths += _compare(args, report)
    say("wrote " + ", ".join(str(p) for p in paths))
    return 0


def _compare(args: argparse.Namespace, report) -> list[Path]:
    """The universal model on the specialist's test trials, written beside its report."""
    from posture_id.fileio import atomic_write_text, json_text
    from posture_id.learning.universal_identifier import BUNDLED_DIR
    from posture_id.studies.universal_on_dataset import universal_on_dataset

    folder = BUNDLED_DIR if args.universal == "bundled" else Path(args.universal)
    modular = report.layout == "modular"
    universal = universal_on_dataset(folder, args.dataset, per_module=modular)
    test = report.splits["test"]
    reading = universal["reading"]
    lines = [f"# The universal model against the specialist on {args.dataset} (test split)",
             "",
             f"Command: `posture-id network cnn evaluate {args.model} {args.dataset} "
             f"--out {args.out} "
             f"--universal{'' if args.universal == 'bundled' else ' ' + args.universal}`", "",
             f"| model | fit RMSE ({reading}) | classes % |", "|---|---|---|",
             f"| specialist ({report.layout}) | {test.fit_rmse_per_sample:.4f} | "
             f"{100 * test.class_accuracy:.2f} |",
             f"| universal | {universal['fit_rmse_per_sample']:.4f} | "
             f"{100 * universal['class_accuracy']:.2f} |", "",
             f"ratio of fit RMSE universal / specialist: "
             f"{universal['fit_rmse_per_sample'] / test.fit_rmse_per_sample:.2f}"]
    universal["specialist"] = {"fit_rmse_per_sample": test.fit_rmse_per_sample,
                               "class_accuracy": test.class_accuracy, "layout": report.layout}
    md = atomic_write_text(args.out / "universal_comparison.md", "\n".join(lines) + "\n")
    js = atomic_write_text(args.out / "universal_comparison.json", json_text(universal))
    print("\n".join(lines[4:]))
    return [md, js]
