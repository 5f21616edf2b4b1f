"""Simulation throughput: compiled batch kernel versus the Pinocchio reference path, and
against another revision's kernel side by side.

Run:  .venv/bin/python benchmarks/simulation.py [--trials 2048] [--workers 2]
      .venv/bin/python benchmarks/simulation.py --before REV [--rounds 6]

Measures, in one run on this machine (medians of --repeats runs):
  1. compiled batch: 121 s TIP trials per second (default parameters, and docs/model.md §5
     random parameters, about a fifth of which fall and are aborted);
  2. the Pinocchio reference path (``pinocchio.aba`` every 2 ms step) on one such trial;
and prints their ratio. Compilation is done (or loaded from cache) before timing.

``--before REV``: this checkout's kernel and revision REV's (a temporary git worktree, the
same interpreter) measured in child processes that take turns, ``--rounds`` rounds in the
order now, REV, REV, now, ...: a shared machine's drift falls on both alike. Each child
compiles (or loads) its kernel first, then times its batches (the best of
``--repeats``); reported: each side's median over the rounds and the median of the
rounds' ratios, and how far the two kernels' sway of the same 96 docs/model.md §5 random trials
(TIP and the bent TALOS) lies apart.

Writes the figures to docs/results/simulation.json (``--before``:
simulation_before.json).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from revisions import IMPORT_BEFORE, checkout

from posture_id import __version__, load_body
from posture_id.dec.parameters import ParameterArrays, default_parameters
from posture_id.dec.prior import sample_parameters
from posture_id.fileio import atomic_write_text
from posture_id.simulation import SimulationOptions, simulate, simulate_batch
from posture_id.simulation.reference import simulate_reference

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"

#: A child's measurement: trials/s with default and with random parameters (JSON on stdout).
CHILD = """
import json, os, sys, time
from posture_id import load_body, simulate
from posture_id.dec.parameters import ParameterArrays, default_parameters
from posture_id.dec.prior import sample_parameters
from posture_id.simulation import simulate_batch
import numpy as np
trials, workers, repeats = (int(a) for a in sys.argv[1:4])
body = load_body()
simulate(body)
sets = {"default": ParameterArrays.from_parameters([default_parameters(body)] * trials),
        "random": sample_parameters(body, trials, np.random.default_rng(0))}
rates = {}
for name, params in sets.items():
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        simulate_batch(body, params, workers=workers)
        best = min(best, time.perf_counter() - start)
    rates[name] = trials / best
print(json.dumps(rates))
"""


#: A child's sway of 96 docs/model.md §5 random trials of 121 s on the TIP and the bent TALOS,
#: saved to the .npz named by its argument (the two kernels' answers compared).
SWAY = """
import sys
import numpy as np
from posture_id import load_body
from posture_id.dec.prior import sample_parameters
from posture_id.simulation import simulate_batch
bodies = {"tip": load_body(), "talos": load_body(sys.argv[2])}
out = {}
for name, body in bodies.items():
    batch = simulate_batch(body, sample_parameters(body, 96, np.random.default_rng(0)))
    out[name] = batch.theta
    out[name + "_fell"] = np.isfinite(batch.abort_time)
np.savez(sys.argv[1], **out)
"""
TALOS = Path(__file__).resolve().parents[1] / "urdf" / "talos_tip.urdf"


def same_answers(sides: dict, folder: Path) -> dict:
    """Max |Δθ| (rad) between the two kernels' sway of the same random trials, and whether
    the same trials fell, per body."""
    sway = {}
    for side, (code, env) in sides.items():
        path = folder / f"sway_{len(sway)}.npz"
        done = subprocess.run([sys.executable, "-c", code + SWAY, str(path), str(TALOS)],
                              capture_output=True, text=True, env=env)
        if done.returncode != 0:
            raise SystemExit(f"the sway child failed:\n{done.stderr}")
        sway[side] = np.load(path)
    a, b = sway.values()
    return {body: {"max_abs_difference_rad": float(np.nanmax(np.abs(a[body] - b[body]))),
                   "same_trials_fell": bool(np.array_equal(a[body + "_fell"],
                                                           b[body + "_fell"]))}
            for body in ("tip", "talos")}


def timed(fn, repeats: int = 1):
    """(result, median wall time in s) over ``repeats`` calls."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return out, float(np.median(times))


def machine() -> str:
    return f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores"


def child_rates(code: str, env: dict, trials: int, workers: int, repeats: int) -> dict:
    """Trials/s of one child process running ``code`` + :data:`CHILD`."""
    out = subprocess.run([sys.executable, "-c", code + CHILD, str(trials), str(workers),
                          str(repeats)], capture_output=True, text=True, env=env)
    if out.returncode != 0:
        raise SystemExit(f"the timing child failed:\n{out.stderr}")
    return json.loads(out.stdout.splitlines()[-1])


def side_by_side(args) -> None:
    """This checkout's kernel against ``args.before``'s, rounds taking turns."""
    rounds: list[dict] = []
    with checkout(args.before) as tree:
        sides = {"now": ("", dict(os.environ)),
                 args.before: (IMPORT_BEFORE, {**os.environ, "POSTURE_ID_BEFORE": str(tree)})}
        # both kernels compiled (or loaded) and their answers compared before any timing
        answers = same_answers(sides, tree.parent)
        for body, found in answers.items():
            print(f"{body}: the two kernels' sway of 96 random trials differs by at most "
                  f"{found['max_abs_difference_rad']:.1e} rad; the same trials fall: "
                  f"{found['same_trials_fell']}", flush=True)
        for k in range(args.rounds):
            order = list(sides) if k % 2 == 0 else list(sides)[::-1]
            rounds.append({side: child_rates(*sides[side], args.trials, args.workers,
                                             args.repeats) for side in order})
            print(f"round {k + 1}: " + ", ".join(
                f"{side} {r['default']:.0f}/{r['random']:.0f}" for side, r in rounds[-1].items())
                + " trials/s (default/random parameters)", flush=True)
    summary = {}
    for kind in ("default", "random"):
        now = [r["now"][kind] for r in rounds]
        before = [r[args.before][kind] for r in rounds]
        ratios = [r["now"][kind] / r[args.before][kind] for r in rounds]
        summary[kind] = {
            "now_trials_per_s": statistics.median(now),
            "before_trials_per_s": statistics.median(before),
            "ratio_median": statistics.median(ratios),
            "ratio_min": min(ratios),
        }
        print(f"{kind} parameters: now {summary[kind]['now_trials_per_s']:.0f} trials/s, "
              f"{args.before} {summary[kind]['before_trials_per_s']:.0f} trials/s; now/before "
              f"median {summary[kind]['ratio_median']:.2f}× (lowest round "
              f"{summary[kind]['ratio_min']:.2f}×)")
    results = {"package_version": __version__, "machine": machine(), "before": args.before,
               "workers": args.workers, "trials": args.trials, "repeats": args.repeats,
               "rounds": rounds, "summary": summary, "same_answers": answers}
    out = args.out or RESULTS / "simulation_before.json"
    atomic_write_text(out, json.dumps(results, indent=2) + "\n")
    print(f"wrote {out}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=2048)
    parser.add_argument("--workers", type=int, default=os.cpu_count())
    parser.add_argument("--repeats", type=int, default=3,
                        help="timings are the median (--before: the best) of this many runs")
    parser.add_argument("--before", help="a revision whose kernel runs beside this one")
    parser.add_argument("--rounds", type=int, default=6,
                        help="with --before: rounds of one child each, taking turns")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    if args.before:
        side_by_side(args)
        return

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
        "machine": machine(),
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
    print(f"  docs/model.md §5 random    : {rate_random:8.1f} trials/s ({t_random:.2f} s, "
          f"{results['random_rejected_fraction']:.0%} aborted)")
    print(f"Pinocchio reference, one 121 s trial: {t_reference:.2f} s")
    print(f"ratio compiled/reference: {results['speedup_default_vs_reference']:.0f}× (default), "
          f"{results['speedup_random_vs_reference']:.0f}× (random)")
    print(f"same trial, compiled vs reference: max |Δθ| = {max_diff:.2e} rad")
    out = args.out or RESULTS / "simulation.json"
    atomic_write_text(out, json.dumps(results, indent=2) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
