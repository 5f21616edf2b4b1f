"""The independent-channel model as the stages see it
(:class:`~posture_id.models.protocol.FrequencyModel`): its parameters, search ranges
and typical values, closed loop and simulation.

The search ranges (docs/model.md §8) are in units of m·g·h for the gains (·s for Kd and
Bpas, /s for Ki), W and G as they are, times in s. The intervals' calibration
(``calibration.json`` beside this module, made by ``benchmarks/ic_recovery.py
--calibrate``): per parameter, the quantiles of |estimate − truth| / standard error at the
levels 0.5–0.99 over IC recordings the project simulated.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from functools import lru_cache
from pathlib import Path

import numpy as np

from posture_id.models.ic.parameters import MODEL_NAME, IcParameters, default_ic_parameters
from posture_id.models.ic.response import PARAMETER_ORDER, IcPlant, closed_loop, is_stable
from posture_id.models.ic.simulation import simulate_ic
from posture_id.models.protocol import Capability, register

__all__ = ["IcModel", "IC", "BOUNDS", "TYPICAL", "CALIBRATION", "parameter_scale"]

#: docs/model.md §8's search bounds: (low, high) per parameter, in search units.
BOUNDS = {"kp": (0.5, 4.0), "kd": (0.05, 1.0), "ki": (0.0, 0.5), "delay_s": (0.02, 0.35),
          "w": (0.0, 1.0), "torque_feedback_gain": (0.0, 0.9),
          "torque_feedback_time_s": (2.0, 100.0), "kpas": (0.0, 1.0), "bpas": (0.0, 0.5)}
#: The literature's typical values, the first start of every search (units of BOUNDS).
TYPICAL = {"kp": 1.5, "kd": 0.35, "ki": 0.05, "delay_s": 0.15, "w": 0.6,
           "torque_feedback_gain": 0.3, "torque_feedback_time_s": 20.0, "kpas": 0.1,
           "bpas": 0.05}
#: The parameters whose unit is m·g·h (times s or per s).
_PER_MGH = ("kp", "kd", "ki", "kpas", "bpas")
#: The calibration of the intervals (the module doc).
CALIBRATION = Path(__file__).with_name("calibration.json")


@lru_cache(maxsize=1)
def _calibration() -> dict | None:
    try:
        return json.loads(CALIBRATION.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def parameter_scale(name: str, plant: IcPlant) -> float:
    """The unit a parameter is searched in: m·g·h for the gains, 1 for the rest."""
    return plant.mgh if name in _PER_MGH else 1.0


class IcModel:
    """The independent-channel model (docs/model.md §8): one body turning about the ankle,
    a PID on the sensory error with a weight W on the platform's tilt, positive torque
    feedback; fitted exactly in the frequency domain."""

    name = MODEL_NAME
    label = "IC"
    capabilities = frozenset({Capability.FREQUENCY_RESPONSE, Capability.DESIGN})
    parameter_order = PARAMETER_ORDER
    typical = TYPICAL
    search_bounds = BOUNDS
    #: Kp, Kd and Δ pinned to ±10 % of their value, W to ±0.1.
    pinned = {"kp": 0.1, "kd": 0.1, "delay_s": 0.1, "w": 0.1}
    absolute_pins = frozenset({"w"})
    #: The parameter a fit of several parts gives each part its own value of (sensory
    #: re-weighting between amplitudes).
    per_part = "w"
    #: Identified unless asked otherwise (Ki and the passive terms held at 0).
    identified = ("kp", "kd", "delay_s", "w", "torque_feedback_gain", "torque_feedback_time_s")

    def parameters_from_dict(self, data: Mapping, body=None, name: str = "IC parameters"
                             ) -> IcParameters:
        return IcParameters.from_dict(data, name)

    def default_parameters(self, body) -> IcParameters:
        return default_ic_parameters(IcPlant.of(body).mgh)

    def bounds(self, body) -> dict[str, tuple[float, float]]:
        plant = IcPlant.of(body)
        return {n: (lo * parameter_scale(n, plant), hi * parameter_scale(n, plant))
                for n, (lo, hi) in BOUNDS.items()}

    def simulate(self, body, params: IcParameters, stimulus=None, options=None,
                 motor_sd_deg: float = 0.0, seed: int = 0):
        return simulate_ic(body, params, stimulus, options, motor_sd_deg, seed=seed)

    def com_sway_deg(self, params: IcParameters, body, trial) -> np.ndarray:
        from posture_id.models.exact import ExactResponse

        rec = trial.recording
        return np.degrees(ExactResponse(self, rec.tilt, rec.sample_rate_hz, self.plant(body))
                          .sway(params))

    def plant(self, body) -> IcPlant:
        return IcPlant.of(body)

    def closed_loop(self, params: IcParameters, plant: IcPlant, s: np.ndarray,
                    gradient: bool = False):
        return closed_loop(params, plant, s, gradient)

    def is_stable(self, params: IcParameters, plant: IcPlant) -> bool:
        return is_stable(params, plant)

    def scale(self, name: str, plant: IcPlant) -> float:
        return parameter_scale(name, plant)

    def search_start(self, plant: IcPlant) -> IcParameters:
        return IcParameters(kp=plant.mgh, kd=0.3 * plant.mgh, delay_s=0.15, w=0.5)

    def with_values(self, params: IcParameters, values: Mapping[str, float]) -> IcParameters:
        return params.replace(**values)

    def interval_multiplier(self, name: str, level: float) -> tuple[float, bool]:
        """(the multiplier of the standard error for a ``level`` interval of ``name``,
        whether it is calibrated); without a calibration, the normal quantile."""
        from scipy.stats import norm

        calibration = _calibration()
        quantiles = (None if calibration is None
                     else calibration.get("quantiles", {}).get(name))
        if quantiles is None or not all(isinstance(q, int | float) for q in quantiles):
            return float(norm.ppf(0.5 + level / 2)), False
        return float(np.interp(level, calibration["levels"], quantiles)), True

    def __repr__(self) -> str:
        return "IC"


#: The independent-channel model.
IC = register(IcModel())
