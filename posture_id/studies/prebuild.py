"""Compile at set-up what a new user's first commands would otherwise wait for: the
simulator for bodies of 1, 2 and 3 segments (numba) and the fit's compiled model for them
(CasADi and gcc), into the prebuilt folder (:func:`posture_id.cache.prebuilt_root`), which
every command reads when its cache has nothing yet.

    python -m posture_id.studies.prebuild [FOLDER]     # make's install step runs it

A progress line per step on stderr; about a minute on 2 cores. Safe to run again: what
is there already is loaded, not compiled.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

__all__ = ["prebuild", "SEGMENTS"]

#: The bodies prebuilt for: every segment count the universal network reads.
SEGMENTS = (1, 2, 3)


def prebuild(folder: str | Path | None = None, say=None) -> Path:
    """Fill ``folder`` (default: the prebuilt folder) with the simulator and the fit's
    compiled model for :data:`SEGMENTS`; its path."""
    from posture_id.cache import prebuilt_root

    say = say or (lambda line: print(line, file=sys.stderr, flush=True))
    root = Path(folder) if folder is not None else prebuilt_root()
    if root is None:
        raise SystemExit("POSTURE_ID_PREBUILT is 'none': nothing to prebuild into")
    os.environ["POSTURE_ID_CACHE"] = str(root)  # this process compiles into it,
    os.environ["POSTURE_ID_PREBUILT"] = "none"  # whatever another prebuilt folder holds
    from posture_id.bodies.anthropometry import winter_body_file
    from posture_id.bodies.body import load_body
    from posture_id.fitting.options import FitOptions
    from posture_id.fitting.problem import FitProblem
    from posture_id.simulation import simulate
    from posture_id.simulation.stimulus import prts

    for n in SEGMENTS:
        say(f"posture-id set-up: compiling the simulator and the fit model for {n} "
            f"segment(s) into {root} (once)")
        start = time.perf_counter()
        body = load_body(winter_body_file(1.75, 70.0, n))  # any body of n segments
        simulate(body, stimulus=prts(cycles=1, states=80))
        problem = FitProblem.get(body, 101, FitOptions())
        say(f"posture-id set-up: {n} segment(s) done, fit model {problem.backend} "
            f"({time.perf_counter() - start:.0f} s)")
    return root


if __name__ == "__main__":
    prebuild(sys.argv[1] if len(sys.argv) > 1 else None)
