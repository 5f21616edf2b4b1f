"""From a force plate's centre of pressure (COP) to the body-COM sway angle, and back.

**The physics.** The platform turns about the ankle axis, so the ankle stays where it is
(docs/model.md §1). About that fixed axis the body's angular momentum L obeys

    dL/dt = m·g·x_c + τ_1,

x_c the body COM's forward distance from the ankle, m the body's mass (the feet are the
platform's) and τ_1 the ankle torque on the body. The feet stand on the plate: what the
ankle torque does to them, the plate measures. With the ground reaction's component normal
to the plate F_n and its COP x_p (forward, along the plate, from the point under the
ankle), and the plate's surface a height d below the ankle axis carrying the shear F_t,

    τ_1 = −x_p·F_n − d·F_t.

**The route** (:func:`com_angle_from_cop`) takes the body as one rigid segment turning
about the ankle, L = I_a·θ̇ with I_a its moment of inertia about the ankle axis upright
and x_c = h·θ (h the ankle-to-COM height, θ the COM sway angle, small), and the shear
along the tilted plate as F_t = m·h·θ̈ − m·g·sin α (the COM's acceleration, and the
weight's share along a plate tilted by α); in the frequency domain

    Θ(ω) = T(ω) / (m·g·h + (I_a + d·m·h)·ω²),     T = F_n·x_p − d·m·g·sin α,

a low-pass whose corner is √(m·g·h/I_a) (about 0.5 Hz for a person): the COP overshoots
the COM at every frequency and the more so the higher. It is solved on the whole
recording at once (the bounded, non-causal solution, by FFT of the mirrored signal: the
kernel e^{−ω₀|t|} decays within a second, so only the first and last second feel the
ends, where the torque before and after the recording is not known: keep a second of
recording beyond the analysed cycles, as labs' level stretches do).
F_n is the plate's normal-force column where there is one, else m·g·cos α (α the
platform's tilt: the static load on a tilted plate). The ankle's position on the plate
is not known from the COP: its mean is taken for it (the mean lean is not recovered; the
FRF and the locked fits remove the offset anyway).

Where it holds: exactly for a one-segment body; for a body that bends (hip and knee) the
angular momentum is not I_a·θ̇ and the route's error grows with frequency
(docs/lab_recordings.md gives the measured range). m, h and I_a come from the body's
URDF through Pinocchio (:class:`BodyLoad`).

**Back** (:func:`cop_of_motion`): a simulated trial's COP, from its motion by the
momentum balance above (L = 1ᵀM(θ)θ̇ of the chain, exact for every body), the ankle
torque and the support's reaction; what ``posture-id simulate --force-plate-out`` writes.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

from posture_id.errors import RecordingError

__all__ = ["CopUnit", "BodyLoad", "CopOptions", "com_angle_from_cop", "cop_of_motion",
           "ankle_torque_of_motion", "normal_force_of_motion", "shear_force_of_motion",
           "ankle_momentum"]


class CopUnit(enum.Enum):
    """The unit of a COP column (and its factor to metres)."""

    MM = "mm"
    CM = "cm"
    M = "m"

    @property
    def metres(self) -> float:
        return {"mm": 1e-3, "cm": 1e-2, "m": 1.0}[self.value]


@dataclass(frozen=True)
class BodyLoad:
    """What the COP route needs of a body, as one rigid segment about the ankle.

    Attributes:
        mass_kg: the body's mass above the ankle. com_height_m: h, ankle to body COM,
        upright. inertia_kg_m2: I_a, about the ankle axis, upright (rigid). gravity_m_s2.
    """

    mass_kg: float
    com_height_m: float
    inertia_kg_m2: float
    gravity_m_s2: float = 9.81

    @classmethod
    def of(cls, body) -> BodyLoad:
        """The load of a :class:`~posture_id.bodies.body.Body` (m·g·h from Pinocchio)."""
        ones = np.ones(body.n_segments)
        upright = np.real(body.coupling) + np.diag(body.inertias)  # M(0) in space angles
        return cls(body.total_mass, float(body.mgh[0] / (body.total_mass * body.gravity)),
                   float(ones @ upright @ ones), body.gravity)

    @property
    def mgh(self) -> float:
        """N·m/rad."""
        return self.mass_kg * self.gravity_m_s2 * self.com_height_m

    @property
    def corner_hz(self) -> float:
        """Hz, √(m·g·h/I_a)/2π: above it the COP leads the COM by more and more."""
        return math.sqrt(self.mgh / self.inertia_kg_m2) / (2 * math.pi)


@dataclass(frozen=True)
class CopOptions:
    """How a COP column is read.

    Attributes:
        unit: of the COP column. ankle_height_m: d, the ankle axis above the plate's
        surface (0: the pivot and the surface at the ankle axis, the model's platform).
        sign: −1 when the plate's positive COP axis points backward.
    """

    unit: CopUnit = CopUnit.MM
    ankle_height_m: float = 0.0
    sign: int = 1

    def __post_init__(self) -> None:
        if not isinstance(self.unit, CopUnit):
            raise RecordingError(f"COP unit must be a CopUnit, got {self.unit!r}")
        if not (math.isfinite(self.ankle_height_m) and 0 <= self.ankle_height_m < 0.5):
            raise RecordingError(f"the ankle height above the plate must be 0 to 0.5 m, got "
                                 f"{self.ankle_height_m}")
        if self.sign not in (1, -1):
            raise RecordingError(f"COP sign must be +1 or −1, got {self.sign}")


def com_angle_from_cop(cop: np.ndarray, sample_rate_hz: float, load: BodyLoad,
                       tilt_rad: np.ndarray | None = None,
                       normal_force_n: np.ndarray | None = None,
                       options: CopOptions | None = None, name: str = "recording"
                       ) -> np.ndarray:
    """The body-COM sway angle (S,) rad from a COP column (the module doc).

    Args:
        cop: (S,) the COP, forward, in ``options.unit``, evenly sampled.
        sample_rate_hz: The COP's sample rate, Hz.
        load: The body (:meth:`BodyLoad.of`).
        tilt_rad: (S,) the platform's tilt (for the static normal force m·g·cos α).
        normal_force_n: (S,) N, the plate's normal force, when it was recorded.
        options: the COP's unit, the ankle's height above the plate, the sign.
        name: what messages call the recording.
    Raises:
        RecordingError: a COP or force that is not finite, a normal force that is not a
            standing body's (below half or above 1.5 times m·g: another unit, or nobody on
            the plate).
    """
    options = options or CopOptions()
    x = np.asarray(cop, dtype=float) * options.unit.metres * options.sign
    if x.ndim != 1 or len(x) < 4:
        raise RecordingError(f"{name}: the COP must be one column of ≥ 4 samples")
    if not np.all(np.isfinite(x)):
        first = int(np.argmax(~np.isfinite(x)))
        raise RecordingError(f"{name}: the COP is not finite from sample {first}")
    weight = load.mass_kg * load.gravity_m_s2
    if normal_force_n is not None:
        force = np.asarray(normal_force_n, dtype=float)
        if force.shape != x.shape or not np.all(np.isfinite(force)):
            raise RecordingError(f"{name}: the normal force must be finite, one value per "
                                 "COP sample")
        median = float(np.median(force))
        if not 0.5 * weight <= abs(median) <= 1.5 * weight:
            raise RecordingError(
                f"{name}: the normal force's median is {median:.4g} N, the body's weight "
                f"{weight:.4g} N (m·g of {load.mass_kg:.4g} kg): not a standing body's "
                "(another unit? the body's mass?)")
        force = np.abs(force)
    elif tilt_rad is not None:
        force = weight * np.cos(np.asarray(tilt_rad, dtype=float))
    else:
        force = np.full(len(x), weight)
    # the ankle's position on the plate is unknown: the COP's mean stands for it
    torque = force * (x - x.mean())
    if options.ankle_height_m and tilt_rad is not None:
        torque -= (options.ankle_height_m * weight
                   * np.sin(np.asarray(tilt_rad, dtype=float)))
    torque -= torque.mean()
    mirrored = np.concatenate([torque, torque[::-1]])
    omega = 2 * np.pi * np.fft.rfftfreq(len(mirrored), 1.0 / sample_rate_hz)
    stiffness = load.mgh + (load.inertia_kg_m2
                            + options.ankle_height_m * load.mass_kg * load.com_height_m
                            ) * omega**2
    return np.fft.irfft(np.fft.rfft(mirrored) / stiffness, len(mirrored))[: len(x)]


def ankle_momentum(body, theta: np.ndarray, theta_dot: np.ndarray) -> np.ndarray:
    """(S,) kg·m²/s, the body's angular momentum about the ankle axis, 1ᵀM(θ)θ̇, from
    segment angles θ (S, N) rad and rates θ̇ (S, N) rad/s in space."""
    d = body.coupling  # M_jk = Re(D_jk e^{i(θj−θk)}) + δ_jk I_j
    rotor = np.exp(1j * np.asarray(theta))
    # Σ_jk Re(D_jk e^{iθj} e^{−iθk}) θ̇_k
    mass_matrix_rates = np.real(np.einsum("sj,jk,sk->s", rotor, d,
                                          np.conj(rotor) * theta_dot))
    return mass_matrix_rates + theta_dot @ body.inertias


def _com(body, theta: np.ndarray) -> np.ndarray:
    """(S,) complex m, the body COM from the ankle (up + 1j·forward)."""
    return (np.exp(1j * np.asarray(theta)) @ body.gravity_lever) / body.total_mass


def ankle_torque_of_motion(body, theta: np.ndarray, sample_rate_hz: float) -> np.ndarray:
    """(S,) N·m, the ankle torque τ_1 on the body, dL/dt − m·g·x_c, from its motion
    θ (S, N) rad sampled at ``sample_rate_hz`` (second-order differences)."""
    dt = 1.0 / sample_rate_hz
    rates = np.gradient(theta, dt, axis=0)
    momentum = ankle_momentum(body, theta, rates)
    forward = _com(body, theta).imag
    return np.gradient(momentum, dt) - body.total_mass * body.gravity * forward


def normal_force_of_motion(body, theta: np.ndarray, tilt_rad: np.ndarray,
                           sample_rate_hz: float) -> np.ndarray:
    """(S,) N, the ground reaction's component normal to the tilted plate,
    m·((g + z̈_c)·cos α + ẍ_c·sin α)."""
    dt = 1.0 / sample_rate_hz
    com = _com(body, theta)
    acc = np.gradient(np.gradient(com, dt), dt)
    alpha = np.asarray(tilt_rad, dtype=float)
    return body.total_mass * ((body.gravity + acc.real) * np.cos(alpha)
                              + acc.imag * np.sin(alpha))


def shear_force_of_motion(body, theta: np.ndarray, tilt_rad: np.ndarray,
                          sample_rate_hz: float) -> np.ndarray:
    """(S,) N, the ground reaction's component along the tilted plate (forward),
    m·(ẍ_c·cos α − (g + z̈_c)·sin α)."""
    dt = 1.0 / sample_rate_hz
    acc = np.gradient(np.gradient(_com(body, theta), dt), dt)
    alpha = np.asarray(tilt_rad, dtype=float)
    return body.total_mass * (acc.imag * np.cos(alpha)
                              - (body.gravity + acc.real) * np.sin(alpha))


def cop_of_motion(body, theta: np.ndarray, tilt_rad: np.ndarray, sample_rate_hz: float,
                  ankle_height_m: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(COP (S,) m forward along the plate from the point under the ankle, normal force
    (S,) N) of a simulated motion θ (S, N) rad on a plate whose surface is
    ``ankle_height_m`` below the ankle axis: x_p = −(τ_1 + d·F_t)/F_n."""
    force = normal_force_of_motion(body, theta, tilt_rad, sample_rate_hz)
    torque = ankle_torque_of_motion(body, theta, sample_rate_hz)
    if ankle_height_m:
        torque = torque + ankle_height_m * shear_force_of_motion(body, theta, tilt_rad,
                                                                 sample_rate_hz)
    return -torque / force, force
