"""Stimulus-locked averages: the periodic part of a signal and a slow drift, separated.

A response to a periodic stimulus (one PRTS cycle of P samples) is modelled as

    x[s] = p[s mod P] + Σ_{k=1..d} c_k · L_k(τ_s),   s = 0..C·P − 1,

a periodic part p (P values: the cycle average) plus a polynomial drift of order d
(Legendre polynomials L_k of τ ∈ [−1, 1] across the analysed span; the constant belongs to
p). Least squares over both at once: with R = I − A, where A replaces a signal by its
cycle average repeated, the drift coefficients solve min ‖R(x − L c)‖ (a C·P × d problem),
and p is the cycle average of x − L c. A drift of order ≤ d is removed exactly, whatever
its size; with d = 0 this is the plain cycle average of the posture literature.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import legendre

from posture_id.errors import PostureIdError

__all__ = ["CycleAverage", "cycle_average", "cycle_spans"]


@dataclass(frozen=True)
class CycleAverage:
    """The stimulus-locked part of a signal.

    Attributes:
        mean: (P, ...) the cycle average (drift removed).
        cycles: (C, P, ...) each analysed cycle, drift removed.
        drift: (C·P, ...) the fitted drift across the analysed span (zero mean).
        locked_share: (...) share of the drift-free signal's variance (about its mean)
            that is stimulus-locked, in [0, 1], corrected for the noise the cycle
            average keeps: averaging C cycles leaves 1/C of the noise's variance in it,
            estimated from how the cycles differ (the remainder, C − 1 degrees of freedom
            per sample), so pure noise has a share about 0, not 1/C. NaN with a single
            cycle (noise and response cannot be told apart).
        uncorrected_share: (...) the cycle average's share as it is, noise left in it
            (1 with a single cycle).
    """

    mean: np.ndarray
    cycles: np.ndarray
    drift: np.ndarray
    locked_share: np.ndarray
    uncorrected_share: np.ndarray


def cycle_spans(n_samples: int, samples_per_cycle: int, skip_cycles: int = 0,
                name: str = "signal") -> tuple[int, int]:
    """(first sample, number of whole cycles) analysed in ``n_samples`` samples."""
    if samples_per_cycle < 2:
        raise PostureIdError(f"{name}: a stimulus cycle must span ≥ 2 samples, "
                             f"got {samples_per_cycle}")
    cycles = n_samples // samples_per_cycle - skip_cycles
    if cycles < 1:
        raise PostureIdError(
            f"{name}: {n_samples} samples hold {n_samples // samples_per_cycle} whole "
            f"stimulus cycle(s) of {samples_per_cycle} samples; skipping {skip_cycles} leaves "
            "none to analyse")
    return skip_cycles * samples_per_cycle, cycles


def cycle_average(signal: np.ndarray, samples_per_cycle: int, skip_cycles: int = 0,
                  drift_order: int = 0, name: str = "signal") -> CycleAverage:
    """Separate the stimulus-locked cycle average from a polynomial drift.

    Args:
        signal: (S, ...) samples along axis 0 (any trailing channels).
        samples_per_cycle: P, samples in one stimulus cycle (an integer: the cycle must
            span whole samples at the recording's rate).
        skip_cycles: whole cycles left out at the start (the transient).
        drift_order: d ≥ 0, the order of the drift polynomial (d > 0 needs ≥ 2 analysed
            cycles).
        name: names the signal in errors.
    """
    x = np.asarray(signal, dtype=float)
    start, cycles = cycle_spans(len(x), samples_per_cycle, skip_cycles, name)
    if drift_order < 0:
        raise PostureIdError(f"{name}: drift order must be ≥ 0, got {drift_order}")
    if drift_order > 0 and cycles < 2:
        raise PostureIdError(f"{name}: a drift can only be told from the response with ≥ 2 "
                             "analysed cycles")
    if drift_order >= 2 * cycles:
        raise PostureIdError(f"{name}: a drift of order {drift_order} over {cycles} cycles "
                             "bends as fast as the stimulus's own lowest frequency and would "
                             f"take up the response: give a drift order below {2 * cycles}")
    p = samples_per_cycle
    span = x[start : start + cycles * p]
    trailing = span.shape[1:]
    flat = span.reshape(cycles * p, -1)
    drift = np.zeros_like(flat)
    if drift_order > 0:
        tau = np.linspace(-1.0, 1.0, cycles * p)
        basis = legendre.legvander(tau, drift_order)[:, 1:]  # (C·P, d), constant left to p
        coefficients = np.linalg.lstsq(_without_cycle_average(basis, cycles, p),
                                       _without_cycle_average(flat, cycles, p), rcond=None)[0]
        drift = basis @ coefficients
    locked = (flat - drift).reshape(cycles, p, -1)
    mean = locked.mean(axis=0)
    # the drift-free signal splits into the repeated cycle average and a remainder whose
    # cycle average is zero: two orthogonal parts, so the shares add up to 1
    periodic = ((mean - mean.mean(axis=0)) ** 2).sum(axis=0) * cycles
    remainder = ((locked - mean) ** 2).sum(axis=(0, 1))
    # the noise in the average: its variance/C per sample, C·P samples (periodic counts C
    # copies), so P·σ² in all, and the remainder estimates (C − 1)·P·σ²
    with np.errstate(invalid="ignore", divide="ignore"):
        share = periodic / (periodic + remainder)
        if cycles >= 2:
            corrected = np.clip((periodic - remainder / (cycles - 1))
                                / (periodic + remainder), 0.0, 1.0)
        else:
            corrected = np.full_like(share, np.nan)
    return CycleAverage(mean=mean.reshape(p, *trailing),
                        cycles=locked.reshape(cycles, p, *trailing),
                        drift=drift.reshape(cycles * p, *trailing),
                        locked_share=corrected.reshape(trailing),
                        uncorrected_share=share.reshape(trailing))


def _without_cycle_average(x: np.ndarray, cycles: int, p: int) -> np.ndarray:
    """(C·P, K) columns minus their cycle average repeated: R x."""
    folded = x.reshape(cycles, p, -1)
    return (folded - folded.mean(axis=0)).reshape(cycles * p, -1)
