"""The independent-channel (IC) model beside DEC (docs/model.md §8): its parameters, closed-loop
response, time-domain simulation, fit to a recording's locked COM sway, and the comparison
of the two models on one recording."""

from posture_id.ic.fit import IcFitOptions, IcFitResult, fit_ic
from posture_id.ic.parameters import IcParameters, default_ic_parameters
from posture_id.ic.response import IcPlant, closed_loop, is_stable
from posture_id.ic.simulation import simulate_ic

__all__ = ["IcParameters", "default_ic_parameters", "IcPlant", "closed_loop", "is_stable",
           "simulate_ic", "fit_ic", "IcFitOptions", "IcFitResult"]
