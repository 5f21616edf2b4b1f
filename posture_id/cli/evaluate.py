"""``posture-id evaluate``: the paper's tables and figures for a trained model."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.cli.arguments import check_output_folder, non_negative_int, say
from posture_id.cli.progress import TerminalProgress

__all__ = ["add_parser"]


def add_parser(sub) -> None:
    p = sub.add_parser("evaluate", help="evaluate a trained model on a data set")
    p.add_argument("model", type=Path, help="model directory")
    p.add_argument("dataset", type=Path, help="data-set directory")
    p.add_argument("--out", type=Path, required=True,
                   help="report directory (report.md, report.json, PNGs)")
    p.add_argument("--resimulate", type=non_negative_int, default=200,
                   help="test trials re-simulated for E_id and E_rel (default %(default)d)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    check_output_folder(args.out, "--out", inputs=(args.model, args.dataset))
    # torch loads here, not when the parser is built: other commands start without it
    from posture_id.learning.evaluation import evaluate

    with TerminalProgress(prefix="posture-id evaluate") as progress:
        report = evaluate(args.model, args.dataset, resimulate=args.resimulate,
                          progress=progress)
    paths = report.write(args.out)
    print(report.summary())
    say("wrote " + ", ".join(str(p) for p in paths))
    return 0
