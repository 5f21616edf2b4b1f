"""Which protocol pins the IC parameters best? (``posture-id design --model ic``)

The same Fisher-information reasoning as DEC's design (:mod:`posture_id.design.predict`),
on the IC fit's own numbers: for each of ``draws`` IC subjects
(:func:`~posture_id.models.ic.subjects.draw_ic_parameters`, the same subjects for every protocol)
and each recording of a protocol (every part, every repetition):

1. the exact derivatives of the model's locked COM-sway harmonics with respect to the
   identified parameters (:class:`~posture_id.models.exact.ExactResponse`: the response from
   rest, the transient included, as the fit sees it), projected as the fit projects them;
2. their noise: white sensor noise on the COM sway (σ/√(2·P·C) at each harmonic of a
   P-sample cycle averaged over C cycles) and, for people-like sway, the motor-noise-driven
   sway of that subject, simulated and scaled to leave ``locked_share`` of the COM sway
   locked, its cycle-average power taken at the compared harmonics (smoothed over
   neighbours);
3. the information summed over recordings, its inverse the covariance of the normalised
   parameters; the predicted 90 % interval width 2·z₀.₉₅·SE against the width of the
   parameter's search range (docs/model.md §8's bounds).

Per protocol: the median over subjects of each width and their geometric mean (the score,
smaller is better). It predicts the linearised fit; where the sway barely sees a parameter
the bounds, not the noise, cap it (a width near or above 1 means "not determined").
"""

from __future__ import annotations

import time as clock
from dataclasses import dataclass, field

import numpy as np

from posture_id.design.information import covariance
from posture_id.fileio import Result
from posture_id.fitting.frequency import IcFitOptions
from posture_id.frf.locked import LockedOptions, LockedProjection
from posture_id.models.exact import ExactResponse
from posture_id.models.ic.model import BOUNDS, IC, parameter_scale
from posture_id.models.ic.response import PARAMETER_ORDER, IcPlant
from posture_id.models.ic.subjects import draw_ic_parameters
from posture_id.progress import Progress, report
from posture_id.simulation.protocols import Protocol

__all__ = ["IcDesignResult", "design_ic", "SHOWN"]

#: The parameters the design ranks by.
SHOWN = ("kp", "kd", "delay_s", "w")
_SAMPLE_RATE_HZ = 50.0


@dataclass(frozen=True)
class IcDesignResult(Result):
    """Protocols ranked by how well they pin the IC parameters.

    Attributes:
        labels: per protocol. minutes: its recording time. widths: (protocols, 4)
        the median predicted 90 % width of Kp, Kd, Δ, W over the search range's width.
        scores: (protocols,) their geometric mean. sensor_noise_deg, locked_share: the
        noise planned for. draws: subjects. protocols: the protocols themselves.
    """

    labels: tuple[str, ...]
    minutes: tuple[float, ...]
    widths: np.ndarray = field(repr=False)
    scores: np.ndarray = field(repr=False)
    sensor_noise_deg: float = 0.05
    locked_share: float | None = None
    draws: int = 0
    seconds: float = 0.0
    protocols: tuple = field(default=(), repr=False)

    @property
    def order(self) -> list[int]:
        return sorted(range(len(self.labels)), key=lambda i: self.scores[i])

    def to_dict(self) -> dict:
        from posture_id.provenance import provenance
        from posture_id.simulation.protocols import protocol_to_dict

        return {"model": "ic", "sensor_noise_deg": self.sensor_noise_deg,
                "locked_share": self.locked_share, "draws": self.draws,
                "parameters": list(SHOWN),
                "protocols": [{"label": self.labels[i], "minutes": self.minutes[i],
                               "widths": dict(zip(SHOWN, self.widths[i].tolist(),
                                                  strict=True)),
                               "score": float(self.scores[i]),
                               "protocol": protocol_to_dict(self.protocols[i])
                               if self.protocols else None}
                              for i in self.order],
                "seconds": self.seconds, "provenance": provenance()}

    def markdown(self) -> str:
        noise = f"sensor {self.sensor_noise_deg:g}°" + (
            f", motor noise leaving {100 * self.locked_share:.0f} % of the COM sway locked"
            if self.locked_share else "")
        lines = ["# Experiment design for the IC model", "",
                 f"Noise: {noise}. {self.draws} IC subjects; {self.seconds:.0f} s. Each cell: "
                 "the predicted 90 % interval width of the IC fit against the width of the "
                 "parameter's search range (docs/model.md §8; median over subjects; below 0.1 well "
                 "determined, near 1 not). Made by `posture-id design --model ic` "
                 "(docs/ic.md).", "",
                 "| rank | protocol | min | score | Kp | Kd | Δ | W |",
                 "|---|---|---|---|---|---|---|---|"]
        for rank, i in enumerate(self.order, 1):
            cells = " | ".join(f"{w:.3f}" for w in self.widths[i])
            lines.append(f"| {rank} | {self.labels[i]} | {self.minutes[i]:.2f} | "
                         f"{self.scores[i]:.3f} | {cells} |")
        return "\n".join(lines)

    def summary(self) -> str:
        return self.markdown()

    def plot(self, path=None, ax=None):
        from posture_id.plotting import plot_score_grid

        order = self.order
        return plot_score_grid([self.labels[i] for i in order], list(SHOWN),
                               {"IC: predicted 90 % width / search range":
                                (self.widths[order], (0.0, 0.5), ".3f")}, path=path, ax=ax)

    def write(self, out) -> list:
        """design.md, design.json, design.png, protocols/NN.json (best first) and
        recommended.json."""
        from posture_id.design.report import write_design_folder

        ranked = [self.protocols[i] for i in self.order]
        return write_design_folder(out, self, ranked, ranked[0] if ranked else None)


def _recording_information(body, plant: IcPlant, params, profile,
                           free: tuple[str, ...], sensor_deg: float,
                           locked_share: float | None, seed: int,
                           locked: LockedOptions) -> np.ndarray:
    """(P, P) information of one recording about the normalised ``free`` parameters."""
    from posture_id.models.ic.simulation import simulate_ic

    duration = profile.duration
    n = int(round(duration * _SAMPLE_RATE_HZ)) + 1
    t = np.arange(n) / _SAMPLE_RATE_HZ
    tilt = profile.angle(t)
    period = profile.period_s
    projection = LockedProjection.for_recording(
        tilt, np.zeros((n, 1)), _SAMPLE_RATE_HZ, period, profile.periodic_from_s,
        LockedOptions(max_frequency_hz=locked.max_frequency_hz, weighted=False))
    model = ExactResponse(IC, tilt, _SAMPLE_RATE_HZ, plant)
    clean, dy = model.sway(params, gradient=True)
    columns = [PARAMETER_ORDER.index(f) for f in free]
    scales = np.array([parameter_scale(f, plant) for f in free])
    jac = projection.spectrum(np.degrees(dy[columns]).T * scales[None, :])  # (K, P)
    p = projection.period
    variance = np.full(len(projection.harmonics), sensor_deg ** 2 / (2 * p * projection.cycles))
    if locked_share:
        unit = simulate_ic(body, params, profile, motor_sd_deg=0.1, seed=seed)
        still = simulate_ic(body, params, profile)
        noise = np.degrees(body.com_angles(unit.theta)[:, 0] - body.com_angles(still.theta)[:, 0])
        if np.all(np.isfinite(noise)):
            level2 = np.var(np.degrees(clean)) * (1 - locked_share) / (
                locked_share * np.var(noise))
            power = np.abs(projection.all_harmonics(noise[:, None])[:, 0]) ** 2 * level2
            smooth = np.convolve(power, np.ones(7) / 7, mode="same")
            variance = variance + smooth[projection.harmonics - 1] / 2
    weights = 1 / np.sqrt(variance)
    real = np.vstack([(jac * weights[:, None]).real, (jac * weights[:, None]).imag])
    return real.T @ real


def design_ic(body, protocols: list[Protocol], sensor_noise_deg: float = 0.05,
              locked_share: float | None = None, draws: int = 8, seed: int = 0,
              options: IcFitOptions | None = None,
              progress: Progress | None = None) -> IcDesignResult:
    """Rank ``protocols`` by the predicted widths of the IC fit's Kp, Kd, Δ and W (the
    module doc)."""
    started = clock.perf_counter()
    options = options or IcFitOptions()
    plant = IcPlant.of(body)
    free = options.free
    shown = [free.index(p) for p in SHOWN]
    span = np.array([BOUNDS[p][1] - BOUNDS[p][0] for p in SHOWN])
    rng = np.random.default_rng(seed)
    subjects = [draw_ic_parameters(rng, plant) for _ in range(draws)]
    z = 1.6448536269514722
    widths = np.zeros((len(protocols), len(SHOWN)))
    total = len(protocols) * draws
    report(progress, 0, total, "subject")
    for i, protocol in enumerate(protocols):
        per_subject = []
        for d, params in enumerate(subjects):
            information = np.zeros((len(free), len(free)))
            for recording in protocol.recordings:
                information += recording.repetitions * _recording_information(
                    body, plant, params, recording.profile(), free,
                    sensor_noise_deg, locked_share, seed + d, options.locked)
            # ∞ where the protocol leaves a direction unseen (one sinusoid: 2 numbers for
            # the model's parameters), as DEC's design says it
            se = np.sqrt(np.clip(np.diag(covariance(information)), 0, None))[shown]
            per_subject.append(np.minimum(2 * z * se / span, 10.0))
            report(progress, i * draws + d + 1, total, "subject")
        widths[i] = np.median(per_subject, axis=0)
    scores = np.exp(np.mean(np.log(np.maximum(widths, 1e-12)), axis=1))
    return IcDesignResult(tuple(p.label() for p in protocols),
                          tuple(p.recording_minutes for p in protocols), widths, scores,
                          sensor_noise_deg, locked_share, draws,
                          clock.perf_counter() - started, tuple(protocols))
