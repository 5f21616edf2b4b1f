"""A force plate's file read as a recording: its COP turned into the body-COM sway angle
(:func:`~posture_id.force_plate.cop.com_angle_from_cop`) of the subject's body taken as one
segment (:func:`~posture_id.bodies.one_segment.one_segment_body`)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from posture_id.bodies.body import Body
from posture_id.bodies.one_segment import one_segment_body
from posture_id.errors import RecordingError
from posture_id.force_plate.cop import BodyLoad, CopOptions, CopUnit, com_angle_from_cop
from posture_id.recording import (
    AngleUnit,
    Recording,
    RecordingColumns,
    TimeUnit,
    lab_columns,
    on_even_time,
)
from posture_id.text_table import read_text_table

__all__ = ["ForcePlateColumns", "read_force_plate", "FORCE_UNITS_N"]

#: The normal force's units a header may state, and their factor to newtons.
FORCE_UNITS_N = {"N": 1.0, "n": 1.0, "kN": 1e3, "kn": 1e3}


@dataclass(frozen=True)
class ForcePlateColumns:
    """Which columns of a force plate's file hold what (a column named with or without
    its header's unit), and how the COP is read.

    Attributes:
        cop: the COP column (forward along the plate).
        time, tilt, unit, time_unit, sample_rate_hz: as :class:`~posture_id.recording.
            RecordingColumns`'s (the tilt's unit; None: the header's, else degrees).
        force: the plate's normal-force column (N, or kN by its header), or None: the
            static load m·g·cos α.
        cop_unit: of the COP column; None: the header's (``[mm]``, ``[cm]``, ``[m]``),
            else mm.
        ankle_height_m: the ankle axis above the plate's surface, m.
        cop_sign: −1 when the plate's COP axis points backward.
    """

    cop: str
    time: str | None = "time_s"
    tilt: str | None = "tilt_deg"
    force: str | None = None
    unit: AngleUnit | None = None
    time_unit: TimeUnit | None = None
    sample_rate_hz: float | None = None
    cop_unit: CopUnit | None = None
    ankle_height_m: float = 0.0
    cop_sign: int = 1

    def __post_init__(self) -> None:
        named = [c for c in (self.time, self.tilt, self.cop, self.force) if c is not None]
        twice = sorted({c for c in named if named.count(c) > 1})
        if twice:
            raise RecordingError(f"column {', '.join(repr(c) for c in twice)} is named more "
                                 "than once (time, tilt, COP and force columns are each their "
                                 "own)")
        if self.cop_unit is not None and not isinstance(self.cop_unit, CopUnit):
            raise RecordingError(f"cop_unit must be a CopUnit or None, got {self.cop_unit!r}")
        self.cop_options(CopUnit.MM)  # checks the height and sign
        self.recording_columns  # noqa: B018 (checks the time, tilt and units)

    @property
    def recording_columns(self) -> RecordingColumns:
        """The time and tilt columns, with their units."""
        return RecordingColumns(self.time, self.tilt, (), self.unit, self.sample_rate_hz,
                                self.time_unit)

    def cop_options(self, unit: CopUnit) -> CopOptions:
        """How the COP column is read, in ``unit``."""
        return CopOptions(unit, self.ankle_height_m, self.cop_sign)

    def to_dict(self) -> dict:
        """JSON-ready (a result's ``source``)."""
        return {"cop_column": self.cop, "force_column": self.force,
                "ankle_height_m": self.ankle_height_m, "cop_sign": self.cop_sign}


def _cop_unit(table, columns: ForcePlateColumns) -> CopUnit:
    """The COP column's unit: its header's, else the one given, else mm; a given one that
    contradicts the header, or a header unit that is not a length, refused."""
    given = columns.cop_unit
    stated = table.stated_unit(columns.cop, (u.value for u in CopUnit),
                               None if given is None else given.value, "--cop-units",
                               "COP column must be a length (mm, cm or m)", "COP")
    return CopUnit(stated) if stated is not None else given or CopUnit.MM


def _force(table, columns: ForcePlateColumns) -> np.ndarray | None:
    """(S,) N, the normal-force column (its header's unit: N or kN), or None."""
    if columns.force is None:
        return None
    stated = table.stated_unit(columns.force, FORCE_UNITS_N, None, "--force-column",
                               "normal force must be in N or kN", "force")
    return table.column(columns.force) * FORCE_UNITS_N.get(stated or "N", 1.0)


def read_force_plate(path: str | Path, columns: ForcePlateColumns, body: Body,
                     tilt_of: Callable[[np.ndarray], np.ndarray] | None = None) -> Recording:
    """The body-COM sway recorded by a force plate: a recording of ``body`` as one
    segment (:func:`~posture_id.bodies.one_segment.one_segment_body`; its one angle the
    body-COM sway from the COP), the tilt from its column or ``tilt_of``.

    Raises:
        RecordingError: naming the file and the column (missing, in a unit that is not a
            length or a force, samples not evenly spaced, a force that is not a standing
            body's).
    """
    path = Path(path)
    table = on_even_time(read_text_table(path, RecordingError, "force-plate recording"),
                         columns.recording_columns)
    table.require([c for c in (columns.cop, columns.force) if c is not None])
    time, tilt, _, notices = lab_columns(table, columns.recording_columns, tilt_of)
    steps = np.diff(time)
    if len(steps) and np.any(np.abs(steps - np.median(steps)) > 0.01 * np.median(steps)):
        bad = int(np.argmax(np.abs(steps - np.median(steps)) > 0.01 * np.median(steps)))
        raise RecordingError(f"{path}: line {table.row_lines[bad + 1]}: samples are not "
                             "evenly spaced in time; the COP route needs an even rate")
    unit = _cop_unit(table, columns)
    load = BodyLoad.of(body)
    rate = 1.0 / float(np.median(steps))
    cop = table.column(columns.cop)
    _check_cop_span(path, columns, cop, unit)
    force = _force(table, columns)
    notices = list(notices)
    if force is not None:
        median = float(np.median(force))
        if median < 0:
            notices.append(f"{path}: column '{columns.force}': the normal force is negative "
                           f"(median {median:.4g} N: the plate's vertical axis points down); "
                           "its magnitude is used")
        notices += _off_the_plate(path, columns, time, np.abs(force), load)
    com = com_angle_from_cop(cop, rate, load, tilt, force, columns.cop_options(unit),
                             str(path))
    single = one_segment_body(body)
    source = {"force_plate": {**columns.to_dict(), "cop_unit": unit.value,
                              "body": body.name, "mass_kg": load.mass_kg,
                              "com_height_m": load.com_height_m,
                              "inertia_about_ankle_kg_m2": load.inertia_kg_m2,
                              "corner_hz": load.corner_hz if math.isfinite(load.corner_hz)
                              else None,
                              "method": "the COP's ankle torque through the body as one "
                                        "rigid segment about the ankle (docs/force_plates.md)"}}
    return Recording(time, tilt, com[:, None], single.segment_names, str(path),
                     tilt_recorded=columns.tilt is not None, source=source,
                     notices=tuple(notices))


def _off_the_plate(path: Path, columns: ForcePlateColumns, time: np.ndarray,
                   force: np.ndarray, load: BodyLoad) -> list[str]:
    """A notice of where the normal force falls below half the body's weight (a foot
    lifted, a step off the plate: the COP there is not the body's), or none."""
    low = force < 0.5 * load.mass_kg * load.gravity_m_s2
    if not low.any():
        return []
    where = np.flatnonzero(low)
    return [f"{path}: column '{columns.force}': the normal force falls below half the "
            f"body's weight in {len(where)} sample(s) from {time[where[0]]:.2f} to "
            f"{time[where[-1]]:.2f} s (a foot lifted, a step off the plate?): the COP there "
            "is not the standing body's; cut the trial to where the subject stands"]


#: The peak-to-peak a standing person's COP spans, m: more than the sway of a quiet
#: stance, less than the length of the feet.
COP_SPAN_M = (5e-4, 0.4)


def _check_cop_span(path: Path, columns: ForcePlateColumns, cop: np.ndarray,
                    unit: CopUnit) -> None:
    """Refuse a COP column that is constant, or whose span read in ``unit`` is not a
    standing person's (:data:`COP_SPAN_M`): another unit, or another column."""
    finite = cop[np.isfinite(cop)]
    span = float(np.ptp(finite)) if len(finite) else 0.0
    said = f"{path}: column '{columns.cop}'"
    if span == 0:
        value = f"{finite[0]:g} throughout" if len(finite) else "no value"
        raise RecordingError(f"{said}: the COP is constant ({value}): nobody on the plate, "
                             "or not the COP column")
    metres = span * unit.metres
    low, high = COP_SPAN_M
    if low <= metres <= high:
        return
    fits = [u.value for u in CopUnit if low <= span * u.metres <= high]
    advice = (f"is it in {' or '.join(fits)}? (--cop-units; a header such as 'COP [mm]' "
              "states it)") if fits else "is it the COP column?"
    raise RecordingError(
        f"{said}: the COP spans {span:.4g} {unit.value} ({metres:.3g} m) peak to peak, "
        f"{'more' if metres > high else 'less'} than a standing person's "
        f"({low * 1e3:g} mm to {high:g} m) read in {unit.value}: {advice}")
