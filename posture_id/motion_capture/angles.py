"""Sagittal angles from markers: each segment's angle in space, the body COM's, and the
platform's tilt, as docs/model.md §1 measures them.

A segment's angle is that of the line from its lower to its upper point, projected on the
sagittal plane (forward, vertical): θ = atan2(d·forward, d·vertical), positive for a
forward lean, from the vertical. The platform's tilt from two markers on it is the angle of
the line from the back marker to the front one, positive when the front edge goes down:
α = atan2(−p·vertical, p·forward), less its value at the start (the platform is level when
the recording starts, and two markers are never mounted at exactly one height). An analog
angle sensor's channel is read as it is, times ``deg_per_unit``, linearly interpolated at
the frame times.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from posture_id.errors import RecordingError
from posture_id.fileio import Result
from posture_id.motion_capture.c3d_file import MotionCaptureTrial
from posture_id.motion_capture.gaps import Gap, fill_gaps
from posture_id.motion_capture.mapping import (
    MarkerMapping,
    MarkerPoint,
    TiltChannel,
    TiltMarkers,
)
from posture_id.recording import Recording

__all__ = ["MarkerAngles", "marker_angles", "LEVEL_S", "UPRIGHT_LIMIT_DEG",
           "PLATFORM_HEADING_LIMIT_DEG", "SAGITTAL_SHARE", "SWAY_ACROSS_RATIO",
           "sway_across"]

#: s, the start of the trial over which the platform markers' level is taken.
LEVEL_S = 0.1
#: A segment leaning further than this from the vertical on average, degrees, is not a
#: standing body's: the vertical axis, or the segment's markers, are wrong.
UPRIGHT_LIMIT_DEG = 45.0
#: A segment's share of its length in the sagittal plane the axes name below which the axes
#: are wrong (a body sways a few degrees out of it; a lateral axis named forward or up
#: leaves a fraction).
SAGITTAL_SHARE = 0.7
#: The segments' sway about the lateral axis (in the plane of the horizontal axis not
#: named and the vertical; each angle averaged over 1 s, which keeps the sway and not the
#: markers' noise) over their sway in the sagittal plane the axes name, above which the
#: forward axis named is across the subject: a body on a platform tilting forward and back
#: sways forward and back (the example C3D trial: under 0.1; its lateral axis named forward:
#: 18).
SWAY_ACROSS_RATIO = 3.0
#: Degrees (SD) of sway about the lateral axis below which it is too small to tell.
SWAY_ACROSS_MIN_DEG = 0.05
#: The platform markers' back-to-front line must point within this of the forward axis,
#: degrees (in the horizontal plane): else the forward axis named is not the subject's.
PLATFORM_HEADING_LIMIT_DEG = 45.0


@dataclass(frozen=True)
class MarkerAngles(Result):
    """The angles a trial's markers give, and what was done to get them.

    Attributes:
        trial: the file as read. mapping: the markers, channels and axes used.
        theta: (F, N) rad, segment angles in space (the body COM's for a COM mapping).
        tilt: (F,) rad, the platform's tilt, or None (none in the file: the stimulus
            named fills it in).
        tilt_level_deg: degrees taken off the platform markers' angle (their angle at the
            start), or None.
        gaps: the gaps filled, per marker.
        points: each point's (F, 3) trajectory (m, gaps filled), by its flag spelling.
    """

    trial: MotionCaptureTrial
    mapping: MarkerMapping
    theta: np.ndarray
    tilt: np.ndarray | None
    tilt_level_deg: float | None
    gaps: tuple[Gap, ...]
    points: dict[str, np.ndarray] = field(repr=False)

    @property
    def time(self) -> np.ndarray:
        return self.trial.time

    def source(self) -> dict:
        """JSON-ready provenance: the file, its unit and rate, the markers, channels and
        axes used, the gaps filled and the platform level taken off."""
        return {
            "format": "c3d", "file": str(self.trial.path), "frames": self.trial.n_frames,
            "rate_hz": self.trial.rate_hz, "point_unit": self.trial.unit,
            **self.mapping.to_dict(),
            "tilt_level_deg": self.tilt_level_deg,
            "gaps_filled": [{"marker": g.marker,
                             "frames": [self.trial.frame_number(g.start),
                                        self.trial.frame_number(g.stop - 1)]}
                            for g in self.gaps],
            "subject_height_m": self.trial.height_m, "subject_mass_kg": self.trial.mass_kg,
        }

    def recording(self, segments: tuple[str, ...] | None = None,
                  tilt_of=None) -> Recording:
        """The sway as a :class:`Recording` for a body of ``segments`` (its link names, in
        order; default the mapping's names); without a platform in the file the tilt is
        ``tilt_of(time)`` (the named stimulus's, rad).

        Raises:
            RecordingError: a body of another number of segments; no platform and no
                stimulus named.
        """
        path = self.trial.path
        names = self.mapping.segment_labels if segments is None else tuple(segments)
        if len(names) != self.theta.shape[1]:
            flag = "--com-markers" if self.mapping.com is not None else "--segment-markers"
            raise RecordingError(
                f"{path}: {flag} give {self.theta.shape[1]} segment(s) "
                f"({', '.join(self.mapping.segment_labels)}) for a body of {len(names)} "
                f"({', '.join(names)}): give one per body segment, support upward")
        if self.tilt is not None:
            tilt = self.tilt
        elif tilt_of is not None:
            tilt = tilt_of(self.time)
        else:
            raise RecordingError(
                f"{path}: no platform tilt: give --tilt-markers BACK,FRONT (two platform "
                "markers) or --tilt-channel NAME (its angle sensor), or name the stimulus "
                "the trial was run with (the PRTS flags, or --tilt FILE)")
        return Recording(self.time, tilt, self.theta, names, str(path),
                         tilt_recorded=self.tilt is not None, source=self.source())

    def to_dict(self) -> dict:
        """The provenance (:meth:`source`) with the angles, degrees."""
        return {**self.source(), "time_s": self.time,
                "angles_deg": {name: np.degrees(self.theta[:, k])
                               for k, name in enumerate(self.mapping.segment_labels)},
                "tilt_deg": None if self.tilt is None else np.degrees(self.tilt)}

    def summary(self) -> str:
        gaps = len(self.gaps)
        return (f"{self.trial.path}: {self.trial.n_frames} frames at {self.trial.rate_hz:g} Hz,"
                f" {self.theta.shape[1]} angle(s) from markers, tilt "
                f"{'none' if self.tilt is None else 'recorded'}, {gaps} gap(s) filled")

    def plot(self, path=None, ax=None):
        """The raw marker traces (forward and vertical, about their means) beside the
        derived angles, gaps shaded: a visual check of the marker route."""
        from posture_id.plotting import plot_marker_angles

        return plot_marker_angles(self, path, ax)


def _point(point: MarkerPoint, tracks: dict[str, np.ndarray]) -> np.ndarray:
    return np.mean([tracks[m] for m in point.markers], axis=0)


def _sagittal_angle(vector: np.ndarray, forward: np.ndarray,
                    vertical: np.ndarray) -> np.ndarray:
    """(F,) rad, the angle of (F, 3) ``vector`` from the vertical, positive forward."""
    return np.arctan2(vector @ forward, vector @ vertical)


def _check_three_d(trial: MotionCaptureTrial, tracks: dict[str, np.ndarray],
                   mapping: MarkerMapping) -> None:
    """Refuse markers with no coordinate along the forward or the vertical axis."""
    stacked = np.stack(list(tracks.values()), axis=1)  # (F, M, 3)
    for flag, axis in (("--vertical-axis", mapping.axes.vertical),
                       ("--forward-axis", mapping.axes.forward)):
        index = "xyz".index(axis[-1])
        if np.all(stacked[..., index] == 0.0):
            spanned = [a for i, a in enumerate("xyz") if np.any(stacked[..., i] != 0.0)]
            raise RecordingError(
                f"{trial.path}: the markers have no {axis[-1]} coordinate (0 in every frame):"
                f" a 2-D file, or the wrong {flag}; its markers span "
                f"{', '.join(spanned) or 'nothing'}, and posture-id needs the forward and "
                "vertical coordinates of 3-D markers")


def _check_upright(trial: MotionCaptureTrial, label: str, vector: np.ndarray,
                   theta: np.ndarray, mapping: MarkerMapping, flag: str) -> None:
    """Refuse a segment that lies mostly outside the sagittal plane the axes name, or
    leans like no standing body's."""
    axes = mapping.axes
    sagittal = np.hypot(vector @ axes.forward_vector, vector @ axes.vertical_vector)
    share = float(np.median(sagittal / np.linalg.norm(vector, axis=1)))
    if share < SAGITTAL_SHARE:
        raise RecordingError(
            f"{trial.path}: {label} lies mostly outside the plane of --forward-axis "
            f"{axes.forward} and --vertical-axis {axes.vertical} (only {100 * share:.0f} % "
            "of its length in it): name the file's axes the subject faces and stands along")
    vertical = axes.vertical
    lean = float(np.degrees(np.mean(np.abs(theta))))
    if lean > UPRIGHT_LIMIT_DEG:
        raise RecordingError(
            f"{trial.path}: {label} leans {lean:.0f}° from the vertical on average, no "
            f"standing body's: check --vertical-axis (now {vertical}) and that {flag} name "
            "each lower point first")


def sway_across(vectors: list[np.ndarray], axes, rate_hz: float) -> tuple[float, float]:
    """(ratio, lateral SD in degrees) of the segments' sway (``vectors``, each (F, 3), the
    file's coordinates) about the horizontal axis ``axes`` leave unnamed against their sway
    in the sagittal plane ``axes`` name: each angle averaged over 1 s first (the sway kept,
    the markers' noise not); the ratio infinite when there is no sagittal sway."""
    forward, vertical = axes.forward_vector, axes.vertical_vector
    lateral = np.cross(vertical, forward)
    window = max(1, int(round(rate_hz)))

    def sway(axis: np.ndarray) -> float:
        return sum(float(np.var(np.convolve(_sagittal_angle(v, axis, vertical),
                                            np.ones(window) / window, mode="valid")))
                   for v in vectors)

    sagittal, across = sway(forward), sway(lateral)
    ratio = math.sqrt(across / sagittal) if sagittal > 0 else math.inf
    return ratio, math.degrees(math.sqrt(across / len(vectors)))


def _check_facing(trial: MotionCaptureTrial, vectors: list[np.ndarray],
                  mapping: MarkerMapping) -> None:
    """Refuse a forward axis across the subject: the segments (``vectors``, each (F, 3))
    sway more about the lateral axis than in the sagittal plane by SWAY_ACROSS_RATIO."""
    axes = mapping.axes
    ratio, lateral_deg = sway_across(vectors, axes, trial.rate_hz)
    if lateral_deg < SWAY_ACROSS_MIN_DEG or ratio <= SWAY_ACROSS_RATIO:
        return
    other = "xyz"[int(np.argmax(np.abs(np.cross(axes.vertical_vector, axes.forward_vector))))]
    how = (f"{ratio:.0f}× more along {other} than along --forward-axis {axes.forward}"
           if math.isfinite(ratio) else
           f"along {other}, and not at all along --forward-axis {axes.forward}")
    raise RecordingError(
        f"{trial.path}: the segments sway {how}; a body on a platform tilting forward and back "
        f"sways forward and back: is the subject facing {other} (--forward-axis {other}, "
        f"or --forward-axis=-{other})?")


def _tilt_from_markers(trial: MotionCaptureTrial, tilt: TiltMarkers,
                       tracks: dict[str, np.ndarray], mapping: MarkerMapping
                       ) -> tuple[np.ndarray, float]:
    forward, vertical = mapping.axes.forward_vector, mapping.axes.vertical_vector
    line = _point(tilt.front, tracks) - _point(tilt.back, tracks)
    horizontal = line - np.outer(line @ vertical, vertical)
    heading = float(np.degrees(np.arccos(np.clip(
        np.mean(horizontal @ forward / np.linalg.norm(horizontal, axis=1)), -1.0, 1.0))))
    if heading > PLATFORM_HEADING_LIMIT_DEG:
        raise RecordingError(
            f"{trial.path}: the platform markers' line {tilt.back}→{tilt.front} points "
            f"{heading:.0f}° away from --forward-axis {mapping.axes.forward}: name the axis "
            "the subject faces, and the back marker first (--tilt-markers BACK,FRONT)")
    angle = np.arctan2(-(line @ vertical), line @ forward)
    start = max(1, int(round(LEVEL_S * trial.rate_hz)))
    level = float(np.mean(angle[:start]))
    return angle - level, math.degrees(level)


def _tilt_from_channel(trial: MotionCaptureTrial, channel: TiltChannel) -> np.ndarray:
    values = trial.channel(channel.name)
    if trial.analog_rate_hz <= 0 or len(values) < 2:
        raise RecordingError(f"{trial.path}: analog channel {channel.name!r} has no samples "
                             "or no rate (ANALOG:RATE)")
    analog_time = np.arange(len(values)) / trial.analog_rate_hz
    if not np.all(np.isfinite(values)):
        raise RecordingError(f"{trial.path}: analog channel {channel.name!r} has missing "
                             "(NaN) samples")
    return np.radians(channel.deg_per_unit * np.interp(trial.time, analog_time, values))


def marker_angles(trial: MotionCaptureTrial, mapping: MarkerMapping) -> MarkerAngles:
    """The sagittal angles ``mapping`` names, from ``trial``'s markers and channels.

    Raises:
        RecordingError: naming the file: a marker it lacks (with those it has), a gap
            longer than ``mapping.max_gap_s``, 2-D markers, a segment that is not upright,
            platform markers that do not point forward, a missing analog channel.
    """
    trial.require_markers(mapping.markers)
    tracks, gaps = {}, []
    for label in mapping.markers:
        tracks[label], found = fill_gaps(trial.marker(label), trial.rate_hz,
                                         mapping.max_gap_s, label, str(trial.path),
                                         trial.frame_number)
        gaps += found
    _check_three_d(trial, tracks, mapping)
    forward, vertical = mapping.axes.forward_vector, mapping.axes.vertical_vector
    points: dict[str, np.ndarray] = {}
    angles, vectors = [], []
    if mapping.com is not None:
        com = mapping.com
        support = _point(com.support, tracks)
        centre = sum(w * _point(p, tracks) for p, w in zip(com.points, com.normalised_weights,
                                                            strict=True))
        points[str(com.support)] = support
        points["COM"] = centre
        vectors.append(centre - support)
        theta = _sagittal_angle(centre - support, forward, vertical)
        _check_upright(trial, "the body COM", centre - support, theta, mapping,
                       "--com-markers")
        angles.append(theta)
    for segment in mapping.segments:
        lower, upper = _point(segment.lower, tracks), _point(segment.upper, tracks)
        points[str(segment.lower)], points[str(segment.upper)] = lower, upper
        vectors.append(upper - lower)
        theta = _sagittal_angle(upper - lower, forward, vertical)
        _check_upright(trial, f"segment {segment.segment!r} ({segment})", upper - lower,
                       theta, mapping, "--segment-markers")
        angles.append(theta)
    tilt, level = None, None
    if isinstance(mapping.tilt, TiltMarkers):
        tilt, level = _tilt_from_markers(trial, mapping.tilt, tracks, mapping)
        points[str(mapping.tilt.back)] = _point(mapping.tilt.back, tracks)
        points[str(mapping.tilt.front)] = _point(mapping.tilt.front, tracks)
    elif isinstance(mapping.tilt, TiltChannel):
        tilt = _tilt_from_channel(trial, mapping.tilt)
    _check_facing(trial, vectors, mapping)  # after the platform markers' own heading check
    return MarkerAngles(trial, mapping, np.column_stack(angles), tilt, level, tuple(gaps),
                        points)
