"""Simulation throughput: compiled batch kernel versus the Pinocchio reference path.

Run:  .venv/bin/python benchmarks/simulation.py [--trials 2048] [--workers 2]

Measures, in one run on this machine (medians of --repeats runs):
  1. compiled batch: 121 s TIP trials per second (default parameters, and MODEL §5
     random parameters, about half of which fall and are aborted);
  2. the Pinocchio reference path (``pinocchio.aba`` every 2 ms step) on one such trial;
and prints their ratio. Compilation is done (or loaded from cache) before timing.
Writes the figures to benchmarks/results/simulation.json.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import numpy as np

from posture_id import __version__, load_body
from posture_id.dec.parameters import ParameterArrays, default_parameters
from posture_id.dec.prior import sample_parameters
from posture_id.fileio import atomic_write_text
from posture_id.simulation import SimulationOptions, simulate, simulate_batch
from posture_id.simulation.reference import simulate_reference


def timed(fn, repeats: int = 1):
    """(result, median wall time in s) over ``repeats`` calls."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return out, float(np.median(times))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=2048)
    parser.add_argument("--workers", type=int, default=os.cpu_count())
    parser.add_argument("--repeats", type=int, default=3,
                        help="timings are the median of this many runs")
    parser.add_argument("--out", type=Path,
                        default=Path(__file__).parent / "results" / "simulation.json")
    args = parser.parse_args()

    body = load_body()
    options = SimulationOptions()
    simulate(body)  # compile or load the kernel

    defaults = ParameterArrays.from_parameters([default_parameters(body)] * args.trials)
    batch_default, t_default = timed(
        lambda: simulate_batch(body, defaults, options=options, workers=args.workers), args.repeats)
    random_params = sample_parameters(body, args.trials, np.random.default_rng(0))
    batch_random, t_random = timed(
        lambda: simulate_batch(body, random_params, options=options, workers=args.workers),
        args.repeats)

    reference, t_reference = timed(lambda: simulate_reference(body))
    fast_one = batch_default.trial(0)
    max_diff = float(np.abs(fast_one.theta - reference.theta).max())

    rate_default = args.trials / t_default
    rate_random = args.trials / t_random
    results = {
        "package_version": __version__,
        "machine": f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores",
        "workers": args.workers,
        "repeats": args.repeats,
        "trials": args.trials,
        "trial_seconds": 121.0,
        "compiled_default_trials_per_s": rate_default,
        "compiled_random_trials_per_s": rate_random,
        "random_rejected_fraction": float(np.mean(~batch_random.stable)),
        "reference_seconds_per_trial": t_reference,
        "speedup_default_vs_reference": rate_default * t_reference,
        "speedup_random_vs_reference": rate_random * t_reference,
        "max_abs_difference_rad_same_trial": max_diff,
    }
    print(f"compiled batch, {args.trials} × 121 s TIP trials, {args.workers} threads:")
    print(f"  default parameters : {rate_default:8.1f} trials/s ({t_default:.2f} s)")
    print(f"  MODEL §5 random    : {rate_random:8.1f} trials/s ({t_random:.2f} s, "
          f"{results['random_rejected_fraction']:.0%} aborted)")
    print(f"Pinocchio reference, one 121 s trial: {t_reference:.2f} s")
    print(f"ratio compiled/reference: {results['speedup_default_vs_reference']:.0f}× (default), "
          f"{results['speedup_random_vs_reference']:.0f}× (random)")
    print(f"same trial, compiled vs reference: max |Δθ| = {max_diff:.2e} rad")
    atomic_write_text(args.out, json.dumps(results, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
