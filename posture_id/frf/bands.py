"""A lab's FRF points: bands of stimulated harmonics with fixed centre frequencies, and the
pseudo-impulse response of an FRF at such points.

Labs report FRFs at a fixed set of points so that subjects, groups and studies compare:
each point averages the cross- and auto-spectra over a band of the stimulated harmonics
(:func:`~posture_id.frf.response.frequency_response_arrays` sums them). A band is given as
the ordinals of the stimulated harmonics it takes (1 = the lowest stimulated one; bands may
overlap) for a reference cycle length, or as a frequency range; for another cycle length a
band of ordinals takes the stimulated harmonics within the frequencies its ordinals span
at the reference (half the reference's spacing of stimulated harmonics beyond each end),
so the points keep their frequencies.

:data:`PETERKA_11`: the 11 points of Peterka (2002) for a 20 s PRTS cycle (the 80-state
PRTS of 0.25 s states, every odd harmonic of 0.05 Hz stimulated): ordinals 1; 2; 3–4; 4–5;
5–7; 6–9; 8–11; 10–13; 12–16; 16–20; 20–25, centred at 0.05, 0.15, 0.30, 0.40, 0.55, 0.70,
0.90, 1.10, 1.35, 1.75 and 2.20 Hz.

The pseudo-impulse response (PIR) of an FRF H_k at frequencies f_k is the time signal
x(t) = Σ_k [Re H_k·cos(2π f_k t) − Im H_k·sin(2π f_k t)] over one common period (1 / the
greatest common divisor of the f_k), the form in which norms and groups of FRFs are
compared (:func:`pseudo_impulse_response`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from functools import reduce

import numpy as np

from posture_id.errors import PostureIdError

__all__ = ["FrequencyBands", "PETERKA_11", "BAND_PRESETS", "pseudo_impulse_response",
           "common_period_s", "parse_bands"]


@dataclass(frozen=True)
class FrequencyBands:
    """A lab's FRF points.

    Attributes:
        harmonics: per band, (first, last) ordinals (1-based, inclusive) among the
            stimulated harmonics, for ``reference_period_s``; or None.
        ranges_hz: per band, [low, high) Hz; or None (one of the two is given).
        centres_hz: per band, the frequency it is reported at (default: the geometric mean
            of the frequencies it takes).
        reference_period_s: the cycle the ordinals count in (None: any cycle, counted as
            they are). reference_spacing_hz: the spacing of the reference's stimulated
            harmonics (for the ranges of another cycle).
        name: what it is called.
    """

    harmonics: tuple[tuple[int, int], ...] | None = None
    ranges_hz: tuple[tuple[float, float], ...] | None = None
    centres_hz: tuple[float, ...] | None = None
    reference_period_s: float | None = None
    reference_spacing_hz: float | None = None
    name: str = "custom"

    def __post_init__(self) -> None:
        if (self.harmonics is None) == (self.ranges_hz is None):
            raise PostureIdError("FRF bands: give the bands as stimulated-harmonic ordinals "
                                 "or as frequency ranges (one of the two)")
        bands = self.harmonics if self.harmonics is not None else self.ranges_hz
        if not bands:
            raise PostureIdError("FRF bands: no band given")
        if self.harmonics is not None:
            for first, last in self.harmonics:
                if not (isinstance(first, int) and isinstance(last, int) and 1 <= first
                        <= last):
                    raise PostureIdError(f"FRF bands: harmonics {first}–{last} must be whole "
                                         "ordinals 1 ≤ first ≤ last")
        else:
            for low, high in self.ranges_hz:
                if not (math.isfinite(low) and math.isfinite(high) and 0 <= low < high):
                    raise PostureIdError(f"FRF bands: range {low:g}–{high:g} Hz must have "
                                         "0 ≤ low < high")
        if self.centres_hz is not None and len(self.centres_hz) != len(bands):
            raise PostureIdError(f"FRF bands: {len(self.centres_hz)} centres for "
                                 f"{len(bands)} bands")

    def __len__(self) -> int:
        return len(self.harmonics if self.harmonics is not None else self.ranges_hz)

    def groups(self, stimulated_hz: np.ndarray, period_s: float) -> list[np.ndarray]:
        """Per band, the indices into ``stimulated_hz`` (the stimulated harmonics of a
        ``period_s`` cycle, ascending) it averages."""
        f = np.asarray(stimulated_hz, dtype=float)
        if self.harmonics is not None and (self.reference_period_s is None or abs(
                period_s - self.reference_period_s) < 1e-6):
            out = []
            for first, last in self.harmonics:
                if last > len(f):
                    raise PostureIdError(
                        f"FRF band of stimulated harmonics {first}–{last}: the stimulus "
                        f"stimulates {len(f)} harmonics up to the highest frequency kept "
                        f"({f[-1] if len(f) else 0:g} Hz)")
                out.append(np.arange(first - 1, last))
            return out
        return [np.flatnonzero((f >= low) & (f < high)) for low, high in self._ranges()]

    def _ranges(self) -> list[tuple[float, float]]:
        if self.ranges_hz is not None:
            return list(self.ranges_hz)
        spacing = self.reference_spacing_hz
        first_hz = spacing / 2  # the reference's stimulated harmonics: odd multiples
        return [(first_hz + (a - 1) * spacing - spacing / 2,
                 first_hz + (b - 1) * spacing + spacing / 2) for a, b in self.harmonics]

    def centres(self, stimulated_hz: np.ndarray, groups: list[np.ndarray]) -> np.ndarray:
        """(B,) the frequencies the bands are reported at."""
        if self.centres_hz is not None:
            return np.asarray(self.centres_hz, dtype=float)
        f = np.asarray(stimulated_hz, dtype=float)
        return np.array([math.exp(np.log(f[g]).mean()) if len(g) else math.nan
                         for g in groups])

    @classmethod
    def from_dict(cls, data: dict) -> FrequencyBands:
        """What :meth:`to_dict` wrote (a preset by its name)."""
        if data.get("name") in BAND_PRESETS:
            return BAND_PRESETS[data["name"]]
        return cls(harmonics=None if data.get("harmonics") is None else tuple(
                       tuple(b) for b in data["harmonics"]),
                   ranges_hz=None if data.get("ranges_hz") is None else tuple(
                       tuple(b) for b in data["ranges_hz"]),
                   centres_hz=None if data.get("centres_hz") is None else tuple(
                       data["centres_hz"]),
                   reference_period_s=data.get("reference_period_s"),
                   name=data.get("name", "custom"))

    def to_dict(self) -> dict:
        """JSON-ready: the name, the harmonic ordinals or ranges (Hz), the centres (Hz) and
        the reference period (s); :meth:`from_dict` reads it back."""
        return {"name": self.name,
                "harmonics": None if self.harmonics is None else [list(b) for b in
                                                                  self.harmonics],
                "ranges_hz": None if self.ranges_hz is None else [list(b) for b in
                                                                  self.ranges_hz],
                "centres_hz": None if self.centres_hz is None else list(self.centres_hz),
                "reference_period_s": self.reference_period_s}


#: Peterka (2002)'s 11 points for a 20 s PRTS cycle (the module doc).
PETERKA_11 = FrequencyBands(
    harmonics=((1, 1), (2, 2), (3, 4), (4, 5), (5, 7), (6, 9), (8, 11), (10, 13), (12, 16),
               (16, 20), (20, 25)),
    centres_hz=(0.05, 0.15, 0.30, 0.40, 0.55, 0.70, 0.90, 1.10, 1.35, 1.75, 2.20),
    reference_period_s=20.0, reference_spacing_hz=0.1, name="peterka11")

#: The named presets (``posture-id frf --band-preset NAME``).
BAND_PRESETS = {"peterka11": PETERKA_11}


def parse_bands(text: str, kind: str) -> FrequencyBands:
    """Bands from a command line: ``"1;2;3-4;4-5"`` (harmonic ordinals, ``kind`` =
    "harmonics") or ``"0.2-0.4;0.4-0.8"`` (Hz, ``kind`` = "ranges")."""
    bands = []
    for part in text.replace(" ", "").split(";"):
        if not part:
            continue
        low, _, high = part.partition("-")
        try:
            a = int(low) if kind == "harmonics" else float(low)
            b = (int(high) if kind == "harmonics" else float(high)) if high else a
        except ValueError:
            raise PostureIdError(f"FRF bands: {part!r} is not a band ("
                                 + ("ordinals like 3-4" if kind == "harmonics"
                                    else "Hz like 0.2-0.4") + ")") from None
        bands.append((a, b))
    if kind == "harmonics":
        return FrequencyBands(harmonics=tuple(bands))
    return FrequencyBands(ranges_hz=tuple(bands))


def common_period_s(frequencies_hz: np.ndarray) -> float:
    """1 / the greatest common divisor of the frequencies (to 1 mHz), s."""
    fractions = [Fraction(float(f)).limit_denominator(1000) for f in frequencies_hz]
    if any(f <= 0 for f in fractions):
        raise PostureIdError("a pseudo-impulse response needs frequencies > 0")

    def gcd(a: Fraction, b: Fraction) -> Fraction:
        return Fraction(math.gcd(a.numerator * b.denominator, b.numerator * a.denominator),
                        a.denominator * b.denominator)

    return float(1 / reduce(gcd, fractions))


def pseudo_impulse_response(frequencies_hz: np.ndarray, response: np.ndarray,
                            rate_hz: float = 22.0) -> tuple[np.ndarray, np.ndarray]:
    """(t (S,) s, x (S, ...)) over one common period sampled at ``rate_hz``:
    x(t) = Σ_k [Re H_k·cos(2π f_k t) − Im H_k·sin(2π f_k t)] for ``response`` (F, ...)."""
    f = np.asarray(frequencies_hz, dtype=float)
    h = np.asarray(response, dtype=complex)
    if not (math.isfinite(rate_hz) and rate_hz > 2 * f.max()):
        raise PostureIdError(f"a pseudo-impulse response at {rate_hz:g} Hz cannot hold "
                             f"{f.max():g} Hz (rate above twice the highest frequency)")
    period = common_period_s(f)
    t = np.arange(int(round(period * rate_hz))) / rate_hz
    phase = 2 * np.pi * np.outer(t, f)  # (S, F)
    x = np.tensordot(np.cos(phase), h.real, axes=(1, 0)) - np.tensordot(
        np.sin(phase), h.imag, axes=(1, 0))
    return t, x
