"""One shard of a data set: simulate its trials and compute their features.

Shard k draws its parameters from the k-th child of ``SeedSequence([seed, 0])``, so its
bytes depend only on (configuration, k), never on workers or completion order.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from posture_id.bodies.body import Body, load_body
from posture_id.dec.parameters import ParameterArrays, default_parameters, normalise_arrays
from posture_id.dec.prior import sample_parameters
from posture_id.learning.data.store import with_sensor_noise
from posture_id.learning.data.trial_config import DatasetConfig
from posture_id.learning.features.spectrograms import modular_images, monolithic_images, stft
from posture_id.simulation.batch import simulate_batch
from posture_id.simulation.noise import MotorNoise

__all__ = ["make_shard", "make_shard_remote", "shard_seed", "motor_noises", "PARAMETER_FIELDS"]

PARAMETER_FIELDS = ParameterArrays.FIELDS


def shard_seed(seed: int, k: int) -> np.random.SeedSequence:
    return np.random.SeedSequence([seed, 0]).spawn(k + 1)[k]


def make_shard(config: DatasetConfig, k: int, body: Body | None = None) -> dict[str, np.ndarray]:
    """Simulate shard ``k`` and compute its features: a dict of arrays for ``np.savez``.

    Keys: parameter arrays (S, N) of all simulated trials, ``abort_time`` (S,) s (NaN when
    kept), ``max_sway_deg`` (S,), ``kept`` (S,) bool; for the K kept trials only:
    ``theta`` (K, 6051, N) float32 rad, ``alpha_bs`` (K, 6051) float32 rad,
    ``modular`` (K, N, 3, 51, 51) float32, ``monolithic`` (K, 2N−1, 51, 51) float32,
    ``targets`` (K, N, 5) normalised [K̃p, K̃i, K̃d, Δ̃, C], ``sensor_noise_deg`` (K,) the
    white noise SD added to each kept trial's segment angles before its features (drawn
    uniformly from [0, ``config.sensor_noise_deg``]; ``theta`` is stored without it),
    ``motor_noise_deg`` (K,) the level of each kept trial's motor noise (drawn uniformly
    from [0, ``config.motor_noise_deg``] with its seed from ``SeedSequence([seed, 2, k])``,
    so sets without motor noise keep their bytes).
    """
    body = body or load_body(config.body)
    rng = np.random.default_rng(shard_seed(config.seed, k))
    params = sample_parameters(body, config.shard_size, rng, sigma=config.sigma)
    motor = motor_noises(config, k)
    batch = simulate_batch(body, params, config.stimulus(), config.simulation, workers=1,
                           motor_noise=motor)
    kept = batch.stable
    with np.errstate(invalid="ignore"):
        max_sway = np.degrees(np.nanmax(np.abs(batch.theta), axis=(1, 2)))
    max_sway = np.where(kept, max_sway, config.simulation.sway_limit_deg)
    theta = batch.theta[kept]
    # sensor noise (after the parameter draws, so parameters do not depend on it)
    noise_sd = config.sensor_noise_deg * rng.random(len(theta))
    noisy = with_sensor_noise(theta, noise_sd, rng)
    spectra = stft(np.moveaxis(noisy, 1, 2))  # (K, N, 51, 51)
    tilt_spectrum = stft(batch.tilt)
    targets = normalise_arrays(params, default_parameters(body))[kept]
    out = {f: getattr(params, f) for f in PARAMETER_FIELDS}
    out.update(
        abort_time=batch.abort_time,
        max_sway_deg=max_sway,
        kept=kept,
        theta=theta.astype(np.float32),
        alpha_bs=batch.alpha[kept, :, 0].astype(np.float32),
        modular=modular_images(tilt_spectrum, spectra),
        monolithic=monolithic_images(spectra),
        targets=targets,
        sensor_noise_deg=noise_sd,
        motor_noise_deg=np.array([m.sd_deg for m in motor] if motor else
                                 np.zeros(len(kept)))[kept],
    )
    return out


def motor_noises(config: DatasetConfig, k: int) -> list[MotorNoise] | None:
    """The motor noise of every trial of shard ``k`` (None when the set has none)."""
    if config.motor_noise_deg == 0:
        return None
    rng = np.random.default_rng(np.random.SeedSequence([config.seed, 2, k]))
    levels = config.motor_noise_deg * rng.random(config.shard_size)
    seeds = rng.integers(0, 2**63 - 1, config.shard_size)
    return [MotorNoise(float(level), config.motor_cutoff_hz, int(seed))
            for level, seed in zip(levels, seeds, strict=True)]


def make_shard_remote(config: DatasetConfig, k: int, urdf_text: str) -> dict[str, np.ndarray]:
    """:func:`make_shard` on a cluster worker, which may not see the body file: the URDF
    text travels with the task."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / Path(config.body).name
        path.write_text(urdf_text)
        return make_shard(config, k, load_body(path))
