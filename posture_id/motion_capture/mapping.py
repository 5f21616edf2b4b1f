"""Which markers and channels of a motion-capture trial make which angle, and how the
lab's axes lie: the typed form of ``--segment-markers``, ``--com-markers``,
``--tilt-markers``, ``--tilt-channel`` and the axis flags.

A *point* is one marker or the mean of several (``LGTR+RGTR``: both hips averaged). A
segment is the line from its lower point to its upper point (support upward); its angle is
that line's angle from the vertical in the sagittal plane, positive for a forward lean
(docs/model.md §1). The body COM of a 1-segment body is a weighted combination of points, its
angle that of the line from the support point to it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from posture_id.errors import RecordingError

__all__ = ["MarkerPoint", "SegmentMarkers", "ComMarkers", "TiltMarkers", "TiltChannel",
           "LabAxes", "MarkerMapping", "parse_segment_markers", "parse_com_markers",
           "parse_tilt_markers", "AXES", "DEFAULT_MAX_GAP_S"]

#: The axis names a flag may give: the file's own axes, either sense.
AXES = ("x", "y", "z", "-x", "-y", "-z")
#: Gaps (occluded marker frames) up to this long are filled, s; longer ones are refused.
DEFAULT_MAX_GAP_S = 0.2


@dataclass(frozen=True)
class MarkerPoint:
    """A point of the body or the platform: one marker, or the mean of several.

    Attributes:
        markers: the markers' labels as the file spells them (≥ 1).
    """

    markers: tuple[str, ...]

    def __post_init__(self) -> None:
        if not self.markers or any(not m.strip() for m in self.markers):
            raise RecordingError(f"a marker point needs marker names, got "
                                 f"{'+'.join(self.markers)!r}")

    @classmethod
    def parse(cls, text: str) -> MarkerPoint:
        """``ANK`` or ``LGTR+RGTR`` (the mean of several markers)."""
        return cls(tuple(m.strip() for m in text.split("+")))

    def __str__(self) -> str:
        return "+".join(self.markers)


@dataclass(frozen=True)
class SegmentMarkers:
    """One body segment: the points at its lower and upper end (support upward).

    Attributes:
        segment: the segment's name (a label: segments are matched to the body in order).
        lower, upper: its ends.
    """

    segment: str
    lower: MarkerPoint
    upper: MarkerPoint

    def __str__(self) -> str:
        return f"{self.segment}={self.lower},{self.upper}"


@dataclass(frozen=True)
class ComMarkers:
    """The body COM as labs define it from markers, for a 1-segment body.

    Attributes:
        support: the point the COM angle is measured from (the ankles).
        points: the points whose weighted mean is the COM.
        weights: one per point, > 0; normalised to sum 1.
    """

    support: MarkerPoint
    points: tuple[MarkerPoint, ...]
    weights: tuple[float, ...]

    def __post_init__(self) -> None:
        if not self.points or len(self.points) != len(self.weights):
            raise RecordingError("--com-markers: give the support point, then one or more "
                                 "weighted points (NAME:WEIGHT)")
        if any(not (math.isfinite(w) and w > 0) for w in self.weights):
            raise RecordingError(f"--com-markers: weights must be finite and > 0, got "
                                 f"{', '.join(f'{w:g}' for w in self.weights)}")

    @property
    def normalised_weights(self) -> np.ndarray:
        """(P,) the weights, summing to 1."""
        w = np.asarray(self.weights, dtype=float)
        return w / w.sum()

    def __str__(self) -> str:
        return " ".join([str(self.support),
                         *(f"{p}:{w:g}" for p, w in zip(self.points, self.weights, strict=True))])


@dataclass(frozen=True)
class TiltMarkers:
    """The platform's tilt from two markers on it, one behind the ankles, one in front."""

    back: MarkerPoint
    front: MarkerPoint

    def __str__(self) -> str:
        return f"{self.back},{self.front}"


@dataclass(frozen=True)
class TiltChannel:
    """The platform's tilt from an analog channel (its angle sensor).

    Attributes:
        name: the channel's label as the file spells it.
        deg_per_unit: degrees of tilt per unit of the channel (1: the channel is in
            degrees), positive when the front edge goes down.
    """

    name: str
    deg_per_unit: float = 1.0

    def __post_init__(self) -> None:
        if not self.name.strip():
            raise RecordingError("--tilt-channel needs the channel's name")
        if not (math.isfinite(self.deg_per_unit) and self.deg_per_unit != 0):
            raise RecordingError(f"--tilt-scale must be a finite number other than 0 "
                                 f"degrees per unit, got {self.deg_per_unit}")


def _axis_vector(name: str) -> np.ndarray:
    vector = np.zeros(3)
    vector["xyz".index(name[-1])] = -1.0 if name.startswith("-") else 1.0
    return vector


@dataclass(frozen=True)
class LabAxes:
    """How the lab's coordinate axes lie: which one points forward (the way the subject
    faces) and which one up.

    Attributes:
        forward: one of :data:`AXES`. vertical: one of :data:`AXES` (default ``z``).
    """

    forward: str
    vertical: str = "z"

    def __post_init__(self) -> None:
        for flag, axis in (("--forward-axis", self.forward), ("--vertical-axis",
                                                               self.vertical)):
            if axis not in AXES:
                raise RecordingError(f"{flag} must be one of {', '.join(AXES)}, got {axis!r}")
        if self.forward[-1] == self.vertical[-1]:
            raise RecordingError(f"--forward-axis {self.forward} and --vertical-axis "
                                 f"{self.vertical} are the same axis: forward must be "
                                 "horizontal")

    @property
    def forward_vector(self) -> np.ndarray:
        """(3,) unit vector, the file's coordinates."""
        return _axis_vector(self.forward)

    @property
    def vertical_vector(self) -> np.ndarray:
        """(3,) unit vector, the file's coordinates (up)."""
        return _axis_vector(self.vertical)


@dataclass(frozen=True)
class MarkerMapping:
    """How a motion-capture trial becomes a recording: the angles' markers, the tilt's
    source, the axes, and how long a gap may be filled.

    Attributes:
        axes: the lab's forward and vertical axes.
        segments: one per body segment, support upward (empty with ``com``).
        com: the body COM of a 1-segment body (None with ``segments``).
        tilt: two platform markers, an analog channel, or None (the stimulus is named or
            recognised, as for a file without a tilt column).
        max_gap_s: s, the longest gap filled (cubic spline over the marker's own frames);
            a longer one is refused.
    """

    axes: LabAxes
    segments: tuple[SegmentMarkers, ...] = ()
    com: ComMarkers | None = None
    tilt: TiltMarkers | TiltChannel | None = None
    max_gap_s: float = DEFAULT_MAX_GAP_S

    def __post_init__(self) -> None:
        if bool(self.segments) == (self.com is not None):
            raise RecordingError("name the body's markers: --segment-markers (one per "
                                 "segment, support upward) or --com-markers (a 1-segment "
                                 "body), one of the two")
        names = [s.segment for s in self.segments]
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            raise RecordingError(f"--segment-markers: segment {', '.join(twice)} named twice")
        if not (math.isfinite(self.max_gap_s) and self.max_gap_s >= 0):
            raise RecordingError(f"--max-gap-s must be a finite number ≥ 0 s, got "
                                 f"{self.max_gap_s}")

    @property
    def n_segments(self) -> int:
        """The number of body segments the mapping gives angles for (1 for a COM mapping)."""
        return 1 if self.com is not None else len(self.segments)

    @property
    def segment_labels(self) -> tuple[str, ...]:
        """The segments' names as the mapping gives them (``body`` for a COM mapping)."""
        return ("body",) if self.com is not None else tuple(s.segment for s in self.segments)

    @property
    def markers(self) -> tuple[str, ...]:
        """Every marker label the mapping reads, in first-use order."""
        points: list[MarkerPoint] = []
        for s in self.segments:
            points += [s.lower, s.upper]
        if self.com is not None:
            points += [self.com.support, *self.com.points]
        if isinstance(self.tilt, TiltMarkers):
            points += [self.tilt.back, self.tilt.front]
        return tuple(dict.fromkeys(m for p in points for m in p.markers))

    def to_dict(self) -> dict:
        """JSON-ready: the flags' own spelling of every part."""
        return {
            "forward_axis": self.axes.forward, "vertical_axis": self.axes.vertical,
            "segment_markers": [str(s) for s in self.segments],
            "com_markers": None if self.com is None else str(self.com),
            "tilt_markers": str(self.tilt) if isinstance(self.tilt, TiltMarkers) else None,
            "tilt_channel": self.tilt.name if isinstance(self.tilt, TiltChannel) else None,
            "tilt_scale_deg_per_unit": (self.tilt.deg_per_unit
                                        if isinstance(self.tilt, TiltChannel) else None),
            "max_gap_s": self.max_gap_s,
        }


def parse_segment_markers(items: list[str] | tuple[str, ...]) -> tuple[SegmentMarkers, ...]:
    """``SEGMENT=LOWER,UPPER`` each (a point may be ``A+B``), support upward."""
    segments = []
    for item in items:
        name, eq, ends = item.partition("=")
        parts = ends.split(",")
        if not eq or not name.strip() or len(parts) != 2 or not all(p.strip() for p in parts):
            raise RecordingError(f"--segment-markers: {item!r} is not SEGMENT=LOWER,UPPER "
                                 "(e.g. leg=ANK,HIP; a point may average markers: "
                                 "LGTR+RGTR)")
        segments.append(SegmentMarkers(name.strip(), MarkerPoint.parse(parts[0]),
                                       MarkerPoint.parse(parts[1])))
    return tuple(segments)


def parse_com_markers(items: list[str] | tuple[str, ...]) -> ComMarkers:
    """``SUPPORT POINT:WEIGHT ...`` (e.g. ``LANK+RANK LGTR+RGTR:0.6 LSHO+RSHO:0.4``); a point
    without ``:WEIGHT`` weighs 1."""
    if len(items) < 2:
        raise RecordingError("--com-markers: give the support point (the ankles), then the "
                             "weighted points of the COM, e.g. ANK HIP:0.6 SHO:0.4")
    points, weights = [], []
    for item in items[1:]:
        name, colon, weight = item.rpartition(":") if ":" in item else (item, "", "1")
        try:
            value = float(weight)
        except ValueError:
            raise RecordingError(f"--com-markers: {item!r}: the weight {weight!r} is not a "
                                 "number (POINT:WEIGHT)") from None
        points.append(MarkerPoint.parse(name))
        weights.append(value)
    return ComMarkers(MarkerPoint.parse(items[0]), tuple(points), tuple(weights))


def parse_tilt_markers(text: str) -> TiltMarkers:
    """``BACK,FRONT``: the platform markers behind and in front of the ankles."""
    parts = text.split(",")
    if len(parts) != 2 or not all(p.strip() for p in parts):
        raise RecordingError(f"--tilt-markers: {text!r} is not BACK,FRONT (two platform "
                             "markers, behind and in front of the ankles)")
    return TiltMarkers(MarkerPoint.parse(parts[0]), MarkerPoint.parse(parts[1]))
