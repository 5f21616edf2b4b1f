"""The recording widening of a universal model (:mod:`posture_id.uncertainty.widening`):
fitted on calibration subjects, checked family by family on subjects it never saw.

    python -m posture_id.studies.widening CALIBRATION_ROWS --model MODEL_DIR
        [--check CHECK_ROWS] [--out REPORT.md]   # = make recording-widening

``CALIBRATION_ROWS`` and ``CHECK_ROWS``: the ``rows.json`` of
``benchmarks/honest_verdict.py --groups people-like`` (each people-like answer with its
estimate, truth and interval, normalised, and its recording's noise share), the first
drawn with another seed than the second (``--seed``). For every noise family F, the
widening fitted on the calibration subjects of the other families is applied to the check
subjects of F (the leave-one-family-out check: a family the widening never saw); then the
widening fitted on every family is written beside the model (``widening.json``) and the
check subjects' coverage with it reported.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from posture_id.fileio import atomic_write_text
from posture_id.uncertainty.widening import RecordingWidening, fit_widening, scores_of

__all__ = ["people_rows", "stack_rows", "widening_for", "coverage_with", "main"]


def people_rows(path: str | Path) -> list[dict]:
    """The people-like answers of an honest-verdict ``rows.json`` that carry their
    normalised estimate, truth and interval."""
    rows = json.loads(Path(path).read_text(encoding="utf-8"))["rows"]
    return [r for r in rows if r.get("group") == "people-like" and not r.get("skipped")
            and r.get("estimate") is not None and r.get("noise_relative") is not None]


def stack_rows(rows: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """(M, 4) scores and (M,) noise shares of every module of ``rows``."""
    scores = np.concatenate([scores_of(r["estimate"], r["truth_normalised"], r["lower"],
                                       r["upper"]) for r in rows])
    share = np.concatenate([[r["noise_relative"]] * len(r["estimate"]) for r in rows])
    return scores, share


def widening_for(model: str | Path, rows: list[dict], level: float = 0.9,
                 made_by: str = "") -> RecordingWidening:
    """The widening of the universal model in ``model`` fitted on its people-like answers
    ``rows`` (:func:`people_rows`), naming the model's weights."""
    from posture_id.learning.universal_model import UniversalModel

    sha = str(UniversalModel.load(model).sidecar.get("weights_sha256"))
    return fit_widening(*stack_rows(rows), level, sha, made_by=made_by)


def coverage_with(rows: list[dict], widening: RecordingWidening | None
                  ) -> tuple[float, float]:
    """(Kp, every parameter) shares of the truths inside the intervals of ``rows``, each
    widened by ``widening`` (None: as they are)."""
    scores, share = stack_rows(rows)
    factor = (np.ones_like(scores) if widening is None
              else np.stack([widening.factor(s) for s in share]))
    inside = scores <= factor
    return float(inside[:, 0].mean()), float(inside.mean())


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("calibration", type=Path)
    parser.add_argument("--model", type=Path, required=True,
                        help="the universal model the rows were identified with")
    parser.add_argument("--check", type=Path, help="rows of other subjects to check on "
                                                   "(default: the calibration rows)")
    parser.add_argument("--level", type=float, default=0.9)
    parser.add_argument("--out", type=Path, help="write the report here too")
    args = parser.parse_args(argv)
    calibration = people_rows(args.calibration)
    check = people_rows(args.check) if args.check else calibration
    families = sorted({r["kind"] for r in calibration})
    given = sys.argv[1:] if argv is None else argv
    command = ".venv/bin/python -m posture_id.studies.widening " + " ".join(given)
    lines = ["# The recording widening, checked on noise families it never saw", "",
             f"Made by `{command}`. Calibration: {len(calibration)} people-like answers; "
             f"check: {len(check)} others. True values inside the {100 * args.level:g} % "
             "intervals of the check's answers, Kp / every parameter:", "",
             "| family | as they are | widened, the family left out of the widening | "
             "widened by the widening written (every family) |", "|---|---|---|---|"]
    widening = widening_for(args.model, calibration, args.level, made_by=command)
    sha = widening.weights_sha256

    def cell(share: tuple[float, float]) -> str:
        return f"{100 * share[0]:.1f} % / {100 * share[1]:.1f} %"

    for family in families:
        others = [r for r in calibration if r["kind"] != family]
        mine = [r for r in check if r["kind"] == family]
        left_out = fit_widening(*stack_rows(others), args.level, sha)
        lines.append(f"| {family} | {cell(coverage_with(mine, None))} | "
                     f"{cell(coverage_with(mine, left_out))} | "
                     f"{cell(coverage_with(mine, widening))} |")
    before, after = coverage_with(check, None), coverage_with(check, widening)
    lines += ["", f"Every family: {100 * before[0]:.0f} % / {100 * before[1]:.0f} % as they "
                  f"are, {100 * after[0]:.0f} % / {100 * after[1]:.0f} % widened. The widening "
                  f"written (noise-share edges {', '.join(f'{e:.3f}' for e in widening.edges)}"
                  "; factors Kp, Ki, Kd, delay per bin: " + "; ".join(
                      ", ".join(f"{v:.2f}" for v in row) for row in widening.factors) + ")."]
    edges = (-np.inf, *widening.edges, np.inf)
    by_bin = []
    for low, high in zip(edges[:-1], edges[1:], strict=True):
        chosen = [r for r in check if low <= r["noise_relative"] < high]
        span = (f"below {high:.3f}" if low == -np.inf else f"from {low:.3f}"
                if high == np.inf else f"{low:.3f}–{high:.3f}")
        by_bin.append(f"noise share {span}: {len(chosen)} answers, "
                      f"{cell(coverage_with(chosen, None))} as they are, "
                      f"{cell(coverage_with(chosen, widening))} widened")
    lines += ["", "By the widening's bins: " + "; ".join(by_bin) + "."]
    widening.save(args.model)
    text = "\n".join(lines) + "\n"
    if args.out:
        atomic_write_text(args.out, text)
    print(text)


if __name__ == "__main__":
    main()
