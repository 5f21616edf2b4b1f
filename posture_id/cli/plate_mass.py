"""The subject's mass from a force plate's load columns, on the command line: the flags
``--load-columns`` and ``--load-units`` of ``body --mass-from``, ``frf --height-m`` and
``study`` (a manifest row with a height and no mass); :mod:`posture_id.force_plate.load`."""

from __future__ import annotations

import argparse

from posture_id.errors import PostureIdError
from posture_id.force_plate.load import LoadColumns, LoadUnit

__all__ = ["add_load_arguments", "load_columns_from_args"]


def add_load_arguments(parser: argparse.ArgumentParser, uses: str) -> None:
    """--load-columns and --load-units; ``uses``: what they are for, in the help."""
    group = parser.add_argument_group("the subject's mass from the plate", uses)
    group.add_argument("--load-columns", nargs="+", metavar="NAME",
                       help="the plate's load cells (their sum is the load), or its vertical "
                            "force: the mass is their median while the platform rests level")
    group.add_argument("--load-units", choices=[u.value for u in LoadUnit],
                       help="unit of the load columns: kg (load cells in kilograms) or N "
                            "(default: their headers', e.g. 'Capteur (Kg)')")


def load_columns_from_args(args: argparse.Namespace) -> LoadColumns | None:
    """The load columns the flags name, or None; --load-units alone refused."""
    names = getattr(args, "load_columns", None)
    unit = getattr(args, "load_units", None)
    if not names:
        if unit is not None:
            raise PostureIdError("--load-units goes with --load-columns (the plate's load)")
        return None
    return LoadColumns(tuple(names), None if unit is None else LoadUnit(unit))
