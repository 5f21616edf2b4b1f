"""Results of a least-squares fit: each stage, and the whole fit with its provenance."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from statistics import NormalDist

import numpy as np

from posture_id.dec.parameters import TARGET_FIELDS, DecParameters, parameter_block
from posture_id.fileio import Result
from posture_id.fitting.unknowns import PER_MODULE, class_names
from posture_id.plotting import plot_fit
from posture_id.trials import PreparedTrial
from posture_id.uncertainty.conformal import ConformalCalibration
from posture_id.uncertainty.intervals import ParameterIntervals
from posture_id.uncertainty.noise import sensor_noise_deg

__all__ = ["StageResult", "FitResult", "class_names", "noise_allows"]


@dataclass(frozen=True)
class StageResult:
    """One bounded least-squares stage.

    Attributes:
        name: what the stage did. q: (7N,) unknowns at its end (see
            :mod:`posture_id.fitting.unknowns`). cost: ½Σr² (deg²). status: scipy's.
        converged: met its tolerance. iterations: Jacobian evaluations. evaluations:
            residual evaluations. jacobian: (S·N, free) at the end (deg per unit).
        residual: (S·N,) deg.
    """

    name: str
    q: np.ndarray = field(repr=False)
    cost: float
    status: int
    converged: bool
    iterations: int
    evaluations: int
    jacobian: np.ndarray = field(repr=False)
    residual: np.ndarray = field(repr=False)

    @property
    def classes(self) -> str:
        n = len(self.q) // PER_MODULE
        return class_names(np.sign(self.q[4 * n : 5 * n]))

    def to_dict(self) -> dict:
        return {"name": self.name, "cost": self.cost, "status": self.status,
                "converged": self.converged, "iterations": self.iterations,
                "evaluations": self.evaluations, "classes": self.classes}


@dataclass(frozen=True)
class FitResult(Result):
    """The identified parameters and how the fit went.

    Attributes:
        parameters: physical units. normalised: (N, 5) [K̃p, K̃i, K̃d, Δ̃, C].
        standard_errors: (N, 4) SE of Kp, Ki, Kd, Δ in physical units;
        standard_errors_normalised: (N, 4) the same relative to the defaults. For a locked
        fit they are the Gauss-Newton ones or, where larger, the cluster-robust ones
        (:mod:`~posture_id.fitting.structure`: the noise each harmonic shares between
        channels, read from the residual); white_standard_errors_normalised (N, 4), or
        None: the Gauss-Newton ones alone, as if every residual were independent.
        poorly_determined: (N, 4) bool. converged: the last stage met its tolerance.
        iterations: Jacobian evaluations in all. evaluations: residual evaluations.
        wall_time_s: s. cost: ½Σr² (deg² comparing every sample; in
            units of the noise level for a locked fit). rms_deg: RMS of fitted minus
            recorded angles, degrees.
        stages: every stage. backend: how CasADi ran. notices: things to know.
        time (S,) s, recorded and fitted (S, N) rad; segments, joints: names.
        provenance: package version, options and the body's identity.
        time_offset_s: the stimulus's fitted time offset, s (0 unless
            ``LockedOptions.max_offset_s`` asked for one).
        trial: the prepared trial fitted (with a fitted offset, the shifted one).
        defaults: the body's default parameters (p_default of the normalisation).
        residual_sd: the residual's SD (its units: degrees, or noise levels for a locked
            fit) and noise_floor_deg the least σ the standard errors assumed; the SEs use
            σ = max(residual_sd, noise_floor_deg).
        precision_rel: the precision ``poorly_determined`` was judged by.
        on_bounds: the parameters that ended on a bound of the search, as
            "<joint> <field> at its lower|upper bound (<value>)" (Kp, Ki, Kd, Δ; the
            passive terms too when they were fitted).
    """

    parameters: DecParameters
    normalised: np.ndarray
    standard_errors: np.ndarray
    standard_errors_normalised: np.ndarray
    poorly_determined: np.ndarray
    converged: bool
    iterations: int
    evaluations: int
    wall_time_s: float
    cost: float
    rms_deg: float
    stages: tuple[StageResult, ...]
    backend: str
    notices: tuple[str, ...]
    time: np.ndarray = field(repr=False)
    recorded: np.ndarray = field(repr=False)
    fitted: np.ndarray = field(repr=False)
    segments: tuple[str, ...] = ()
    joints: tuple[str, ...] = ()
    provenance: dict = field(default_factory=dict, repr=False)
    time_offset_s: float = 0.0
    residual_sd: float = math.nan
    noise_floor_deg: float = 0.0
    trial: PreparedTrial | None = field(default=None, repr=False, compare=False)
    defaults: DecParameters | None = field(default=None, repr=False, compare=False)
    on_bounds: tuple[str, ...] = ()
    precision_rel: float = 0.05
    white_standard_errors_normalised: np.ndarray | None = field(default=None, repr=False)

    @property
    def classes(self) -> tuple[str, ...]:
        """The fitted class C of each module (a :class:`~posture_id.dec.parameters.Controls`),
        support upward."""
        return tuple(self.parameters[j].controls for j in self.joints)

    def to_dict(self) -> dict:
        """JSON-ready (no sample arrays): parameters, standard errors, poorly determined
        fields, the solver's status and stages, bounds reached, notices and provenance."""
        fields = TARGET_FIELDS
        block = parameter_block(self.parameters, self.normalised)
        del block["class_probability_com"]  # least squares has no class probability
        return {
            **block,
            "standard_errors": {j: dict(zip(fields, map(_finite, row), strict=True))
                                for j, row in zip(self.joints, self.standard_errors,
                                                  strict=True)},
            "poorly_determined": {j: [f for f, bad in zip(fields, row, strict=True) if bad]
                                  for j, row in zip(self.joints, self.poorly_determined,
                                                    strict=True)},
            "status": {
                "converged": self.converged, "iterations": self.iterations,
                "evaluations": self.evaluations, "wall_time_s": self.wall_time_s,
                "cost_deg2": self.cost, "rms_deg": self.rms_deg, "backend": self.backend,
                "time_offset_s": self.time_offset_s,
                "stages": [s.to_dict() for s in self.stages],
            },
            "on_bounds": list(self.on_bounds),
            "notices": list(self.notices),
            "provenance": self.provenance,
        }

    def summary(self) -> str:
        """A printable table: values ± standard errors, flags, classes and the outcome."""
        lines = [
            f"{'module':<8}{'Kp':>11}{'Ki':>11}{'Kd':>11}{'Δ s':>11}  controls   "
            "(± standard error; * poorly determined)"
        ]
        for i, joint in enumerate(self.joints):
            m = self.parameters[joint]
            cells = []
            for k, (value, digits) in enumerate(
                ((m.kp, 2), (m.ki, 3), (m.kd, 3), (m.delay_s, 4))
            ):
                flag = "*" if self.poorly_determined[i, k] else " "
                cells.append(f"{value:>10.{digits}f}{flag}")
            lines.append(f"{joint:<8}{''.join(cells)}  {m.controls}")
            errs = "".join(f"{'±' + format(e, '.3g'):>11}" for e in self.standard_errors[i])
            lines.append(f"{'':<8}{errs}")
        status = "converged" if self.converged else "NOT converged"
        lines.append(f"{status} in {self.iterations} iterations, {self.wall_time_s:.1f} s, "
                     f"residual RMS {self.rms_deg:.5f}° ({self.backend})"
                     + (f"; stimulus offset {1000 * self.time_offset_s:+.0f} ms"
                        if self.time_offset_s else ""))
        if self.on_bounds:
            lines.append("on a search bound (a wider --gain-range / --delay-range, or for a "
                         "noisy recording --locked --prior-sd 0.5): " + ", ".join(self.on_bounds))
        lines += [f"note: {n}" for n in self.notices]
        return "\n".join(lines)

    @property
    def intervals(self) -> ParameterIntervals:
        """The 90 % Gauss-Newton intervals, ±z·SE (:meth:`intervals_at` for another level
        or calibrated scales)."""
        return self.intervals_at(0.9)

    def intervals_at(self, level: float = 0.9, scales: ConformalCalibration | None = None,
                     at_least: np.ndarray | None = None, at_least_from: str = ""
                     ) -> ParameterIntervals:
        """Intervals of Kp, Ki, Kd, Δ at ``level``: ±z·SE (the standard errors as
        reported: for a locked fit, widened where the residual's structure asks,
        :mod:`~posture_id.fitting.structure`) or, with the ``scales`` of a calibration
        (:mod:`posture_id.studies.calibration`, made of Gauss-Newton standard errors),
        ±scale·SE_GN, where scale is the conformal one at the recording's estimated sensor
        noise, never below :func:`noise_allows`, and the interval never narrower than
        that least scale times the reported SE: a calibrated interval is never narrower
        than the interval of the fit's own residual noise and its structure.
        ``at_least``: (N, 4) normalised half-widths no interval is narrower than
        (``at_least_from`` says whose, for the intervals' method line)."""
        if self.defaults is None:
            raise ValueError("intervals need the body's defaults (FitResult.defaults)")
        defaults = self.defaults
        z = NormalDist().inv_cdf((1 + level) / 2)
        noise = sensor_noise_deg(self.recorded)
        se = self.standard_errors_normalised
        white = self.white_standard_errors_normalised
        white = se if white is None else white
        structured = bool(np.any(se > white))
        widened = ", widened by the residual's structure" if structured else ""
        method = f"Gauss-Newton ±z·SE{widened} (coverage not checked)"
        half_width = z * se
        if scales is not None:
            least = noise_allows(level, self.residual_sd, self.noise_floor_deg)
            factor = np.maximum(scales.scale(level, noise), least)
            half_width = np.maximum(factor * white, least * se)
            method = "Gauss-Newton SE × calibrated scale" + (
                ", no narrower than the residual's structure allows" if structured else "")
        si = np.column_stack([defaults.array(f) for f in TARGET_FIELDS])
        if at_least is not None:
            half_width = np.maximum(half_width, at_least)
            method += f", no narrower than {at_least_from or 'given'}"
        return ParameterIntervals.around(self.normalised[:, :4], half_width, si,
                                         level, method, noise, self.joints,
                                         self.poorly_determined, self.precision_rel)

    def plot(self, path=None, ax=None):
        """Recorded versus fitted sway per segment (degrees); saved to ``path`` if given,
        drawn into ``ax`` (N axes) if given."""
        return plot_fit(self, path=path, ax=ax)


def noise_allows(level: float, residual_sd: float, noise_floor: float) -> float:
    """The least scale of the standard errors at ``level``: z·σ_residual/σ_SE, the
    Gauss-Newton half-width of the fit's own residual noise (z when the residual is above
    the standard errors' floor; less when the floor made them wider than the noise)."""
    z = NormalDist().inv_cdf((1 + level) / 2)
    if not (noise_floor > 0 and math.isfinite(residual_sd)):
        return z
    return z * min(1.0, residual_sd / noise_floor)


def _finite(x) -> float | None:
    """A standard error for JSON: None when it is infinite (not determined at all)."""
    x = float(x)
    return x if np.isfinite(x) else None
