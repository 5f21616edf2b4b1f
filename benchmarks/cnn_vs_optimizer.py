"""The CNN against the optimiser: ``posture-id network cnn benchmark`` as a script.

Run:  .venv/bin/python benchmarks/cnn_vs_optimizer.py --out docs/results/benchmark
          [--trials 24] [--sensor-noise-deg 0.05] [--people-like] [--methods ...]

See :mod:`posture_id.studies.benchmark` and docs/benchmark.md; writes
``cnn_vs_optimizer.{md,json,png}`` into ``--out``.
"""

import sys

from posture_id.cli import main

if __name__ == "__main__":
    sys.exit(main(["benchmark", *sys.argv[1:]]))
