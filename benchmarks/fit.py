"""Least-squares identification benchmark (CasADi baseline).

Run:  .venv/bin/python benchmarks/fit.py [--recordings 10] [--exhaustive 3]

Simulates ``--recordings`` 121 s TIP recordings with docs/model.md §5 random parameters (stable
ones), and fits each
  1. from the defaults,
  2. from the true values perturbed by 30 % (each continuous parameter × (1 ± 0.3), the
     true classes: what a good CNN guess looks like),
with the default scheme (relaxed classes, then an exact polish), and the first
``--exhaustive`` recordings also with every class combination fitted (2^N fits), to check
the relaxed scheme's class choice against the honest search. Reports per-parameter errors
(in normalised units, |p̃_fit − p̃_true|, and relative |p_fit/p_true − 1|), class accuracy,
iterations and wall time per recording; writes docs/results/fit.json.
The compiled CasADi model is built (or loaded from its cache) before timing.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from posture_id import load_body, simulate
from posture_id.dec.parameters import DecParameters, default_parameters, normalise
from posture_id.dec.prior import sample_parameters
from posture_id.fileio import atomic_write_text
from posture_id.fitting import ExhaustiveClasses, FitOptions, FitProblem, fit_recording
from posture_id.recording import Recording
from posture_id.trials import prepare_trial

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"

FIELDS = ("kp", "ki", "kd", "delay_s")


def recordings(body, count: int, seed: int):
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < count:
        truth = sample_parameters(body, 1, rng).trial(0, body.joint_names)
        result = simulate(body, truth)
        if result.stable:
            out.append((truth, Recording(result.time, result.tilt, result.theta,
                                         result.segments)))
    return out, rng


def perturbed(truth: DecParameters, rng) -> DecParameters:
    params = truth
    defaults = {j: truth[j] for j in truth.joints}
    for joint in truth.joints:
        factors = 1 + 0.3 * rng.choice([-1.0, 1.0], size=4)
        params = params.replace(joint, **{f: getattr(defaults[joint], f) * k
                                          for f, k in zip(FIELDS, factors, strict=True)})
    return params


def summarise(fit, truth, body) -> dict:
    defaults = default_parameters(body)
    t_norm = normalise(truth, defaults)
    rel = np.column_stack([fit.parameters.array(f) / truth.array(f) - 1 for f in FIELDS])
    return {
        "abs_error_normalised": np.abs(fit.normalised[:, :4] - t_norm[:, :4]).tolist(),
        "rel_error": rel.tolist(),
        "poorly_determined": fit.poorly_determined.tolist(),
        "classes_correct": int(np.sum(np.sign(fit.normalised[:, 4]) == t_norm[:, 4])),
        "converged": fit.converged,
        "iterations": fit.iterations,
        "wall_time_s": fit.wall_time_s,
        "rms_deg": fit.rms_deg,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--recordings", type=int, default=10)
    parser.add_argument("--exhaustive", type=int, default=3)
    parser.add_argument("--seed", type=int, default=2024)
    parser.add_argument("--out", type=Path,
                        default=RESULTS / "fit.json")
    args = parser.parse_args()
    body = load_body()
    data, rng = recordings(body, args.recordings, args.seed)
    exhaustive = FitOptions(classes=ExhaustiveClasses())
    # compile or load; the exhaustive fit shares the problem (same compiled code)
    problem = FitProblem.get(body, len(data[0][1].time), FitOptions(), print)
    rows = {"defaults": [], "truth_30pct": [], "exhaustive": []}
    for i, (truth, rec) in enumerate(data):
        for start, init in (("defaults", None), ("truth_30pct", perturbed(truth, rng))):
            t0 = time.perf_counter()
            fit = fit_recording(prepare_trial(rec), body, init, problem=problem)
            row = summarise(fit, truth, body)
            rows[start].append(row)
            print(f"recording {i} from {start:<11}: {time.perf_counter() - t0:5.1f} s, "
                  f"{row['iterations']:3d} iterations, classes {row['classes_correct']}/3, "
                  f"max rel. error of determined parameters "
                  f"{np.max(np.where(fit.poorly_determined, 0, np.abs(row['rel_error']))):.2e}")
        if i < args.exhaustive:
            fit = fit_recording(prepare_trial(rec), body, None, exhaustive, problem=problem)
            row = summarise(fit, truth, body)
            rows["exhaustive"].append(row)
            print(f"recording {i} exhaustive  : {fit.wall_time_s:5.1f} s, classes "
                  f"{row['classes_correct']}/3 (relaxed: "
                  f"{rows['defaults'][-1]['classes_correct']}/3)")

    table = {}
    for start in ("defaults", "truth_30pct", "exhaustive"):
        if not rows[start]:
            continue
        err = np.array([r["abs_error_normalised"] for r in rows[start]])  # (R, N, 4)
        rel = np.abs(np.array([r["rel_error"] for r in rows[start]]))
        table[start] = {
            "recordings": len(rows[start]),
            "mean_abs_error_normalised": err.mean(axis=0).tolist(),
            "max_rel_error": rel.max(axis=0).tolist(),
            "median_rel_error": np.median(rel, axis=0).tolist(),
            "class_accuracy": float(np.mean([r["classes_correct"] / 3 for r in rows[start]])),
            "converged": int(sum(r["converged"] for r in rows[start])),
            "iterations_mean": float(np.mean([r["iterations"] for r in rows[start]])),
            "wall_time_s_mean": float(np.mean([r["wall_time_s"] for r in rows[start]])),
            "wall_time_s_max": float(np.max([r["wall_time_s"] for r in rows[start]])),
        }
    print()
    print(f"{'start':<12}{'n':>3}{'classes':>9}{'iters':>7}{'mean s':>8}{'max s':>7}"
          f"   max relative error per module (Kp, Ki, Kd, Δ)")
    for start, t in table.items():
        worst = "; ".join(
            ",".join(f"{100 * e:.2g}%" for e in module) for module in t["max_rel_error"])
        print(f"{start:<12}{t['recordings']:>3}{100 * t['class_accuracy']:>8.1f}%"
              f"{t['iterations_mean']:>7.1f}{t['wall_time_s_mean']:>8.1f}"
              f"{t['wall_time_s_max']:>7.1f}   {worst}")
    atomic_write_text(args.out, json.dumps({"summary": table, "fits": rows}, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
