"""Studies built on :mod:`posture_id.identify`: the CNN-versus-optimiser benchmark, the
calibration runs, least-squares runs over held-out trials, the demo, and what they share
(one resumable :class:`~.journal.Journal`, one pool of one-thread worker processes).

A layer above ``identify`` (import-linter keeps it so): the identification API never
imports a study.
"""
