"""What the compiled CasADi model costs a cohort whose subjects each have their own body.

Run:  .venv/bin/python benchmarks/cohort_compile.py [--subjects 10] [--before REV]

Makes ``--subjects`` Winter 3-segment bodies of different heights (1.50–1.95 m) and masses
(50–100 kg) with ``posture-id body``, records each subject once with ``posture-id simulate``
(the body's default parameters, 80-state PRTS × 2 = 40 s, 0.02° sensor noise, one seed per
subject), then, each on an empty compile cache (``POSTURE_ID_CACHE``):

  1. the whole cohort by least squares: ``posture-id identify 'recordings/*.csv' --bodies
     bodies --method fit``, wall time, and the compiled libraries the cache holds after it;
  2. the first hybrid of a 121 s TIP recording: ``posture-id identify --method hybrid``.

Both for this checkout and for revision ``--before`` (default: the last commit whose
compiled model embedded the body's constants), checked out into a temporary git worktree
and run with the same interpreter, side by side in this one run. Writes
docs/results/cohort_compile.json.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from cold_start import CLI, CLI_BEFORE

from posture_id import __version__
from posture_id.fileio import atomic_write_text

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"

ROOT = Path(__file__).resolve().parents[1]
#: The last commit whose compiled model held the body's constants.
BEFORE = "52a9ef7"


def run(cmd: list[str], env: dict) -> float:
    """Wall time of ``cmd`` (s); exits with its output when it fails."""
    start = time.perf_counter()
    out = subprocess.run(cmd, capture_output=True, text=True, env=env)
    elapsed = time.perf_counter() - start
    if out.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({out.returncode}):\n{out.stderr[-3000:]}")
    return elapsed


def make_cohort(cli: list[str], folder: Path, subjects: int) -> None:
    """Bodies in folder/bodies, one recording each in folder/recordings (same names)."""
    (folder / "bodies").mkdir(parents=True)
    (folder / "recordings").mkdir()
    env = dict(os.environ)
    for i in range(subjects):
        share = i / max(subjects - 1, 1)
        height, mass = 1.50 + 0.45 * share, 50.0 + 50.0 * ((i * 7) % subjects) / subjects
        name = f"subject_{i:02d}"
        body = folder / "bodies" / f"{name}.urdf"
        run([*cli, "body", "--height-m", f"{height:.3f}", "--mass-kg", f"{mass:.1f}",
             "--segments", "3", "--out", str(body)], env)
        run([*cli, "simulate", "--body", str(body), "--states", "80", "--cycles", "2",
             "--sensor-noise-deg", "0.02", "--seed", str(i),
             "--out", str(folder / "recordings" / f"{name}.csv")], env)
    run([*cli, "simulate", "--sensor-noise-deg", "0.02", "--seed", "99",
         "--out", str(folder / "tip.csv")], env)


def measure(cli: list[str], folder: Path, tag: str, env: dict) -> dict:
    """The cohort and the first hybrid, each on an empty compile cache."""
    cache = folder / f"cache_cohort_{tag}"
    cohort_s = run([*cli, "identify", str(folder / "recordings" / "*.csv"), "--bodies",
                    str(folder / "bodies"), "--method", "fit",
                    "--out", str(folder / f"cohort_{tag}")],
                   {**env, "POSTURE_ID_CACHE": str(cache)})
    libraries = len(list((cache / "casadi").glob("*.so")))
    cache = folder / f"cache_hybrid_{tag}"
    hybrid_s = run([*cli, "identify", str(folder / "tip.csv"), "--method", "hybrid",
                    "--out", str(folder / f"hybrid_{tag}.json")],
                   {**env, "POSTURE_ID_CACHE": str(cache)})
    print(f"{tag}: cohort {cohort_s:.0f} s ({libraries} compiled libraries), "
          f"first hybrid {hybrid_s:.0f} s", flush=True)
    return {"cohort_fit_wall_s": cohort_s, "compiled_libraries": libraries,
            "first_hybrid_wall_s": hybrid_s}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", type=int, default=10)
    parser.add_argument("--before", default=BEFORE, help="revision to compare with")
    parser.add_argument("--out", type=Path,
                        default=RESULTS / "cohort_compile.json")
    args = parser.parse_args()
    cli = [sys.executable, "-c", CLI]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        make_cohort(cli, folder, args.subjects)
        after = measure(cli, folder, "this_checkout", dict(os.environ))
        worktree = folder / "before"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(worktree),
                        args.before], check=True, capture_output=True)
        try:
            env = {**os.environ, "POSTURE_ID_BEFORE": str(worktree)}
            before = measure([sys.executable, "-c", CLI_BEFORE], folder, args.before, env)
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force",
                            str(worktree)], check=True, capture_output=True)
    ratio = after["cohort_fit_wall_s"] / before["cohort_fit_wall_s"]
    print(f"the cohort takes {ratio:.2f}× as long as at {args.before}")
    results = {
        "package_version": __version__,
        "machine": {"processor": platform.processor() or platform.machine(),
                    "cpus": os.cpu_count(), "python": platform.python_version()},
        "subjects": args.subjects,
        "recording": "Winter 3-segment bodies, 80-state PRTS x2 (40 s), 0.02 deg noise",
        "this_checkout": after,
        args.before: before,
        "cohort_ratio": ratio,
        "first_hybrid_ratio": after["first_hybrid_wall_s"] / before["first_hybrid_wall_s"],
    }
    atomic_write_text(args.out, json.dumps(results, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
