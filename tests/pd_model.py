"""A third model, written against the model protocol alone (posture_id.models.protocol): a
pure PD controller with a lumped delay on the ankle angle (the body against the platform),
the body one pendulum turning about the ankle. Its closed loop, tilt to body COM sway:

    H(s) = N·D / (J·s² − m·g·h + N·D),  N = Kp + Kd·s,  D = e^{−sΔ}.

Nothing outside this module knows it: it registers itself and the stages take it through
the protocol (tests/test_model_protocol.py)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np

from posture_id.errors import ParameterError
from posture_id.models.exact import ExactResponse
from posture_id.models.protocol import Capability, register
from posture_id.recording import Recording


@dataclass(frozen=True)
class PdParameters:
    """kp: N·m/rad. kd: N·m·s/rad. delay_s: s."""

    kp: float
    kd: float
    delay_s: float

    def __post_init__(self) -> None:
        for name, value in asdict(self).items():
            if not math.isfinite(value) or value < 0:
                raise ParameterError(f"PD {name} must be a finite number ≥ 0, got {value!r}")

    def to_dict(self) -> dict:
        return {"model": "pd", **asdict(self)}

    def summary(self) -> str:
        return f"PD  Kp {self.kp:.1f} N·m/rad  Kd {self.kd:.1f} N·m·s/rad  Δ {self.delay_s:.3f} s"


@dataclass(frozen=True)
class Pendulum:
    """inertia: J, kg·m² about the ankle. mgh: N·m/rad."""

    inertia: float
    mgh: float


class PdModel:
    name = "pd"
    label = "PD"
    capabilities = frozenset({Capability.FREQUENCY_RESPONSE})
    parameter_order = ("kp", "kd", "delay_s")
    identified = ("kp", "kd", "delay_s")
    per_part = "kp"
    typical = {"kp": 1.5, "kd": 0.35, "delay_s": 0.15}
    search_bounds = {"kp": (1.05, 4.0), "kd": (0.05, 1.0), "delay_s": (0.02, 0.35)}
    pinned = {"kp": 0.1, "kd": 0.1, "delay_s": 0.1}
    absolute_pins = frozenset()

    def parameters_from_dict(self, data, body=None, name="PD parameters") -> PdParameters:
        if not isinstance(data, dict) or data.get("model") != "pd":
            raise ParameterError(f"{name}: \"model\" must be \"pd\"")
        try:
            return PdParameters(**{k: v for k, v in data.items() if k != "model"})
        except TypeError as exc:
            raise ParameterError(f"{name}: {exc}") from None

    def plant(self, body) -> Pendulum:
        mass_matrix = np.real(body.coupling) + np.diag(body.inertias)
        return Pendulum(float(mass_matrix.sum()), float(body.mgh[0]))

    def default_parameters(self, body) -> PdParameters:
        mgh = self.plant(body).mgh
        return PdParameters(kp=1.5 * mgh, kd=0.35 * mgh, delay_s=0.15)

    def bounds(self, body) -> dict:
        plant = self.plant(body)
        return {n: (lo * self.scale(n, plant), hi * self.scale(n, plant))
                for n, (lo, hi) in self.search_bounds.items()}

    def scale(self, name: str, plant: Pendulum) -> float:
        return plant.mgh if name in ("kp", "kd") else 1.0

    def search_start(self, plant: Pendulum) -> PdParameters:
        return PdParameters(kp=1.5 * plant.mgh, kd=0.35 * plant.mgh, delay_s=0.15)

    def with_values(self, params: PdParameters, values) -> PdParameters:
        return replace(params, **values)

    def interval_multiplier(self, name: str, level: float) -> tuple[float, bool]:
        from scipy.stats import norm

        return float(norm.ppf(0.5 + level / 2)), False

    def closed_loop(self, params: PdParameters, plant: Pendulum, s, gradient: bool = False):
        s = np.asarray(s, dtype=complex)
        d = np.exp(-s * params.delay_s)
        nd = (params.kp + params.kd * s) * d
        body = plant.inertia * s ** 2 - plant.mgh
        h = nd / (body + nd)
        if not gradient:
            return h
        dh_dnd = body / (body + nd) ** 2
        grads = [dh_dnd * d, dh_dnd * s * d, dh_dnd * (-s * nd)]
        return h, np.stack(grads)

    def is_stable(self, params: PdParameters, plant: Pendulum) -> bool:
        """Every root of (J·s² − m·g·h)·Q(s) + (Kd·s + Kp)·P(s) in the left half plane,
        P/Q the [6/6] Padé approximant of e^{−sΔ}."""
        k = np.arange(7)
        c = np.array([math.factorial(12 - j) * math.factorial(6)
                      / (math.factorial(12) * math.factorial(j) * math.factorial(6 - j))
                      for j in k])
        p, q = (c * (-params.delay_s) ** k)[::-1], (c * params.delay_s ** k)[::-1]
        poly = np.polyadd(np.polymul([plant.inertia, 0.0, -plant.mgh], q),
                          np.polymul([params.kd, params.kp], p))
        return bool(np.roots(np.trim_zeros(poly, "f")).real.max() < -1e-6)

    def simulate(self, body, params: PdParameters, stimulus=None, options=None,
                 motor_sd_deg: float = 0.0, seed: int = 0) -> Recording:
        """Semi-implicit Euler at 1 ms, the delayed torque read from a buffer; white motor
        noise torque m·g·h·σ (σ in rad) held over 10 ms."""
        from posture_id.simulation.stimulus import prts

        stimulus = stimulus or prts()
        plant = self.plant(body)
        dt, rate = 0.001, 100.0
        n = int(round(stimulus.duration / dt))
        t = np.arange(n + 1) * dt
        tilt = stimulus.angle(t)
        lag = int(round(params.delay_s / dt))
        rng = np.random.default_rng(seed)
        kicks = rng.standard_normal(n // 10 + 1) * plant.mgh * math.radians(motor_sd_deg)
        theta = np.zeros(n + 1)
        servo = np.zeros(n + 1)
        velocity = 0.0
        for i in range(n):
            servo[i] = params.kp * (theta[i] - tilt[i]) + params.kd * (
                velocity - (tilt[i] - tilt[i - 1]) / dt if i else velocity)
            torque = (servo[i - lag] if i >= lag else 0.0) + kicks[i // 10]
            velocity += dt * (plant.mgh * theta[i] - torque) / plant.inertia
            theta[i + 1] = theta[i] + dt * velocity
        every = int(round(1 / (rate * dt)))
        time, com = t[::every], theta[::every]
        angles = np.repeat((com - body.reference_com_angles[0])[:, None], body.n_segments, 1)
        return Recording(time, tilt[::every], angles, body.segment_names, name="PD simulation")

    def com_sway_deg(self, params: PdParameters, body, trial) -> np.ndarray:
        rec = trial.recording
        return np.degrees(ExactResponse(self, rec.tilt, rec.sample_rate_hz, self.plant(body))
                          .sway(params))

    def __repr__(self) -> str:
        return "PD"


PD = register(PdModel())
