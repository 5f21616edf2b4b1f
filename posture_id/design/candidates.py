"""The protocols a design compares when none are given: today's PRTS and what a lab can
run instead within about 3 minutes and 4° peak to peak."""

from __future__ import annotations

from posture_id.simulation.protocols import (
    MultisineProtocol,
    Protocol,
    PrtsProtocol,
    SumOfSinesProtocol,
    TwoAmplitudeProtocol,
)

__all__ = ["default_candidates", "TODAY"]

#: Today's protocol (docs/model.md §4): the 242-state PRTS, 1° peak to peak, two cycles.
TODAY = PrtsProtocol(242, 0.25, 1.0, 2)


def default_candidates() -> list[Protocol]:
    """Ten protocols: PRTS of both lengths at 1–4°, a low-frequency multisine, a sum of
    sines and a two-amplitude PRTS; each at most 3.0 minutes of recording."""
    return [
        TODAY,
        PrtsProtocol(242, 0.25, 3.0, 2),
        PrtsProtocol(80, 0.25, 1.0, 9),
        PrtsProtocol(80, 0.25, 4.0, 9),
        PrtsProtocol(80, 0.3, 2.0, 7),
        PrtsProtocol(242, 0.2, 2.0, 3),
        MultisineProtocol(60.0, (1, 2, 3, 5, 8, 12, 18, 27, 40, 60, 90), 2.0, cycles=3),
        MultisineProtocol(60.0, (1, 2, 3, 4, 5, 6, 8, 10, 13, 17, 22), 4.0, cycles=3),
        SumOfSinesProtocol((0.05, 0.1, 0.2, 0.4, 0.8), (1.0, 0.7, 0.4, 0.25, 0.15), cycles=9),
        TwoAmplitudeProtocol(PrtsProtocol(80, 0.25, 1.0, 4), (1.0, 4.0)),
    ]
