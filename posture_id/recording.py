"""Sway recordings as CSV: ``time_s,tilt_deg,<segment>_deg,...`` (degrees at the edge).

Segments are named by their URDF links (``shank,thigh,trunk`` for the default body);
angles are segment angles in space, positive = forward lean (docs/model.md §1).
"""

from __future__ import annotations

import csv
import enum
import io
import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path

import numpy as np

from posture_id.errors import RecordingError
from posture_id.fileio import atomic_write_text, check_time_column
from posture_id.text_table import TextTable, read_text_table, split_unit

__all__ = ["Recording", "RecordingColumns", "on_even_time", "JITTER_SHARE", "lab_columns",
           "AngleUnit", "TimeUnit", "RADIANS_SUSPECT_DEG"]

#: A recording whose every angle (tilt and segments, "degrees") stays below this is taken
#: to be in radians by mistake: 0.1° of sway and tilt at most is below any stimulus used.
RADIANS_SUSPECT_DEG = 0.1
#: A recording read as radians whose segment angles reach this (degrees) is taken to be in
#: degrees by mistake: a segment 30° from the vertical is a fall, not sway (the
#: simulator's widest sway limit is far below).
DEGREES_SUSPECT_DEG = 30.0
#: A tilt column read as radians that spans more than this (degrees) is taken to be in
#: degrees by mistake (posture platforms tilt a few degrees; the universal network's
#: scope is 0.5–4° peak to peak).
TILT_SUSPECT_DEG = 20.0


class AngleUnit(enum.Enum):
    """The unit of a file's angle columns."""

    DEGREES = "deg"
    RADIANS = "rad"


class TimeUnit(enum.Enum):
    """The unit of a file's time column."""

    SECONDS = "s"
    MILLISECONDS = "ms"

    @property
    def per_second(self) -> float:
        """How many of this unit make a second."""
        return 1000.0 if self is TimeUnit.MILLISECONDS else 1.0


@dataclass(frozen=True)
class RecordingColumns:
    """Which columns of a lab's file hold what, and in which units: the file read as it
    is, whatever its header says (:func:`posture_id.text_table.read_text_table`: comma,
    tab or ``;`` separated, decimal commas, title lines, units in the header).

    A column is named by its whole header name (``"Time [ms]"``) or by its name without
    the unit (``"Time"``). A unit the header states in brackets (``[ms]``, ``[deg]``,
    ``[°]``, ``[rad]``) is the column's unit; a unit given here that contradicts it is
    refused.

    Attributes:
        time: the time column, or None: samples at ``sample_rate_hz``.
        tilt: the platform-tilt column, or None: the file has none (the tilt is taken from
            the named stimulus).
        angles: the angle columns, support upward, one per body segment; their segment
            names are the body's (``Recording.from_csv``'s ``segments``); none where the
            sway comes from other columns (a force plate's COP:
            :class:`~posture_id.force_plate.reading.ForcePlateColumns`).
        unit: of the tilt and angle columns whose header states none; None: degrees.
            A column's header's unit is its own.
        time_unit: of the time column; None: the header's, else seconds.
        sample_rate_hz: the true sampling rate: overrides a wrong time column (and is
            needed without one).
    """

    time: str | None = "time_s"
    tilt: str | None = "tilt_deg"
    angles: tuple[str, ...] = ()
    unit: AngleUnit | None = None
    sample_rate_hz: float | None = None
    time_unit: TimeUnit | None = None

    def __post_init__(self) -> None:
        named = [c for c in (self.time, self.tilt, *self.angles) if c is not None]
        twice = sorted({c for c in named if named.count(c) > 1})
        if twice:
            raise RecordingError(f"column {', '.join(repr(c) for c in twice)} is named more "
                                 "than once (time, tilt and angle columns must each be their "
                                 "own): one segment's sway would be read as another's")
        if self.unit is not None and not isinstance(self.unit, AngleUnit):
            raise RecordingError(f"unit must be an AngleUnit or None, got {self.unit!r}")
        if self.time_unit is not None and not isinstance(self.time_unit, TimeUnit):
            raise RecordingError(f"time_unit must be a TimeUnit or None, got "
                                 f"{self.time_unit!r}")
        rate = self.sample_rate_hz
        if rate is not None and not (math.isfinite(rate) and rate > 0):
            raise RecordingError(f"sample rate must be a finite number > 0 Hz, got {rate}")
        if self.time is None and rate is None:
            raise RecordingError("without a time column, give the sample rate")
        if self.time is None and self.time_unit is not None:
            raise RecordingError("a time unit without a time column: name the column")


@dataclass(frozen=True)
class Recording:
    """Recorded or simulated sway, checked when made.

    Attributes:
        time: (S,) s, from 0, strictly increasing. tilt: (S,) rad, platform tilt α_FS.
        theta: (S, N) rad, segment angles in space (NaN after a simulated fall).
        segments: (N,) link names.
        name: what messages call it (the file it was read from, "trial 3", ...).
        tilt_recorded: the tilt comes from the file (or the simulation); False when the
            file had no tilt column and the named stimulus filled it in (its onset then
            rests on the lab's word alone).
        source: how the angles were derived when not read from columns (a motion-capture
            trial's markers, axes and channels: JSON-ready), or None.
        notices: what reading the file noticed that a reader may want to know (an
            encoding other than UTF-8, title lines skipped, a rate given against the time
            column, a force's sign), each naming the file.

    Raises:
        RecordingError: shapes that disagree, fewer than 2 samples, a time column that
            does not start at 0 or does not increase, no segments.
    """

    time: np.ndarray
    tilt: np.ndarray
    theta: np.ndarray
    segments: tuple[str, ...]
    name: str = "recording"
    tilt_recorded: bool = True
    source: dict | None = field(default=None, compare=False, repr=False)
    notices: tuple[str, ...] = field(default=(), compare=False, repr=False)

    def __post_init__(self) -> None:
        time = np.asarray(self.time, dtype=float)
        tilt = np.asarray(self.tilt, dtype=float)
        theta = np.asarray(self.theta, dtype=float)
        segments = tuple(self.segments)
        if time.ndim != 1 or len(time) < 2:
            raise RecordingError(f"{self.name}: time must be 1-D with at least 2 samples, "
                                 f"got shape {time.shape}")
        if tilt.shape != time.shape:
            raise RecordingError(f"{self.name}: tilt has shape {tilt.shape}, time {time.shape}")
        if not segments or theta.shape != (len(time), len(segments)):
            raise RecordingError(f"{self.name}: segment angles have shape {theta.shape}, "
                                 f"expected ({len(time)}, {len(segments)}) for the segments "
                                 f"{','.join(segments) or '(none)'}")
        if not np.all(np.isfinite(time)) or abs(time[0]) > 1e-9:
            raise RecordingError(f"{self.name}: time must be finite and start at 0, starts "
                                 f"at {time[0]}")
        step = np.flatnonzero(np.diff(time) <= 0)
        if step.size:
            raise RecordingError(f"{self.name}: sample {step[0] + 1}: time does not increase "
                                 f"({time[step[0] + 1]} s)")
        object.__setattr__(self, "time", time)
        object.__setattr__(self, "tilt", tilt)
        object.__setattr__(self, "theta", theta)
        object.__setattr__(self, "segments", segments)

    @cached_property
    def sample_rate_hz(self) -> float:
        """Hz, from the median sample interval (computed once)."""
        return float(1.0 / np.median(np.diff(self.time)))

    @property
    def duration_s(self) -> float:
        """s, time of the last sample."""
        return float(self.time[-1])

    def evenly_sampled(self, tolerance: float = 0.01) -> bool:
        """True when every interval is within ``tolerance`` (relative) of the median."""
        steps = np.diff(self.time)
        median = float(np.median(steps))
        return bool(np.all(np.abs(steps - median) <= tolerance * median))

    def resampled(self, rate_hz: float) -> Recording:
        """The recording at ``rate_hz`` from t = 0 to its end, by linear interpolation
        (itself when it is already at that rate)."""
        if abs(self.sample_rate_hz - rate_hz) <= 1e-6 * rate_hz:
            return self
        n = int(math.floor(self.duration_s * rate_hz + 1e-9)) + 1
        t = np.arange(n) / rate_hz
        theta = np.stack([np.interp(t, self.time, self.theta[:, j])
                          for j in range(self.theta.shape[1])], axis=1)
        return replace(self, time=t, tilt=np.interp(t, self.time, self.tilt), theta=theta)

    def check_segments(self, segments: tuple[str, ...]) -> None:
        """Refuse a recording whose segment columns are not ``segments`` (a body's), in
        order."""
        _check_segment_names(self.segments, segments, self.name)

    def with_sensor_noise(self, sd_deg: float, seed: int) -> Recording:
        """A copy with white Gaussian noise of ``sd_deg`` degrees added to every segment
        angle (the platform tilt is the commanded stimulus and stays clean), seeded."""
        if not (math.isfinite(sd_deg) and sd_deg >= 0):
            raise RecordingError(f"sensor noise must be a finite number ≥ 0 degrees, got {sd_deg}")
        rng = np.random.default_rng(seed)
        noise = math.radians(sd_deg) * rng.standard_normal(self.theta.shape)
        return replace(self, theta=self.theta + noise)

    def to_csv(self, path: str | Path) -> Path:
        """Write atomically. Rows after the first NaN (an aborted trial) are left out."""
        valid = np.all(np.isfinite(self.theta), axis=1)
        last = len(valid) if valid.all() else int(np.argmin(valid))
        out = io.StringIO()
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(["time_s", "tilt_deg", *(f"{s}_deg" for s in self.segments)])
        deg_tilt = np.degrees(self.tilt)
        deg = np.degrees(self.theta)
        for k in range(last):
            writer.writerow(
                [f"{self.time[k]:.6f}", f"{deg_tilt[k]:.12g}", *(f"{x:.12g}" for x in deg[k])]
            )
        return atomic_write_text(Path(path), out.getvalue())

    @classmethod
    def read(cls, path: str | Path, segments: tuple[str, ...] | None = None,
             tilt_of: Callable[[np.ndarray], np.ndarray] | None = None,
             columns: RecordingColumns | None = None) -> Recording:
        """A recording file with the standard header (:meth:`from_csv`), or a lab's file
        read by its ``columns`` (:meth:`from_lab_csv`; without ``segments`` the angle
        columns name the segments, a unit and ``_deg`` left out)."""
        if columns is None:
            return cls.from_csv(path, segments, tilt_of)
        names = tuple(segments) if segments is not None else tuple(
            split_unit(c)[0].removesuffix("_deg") for c in columns.angles)
        return cls.from_lab_csv(path, columns, names, tilt_of)

    @classmethod
    def from_lab_csv(cls, path: str | Path, columns: RecordingColumns,
                     segments: tuple[str, ...],
                     tilt_of: Callable[[np.ndarray], np.ndarray] | None = None) -> Recording:
        """Read a lab's file as it is: the columns ``columns`` names, in its units (those
        its header states, else ``columns``'s; milliseconds converted to seconds), with
        the angle columns taken for the body's ``segments`` (in order).

        Raises:
            RecordingError: naming the file, the missing column or the problem (a unit
                given that contradicts the header's, a unit that is not an angle's or a
                time's, a time column in the wrong unit, angles that look like the other
                unit).
        """
        path = Path(path)
        if not columns.angles:
            raise RecordingError(f"{path}: name the angle columns (one per body segment)")
        table = on_even_time(read_text_table(path, RecordingError, "recording"), columns)
        if len(columns.angles) != len(segments):
            raise RecordingError(
                f"{path}: {len(columns.angles)} angle column(s) "
                f"({','.join(columns.angles)}) for a body of {len(segments)} segment(s) "
                f"({','.join(segments)}): give one per segment, support upward")
        time, tilt, theta, notices = lab_columns(table, columns, tilt_of)
        return cls(time, tilt, theta, tuple(segments), str(path),
                   tilt_recorded=columns.tilt is not None, notices=notices)

    @classmethod
    def from_csv(cls, path: str | Path, segments: tuple[str, ...] | None = None,
                 tilt_of: Callable[[np.ndarray], np.ndarray] | None = None) -> Recording:
        """Read a recording; with ``segments`` given, its columns must match them in order.

        Args:
            tilt_of: the named stimulus's tilt (rad) at given times (s), e.g.
                ``TiltProfile.angle``: then the file may leave out its ``tilt_deg`` column
                (``time_s,<segment>_deg...``) and the tilt is taken from the stimulus.

        Raises:
            RecordingError: naming the file, the line or column, and the problem.
        """
        path = Path(path)
        table = read_text_table(path, RecordingError, "recording")
        header, values = list(table.header), table.values
        recorded = True
        if header[:1] == ["time_s"] and header[1:2] != ["tilt_deg"] and tilt_of is not None:
            values = np.insert(values, 1, np.degrees(tilt_of(values[:, 0] - values[0, 0])),
                               axis=1)
            header = ["time_s", "tilt_deg", *header[1:]]
            recorded = False
        elif header[:1] == ["time_s"] and header[1:2] != ["tilt_deg"]:
            raise RecordingError(
                f"{path}: no 'tilt_deg' column after time_s; name the stimulus the recording "
                "was made with (the PRTS flags, or --tilt FILE) to take the tilt from it")
        if header[:2] != ["time_s", "tilt_deg"]:
            raise RecordingError(
                f"{path}: header must start with 'time_s,tilt_deg', got "
                f"'{','.join(header[:2])}'; name a lab's own columns: --time-column NAME "
                "--tilt-column NAME --angle-columns NAME... (Python: RecordingColumns; "
                "docs/lab_recordings.md)")
        names = []
        for col in header[2:]:
            if not col.endswith("_deg") or len(col) <= 4:
                raise RecordingError(f"{path}: column '{col}' is not '<segment>_deg'")
            names.append(col[:-4])
        if not names:
            raise RecordingError(f"{path}: no segment columns after time_s,tilt_deg")
        if segments is not None:
            _check_segment_names(names, segments, str(path))
        check_time_column(path, values[:, 0], RecordingError)
        largest = float(np.abs(values[:, 1:]).max())
        if 0 < largest < RADIANS_SUSPECT_DEG:
            raise RecordingError(
                f"{path}: every angle is below {RADIANS_SUSPECT_DEG}° (largest |value| "
                f"{largest:.3g}); the columns look like radians, they must be degrees")
        return cls(
            time=values[:, 0] - values[0, 0],
            tilt=np.radians(values[:, 1]),
            theta=np.radians(values[:, 2:]),
            segments=tuple(names),
            name=str(path),
            tilt_recorded=recorded,
            notices=table.notices,
        )


#: Time stamps that jitter by less than this share of their mean interval are an even
#: rate's, resampled onto it (a headset's or tracker's clock); a larger step is a gap.
JITTER_SHARE = 0.25
#: Steps within this share of the mean interval are even as they are (rounding).
_EVEN_SHARE = 0.01


def on_even_time(table: TextTable, columns: RecordingColumns) -> TextTable:
    """``table`` with its rows on an even time grid: itself where the time column's steps
    are even (within 1 %), no time column is named or a sample rate is given; the rows
    linearly interpolated onto the mean rate where the stamps only jitter (every step
    within :data:`JITTER_SHARE` of the mean interval), said in a notice.

    Raises:
        RecordingError: naming the line: time that does not increase, or a step beyond the
            jitter (a gap, a dropped or doubled sample).
    """
    if columns.time is None or columns.sample_rate_hz is not None or table.n_rows < 3:
        return table
    table.require([columns.time])
    unit, _, seconds = _time_column_seconds(table, columns)
    steps = np.diff(seconds)
    if not np.all(steps > 0):
        return table  # said by the time column's check, naming the line
    mean = float((seconds[-1] - seconds[0]) / (len(seconds) - 1))
    off = np.abs(steps - mean)
    if np.all(off <= _EVEN_SHARE * mean):
        return table
    worst = int(np.argmax(off))
    if off[worst] > JITTER_SHARE * mean:
        raise RecordingError(
            f"{table.path}: line {table.row_lines[worst + 1]}: a step of "
            f"{steps[worst] * 1e3:.4g} ms in column '{columns.time}', the mean interval "
            f"{mean * 1e3:.4g} ms: a gap or a doubled sample, not the jitter of a clock "
            f"(within {100 * JITTER_SHARE:g} % of the interval); cut the recording there")
    index = np.arange(len(seconds))
    interval, intercept = np.polyfit(index, seconds, 1)  # the clock's rate, its jitter out
    jitter = float(np.abs(seconds - (intercept + interval * index)).max())
    grid = seconds[0] + interval * index
    k = table.index(columns.time)
    values = np.column_stack([grid * unit.per_second if j == k
                              else np.interp(grid, seconds, table.values[:, j])
                              for j in range(table.values.shape[1])])
    notice = (f"{table.path}: column '{columns.time}': the time stamps jitter by up to "
              f"{jitter * 1e3:.2g} ms about an even {1 / interval:.5g} Hz clock "
              f"({100 * jitter / interval:.2g} % of its {interval * 1e3:.4g} ms interval): "
              "every column resampled onto that clock by linear interpolation")
    return replace(table, values=values, notices=(*table.notices, notice))


def lab_columns(table: TextTable, columns: RecordingColumns,
                tilt_of: Callable[[np.ndarray], np.ndarray] | None = None
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[str, ...]]:
    """(time (S,) s from 0, tilt (S,) rad, angles (S, A) rad, notices) of a lab's
    ``table`` read by ``columns`` (:meth:`Recording.from_lab_csv`; A may be 0: the sway
    comes from other columns); the tilt from ``tilt_of`` where no tilt column is named.
    The notices: the table's (its encoding, lines skipped, decimal commas), and a sample
    rate given that is not the time column's.

    Raises:
        RecordingError: naming the file and the column (missing, a unit contradicted or
            not an angle's or a time's, angles that look like the other unit).
    """
    path = table.path
    if columns.tilt is not None and not table.has(columns.tilt):
        others = [c for c in (columns.time, *columns.angles) if c is not None]
        if all(table.has(c) for c in others):  # the tilt column alone is missing
            way = ("give --tilt-column none to take the tilt from the stimulus named"
                   if tilt_of is not None else "give --tilt-column none and the stimulus "
                   "the recording was made with (the PRTS flags, --tilt FILE or --protocol "
                   "FILE)")
            raise RecordingError(
                f"{path}: no tilt column {columns.tilt!r} (the header is "
                f"{','.join(table.header)}): name the file's tilt column (--tilt-column "
                f"NAME), or, if it has none, {way}")
    wanted = [c for c in (columns.time, columns.tilt, *columns.angles) if c is not None]
    table.require(wanted)
    column = {name: table.column(name) for name in wanted}
    notices = list(table.notices)
    if columns.sample_rate_hz is not None:
        time = np.arange(table.n_rows) / columns.sample_rate_hz
        stated = _time_column_rate(table, columns)
        rate = columns.sample_rate_hz
        if stated is not None and abs(stated - rate) > 0.01 * rate:
            notices.append(f"{path}: the sample rate given (--sample-rate-hz {rate:g}) "
                           f"replaces the time column '{columns.time}''s {stated:.4g} Hz: "
                           f"every time is {stated / rate:.3g}× and every frequency "
                           f"{rate / stated:.3g}× what the time column says")
    else:
        unit, stated, seconds = _time_column_seconds(table, columns)
        check_time_column(path, seconds, RecordingError, column=columns.time,
                          unit=unit.value, flag=None if stated else "--time-units",
                          lines=table.row_lines)
        time = seconds - seconds[0]
    units = _angle_units(table, columns)
    angle_names = [*columns.angles, *([columns.tilt] if columns.tilt is not None else [])]

    def to_rad(name: str) -> np.ndarray:
        values = column[name]
        return np.radians(values) if units[name][0] is AngleUnit.DEGREES else values

    theta = (np.column_stack([to_rad(c) for c in columns.angles]) if columns.angles
             else np.zeros((len(time), 0)))
    if columns.tilt is not None:
        tilt = to_rad(columns.tilt)
    elif tilt_of is not None:
        tilt = tilt_of(time)
    else:
        raise RecordingError(f"{path}: no tilt column named; name the stimulus the "
                             "recording was made with (the PRTS flags, --tilt FILE or "
                             "--protocol FILE)")
    _check_angle_units(path, column, units, angle_names, columns)
    return time, tilt, theta, tuple(notices)


def _time_column_seconds(table: TextTable, columns: RecordingColumns
                         ) -> tuple[TimeUnit, bool, np.ndarray]:
    """(the time column's unit, whether its header states it, the column in seconds)."""
    unit, stated = _time_unit(table, columns)
    return unit, stated, table.column(columns.time) / unit.per_second


def _time_column_rate(table: TextTable, columns: RecordingColumns) -> float | None:
    """Hz, the rate of a named time column (in its unit) when it increases, else None."""
    if columns.time is None:
        return None
    steps = np.diff(_time_column_seconds(table, columns)[2])
    if not len(steps) or not np.all(steps > 0):
        return None
    return float(1.0 / np.median(steps))


def _check_segment_names(names, segments, name: str) -> None:
    if tuple(names) != tuple(segments):
        raise RecordingError(f"{name}: segment columns {','.join(names)} do not match the "
                             f"body's segments {','.join(segments)}; give the body the "
                             "recording was made with (--body URDF)")


def _time_unit(table: TextTable, columns: RecordingColumns) -> tuple[TimeUnit, bool]:
    """The time column's unit (its header's, else ``columns.time_unit``, else seconds) and
    whether the header states it.

    Raises:
        RecordingError: a header unit that is not a time's, or one the columns contradict.
    """
    given = columns.time_unit
    stated = table.stated_unit(columns.time, (u.value for u in TimeUnit),
                               None if given is None else given.value, "--time-units",
                               "time column must be in s or ms", "time")
    if stated is None:
        return given or TimeUnit.SECONDS, False
    return TimeUnit(stated), True


def _angle_units(table: TextTable, columns: RecordingColumns
                 ) -> dict[str, tuple[AngleUnit, str]]:
    """Each tilt and angle column's unit and where it comes from: ``"header"`` (its
    header states it), ``"given"`` (``columns.unit``) or ``"default"`` (degrees).

    Raises:
        RecordingError: a header unit that is not an angle's, or one ``columns.unit``
            contradicts.
    """
    names = [c for c in (columns.tilt, *columns.angles) if c is not None]
    stated = {}
    for name in names:
        unit = table.stated_unit(name, (u.value for u in AngleUnit),
                                 None if columns.unit is None else columns.unit.value,
                                 "--units", "tilt and angle columns must be angles (deg or "
                                 "rad)", "angle")
        if unit is not None:
            stated[name] = AngleUnit(unit)
    return {name: (stated[name], "header") if name in stated
            else (columns.unit, "given") if columns.unit is not None
            else (AngleUnit.DEGREES, "default") for name in names}


def _check_angle_units(path: Path, column: dict[str, np.ndarray],
                       units: dict[str, tuple[AngleUnit, str]], names: list[str],
                       columns: RecordingColumns) -> None:
    """Refuse angle columns whose values look like the other unit than the one they are
    read in, when no header states it: all below 0.1° as degrees; a tilt spanning more
    than 20° or a segment beyond 30° as radians."""
    assumed = [n for n in names if units[n][1] != "header"]
    segments = [n for n in columns.angles if n in assumed]
    if segments and all(units[n][0] is AngleUnit.DEGREES for n in segments):
        largest = max(float(np.abs(column[n]).max()) for n in segments)
        if len(segments) == len(columns.angles) and 0 < largest < RADIANS_SUSPECT_DEG:
            raise RecordingError(
                f"{path}: every angle is below {RADIANS_SUSPECT_DEG}° (largest |value| "
                f"{largest:.3g}); the columns look like radians: give their unit (--units "
                "rad)")
    tilt = columns.tilt
    if tilt in assumed and units[tilt][0] is AngleUnit.RADIANS:
        tilt_range = float(np.degrees(np.ptp(column[tilt])))
        if tilt_range > TILT_SUSPECT_DEG:
            raise RecordingError(
                f"{path}: column {tilt!r} spans {np.ptp(column[tilt]):.3g}, which in radians "
                f"is {tilt_range:.0f}° of platform tilt, more than any posture platform runs; "
                "the columns look like degrees: give their unit (--units deg)")
    in_radians = [n for n in segments if units[n][0] is AngleUnit.RADIANS]
    if in_radians:
        worst = max(in_radians, key=lambda c: float(np.abs(column[c]).max()))
        largest = float(np.degrees(np.abs(column[worst]).max()))
        if largest > DEGREES_SUSPECT_DEG:
            raise RecordingError(
                f"{path}: column {worst!r} reaches {np.abs(column[worst]).max():.3g}, which "
                f"in radians is {largest:.0f}°: no standing body sways so far; the columns "
                "look like degrees: give their unit (--units deg)")
