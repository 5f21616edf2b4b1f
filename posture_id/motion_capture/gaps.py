"""Gaps in a marker's trajectory (frames where the cameras did not see it): filled by a
documented rule up to a limit, refused beyond it.

The rule: a gap of at most ``max_gap_s`` between seen frames is filled by a cubic spline
through the marker's seen frames (each coordinate its own: scipy's not-a-knot
``CubicSpline`` over at most :data:`SUPPORT_FRAMES` seen frames each side, the fill labs
know from their capture software); a gap at the start or the end of the trial, which no
spline can bridge, holds the nearest seen position when it is within the limit. A longer
gap is refused with the marker, the frames and the seconds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from posture_id.errors import RecordingError

__all__ = ["Gap", "find_gaps", "fill_gaps", "SUPPORT_FRAMES"]

#: Seen frames each side of a gap that the spline passes through.
SUPPORT_FRAMES = 10


@dataclass(frozen=True)
class Gap:
    """Frames ``start``..``stop - 1`` (0-based) of one marker not seen."""

    marker: str
    start: int
    stop: int

    @property
    def frames(self) -> int:
        return self.stop - self.start


def find_gaps(seen: np.ndarray, marker: str) -> list[Gap]:
    """The runs of False in ``seen`` ((F,) bool), in order."""
    edges = np.diff(np.concatenate(([1], seen.astype(np.int8), [1])))
    starts, stops = np.flatnonzero(edges == -1), np.flatnonzero(edges == 1)
    return [Gap(marker, int(a), int(b)) for a, b in zip(starts, stops, strict=True)]


def fill_gaps(track: np.ndarray, rate_hz: float, max_gap_s: float, marker: str,
              where: str, frame_number=lambda i: i + 1) -> tuple[np.ndarray, list[Gap]]:
    """One marker's trajectory with its gaps filled.

    Args:
        track: (F, 3) m, NaN where the marker was not seen.
        rate_hz: frames per second. max_gap_s: s, the longest gap filled.
        marker: its label; where: the file, for messages; frame_number: the file's number
            of a 0-based frame, for messages.

    Returns:
        the filled (F, 3) trajectory, and the gaps filled.

    Raises:
        RecordingError: the marker never seen, or a gap longer than ``max_gap_s``, named by
            marker, frames and seconds.
    """
    seen = np.all(np.isfinite(track), axis=1)
    if not seen.any():
        raise RecordingError(f"{where}: marker {marker!r} is never seen (no frame has it)")
    gaps = find_gaps(seen, marker)
    if not gaps:
        return track, []
    limit = int(np.floor(max_gap_s * rate_hz + 1e-9))
    for gap in gaps:
        if gap.frames > limit:
            raise RecordingError(
                f"{where}: marker {marker!r} is missing in frames {frame_number(gap.start)}–"
                f"{frame_number(gap.stop - 1)} ({gap.start / rate_hz:.2f}–"
                f"{(gap.stop - 1) / rate_hz:.2f} s, {gap.frames / rate_hz:.2f} s), longer than"
                f" the {max_gap_s:g} s a gap may be filled (--max-gap-s); fill it in the "
                "capture software or leave the marker out")
    filled = track.copy()
    seen_index = np.flatnonzero(seen)
    for gap in gaps:
        if gap.start == 0 or gap.stop == len(track):  # an end: hold the nearest seen frame
            nearest = gap.stop if gap.start == 0 else gap.start - 1
            filled[gap.start:gap.stop] = track[nearest]
            continue
        before = seen_index[seen_index < gap.start][-SUPPORT_FRAMES:]
        after = seen_index[seen_index >= gap.stop][:SUPPORT_FRAMES]
        support = np.concatenate((before, after))
        if len(support) < 4:  # too few frames for a cubic: a straight line
            for axis in range(3):
                filled[gap.start:gap.stop, axis] = np.interp(
                    np.arange(gap.start, gap.stop), support, track[support, axis])
            continue
        spline = CubicSpline(support, track[support], axis=0)
        filled[gap.start:gap.stop] = spline(np.arange(gap.start, gap.stop))
    return filled, gaps
