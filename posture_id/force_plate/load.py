"""The subject's mass from the plate: the load its cells (or its vertical force) carry
while the platform rests level.

A posturography plate stands on load cells; their sum is the weight on the plate, the
subject's (the plate's own tare taken out by the system). A study that gives no mass has
it in every trial: the median of the cells' sum over the samples where the platform rests
at its first level (all samples where the file has no tilt column), in kg (cells calibrated
in kilograms, as ``Capteur (Kg)``) or N (a force, divided by g). :func:`standing_mass`
reads it; ``posture-id body --mass-from TRIAL``, ``frf --height-m`` and a manifest row
with a height and no mass use it (docs/force_plates.md).
"""

from __future__ import annotations

import enum
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from posture_id.errors import RecordingError
from posture_id.text_table import read_text_table

__all__ = ["LoadUnit", "LoadColumns", "PlateMass", "standing_mass", "STILL_DEG"]

#: The platform rests where its tilt stays within this of its first level, deg.
STILL_DEG = 0.05
#: A person's mass, kg.
_PERSON_KG = (20.0, 250.0)
_GRAVITY = 9.81
_STATED = re.compile(r"[\[(]\s*(kg|n)\s*[\])]", re.IGNORECASE)


class LoadUnit(enum.Enum):
    """The unit of a plate's load columns."""

    KG = "kg"
    N = "N"


@dataclass(frozen=True)
class LoadColumns:
    """The columns whose sum is the load on the plate (its load cells, or one vertical
    force), and their unit (None: the one their headers state, ``(Kg)`` or ``[N]``
    anywhere in the name)."""

    columns: tuple[str, ...]
    unit: LoadUnit | None = None

    def __post_init__(self) -> None:
        if not self.columns or len(set(self.columns)) != len(self.columns):
            raise RecordingError(f"load columns: name each column once, got "
                                 f"{', '.join(map(repr, self.columns)) or 'none'}")
        if self.unit is not None and not isinstance(self.unit, LoadUnit):
            raise RecordingError(f"load unit must be a LoadUnit or None, got {self.unit!r}")


@dataclass(frozen=True)
class PlateMass:
    """The subject's mass read from one trial.

    Attributes:
        mass_kg: the median load over the level samples, kg. samples: how many.
        spread_kg: the load's interquartile range over them, kg (the subject's sway and
        shifts). unit: of the columns. notice: one line saying where it came from.
    """

    mass_kg: float
    samples: int
    spread_kg: float
    unit: LoadUnit
    notice: str


def _unit(path: Path, table, load: LoadColumns) -> LoadUnit:
    stated = set()
    for name in load.columns:
        other = table.unit_of(name)
        if other is not None and other.lower() not in ("kg", "n"):
            raise RecordingError(f"{path}: column {name!r} is in {other} by its header: not a "
                                 "load (load cells in kg, or a force in N)")
        found = _STATED.search(table.header[table.index(name)])
        if found:
            stated.add(LoadUnit.KG if found[1].lower() == "kg" else LoadUnit.N)
    if len(stated) > 1:
        raise RecordingError(f"{path}: the load columns' headers state both kg and N: name "
                             "columns of one unit")
    if stated and load.unit is not None and load.unit not in stated:
        raise RecordingError(f"{path}: the load columns are in {stated.pop().value} by their "
                             f"headers, not {load.unit.value} (--load-units)")
    if stated:
        return stated.pop()
    if load.unit is None:
        raise RecordingError(f"{path}: the load columns' headers state no unit: give it "
                             "(--load-units kg for load cells in kilograms, N for a force)")
    return load.unit


def standing_mass(path: str | Path, load: LoadColumns, tilt_column: str | None = None
                  ) -> PlateMass:
    """The subject's mass from a plate's trial (the module doc).

    Args:
        path: the trial's file (any text table :func:`~posture_id.text_table.
            read_text_table` reads).
        load: the load columns and their unit.
        tilt_column: the platform's tilt column (degrees); None: every sample counts.
    Raises:
        RecordingError: naming the file and the column: missing, no unit, a sum that is
            not a person's mass (another unit? a column that is not a load?), no level
            samples.
    """
    path = Path(path)
    table = read_text_table(path, RecordingError, "force-plate recording")
    table.require([*load.columns, *([tilt_column] if tilt_column else [])])
    unit = _unit(path, table, load)
    total = np.sum([table.column(c) for c in load.columns], axis=0)
    kg = total if unit is LoadUnit.KG else total / _GRAVITY
    still = np.ones(len(kg), dtype=bool)
    where = "every sample"
    if tilt_column:
        tilt = table.column(tilt_column)
        still = np.abs(tilt - tilt[0]) <= STILL_DEG
        where = (f"the {int(still.sum())} samples where '{tilt_column}' rests level (within "
                 f"{STILL_DEG:g}° of its first value)")
    if not still.any():
        raise RecordingError(f"{path}: no sample where the platform rests level: the mass is "
                             "read from a level stretch")
    mass = float(np.median(kg[still]))
    low, high = _PERSON_KG
    named = ", ".join(repr(c) for c in load.columns)
    if not (math.isfinite(mass) and low <= mass <= high):
        raise RecordingError(f"{path}: the load columns {named} sum to {mass:.4g} kg (read in "
                             f"{unit.value}), not a person's {low:g}–{high:g} kg: another unit, "
                             "or columns that are not the plate's load?")
    q1, q3 = np.percentile(kg[still], [25, 75])
    notice = (f"{path}: the subject's mass is {mass:.4g} kg, the median sum of {named} "
              f"({unit.value}) over {where} (interquartile range {q3 - q1:.2g} kg)")
    return PlateMass(mass, int(still.sum()), float(q3 - q1), unit, notice)
