"""Two universal tables on the same trials, side by side: how much each cell moved.

Run:  .venv/bin/python benchmarks/table_against.py BASE/table.json OTHER/table.json

Both tables must hold the same cells (``posture-id network universal table --trials 2048 --cache
data/table_cells``: the cache keeps the trials, so a second model is scored on the very
sway the first was). For the clean cells and for the people-like ones apart, prints the
change of each cell's median |Kp error| (``median_error_pct``, percentage points: least,
median, largest; how many cells are higher) and of its class accuracy, and how many cells
have all four 90 % coverages within 87–93 % in each table. The base table the docs compare
against: ``git show 18d0c0d:docs/results/universal/table.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

#: A cell's coverages count as on target within this band (percent).
COVERAGE_BAND = (87.0, 93.0)


def _cells(path: Path) -> dict:
    try:
        return json.loads(path.read_text(encoding="utf-8"))["cells"]
    except (OSError, ValueError, KeyError) as exc:
        sys.exit(f"{path}: not a universal table.json ({exc})")


def _in_band(cell: dict) -> bool:
    low, high = COVERAGE_BAND
    return all(low <= v <= high for v in cell["coverage_pct"].values())


def compare(base: dict, other: dict) -> list[str]:
    """One line per kind of sway (clean, people-like)."""
    if set(base) != set(other):
        sys.exit("the two tables hold other cells: score both on the same trials "
                 "(--cache)")
    lines = []
    for kind in ("clean", "people-like"):
        names = [n for n in base if n.endswith("| " + kind)]
        kp = np.array([other[n]["median_error_pct"]["kp"] - base[n]["median_error_pct"]["kp"]
                       for n in names])
        classes = np.array([other[n]["classes_pct"] - base[n]["classes_pct"] for n in names])
        on_target = [sum(_in_band(table[n]) for n in names) for table in (base, other)]
        lines.append(
            f"{kind}: {len(names)} cells; Kp error {kp.min():+.2f} to {kp.max():+.2f} points "
            f"(median {np.median(kp):+.2f}; higher in {int((kp > 0).sum())}); classes "
            f"{classes.min():+.2f} to {classes.max():+.2f}; all four coverages within "
            f"{COVERAGE_BAND[0]:g}–{COVERAGE_BAND[1]:g} %: {on_target[0]} cells against "
            f"{on_target[1]}")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("base", type=Path)
    parser.add_argument("other", type=Path)
    args = parser.parse_args()
    print("\n".join(compare(_cells(args.base), _cells(args.other))))


if __name__ == "__main__":
    main()
