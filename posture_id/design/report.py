"""A design's result: the predictions, the ranking for a goal, a report and a plot."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from posture_id.bodies.body import Body
from posture_id.design.goal import PARAMETERS, DesignGoal
from posture_id.design.noise import SwayNoise
from posture_id.design.predict import DesignOptions, ProtocolPrediction, predict_protocols
from posture_id.fileio import atomic_write_text, json_text
from posture_id.progress import Progress
from posture_id.simulation.protocols import Protocol, write_protocol

__all__ = ["DesignResult", "Ranked", "UNDETERMINED", "design"]

_NAMES = {"kp": "Kp", "ki": "Ki", "kd": "Kd", "delay_s": "Δ"}
#: A parameter whose median predicted width is at least this share of the prior's is not
#: determined: beyond the fit's linear range (docs/design.md, the check).
UNDETERMINED = 0.5


@dataclass(frozen=True)
class Ranked:
    """One protocol's place: its score for the goal (∞: a chosen parameter unbounded) and
    the limits it breaks (then it is not ranked)."""

    prediction: ProtocolPrediction
    score: float
    breaks: tuple[str, ...]

    @property
    def allowed(self) -> bool:
        return not self.breaks


@dataclass(frozen=True)
class DesignResult:
    """Predictions for a body, a noise model and candidate protocols, ranked for a goal.

    Attributes:
        body: the body's name. joints: its joints. noise, options, goal: what was asked.
        predictions: one per protocol, in the order given. seconds: time taken.
    """

    body: str
    joints: tuple[str, ...]
    noise: SwayNoise
    options: DesignOptions
    goal: DesignGoal
    predictions: tuple[ProtocolPrediction, ...]
    seconds: float

    def ranking(self, goal: DesignGoal | None = None) -> list[Ranked]:
        """Every protocol, the allowed ones best first, then those breaking a limit."""
        goal = goal or self.goal
        ranked = [Ranked(p, goal.score(p.widths), tuple(goal.breaks(
            p.minutes, p.peak_to_peak_deg, p.peak_velocity_deg_s))) for p in self.predictions]
        return sorted(ranked, key=lambda r: (not r.allowed, r.score))

    @property
    def notices(self) -> tuple[str, ...]:
        """Where the predictions should not be trusted as they stand: a protocol that
        leaves parameters undetermined (median predicted width at least
        :data:`UNDETERMINED` of the prior's). The fit then works beyond its linear range
        for them, and the widths predicted for the others are likely too narrow
        (docs/design.md: 1.3–1.75× on people-like sway); and goal limits that no
        candidate meets."""
        out = []
        if self.predictions and self.best is None:
            out.append("no candidate keeps within the goal's limits (each row says which it "
                       "breaks): nothing is recommended and recommended.json is not written; "
                       "relax a limit or give candidates that meet it (--protocol)")
        for p in self.predictions:
            loose = int(np.sum(~(p.widths < UNDETERMINED)))
            if loose:
                out.append(f"{p.label}: {loose} of {p.widths.size} parameters are not "
                           f"determined (width ≥ {UNDETERMINED:g} of the prior's); the fit "
                           "works beyond its linear range for them, and the widths predicted "
                           "for the others are likely too narrow")
        return tuple(out)

    @property
    def best(self) -> ProtocolPrediction | None:
        first = self.ranking()[0]
        return first.prediction if first.allowed and math.isfinite(first.score) else None

    def to_dict(self) -> dict:
        return {"body": self.body, "joints": list(self.joints), "noise": self.noise.to_dict(),
                "options": self.options.to_dict(), "goal": self.goal.to_dict(),
                "ranking": [{"label": r.prediction.label, "score": r.score,
                             "breaks": list(r.breaks)} for r in self.ranking()],
                "predictions": [p.to_dict() for p in self.predictions],
                "notices": list(self.notices), "seconds": self.seconds}

    def markdown(self) -> str:
        head = "| rank | protocol | min | ° p-p | °/s | score | " + " | ".join(
            f"{_NAMES[p]} {j}" for j in self.joints for p in PARAMETERS) + " | class wrong % |"
        lines = [f"# Experiment design for {self.body}", "",
                 f"Noise: {self.noise.label()}. Goal: {self.goal.label()}. "
                 f"{self.options.draws} subjects drawn from the prior (seed "
                 f"{self.options.seed}); {self.seconds:.0f} s.", "",
                 f"Each cell: the predicted 90 % interval width of the {self.options.residual} "
                 "least-squares "
                 "fit against the prior's (median over subjects; below 0.25 well "
                 "determined, above 0.75 not). Score: geometric mean over the goal's "
                 "parameters (smaller is better). Class wrong: mean predicted chance per "
                 "module. Made by `posture-id design` (docs/design.md).", "",
                 head, "|" + "---|" * (7 + 4 * len(self.joints))]
        for i, r in enumerate(self.ranking(), 1):
            p = r.prediction
            rank = str(i) if r.allowed else "–"
            cells = " | ".join(_cell(v) for v in p.widths.ravel())
            wrong = " / ".join(f"{100 * v:.1f}" for v in p.class_wrong)
            note = f" (breaks {', '.join(r.breaks)})" if r.breaks else ""
            lines.append(f"| {rank} | {p.label}{note} | {p.minutes:.2f} | "
                         f"{p.peak_to_peak_deg:.2g} | {p.peak_velocity_deg_s:.2g} | "
                         f"{_cell(r.score)} | {cells} | {wrong} |")
        best = self.best
        if best is not None:
            lines += ["", f"Recommended: **{best.label}** ({best.subjects} of "
                          f"{self.options.draws} drawn subjects stayed up under every "
                          "protocol; every protocol is summarised on them)."]
        if self.notices:
            lines += ["", "Notices:", ""] + [f"- {n}" for n in self.notices]
        return "\n".join(lines)

    def plot(self, path: str | Path | None = None, ax=None):
        from posture_id.plotting import plot_identifiability

        labels = [f"{_NAMES[p]} {j}" for j in self.joints for p in PARAMETERS]
        ratios = {p.label: np.minimum(p.widths.ravel(), 3.0) for p in self.predictions}
        return plot_identifiability(ratios, labels, path, ax)

    def write(self, out: str | Path) -> list[Path]:
        """design.md, design.json, design.png and protocols/NN.json (each candidate's
        protocol, for ``posture-id stimulus`` and ``--protocol``) into ``out``."""
        return write_design_folder(out, self, [p.protocol for p in self.predictions],
                                   None if self.best is None else self.best.protocol)


def write_design_folder(out: str | Path, result, protocols: list,
                        recommended) -> list[Path]:
    """A design's folder: ``result``'s design.md (its ``markdown()``), design.json and
    design.png, ``protocols``/NN.json in their order and ``recommended``.json (when one is
    recommended)."""
    out = Path(out)
    (out / "protocols").mkdir(parents=True, exist_ok=True)
    files = [atomic_write_text(out / "design.md", result.markdown() + "\n"),
             atomic_write_text(out / "design.json", json_text(result.to_dict()))]
    result.plot(out / "design.png")
    files.append(out / "design.png")
    for i, protocol in enumerate(protocols, 1):
        files.append(write_protocol(protocol, out / "protocols" / f"{i:02d}.json"))
    if recommended is not None:
        files.append(write_protocol(recommended, out / "recommended.json"))
    return files


def _cell(value: float) -> str:
    if not math.isfinite(value):
        return "∞"
    return f"{value:.2f}" if value < 10 else f"{value:.0f}"


def design(body: Body, protocols: list[Protocol], noise: SwayNoise,
           goal=None, options: DesignOptions | None = None,
           progress: Progress | None = None):
    """Predict every protocol and rank them for ``goal``
    (:class:`DesignResult`)."""
    options = options or DesignOptions()
    started = time.perf_counter()
    predictions = predict_protocols(body, protocols, noise, options, progress)
    return DesignResult(body.name, tuple(body.joint_names), noise, options,
                        goal or DesignGoal(), tuple(predictions),
                        time.perf_counter() - started)
