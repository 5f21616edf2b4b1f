"""Do two trees of posture_id report the same results? Runs the project's result-making
commands on one tree and, given the rows of another tree's run, writes the table of
values that stayed identical and how far the others moved.

Run:  .venv/bin/python benchmarks/same_results.py --out DIR [--tree PATH] [--before ROWS_JSON]

``--tree`` is a checkout of posture_id (default: this one); its package and its benchmark
scripts are the ones run (``PYTHONPATH`` points at it), so that the commit before a change
can be run with the same interpreter. The commands, each small enough to run in minutes on
2 cores and each seeded:

- ``posture-id demo``: the answers of the shipped example recordings;
- ``posture-id network universal table --trials 256``: every cell of the universal table;
- ``benchmarks/ic_recovery.py --per-cell 1``: the IC fit on 12 IC recordings;
- ``benchmarks/model_comparison.py --per-model 4``: DEC against IC on 8 recordings;
- ``benchmarks/honest_verdict.py --subjects 2``: the verdict's counts on clean, people-like
  and planted-mistake recordings;
- the paper CNN's Table 2 and 4 figures: ``posture-id network cnn evaluate`` of the bundled
  TIP CNN on a data set of 256 TIP trials (``posture-id network cnn data generate --seed 77``).

Every number in the JSON files each command writes is read (keys that are wall-clock times
left out) and compared with the same path in the other run: identical, or its largest
relative difference. Writes ``rows.json`` (the values) and, with ``--before``,
``report.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
#: Keys whose values are wall-clock times or machine facts (a compiled model found in
#: the cache or compiled), not results.
TIMING_KEYS = frozenset({"seconds", "elapsed_s", "wall_s", "fit_seconds", "longest_fit_s",
                         "threads", "workers", "created", "duration_s", "time_per_trial_ms",
                         "ms_per_trial", "trials_per_s", "backend", "wall_time_s",
                         "identification_time_s"})


@dataclass(frozen=True)
class Step:
    """One result-making command: its name, argv (``{py}``, ``{out}``, ``{tree}`` and
    ``{data}`` filled in) and the JSON files under its output folder to compare."""

    name: str
    argv: tuple[str, ...]
    outputs: tuple[str, ...]


STEPS = (
    Step("demo", ("{py}", "-m", "posture_id.cli", "demo", "--out", "{out}"), ("*.json",)),
    Step("universal table", ("{py}", "-m", "posture_id.cli", "universal", "table",
                             "--trials", "256", "--out", "{out}"), ("table.json",)),
    Step("ic_recovery", ("{py}", "{tree}/benchmarks/ic_recovery.py", "--per-cell", "1",
                         "--out", "{out}"), ("rows.json",)),
    Step("model_comparison", ("{py}", "{tree}/benchmarks/model_comparison.py",
                              "--per-model", "4", "--out", "{out}"), ("rows.json",)),
    Step("honest_verdict", ("{py}", "{tree}/benchmarks/honest_verdict.py", "--subjects", "2",
                            "--out", "{out}"), ("rows.json",)),
    Step("paper CNN data", ("{py}", "-m", "posture_id.cli", "dataset", "generate", "--trials",
                            "256", "--seed", "77", "--quiet", "--out", "{data}"), ()),
    Step("paper CNN Table 2/4", ("{py}", "-m", "posture_id.cli", "evaluate",
                                 "{tree}/posture_id/learning/models/tip_default", "{data}",
                                 "--resimulate", "32", "--out", "{out}"), ("report.json",)),
)


def numbers(value, path: str = "") -> dict[str, object]:
    """Flatten a JSON value into {path: leaf}; numbers, strings and booleans kept,
    wall-clock keys left out."""
    out: dict[str, object] = {}
    if isinstance(value, dict):
        for key, item in value.items():
            if key in TIMING_KEYS:
                continue
            out.update(numbers(item, f"{path}/{key}"))
    elif isinstance(value, list):
        for i, item in enumerate(value):
            out.update(numbers(item, f"{path}[{i}]"))
    else:
        out[path] = value
    return out


def run_step(step: Step, tree: Path, out: Path) -> dict:
    """Run one step on ``tree``; returns {"seconds", "rc", "values"}."""
    folder = out / step.name.replace(" ", "_").replace("/", "_")
    fill = {"py": sys.executable, "out": str(folder), "tree": str(tree),
            "data": str(out / "paper_cnn_data")}
    argv = [a.format(**fill) for a in step.argv]
    env = dict(os.environ, PYTHONPATH=str(tree), MPLBACKEND="Agg")
    start = time.perf_counter()
    done = subprocess.run(argv, cwd=tree, env=env, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    (out / f"{folder.name}.log").write_text(done.stdout + done.stderr)
    values: dict[str, object] = {}
    for pattern in step.outputs:
        for file in sorted(folder.glob(pattern)):
            values.update({f"{file.name}{k}": v
                           for k, v in numbers(json.loads(file.read_text())).items()})
    return {"seconds": seconds, "rc": done.returncode, "values": values, "tree": str(tree),
            "out": str(out)}


def _is_result(path: str) -> bool:
    """Whether a value's path names a result (not a time or a machine fact)."""
    return path.rsplit("/", 1)[-1].split("[", 1)[0] not in TIMING_KEYS


def _in_tree(value, run: dict):
    """A string value with the paths of its run's package and output folder written
    ``<tree>`` and ``<out>`` (where the run was, not what it found)."""
    if not isinstance(value, str):
        return value
    if run.get("tree"):
        value = value.replace(f"{run['tree']}/posture_id/", "<tree>/posture_id/")
    return value.replace(run["out"], "<out>") if run.get("out") else value


def difference(a, b) -> float:
    """0 for identical leaves, else the relative difference (inf where not numbers)."""
    if a == b:
        return 0.0
    if isinstance(a, bool) or isinstance(b, bool):
        return float("inf")
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        if not (np.isfinite(a) and np.isfinite(b)):
            return float("inf")
        return abs(a - b) / max(abs(a), abs(b), 1e-12)
    return float("inf")


def report(before: dict, after: dict) -> str:
    """The before/after table, one row per step."""
    lines = ["| command | values | identical | differ | largest relative difference "
             "| missing / new | exit before → after | seconds before → after |",
             "|---|---|---|---|---|---|---|---|"]
    details = []
    for name, b in before.items():
        a = after.get(name)
        if a is None:
            continue
        common = sorted(k for k in set(b["values"]) & set(a["values"]) if _is_result(k))
        diffs = {k: difference(_in_tree(b["values"][k], b), _in_tree(a["values"][k], a))
                 for k in common}
        changed = {k: d for k, d in diffs.items() if d > 0}
        largest = max(changed.values(), default=0.0)
        lost = len(set(b["values"]) - set(a["values"]))
        new = len(set(a["values"]) - set(b["values"]))
        lines.append(f"| {name} | {len(common)} | {len(common) - len(changed)} | {len(changed)} "
                     f"| {largest:.3g} | {lost} / {new} | {b['rc']} → {a['rc']} "
                     f"| {b['seconds']:.0f} → {a['seconds']:.0f} |")
        for key, _ in sorted(changed.items(), key=lambda kv: -kv[1])[:8]:
            details.append(f"- {name}: `{key}` {b['values'][key]!r} → {a['values'][key]!r}")
    return "\n".join(lines + ([""] + details if details else [])) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--tree", type=Path, default=ROOT)
    parser.add_argument("--before", type=Path, help="rows.json of the run on the other tree")
    parser.add_argument("--steps", nargs="+", help="names of the steps to run (default all)")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    rows_file = args.out / "rows.json"
    rows = json.loads(rows_file.read_text()) if rows_file.exists() else {}
    for step in STEPS:
        if args.steps and step.name not in args.steps:
            continue
        print(f"{step.name} ...", flush=True)
        rows[step.name] = run_step(step, args.tree.resolve(), args.out.resolve())
        print(f"  {rows[step.name]['seconds']:.0f} s, exit {rows[step.name]['rc']}, "
              f"{len(rows[step.name]['values'])} values", flush=True)
        tmp = rows_file.with_suffix(".tmp")
        tmp.write_text(json.dumps(rows, indent=1, default=str))
        tmp.replace(rows_file)
    if args.before:
        text = report(json.loads(args.before.read_text()), rows)
        (args.out / "report.md").write_text(text)
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
