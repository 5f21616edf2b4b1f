"""Predict, for a body, a noise model and candidate protocols, how well a locked
least-squares fit will determine every module's Kp, Ki, Kd, delay and class.

For each of ``draws`` subjects drawn from docs/model.md §5's prior (the same subjects for every
protocol, so protocols are compared on equal terms):

1. the exact Jacobian of the CasADi model (:class:`~posture_id.fitting.problem.
   FitProblem`, the fit's own model) with respect to the normalised gains, delays and
   relaxed classes, along the protocol's whole recording from rest, projected as the
   locked fit projects the sway (:class:`~posture_id.frf.locked.LockedProjection`,
   unweighted: the cycle average of every cycle, drift removed, at the harmonics the tilt
   excites up to ``max_frequency_hz``); the transient is in it, as it is in the fit;
2. the noise of those harmonics: white sensor noise, and the simulated noise-driven sway
   of that subject (:func:`.noise.noise_spectra`), divided by the cycles averaged;
3. the information (:mod:`.information`) of every recording and repetition, summed; the
   weighted fit's covariance A⁻¹BA⁻¹ with the classes known (the fit's final polish)
   gives the standard errors of K̃p, K̃i, K̃d, Δ̃, and with the relaxed classes free the
   standard error of each class c, whose sign is the class: the chance of calling it
   wrong is Φ(−1/SE(c));
4. the errors of that fit held within its search bounds (:mod:`.bounded`, Monte Carlo of
   the linearised fit): where the sway says little about a parameter the bounds, not the
   noise, cap its error and those of the parameters estimated with it.

The predicted 90 % interval width is 2·z₀.₉₅·SE (unbounded where the sway does not see a
parameter), reported against the prior's own 90 % width (:func:`prior_width`); the
per-protocol summary is the median over the subjects that stayed up under every protocol
(the protocols are compared on the same subjects), and the predicted RMS error is that of
the bounded fit over those subjects and their noise draws.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field

import numpy as np
from scipy.optimize import brentq
from scipy.stats import norm

from posture_id.bodies.body import Body
from posture_id.choices import Choice
from posture_id.dec.parameters import ParameterArrays, default_parameters, normalise_arrays
from posture_id.dec.prior import SIGMA, sample_parameters
from posture_id.design.bounded import bounded_errors, fit_bounds
from posture_id.design.information import Information, harmonic_information
from posture_id.design.noise import DesignError, NoiseSpectra, SwayNoise, noise_spectra
from posture_id.errors import PostureIdError
from posture_id.fitting.options import FitOptions
from posture_id.fitting.problem import FitProblem
from posture_id.fitting.symbolic import step_inputs
from posture_id.fitting.unknowns import q_from_targets
from posture_id.frf.locked import LockedOptions, LockedProjection
from posture_id.progress import Progress, report
from posture_id.simulation.batch import simulate_batch
from posture_id.simulation.options import SimulationOptions
from posture_id.simulation.protocols import Protocol, SingleProtocol

__all__ = ["DesignOptions", "Residual", "ProtocolPrediction", "predict_protocols", "prior_width"]

class Residual(Choice):
    """What the predicted fit minimises (:class:`DesignOptions`)."""

    LOCKED = "locked"
    RAW = "raw"



@dataclass(frozen=True)
class DesignOptions:
    """How a design is computed.

    Attributes:
        draws: subjects drawn from the prior. seed: their seed.
        level: the interval's level (0.9).
        dt: integration step of the Jacobian's model, s (5 ms: about 3× faster than the
            fit's 2 ms; 10 ms makes the semi-implicit Euler step unstable for many
            subjects; docs/design.md checks 5 ms against 2.5 ms by step-halving).
        max_frequency_hz: highest harmonic compared (as the locked fit's).
        excited_threshold: a harmonic is compared when the tilt's amplitude there exceeds
            this share of its largest (as the locked fit's).
        noise_cycles: cycles of noise-driven sway simulated for its spectrum.
        error_draws: noise draws per subject of the bounded fit's error (:mod:`.bounded`).
        residual: :attr:`Residual.LOCKED` (default): the locked fit, each harmonic and
            channel weighted by its own noise; :attr:`Residual.RAW`: least squares on every
            sample, which weighs every frequency alike (by Parseval; in steady state the
            tilt's response lives at
            its harmonics, so the same harmonics, unweighted, with the noise there; what
            the raw fit gains from the transient outside them is left out).
    """

    draws: int = 8
    seed: int = 0
    level: float = 0.9
    dt: float = 0.005
    max_frequency_hz: float = 2.0
    excited_threshold: float = 1e-3
    noise_cycles: int = 8
    residual: Residual = Residual.LOCKED
    error_draws: int = 256

    def __post_init__(self) -> None:
        if self.draws < 1 or self.noise_cycles < 1 or self.error_draws < 1:
            raise DesignError("draws, noise_cycles and error_draws must be ≥ 1")
        if not 0 < self.level < 1:
            raise DesignError(f"level must be in (0, 1), got {self.level}")
        try:
            object.__setattr__(self, "residual", Residual(self.residual))
        except ValueError:
            raise DesignError(f"residual must be 'locked' or 'raw', got {self.residual!r}") \
                from None

    def to_dict(self) -> dict:
        return asdict(self)


def prior_width(level: float = 0.9, sigma: float = SIGMA) -> float:
    """The width of the prior's central ``level`` interval of a normalised gain or delay
    p̃ = |1 + X| − 1, X ~ N(0, σ²) (docs/model.md §5)."""

    def cdf(y: float) -> float:  # P(|1 + X| ≤ y)
        return float(norm.cdf((y - 1) / sigma) - norm.cdf((-y - 1) / sigma))

    lo = brentq(lambda y: cdf(y) - (1 - level) / 2, 0.0, 1 + 10 * sigma)
    hi = brentq(lambda y: cdf(y) - (1 + level) / 2, 0.0, 1 + 10 * sigma)
    return hi - lo


@dataclass(frozen=True)
class ProtocolPrediction:
    """What a protocol is predicted to determine.

    Attributes:
        protocol: the protocol. label: its name.
        minutes, peak_to_peak_deg, peak_velocity_deg_s: what it asks of the lab.
        standard_errors: (D, N, 4) normalised SE of K̃p, K̃i, K̃d, Δ̃ per subject (NaN for
            a subject who fell), ∞ where the harmonics do not see a parameter.
        class_se: (D, N) SE of the relaxed class c.
        bounded_rms: (D, N, 4) RMS error of the fit held within its bounds, per subject
            (:mod:`.bounded`; NaN for a subject who fell).
        widths: (N, 4) median over subjects of the predicted 90 % width / the prior's.
        rms_error: (N, 4) predicted RMS error of the normalised parameters (the bounded
            fit's, over the subjects summarised).
        class_wrong: (N,) mean chance of calling the class wrong.
        subjects: the subjects summarised: those who stayed up under every protocol
            predicted together (else under this one). seconds: time taken.
    """

    protocol: Protocol
    label: str
    minutes: float
    peak_to_peak_deg: float
    peak_velocity_deg_s: float
    standard_errors: np.ndarray = field(repr=False)
    class_se: np.ndarray = field(repr=False)
    bounded_rms: np.ndarray = field(repr=False)
    widths: np.ndarray
    rms_error: np.ndarray
    class_wrong: np.ndarray
    subjects: int
    seconds: float

    def to_dict(self) -> dict:
        """JSON-ready through :func:`~posture_id.fileio.json_text` (∞ becomes null)."""
        return {"protocol": self.protocol.to_dict(), "label": self.label,
                "minutes": self.minutes, "peak_to_peak_deg": self.peak_to_peak_deg,
                "peak_velocity_deg_s": self.peak_velocity_deg_s, "widths": self.widths,
                "rms_error": self.rms_error, "class_wrong": self.class_wrong,
                "subjects": self.subjects, "standard_errors": self.standard_errors,
                "class_se": self.class_se, "bounded_rms": self.bounded_rms,
                "seconds": self.seconds}


class _Recording:
    """One single protocol's compiled model over its whole recording, its tilt input, and
    the locked fit's own (unweighted) projection of the sway onto the compared harmonics:
    the cycle average of every cycle from rest, drift removed, its excited harmonics up to
    ``max_frequency_hz``."""

    def __init__(self, body: Body, protocol: SingleProtocol, options: DesignOptions,
                 notify) -> None:
        sim = SimulationOptions(dt=options.dt)
        rate = sim.sample_rate_hz
        self.protocol = protocol
        self.profile = protocol.profile()
        self.n_samples = int(round(self.profile.duration * rate)) + 1
        self.problem = FitProblem.get(body, self.n_samples, FitOptions(simulation=sim),
                                      notify=notify)
        self.simulation = sim
        tilt, velocity = self.profile.on_grid(options.dt, self.problem.n_steps_u)
        self.u = step_inputs(tilt, velocity, self.problem.n_steps_u)
        on_samples = self.profile.angle(np.arange(self.n_samples) / rate)
        try:
            self.projection = LockedProjection.for_recording(
                on_samples, np.zeros((self.n_samples, 1)), rate, protocol.period_s,
                self.profile.periodic_from_s,
                LockedOptions(weighted=False, max_frequency_hz=options.max_frequency_hz,
                              excited_threshold=options.excited_threshold),
                protocol.label())
        except PostureIdError as exc:
            raise DesignError(str(exc)) from None
        self.rows = self.projection.harmonics - 1

    def stays_up(self, body: Body, params) -> np.ndarray:
        """(D,) the subjects who stay within the sway limit over the recording (the fast
        simulator, the Jacobian's step)."""
        return simulate_batch(body, params, self.profile, self.simulation, workers=1).stable

    def harmonics_jacobian(self, q: np.ndarray, columns: list[int]) -> np.ndarray:
        """(K, N, len(columns)) complex, degrees: ∂(compared harmonics)/∂q."""
        n = self.problem.n
        jac = self.problem.jacobian(q, self.u, columns).reshape(self.n_samples, n, -1)
        return self.projection.spectrum(np.degrees(jac))


def predict_protocols(body: Body, protocols: list[Protocol], noise: SwayNoise,
                      options: DesignOptions | None = None,
                      progress: Progress | None = None,
                      params: ParameterArrays | None = None) -> list[ProtocolPrediction]:
    """Predictions for every protocol (module docstring); for the subjects ``params``
    (D, N) when given (a check against fits of those subjects), else ``options.draws``
    drawn from the prior."""
    options = options or DesignOptions()
    if not protocols:
        raise DesignError("no protocol to predict")
    n = body.n_segments
    gains_delays = list(range(4 * n))
    classes = list(range(4 * n, 5 * n))
    if params is None:
        params = sample_parameters(body, options.draws, np.random.default_rng(
            np.random.SeedSequence([options.seed, 0x44455349])))
    draws = params.kp.shape[0]
    targets = normalise_arrays(params, default_parameters(body))  # (D, N, 5)
    z = norm.ppf(0.5 + options.level / 2)
    width0 = prior_width(options.level)
    lower, upper = fit_bounds(n)
    recordings: dict = {}
    per_protocol = []
    total = sum(len(p.recordings) for p in protocols)
    done = 0

    def say(message: str) -> None:
        report(progress, done, total, "message", message)

    for protocol in protocols:
        started = time.perf_counter()
        info: list[Information | None] = [None] * draws
        stable = np.ones(draws, bool)
        for single in protocol.recordings:
            if single not in recordings:
                recordings[single] = _Recording(body, single, options, say)
            rec = recordings[single]
            spectra: NoiseSpectra = noise_spectra(
                body, params, single, noise, options.seed, options.noise_cycles,
                options=SimulationOptions(dt=options.dt))
            stable &= spectra.stable & rec.stays_up(body, params)
            for d in range(draws):
                if not stable[d]:
                    continue
                q = q_from_targets(targets[d])
                jac = rec.harmonics_jacobian(q, gains_delays + classes)
                if not np.all(np.isfinite(jac)):  # the model's rollout diverged
                    stable[d] = False
                    continue
                cov = spectra.covariance[d][rec.rows] / single.cycles
                one = single.repetitions * harmonic_information(
                    jac, cov, weighted=options.residual is Residual.LOCKED)
                info[d] = one if info[d] is None else info[d] + one
            done += 1
            report(progress, done, total, "recording", single.label())
        se = np.full((draws, n, 4), np.nan)
        class_se = np.full((draws, n), np.nan)
        bounded = np.full((draws, n, 4), np.nan)
        for d in range(draws):
            if not stable[d] or info[d] is None:
                continue
            known = info[d].marginal(np.arange(4 * n))
            se[d] = np.sqrt(np.diag(known.fit_covariance())).reshape(4, n).T
            free = info[d].fit_covariance()
            class_se[d] = np.sqrt(np.diag(free))[4 * n:5 * n]
            errors = bounded_errors(known, targets[d, :, :4].T.ravel(), lower, upper,
                                    options.error_draws,
                                    np.random.default_rng([options.seed, 0x424F, d]))
            bounded[d] = np.sqrt(np.mean(errors**2, axis=0)).reshape(4, n).T
        if not stable.any():
            raise DesignError(f"{protocol.label()}: every drawn subject fell; draw more")
        per_protocol.append((protocol, se, class_se, bounded, stable,
                             time.perf_counter() - started))
    # compare the protocols on the subjects who stay up under every one of them (each on
    # its own where none does)
    common = np.all([stable for *_, stable, _ in per_protocol], axis=0)
    return [ProtocolPrediction(
        protocol, protocol.label(), protocol.recording_minutes, protocol.peak_to_peak_deg,
        protocol.peak_velocity_deg_s, se, class_se, bounded,
        *_summary(se, class_se, bounded, common if common.any() else stable, z, width0),
        seconds)
        for protocol, se, class_se, bounded, stable, seconds in per_protocol]


def _summary(se: np.ndarray, class_se: np.ndarray, bounded: np.ndarray,
             subjects: np.ndarray, z: float, width0: float
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """(widths, rms_error, class_wrong, count) of ``subjects`` (mask)."""
    se, class_se, bounded = se[subjects], class_se[subjects], bounded[subjects]
    with np.errstate(invalid="ignore"):
        widths = np.median(2 * z * se, axis=0) / width0
        rms = np.sqrt(np.mean(bounded**2, axis=0))
        wrong = np.mean(norm.cdf(-1.0 / class_se), axis=0)
    return widths, rms, wrong, int(subjects.sum())
