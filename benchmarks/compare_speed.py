"""How long ``posture-id compare`` takes on 3-segment people-like recordings, and what it
says, on this tree and (``--before TREE``) another checkout side by side.

Run:  .venv/bin/python benchmarks/compare_speed.py --out DIR [--before TREE] [--recordings 3]

Recordings: the TIP (3 segments) under DEC parameters drawn from docs/model.md §5's prior
(seed 31 + k; a subject that falls is skipped), 2 cycles of the 242-state PRTS at 1°,
motor noise leaving 30 % of the body COM sway locked, 0.05° sensor noise
(:func:`~posture_id.simulation.subjects.people_like`).
Each is compared by the command line of each tree (``python -m posture_id.cli compare``,
``PYTHONPATH`` at the tree), one after the other on the same machine. Writes
``report.md`` and ``rows.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def make_recordings(folder: Path, count: int) -> list[Path]:
    from posture_id.bodies.body import load_body
    from posture_id.dec.prior import sample_parameters
    from posture_id.errors import SimulationError
    from posture_id.simulation.batch import simulate
    from posture_id.simulation.stimulus import prts
    from posture_id.simulation.subjects import people_like

    body = load_body()
    stimulus = prts()
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    k = seed = 0
    while len(paths) < count:
        seed = 31 + k
        k += 1
        params = sample_parameters(body, 1, np.random.default_rng(seed)).trial(0, body.joint_names)
        if not simulate(body, params, stimulus).stable:
            continue
        path = folder / f"tip_people_like_{seed}.csv"
        try:
            people_like(body, params, stimulus, 0.3, seed).recording.to_csv(path)
        except SimulationError:  # the motor noise tips it over: another subject
            continue
        paths.append(path)
    return paths


def compare(tree: Path, recording: Path, out: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree), MPLBACKEND="Agg")
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "posture_id.cli", "compare", str(recording),
                           "--out", str(out)], cwd=tree, env=env, capture_output=True,
                          text=True)
    seconds = time.perf_counter() - start
    data = json.loads(out.read_text()) if out.exists() else {}
    return {"seconds": seconds, "rc": done.returncode, "preferred": data.get("preferred"),
            "within_noise": data.get("within_noise"),
            "stderr": done.stderr.strip().splitlines()[-1:] if done.returncode else []}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--before", type=Path, help="another checkout, timed beside this one")
    parser.add_argument("--recordings", type=int, default=3)
    args = parser.parse_args(argv)
    recordings = make_recordings(args.out / "recordings", args.recordings)
    trees = {"after": ROOT} | ({"before": args.before.resolve()} if args.before else {})
    rows = []
    for path in recordings:
        for name, tree in trees.items():
            row = {"recording": path.name, "tree": name,
                   **compare(tree, path, args.out / f"{path.stem}.{name}.json")}
            print(row, flush=True)
            rows.append(row)
    (args.out / "rows.json").write_text(json.dumps(rows, indent=1))
    lines = ["| recording | tree | seconds | preferred | within the noise (DEC, IC) |",
             "|---|---|---|---|---|"]
    for r in rows:
        w = r["within_noise"] or {}
        lines.append(f"| {r['recording']} | {r['tree']} | {r['seconds']:.1f} | {r['preferred']} "
                     f"| {w.get('dec')}, {w.get('ic')} |")
    (args.out / "report.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
