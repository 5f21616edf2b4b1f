"""Stimulus-locked analysis: cycle averages with drift removal, and frequency-response
functions with coherence at the stimulus's excited frequencies (docs/frf.md)."""

from posture_id.frf.analysis import frequency_response
from posture_id.frf.cycles import CycleAverage, cycle_average
from posture_id.frf.response import FrequencyResponse, FrfOptions, frequency_response_arrays

__all__ = ["CycleAverage", "cycle_average", "FrequencyResponse", "FrfOptions",
           "frequency_response", "frequency_response_arrays"]
