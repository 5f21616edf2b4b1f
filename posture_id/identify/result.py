"""The answer to "how does this body keep its balance": an identification result."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from posture_id.dec.parameters import Controls, DecParameters, parameter_block
from posture_id.fileio import Result
from posture_id.identify.method import Method
from posture_id.identify.verdict import TrustVerdict
from posture_id.plotting import plot_identification
from posture_id.uncertainty.intervals import ParameterIntervals

if TYPE_CHECKING:  # CasADi and torch load only with the methods that need them
    from posture_id.fitting.result import FitResult
    from posture_id.learning.identifier import CnnIdentification

__all__ = ["SegmentFit", "IdentificationResult", "FELL", "NOTHING_BALANCES"]

#: The one line of a result whose identified model falls in re-simulation.
FELL = ("the identified model falls in re-simulation{at}: these parameters do not balance "
        "this body on this stimulus; try --method hybrid, or for noisy sway --method fit "
        "--locked --prior-sd 0.5")
#: ``auto``'s notice when everything it tries falls (and the line such a result ends with).
NOTHING_BALANCES = "no model tried balances this body on this stimulus"
FELL_AFTER_ALL = ("the identified model falls in re-simulation{at}: " + NOTHING_BALANCES
                  + " (the network's answer, least squares from it and from the body's "
                  "defaults): check that the body (--body) and the stimulus are the "
                  "recording's")


@dataclass(frozen=True)
class SegmentFit:
    """How well the identified model reproduces one recorded segment.

    Attributes:
        segment: link name. rms_deg: RMS of recorded minus re-simulated angle, degrees.
        variance_explained: 1 − var(residual) / var(recorded), of the raw sway.
        locked_variance_explained: the share of the stimulus-locked sway (the drift-free
            cycle average at the stimulated harmonics) that the identified model explains;
            None for a stimulus that is not periodic.
        locked_share: the share of the recorded sway's variance that is stimulus-locked
            (the rest: noise, drift, sway of the subject's own); None likewise.
    """

    segment: str
    rms_deg: float
    variance_explained: float
    locked_variance_explained: float | None = None
    locked_share: float | None = None


@dataclass(frozen=True)
class IdentificationResult(Result):
    """Identified DEC parameters of one recording and the evidence for them.

    Attributes:
        method: :class:`Method`. parameters: every module, SI units (the
            parameter-file format). normalised: (N, 5) [K̃p, K̃i, K̃d, Δ̃, C].
        class_probability: (N,) P(C = +1) from the CNN, or None (least squares alone).
        e_id_deg, e_rel: docs/model.md §7 of the body sway α_BS, recorded against re-simulated
            with the identified parameters (inf when the re-simulation falls).
        segments: per-segment fit. wall_time_s: the whole call's time, s.
        identification_time_s: s spent identifying (the CNN and/or least squares), without
            the checks and the re-simulation that every method shares.
        time (S,) s; recorded, resimulated (S, N) rad; sway_recorded, sway_resimulated (S,)
        rad (α_BS); joints. cnn, fit: the stages' own results
        (:class:`~posture_id.learning.identifier.CnnIdentification`,
        :class:`~posture_id.fitting.result.FitResult`), or None.
        intervals: each parameter's interval and how well the recording determines it
            (:class:`~posture_id.uncertainty.intervals.ParameterIntervals`), or None (a
            CNN without a calibration).
        notices: things to know. provenance: version, options, body identity, source.
        verdict: whether the answer should be trusted, and what to run if not
            (:class:`~posture_id.identify.verdict.TrustVerdict`), or None.
        relaxed_refit: the hybrid fitted again with the classes relaxed (the CNN was unsure
            of a class, or its classes left more than the recording's noise).
        stimulus_offset_s: s, how far the answer's stimulus is from the one recorded or
            named (moved by ``auto`` to where the sway says it ran, or fitted with
            ``--max-offset-s``); 0 when it is where the file or the command line put it.
    """

    method: Method
    parameters: DecParameters
    normalised: np.ndarray
    class_probability: np.ndarray | None
    e_id_deg: float
    e_rel: float
    segments: tuple[SegmentFit, ...]
    wall_time_s: float
    identification_time_s: float
    joints: tuple[str, ...]
    time: np.ndarray = field(repr=False)
    recorded: np.ndarray = field(repr=False)
    resimulated: np.ndarray = field(repr=False)
    sway_recorded: np.ndarray = field(repr=False)
    sway_resimulated: np.ndarray = field(repr=False)
    cnn: CnnIdentification | None = field(default=None, repr=False)
    fit: FitResult | None = field(default=None, repr=False)
    intervals: ParameterIntervals | None = None
    notices: tuple[str, ...] = ()
    provenance: dict = field(default_factory=dict, repr=False)
    fell_at_s: float | None = None
    verdict: TrustVerdict | None = None
    relaxed_refit: bool = False
    stimulus_offset_s: float = 0.0

    @property
    def fell(self) -> bool:
        """The identified model falls in re-simulation (E_rel is then ∞)."""
        return self.fell_at_s is not None or not np.isfinite(self.e_rel)

    @property
    def classes(self) -> tuple[Controls, ...]:
        """The identified class C of each module (:class:`Controls`), support upward."""
        return tuple(self.parameters[j].controls for j in self.joints)

    def to_dict(self) -> dict:
        """JSON-ready (no sample arrays): parameters, errors, per-segment fit, trust verdict,
        intervals, notices, the stages' results and provenance."""
        return {
            "method": self.method.value,
            **parameter_block(self.parameters, self.normalised, self.class_probability),
            "e_id_deg": self.e_id_deg,
            "e_rel": self.e_rel,
            "segments": {s.segment: {"rms_deg": s.rms_deg,
                                     "variance_explained": s.variance_explained,
                                     "locked_variance_explained": s.locked_variance_explained,
                                     "locked_share": s.locked_share}
                         for s in self.segments},
            "fell_at_s": self.fell_at_s,
            "stimulus_offset_s": self.stimulus_offset_s,
            "trust": None if self.verdict is None else self.verdict.to_dict(),
            "wall_time_s": self.wall_time_s,
            "identification_time_s": self.identification_time_s,
            "intervals": None if self.intervals is None else self.intervals.to_dict(),
            "notices": list(self.notices),
            "cnn": None if self.cnn is None else self.cnn.to_dict(),
            "fit": None if self.fit is None else {k: v for k, v in self.fit.to_dict().items()
                                                  if k != "provenance"},
            "provenance": self.provenance,
        }

    def fell_line(self) -> str:
        """The one line that says the identified model falls (and what to try, unless
        ``auto`` tried it all already)."""
        at = "" if self.fell_at_s is None else f" at t = {self.fell_at_s:.2f} s"
        tried = any(NOTHING_BALANCES in notice for notice in self.notices)
        return (FELL_AFTER_ALL if tried else FELL).format(at=at)

    def summary(self) -> str:
        """A printable report: the parameter table, the re-simulation's fit (or that it
        falls), the time taken, the intervals, notices and the trust verdict."""
        lines = self.parameters.identified_table(self.class_probability)
        if self.fell:
            lines.append(self.fell_line())
        else:
            lines.append("re-simulated: " + ", ".join(
                f"{s.segment} RMS {s.rms_deg:.4f}° (raw sway: {100 * s.variance_explained:.1f} "
                "% of the variance explained" + (
                    "" if s.locked_variance_explained is None else
                    "; stimulus-locked sway" + ("" if s.locked_share is None else
                                                f", {100 * s.locked_share:.0f} % of it") + ": "
                    f"{100 * s.locked_variance_explained:.1f} % explained") + ")"
                for s in self.segments))
            lines.append(f"body sway: E_id {self.e_id_deg:.2e}°, E_rel "
                         f"{100 * self.e_rel:.2f} % (of the raw sway)")
        lines.append(f"{self.method.value} in {self.identification_time_s:.3g} s "
                     f"({self.wall_time_s:.3g} s with the checks)")
        if self.intervals is not None:
            lines += self.intervals.table()
        lines += [f"note: {n}" for n in self.notices]
        if self.verdict is not None:
            lines.append(self.verdict.line())
        return "\n".join(lines)

    def plot(self, path=None, ax=None):
        """Recorded versus re-simulated sway per segment and of the body COM (Fig. 7)."""
        return plot_identification(self, path=path, ax=ax)

    def plot_intervals(self, path=None, ax=None):
        """Each parameter's interval against the prior's (None without intervals)."""
        if self.intervals is None:
            return None
        return self.intervals.plot(self.normalised[:, :4], path=path, ax=ax)
