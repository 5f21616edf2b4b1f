"""How the least-squares fit runs: typed, frozen options (no string flags).

:class:`FitOptions` embeds the :class:`~posture_id.simulation.options.SimulationOptions`
of the recordings it models (step, output rate, dead-band); the class strategy and the
compilation mode are typed values.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field

from posture_id.errors import PostureIdError
from posture_id.frf.locked import LockedOptions
from posture_id.models.dec import DELAY_BOUNDS, GAIN_BOUNDS
from posture_id.simulation.options import SimulationOptions

__all__ = [
    "FitError",
    "Compilation",
    "RelaxedClasses",
    "ExhaustiveClasses",
    "FixedClasses",
    "ClassStrategy",
    "FitOptions",
]


class FitError(PostureIdError):
    """A fit request is inconsistent (options, recording, initial guess)."""


class Compilation(enum.Enum):
    """How CasADi's functions run: compiled to C when a compiler exists (AUTO), compiled
    or fail (ALWAYS), or in CasADi's virtual machine (NEVER; slower, no compiler)."""

    AUTO = "auto"
    ALWAYS = "always"
    NEVER = "never"


@dataclass(frozen=True)
class RelaxedClasses:
    """Relax every class C to c ∈ [−1, 1], fit it with the rest, take C = sign(c), then
    refit the continuous parameters with C fixed: one relaxed fit instead of 2^N.

    Attributes:
        starts: relaxed fits from the initial guess and from ``starts − 1`` draws of the
            docs/model.md §5 prior (classes open); the best goes on to the polish.
        seed: seed of those draws.
    """

    starts: int = 1
    seed: int = 0

    def __post_init__(self) -> None:
        if isinstance(self.starts, bool) or not isinstance(self.starts, int) or self.starts < 1:
            raise FitError(f"starts must be an integer ≥ 1, got {self.starts!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise FitError(f"seed must be an integer ≥ 0, got {self.seed!r}")


@dataclass(frozen=True)
class ExhaustiveClasses:
    """Fit every one of the 2^N class combinations; keep the best."""


@dataclass(frozen=True)
class FixedClasses:
    """Keep the classes of the initial guess."""


ClassStrategy = RelaxedClasses | ExhaustiveClasses | FixedClasses


@dataclass(frozen=True)
class FitOptions:
    """How to fit (see :mod:`posture_id.fitting.least_squares`).

    Attributes:
        simulation: the model of the recordings: step, output rate, dead-band (docs/model.md §2).
        classes: :class:`RelaxedClasses` (default), :class:`ExhaustiveClasses` or
            :class:`FixedClasses`.
        gain_bounds: bounds of K̃p, K̃i, K̃d (normalised: −1 = zero, 3 = 4× the default).
        delay_bounds: bounds of Δ̃ (the upper one sizes the delay buffers).
        max_iterations: residual evaluations per stage at most.
        polish_iterations: the same for the exact polish after a warm start (it needs a
            few when the warm start has converged; more cannot rescue one that has not).
        tolerance: relative tolerance on cost, step and gradient (scipy's ftol/xtol/gtol).
        smooth_deadband_rad_s: softplus width of the dead-band inside the exact stages.
        noise_floor_deg: least σ assumed for standard errors (sensor resolution).
        precision_rel: a parameter is poorly determined when 1.96·SE > this × |value|.
        min_duration_s: shortest recording accepted; None (default): one whole cycle of
            the recording's stimulus (named, or a recognised PRTS: 60.5 s for 242 states,
            20 s for 80, plus any lead-in), and :data:`MIN_ANY_TILT_S` for a tilt that is
            not periodic.
        compilation: :class:`Compilation` of the CasADi functions.
        threads: threads evaluating Jacobian columns.
        warm_start: first fit with the fast simulator and finite differences (cheap), then
            finish with CasADi's exact derivatives; otherwise CasADi does every stage.
        warm_tolerance: tolerance of the warm-start stage.
        locked: None (default): compare every sample of the sway; a
            :class:`~posture_id.frf.locked.LockedOptions`: compare only the stimulus-locked
            part (cycle average without drift, at the excited harmonics, each weighted by
            the recording's noise level there): the fit for real, noisy sway
            (docs/real_recordings.md). Needs a periodic stimulus.
        prior_sd: None (default): least squares. A number σ_p: maximum a posteriori under
            a Gaussian prior of SD σ_p on every normalised gain and delay, centred on the
            body's defaults (docs/model.md §5 draws with σ = 0.5): parameters the sway does not
            determine stay near the defaults instead of wandering. Needs the locked fit
            (whose residuals are in units of the recording's noise). A tuple gives each
            normalised gain and delay its own SD (4N values, in the order of
            ``prior_centre``).
        prior_centre: None (default): the prior is centred on the defaults (0). 4N
            normalised values [K̃p of every module, then K̃i, K̃d, Δ̃]: centred there
            instead (``auto`` centres it on the network's answer, with the network's
            calibrated spread as ``prior_sd``). Needs ``prior_sd``.
        fit_passive: also fit every module's passive stiffness Kpas and damping Bpas
            (normalised like the gains, within ``gain_bounds``); otherwise they stay at the
            initial guess's values (the defaults).
    """

    simulation: SimulationOptions = field(default_factory=SimulationOptions)
    classes: ClassStrategy = field(default_factory=RelaxedClasses)
    gain_bounds: tuple[float, float] = GAIN_BOUNDS
    delay_bounds: tuple[float, float] = DELAY_BOUNDS
    max_iterations: int = 60
    polish_iterations: int = 20
    tolerance: float = 1e-10
    smooth_deadband_rad_s: float = 1e-5
    noise_floor_deg: float = 0.001
    precision_rel: float = 0.05
    min_duration_s: float | None = None
    compilation: Compilation = Compilation.AUTO
    threads: int = 2
    warm_start: bool = True
    warm_tolerance: float = 1e-7
    locked: LockedOptions | None = None
    prior_sd: float | tuple[float, ...] | None = None
    prior_centre: tuple[float, ...] | None = None
    fit_passive: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.classes, RelaxedClasses | ExhaustiveClasses | FixedClasses):
            raise FitError(f"classes must be RelaxedClasses(), ExhaustiveClasses() or "
                           f"FixedClasses(), got {self.classes!r}")
        if not isinstance(self.compilation, Compilation):
            raise FitError(f"compilation must be a Compilation, got {self.compilation!r}")
        for name in ("gain_bounds", "delay_bounds"):
            lo, hi = getattr(self, name)
            if not (math.isfinite(lo) and math.isfinite(hi) and -1.0 <= lo < hi):
                raise FitError(f"{name} must be finite with −1 ≤ lower < upper, got {(lo, hi)}")
        for name in ("max_iterations", "polish_iterations", "threads"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise FitError(f"{name} must be an integer ≥ 1, got {value!r}")
        for name in ("tolerance", "warm_tolerance", "noise_floor_deg", "precision_rel",
                     "min_duration_s"):
            value = getattr(self, name)
            if name == "min_duration_s" and value is None:
                continue
            if not (math.isfinite(value) and value > 0):
                raise FitError(f"{name} must be a finite number > 0, got {value!r}")
        if self.locked is not None and not isinstance(self.locked, LockedOptions):
            raise FitError(f"locked must be None or LockedOptions(), got {self.locked!r}")
        if self.prior_sd is not None:
            sds = self.prior_sd if isinstance(self.prior_sd, tuple) else (self.prior_sd,)
            if not sds or not all(isinstance(v, int | float) and math.isfinite(v) and v > 0
                                  for v in sds):
                raise FitError(f"prior_sd must be a finite number > 0 (or a tuple of them), "
                               f"got {self.prior_sd!r}")
            if self.locked is None or not self.locked.weighted:
                raise FitError("prior_sd needs the locked, weighted fit (residuals in units "
                               "of the noise): set locked=LockedOptions()")
        if self.prior_centre is not None:
            if self.prior_sd is None:
                raise FitError("prior_centre needs prior_sd (the prior's spread)")
            if not all(math.isfinite(v) for v in self.prior_centre):
                raise FitError(f"prior_centre must be finite, got {self.prior_centre!r}")
        if not (math.isfinite(self.smooth_deadband_rad_s) and self.smooth_deadband_rad_s >= 0):
            raise FitError(f"smooth_deadband_rad_s must be ≥ 0, got {self.smooth_deadband_rad_s}")
