"""A simulated trial written as a force plate records it: time, platform tilt, COP and
normal force (:func:`~posture_id.force_plate.cop.cop_of_motion`), in the project's CSV
or as a lab's export (tab-separated, a title line, times in ms, units in the header)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from posture_id.errors import RecordingError
from posture_id.fileio import atomic_write_text
from posture_id.force_plate.cop import cop_of_motion
from posture_id.recording import Recording

__all__ = ["ExportFormat", "PROJECT_CSV", "LAB_EXPORT", "force_plate_columns",
           "write_force_plate_csv"]


@dataclass(frozen=True)
class ExportFormat:
    """How the columns are written.

    Attributes:
        delimiter: between fields. decimal_comma: numbers written with a decimal comma.
        time_ms: the time in milliseconds (else seconds). units_in_brackets: the header
        names its units as ``Name [unit]`` (else ``name_unit``). title: a line above the
        header (None: none).
    """

    delimiter: str = ","
    decimal_comma: bool = False
    time_ms: bool = False
    units_in_brackets: bool = False
    title: str | None = None

    def __post_init__(self) -> None:
        if self.decimal_comma and self.delimiter == ",":
            raise RecordingError("a decimal comma needs another delimiter than the comma")


#: The project's CSV: ``time_s,tilt_deg,cop_mm,fz_n``.
PROJECT_CSV = ExportFormat()
#: A posturography system's export: tab-separated, a title line, ms, units in brackets.
LAB_EXPORT = ExportFormat(delimiter="\t", time_ms=True, units_in_brackets=True,
                          title="Force plate export")


def force_plate_columns(body, recording: Recording, cop_noise_mm: float = 0.0,
                        seed: int = 0, ankle_height_m: float = 0.0) -> dict[str, np.ndarray]:
    """{time_s, tilt_deg, cop_mm, fz_n}: (S,) each, the samples before any fall (a fallen
    trial's motion stops there), white noise of ``cop_noise_mm`` (SD) on the COP; the
    plate's surface ``ankle_height_m`` below the ankle axis."""
    if not (math.isfinite(cop_noise_mm) and cop_noise_mm >= 0):
        raise RecordingError(f"COP noise must be a finite number ≥ 0 mm, got {cop_noise_mm}")
    finite = np.all(np.isfinite(recording.theta), axis=1)
    last = len(finite) if finite.all() else int(np.argmin(finite))
    if last < 4:
        raise RecordingError(f"{recording.name}: fewer than 4 samples before the body fell")
    theta, tilt = recording.theta[:last], recording.tilt[:last]
    cop, force = cop_of_motion(body, theta, tilt, recording.sample_rate_hz, ankle_height_m)
    cop_mm = 1e3 * cop
    if cop_noise_mm > 0:
        cop_mm = cop_mm + cop_noise_mm * np.random.default_rng(seed).standard_normal(last)
    return {"time_s": recording.time[:last], "tilt_deg": np.degrees(tilt),
            "cop_mm": cop_mm, "fz_n": force}


def write_force_plate_csv(path: str | Path, body, recording: Recording,
                          cop_noise_mm: float = 0.0, seed: int = 0,
                          export: ExportFormat = PROJECT_CSV, ankle_height_m: float = 0.0
                          ) -> Path:
    """Write :func:`force_plate_columns` atomically in ``export``'s format."""
    columns = force_plate_columns(body, recording, cop_noise_mm, seed, ankle_height_m)
    if export.units_in_brackets:
        header = ["Time [ms]" if export.time_ms else "Time [s]", "Platform [deg]",
                  "COP AP [mm]", "Fz [N]"]
    else:
        header = ["time_ms" if export.time_ms else "time_s", "tilt_deg", "cop_mm", "fz_n"]
    time = columns["time_s"] * (1e3 if export.time_ms else 1.0)
    rows = np.column_stack([time, columns["tilt_deg"], columns["cop_mm"], columns["fz_n"]])
    rows[rows == 0] = 0.0  # no "-0.0000"
    formats = ("{:.10g}" if export.time_ms else "{:.6f}", "{:.4f}", "{:.2f}", "{:.1f}")
    lines = [] if export.title is None else [export.title]
    lines.append(export.delimiter.join(header))
    for row in rows:
        text = [f.format(v) for f, v in zip(formats, row, strict=True)]
        if export.decimal_comma:
            text = [t.replace(".", ",") for t in text]
        lines.append(export.delimiter.join(text))
    return atomic_write_text(Path(path), "\n".join(lines) + "\n")
