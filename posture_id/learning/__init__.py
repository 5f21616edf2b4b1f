"""Learning: the CNN identifier (networks, training, checkpoints, evaluation).

The only layer that imports torch (a contract in ``pyproject.toml`` enforces it). It reads
data sets from :mod:`posture_id.datasets` and sits beside :mod:`posture_id.fitting`, which
it never imports.
"""
