"""The independent-channel (IC) model (docs/model.md §8): its parameters, closed-loop
response, time-domain simulation and subjects to test on; :data:`IC` the model as the
stages see it."""

from posture_id.models.ic.model import IC, IcModel
from posture_id.models.ic.parameters import IcParameters, default_ic_parameters
from posture_id.models.ic.response import IcPlant, closed_loop, is_stable
from posture_id.models.ic.simulation import simulate_ic

__all__ = ["IC", "IcModel", "IcParameters", "default_ic_parameters", "IcPlant",
           "closed_loop", "is_stable", "simulate_ic"]
