"""The universal network's sets over noise families: shards whose trials draw their torque
noise from several families (and say which), coloured sensor noise on the stored
harmonics against noise on the sway, training that leaves families out, and fine-tuning
from a trained model."""

from __future__ import annotations

import numpy as np
import pytest

from posture_id.learning.data.scope import ScopeError, UniversalScope
from posture_id.learning.features.harmonics import (
    coloured_noise_parts,
    harmonic_layout,
    sensor_noise_parts,
    sway_harmonics,
)
from posture_id.simulation.measurement import MeasurementNoise

FAMILIES = ("low_pass", "shallow", "drifting")


@pytest.fixture(scope="module")
def family_set(tmp_path_factory):
    """12 shards of 8 trials, every noisy trial of one of three families."""
    from posture_id.learning.data.drawn import UniversalDataConfig, generate_universal

    out = tmp_path_factory.mktemp("universal") / "families"
    scope = UniversalScope(noise_families=FAMILIES, clean_share=0.0)
    return generate_universal(UniversalDataConfig(shards=12, trials=8, seed=3, scope=scope),
                              out, workers=2)


def test_a_scope_draws_tilts_a_platform_can_run():
    with pytest.raises(ScopeError, match="within \\(0, 20\\]° peak to peak"):
        UniversalScope(amplitude_deg=(30.0, 40.0))
    assert UniversalScope(amplitude_deg=(8.0, 12.0)).amplitude_deg == (8.0, 12.0)


def test_a_scope_names_known_families_once():
    with pytest.raises(ScopeError, match="noise_families"):
        UniversalScope(noise_families=("pink",))
    with pytest.raises(ScopeError, match="noise_families"):
        UniversalScope(noise_families=("shallow", "shallow"))
    assert UniversalScope(noise_families=["shallow"]).noise_families == ("shallow",)


def test_a_scope_without_families_draws_nothing_more():
    """A set made before families draws as it did: no number is taken from the stream."""
    from posture_id.learning.data.drawn import _noise_draws

    rng = np.random.default_rng(1)
    family, cutoff, shapes = _noise_draws(UniversalScope(), 5, rng)
    assert (family == -1).all() and cutoff == [0.2] * 5
    assert rng.random() == np.random.default_rng(1).random()


def test_shards_say_each_trials_family_and_draw_them_all(family_set):
    from posture_id.learning.universal_samples import load_split

    shards = load_split([family_set], "train")
    family = np.concatenate([s.arrays["noise_family"] for s in shards])
    assert set(family.tolist()) == {0, 1, 2}
    level = np.concatenate([s.arrays["motor_noise_deg"] for s in shards])
    assert np.all(level > 0)  # clean_share 0: every trial has motor noise


def test_training_can_leave_a_family_out(family_set):
    from posture_id.learning.config import LearningError
    from posture_id.learning.universal_samples import load_split, without_families

    scope = family_set.manifest["config"]["scope"]
    scope = UniversalScope.from_dict(scope)
    shards = load_split([family_set], "train")
    kept = without_families(shards, scope, ("shallow",))
    before = np.concatenate([s.arrays["noise_family"] for s in shards])
    after = np.concatenate([s.arrays["noise_family"] for s in kept])
    assert 1 not in after and len(after) == int(np.sum(before != 1))
    for shard in kept:
        t = len(shard.arrays["noise_family"])
        assert shard.arrays["y"].shape[0] == t == len(shard.arrays["targets"])
        assert shard.arrays["y_locked"].shape[0] == t == len(shard.arrays["kp"])
    with pytest.raises(LearningError, match="correlated"):
        without_families(shards, scope, ("correlated",))


def test_coloured_sensor_noise_on_harmonics_matches_noise_on_the_sway():
    from posture_id.simulation.stimulus import prts

    profile = prts(1.0, 3, 80)
    t = np.arange(int(round(profile.duration * 50)) + 1) / 50
    layout = harmonic_layout(profile.angle(t), 50.0, profile.period_s)
    sd, slope = 0.002, 1.5
    noise = np.radians(MeasurementNoise(sd_deg=np.degrees(sd), colour_slope=slope).draw(
        t, 300, seed=4))
    y = sway_harmonics(layout, noise)  # (K, 300)
    predicted = coloured_noise_parts(layout.period_samples, layout.cycles, np.array(sd),
                                     layout.frequencies_hz, 50.0, np.array(slope))
    measured = np.sqrt(np.mean(y.real**2, axis=1))
    band = slice(5, None)  # the lowest harmonics are touched by the detrending
    ratio = measured[band] / predicted[band]
    assert np.median(ratio) == pytest.approx(1.0, abs=0.05)
    assert np.all(np.abs(ratio - 1) < 0.35)  # 300 draws per harmonic
    white = coloured_noise_parts(layout.period_samples, layout.cycles, np.array(sd),
                                 layout.frequencies_hz, 50.0, np.array(0.0))
    # white: the white formula, but for the offset the draw leaves out (one bin of 2N)
    np.testing.assert_allclose(white, sensor_noise_parts(layout.period_samples,
                                                         layout.cycles, sd), rtol=2e-4)


@pytest.mark.slow("trains a network")
def test_a_model_fine_tuned_from_the_bundled_one_keeps_its_standardisation(family_set,
                                                                          tmp_path):
    from posture_id.learning.universal_identifier import BUNDLED_DIR
    from posture_id.learning.universal_model import UniversalModel
    from posture_id.learning.universal_training import UniversalTrainingConfig, train_universal

    base = UniversalModel.load(BUNDLED_DIR)
    config = UniversalTrainingConfig(epochs=1, batch_size=64, threads=1, init=str(BUNDLED_DIR),
                                     max_learning_rate=1e-4, exclude_families=("shallow",))
    tuned = train_universal(family_set.path, tmp_path / "tuned", config)
    again = UniversalModel.load(tmp_path / "tuned")
    np.testing.assert_array_equal(again.input_mean, base.input_mean)
    np.testing.assert_array_equal(again.target_std, base.target_std)
    assert again.network.config == base.network.config
    assert again.sidecar["fine_tuned_from"]["weights_sha256"] == base.sidecar["weights_sha256"]
    assert again.scope.noise_families == FAMILIES
    low = np.array(again.sidecar["ranges"]["descriptors_low"])
    assert np.all(low <= np.array(base.sidecar["ranges"]["descriptors_low"]))
    assert again.sidecar["training"]["exclude_families"] == ["shallow"]
    assert tuned.path == tmp_path / "tuned"


def test_the_command_line_refuses_network_flags_with_init_and_families_a_set_lacks(
        family_set, tmp_path, capsys):
    from posture_id.cli import main
    from posture_id.learning.universal_identifier import BUNDLED_DIR

    status = main(["network", "universal", "train", str(family_set.path), "--out",
                  str(tmp_path / "m"),
                   "--init", str(BUNDLED_DIR), "--hidden", "64", "64"])
    assert status == 2
    assert "--init keeps its model's network" in capsys.readouterr().err
    status = main(["network", "universal", "train", str(family_set.path), "--out",
                  str(tmp_path / "n"),
                   "--exclude-families", "correlated", "--epochs", "1"])
    assert status == 2
    err = capsys.readouterr().err
    assert "no trial of these sets is of the noise families correlated" in err
    assert "low_pass, shallow, drifting" in err
    assert not (tmp_path / "n").exists()  # nothing left behind


def test_a_set_too_small_for_a_split_is_refused_in_one_line(tmp_path, capsys):
    from posture_id.cli import main
    from posture_id.learning.data.drawn import UniversalDataConfig, generate_universal

    small = generate_universal(UniversalDataConfig(shards=2, trials=3, seed=1),
                               tmp_path / "small", workers=1)
    out = tmp_path / "model"
    assert main(["network", "universal", "train", str(small.path), "--out", str(out), "--epochs",
                "1",
                 "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "no train trial: the train split takes the shards whose index is ≥ 3" in err
    assert "holds 2" in err and not out.exists()
