"""Experiment design: which protocol identifies which DEC parameter, predicted before
anyone stands on the platform (docs/design.md)."""
