"""The demo: identify the example recordings shipped with the package and compare with the
parameters they were simulated with.

The examples (``posture_id/studies/examples/``, made by ``make examples``) are simulated
subjects with 0.01° white sensor noise: a TIP and a straight-leg 2-segment body (the
paper's human experiment). ``posture-id demo --out DIR`` identifies each with the hybrid
(the bundled universal network's answer refined by least squares), prints identified
against true parameters, and writes ``DIR/report.md`` with a plot per recording.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from posture_id.bodies.body import BUNDLED_URDFS, load_body
from posture_id.dec.parameters import TARGET_FIELDS, DecParameters
from posture_id.fileio import atomic_write_text
from posture_id.identify.core import Method, identify
from posture_id.identify.result import IdentificationResult
from posture_id.progress import Progress, report
from posture_id.recording import Recording

__all__ = ["EXAMPLES_DIR", "EXAMPLES", "DemoRow", "run_demo"]

EXAMPLES_DIR = Path(__file__).resolve().parent / "examples"
#: Example name → the bundled body it was simulated on (see the Makefile's examples).
EXAMPLES = {"tip_subject": "tip_default", "straight_leg_subject": "winter_1.75m_70kg_2seg"}


@dataclass(frozen=True)
class DemoRow:
    """One example: what was identified, what is true."""

    name: str
    body: str
    result: IdentificationResult
    truth: DecParameters

    def relative_errors(self) -> np.ndarray:
        """(N, 4) identified / true − 1 of Kp, Ki, Kd, Δ."""
        return np.column_stack([self.result.parameters.array(f) / self.truth.array(f) - 1
                                for f in TARGET_FIELDS])

    def table(self) -> str:
        lines = ["| module | | Kp | Ki | Kd | Δ (s) | controls |", "|---|---|---|---|---|---|---|"]
        errors = self.relative_errors()
        for i, joint in enumerate(self.result.joints):
            got, true = self.result.parameters[joint], self.truth[joint]
            lines.append(f"| {joint} | identified | {got.kp:.2f} | {got.ki:.3f} | {got.kd:.2f} | "
                         f"{got.delay_s:.4f} | {got.controls} |")
            lines.append(f"| | true | {true.kp:.2f} | {true.ki:.3f} | {true.kd:.2f} | "
                         f"{true.delay_s:.4f} | {true.controls} |")
            lines.append("| | error | " + " | ".join(f"{100 * e:+.1f} %" for e in errors[i])
                         + f" | {'right' if got.controls == true.controls else 'WRONG'} |")
            intervals = self.result.intervals
            if intervals is not None:
                cells = []
                for k, field in enumerate(TARGET_FIELDS):
                    low, high = intervals.lower_si[i, k], intervals.upper_si[i, k]
                    inside = low <= getattr(true, field) <= high
                    cells.append(f"{low:.4g}–{high:.4g}{'' if inside else ' (truth outside)'}")
                lines.append(f"| | {100 * intervals.level:g} % interval | " + " | ".join(cells)
                             + " | |")
        return "\n".join(lines)


def run_demo(out: str | Path, method: Method = Method.HYBRID,
             progress: Progress | None = None) -> list[DemoRow]:
    """Identify every example, write ``out/report.md``, a JSON and a PNG per example."""
    out = Path(out)
    rows = []
    for name, body_name in EXAMPLES.items():
        body = load_body(BUNDLED_URDFS[body_name])
        csv = EXAMPLES_DIR / f"{name}.csv"
        truth = DecParameters.from_json(EXAMPLES_DIR / f"{name}.truth.json", body)
        report(progress, len(rows), len(EXAMPLES), "recording", f"identifying {csv.name} "
               f"({body_name}, {method.value})")
        result = identify(Recording.from_csv(csv, body.segment_names), body, method,
                          progress=progress)
        result.to_json(out / f"{name}.json")
        result.plot(out / f"{name}.png")
        result.plot_intervals(out / f"{name}.intervals.png")
        rows.append(DemoRow(name, body_name, result, truth))
    atomic_write_text(out / "report.md", _markdown(rows, method))
    return rows


def _markdown(rows: list[DemoRow], method: Method) -> str:
    parts = ["# posture_id demo", "",
             f"Each example recording (simulated subject, 0.01° sensor noise; made by `make "
             f"examples`) identified with `{method.value}` (the bundled universal network, then "
             "least squares from its answer) and compared with the parameters it was simulated "
             "with. Made by `posture-id demo`.", ""]
    for row in rows:
        r = row.result
        parts += [f"## {row.name} (body {row.body})", "", row.table(), "",
                  f"Re-simulated body sway: E_rel {100 * r.e_rel:.2f} %, E_id "
                  f"{r.e_id_deg:.2e}°; " + ", ".join(
                      f"{s.segment} {100 * s.variance_explained:.1f} % of variance"
                      for s in r.segments) + f"; {r.wall_time_s:.1f} s.", "",
                  f"![{row.name}]({row.name}.png)", ""]
        if r.intervals is not None:
            parts += [f"Intervals: {r.intervals.method}, at the recording's estimated sensor "
                      f"noise {r.intervals.noise_deg:.3f}°. "
                      + " ".join(s[0].upper() + s[1:] + "." for s in r.intervals.sentences()),
                      "", f"![{row.name} intervals]({row.name}.intervals.png)", ""]
        parts += [f"Note: {n}" for n in r.notices] + [""]
    return "\n".join(parts)
