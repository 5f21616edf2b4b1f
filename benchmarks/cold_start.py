"""Cold start: what a new process pays before it does any work.

Run:  .venv/bin/python benchmarks/cold_start.py [--before REV] [--repeats 3]
      .venv/bin/python benchmarks/cold_start.py --first-session [--before REV]

``--first-session``: a new user's first commands, each on an empty cache folder
(``POSTURE_ID_CACHE`` a new folder: no compiled simulator, no compiled fit model) and then
again on the cache that run filled, for this checkout and for revision ``--before``
(default: the last commit before issue 44's work), side by side in one run: ``posture-id
simulate`` (121 s TIP), ``posture-id identify tip_subject.csv`` (auto) and ``posture-id
identify tip_subject.csv --method hybrid``. Writes docs/results/first_session.json
and docs/results/first_session.md.

Without it:

With every cache already filled (one warm-up run of each), it measures in fresh child
processes (medians of ``--repeats``):
  1. the first simulation in a new process (``simulate`` of one 121 s TIP trial, the
     call alone; import and URDF loading reported beside it);
  2. ``posture-id simulate`` of one trial, wall time of the whole command;
  3. ``posture-id identify --method cnn`` of that recording (the bundled model), whole
     command;
  4. ``posture-id fit`` of a 121 s TIP recording, wall time of the whole command;
and 2, 3 and 4 again for revision ``--before`` (default: the last commit before the package
layout), checked out into a temporary git worktree and run with the same interpreter,
side by side in this one run.
Writes docs/results/cold_start.json.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from revisions import IMPORT_BEFORE, ROOT, checkout

from posture_id import __version__
from posture_id.fileio import atomic_write_text

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"

#: The last commit of the flat layout (before the package layout).
BEFORE = "cc63128"
#: The last commit before issue 44's work (length buckets, -Og, the length-free model).
FIRST_SESSION_BEFORE = "f15f0ca"
#: The example recording the first-session commands identify.
EXAMPLE = ROOT / "posture_id" / "studies" / "examples" / "tip_subject.csv"
#: (what, command line) of a new user's first commands.
FIRST_SESSION = (
    ("posture-id simulate (121 s TIP)", ["simulate", "--out", "{tmp}/trial.csv"]),
    ("posture-id identify tip_subject.csv (auto)",
     ["identify", str(EXAMPLE), "--out", "{tmp}/auto.json"]),
    ("posture-id identify tip_subject.csv --method hybrid",
     ["identify", str(EXAMPLE), "--method", "hybrid", "--out", "{tmp}/hybrid.json"]),
)

FIRST_SIMULATION = """
import time
t0 = time.perf_counter()
from posture_id import load_body, simulate
body = load_body()
t1 = time.perf_counter()
simulate(body)
t2 = time.perf_counter()
print(t1 - t0, t2 - t1)
"""
#: Runs the command line of this checkout.
CLI = "import sys; from posture_id.cli import main; sys.exit(main(sys.argv[1:]))"
#: Runs the command line of the checkout in $POSTURE_ID_BEFORE: the editable install's
#: import hook is removed first, so that the older tree's modules are the ones imported.
CLI_BEFORE = IMPORT_BEFORE + "from posture_id.cli import main; sys.exit(main(sys.argv[1:]))"


def wall(cmd: list[str], env: dict | None = None) -> float:
    start = time.perf_counter()
    out = subprocess.run(cmd, capture_output=True, text=True, env=env)
    elapsed = time.perf_counter() - start
    if out.returncode not in (0, 1):
        raise SystemExit(f"{' '.join(cmd)} failed:\n{out.stderr}")
    return elapsed


def median_wall(cmd: list[str], repeats: int, env: dict | None = None) -> float:
    wall(cmd, env)  # fill the caches
    return statistics.median(wall(cmd, env) for _ in range(repeats))


def first_simulation(repeats: int) -> tuple[float, float]:
    cmd = [sys.executable, "-c", FIRST_SIMULATION]
    subprocess.run(cmd, check=True, capture_output=True)  # fill the kernel cache
    runs = []
    for _ in range(repeats):
        out = subprocess.run(cmd, check=True, capture_output=True, text=True)
        runs.append(tuple(float(x) for x in out.stdout.split()))
    return (statistics.median(r[0] for r in runs), statistics.median(r[1] for r in runs))


def first_session_of(cli: list[str], env: dict, tmp: Path) -> dict:
    """Each first-session command on a new empty cache folder, then again on it: wall s."""
    subprocess.run([*cli, "--help"], capture_output=True, env=env)  # byte-compile first
    rows = {}
    for k, (what, argv) in enumerate(FIRST_SESSION):
        cache = tmp / f"cache-{k}"
        run_env = {**env, "POSTURE_ID_CACHE": str(cache)}
        command = [*cli, *(a.format(tmp=tmp) for a in argv)]
        rows[what] = {"first_s": wall(command, run_env), "again_s": wall(command, run_env)}
        print(f"{what}: first {rows[what]['first_s']:.1f} s, again "
              f"{rows[what]['again_s']:.1f} s", flush=True)
    return rows


def first_session(before: str) -> None:
    """The ``--first-session`` table, this checkout beside ``before``: this checkout with
    no set-up compile (``POSTURE_ID_PREBUILT=none``) and after the set-up's (a prebuilt
    folder made by ``python -m posture_id.studies.prebuild``, timed)."""
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "posture_id.studies.prebuild",
                        str(tmp / "prebuilt")], check=True, capture_output=True)
        setup_s = time.perf_counter() - start
        print(f"set-up compile (python -m posture_id.studies.prebuild): {setup_s:.1f} s")
        runs = {}
        for label, prebuilt in (("now", "none"), ("now, after set-up", str(tmp / "prebuilt"))):
            (tmp / label).mkdir()
            runs[label] = first_session_of(
                [sys.executable, "-c", CLI],
                {**os.environ, "POSTURE_ID_PREBUILT": prebuilt}, tmp / label)
        with checkout(before) as worktree:
            (tmp / "before").mkdir()
            env = {**os.environ, "POSTURE_ID_BEFORE": str(worktree)}
            runs[before] = first_session_of([sys.executable, "-c", CLI_BEFORE], env,
                                            tmp / "before")
    results = {"package_version": __version__, "before": before, "setup_compile_s": setup_s,
               "machine": {"processor": platform.processor() or platform.machine(),
                           "cpus": os.cpu_count(), "python": platform.python_version()},
               "rows": {what: {label: run[what] for label, run in runs.items()}
                        for what in runs["now"]}}
    out = RESULTS / "first_session.json"
    atomic_write_text(out, json.dumps(results, indent=2) + "\n")
    lines = [
        "# A new user's first commands: an empty cache, then again",
        "",
        f"Made by `.venv/bin/python benchmarks/cold_start.py --first-session --before "
        f"{before}`: each command on a new empty cache folder (`POSTURE_ID_CACHE`: no "
        "compiled simulator, no compiled fit model), then again on the cache it filled; "
        f"this checkout beside {before} (the last commit before issue 44's work), with no "
        "set-up compile (`POSTURE_ID_PREBUILT=none`) and after the set-up's "
        f"(`python -m posture_id.studies.prebuild`, which `make` runs: {setup_s:.0f} s "
        f"here); one run on this machine ({os.cpu_count()} cores), wall seconds of the "
        "whole command, ratios against " + before + ".",
        "",
        f"| command | first, {before} | first, now (ratio) | first, now after set-up "
        f"(ratio) | again, {before} | again, now (ratio) |",
        "|---|---|---|---|---|---|",
    ]
    for what, row in results["rows"].items():
        b, a, p = row[before], row["now"], row["now, after set-up"]
        lines.append(
            f"| `{what}` | {b['first_s']:.1f} s | {a['first_s']:.1f} s "
            f"({a['first_s'] / b['first_s']:.2f}) | {p['first_s']:.1f} s "
            f"({p['first_s'] / b['first_s']:.2f}) | {b['again_s']:.1f} s | "
            f"{a['again_s']:.1f} s ({a['again_s'] / b['again_s']:.2f}) |")
    report = ROOT / "docs" / "results" / "first_session.md"
    atomic_write_text(report, "\n".join(lines) + "\n")
    print("\n".join(lines))
    print(f"wrote {out} and {report}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", help="revision to compare with (default: "
                                         f"{BEFORE}; with --first-session {FIRST_SESSION_BEFORE})")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--first-session", action="store_true",
                        help="a new user's first commands on an empty cache, then again")
    parser.add_argument("--out", type=Path,
                        default=RESULTS / "cold_start.json")
    args = parser.parse_args()
    if args.first_session:
        first_session(args.before or FIRST_SESSION_BEFORE)
        return
    args.before = args.before or BEFORE

    import_s, simulate_s = first_simulation(args.repeats)
    print(f"first simulation in a new process: {simulate_s:.3f} s "
          f"(import and URDF load before it: {import_s:.3f} s)")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        cli = [sys.executable, "-c", CLI]
        sim_s = median_wall([*cli, "simulate", "--out", str(tmp / "trial.csv")], args.repeats)
        print(f"posture-id simulate, one 121 s trial: {sim_s:.2f} s wall")

        import numpy as np

        from posture_id import load_body, sample_parameters, simulate

        body = load_body()
        rng = np.random.default_rng(11)
        while True:
            truth = sample_parameters(body, 1, rng).trial(0, body.joint_names)
            trial = simulate(body, truth)
            if trial.stable:
                break
        recording = tmp / "recording.csv"
        trial.to_csv(recording)
        identify_s = median_wall([*cli, "identify", str(recording), "--method", "cnn", "--out",
                                  str(tmp / "cnn.json")], args.repeats)
        print(f"posture-id identify --method cnn, one recording: {identify_s:.2f} s wall")
        fit_args = ["fit", str(recording), "--out", str(tmp / "fit.json")]
        after_s = median_wall([*cli, *fit_args], args.repeats)
        print(f"posture-id fit, 121 s TIP recording, this checkout: {after_s:.1f} s wall")

        with checkout(args.before) as worktree:
            env = {**os.environ, "POSTURE_ID_BEFORE": str(worktree)}
            before_s = median_wall([sys.executable, "-c", CLI_BEFORE, *fit_args],
                                   args.repeats, env)
            sim_before_s = median_wall([sys.executable, "-c", CLI_BEFORE, "simulate", "--out",
                                        str(tmp / "trial_before.csv")], args.repeats, env)
            identify_before_s = median_wall(
                [sys.executable, "-c", CLI_BEFORE, "identify", str(recording), "--method",
                 "cnn", "--out", str(tmp / "cnn_before.json")], args.repeats, env)
        print(f"posture-id fit, same recording, {args.before}: {before_s:.1f} s wall "
              f"(this checkout takes {after_s / before_s:.2f}× as long)")
        print(f"posture-id simulate, {args.before}: {sim_before_s:.2f} s wall "
              f"(this checkout takes {sim_s / sim_before_s:.2f}× as long)")
        print(f"posture-id identify --method cnn, {args.before}: {identify_before_s:.2f} s "
              f"wall (this checkout takes {identify_s / identify_before_s:.2f}× as long)")

    results = {
        "package_version": __version__,
        "machine": {"processor": platform.processor() or platform.machine(),
                    "cpus": os.cpu_count(), "python": platform.python_version()},
        "repeats": args.repeats,
        "first_simulation_s": simulate_s,
        "import_and_load_s": import_s,
        "cli_simulate_wall_s": {"this_checkout": sim_s, args.before: sim_before_s,
                                "ratio": sim_s / sim_before_s},
        "cli_identify_cnn_wall_s": {"this_checkout": identify_s,
                                    args.before: identify_before_s,
                                    "ratio": identify_s / identify_before_s},
        "cli_fit_wall_s": {"this_checkout": after_s, args.before: before_s,
                           "ratio": after_s / before_s},
    }
    atomic_write_text(args.out, json.dumps(results, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
