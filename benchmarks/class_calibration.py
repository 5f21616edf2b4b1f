"""Class probabilities on noise the network never saw: the leave-one-family-out answers.

Run:  .venv/bin/python benchmarks/class_calibration.py [--runs docs/results/noise_lofo_widened]
                                                       [--out docs/results/class_calibration]

Reads the people-like answers of a leave-one-family-out run (``benchmarks/noise_lofo.py``'s
``--out`` folder: one folder per held-out family, each answered by the network fine-tuned
without that family; by default the bundled recipe's, 48 subjects a family) and of the
bundled network (``docs/results/honest_verdict``, every family seen), and reports how
well the network's P(com) says how often a module controls the COM: the expected
calibration error (10 bins) per family and pooled, the share right of the modules given a
class with probability ≥ 0.9, and the reliability diagram of both (``reliability.png``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from posture_id.fileio import atomic_write_text
from posture_id.simulation.noise_families import NoiseFamily
from posture_id.uncertainty.coverage import (
    calibrated_ece,
    expected_calibration_error,
    fit_temperature,
    reliability,
)

sys.path.insert(0, str(Path(__file__).resolve().parent))
from honest_verdict import _judged, _names_class, _truth_com  # noqa: E402  (a sibling script)

COMMAND = ".venv/bin/python benchmarks/class_calibration.py"


def _modules(rows: list[dict], family: str | None = None, noise: bool = False):
    """(P(com), true class is COM) of every people-like module whose truth is known; with
    ``noise``, each module's recording's noise share (``noise_relative``) too."""
    p, truth, share = [], [], []
    for row in rows:
        if row.get("group") != "people-like" or row.get("skipped"):
            continue
        if family is not None and row["kind"] != family:
            continue
        known = _truth_com(row)
        if known is not None:
            p += row["p_com"]
            truth += known
            share += [row["noise_relative"]] * len(known)
    out = np.asarray(p, dtype=float), np.asarray(truth, dtype=bool)
    return (*out, np.asarray(share, dtype=float)) if noise else out


def _cells(p: np.ndarray, truth: np.ndarray) -> str:
    sure = np.maximum(p, 1 - p) >= 0.9
    right = (p >= 0.5) == truth
    ece = expected_calibration_error(p, truth)
    floor = calibrated_ece(p)
    return (f"{len(p)} | {ece:.3f} | {floor.mean():.3f} | {np.mean(floor >= ece):.3f} | "
            f"{int(sure.sum())} | {100 * right[sure].mean():.1f} %")


def _logit(p: np.ndarray) -> np.ndarray:
    p = np.clip(p, 1e-9, 1 - 1e-9)
    return np.log(p / (1 - p))


def _platt(logit: np.ndarray, truth: np.ndarray) -> tuple[float, float]:
    """(a, b) of P = sigmoid(a·logit + b) with the least negative log-likelihood."""
    from scipy.optimize import minimize

    def nll(ab: np.ndarray) -> float:
        s = ab[0] * logit + ab[1]
        return float(np.mean(np.logaddexp(0.0, s) - truth * s))

    return tuple(minimize(nll, np.array([1.0, 0.0]), method="Nelder-Mead").x)


def _recalibrated(held: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]) -> list[str]:
    """Each held-out family's P(com) recalibrated three ways, each fitted on the other
    held-out families' answers (the recalibration a family never seen would get): one
    temperature; a temperature for each half of the noise share (split at the others'
    median); a slope and offset of the logit (Platt). Their ECE beside the answers'."""
    lines = ["", "Recalibrated on the other held-out families, each way fitted (least "
             "negative log-likelihood) on the other four families' answers and applied to "
             "the fifth's: one temperature, P = sigmoid(logit / T); a temperature for each "
             "half of the recordings' noise share (split at the other families' median); "
             "P = sigmoid(a·logit + b) (Platt). ECE:", "",
             "| family | as answered | T | one temperature | by the noise share | Platt |",
             "|---|---|---|---|---|---|"]
    for family, (p, truth, share) in held.items():
        others = [held[f] for f in held if f != family]
        z_o, t_o, s_o = (np.concatenate([o[k] for o in others]) for k in range(3))
        t = fit_temperature(_logit(z_o), t_o)
        edge = float(np.median(s_o))
        low, high = (fit_temperature(_logit(z_o[m]), t_o[m])
                     for m in (s_o < edge, s_o >= edge))
        by_noise = np.where(share < edge, low, high)
        a, b = _platt(_logit(z_o), t_o)
        z = _logit(p)
        cells = [expected_calibration_error(q, truth) for q in
                 (1 / (1 + np.exp(-z / t)), 1 / (1 + np.exp(-z / by_noise)),
                  1 / (1 + np.exp(-(a * z + b))))]
        lines.append(f"| {family} | {expected_calibration_error(p, truth):.3f} | {t:.2f} | "
                     + " | ".join(f"{c:.3f}" for c in cells) + " |")
    return lines


def _verdict_line(rows: list[dict]) -> str:
    """How the verdict treats the answers with a class wrong (doubtful, or imprecise naming
    that module's class) and the right ones (every class right, every truth inside its
    interval: doubtful)."""
    wrong = [r for r in rows if not all(r["classes_right"])]
    flagged = [r for r in wrong if r["level"] == "doubtful" or any(
        _names_class(r, m) for m, ok in enumerate(r["classes_right"]) if not ok)]
    right = [r for r in rows if _judged(r) == "right"]
    doubted = [r for r in right if r["level"] == "doubtful"]
    return (f"of {len(wrong)} answers with a class wrong, {len(flagged)} doubtful or "
            f"imprecise naming that module's class; of {len(right)} right answers, "
            f"{len(doubted)} doubtful")


def _rows(folder: Path) -> list[dict]:
    return json.loads((folder / "rows.json").read_text(encoding="utf-8"))["rows"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=Path, default=Path("docs/results/noise_lofo_widened"))
    parser.add_argument("--seen", type=Path, default=Path("docs/results/honest_verdict"))
    parser.add_argument("--out", type=Path, default=Path("docs/results/class_calibration"))
    args = parser.parse_args()
    held = {f.value: _rows(args.runs / f.value) for f in NoiseFamily
            if (args.runs / f.value / "rows.json").is_file()}
    seen = _rows(args.seen)
    lines = ["# Class probabilities on noise the network never saw", "",
             f"Made by `{COMMAND} --runs {args.runs} --seen {args.seen}` (what it reads: the "
             "script's docstring). Expected calibration error of P(com) against the true "
             "class (10 bins); the modules given a class with probability ≥ 0.9 and the "
             "share of them right.", "",
             "| family | answered by | modules | ECE | ECE if calibrated | chance of this "
             "ECE if calibrated | given ≥ 0.9 | of them right |",
             "|---|---|---|---|---|---|---|---|"]
    for family, rows in held.items():
        lines.append(f"| {family} | fine-tuned without it | {_cells(*_modules(rows, family))} |")
    pooled = [np.concatenate(x) for x in zip(*(_modules(rows, f) for f, rows in held.items()),
                                              strict=True)]
    lines.append(f"| every held-out family | fine-tuned without it | {_cells(*pooled)} |")
    for family in NoiseFamily:
        p, truth = _modules(seen, family.value)
        if len(p):
            lines.append(f"| {family.value} | the bundled network (seen) | {_cells(p, truth)} |")
    lines.append(f"| every family | the bundled network (seen) | {_cells(*_modules(seen))} |")
    lines += ["", "ECE if calibrated: the mean ECE of these probabilities against classes "
              "drawn from them (2000 draws), what a perfectly calibrated network would "
              "read on this many modules; the chance: the share of those draws at or above "
              "the ECE measured."]
    lines += _recalibrated({f: _modules(rows, f, noise=True) for f, rows in held.items()})
    lines += ["", "The verdict on the held-out families' answers: " + _verdict_line(
        [r for rows in held.values() for r in rows if r.get("group") == "people-like"
         and not r.get("skipped")]) + "."]
    args.out.mkdir(parents=True, exist_ok=True)
    _figure(pooled, _modules(seen), args.out / "reliability.png")
    lines += ["", "![Reliability diagram](reliability.png)"]
    atomic_write_text(args.out / "report.md", "\n".join(lines) + "\n")
    print("\n".join(lines))


def _figure(held: list[np.ndarray], seen: tuple[np.ndarray, np.ndarray], path: Path) -> None:
    from posture_id.plotting import plot_reliability

    diagrams = {}
    for (p, truth), label in ((held, "held-out families, fine-tuned without"),
                              (seen, "every family seen, bundled")):
        mean_p, freq, count = reliability(p, truth)
        diagrams[f"{label} ({len(p)} modules)"] = {"mean_probability": mean_p,
                                                  "frequency": freq, "count": count}
    plot_reliability(diagrams, path)


if __name__ == "__main__":
    main()
