"""What the universal network sees of one DEC module: FRFs on a fixed frequency grid and
what it needs to know of the body and the stimulus.

Module i of an N-segment body gets :data:`CHANNELS` rows over :data:`GRID_HZ` (G bands,
log-spaced, whatever the stimulus's harmonics):

- for the segment below joint i (the platform for the ankle), segment i itself and the
  one above it (none for the top): Re H, Im H and log10 σ_H, with H the FRF of the
  segment's angle relative to the tilt averaged over the excited harmonics in the band,
  weighted by the tilt's power there (Σ Y·conj(U) / Σ|U|²), and σ_H its noise level from
  the harmonics the stimulus leaves empty; a band holding no excited harmonic is
  interpolated (in log frequency) from its neighbours;
- the same three for the angle of the COM of everything above joint i (linearised at
  upright, :func:`com_weights`): what the module controls when its class is "COM in
  space";
- log(1 + the excited harmonics in the band): how much each band was measured.

and :data:`DESCRIPTORS` numbers: the module's place (ankle, knee, hip column of docs/model.md §3;
segment count), the body around it (its time scale √(M_ii/mgh_i), its inertial coupling
to the segments below and above, the ratios of m·g·h to its neighbours'), and the
stimulus (peak to peak, RMS velocity, period, cycles). Gains are normalised by each
module's m·g·h (docs/model.md §3), so these are all the body and the stimulus it needs.
"""

from __future__ import annotations

import numpy as np

from posture_id.bodies.body import Body
from posture_id.dec.parameters import _column
from posture_id.frf.locked import noise_levels
from posture_id.learning.features.harmonics import HarmonicLayout

__all__ = ["GRID_HZ", "CHANNELS", "com_weights", "features_and_noise", "DESCRIPTORS",
           "FEATURE_MAX_HZ", "band_weights", "module_features", "body_descriptors",
           "stimulus_descriptors", "noise_ratio", "noise_colour", "UNIVERSAL_FEATURE_DEFINITION",
           "N_INPUTS", "COLOUR_LOW_HZ", "COLOUR_HIGH_HZ"]

#: Highest frequency the features hold, Hz.
FEATURE_MAX_HZ = 2.5
#: Band centres, Hz.
GRID_HZ = np.geomspace(0.03, FEATURE_MAX_HZ, 20)
_EDGES = np.sqrt(GRID_HZ[1:] * GRID_HZ[:-1])
CHANNELS = 13
DESCRIPTORS = 15
N_INPUTS = CHANNELS * len(GRID_HZ) + DESCRIPTORS
_NEIGHBOURS = 3
_LOG_FLOOR, _LOG_CEIL, _H_LIMIT = -4.0, 1.0, 20.0
#: The noise colour compares the noise power below this (Hz) with that above
#: :data:`COLOUR_HIGH_HZ` (up to :data:`FEATURE_MAX_HZ`).
COLOUR_LOW_HZ, COLOUR_HIGH_HZ = 0.3, 0.8

UNIVERSAL_FEATURE_DEFINITION = {
    "version": 1,
    "kind": "universal",
    "grid_hz": [round(float(f), 6) for f in GRID_HZ],
    "channels": "below/own/above segment, COM above the joint: Re H, Im H, log10 noise of "
                "H; log(1 + harmonics)",
    "descriptors": "column one-hot (3), segments one-hot (3), log10 sqrt(M_ii/mgh_i), "
                   "M_i,i-1/M_ii, M_i,i+1/M_ii, ln(mgh_i/mgh_i-1), ln(mgh_i+1/mgh_i), "
                   "log10 p-p deg, log10 RMS velocity deg/s, log10 period s, log10 cycles",
    "harmonics": "DFT/P of the drift-free (linear) cycle average of whole cycles",
    "noise_neighbours": _NEIGHBOURS,
}


def _rows(layout: HarmonicLayout) -> np.ndarray:
    return np.flatnonzero(layout.excited & (layout.frequencies_hz <= FEATURE_MAX_HZ))


def band_weights(layout: HarmonicLayout) -> tuple[np.ndarray, np.ndarray]:
    """((G, R) complex W, (G,) harmonics per band): H_band = W @ Y over the R excited
    harmonics up to :data:`FEATURE_MAX_HZ`; empty bands interpolate their neighbours.
    Made once per layout."""
    cached = layout.__dict__.get("_band_weights")
    if cached is None:
        cached = _band_weights(layout)
        object.__setattr__(layout, "_band_weights", cached)
    return cached


def _band_weights(layout: HarmonicLayout) -> tuple[np.ndarray, np.ndarray]:
    rows = _rows(layout)
    f = layout.frequencies_hz[rows]
    u = layout.tilt[rows]
    band = np.searchsorted(_EDGES, f)
    g = len(GRID_HZ)
    w = np.zeros((g, len(rows)), dtype=complex)
    count = np.bincount(band, minlength=g)
    for b in np.flatnonzero(count):
        sel = band == b
        w[b, sel] = np.conj(u[sel]) / np.sum(np.abs(u[sel]) ** 2)
    full = np.flatnonzero(count)
    logf = np.log(GRID_HZ)
    for b in np.flatnonzero(count == 0):
        right = full[full > b]
        left = full[full < b]
        if not len(left):
            w[b] = w[right[0]]
        elif not len(right):
            w[b] = w[left[-1]]
        else:
            lo, hi = left[-1], right[0]
            a = (logf[b] - logf[lo]) / (logf[hi] - logf[lo])
            w[b] = (1 - a) * w[lo] + a * w[hi]
    return w, count


def com_weights(body: Body) -> np.ndarray:
    """(N, N) W with α_i ≈ Σ_j W_ij θ_j: the angle of the COM above joint i from the
    segment angles, linearised at upright (∂ angle(Σ_{j≥i} e^{iθ_j} S_j) / ∂θ_j at 0)."""
    s = np.asarray(body.gravity_lever)
    n = len(s)
    w = np.zeros((n, n))
    for i in range(n):
        total = s[i:].sum()
        w[i, i:] = (s[i:] * np.conj(total)).real / abs(total) ** 2
    return w


def _frf_channels(y: np.ndarray, rows: np.ndarray, excited: np.ndarray, w: np.ndarray,
                  sigma: np.ndarray | None = None) -> np.ndarray:
    """(B, N, 3, G) Re H, Im H, log10 σ_H of harmonics ``y`` (K, B, N) in the bands;
    ``sigma``: their noise levels at ``rows`` when already known."""
    if sigma is None:
        sigma = noise_levels(np.abs(y) ** 2, excited, rows, _NEIGHBOURS)  # (R, B, N)
    h = np.einsum("gr,rbn->gbn", w, y[rows])  # (G, B, N)
    sd = np.sqrt(np.einsum("gr,rbn->gbn", np.abs(w) ** 2, sigma**2))
    log_sd = np.clip(np.log10(np.maximum(sd, 1e-12)), _LOG_FLOOR, _LOG_CEIL)
    re = np.clip(h.real, -_H_LIMIT, _H_LIMIT)
    im = np.clip(h.imag, -_H_LIMIT, _H_LIMIT)
    return np.stack([re, im, log_sd]).transpose(2, 3, 0, 1)


def module_features(layout: HarmonicLayout, sway: np.ndarray,
                    com: np.ndarray | None = None) -> np.ndarray:
    """(B, N, CHANNELS, G) float32 features of B sways' harmonics ``sway`` (K, B, N);
    ``com``: the body's :func:`com_weights` (default: each segment its own COM)."""
    return features_and_noise(layout, sway, com)[0]


def features_and_noise(layout: HarmonicLayout, sway: np.ndarray, com: np.ndarray | None = None
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(:func:`module_features`, :func:`noise_ratio`, :func:`noise_colour`) of the same
    sways, their noise levels estimated once."""
    k, b, n = sway.shape
    w, count = band_weights(layout)
    rows, power, sigma = _noise(layout, sway)
    ratio = _ratio(power, sigma, rows)
    colour = _colour(sigma, layout.frequencies_hz[rows])
    seg = _frf_channels(sway, rows, layout.excited, w, sigma)  # (B, N, 3, G)
    com = np.eye(n) if com is None else np.asarray(com)
    above = _frf_channels(np.einsum("ij,kbj->kbi", com, sway), rows, layout.excited, w)
    g = len(GRID_HZ)
    platform = np.zeros((b, 1, 3, g))
    platform[:, :, 0] = 1.0
    platform[:, :, 2] = _LOG_FLOOR
    nothing = np.zeros((b, 1, 3, g))
    nothing[:, :, 2] = _LOG_FLOOR
    padded = np.concatenate([platform, seg, nothing], axis=1)  # (B, N + 2, 3, G)
    out = np.empty((b, n, CHANNELS, g), dtype=np.float32)
    out[:, :, 0:3] = padded[:, :-2]
    out[:, :, 3:6] = padded[:, 1:-1]
    out[:, :, 6:9] = padded[:, 2:]
    out[:, :, 9:12] = above
    out[:, :, 12] = np.log1p(count)
    return out, ratio, colour


def _noise(layout: HarmonicLayout, sway: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(R,) the excited harmonics up to :data:`FEATURE_MAX_HZ`, (K, B, N) the sway's power
    and (R, B, N) its noise level there, from the nearest empty harmonics."""
    rows = _rows(layout)
    power = np.abs(sway) ** 2
    return rows, power, noise_levels(power, layout.excited, rows, _NEIGHBOURS)


def noise_ratio(layout: HarmonicLayout, sway: np.ndarray) -> np.ndarray:
    """(B,) Σσ²/Σ|Y|² over the excited harmonics up to :data:`FEATURE_MAX_HZ` and every
    segment: the share of the locked harmonics that is noise (0 clean, → 1 all noise)."""
    rows, power, sigma = _noise(layout, sway)
    return _ratio(power, sigma, rows)


def noise_colour(layout: HarmonicLayout, sway: np.ndarray) -> np.ndarray:
    """(B,) log10 of the mean noise power (summed over segments) at the excited harmonics
    below :data:`COLOUR_LOW_HZ` over that above :data:`COLOUR_HIGH_HZ`: about 0 for white
    noise (a sensor's), higher for noise shaped by the body (motor noise, drift); 0 when
    either side has no harmonic or no noise."""
    rows, _, sigma = _noise(layout, sway)
    return _colour(sigma, layout.frequencies_hz[rows])


def _colour(sigma: np.ndarray, frequencies_hz: np.ndarray) -> np.ndarray:
    noise = (sigma**2).sum(axis=2)  # (R, B)
    low, high = frequencies_hz < COLOUR_LOW_HZ, frequencies_hz > COLOUR_HIGH_HZ
    if not low.any() or not high.any():
        return np.zeros(noise.shape[1])
    lo, hi = noise[low].mean(axis=0), noise[high].mean(axis=0)
    return np.log10(np.divide(lo, hi, out=np.ones_like(lo), where=(lo > 0) & (hi > 0)))


def _ratio(power: np.ndarray, sigma: np.ndarray, rows: np.ndarray) -> np.ndarray:
    return (2 * sigma**2).sum(axis=(0, 2)) / np.maximum(power[rows].sum(axis=(0, 2)), 1e-30)


def body_descriptors(body: Body) -> np.ndarray:
    """(N, 11) the body around each module (see the module's docstring)."""
    n = body.n_segments
    mass = body.coupling.real + np.diag(body.inertias)
    mgh = np.asarray(body.mgh, dtype=float)
    out = np.zeros((n, 11))
    for i in range(n):
        out[i, ["ankle", "knee", "hip"].index(_column(i, n))] = 1.0
        out[i, 3 + n - 1] = 1.0
        # the inertia of the segments above joint i about it, straight up
        j_above = mass[i:, i:].sum()
        out[i, 6] = np.log10(np.sqrt(j_above / mgh[i]))
        out[i, 7] = mass[i, i - 1] / mass[i, i] if i > 0 else 0.0
        out[i, 8] = mass[i, i + 1] / mass[i, i] if i + 1 < n else 0.0
        out[i, 9] = np.log(mgh[i] / mgh[i - 1]) if i > 0 else 0.0
        out[i, 10] = np.log(mgh[i + 1] / mgh[i]) if i + 1 < n else 0.0
    return out


def stimulus_descriptors(layout: HarmonicLayout) -> np.ndarray:
    """(4,) log10 of peak to peak (°), RMS velocity (°/s), period (s), cycles."""
    return np.log10([max(layout.amplitude_deg, 1e-6), max(layout.velocity_deg_s, 1e-6),
                     layout.period_samples / layout.sample_rate_hz, layout.cycles])
