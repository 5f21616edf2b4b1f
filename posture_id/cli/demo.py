"""``posture-id demo``: identify the shipped example recordings and report."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.cli.arguments import check_output_folder, say
from posture_id.cli.progress import TerminalProgress

__all__ = ["add_parser"]


def add_parser(sub) -> None:
    p = sub.add_parser("demo", help="identify the example recordings; write a report")
    p.add_argument("--out", type=Path, default=Path("demo"),
                   help="report folder (default %(default)s)")
    p.add_argument("--method", choices=("cnn", "fit", "hybrid"), default="hybrid",
                   help="identification method (default %(default)s)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    check_output_folder(args.out, "--out")
    # torch and CasADi load here, not when the parser is built
    from posture_id.identify import Method
    from posture_id.studies.demo import run_demo

    with TerminalProgress(prefix="posture-id demo", quiet=True) as progress:
        rows = run_demo(args.out, Method(args.method), progress)
    for row in rows:
        print(f"\n{row.name} (body {row.body}): identified, then true\n"
              + row.result.summary())
        print("true:      " + ", ".join(
            f"{j} Kp {m.kp:.2f} Ki {m.ki:.3f} Kd {m.kd:.2f} Δ {m.delay_s:.4f} {m.controls}"
            for j, m in row.truth.modules.items()))
        worst = float(abs(row.relative_errors()[:, 0]).max())
        print(f"largest Kp error {100 * worst:.1f} %")
    say(f"wrote {args.out / 'report.md'} with a JSON and a PNG per recording")
    return 0
