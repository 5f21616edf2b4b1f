"""Data-set generation end to end: wall time and peak memory.

Run:  .venv/bin/python benchmarks/dataset.py [--sizes 6910 27640] [--workdir DIR]

For each size (kept trials; 6910 is the paper's set, 20 730 modular samples) it runs
``posture-id network cnn data generate`` in a child process into a fresh directory and reports
wall time, peak resident memory of the child (from wait4) and disk use, then deletes
the directory. Figures go to docs/results/dataset.json.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from posture_id.fileio import atomic_write_text

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"


def run(trials: int, workdir: Path) -> dict:
    out = workdir / f"set-{trials}"
    shutil.rmtree(out, ignore_errors=True)
    cmd = [sys.executable, "-m", "posture_id.cli", "dataset", "generate", "--trials",
           str(trials), "--out", str(out), "--quiet"]
    start = time.perf_counter()
    proc = subprocess.Popen(cmd)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    if status != 0:
        raise SystemExit(f"generation failed with status {status}")
    manifest = json.loads((out / "manifest.json").read_text())
    disk = sum(p.stat().st_size for p in out.iterdir())
    shutil.rmtree(out)
    return {
        "kept_trials": trials,
        "modular_samples": trials * manifest["body"]["n_segments"],
        "simulated_trials": manifest["counts"]["simulated"],
        "rejection_rate": manifest["counts"]["rejection_rate"],
        "wall_s": wall,
        "peak_rss_mb": usage.ru_maxrss / 1024,
        "disk_gb": disk / 1e9,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[6910, 4 * 6910])
    parser.add_argument("--workdir", type=Path, default=None)
    parser.add_argument("--out", type=Path,
                        default=RESULTS / "dataset.json")
    args = parser.parse_args()
    # warm numba's cache so that compilation is not timed
    subprocess.run([sys.executable, "-c", "from posture_id import load_body, simulate; "
                    "simulate(load_body())"], check=True)
    with tempfile.TemporaryDirectory(dir=args.workdir) as tmp:
        rows = [run(n, Path(tmp)) for n in args.sizes]
    print(f"{'kept':>7} {'modular':>8} {'simulated':>9} {'rejected':>8} {'wall s':>7} "
          f"{'peak MB':>8} {'disk GB':>8}")
    for r in rows:
        print(f"{r['kept_trials']:>7} {r['modular_samples']:>8} {r['simulated_trials']:>9} "
              f"{r['rejection_rate']:>8.1%} {r['wall_s']:>7.1f} {r['peak_rss_mb']:>8.0f} "
              f"{r['disk_gb']:>8.2f}")
    atomic_write_text(args.out, json.dumps({"cpu_count": os.cpu_count(), "runs": rows},
                                           indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
