"""``posture-id network ARCHITECTURE JOB``: every network's training set, training,
calibration and evaluation, one family of commands by architecture.

- ``network universal data | train | calibrate | ensemble | typicality | table``: the
  universal network (:mod:`.universal`);
- ``network cnn data | train | calibrate | evaluate | benchmark``: the paper's spectrogram
  CNN, a specialist of one body (:mod:`.dataset`, :mod:`.train`, :mod:`.calibration`,
  :mod:`.evaluate`, :mod:`.benchmark`).

The commands they were before (``universal``, ``dataset``, ``train``, ``calibration``,
``evaluate``, ``benchmark``) still work, each with a one-line notice of its new spelling
(:mod:`.renamed`).
"""

from __future__ import annotations

from posture_id.cli import benchmark, calibration, dataset, evaluate, train, universal

__all__ = ["add_parser", "ARCHITECTURES"]

#: The architectures the family names, and their jobs (in the order the help lists them).
ARCHITECTURES = {
    "universal": ("data", "train", "calibrate", "ensemble", "typicality", "table"),
    "cnn": ("data", "train", "calibrate", "evaluate", "benchmark"),
}


def add_parser(sub) -> None:
    p = sub.add_parser("network", help="networks: training sets, training, calibration and "
                       "evaluation (universal | cnn)")
    kinds = p.add_subparsers(dest="architecture", required=True, parser_class=type(p),
                             metavar="ARCHITECTURE")
    universal.add_parser(kinds, "universal")
    cnn = kinds.add_parser("cnn", help="the paper's spectrogram CNN, a specialist of one body")
    jobs = cnn.add_subparsers(dest="cnn_command", required=True, parser_class=type(p))
    for module in (dataset, train, calibration, evaluate, benchmark):
        module.add_parser(jobs)
