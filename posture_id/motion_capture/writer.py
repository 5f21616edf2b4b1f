"""A motion-capture trial written as a lab's system would write it (C3D, through ezc3d),
from a recording's angles and the body's segment lengths: what the project's own C3D tests,
example and benchmarks read.

Markers, both sides of the body (``L``/``R`` prefixes, ``lateral_m`` apart from the
sagittal plane): one per joint and one at the top of the last segment, named by
:func:`joint_marker_names` (``ANK``, ``KNE``, ``HIP``, ``SHO`` for the TIP); a 1-segment
body gets ``ANK``, ``HIP`` (at half its length) and ``SHO`` (its top). Two platform
markers ``PLATB`` and ``PLATF`` on its surface, behind and in front of the ankle axis, tilt
with it (docs/model.md §1: the platform rotates about the ankle axis). An analog channel
``platform_angle`` carries the tilt in volts (``deg_per_volt``) at ``analog_per_frame``
samples per frame, beside a ``force_z`` channel.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from posture_id.errors import RecordingError
from posture_id.fileio import atomic_write
from posture_id.motion_capture.c3d_file import METRES_PER_UNIT
from posture_id.motion_capture.mapping import LabAxes
from posture_id.recording import Recording

__all__ = ["C3dWriteOptions", "write_c3d", "joint_marker_names", "marker_positions",
           "TILT_CHANNEL", "PLATFORM_MARKERS"]

#: The analog channel that carries the tilt.
TILT_CHANNEL = "platform_angle"
#: The platform markers: (name, forward position from the ankle axis, m).
PLATFORM_MARKERS = (("PLATB", -0.10), ("PLATF", 0.30))
#: m, the platform surface below the ankle axis.
PLATFORM_DEPTH_M = 0.08


@dataclass(frozen=True)
class C3dWriteOptions:
    """How the trial is written.

    Attributes:
        axes: the lab's forward and vertical axes in the file.
        unit: POINT:UNITS, ``mm`` or ``m``.
        rate_hz: frames per second (the recording is resampled to it).
        marker_noise_mm: SD of white noise on every marker coordinate, mm.
        gaps: (marker, start_s, duration_s) each: frames where a marker is not seen.
        analog_per_frame: analog samples per frame (0: no analog channels).
        deg_per_volt: the tilt channel's scale.
        extra_markers: markers on the body no angle uses (a full marker set's others).
        lateral_m: each side's markers from the sagittal plane, m.
        origin_m: the ankle axis's midpoint in the lab's coordinates, m.
        height_m, mass_kg: the subject's, written as Vicon does (PROCESSING:Height in mm,
            PROCESSING:Bodymass in kg), or None.
        seed: of the marker noise.
    """

    axes: LabAxes = LabAxes("x")
    unit: str = "mm"
    rate_hz: float = 100.0
    marker_noise_mm: float = 0.0
    gaps: tuple[tuple[str, float, float], ...] = ()
    analog_per_frame: int = 10
    deg_per_volt: float = 2.0
    extra_markers: int = 0
    lateral_m: float = 0.09
    origin_m: tuple[float, float, float] = (0.4, 0.3, 0.1)
    height_m: float | None = None
    mass_kg: float | None = None
    seed: int = 0

    def __post_init__(self) -> None:
        if self.unit not in ("mm", "m"):
            raise RecordingError(f"unit must be mm or m, got {self.unit!r}")
        if not (math.isfinite(self.marker_noise_mm) and self.marker_noise_mm >= 0):
            raise RecordingError(f"marker noise must be ≥ 0 mm, got {self.marker_noise_mm}")


def joint_marker_names(n_segments: int) -> tuple[str, ...]:
    """The sagittal points' names, support upward (N + 1 of them; 3 for 1 segment)."""
    return {1: ("ANK", "HIP", "SHO"), 2: ("ANK", "HIP", "SHO"),
            3: ("ANK", "KNE", "HIP", "SHO")}[n_segments]


def marker_positions(theta: np.ndarray, lengths: tuple[float, ...]) -> np.ndarray:
    """(F, P, 2) m, the sagittal points (forward, up) of :func:`joint_marker_names`, the
    ankle at the origin, from segment angles ``theta`` ((F, N) rad) and lengths (m)."""
    direction = np.stack([np.sin(theta), np.cos(theta)], axis=2)  # (F, N, 2)
    ends = np.cumsum(direction * np.asarray(lengths)[None, :, None], axis=1)
    points = np.concatenate([np.zeros_like(ends[:, :1]), ends], axis=1)
    if theta.shape[1] == 1:  # ANK, HIP at half the length, SHO at the top
        points = np.concatenate([points[:, :1], 0.5 * points[:, 1:], points[:, 1:]], axis=1)
    return points


def _lab(sagittal: np.ndarray, lateral: float, axes: LabAxes,
         origin: np.ndarray) -> np.ndarray:
    """(..., 3) lab coordinates of (..., 2) (forward, up) points ``lateral`` m to the side."""
    forward, up = axes.forward_vector, axes.vertical_vector
    side = np.cross(up, forward)
    return (origin + sagittal[..., :1] * forward + sagittal[..., 1:] * up + lateral * side)


def _platform(tilt: np.ndarray) -> np.ndarray:
    """(F, 2, 2) the platform markers (forward, up), rotated by the tilt about the ankle
    axis (front down for a positive tilt)."""
    cos, sin = np.cos(tilt)[:, None], np.sin(tilt)[:, None]
    out = []
    for _, forward in PLATFORM_MARKERS:
        f, u = forward, -PLATFORM_DEPTH_M
        out.append(np.stack([f * cos + u * sin, -f * sin + u * cos], axis=-1)[:, 0])
    return np.stack(out, axis=1)


def write_c3d(path: str | Path, recording: Recording, lengths: tuple[float, ...],
              options: C3dWriteOptions = C3dWriteOptions()) -> Path:
    """Write ``recording`` (its angles and tilt) as a C3D trial of a body with segment
    ``lengths`` (m, support upward), atomically.

    Returns:
        the path written.
    """
    import ezc3d  # loaded here: only motion capture needs it

    if len(lengths) != recording.theta.shape[1]:
        raise RecordingError(f"{len(lengths)} segment lengths for a recording of "
                             f"{recording.theta.shape[1]} segments")
    valid = np.all(np.isfinite(recording.theta), axis=1)
    if not valid.all():  # a fall: the trial ends there, as the CSV does
        end = int(np.argmin(valid))
        recording = replace(recording, time=recording.time[:end], tilt=recording.tilt[:end],
                            theta=recording.theta[:end])
    recording = recording.resampled(options.rate_hz)
    frames = len(recording.time)
    rng = np.random.default_rng(options.seed)
    origin = np.asarray(options.origin_m)
    sagittal = marker_positions(recording.theta, tuple(lengths))
    names = joint_marker_names(recording.theta.shape[1])
    labels, tracks = [], []
    for k, name in enumerate(names):
        for prefix, sign in (("L", 1.0), ("R", -1.0)):
            labels.append(prefix + name)
            tracks.append(_lab(sagittal[:, k], sign * options.lateral_m, options.axes, origin))
    platform = _platform(recording.tilt)
    for k, (name, _) in enumerate(PLATFORM_MARKERS):
        labels.append(name)
        tracks.append(_lab(platform[:, k], 0.0, options.axes, origin))
    for k in range(options.extra_markers):  # others of a full set: along the segments
        segment = k % recording.theta.shape[1]
        share = 0.2 + 0.6 * rng.random()
        where = sagittal[:, segment] + share * (sagittal[:, segment + 1] - sagittal[:, segment])
        labels.append(f"M{k + 1:02d}")
        tracks.append(_lab(where, rng.uniform(-0.15, 0.15), options.axes, origin))
    points = np.stack(tracks, axis=1)  # (F, M, 3) m
    points = points + 1e-3 * options.marker_noise_mm * rng.standard_normal(points.shape)
    time = recording.time
    for marker, start_s, duration_s in options.gaps:
        if marker not in labels:
            raise RecordingError(f"a gap in marker {marker!r}, which is not written "
                                 f"({', '.join(labels)})")
        hidden = (time >= start_s) & (time < start_s + duration_s)
        points[hidden, labels.index(marker)] = np.nan
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = [options.rate_hz]
    c3d["parameters"]["POINT"]["LABELS"]["value"] = tuple(labels)
    c3d["parameters"]["POINT"]["UNITS"]["value"] = [options.unit]
    data = np.ones((4, len(labels), frames))
    data[:3] = points.transpose(2, 1, 0) / METRES_PER_UNIT[options.unit]
    c3d["data"]["points"] = data
    if options.analog_per_frame > 0:
        rate = options.rate_hz * options.analog_per_frame
        analog_time = np.arange(frames * options.analog_per_frame) / rate
        volts = np.degrees(np.interp(analog_time, time, recording.tilt)) / options.deg_per_volt
        force = np.full_like(volts, 9.81 * (options.mass_kg or 70.0))
        c3d["parameters"]["ANALOG"]["RATE"]["value"] = [rate]
        c3d["parameters"]["ANALOG"]["LABELS"]["value"] = (TILT_CHANNEL, "force_z")
        c3d["parameters"]["ANALOG"]["UNITS"]["value"] = ["V", "N"]
        c3d["data"]["analogs"] = np.stack([volts, force])[None]
    if options.height_m is not None:
        c3d.add_parameter("PROCESSING", "Height", [1000.0 * options.height_m])
    if options.mass_kg is not None:
        c3d.add_parameter("PROCESSING", "Bodymass", [float(options.mass_kg)])
    def write(tmp: Path) -> None:  # ezc3d adds .c3d to a name without it
        named = tmp.with_name(tmp.name + ".c3d")
        try:
            c3d.write(str(named))
            os.replace(named, tmp)
        finally:
            named.unlink(missing_ok=True)

    return atomic_write(Path(path), write)
