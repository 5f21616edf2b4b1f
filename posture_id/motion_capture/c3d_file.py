"""A C3D file read as it is, through ezc3d: marker trajectories in metres, analog channels,
rates, and the subject's height and mass when the file has them.

C3D marks an occluded marker by a negative residual (ezc3d reads it as NaN); older files
write it as the point (0, 0, 0). Both are read as missing (NaN) here.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from posture_id.errors import RecordingError

__all__ = ["MotionCaptureTrial", "read_c3d", "C3D_KEY", "METRES_PER_UNIT",
           "HEIGHT_PARAMETERS", "MASS_PARAMETERS"]

#: The second byte of every C3D file (its header's key, 0x50).
C3D_KEY = 0x50
#: POINT:UNITS values the reader knows, in metres per unit.
METRES_PER_UNIT = {"mm": 1e-3, "cm": 1e-2, "m": 1.0}
#: Where motion-capture software writes the subject's height ((group, parameter), first
#: found wins): Vicon Nexus's PROCESSING:Height (mm), others' SUBJECT(S):HEIGHT. A value
#: above 3 is taken for millimetres.
HEIGHT_PARAMETERS = (("PROCESSING", "Height"), ("SUBJECTS", "HEIGHT"), ("SUBJECT", "HEIGHT"))
#: ... and its mass (kg): Vicon's PROCESSING:Bodymass, others' MASS or WEIGHT.
MASS_PARAMETERS = (("PROCESSING", "Bodymass"), ("SUBJECTS", "MASS"), ("SUBJECT", "MASS"),
                   ("SUBJECTS", "WEIGHT"), ("SUBJECT", "WEIGHT"))


@dataclass(frozen=True)
class MotionCaptureTrial:
    """A motion-capture trial's contents.

    Attributes:
        path: the file. labels: (M,) the markers' labels.
        points: (F, M, 3) m, the file's coordinates; NaN where a marker was not seen.
        rate_hz: frames per second. first_frame: the file's number of its first frame
            (C3D counts from 1).
        unit: POINT:UNITS as the file says it (``mm``, ``m``).
        analog_labels: (C,) the analog channels' labels.
        analogs: (C, A) the channels in their units (scale and offset applied).
        analog_rate_hz: samples per second of the analog channels (0 without any).
        height_m, mass_kg: the subject's, from the file's metadata, or None.
    """

    path: Path
    labels: tuple[str, ...]
    points: np.ndarray
    rate_hz: float
    first_frame: int
    unit: str
    analog_labels: tuple[str, ...]
    analogs: np.ndarray
    analog_rate_hz: float
    height_m: float | None = None
    mass_kg: float | None = None

    @property
    def n_frames(self) -> int:
        return int(self.points.shape[0])

    @property
    def time(self) -> np.ndarray:
        """(F,) s, from 0 at the first frame."""
        return np.arange(self.n_frames) / self.rate_hz

    def frame_number(self, index: int) -> int:
        """The file's number of frame ``index`` (0-based in :attr:`points`)."""
        return self.first_frame + index

    def marker(self, label: str) -> np.ndarray:
        """(F, 3) m, one marker's trajectory; a missing label is refused with the labels
        the file has."""
        if label not in self.labels:
            raise RecordingError(f"{self.path}: no marker {label!r}; the file's markers are "
                                 f"{', '.join(self.labels) or '(none)'}")
        return self.points[:, self.labels.index(label), :]

    def require_markers(self, labels: tuple[str, ...]) -> None:
        """Refuse, in one line, every label of ``labels`` the file lacks."""
        missing = [m for m in labels if m not in self.labels]
        if missing:
            raise RecordingError(f"{self.path}: no marker {', '.join(repr(m) for m in missing)};"
                                 f" the file's markers are {', '.join(self.labels) or '(none)'}")

    def channel(self, label: str) -> np.ndarray:
        """(A,) one analog channel; a missing label is refused with those the file has."""
        if label not in self.analog_labels:
            raise RecordingError(f"{self.path}: no analog channel {label!r}; the file's "
                                 f"channels are {', '.join(self.analog_labels) or '(none)'}")
        return self.analogs[self.analog_labels.index(label)]


def _value(parameters: dict, group: str, name: str):
    try:
        return parameters[group][name]["value"]
    except (KeyError, TypeError):
        return None


def _labels(parameters: dict, group: str, count: int) -> tuple[str, ...]:
    """A group's LABELS, LABELS2, ... joined (files with over 255 labels), ``count`` of them."""
    labels: list[str] = []
    for key in ("LABELS", *(f"LABELS{k}" for k in range(2, 10))):
        value = _value(parameters, group, key)
        if value is None:
            break
        labels += [str(v).strip() for v in value]
    return tuple(labels[:count])


def _metadata(parameters: dict, candidates) -> float | None:
    for group, name in candidates:
        value = _value(parameters, group, name)
        if value is None or len(np.atleast_1d(value)) == 0:
            continue
        try:
            number = float(np.atleast_1d(value)[0])
        except (TypeError, ValueError):
            continue
        if math.isfinite(number) and number > 0:
            return number
    return None


def _check_length(path: Path, head: bytes) -> None:
    """Refuse a file shorter than the frames its header promises (ezc3d reads the frames
    a truncated file still holds and says nothing).

    The C3D header's 16-bit words: 2 markers, 3 analog values per frame, 4 and 5 the first
    and last frame, 7–8 the scale (negative: 4-byte floats, else 2-byte integers), 9 the
    data's first 512-byte block. Big-endian only for files of a MIPS processor (the
    parameter section's 4th byte, 86)."""
    with path.open("rb") as handle:
        handle.seek(512 * max(head[0] - 1, 0))
        processor = handle.read(4)[3:4]
    order = ">" if processor == b"\x56" else "<"
    points, analog, first, last = struct.unpack(order + "4H", head[2:10])
    (scale,) = struct.unpack(order + "f", head[12:16])
    (data_block,) = struct.unpack(order + "H", head[16:18])
    if last == 0xFFFF or last < first or data_block == 0:
        return  # a long trial's count lives elsewhere: left to the reader
    word = 4 if scale < 0 else 2
    frames = last - first + 1
    needed = 512 * (data_block - 1) + word * frames * (4 * points + analog)
    size = path.stat().st_size
    if size < needed:
        raise RecordingError(f"{path}: a C3D file that cannot be read (truncated: {size} "
                             f"bytes, its header promises {needed} for {frames} frames)")


def read_c3d(path: str | Path) -> MotionCaptureTrial:
    """Read a C3D file (any C3D: Vicon, Qualisys, Motion Analysis, ezc3d, ...).

    The last few files read are kept (keyed on the file's path, size and modification
    time): a command that takes the subject's body from the file's metadata, reads its
    angles and plots its markers reads it once. The trial's arrays are read-only.

    Raises:
        RecordingError: naming the file: not a C3D file, a file ezc3d cannot read
            (truncated, corrupt), no markers, a unit other than mm, cm or m, no frame rate.
    """
    path = Path(path)
    if not path.is_file():
        raise RecordingError(f"{path}: no such file" if not path.exists()
                             else f"{path}: a folder, not a C3D file")
    stat = path.stat()
    return _read_c3d(path, stat.st_size, stat.st_mtime_ns)


@lru_cache(maxsize=2)
def _read_c3d(path: Path, size: int, mtime_ns: int) -> MotionCaptureTrial:
    """:func:`read_c3d` of one version of a file (``size`` and ``mtime_ns`` tell it)."""
    with path.open("rb") as handle:
        head = handle.read(512)
    if len(head) < 512 or head[1] != C3D_KEY:
        raise RecordingError(f"{path}: not a C3D file (its header lacks the C3D key 0x50"
                             f"{'; the file is shorter than a header' if len(head) < 512 else ''})")
    _check_length(path, head)
    import ezc3d  # loaded here: only motion capture needs it

    try:
        c3d = ezc3d.c3d(str(path))
        parameters = c3d["parameters"]
        raw = np.asarray(c3d["data"]["points"], dtype=float)
        analogs = np.asarray(c3d["data"]["analogs"], dtype=float)
    except (OSError, RuntimeError, ValueError, IndexError, MemoryError) as exc:
        raise RecordingError(f"{path}: a C3D file that cannot be read (truncated or corrupt: "
                             f"{str(exc).strip() or type(exc).__name__})") from None
    n_markers = raw.shape[1] if raw.ndim == 3 else 0
    if n_markers == 0 or raw.shape[2] == 0:
        raise RecordingError(f"{path}: no marker trajectories (POINT:USED is 0 or no frames): "
                             "posture-id derives the angles from markers")
    unit = str((_value(parameters, "POINT", "UNITS") or [""])[0]).strip()
    if unit.lower() not in METRES_PER_UNIT:
        raise RecordingError(f"{path}: POINT:UNITS is {unit!r}; the markers' unit must be "
                             f"{', '.join(METRES_PER_UNIT)}")
    rate = float(np.atleast_1d(_value(parameters, "POINT", "RATE") or [0.0])[0])
    if not (math.isfinite(rate) and rate > 0):
        raise RecordingError(f"{path}: POINT:RATE is {rate}: the file gives no frame rate")
    points = raw[:3].transpose(2, 1, 0) * METRES_PER_UNIT[unit.lower()]
    points[np.all(points == 0.0, axis=2)] = np.nan  # an older file's mark of a missing one
    points.flags.writeable = False
    analogs.flags.writeable = False
    n_channels = analogs.shape[1] if analogs.ndim == 3 else 0
    analog_rate = float(np.atleast_1d(_value(parameters, "ANALOG", "RATE") or [0.0])[0])
    height = _metadata(parameters, HEIGHT_PARAMETERS)
    first = int(c3d["header"]["points"].get("first_frame", 0)) + 1
    return MotionCaptureTrial(
        path=path, labels=_labels(parameters, "POINT", n_markers), points=points,
        rate_hz=rate, first_frame=first, unit=unit,
        analog_labels=_labels(parameters, "ANALOG", n_channels),
        analogs=analogs[0] if n_channels else np.zeros((0, 0)),
        analog_rate_hz=analog_rate if n_channels else 0.0,
        height_m=None if height is None else (height / 1000.0 if height > 3.0 else height),
        mass_kg=_metadata(parameters, MASS_PARAMETERS),
    )
