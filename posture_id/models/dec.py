"""DEC as the stages see it (:class:`~posture_id.models.protocol.Model`): its parameters
(:mod:`posture_id.dec`, one module per joint), the compiled simulator
(:mod:`posture_id.simulation`) and what identifies it: the locked time-domain least
squares per joint and the networks (docs/model.md §1–§5)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from posture_id.dec.parameters import DecParameters, default_parameters
from posture_id.models.protocol import Capability, register

__all__ = ["DecModel", "DEC", "com_deg"]

#: The identified parameters of one module (Kp, Ki, Kd, delay, class).
PER_MODULE = 5
#: The locked fit's default bounds of the normalised gains K̃ = K / K_default − 1 and of
#: the normalised delay (docs/fit.md): gains 0–4×, delays 0–2.5× their defaults.
GAIN_BOUNDS = (-1.0, 3.0)
DELAY_BOUNDS = (-1.0, 1.5)


def com_deg(theta: np.ndarray, body) -> np.ndarray:
    """(S,) degrees: the body COM sway α_BS of segment angles ``theta`` (S, N) rad, from
    the body's reference posture."""
    theta = np.asarray(theta, dtype=float)
    return np.degrees(body.com_angles(theta)[:, 0] - body.reference_com_angles[0])


class DecModel:
    """Disturbance estimation and compensation: a module per joint (PID servo with a lumped
    delay, gravity compensation, dead-band tilt estimator), simulated by the compiled
    simulator; it has no closed loop in the frequency domain (the dead-band is not linear)."""

    name = "dec"
    label = "DEC"
    capabilities = frozenset({Capability.LOCKED_FIT, Capability.NETWORK, Capability.DESIGN})

    def parameters_from_dict(self, data: Mapping, body, name: str = "parameters"
                             ) -> DecParameters:
        return DecParameters.from_dict(data, body, name)

    def default_parameters(self, body) -> DecParameters:
        return default_parameters(body)

    def bounds(self, body) -> dict[str, tuple[float, float]]:
        """``"<joint>.<parameter>"``: the locked fit's default search range (SI units):
        each gain from 0 to 4× its default, each delay from 0 to 2.5× its default."""
        defaults = default_parameters(body)
        out = {}
        for joint, module in defaults.modules.items():
            for name in ("kp", "ki", "kd", "delay_s"):
                low, high = DELAY_BOUNDS if name == "delay_s" else GAIN_BOUNDS
                value = getattr(module, name)
                out[f"{joint}.{name}"] = (value * (1 + low), value * (1 + high))
        return out

    def identified_count(self, body) -> int:
        """k: Kp, Ki, Kd, delay and class of every module."""
        return PER_MODULE * body.n_segments

    def simulate(self, body, params: DecParameters, stimulus=None, options=None,
                 motor_sd_deg: float = 0.0, seed: int = 0):
        from posture_id.simulation.batch import simulate
        from posture_id.simulation.noise import MotorNoise

        motor = MotorNoise(motor_sd_deg, seed=seed) if motor_sd_deg > 0 else None
        return simulate(body, params, stimulus, options, motor).to_recording()

    def com_sway_deg(self, params: DecParameters, body, trial) -> np.ndarray:
        from posture_id.simulation.batch import simulate
        from posture_id.simulation.options import SimulationOptions

        rec = trial.recording
        options = SimulationOptions(sample_rate_hz=rec.sample_rate_hz)
        theta = simulate(body, params, trial.stimulus, options).theta[: len(rec.time)]
        return com_deg(theta, body)

    def __repr__(self) -> str:
        return "DEC"


#: DEC, the project's model.
DEC = register(DecModel())
