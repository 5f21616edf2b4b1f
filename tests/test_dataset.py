"""Training data: determinism, resume, splits, manifest, Dask, bad input."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from posture_id.bodies.body import DEFAULT_URDF
from posture_id.cli import main
from posture_id.learning.data.trial_generation import (
    Dataset,
    DatasetConfig,
    DatasetError,
    generate_dataset,
)


def _config(body=DEFAULT_URDF, **kw) -> DatasetConfig:
    args = dict(trials=20, body=str(body), seed=7, shard_size=8)
    args.update(kw)
    return DatasetConfig(**args)


def _digests(path: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(path.iterdir()) if p.is_file()}


@pytest.fixture(scope="module")
def reference_set(tmp_path_factory):
    out = tmp_path_factory.mktemp("data") / "ref"
    generate_dataset(_config(), out, workers=1)
    return out


def test_dataset_content(reference_set):
    data = Dataset.open(reference_set)
    m = data.manifest
    assert m["complete"] and m["counts"]["used"] == 20
    assert m["counts"]["simulated"] == 8 * len(m["shards"])
    assert sum(s["used"] for s in m["shards"]) == 20
    first = data.load_shard(0)
    kept = first["kept"]
    assert first["theta"].shape == (min(kept.sum(), 20), 6051, 3)
    assert first["modular"].shape[1:] == (3, 3, 51, 51)
    assert first["monolithic"].shape[1:] == (5, 51, 51)
    # rejected trials keep their parameters and abort times
    assert np.all(np.isnan(first["abort_time"][kept]))
    assert np.all(np.isfinite(first["abort_time"][~kept]))
    assert first["kp"].shape == (8, 3)
    # targets are the normalised parameters of the kept trials
    kp0 = np.array(m["body"]["mgh"])
    np.testing.assert_allclose(first["targets"][:, :, 0], first["kp"][kept] / kp0 - 1,
                               rtol=1e-12)
    np.testing.assert_array_equal(first["targets"][:, :, 4], first["sign"][kept])


def test_determinism_across_worker_counts(reference_set, tmp_path):
    generate_dataset(_config(), tmp_path / "two", workers=2)
    assert _digests(tmp_path / "two") == _digests(reference_set)


def test_kill_and_resume_gives_the_same_bytes(reference_set, tmp_path):
    out = tmp_path / "resumed"
    calls = []

    def die_after_first_shard(update):
        calls.append(update.done)
        if update.done > 0:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        generate_dataset(_config(), out, workers=1, progress=die_after_first_shard)
    manifest = json.loads((out / "manifest.json").read_text())
    assert not manifest["complete"] and len(manifest["shards"]) >= 1
    # also a shard written whose manifest entry was lost in the kill
    manifest["shards"] = manifest["shards"][:-1]
    (out / "manifest.json").write_text(json.dumps(manifest))
    generate_dataset(_config(), out, workers=2)
    assert _digests(out) == _digests(reference_set)


def test_split_is_by_trial_and_disjoint(reference_set):
    data = Dataset.open(reference_set)
    split = data.split()
    sets = [set(split[k].tolist()) for k in ("train", "validation", "test")]
    assert sum(len(s) for s in sets) == 20
    assert set().union(*sets) == set(range(20))
    assert not (sets[0] & sets[1] or sets[0] & sets[2] or sets[1] & sets[2])
    assert data.manifest["split"]["train"]["modular_samples"] == 3 * len(sets[0])


def test_statistics_come_from_the_training_set(reference_set):
    data = Dataset.open(reference_set)
    train = data.split()["train"]
    images = np.concatenate([s["modular"] for s in data.iter_shards()])[train]
    stats = data.stats()
    flat = images.reshape(-1, 3, 51, 51).astype(np.float64)
    np.testing.assert_allclose(stats["modular_mean"], flat.mean(axis=0), rtol=1e-10)
    np.testing.assert_allclose(stats["modular_std"], flat.std(axis=0, ddof=1), rtol=1e-8)
    targets = np.concatenate([s["targets"] for s in data.iter_shards()])[train]
    np.testing.assert_allclose(stats["targets_mean"], targets.reshape(-1, 5).mean(axis=0))


def test_manifest_round_trips(reference_set):
    text = (reference_set / "manifest.json").read_text()
    manifest = json.loads(text)
    assert json.dumps(manifest, indent=2) + "\n" == text
    assert manifest["config"] == _config().identity()
    assert manifest["package_version"]
    assert manifest["body"]["sha256"] == hashlib.sha256(DEFAULT_URDF.read_bytes()).hexdigest()


def test_other_arguments_are_refused_and_touch_nothing(reference_set, tmp_path):
    out = tmp_path / "copy"
    shutil.copytree(reference_set, out)
    before = _digests(out)
    with pytest.raises(DatasetError, match="other arguments \\(seed differ"):
        generate_dataset(_config(seed=8), out)
    assert _digests(out) == before


def test_corrupt_shard_is_reported_and_untouched(reference_set, tmp_path):
    out = tmp_path / "copy"
    shutil.copytree(reference_set, out)
    shard = out / "shard-00001.npz"
    shard.write_bytes(shard.read_bytes()[:1000])
    before = _digests(out)
    with pytest.raises(DatasetError, match="shard-00001.npz: shard is corrupt or truncated"):
        generate_dataset(_config(), out)
    with pytest.raises(DatasetError, match="corrupt or truncated"):
        Dataset.open(out)
    assert _digests(out) == before


def test_changed_body_file_is_refused(tmp_path):
    body = tmp_path / "body.urdf"
    body.write_text(DEFAULT_URDF.read_text())
    out = tmp_path / "set"
    generate_dataset(_config(body=body, trials=3), out, workers=1)
    before = _digests(out)
    body.write_text(DEFAULT_URDF.read_text().replace('value="30.0"', 'value="31.0"'))
    with pytest.raises(DatasetError, match="changed since this data set was started"):
        generate_dataset(_config(body=body, trials=3), out)
    assert _digests(out) == before


def test_dask_local_cluster_gives_the_same_shards(reference_set, tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster:
        generate_dataset(_config(), tmp_path / "dask", scheduler=cluster.scheduler_address)
    assert _digests(tmp_path / "dask") == _digests(reference_set)


def test_cli_generate_and_info(tmp_path, capsys):
    out = tmp_path / "cli"
    assert main(["network", "cnn", "data", "generate", "--trials", "4", "--shard-size", "8",
                "--out",
                 str(out), "--quiet"]) == 0
    assert main(["network", "cnn", "data", "info", str(out)]) == 0
    text = capsys.readouterr().out
    assert "4 trials used" in text and "rejected" in text and "train" in text
    assert (out / "dataset_overview.png").stat().st_size > 10_000
    assert (out / "dataset_images.png").stat().st_size > 10_000
    assert main(["network", "cnn", "data", "generate", "--trials", "5", "--shard-size", "8",
                "--out",
                 str(out), "--quiet"]) == 2
    assert "other arguments (trials differ" in capsys.readouterr().err


def test_features_need_the_rate_they_are_defined_for():
    from posture_id.simulation import SimulationOptions

    with pytest.raises(DatasetError, match="defined at 50 Hz; the simulation samples at 100 Hz"):
        _config(simulation=SimulationOptions(sample_rate_hz=100.0))


def test_sensor_noise_changes_the_features_only(tmp_path):
    clean = generate_dataset(_config(trials=4, shard_size=8), tmp_path / "clean", workers=1)
    noisy = generate_dataset(_config(trials=4, shard_size=8, sensor_noise_deg=0.05),
                             tmp_path / "noisy", workers=1)
    a, b = clean.load_shard(0), noisy.load_shard(0)
    for key in ("kp", "delay_s", "sign", "theta", "targets"):
        np.testing.assert_array_equal(a[key], b[key])
    assert np.all(a["sensor_noise_deg"] == 0) and np.all(b["sensor_noise_deg"] <= 0.05)
    assert b["sensor_noise_deg"].max() > 0
    assert not np.allclose(a["modular"], b["modular"])
    # white noise lifts the high-frequency magnitudes, where the clean sway has little
    assert b["modular"][:, :, 0, 40:].mean() > 2 * a["modular"][:, :, 0, 40:].mean()


def test_motor_noise_moves_the_bodies_with_each_trials_own_seed(tmp_path):
    from posture_id.bodies.body import load_body
    from posture_id.dec.parameters import ParameterArrays
    from posture_id.simulation import simulate_batch
    from posture_id.simulation.noise import MotorNoise

    config = _config(trials=4, shard_size=8, motor_noise_deg=0.3, motor_cutoff_hz=0.5)
    clean = generate_dataset(_config(trials=4, shard_size=8), tmp_path / "clean", workers=1)
    noisy = generate_dataset(config, tmp_path / "noisy", workers=1)
    a, b = clean.load_shard(0), noisy.load_shard(0)
    for key in ("kp", "delay_s", "sign"):  # the parameters do not depend on the noise
        np.testing.assert_array_equal(a[key], b[key])
    assert np.all(a["motor_noise_deg"] == 0)
    assert np.all((b["motor_noise_deg"] >= 0) & (b["motor_noise_deg"] <= 0.3))
    assert len(set(b["motor_noise_deg"].round(12))) == len(b["motor_noise_deg"])
    # the stored sway is the noisy sway: one trial re-simulated alone with its own noise
    from posture_id.learning.data.trial_shards import motor_noises

    noises = motor_noises(config, 0)
    first = int(np.flatnonzero(b["kept"])[0])
    assert noises[first].sd_deg == b["motor_noise_deg"][0]
    params = ParameterArrays(**{f: b[f][first : first + 1] for f in ParameterArrays.FIELDS})
    alone = simulate_batch(load_body(config.body), params, config.stimulus(),
                           config.simulation, motor_noise=[noises[first]])
    np.testing.assert_allclose(b["theta"][0], alone.theta[0], atol=1e-7)  # float32 storage
    assert isinstance(noises[first], MotorNoise)
    assert not np.allclose(a["theta"][0], b["theta"][0], atol=1e-5)
    assert noisy.manifest["config"]["motor_noise_deg"] == 0.3
