"""Identification of recordings: the CNN, least squares and the hybrid behind one entry
point, cohorts and reports. Uses :mod:`posture_id.learning` and :mod:`posture_id.fitting`;
only the command line sits above it."""
