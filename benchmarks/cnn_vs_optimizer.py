"""The CNN against the optimiser: ``posture-id benchmark`` as a script.

Run:  .venv/bin/python benchmarks/cnn_vs_optimizer.py [--trials 50] [--noise-deg 0 0.01 0.05]

See :mod:`posture_id.identify.benchmark`; writes docs/results/cnn_vs_optimizer.{md,json,png}.
"""

import sys

from posture_id.cli import main

if __name__ == "__main__":
    sys.exit(main(["benchmark", *sys.argv[1:]]))
