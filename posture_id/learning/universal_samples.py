"""Training samples of the universal network: one per module of every trial, made from a
shard's stored harmonics with fresh sensor noise and drift (:mod:`~.features.harmonics`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from posture_id.dec.parameters import ParameterArrays
from posture_id.learning.config import LearningError
from posture_id.learning.data.drawn import UniversalSet, shard_com_weights, shard_layout
from posture_id.learning.data.scope import UniversalScope
from posture_id.learning.features.harmonics import (
    coloured_noise_parts,
    drift_parts,
    sensor_noise_parts,
)
from posture_id.learning.features.module_frfs import (
    N_INPUTS,
    features_and_noise,
    stimulus_descriptors,
)
from posture_id.simulation.noise_families import DRIFTING_COLOUR_SLOPE, NoiseFamily

__all__ = ["LoadedShard", "Samples", "SET_STRIDE", "STIMULUS_COLUMNS", "load_split",
           "make_samples", "inputs_and_noise", "rotate_motor_noise",
           "tilt_motor_noise", "TILT_PIVOT_HZ", "without_families", "split_shards"]


@dataclass(frozen=True)
class LoadedShard:
    """A shard's arrays, its layout and its body's COM weights."""

    arrays: dict
    layout: object
    com: np.ndarray

    @classmethod
    def of(cls, arrays: dict) -> LoadedShard:
        return cls(arrays, shard_layout(arrays), shard_com_weights(arrays))

    @property
    def n_segments(self) -> int:
        return int(self.arrays["y"].shape[2])


@dataclass(frozen=True)
class Samples:
    """Module samples. inputs: (M, N_INPUTS) float32 (unstandardised). targets: (M, 5)
    normalised [K̃p, K̃i, K̃d, Δ̃, C]. trial: (M,) trial index within the set made;
    module: (M,) its index in the body; segments: (M,) N; noise_ratio: (M,) the trial's
    share of locked harmonics that is noise; noise_colour: (M,) its noise's colour
    (:func:`~.features.module_frfs.noise_colour`); locked_share: (M,) its body COM sway's
    realised locked share; sensor_noise_deg, drift_deg: (M,) what was added; shard: (M,)
    the shard index."""

    inputs: np.ndarray
    targets: np.ndarray
    trial: np.ndarray
    module: np.ndarray
    segments: np.ndarray
    noise_ratio: np.ndarray
    noise_colour: np.ndarray
    locked_share: np.ndarray
    sensor_noise_deg: np.ndarray
    drift_deg: np.ndarray
    shard: np.ndarray

    def __len__(self) -> int:
        return len(self.inputs)


#: Shard labels of the i-th set trained on together start at i × this.
SET_STRIDE = 1_000_000


def load_split(data: UniversalSet | Sequence[UniversalSet], split: str) -> list[LoadedShard]:
    """Every non-empty shard of a split of one set or of several (shard labels of the
    i-th set offset by i × :data:`SET_STRIDE`), in memory (a few kB per trial)."""
    sets = [data] if isinstance(data, UniversalSet) else list(data)
    out = []
    for i, one in enumerate(sets):
        for entry in one.shards(split):
            if entry["kept"]:
                arrays = one.load(entry)
                arrays["index"] = i * SET_STRIDE + entry["index"]
                out.append(LoadedShard.of(arrays))
    return out


#: The columns of :func:`inputs_and_noise`'s inputs holding
#: :func:`~.features.module_frfs.stimulus_descriptors`
#: (the last four).
STIMULUS_COLUMNS = slice(N_INPUTS - 4, N_INPUTS)


def inputs_and_noise(layout, harmonics: np.ndarray, body: np.ndarray, com: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The network's inputs of B sways' harmonics (K, B, N) on a body whose descriptors
    are ``body`` (N, 11) and COM weights ``com`` (N, N): (B·N, N_INPUTS) float32, module
    after module within each trial; and each module's trial's
    :func:`~.features.module_frfs.noise_ratio` and
    :func:`~.features.module_frfs.noise_colour`, (B·N,) (what the calibration's regimes
    and a gated model read), the noise estimated once."""
    feats, ratio, colour = features_and_noise(layout, harmonics, com)  # (B, N, C, G)
    b, n = feats.shape[:2]
    stim = np.broadcast_to(stimulus_descriptors(layout), (b, n, 4))
    desc = np.broadcast_to(body, (b, n, body.shape[1]))
    return np.concatenate([feats.reshape(b, n, -1), desc, stim], axis=2).reshape(
        b * n, -1).astype(np.float32), np.repeat(ratio, n), np.repeat(colour, n)


def rotate_motor_noise(y: np.ndarray, y_locked: np.ndarray, rng: np.random.Generator
                       ) -> np.ndarray:
    """Harmonics (K, T, N) of the same trials with another draw of their motor noise.

    ``y`` holds each trial's harmonics with motor noise, ``y_locked`` those of the same
    trial without it (the shard's two simulations); their difference is what the noise
    did. For stationary noise through the (nearly linear) closed loop, the harmonics of
    a cycle average are complex Gaussian with a phase uniform and independent from one
    harmonic to the next: turning each harmonic's noise by its own uniform phase, the
    same for every channel of a trial (so the segments' cross-spectra stay as
    simulated), gives a realisation as likely as the simulated one, with the same power
    at every harmonic and so the same locked share. A trial without motor noise has no
    difference and is left as it is. ``tests/test_universal.py`` checks the premise
    (the noise's harmonics over many draws centred on zero, their phases uniform)
    against simulations."""
    noise = y - y_locked
    turn = np.exp(2j * np.pi * rng.random(noise.shape[:2]))[:, :, None]
    return y_locked + noise * turn


#: The motor noise's spectral tilt (:func:`tilt_motor_noise`) pivots about a frequency
#: drawn log-uniformly in this range, Hz: where people's sway is excited and measured.
TILT_PIVOT_HZ = (0.1, 1.0)


def tilt_motor_noise(y: np.ndarray, y_locked: np.ndarray, frequencies_hz: np.ndarray,
                     max_tilt: float, rng: np.random.Generator) -> np.ndarray:
    """Harmonics (K, T, N) of the same trials with their motor noise of another spectral
    shape: each trial's noise ``y − y_locked`` (harmonics at ``frequencies_hz`` (K,), Hz)
    multiplied by ``(f / f₀)^(−s/2)``, the slope ``s`` uniform in ``[−max_tilt,
    max_tilt]`` and the pivot ``f₀`` log-uniform in :data:`TILT_PIVOT_HZ`, both drawn
    per trial, then scaled so that the trial keeps the noise power it had (summed over
    harmonics and segments: the same locked share).

    Through the (nearly linear) closed loop, torque noise whose PSD is multiplied by
    ``G(f)`` moves each harmonic of the sway's noise by ``√G(f)``, at every segment
    alike when the joints' torque noises share their shape: this is the sway of the
    same trial under torque noise whose PSD slope is steeper (``s > 0``) or shallower
    by ``s``, which no simulation made. The network then cannot read the controller
    from the noise's own spectrum (which is the closed loop's shape times the torque
    noise's, so a network that saw only one torque-noise shape learns to), only from
    what is locked to the stimulus. ``tests/test_universal.py`` checks the premise
    against simulations of two torque-noise slopes. A trial without motor noise is
    left as it is."""
    if max_tilt <= 0:
        return y
    t = y.shape[1]
    noise = y - y_locked
    slope = rng.uniform(-max_tilt, max_tilt, t)
    pivot = np.exp(rng.uniform(*np.log(TILT_PIVOT_HZ), t))
    gain = (np.asarray(frequencies_hz, dtype=float)[:, None] / pivot[None, :]) ** (
        -slope[None, :] / 2)  # (K, T)
    before = np.sum(np.abs(noise) ** 2, axis=(0, 2))
    after = np.sum(np.abs(noise) ** 2 * gain[:, :, None] ** 2, axis=(0, 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        keep = np.where(after > 0, np.sqrt(before / after), 1.0)
    return y_locked + noise * (gain * keep[None, :])[:, :, None]


def _sensor_parts(arrays: dict, layout, scope: UniversalScope, sd_rad: np.ndarray,
                  rng: np.random.Generator) -> np.ndarray:
    """(K, T) SD of each part of each harmonic for the sensor noise of a shard's trials:
    white, but coloured (slope uniform in the family's
    :data:`~posture_id.simulation.noise_families.DRIFTING_COLOUR_SLOPE`, drawn here, afresh
    every epoch) for the trials whose noise family is ``drifting`` (:mod:`posture_id.
    simulation.noise_families`)."""
    white = sensor_noise_parts(layout.period_samples, layout.cycles, sd_rad)  # (T,)
    parts = np.broadcast_to(white[None, :], (len(layout.frequencies_hz), len(white))).copy()
    family = arrays.get("noise_family")
    if family is None or NoiseFamily.DRIFTING.value not in scope.noise_families:
        return parts
    coloured = np.asarray(family) == scope.noise_families.index(NoiseFamily.DRIFTING.value)
    if coloured.any():
        slope = rng.uniform(*DRIFTING_COLOUR_SLOPE, int(coloured.sum()))
        parts[:, coloured] = coloured_noise_parts(
            layout.period_samples, layout.cycles, sd_rad[coloured], layout.frequencies_hz,
            layout.sample_rate_hz, slope).T
    return parts


def make_samples(shards: list[LoadedShard], scope: UniversalScope,
                 rng: np.random.Generator, fresh_motor_noise: bool = False,
                 motor_noise_tilt: float = 0.0) -> Samples:
    """The module samples of ``shards`` with sensor noise (SD uniform in the scope's range,
    per trial) and drift (level uniform in the scope's range, for trials with motor
    noise) drawn from ``rng``; with ``fresh_motor_noise``, each trial's motor noise
    as well (:func:`rotate_motor_noise`); with ``motor_noise_tilt`` > 0, its spectral
    shape too (:func:`tilt_motor_noise`, slopes up to that far from the simulated)."""
    parts: dict[str, list] = {k: [] for k in Samples.__dataclass_fields__}
    first = 0
    for shard in shards:
        a, layout = shard.arrays, shard.layout
        y = np.moveaxis(a["y"], 0, 1).astype(np.complex128)  # (K, T, N)
        k, t, n = y.shape
        if fresh_motor_noise or motor_noise_tilt > 0:
            y_locked = np.moveaxis(a["y_locked"], 0, 1)
            if fresh_motor_noise:
                y = rotate_motor_noise(y, y_locked, rng)
            y = tilt_motor_noise(y, y_locked, layout.frequencies_hz, motor_noise_tilt, rng)
        sensor = rng.uniform(*scope.sensor_noise_deg, t)
        drift = np.where(a["motor_noise_deg"] > 0, rng.uniform(*scope.drift_deg, t), 0.0)
        sd = np.sqrt(_sensor_parts(a, layout, scope, np.radians(sensor), rng) ** 2
                     + drift_parts(layout.frequencies_hz, layout.cycles * layout.period_samples
                                   / layout.sample_rate_hz, drift).T ** 2)  # (K, T)
        y = y + sd[:, :, None] * (rng.standard_normal(y.shape) + 1j * rng.standard_normal(y.shape))
        inputs, rho, colour = inputs_and_noise(layout, y, a["body"], shard.com)
        parts["inputs"].append(inputs)
        parts["noise_ratio"].append(rho)
        parts["noise_colour"].append(colour)
        parts["targets"].append(a["targets"].reshape(t * n, 5))
        per_module = {"trial": first + np.arange(t), "locked_share": a["locked_share"],
                      "sensor_noise_deg": sensor, "drift_deg": drift}
        for key, value in per_module.items():
            parts[key].append(np.repeat(value, n))
        parts["module"].append(np.tile(np.arange(n), t))
        parts["segments"].append(np.full(t * n, n))
        parts["shard"].append(np.full(t * n, a["index"]))
        first += t
    return Samples(**{k: np.concatenate(v) for k, v in parts.items()})


def without_families(shards: list[LoadedShard], scope: UniversalScope,
                     families: tuple[str, ...]) -> list[LoadedShard]:
    """``shards`` without the trials whose motor noise is of one of ``families`` (a set
    made without noise families has none of them: every trial is kept)."""
    if not families:
        return shards
    unknown = [f for f in families if f not in scope.noise_families]
    if unknown:
        drawn = ", ".join(scope.noise_families) or "the low-pass only"
        raise LearningError(f"no trial of these sets is of the noise families "
                            f"{', '.join(unknown)}; they draw {drawn}")
    drop = [scope.noise_families.index(f) for f in families]
    out = []
    for shard in shards:
        family = shard.arrays.get("noise_family")
        if family is None:
            out.append(shard)
            continue
        keep = ~np.isin(family, drop)
        if keep.all():
            out.append(shard)
        elif keep.any():
            per_trial = {"y", "y_locked", "targets", "locked_share", "motor_noise_deg",
                         "noise_family", *ParameterArrays.FIELDS}
            arrays = {k: v[keep] if k in per_trial else v for k, v in shard.arrays.items()}
            out.append(replace(shard, arrays=arrays))
    return out


#: Which shard index (mod 10) each split takes (:func:`~.data.drawn.split_of`).
_SPLIT_INDEX = {"test": "≡ 0", "calibration": "≡ 1", "validation": "≡ 2", "train": "≥ 3"}


def split_shards(data: Sequence[UniversalSet], split: str, scope: UniversalScope,
                 families: tuple[str, ...] = ()) -> list[LoadedShard]:
    """The shards of ``split`` of the sets ``data`` (:func:`load_split`) without the trials
    of the noise ``families`` (:func:`without_families`), refused in one line when they
    hold no trial (a set too small to have that split, or every trial of it in a family
    left out)."""
    shards = without_families(load_split(data, split), scope, families)
    if shards:
        return shards
    names = ", ".join(str(d.path) for d in data)
    made = sum(len(d.manifest["shards"]) for d in data)
    left = f" outside the families left out ({', '.join(families)})" if families else ""
    raise LearningError(f"{names}: no {split} trial{left}: the {split} split takes the shards "
                        f"whose index is {_SPLIT_INDEX[split]} (mod 10) and this holds "
                        f"{made}; make at least 10 shards (posture-id network universal data "
                        "--shards N, resumable)")
