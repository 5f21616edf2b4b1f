"""Modular versus monolithic CNN, paper-shaped versus ours, on the same trials.

Run:  .venv/bin/python benchmarks/modular_vs_monolithic.py DATASET [--epochs 15]
                                                             [--workdir DIR]

Trains four networks on one data set (same split, same epochs, same seed):

  modular,    paper-shaped: class as a regression target (MSE), SGD with momentum
  modular,    ours:         class as a logit (cross-entropy), AdamW one-cycle
  monolithic, paper-shaped
  monolithic, ours

evaluates each on its test split (``posture_id.learning.evaluate``, 200 re-simulated
trials) and writes the paper's Tables 2 (modular) and 4 (monolithic) beside ours to
docs/modular_vs_monolithic.md and docs/results/modular_vs_monolithic.json.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from posture_id import __version__
from posture_id.fileio import atomic_write_text
from posture_id.learning import (
    AdamWOneCycle,
    ClassOutput,
    Layout,
    NetworkConfig,
    SgdMomentum,
    TrainingConfig,
    evaluate,
    train,
)
from posture_id.learning.data import Dataset

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"

ROOT = Path(__file__).resolve().parents[1]
#: The paper's test rows (total RMSE, fit RMSE, accuracy): Table 2 and Table 4.
PAPER = {"modular": (1.4846, 1.4486, 0.8472), "monolithic": (4.0531, 3.2586, 0.5151)}
VARIANTS = {
    "paper-shaped": (ClassOutput.REGRESSION, SgdMomentum()),
    "ours": (ClassOutput.LOGIT, AdamWOneCycle()),
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset", type=Path)
    parser.add_argument("--epochs", type=int, default=15)
    parser.add_argument("--workdir", type=Path, default=ROOT / "data" / "benchmark_models")
    parser.add_argument("--doc", type=Path, default=ROOT / "docs" / "modular_vs_monolithic.md")
    parser.add_argument("--out", type=Path,
                        default=RESULTS / "modular_vs_monolithic.json")
    args = parser.parse_args()
    n = Dataset.open(args.dataset, verify=False).n_segments
    rows = {}
    for layout in (Layout.MODULAR, Layout.MONOLITHIC):
        for variant, (class_output, optimiser) in VARIANTS.items():
            name = f"{layout.value}-{variant}"
            folder = args.workdir / name
            network = NetworkConfig.for_body(layout, n, class_output=class_output)
            training = TrainingConfig(optimiser=optimiser, epochs=args.epochs,
                                      patience=args.epochs)
            start = time.perf_counter()
            result = train(args.dataset, folder, network, training)
            report = evaluate(folder, args.dataset, resimulate=200)
            print(f"{name}: {time.perf_counter() - start:.0f} s\n{report.summary()}\n",
                  flush=True)
            rows[name] = {"layout": layout.value, "variant": variant,
                          "training_s": sum(r["seconds"] for r in result.history),
                          "epochs": result.epochs_run, "report": report.to_dict()}
    atomic_write_text(args.out, json.dumps({"package_version": __version__,
                                            "dataset": str(args.dataset),
                                            "epochs": args.epochs, "runs": rows}, indent=2)
                      + "\n")
    atomic_write_text(args.doc, markdown(rows, args))
    print(f"wrote {args.out} and {args.doc}")


def markdown(rows: dict, args) -> str:
    out = ["# Modular versus monolithic CNN (made by benchmarks/modular_vs_monolithic.py)", "",
           f"Data set `{args.dataset}`; every network trained {args.epochs} epochs with the "
           "same split and seed; test split. RMSE in standardised target units, per sample "
           "(the paper's reading: predicting the training mean gives about √5 = 2.24 total "
           "and 2.0 fit for a module, √15 and √12 for a monolithic TIP sample), then per "
           "element (the mean gives 1.0). Command: `.venv/bin/python "
           "benchmarks/modular_vs_monolithic.py " + str(args.dataset)
           + f" --epochs {args.epochs}`.", "",
           "| network | total RMSE | fit RMSE | accuracy | total / fit RMSE per element | "
           "E_rel median | fell | training |", "|---|---|---|---|---|---|---|---|"]
    for layout in ("modular", "monolithic"):
        total, fit, acc = PAPER[layout]
        out.append(f"| {layout}, paper (Table {2 if layout == 'modular' else 4}) | {total} | "
                   f"{fit} | {100 * acc:.2f} % | | | | |")
        for row in rows.values():
            if row["layout"] != layout:
                continue
            test = row["report"]["splits"]["test"]
            ident = row["report"]["identification"]
            out.append(
                f"| {layout}, {row['variant']} | {test['total_rmse_per_sample']:.4f} | "
                f"{test['fit_rmse_per_sample']:.4f} | {100 * test['class_accuracy']:.2f} % | "
                f"{test['total_rmse_per_element']:.4f} / {test['fit_rmse_per_element']:.4f} | "
                f"{100 * ident['e_rel_median']:.2f} % | {ident['fell']}/{ident['trials']} | "
                f"{row['training_s'] / 60:.1f} min |")
        mean = next(r for r in rows.values() if r["layout"] == layout)["report"][
            "mean_predictor_test"]
        out.append(f"| {layout}, predict the training mean | "
                   f"{mean['total_rmse_per_sample']:.4f} | {mean['fit_rmse_per_sample']:.4f} | "
                   f"{100 * mean['class_accuracy']:.2f} % | "
                   f"{mean['total_rmse_per_element']:.4f} / "
                   f"{mean['fit_rmse_per_element']:.4f} | | | |")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    main()
