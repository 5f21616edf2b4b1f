"""posture_id: identify DEC posture-control parameters from body sway on a tilting support."""

__version__ = "0.1.0"
