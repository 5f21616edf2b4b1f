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
from posture_id.fileio import atomic_write_text, check_time_column, read_numeric_csv

__all__ = ["Recording", "RecordingColumns", "AngleUnit", "RADIANS_SUSPECT_DEG"]

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


@dataclass(frozen=True)
class RecordingColumns:
    """Which columns of a lab's CSV file hold what, and in which units: the file read as it
    is, whatever its header says.

    Attributes:
        time: the time column (seconds), or None: samples at ``sample_rate_hz``.
        tilt: the platform-tilt column, or None: the file has none (the tilt is taken from
            the named stimulus).
        angles: the angle columns, support upward, one per body segment; their segment
            names are the body's (``Recording.from_csv``'s ``segments``).
        unit: of the tilt and angle columns.
        sample_rate_hz: the true sampling rate: overrides a wrong time column (and is
            needed without one).
    """

    time: str | None = "time_s"
    tilt: str | None = "tilt_deg"
    angles: tuple[str, ...] = ()
    unit: AngleUnit = AngleUnit.DEGREES
    sample_rate_hz: float | None = None

    def __post_init__(self) -> None:
        if not self.angles:
            raise RecordingError("name the angle columns (one per body segment)")
        named = [c for c in (self.time, self.tilt, *self.angles) if c is not None]
        twice = sorted({c for c in named if named.count(c) > 1})
        if twice:
            raise RecordingError(f"column {', '.join(repr(c) for c in twice)} is named more "
                                 "than once (time, tilt and angle columns must each be their "
                                 "own): one segment's sway would be read as another's")
        if not isinstance(self.unit, AngleUnit):
            raise RecordingError(f"unit must be an AngleUnit, got {self.unit!r}")
        rate = self.sample_rate_hz
        if rate is not None and not (math.isfinite(rate) and rate > 0):
            raise RecordingError(f"sample rate must be a finite number > 0 Hz, got {rate}")
        if self.time is None and rate is None:
            raise RecordingError("without a time column, give the sample rate")


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
        columns name the segments, ``_deg`` left out)."""
        if columns is None:
            return cls.from_csv(path, segments, tilt_of)
        names = tuple(segments) if segments is not None else tuple(
            c.removesuffix("_deg") for c in columns.angles)
        return cls.from_lab_csv(path, columns, names, tilt_of)

    @classmethod
    def from_lab_csv(cls, path: str | Path, columns: RecordingColumns,
                     segments: tuple[str, ...],
                     tilt_of: Callable[[np.ndarray], np.ndarray] | None = None) -> Recording:
        """Read a lab's file as it is: the columns ``columns`` names, in its units, with
        the angle columns taken for the body's ``segments`` (in order).

        Raises:
            RecordingError: naming the file, the missing column or the problem.
        """
        path = Path(path)
        header, values = read_numeric_csv(path, RecordingError, "recording")
        wanted = [c for c in (columns.time, columns.tilt, *columns.angles) if c is not None]
        missing = [c for c in wanted if c not in header]
        if missing:
            raise RecordingError(f"{path}: no column {', '.join(repr(c) for c in missing)} "
                                 f"(the header is {','.join(header)})")
        if len(columns.angles) != len(segments):
            raise RecordingError(
                f"{path}: {len(columns.angles)} angle column(s) "
                f"({','.join(columns.angles)}) for a body of {len(segments)} segment(s) "
                f"({','.join(segments)}): give one per segment, support upward")
        column = {name: values[:, header.index(name)] for name in wanted}
        if columns.sample_rate_hz is not None:
            time = np.arange(len(values)) / columns.sample_rate_hz
        else:
            check_time_column(path, column[columns.time], RecordingError)
            time = column[columns.time] - column[columns.time][0]
        to_rad = np.radians if columns.unit is AngleUnit.DEGREES else np.asarray
        theta = np.column_stack([to_rad(column[c]) for c in columns.angles])
        if columns.tilt is not None:
            tilt = to_rad(column[columns.tilt])
        elif tilt_of is not None:
            tilt = tilt_of(time)
        else:
            raise RecordingError(f"{path}: no tilt column named; name the stimulus the "
                                 "recording was made with (the PRTS flags, or --tilt FILE)")
        largest = float(np.degrees(np.abs(theta).max()))
        if columns.unit is AngleUnit.DEGREES and 0 < largest < RADIANS_SUSPECT_DEG:
            raise RecordingError(
                f"{path}: every angle is below {RADIANS_SUSPECT_DEG}° (largest |value| "
                f"{largest:.3g}); the columns look like radians: give their unit (--units rad)")
        if columns.unit is AngleUnit.RADIANS:
            tilt_range = (float(np.degrees(np.ptp(tilt))) if columns.tilt is not None
                          else 0.0)
            if tilt_range > TILT_SUSPECT_DEG:
                raise RecordingError(
                    f"{path}: column {columns.tilt!r} spans {np.ptp(column[columns.tilt]):.3g}, "
                    f"which in radians is {tilt_range:.0f}° of platform tilt, more than any "
                    "posture platform runs; the columns look like degrees: give their unit "
                    "(--units deg, the default)")
            if largest > DEGREES_SUSPECT_DEG:
                worst = max(columns.angles, key=lambda c: float(np.abs(column[c]).max()))
                raise RecordingError(
                    f"{path}: column {worst!r} reaches {np.abs(column[worst]).max():.3g}, "
                    f"which in radians is {largest:.0f}°: no standing body sways so far; "
                    "the columns look like degrees: give their unit (--units deg, the "
                    "default)")
        return cls(time, tilt, theta, tuple(segments), str(path),
                   tilt_recorded=columns.tilt is not None)

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
        header, values = read_numeric_csv(path, RecordingError, "recording")
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
        )


def _check_segment_names(names, segments, name: str) -> None:
    if tuple(names) != tuple(segments):
        raise RecordingError(f"{name}: segment columns {','.join(names)} do not match the "
                             f"body's segments {','.join(segments)}; give the body the "
                             "recording was made with (--body URDF)")
