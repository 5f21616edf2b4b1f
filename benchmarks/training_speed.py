"""Do two trees of posture_id train at the same speed? Trains the paper's CNN and the
universal network on the same small sets with each tree, the trees taking turns, and
reports the seconds per epoch side by side and their ratio.

Run:  .venv/bin/python benchmarks/training_speed.py --tree BEFORE --tree AFTER --out DIR
      [--rounds 3] [--epochs 3] [--threads 1]

Each round trains once with every tree (the order alternating from round to round, so a
machine that slows or speeds up weighs on both alike), each run a fresh process with
``PYTHONPATH`` at its tree, through the commands every tree reads (``posture-id train``
and ``posture-id universal train``, in a later tree the old spelling of ``network cnn
train`` and ``network universal train``). The sets are made once, by this tree: a paper
set of 240 TIP trials (``dataset generate --seed 5``) and a universal set of 20 shards of
40 parameter sets (``universal data --seed 5``). An epoch's seconds are what the trainer
itself logs (``log.jsonl`` for the CNN, the model's training history for the universal
network); the process's wall time, data loading included, beside them. Writes
``rows.json`` and ``report.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _cli(tree: Path, *argv: str) -> float:
    """Run ``posture-id ARGV`` with ``tree``'s package; its wall time, s."""
    env = dict(os.environ, PYTHONPATH=str(tree), MPLBACKEND="Agg")
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "posture_id.cli", *argv], cwd=tree, env=env,
                          capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"{tree}: posture-id {' '.join(argv)} failed:\n{done.stderr[-2000:]}")
    return time.perf_counter() - start


def _epoch_seconds(model: Path, network: str) -> list[float]:
    if network == "cnn":
        rows = [json.loads(line) for line in (model / "log.jsonl").read_text().splitlines()]
    else:
        rows = json.loads((model / "model.json").read_text())["training"]["history"]
    return [float(r["seconds"]) for r in rows]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tree", type=Path, action="append", required=True,
                        help="a checkout of posture_id (give two or more)")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--epochs", type=int, default=3)
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    paper, drawn = args.out / "paper_set", args.out / "universal_set"
    if not (paper / "manifest.json").exists():
        _cli(ROOT, "dataset", "generate", "--trials", "240", "--seed", "5", "--quiet",
             "--out", str(paper))
    if not (drawn / "manifest.json").exists():
        _cli(ROOT, "universal", "data", "--out", str(drawn), "--shards", "20", "--trials",
             "40", "--seed", "5", "--quiet")
    common = ("--epochs", str(args.epochs), "--threads", str(args.threads), "--quiet")
    commands = {"cnn": ("train", str(paper), *common),
                "universal": ("universal", "train", str(drawn), *common)}
    rows = []
    for r in range(args.rounds):
        trees = args.tree if r % 2 == 0 else list(reversed(args.tree))
        for network, command in commands.items():
            for t, tree in enumerate(trees):
                model = args.out / f"model_{network}_{r}_{t}"
                shutil.rmtree(model, ignore_errors=True)
                wall = _cli(tree, *command, "--out", str(model))
                epochs = _epoch_seconds(model, network)
                rows.append({"round": r, "tree": str(tree), "network": network,
                             "wall_s": wall, "epoch_s": epochs})
                print(f"round {r} {network} {tree}: {statistics.median(epochs):.2f} s/epoch, "
                      f"{wall:.1f} s in all", file=sys.stderr)
                shutil.rmtree(model, ignore_errors=True)
    (args.out / "rows.json").write_text(json.dumps(rows, indent=1))
    lines = ["# Training speed, side by side", "",
             f"`benchmarks/training_speed.py`: {args.rounds} rounds, {args.epochs} epochs each, "
             f"{args.threads} torch thread(s); median over rounds of each run's median "
             "epoch, and of its whole process (data loading included).", "",
             "| network | tree | s / epoch | process s | ratio to the first tree |",
             "|---|---|---|---|---|"]
    for network in commands:
        first = None
        for tree in args.tree:
            mine = [r for r in rows if r["network"] == network and r["tree"] == str(tree)]
            epoch = statistics.median(statistics.median(r["epoch_s"]) for r in mine)
            wall = statistics.median(r["wall_s"] for r in mine)
            first = first or epoch
            lines.append(f"| {network} | `{tree}` | {epoch:.3f} | {wall:.1f} | "
                         f"{epoch / first:.3f} |")
    (args.out / "report.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
