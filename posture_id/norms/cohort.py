"""A cohort's FRFs at a lab's points, and each recording against a norm: the cohort of
``posture-id identify DIR --out FOLDER --band-preset NAME [--norm norm.json]`` then is a
normative set in one more command (``norm build FOLDER/*.frf.json``), and its
``summary.csv`` gains the norm test's columns."""

from __future__ import annotations

import csv
from pathlib import Path

from posture_id.cohorts import CohortRow, write_summary
from posture_id.errors import PostureIdError
from posture_id.frf.analysis import frequency_response
from posture_id.frf.bands import FrequencyBands
from posture_id.frf.response import FrfOptions
from posture_id.norms.norm import Norm, against_norm, tested_channels

__all__ = ["cohort_frfs", "NORM_COLUMNS"]

#: The columns a norm adds to a cohort's summary.csv.
NORM_COLUMNS = ("human_likeness", "inside_prediction_band", "distance_percentile")


def cohort_frfs(recordings: list[Path], out: Path, read, body_of, bands: FrequencyBands,
                norm: Norm | None = None) -> dict[str, str]:
    """Write ``<recording>.frf.json`` (the labs' convention at ``bands``) into ``out`` for
    every recording, test each against ``norm`` (when given) and add its columns to
    ``out``/summary.csv. ``read(path)``: the prepared trial at its own rate;
    ``body_of(path)``: its body (for the body COM channel). Returns the recordings whose
    FRF could not be computed, with why."""
    options = FrfOptions.lab_convention(bands)
    extras, failed = {}, {}
    for path in recordings:
        try:
            body = body_of(path)
            frf = frequency_response(read(path), body, options)
            frf.to_json(out / f"{path.stem}.frf.json")
            if norm is not None:
                names = tested_channels(norm, tuple(frf.channels), where=path.name)
                columns = [frf.channels.index(c) for c in names]
                tested = against_norm(norm, frf.frequencies_hz, frf.response[:, columns],
                                      path.name)
                extras[path.name] = {"human_likeness": tested.human_likeness,
                                     "inside_prediction_band": tested.inside_prediction_band,
                                     "distance_percentile": tested.distance_percentile}
        except PostureIdError as exc:
            failed[path.name] = str(exc)
    if norm is not None:
        _extend_summary(out / "summary.csv", extras)
    return failed


def _extend_summary(summary: Path, extras: dict[str, dict]) -> None:
    """summary.csv with the norm's columns (empty for a recording without them)."""
    with summary.open(encoding="utf-8", newline="") as handle:
        read = list(csv.DictReader(handle))
    fields = list(read[0]) if read else ["recording"]
    fields += [c for c in NORM_COLUMNS if c not in fields]
    rows = []
    for row in read:
        values = {**{k: v for k, v in row.items() if k not in ("recording", "status")},
                  **{c: "" for c in NORM_COLUMNS}}
        values.update({k: "" if v is None else v
                       for k, v in extras.get(row.get("recording"), {}).items()})
        rows.append(CohortRow(row.get("recording", ""), row.get("status", ""), values))
    write_summary(summary, rows, fields)
