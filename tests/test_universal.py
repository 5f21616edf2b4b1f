"""The universal identifier's pieces against known answers: the noise added to stored
harmonics against noise added to the sway, the band FRFs against a known system, the
body descriptors against Pinocchio, the draws, the shards, training and resumption."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from posture_id.errors import LearningError
from posture_id.learning.data.scope import (
    BodyDraw,
    UniversalScope,
    draw_body,
    draw_stimulus,
)
from posture_id.learning.features.harmonics import (
    drift_parts,
    harmonic_layout,
    sensor_noise_parts,
    sway_harmonics,
)
from posture_id.learning.features.module_frfs import (
    CHANNELS,
    GRID_HZ,
    band_weights,
    body_descriptors,
    module_features,
)


def _layout(states=80, state_s=0.25, cycles=4, amp=1.0):
    from posture_id.simulation.stimulus import prts

    profile = prts(amp, cycles, states, state_s)
    t = np.arange(int(round(profile.duration * 50)) + 1) / 50
    return harmonic_layout(profile.angle(t), 50.0, profile.period_s), t


def test_sensor_noise_on_harmonics_matches_noise_on_the_sway():
    layout, t = _layout(cycles=3)
    rng = np.random.default_rng(1)
    sd = 0.002
    noise = sd * rng.standard_normal((len(t), 400))
    y = sway_harmonics(layout, noise)  # (K, 400)
    measured = np.sqrt(np.mean(y.real[5:] ** 2))  # skip the lowest, touched by detrending
    predicted = sensor_noise_parts(layout.period_samples, layout.cycles, sd)
    assert measured == pytest.approx(predicted, rel=0.03)
    assert np.sqrt(np.mean(y.imag[5:] ** 2)) == pytest.approx(predicted, rel=0.03)


def test_noise_colour_is_flat_for_white_noise_and_follows_a_known_spectrum():
    """White sensor noise on the sway reads 0; harmonics whose noise SD falls as 1/f (power
    ∝ 1/f², a random walk's) read the log ratio of the noise power expected below 0.3 Hz
    to that above 0.8 Hz at the excited harmonics (each estimated, as the features do,
    from the empty harmonics nearest it)."""
    from posture_id.frf.locked import noise_levels
    from posture_id.learning.features.module_frfs import (
        COLOUR_HIGH_HZ,
        COLOUR_LOW_HZ,
        _rows,
        noise_colour,
    )

    layout, t = _layout(cycles=4)
    rng = np.random.default_rng(3)
    k = len(layout.frequencies_hz)
    white = sway_harmonics(layout, 0.002 * rng.standard_normal((len(t), 400)))
    assert abs(np.median(noise_colour(layout, white.reshape(k, 200, 2)))) < 0.05
    sd = 1e-3 / layout.frequencies_hz  # (K,)
    red = sd[:, None, None] * (rng.standard_normal((k, 200, 2))
                               + 1j * rng.standard_normal((k, 200, 2)))
    rows = _rows(layout)
    f = layout.frequencies_hz[rows]
    # the estimator is linear in power: its expectation is the neighbours' mean of E|Y|²
    level = noise_levels((2 * sd**2)[:, None], layout.excited, rows, 3)[:, 0]
    power = 2 * level**2 * 2  # two segments
    expected = np.log10(power[f < COLOUR_LOW_HZ].mean() / power[f > COLOUR_HIGH_HZ].mean())
    assert expected > 1.0
    assert np.median(noise_colour(layout, red)) == pytest.approx(expected, abs=0.15)


def test_drift_on_harmonics_matches_a_random_walk_of_the_sway():
    layout, t = _layout(cycles=4)
    rng = np.random.default_rng(2)
    drift_deg = 0.4
    q = math.radians(drift_deg) ** 2 / 60.0  # rad²/s
    walk = np.cumsum(math.sqrt(q / 50.0) * rng.standard_normal((len(t), 600)), axis=0)
    y = sway_harmonics(layout, walk)
    predicted = drift_parts(layout.frequencies_hz, layout.record_s, np.array([drift_deg]))[0]
    rows = slice(3, 40)  # above the detrending's reach, below the sampling's
    ratio = np.sqrt(np.mean(np.abs(y[rows]) ** 2, axis=1) / 2) / predicted[rows]
    assert np.median(ratio) == pytest.approx(1.0, abs=0.15)


def test_band_frf_of_a_known_system_is_its_tilt_weighted_mean():
    layout, _ = _layout(states=242, state_s=0.2, cycles=2)
    f = layout.frequencies_hz
    h_true = 1.0 / (1.0 + 1j * f / 0.5)  # a first-order low-pass
    y = (h_true * layout.tilt)[:, None, None]
    feats = module_features(layout, y)  # (1, 1, C, G)
    w, count = band_weights(layout)
    rows = np.flatnonzero(layout.excited & (f <= 2.5))
    expected = w @ (h_true[rows] * layout.tilt[rows])
    assert np.allclose(feats[0, 0, 3] + 1j * feats[0, 0, 4], expected, atol=1e-6)
    # where a band holds harmonics, the estimate is the low-pass at about its centre
    full = count > 0
    assert np.allclose(expected[full], 1.0 / (1.0 + 1j * GRID_HZ[full] / 0.5), atol=0.08)
    # a constant FRF comes back exactly in every band, measured or interpolated
    const = ((0.5 - 0.2j) * layout.tilt)[:, None, None]
    feats = module_features(layout, const)
    assert np.allclose(feats[0, 0, 3], 0.5, atol=1e-6)
    assert np.allclose(feats[0, 0, 4], -0.2, atol=1e-6)


def test_module_channels_hold_the_platform_below_and_nothing_above(winter2):
    layout, t = _layout()
    y = (np.array([0.8, 1.2])[None, None, :] * layout.tilt[:, None, None]).astype(complex)
    feats = module_features(layout, y)  # (1, 2, C, G)
    assert feats.shape == (1, 2, CHANNELS, len(GRID_HZ))
    assert np.allclose(feats[0, 0, 0], 1.0) and np.allclose(feats[0, 0, 1], 0.0)
    assert np.allclose(feats[0, 0, 3], 0.8, atol=1e-6)
    assert np.allclose(feats[0, 0, 6], 1.2, atol=1e-6)  # the segment above the ankle
    assert np.allclose(feats[0, 1, 0], 0.8, atol=1e-6)  # below the hip: the leg
    assert np.allclose(feats[0, 1, 6:8], 0.0)  # nothing above the top segment


@pytest.mark.parametrize("body_name", ["tip", "winter", "winter2", "winter1"])
def test_time_scale_descriptor_is_pinocchios_inertia_about_the_joint(body_name, request):
    import pinocchio as pin

    body = request.getfixturevalue(body_name)
    data = body.model.createData()
    joint_inertia = pin.crba(body.model, data, pin.neutral(body.model))
    desc = body_descriptors(body)
    for i in range(body.n_segments):
        assert 10 ** desc[i, 6] == pytest.approx(
            math.sqrt(joint_inertia[i, i] / body.mgh[i]), rel=1e-9)
    assert np.allclose(desc[:, 3 + body.n_segments - 1], 1.0)


def test_draws_stay_in_the_scope_and_cycles_fit_the_sample_grid():
    scope = UniversalScope()
    rng = np.random.default_rng(3)
    kinds = set()
    for _ in range(300):
        body = draw_body(scope, rng)
        kinds.add(body.kind)
        if body.kind == "winter":
            assert scope.heights_m[0] <= body.height_m <= scope.heights_m[1]
            assert len(body.factors) == body.segments
        stim = draw_stimulus(scope, rng)
        period_samples = stim.states * stim.state_s * 50
        assert period_samples == pytest.approx(round(period_samples), abs=1e-9)
        assert 0.2 - 0.01 <= stim.state_s <= 0.3 + 0.01
        assert 0.5 - 1e-9 <= stim.amplitude_deg <= 4.0 + 1e-4
        assert stim.cycles >= 1
        assert stim.duration_s <= 250 or stim.cycles == 1
    assert kinds == {"winter", "tip", "talos", "g1", "human"}
    # a set of small tilts draws within its own range, log-uniform (a third below 0.5°)
    small = UniversalScope(amplitude_deg=(0.35, 1.0))
    amps = np.array([draw_stimulus(small, rng).amplitude_deg for _ in range(600)])
    assert amps.min() >= 0.35 - 1e-4 and amps.max() <= 1.0 + 1e-4
    expected = math.log(0.5 / 0.35) / math.log(1.0 / 0.35)
    assert abs(np.mean(amps < 0.5) - expected) < 0.06


def test_a_jittered_robot_is_the_lumped_robot_with_each_segment_scaled():
    """Loaded by Pinocchio, a jittered preset's segment i has mass a_i·m_i, COM b_i·c_i,
    inertia a_i·b_i²·I_i, and its joint b_(i-1) further up the segment below; the scope
    draws the factors within 1 ± preset_jitter, and none without it."""
    from posture_id.learning.data.bodies import build_body

    factors = ((1.2, 0.9), (0.85, 1.1), (1.05, 1.15))
    lumped, jittered = build_body(BodyDraw("talos", 3)), build_body(
        BodyDraw("talos", 3, factors=factors))
    below = 1.0
    for seg, new, (a, b) in zip(lumped.segments, jittered.segments, factors, strict=True):
        assert new.mass == pytest.approx(a * seg.mass, rel=1e-9)
        assert np.allclose(new.com, np.multiply(seg.com, b), atol=1e-12)
        assert new.inertia == pytest.approx(a * b**2 * seg.inertia, rel=1e-9)
        assert np.allclose(new.joint_origin, np.multiply(seg.joint_origin, below), atol=1e-12)
        below = b
    rng = np.random.default_rng(4)
    robots = UniversalScope(tip_share=0.0, preset_share=1.0, preset_jitter=0.2)
    draws = [draw_body(robots, rng) for _ in range(50)]
    assert all(len(d.factors) == d.segments for d in draws)
    spread = np.concatenate([np.ravel(d.factors) for d in draws])
    assert spread.min() >= 0.8 and spread.max() <= 1.2 and spread.std() > 0.08
    plain = UniversalScope(tip_share=0.0, preset_share=1.0)
    assert all(draw_body(plain, rng).factors == () for _ in range(20))


@pytest.fixture(scope="module")
def tiny_set(tmp_path_factory):
    """A 20-shard set of 6 trials each: enough for every split."""
    from posture_id.learning.data.drawn import UniversalDataConfig, generate_universal

    out = tmp_path_factory.mktemp("universal") / "set"
    return generate_universal(UniversalDataConfig(shards=20, trials=6, seed=5), out, workers=2)


@pytest.mark.slow("generates a training set")
def test_shards_are_reproducible_and_a_killed_run_resumes(tiny_set, tmp_path):
    from posture_id.learning.data.drawn import (
        UniversalDataConfig,
        UniversalSet,
        generate_universal,
        make_shard,
    )
    from posture_id.learning.data.trial_config import DatasetError

    config = UniversalDataConfig(shards=20, trials=6, seed=5)
    entry = tiny_set.shards()[3]
    again = make_shard(config, 3)
    stored = tiny_set.load(entry)
    for key, value in again.items():
        assert np.array_equal(value, stored[key]), key
    kept = stored["locked_share"][stored["motor_noise_deg"] > 0]
    assert np.all((kept > 0.03) & (kept < 1.2))
    assert {e["split"] for e in tiny_set.shards()} == {"train", "validation", "calibration",
                                                       "test"}
    # a run killed after 2 shards finishes with the same bytes, also when its manifest was
    # written before a scope field with a neutral default existed (preset_jitter)
    partial = tmp_path / "set"
    generate_universal(UniversalDataConfig(shards=2, trials=6, seed=5), partial, workers=1)
    manifest_file = partial / "manifest.json"
    manifest = json.loads(manifest_file.read_text())
    del manifest["config"]["scope"]["preset_jitter"]
    manifest_file.write_text(json.dumps(manifest))
    finished = generate_universal(config, partial, workers=2)
    assert [e["sha256"] for e in finished.shards()] == [e["sha256"] for e in tiny_set.shards()]
    with pytest.raises(DatasetError, match="other arguments"):
        generate_universal(UniversalDataConfig(shards=20, trials=7, seed=5), partial)
    assert UniversalSet.open(partial).manifest["complete"]


@pytest.mark.slow("trains a network")
def test_training_resumes_exactly_and_the_model_round_trips(tiny_set, tmp_path):
    import torch

    from posture_id.learning.universal_model import ModelError, UniversalModel
    from posture_id.learning.universal_network import UniversalNetworkConfig
    from posture_id.learning.universal_training import UniversalTrainingConfig, train_universal

    config = UniversalTrainingConfig(epochs=3, batch_size=64, threads=1, patience=10)
    net = UniversalNetworkConfig(hidden=(32, 32))
    threads = torch.get_num_threads()
    whole = train_universal(tiny_set.path, tmp_path / "whole", config, net)
    assert torch.get_num_threads() == threads  # the training's one thread, not the process's

    class Stop(Exception):
        pass

    def stop_after_first(update):
        if update.message.startswith("epoch 1/"):
            raise Stop

    with pytest.raises(Stop):
        train_universal(tiny_set.path, tmp_path / "resumed", config, net, progress=stop_after_first)
    resumed = train_universal(tiny_set.path, tmp_path / "resumed", config, net)
    for key, value in whole.network.state_dict().items():
        assert torch.equal(value, resumed.network.state_dict()[key]), key
    # the state every trainer keeps, and a finished run asked again: its model, no epoch
    state = json.loads((tmp_path / "resumed" / "training" / "state.json").read_text())
    assert len(state["history"]) == 3 and state["weights"] == "training/epoch-0003.safetensors"
    said: list[str] = []
    again = train_universal(tiny_set.path, tmp_path / "resumed", config, net,
                            progress=lambda update: said.append(update.message))
    assert not [m for m in said if m.startswith("epoch ")]
    assert all(torch.equal(v, again.network.state_dict()[k])
               for k, v in whole.network.state_dict().items())
    # an interrupted run on other data (here: its set had another shard count) is refused,
    # naming what differs, and nothing of it is overwritten
    with pytest.raises(Stop):
        train_universal(tiny_set.path, tmp_path / "other", config, net, progress=stop_after_first)
    state_file = tmp_path / "other" / "training" / "state.json"
    state = json.loads(state_file.read_text())
    state["identity"]["sets"][0]["shards"] += 1
    state_file.write_text(json.dumps(state))
    with pytest.raises(LearningError, match=r"other: was trained with other arguments \(sets "):
        train_universal(tiny_set.path, tmp_path / "other", config, net)
    assert json.loads(state_file.read_text()) == state
    loaded = UniversalModel.load(tmp_path / "whole")
    x = np.random.default_rng(0).standard_normal((5, whole.input_mean.size)).astype(np.float32)
    assert np.allclose(loaded.predict(x).mean, whole.predict(x).mean)
    (tmp_path / "whole" / "model.safetensors").write_bytes(b"not weights")
    with pytest.raises(ModelError, match="SHA-256"):
        UniversalModel.load(tmp_path / "whole")


@pytest.mark.slow("trains a network")
def test_keep_clean_holds_the_clean_outputs_of_the_model_fine_tuned_from(tiny_set, tmp_path):
    """A fine-tune at a high learning rate moves every output; with ``keep_clean`` the
    outputs on clean trials (no motor noise) stay nearer the starting model's, by half or
    more, than without it, while those on noisy trials move about as much; without
    ``init`` it is refused. The gap reads the class as a probability: two saturated logits
    agree."""
    import torch

    from posture_id.learning.data.drawn import merged_scope, open_sets
    from posture_id.learning.universal_network import UniversalNetworkConfig
    from posture_id.learning.universal_samples import load_split, make_samples
    from posture_id.learning.universal_training import (
        CLEAN_LOCKED_SHARE,
        UniversalTrainingConfig,
        _gap,
        train_universal,
    )

    quiet = {"progress": None}
    net = UniversalNetworkConfig(hidden=(32, 32), dropout=0.0)
    start = train_universal(tiny_set.path, tmp_path / "start", UniversalTrainingConfig(
        epochs=2, batch_size=64, threads=1), net, **quiet)
    tuned = {}
    for weight in (0.0, 300.0):
        config = UniversalTrainingConfig(epochs=3, batch_size=64, threads=1, seed=1,
                                         max_learning_rate=5e-3, keep_clean=weight,
                                         init=str(tmp_path / "start"))
        tuned[weight] = train_universal(tiny_set.path, tmp_path / f"k{weight:g}", config,
                                        **quiet)
    data = open_sets(tiny_set.path)
    samples = make_samples(load_split(data, "train"), merged_scope(data),
                           np.random.default_rng(9))
    clean = samples.locked_share >= CLEAN_LOCKED_SHARE
    assert 0 < clean.sum() < len(clean)

    def moved(model, rows):
        x = start.standardise(samples.inputs[rows])
        with torch.no_grad():
            return float(_gap(model.network.eval()(x), start.network.eval()(x).mean(0)))

    assert moved(tuned[300.0], clean) < 0.5 * moved(tuned[0.0], clean)
    assert moved(tuned[300.0], ~clean) > 0.5 * moved(tuned[0.0], ~clean)
    with pytest.raises(LearningError, match="needs init"):
        UniversalTrainingConfig(keep_clean=1.0)
    logits = torch.zeros(1, 2, 9)
    logits[..., 8] = 12.0
    teacher = torch.zeros(2, 9)
    teacher[:, 8] = 9.0
    assert float(_gap(logits, teacher)) < 1e-7


def test_sets_trained_together_agree_but_on_motor_noise_body_mix_and_tilt_range(tmp_path):
    from dataclasses import replace

    from posture_id.learning.data.drawn import UniversalSet, merged_scope
    from posture_id.learning.data.scope import ScopeError, UniversalScope
    from posture_id.learning.data.trial_config import DatasetError

    def a_set(name, scope):
        return UniversalSet(tmp_path / name, {"config": {"scope": scope.to_dict()}})

    base = UniversalScope()
    people = replace(base, clean_share=0.0, locked_share=(0.05, 0.4))
    merged = merged_scope([a_set("a", base), a_set("b", people)])
    assert merged.locked_share == (0.05, 1.0) and merged.clean_share == base.clean_share
    assert merged.sensor_noise_deg == base.sensor_noise_deg
    with pytest.raises(DatasetError, match=r"b: scope field sensor_noise_deg"):
        merged_scope([a_set("a", base), a_set("b", replace(base, sensor_noise_deg=(0, 0.3)))])
    # a set of more varied bodies joins; the proportions span the wider jitter
    varied = replace(base, proportion_jitter=0.35, tip_share=0.05, preset_share=0.3,
                     preset_jitter=0.15)
    merged = merged_scope([a_set("a", base), a_set("c", varied)])
    assert merged.proportion_jitter == 0.35 and merged.preset_share == base.preset_share
    assert merged.preset_jitter == 0.15
    # a set of small tilts, with a margin below the range, joins; recordings are checked
    # against the first set's range
    small = replace(base, amplitude_deg=(0.35, 1.0))
    assert merged_scope([a_set("a", base), a_set("s", small)]).amplitude_deg == (0.5, 4.0)
    assert merged_scope([a_set("s", small), a_set("a", base)]).amplitude_deg == (0.35, 1.0)
    with pytest.raises(DatasetError, match=r"w: scope field amplitude_deg .* must overlap"):
        merged_scope([a_set("a", base), a_set("w", replace(base, amplitude_deg=(0.1, 0.4)))])
    with pytest.raises(ScopeError, match="proportion_jitter must be within"):
        replace(base, proportion_jitter=1.0)
    with pytest.raises(ScopeError, match="tip_share and preset_share"):
        replace(base, tip_share=-0.1)


@pytest.mark.slow("generates a training set and trains a network")
def test_training_on_two_sets_reads_both(tiny_set, tmp_path):
    from posture_id.learning.data.drawn import UniversalDataConfig, generate_universal
    from posture_id.learning.data.scope import UniversalScope
    from posture_id.learning.universal_network import UniversalNetworkConfig
    from posture_id.learning.universal_samples import SET_STRIDE, load_split
    from posture_id.learning.universal_training import UniversalTrainingConfig, train_universal

    people = generate_universal(UniversalDataConfig(
        shards=10, trials=4, seed=6, scope=UniversalScope(clean_share=0.0,
                                                          locked_share=(0.1, 0.4))),
        tmp_path / "people", workers=2)
    shards = load_split([tiny_set, people], "train")
    labels = {int(s.arrays["index"]) for s in shards}
    assert labels == ({e["index"] for e in tiny_set.shards("train") if e["kept"]}
                      | {SET_STRIDE + e["index"] for e in people.shards("train") if e["kept"]})
    for shard in shards:
        if shard.arrays["index"] >= SET_STRIDE:
            assert np.all(shard.arrays["motor_noise_deg"] > 0)
    model = train_universal([tiny_set.path, people.path], tmp_path / "model",
                            UniversalTrainingConfig(epochs=1, batch_size=64, threads=1),
                            UniversalNetworkConfig(hidden=(16,)))
    assert [d["path"] for d in model.sidecar["datasets"]] == [
        str(tiny_set.path.resolve()), str(people.path.resolve())]
    assert model.scope.locked_share == (0.1, 1.0)
    assert model.sidecar["training"]["train_samples"] == sum(
        s.arrays["y"].shape[0] * s.n_segments for s in shards)


@pytest.mark.parametrize("body_name", ["tip", "winter", "winter2"])
def test_com_weights_linearise_the_com_above_each_joint(body_name, request):
    from posture_id.learning.features.module_frfs import com_weights

    body = request.getfixturevalue(body_name)
    w = com_weights(body)
    theta = 1e-5 * np.random.default_rng(4).standard_normal(body.n_segments)
    exact = body.com_angles(theta) - body.com_angles(np.zeros(body.n_segments))
    assert np.allclose(w @ theta, exact, rtol=1e-4, atol=1e-12)
    assert np.allclose(w.sum(axis=1), 1.0)  # a rigid lean of the whole body moves every COM


def test_identify_by_default_reads_a_body_and_prts_no_network_was_trained_on(tmp_path):
    """The command line alone, as a lab would run it: a 1-segment Winter body, an 80-state
    PRTS of 0.22 s states at 2° peak to peak, three cycles, sensor noise."""
    import json

    from posture_id.cli import main

    urdf, rec, out = tmp_path / "b.urdf", tmp_path / "rec.csv", tmp_path / "r.json"
    assert main(["body", "--height-m", "1.68", "--mass-kg", "61", "--segments", "1",
                 "--out", str(urdf)]) == 0
    assert main(["simulate", "--body", str(urdf), "--states", "80", "--state-s", "0.22",
                 "--amplitude-deg", "2", "--cycles", "3", "--sensor-noise-deg", "0.02",
                 "--seed", "3", "--out", str(rec)]) == 0
    assert main(["identify", str(rec), "--body", str(urdf), "--out", str(out)]) == 0
    result = json.loads(out.read_text())
    assert result["cnn"]["model"]["layout"] == "universal"
    (joint, estimate), = result["normalised"].items()
    # the subject has the body's default parameters: normalised 0, the ankle's class
    from posture_id import load_body
    from posture_id.dec.parameters import default_parameters

    truth = default_parameters(load_body(urdf))[joint]
    assert abs(estimate["kp"]) < 0.1
    assert estimate["class"] == truth.sign
    assert result["intervals"] is not None
    assert result["trust"]["doubtful"] in (True, False)


def test_conformal_quantiles_and_temperature_recover_known_answers():
    from posture_id.learning.calibration import (
        LEVELS,
        _conformal,
        _temperature,
        regime_of,
        regime_text,
    )

    rng = np.random.default_rng(6)
    scores = np.abs(rng.standard_normal((40000, 4)))
    table = np.asarray(_conformal(scores))
    row = LEVELS.index(0.9)
    assert np.allclose(table[row], 1.6449, atol=0.03)  # the 90 % point of |N(0, 1)|
    # logits twice as confident as the truth: temperature 2
    true_logit = rng.normal(0, 2, 50000)
    truth = np.where(rng.random(50000) < 1 / (1 + np.exp(-true_logit)), 1.0, -1.0)
    assert _temperature(2 * true_logit, truth) == pytest.approx(2.0, rel=0.05)
    keys = list(regime_of(np.array([1, 3, 2, 3]), np.array([0.0005, 0.5, 0.015, 0.05]),
                          np.array([0.1, 1.5, 0.79, 0.81])))
    assert keys == ["1:0w", "3:6c", "2:3w", "3:4c"]
    assert [regime_text(k) for k in keys] == [
        "1 segment, clean, white noise", "3 segments, mostly noise, noise shaped by the body",
        "2 segments, clean, white noise", "3 segments, a little noisy, noise shaped by the body"]
    from posture_id.learning.calibration import Regime

    assert [Regime.parse(k).key for k in (*keys, "2:3", "3")] == [*keys, "2:3", "3"]
    assert [r.key for r in Regime.parse("3:4c").broader()] == ["3:4c", "3:4", "3"]


def test_a_body_the_calibration_had_none_of_gets_the_pooled_values_or_a_clear_error():
    """Calibrated on 2- and 3-segment bodies only, a 1-segment body's intervals use the
    values pooled over every sample (no KeyError); a calibration without them says what
    is missing."""
    from posture_id.learning.calibration import POOLED, UniversalCalibration
    from posture_id.learning.universal_model import ModelError

    row = [[1.0, 2.0, 3.0, 4.0]] * 99
    cal = UniversalCalibration({"2": row, "3:4": [[5.0] * 4] * 99, "3:4c": [[6.0] * 4] * 99,
                                POOLED: [[7.0] * 4] * 99},
                               {"2": 1.0, POOLED: 2.0}, {"2": 300, "3:4": 200, POOLED: 500},
                               "x")
    assert cal.scale("3:4c", 0.9).tolist() == [6.0] * 4  # its own regime
    assert cal.scale("3:4w", 0.9).tolist() == [5.0] * 4  # its noise bin over both colours
    assert cal.scale("2:5w", 0.9).tolist() == [1.0, 2.0, 3.0, 4.0]  # its segment count's
    assert cal.scale("1:3c", 0.9).tolist() == [7.0] * 4  # pooled
    assert cal.probability("1:3w", np.array([2.0])) == pytest.approx(1 / (1 + np.exp(-1.0)))
    old = UniversalCalibration({"2": row}, {"2": 1.0}, {"2": 300}, "x")
    with pytest.raises(ModelError, match="no values for 1 segment, clean, white noise nor"):
        old.scale("1:0w", 0.9)


def test_a_calibration_made_before_the_noise_colour_is_refused_with_the_fix(tmp_path):
    from posture_id.learning.calibration import POOLED, UniversalCalibration
    from posture_id.learning.universal_model import ModelError

    cal = UniversalCalibration({POOLED: [[1.0] * 4] * 99}, {POOLED: 1.0}, {POOLED: 500}, "x")
    cal.save(tmp_path)
    assert UniversalCalibration.load(tmp_path).counts == {POOLED: 500}
    saved = json.loads((tmp_path / "calibration.json").read_text())
    # before the colour; before the trend; before its noise-ratio floor
    for before in ("colour_edge", "trend_terms", "trend_ratio_floor"):
        data = dict(saved)
        del data[before]
        (tmp_path / "calibration.json").write_text(json.dumps(data))
        with pytest.raises(ModelError, match="calibration.json: made for other levels or "
                                             "regimes.*posture-id network universal calibrate"):
            UniversalCalibration.load(tmp_path)


class _ScaledErrorsModel:
    """A stand-in network, SD 1, whose errors are z · 10**(slope · log10 p-p) with z kept
    in the first four inputs: too confident on large tilts, too cautious on small ones."""

    sidecar = {"weights_sha256": "stand-in"}

    def __init__(self, slope: float):
        self.slope = slope

    def predict(self, inputs, noise_ratio=None, noise_colour=None):
        from posture_id.learning.universal_model import UniversalPrediction
        from posture_id.learning.universal_samples import STIMULUS_COLUMNS

        log_pp = inputs[:, STIMULUS_COLUMNS][:, 0].astype(float)
        errors = inputs[:, :4].astype(float) * 10 ** (self.slope * log_pp)[:, None]
        return UniversalPrediction(errors, np.ones_like(errors), np.full(len(inputs), 3.0))


def _stimulus_samples(rng, m: int):
    """M clean module samples of every segment count over 0.5–4° tilts (equal p-p and
    velocity descriptors), true values 0, z ~ N(0, 1) in the first four inputs."""
    from posture_id.learning.features.module_frfs import N_INPUTS
    from posture_id.learning.universal_samples import STIMULUS_COLUMNS, Samples

    log_pp = rng.uniform(np.log10(0.5), np.log10(4.0), m)
    inputs = np.zeros((m, N_INPUTS), dtype=np.float32)
    inputs[:, :4] = rng.standard_normal((m, 4))
    inputs[:, STIMULUS_COLUMNS] = np.column_stack([log_pp, log_pp, np.full(m, 1.5),
                                                    np.full(m, np.log10(2))])
    targets = np.zeros((m, 5))
    targets[:, 4] = 1.0
    zeros = np.zeros(m)
    return Samples(inputs, targets, np.arange(m), np.zeros(m, int), rng.integers(1, 4, m),
                   np.full(m, 0.005), zeros, np.ones(m), zeros, zeros, zeros.astype(int))


def test_the_difficulty_trend_evens_the_coverage_over_stimuli():
    """A network too confident on large tilts: one conformal quantile covers the small
    tilts more than 90 % and the large ones less; the difficulty trend, fitted on other
    samples, finds the slope, and the calibration covers every third of the tilts 90 %
    on a third set."""
    from posture_id.learning.calibration import (
        POOLED,
        TREND_TERMS,
        UniversalCalibration,
        _conformal,
        calibrate,
    )
    from posture_id.learning.evaluation import score_samples

    rng = np.random.default_rng(11)
    model = _ScaledErrorsModel(slope=0.5)
    trend_set, cal_set, test_set = (_stimulus_samples(rng, m) for m in (20000, 20000, 30000))
    cal = calibrate(model, cal_set, trend_set)
    beta = np.asarray(cal.trend)
    assert beta.shape == (len(TREND_TERMS), 4)
    # d = 10**(0.5 · log10 p-p) = exp(0.5 · ln 10 · log10 p-p); p-p and velocity are one
    # column here, so their coefficients share the slope
    pp = TREND_TERMS.index("log10 p-p deg")
    assert np.allclose(beta[pp] + beta[pp + 1], 0.5 * np.log(10), rtol=0.05)
    log_pp = test_set.inputs[:, -4]
    groups = np.array(["small", "middle", "large"])[
        np.digitize(log_pp, np.quantile(log_pp, [1 / 3, 2 / 3]))]
    scores = np.abs(model.predict(cal_set.inputs).mean)
    flat = UniversalCalibration({POOLED: _conformal(scores)}, {POOLED: 1.0},
                                {POOLED: len(scores)}, "stand-in")
    assert flat.difficulty(np.zeros((2, len(TREND_TERMS)))).tolist() == [[1.0] * 4] * 2
    untrended = score_samples(model, test_set, flat, 0.9, groups)
    assert untrended["small"].coverage_pct["kp"] > 95
    assert untrended["large"].coverage_pct["kp"] < 85
    trended = score_samples(model, test_set, cal, 0.9, groups)
    for group in ("small", "middle", "large"):
        for name, value in trended[group].coverage_pct.items():
            assert 88.5 <= value <= 91.5, (group, name, value)


def test_the_trend_terms_of_one_recording_are_its_modules_rows():
    from posture_id.learning.calibration import TREND_TERMS, trend_terms
    from posture_id.learning.features.module_frfs import N_INPUTS

    inputs = np.random.default_rng(2).normal(size=(3, N_INPUTS))
    one = trend_terms(3, 0.01, 1.0, inputs)
    rows = trend_terms(np.full(3, 3), np.full(3, 0.01), np.full(3, 1.0), inputs)
    assert one.shape == (3, len(TREND_TERMS))
    assert np.array_equal(one, rows)
    assert one[0, :7].tolist() == [0, 0, 1, 0, 0, -2, 1]  # 3 segments, log10 0.01, coloured
    assert np.array_equal(one[:, 7:], inputs[:, -4:])


def test_a_recording_outside_the_training_scope_is_identified_with_a_notice(tmp_path):
    import json

    from posture_id.cli import main

    rec, out = tmp_path / "rec.csv", tmp_path / "r.json"
    assert main(["simulate", "--amplitude-deg", "0.3", "--sensor-noise-deg", "0.01", "--seed", "4",
                 "--out", str(rec)]) == 0
    # the network alone: the default (auto) refines a doubtful answer by least squares
    assert main(["identify", str(rec), "--method", "cnn", "--out", str(out)]) == 1  # doubtful
    result = json.loads(out.read_text())
    outside = result["cnn"]["outside"]
    assert any("stimulus: peak-to-peak tilt 0.3° outside the 0.5–4°" in o for o in outside), outside
    assert not any("body" in o for o in outside)  # the TIP itself is inside
    assert result["trust"]["doubtful"]


@pytest.mark.slow("simulates TALOS until enough trials stay up")
def test_a_table_cell_draws_until_enough_trials_stay_up():
    """TALOS falls under many prior draws: its cells draw more batches until they hold
    the trials asked for; every per-trial array is cut alike. It is one body."""
    from posture_id.studies.universal_table import _cell, _cells

    cells = list(_cells())
    index = next(i for i, (family, stim, sway) in enumerate(cells)
                 if family.startswith("TALOS") and stim == (80, 6, 1.0) and sway == "clean")
    (arrays,) = _cell(index, 4, UniversalScope().to_dict())
    assert int(arrays["kept"]) == 4 == len(arrays["y"]) == len(arrays["targets"])
    assert len(arrays["kp"]) == len(arrays["locked_share"]) == 4
    assert int(arrays["simulated"]) >= 4 and np.all(arrays["motor_noise_deg"] == 0)


def test_a_table_cell_with_a_body_whose_trials_all_fell_scores_the_others():
    """With few trials a Winter cell gives each body one: a body whose one trial fell adds
    nothing to the cell (it stopped `universal table --trials 64` with a reshape error)."""
    from posture_id.studies.universal_table import _PER_TRIAL, _cell, _cells, cell_samples

    cells = list(_cells())
    index = next(i for i, (family, stim, sway) in enumerate(cells)
                 if family == "Winter 3-seg" and stim == (80, 6, 3.0) and sway == "clean")
    scope = UniversalScope()
    groups = _cell(index, 3, scope.to_dict(), bodies_per_cell=3)
    whole = cell_samples(index, [dict(g) for g in groups], scope, bodies_per_cell=3)
    fallen = dict(groups[1])
    fallen.update({key: fallen[key][:0] for key in _PER_TRIAL}, kept=np.array(0))
    rest = cell_samples(index, [dict(groups[0]), fallen, dict(groups[2])], scope,
                        bodies_per_cell=3)
    kept = [int(g["kept"]) for g in groups]
    assert len(rest.targets) == len(whole.targets) * (kept[0] + kept[2]) // sum(kept)
    assert len(rest.targets) > 0


def test_a_winter_table_cell_spreads_its_trials_over_bodies_of_the_family():
    """A Winter cell scores the family: its trials are split evenly over bodies drawn
    from the scope's heights and masses, not spent on one body."""
    import json

    from posture_id.studies.universal_table import TABLE_SEED, _cell, _cells

    cells = list(_cells())
    index = next(i for i, (family, stim, sway) in enumerate(cells)
                 if family == "Winter 1-seg" and stim == (80, 6, 3.0) and sway == "clean")
    scope = UniversalScope()
    bodies_per_cell = 8  # the default (64) is the documented table's; fewer here, as fast
    groups = _cell(index, bodies_per_cell + 3, scope.to_dict(), bodies_per_cell=bodies_per_cell)
    assert len(groups) == bodies_per_cell
    assert sorted(len(g["targets"]) for g in groups) == [1] * (bodies_per_cell - 3) + [2] * 3
    bodies = [json.loads(str(g["draw"]))["body"] for g in groups]
    heights = [b["height_m"] for b in bodies]
    assert len(set(heights)) == bodies_per_cell
    assert all(scope.heights_m[0] <= h <= scope.heights_m[1] for h in heights)
    assert all(scope.masses_kg[0] <= b["mass_kg"] <= scope.masses_kg[1] for b in bodies)
    # another seed: the same cell on other bodies (the documented table's are the default)
    again = _cell(index, bodies_per_cell + 3, scope.to_dict(), TABLE_SEED, bodies_per_cell)
    assert [json.loads(str(g["draw"]))["body"] for g in again] == bodies
    other = _cell(index, bodies_per_cell + 3, scope.to_dict(), TABLE_SEED + 1,
                  bodies_per_cell)
    assert not {b["height_m"] for b in (json.loads(str(g["draw"]))["body"]
                                        for g in other)} & set(heights)
    # fewer bodies than trials (--bodies-per-cell): the trials spread over that many
    few = _cell(index, 5, scope.to_dict(), TABLE_SEED, 3)
    assert sorted(len(g["targets"]) for g in few) == [1, 2, 2]


def test_a_cached_table_cell_is_read_back_only_when_made_the_same_way(tmp_path):
    from posture_id.studies.universal_table import (
        TableCacheError,
        _cache_key,
        _load_cell,
        _save_cell,
    )

    scope = UniversalScope()
    groups = [{"y": np.arange(6, dtype=np.complex64).reshape(2, 3, 1),
               "draw": np.array('{"body": {}}'), "kept": np.array(2)},
              {"y": np.ones((1, 3, 1), np.complex64), "draw": np.array("{}"),
               "kept": np.array(1)}]
    path = tmp_path / "cell-00.npz"
    _save_cell(path, groups, _cache_key(3, scope))
    back = _load_cell(path, _cache_key(3, scope))
    assert len(back) == 2
    for got, made in zip(back, groups, strict=True):
        assert got.keys() == made.keys()
        for key in made:
            np.testing.assert_array_equal(got[key], made[key])
    # made otherwise: refused, naming the file, what made it and what is asked
    with pytest.raises(TableCacheError, match=r"cell-00.npz: a table cell made with 3 trials "
                       r"per cell, the default seed, 64 bodies per Winter cell; this table "
                       r"asks for 4 trials per cell, the default seed, 64 bodies"):
        _load_cell(path, _cache_key(4, scope))
    with pytest.raises(TableCacheError, match="asks for 3 trials per cell, seed 1, 8 bodies"):
        _load_cell(path, _cache_key(3, scope, seed=1, bodies_per_cell=8))
    with pytest.raises(TableCacheError, match="and another scope"):
        _load_cell(path, _cache_key(3, UniversalScope(tip_share=0.2)))
    assert _load_cell(tmp_path / "cell-01.npz", _cache_key(3, scope)) is None
    path.write_bytes(path.read_bytes()[:40])  # truncated: made again, no traceback
    assert _load_cell(path, _cache_key(3, scope)) is None


@pytest.mark.slow("a table cell simulated through the command line")
def test_universal_table_command_simulates_only_the_cells_its_cache_lacks(tmp_path, capsys):
    """`posture-id universal table --cache`: cells already kept are read, the one missing
    is simulated (by the process pool) and kept; a second run reads every cell and
    writes the same table; a run asking for other trials is refused and leaves the
    folder as it was."""
    from posture_id.cli import main
    from posture_id.learning.universal_identifier import BUNDLED_DIR
    from posture_id.learning.universal_model import UniversalModel
    from posture_id.studies.universal_table import (
        _cache_key,
        _cell,
        _cell_file,
        _cells,
        _load_cell,
        _save_cell,
        table_scope,
    )

    cells = list(_cells())
    missing = next(i for i, (family, stim, sway) in enumerate(cells)
                   if family == "Winter 1-seg" and stim == (242, 2, 3.0) and sway == "clean")
    scope = table_scope(UniversalModel.load(BUNDLED_DIR).scope)
    key = _cache_key(2, scope)
    stand_in = _cell(0, 2, scope.to_dict())
    cache = tmp_path / "cells"
    cache.mkdir()
    for i in range(len(cells)):  # every other cell stands in with cell 0's trials
        if i != missing:
            _save_cell(_cell_file(cache, i), stand_in, key)
    argv = ["network", "universal", "table", "--trials", "2", "--workers", "1", "--cache",
            str(cache),
            "--quiet"]
    assert main([*argv, "--out", str(tmp_path / "a")]) == 0
    made = _load_cell(_cell_file(cache, missing), key)
    assert made is not None and len(made) == 2  # two trials: two bodies of the family
    table = json.loads((tmp_path / "a" / "table.json").read_text())
    label = "Winter 1-seg | 242×2, 3° | clean"
    assert [b["height_m"] for b in table["bodies"][label]] == [
        json.loads(str(g["draw"]))["body"]["height_m"] for g in made]
    assert len(table["cells"]) == len(cells) and table["trials_per_cell"] == 2
    assert table["bodies"]["TALOS 3-seg | 80×6, 3° | people-like"] == [  # read, not made
        json.loads(str(g["draw"]))["body"] for g in stand_in]
    assert main([*argv, "--out", str(tmp_path / "b")]) == 0
    assert (tmp_path / "a" / "table.md").read_text() == (tmp_path / "b" / "table.md").read_text()
    capsys.readouterr()
    # other trials on the same folder: refused in one line, nothing simulated or overwritten
    kept = {f.name: f.read_bytes() for f in cache.iterdir()}
    argv[argv.index("--trials") + 1] = "3"
    assert main([*argv, "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "made with 2 trials per cell" in err
    assert "Give another --cache folder" in err and not (tmp_path / "c").exists()
    assert {f.name: f.read_bytes() for f in cache.iterdir()} == kept


def test_ece_of_calibrated_and_overconfident_probabilities():
    from posture_id.uncertainty.coverage import confidence_calibration_error as _ece

    rng = np.random.default_rng(9)
    p = rng.uniform(0, 1, 200000)
    truth = rng.random(200000) < p
    assert _ece(p, truth) < 0.005  # calibrated
    sharp = np.where(p > 0.5, 0.999, 0.001)  # always sure, right 75 % of the time
    assert _ece(sharp, truth) == pytest.approx(0.249, abs=0.005)


@pytest.mark.parametrize(("states", "state_s", "amplitude", "cycles", "expected"), [
    (80, 0.2, 4.0, 3, ""),            # the scope's edges are inside it
    (242, 0.3, 0.5, 1, ""),
    (80, 0.25, 1.0, 2, ""),           # 40 s: two 80-state cycles
    (80, 0.25, 1.0, 12, ""),          # 240 s
    (80, 0.25, 4.5, 2, "peak-to-peak tilt 4.46° outside the 0.5–4°"),
    (80, 0.35, 1.0, 2, "states of 0.35 s outside the 0.2–0.3 s"),
    (80, 0.25, 1.0, 1, "1 whole cycle of 20 s analysed; the universal model was trained on 2–12"),
    (80, 0.25, 1.0, 14, "14 whole cycles of 20 s analysed"),
])
def test_the_stimulus_is_checked_against_the_scope_s_own_ranges(states, state_s, amplitude,
                                                                  cycles, expected):
    from posture_id.learning.data.scope import UniversalScope
    from posture_id.learning.features.harmonics import harmonic_layout
    from posture_id.learning.universal_identifier import stimulus_outside
    from posture_id.simulation.stimulus import prts

    stimulus = prts(amplitude, cycles, states, state_s)
    t = np.arange(round(stimulus.duration * 50) + 1) / 50
    layout = harmonic_layout(stimulus.angle(t), 50.0, stimulus.period_s)
    out = stimulus_outside(UniversalScope(), layout, stimulus.states, "rec.csv, stimulus")
    if expected:
        assert len(out) == 1 and expected in out[0], out
    else:
        assert out == []
    # a periodic tilt of unknown states: its period is checked
    out = stimulus_outside(UniversalScope(), layout, None, "rec.csv, stimulus")
    period_ok = 16 <= stimulus.period_s <= 72.6
    assert any("a cycle of" in o for o in out) == (not period_ok)


def test_an_ensemble_s_members_combine_into_their_mixture_and_round_trip(tmp_path):
    """Two members whose outputs are constants: the prediction is the mean of their means
    and logits, with the SD of their mixture; saved and loaded alike; a one-perceptron
    state dict of before (keys ``layers.*``) loads into today's network."""
    import torch

    from posture_id.learning.universal_model import UniversalModel
    from posture_id.learning.universal_network import UniversalNetwork, UniversalNetworkConfig
    from posture_id.learning.universal_training import _loss

    config = UniversalNetworkConfig(inputs=6, hidden=(4,), members=2)
    net = UniversalNetwork(config)
    outputs = torch.tensor([[0.2, -0.1, 0.0, 0.4, np.log(0.1), 0, 0, 0, 2.0],
                            [0.6, -0.1, 0.0, 0.0, np.log(0.2), 0, 0, 0, -1.0]])
    with torch.no_grad():
        for member, out in zip(net.members, outputs, strict=True):
            member[-1].weight.zero_()
            member[-1].bias.copy_(out)
    std = np.array([2.0, 1.0, 1.0, 1.0])
    model = UniversalModel(net, np.zeros(6), np.ones(6), np.zeros(4), std)
    pred = model.predict(np.ones((3, 6), np.float32))
    assert np.allclose(pred.mean[:, 0], 2.0 * 0.4) and np.allclose(pred.mean[:, 3], 0.2)
    assert np.allclose(pred.logit, 0.5)
    expected = np.sqrt(np.mean(np.square([0.1 * 2, 0.2 * 2])) + np.var([0.4, 1.2]))
    assert np.allclose(pred.sd[:, 0], expected)
    assert np.allclose(pred.sd[:, 1], 1.0)  # exp(0) × 1, members agreeing
    model.save(tmp_path / "ens")
    loaded = UniversalModel.load(tmp_path / "ens")
    assert loaded.network.config.members == 2
    assert np.allclose(loaded.predict(np.ones((3, 6), np.float32)).sd, pred.sd)
    # a one-perceptron network saved before members existed
    one = UniversalNetwork(UniversalNetworkConfig(inputs=6, hidden=(4,)))
    old = {k.replace("members.0.", "layers."): v for k, v in one.state_dict().items()}
    again = UniversalNetwork(UniversalNetworkConfig(inputs=6, hidden=(4,)))
    again.load_state_dict(UniversalNetwork.upgrade_state(old))
    x = torch.ones(2, 6)
    assert torch.equal(one.eval()(x), again.eval()(x))
    # the loss: members' own losses averaged for training, the deployed mean validated
    target = torch.tensor([[0.5, 0.0, 0.0, 0.0, 1.0]])
    same = torch.stack([outputs[0], outputs[0]])[:, None, :]
    train_two, val_two = _loss(same, target)
    train_one, val_one = _loss(same[:1], target)
    assert torch.isclose(train_two, train_one) and torch.isclose(val_two, val_one)
    _, val_mixed = _loss(outputs[:, None, :], target)
    mean = outputs[:, :4].mean(0)
    deployed = ((target[0, :4] - mean) ** 2).mean() + torch.nn.functional.softplus(
        -outputs[:, 8].mean())
    assert torch.isclose(val_mixed, deployed)
    # the absolute point loss: the members' mean estimate's mean absolute error, and in
    # training each member's own (the log-SD and class terms unchanged)
    _, val_abs = _loss(outputs[:, None, :], target, "absolute")
    assert torch.isclose(val_abs, (target[0, :4] - mean).abs().mean()
                         + torch.nn.functional.softplus(-outputs[:, 8].mean()))
    train_sq, _ = _loss(outputs[:, None, :], target, "squared")
    train_abs, _ = _loss(outputs[:, None, :], target, "absolute")
    err = target[:, :4] - outputs[:, None, :4]
    assert torch.isclose(train_sq - train_abs, (err**2).mean() - err.abs().mean())


def test_models_trained_apart_make_one_ensemble_and_mismatches_are_refused(tmp_path):
    """``ensemble_of`` (and ``posture-id universal ensemble``): the ensemble of two saved
    one-member models predicts what a two-member network of their very weights predicts
    (the mean of their means, the mixture's SD), keeps the last one's scope and names
    both; another width or another standardisation is refused by path."""
    import torch

    from posture_id.cli import main
    from posture_id.learning.universal_model import ModelError, UniversalModel, ensemble_of
    from posture_id.learning.universal_network import UniversalNetwork, UniversalNetworkConfig

    torch.manual_seed(3)
    config = UniversalNetworkConfig(inputs=6, hidden=(4,))
    std = (np.zeros(6), np.full(6, 2.0), np.zeros(4), np.array([2.0, 1.0, 1.0, 1.0]))
    models = []
    for name, families in (("a", None), ("b", ["low_pass", "shallow"])):
        sidecar = {"scope": {"segments": [1, 2, 3]}}
        if families:
            sidecar["scope"]["noise_families"] = families
        model = UniversalModel(UniversalNetwork(config).eval(), *std, sidecar)
        model.save(tmp_path / name)
        models.append(UniversalModel.load(tmp_path / name))
    assert main(["network", "universal", "ensemble", str(tmp_path / "a"), str(tmp_path / "b"),
                 "--out", str(tmp_path / "ens")]) == 0
    ens = UniversalModel.load(tmp_path / "ens")
    assert ens.network.config.members == 2
    assert ens.sidecar["scope"]["noise_families"] == ["low_pass", "shallow"]
    assert [m["path"] for m in ens.sidecar["ensemble_of"]] == [str(tmp_path / "a"),
                                                               str(tmp_path / "b")]
    x = np.random.default_rng(0).normal(size=(5, 6))
    both = UniversalNetwork(UniversalNetworkConfig(inputs=6, hidden=(4,), members=2))
    for mine, model in zip(both.members, models, strict=True):
        mine.load_state_dict(model.network.members[0].state_dict())
    direct = UniversalModel(both.eval(), *std).predict(x)
    got = ens.predict(x)
    assert np.allclose(got.mean, direct.mean) and np.allclose(got.sd, direct.sd)
    parts = [m.predict(x) for m in models]
    assert np.allclose(got.mean, (parts[0].mean + parts[1].mean) / 2)
    assert np.allclose(got.logit, (parts[0].logit + parts[1].logit) / 2)
    wider = UniversalModel(UniversalNetwork(UniversalNetworkConfig(inputs=6, hidden=(5,))),
                           *std, path=tmp_path / "wide")
    with pytest.raises(ModelError, match="wide: another architecture"):
        ensemble_of([models[0], wider])
    other = UniversalModel(UniversalNetwork(config), np.ones(6), *std[1:],
                           path=tmp_path / "other")
    with pytest.raises(ModelError, match="other: standardised otherwise.*input_mean"):
        ensemble_of([models[0], other])
    with pytest.raises(ModelError, match="two or more"):
        ensemble_of(models[:1])
    assert main(["network", "universal", "ensemble", str(tmp_path / "a"), "--out",
                 str(tmp_path / "one")]) != 0


def test_a_model_gated_by_the_noise_answers_white_noise_by_its_first_network(tmp_path):
    """``posture-id universal ensemble A B --by-noise``: a recording whose noise is white
    or nearly none gets A's answer, one whose noise is shaped by the body B's, between
    them the mixture of the two (its mean, the SD of the mixture, the logit of its
    probability); the gate is kept through save and load, a gated model refuses to
    answer without the noise, and is not itself a member of another."""
    import torch

    from posture_id.cli import main
    from posture_id.learning.noise_gate import NoiseGate
    from posture_id.learning.universal_model import ModelError, UniversalModel, ensemble_of
    from posture_id.learning.universal_network import UniversalNetwork, UniversalNetworkConfig

    torch.manual_seed(4)
    config = UniversalNetworkConfig(inputs=6, hidden=(4,))
    std = (np.zeros(6), np.full(6, 2.0), np.zeros(4), np.array([2.0, 1.0, 1.0, 1.0]))
    for name in ("white", "coloured"):
        UniversalModel(UniversalNetwork(config).eval(), *std,
                       {"scope": {"segments": [1, 2, 3]}}).save(tmp_path / name)
    assert main(["network", "universal", "ensemble", str(tmp_path / "white"),
                str(tmp_path / "coloured"),
                 "--by-noise", "--out", str(tmp_path / "gated")]) == 0
    gated = UniversalModel.load(tmp_path / "gated")
    white, coloured = (UniversalModel.load(tmp_path / n) for n in ("white", "coloured"))
    gate = gated.gate
    assert gate == NoiseGate(1)
    x = np.random.default_rng(1).normal(size=(4, 6))
    # white sensor noise; a dead band's "noise" (tiny ratio) however coloured; noise shaped
    # by the body; halfway up both ramps
    ratio = np.array([0.05, 1e-4, 0.3, np.sqrt(gate.ratio_from * gate.ratio_to)])
    colour = np.array([0.0, 2.0, 1.5, (gate.colour_from + gate.colour_to) / 2])
    w = gate.coloured_share(ratio, colour)
    assert np.allclose(w, [0.0, 0.0, 1.0, 0.25])
    got, a, b = (m.predict(x, ratio, colour) for m in (gated, white, coloured))
    for i in (0, 1):
        assert np.allclose(got.mean[i], a.mean[i]) and np.allclose(got.sd[i], a.sd[i])
        assert np.isclose(got.logit[i], a.logit[i])
    assert np.allclose(got.mean[2], b.mean[2]) and np.allclose(got.sd[2], b.sd[2])
    assert np.isclose(got.logit[2], b.logit[2])
    mean = 0.75 * a.mean[3] + 0.25 * b.mean[3]
    var = 0.75 * (a.sd[3] ** 2 + a.mean[3] ** 2) + 0.25 * (b.sd[3] ** 2 + b.mean[3] ** 2) - mean**2
    assert np.allclose(got.mean[3], mean) and np.allclose(got.sd[3], np.sqrt(var))
    p = 0.75 / (1 + np.exp(-a.logit[3])) + 0.25 / (1 + np.exp(-b.logit[3]))
    assert np.isclose(got.logit[3], np.log(p / (1 - p)))
    with pytest.raises(ModelError, match="noise ratio and colour"):
        gated.predict(x)
    with pytest.raises(ModelError, match="gated by the noise already"):
        ensemble_of([gated, white])
    sidecar = tmp_path / "gated" / "model.json"
    data = json.loads(sidecar.read_text())
    for gate, message in (({**data["gate"], "white_members": 2}, "gives 2 of 2 members"),
                          ({"white_members": 1}, "its gate cannot be read"),
                          ({**data["gate"], "colour_to": 0.0}, "its gate cannot be read")):
        sidecar.write_text(json.dumps({**data, "gate": gate}))
        with pytest.raises(ModelError, match=message):
            UniversalModel.load(tmp_path / "gated")


def test_an_ensemble_member_saved_alone_is_the_model_it_came_from(tmp_path):
    """``UniversalModel.member(i)``: the network an ensemble took from a model, saved
    alone, has that model's weights byte for byte (the SHA-256 its ``ensemble_of`` entry
    names) and answers as it did; a model of one network, or a member it lacks, is
    refused."""
    import torch

    from posture_id.learning.universal_model import ModelError, UniversalModel, ensemble_of
    from posture_id.learning.universal_network import UniversalNetwork, UniversalNetworkConfig

    torch.manual_seed(5)
    config = UniversalNetworkConfig(inputs=6, hidden=(4,))
    std = (np.zeros(6), np.full(6, 2.0), np.zeros(4), np.array([2.0, 1.0, 1.0, 1.0]))
    for name in ("white", "coloured"):
        UniversalModel(UniversalNetwork(config).eval(), *std,
                       {"scope": {"segments": [1, 2, 3]}}).save(tmp_path / name)
    white, coloured = (UniversalModel.load(tmp_path / n) for n in ("white", "coloured"))
    ensemble_of([white, coloured], by_noise=True).save(tmp_path / "gated")
    gated = UniversalModel.load(tmp_path / "gated")
    x = np.random.default_rng(2).normal(size=(3, 6))
    for index, original in enumerate((white, coloured)):
        alone = gated.member(index)
        alone.save(tmp_path / f"member{index}")
        assert alone.sidecar["weights_sha256"] == original.sidecar["weights_sha256"]
        assert gated.member_sha256(index) == original.sidecar["weights_sha256"]
        assert alone.gate is None and "ensemble_of" not in alone.sidecar
        got, want = alone.predict(x), original.predict(x)
        assert np.allclose(got.mean, want.mean) and np.allclose(got.logit, want.logit)
    with pytest.raises(ModelError, match="no member 2"):
        gated.member(2)
    with pytest.raises(ModelError, match="one network, not an ensemble"):
        white.member(0)


def test_the_scope_s_bodies_are_inside_and_a_small_robot_is_not(tmp_path):
    """What docs/universal.md says of the body check: every corner of the Winter scope,
    the TIP and the lumped presets are inside what the network was trained on; iCub
    (about 1 m tall, lumped from example-robot-data) is outside, by its time scale."""
    from posture_id.bodies.body import load_body
    from posture_id.bodies.lumping import robots_dir
    from posture_id.cli import main
    from posture_id.learning.data.bodies import build_body
    from posture_id.learning.data.scope import BodyDraw, UniversalScope
    from posture_id.learning.universal_identifier import UniversalIdentifier

    scope = UniversalScope()
    draws = [BodyDraw("winter", n, h, m, ((1.0, 1.0),) * n) for n in (1, 2, 3)
             for h in scope.heights_m for m in scope.masses_kg]
    draws += [BodyDraw(p, n) for p in scope.presets for n in (2, 3)] + [BodyDraw("tip", 3)]
    for draw in draws:
        assert UniversalIdentifier.bundled(build_body(draw)).body_outside == [], draw
    urdf = tmp_path / "icub.urdf"
    assert main(["body", "--lump", str(robots_dir() / "icub_description/robots/icub_reduced.urdf"),
                 "--segments", "3", "--ankle-joints", "l_ankle_pitch", "r_ankle_pitch",
                 "--knee-joints", "l_knee", "r_knee", "--hip-joints", "l_hip_pitch",
                 "r_hip_pitch", "--out", str(urdf)]) == 0
    outside = UniversalIdentifier.bundled(load_body(urdf)).body_outside
    assert outside and all("time scale outside" in o for o in outside), outside


def test_the_network_s_shape_is_checked_and_kept_with_the_model(tmp_path):
    """Widths given are the layers built and saved; a width that is not a positive integer,
    or none at all, is refused naming the field."""
    import torch

    from posture_id.learning.universal_model import UniversalModel
    from posture_id.learning.universal_network import UniversalNetwork, UniversalNetworkConfig

    config = UniversalNetworkConfig(inputs=6, hidden=(7, 5, 3))
    net = UniversalNetwork(config)
    widths = [layer.out_features for layer in net.members[0]
              if isinstance(layer, torch.nn.Linear)]
    assert widths == [7, 5, 3, 9]
    UniversalModel(net, np.zeros(6), np.ones(6), np.zeros(4), np.ones(4)).save(tmp_path / "m")
    assert UniversalModel.load(tmp_path / "m").network.config.hidden == (7, 5, 3)
    for bad in [(), (0,), (4, -1), (2.5,)]:
        with pytest.raises(LearningError, match="hidden must be one or more positive integer"):
            UniversalNetworkConfig(hidden=bad)


def test_the_training_configuration_names_its_point_loss():
    """The point loss is one of the two known; another is refused by name, and the command
    line passes its choice through."""
    from posture_id.cli import build_parser
    from posture_id.learning.universal_training import UniversalTrainingConfig

    assert UniversalTrainingConfig().point_loss == "squared"
    assert UniversalTrainingConfig(point_loss="absolute").point_loss == "absolute"
    with pytest.raises(LearningError, match="point_loss must be one of squared, absolute"):
        UniversalTrainingConfig(point_loss="huber")
    args = build_parser().parse_args(["network", "universal", "train", "set", "--out", "m",
                                      "--point-loss", "absolute"])
    assert args.point_loss == "absolute"


def _motor_noise_harmonics(draws: int, shape=None, cutoff_hz: float = 0.2,
                           with_frequencies: bool = False):
    """(E, draws, N) harmonics of what motor noise adds to the sway of one 2-segment
    Winter body, one parameter set, under an 80-state PRTS ×4 at 0.5° (the dead-band
    weighs most at small tilts), one noise draw per trial (torque noise of ``shape``,
    a :class:`~posture_id.simulation.noise.MotorShape`, default the first-order
    low-pass); and (E, N) the locked sway's (and (E,) their frequencies, Hz, when
    ``with_frequencies``)."""
    from posture_id.dec.parameters import ParameterArrays
    from posture_id.dec.prior import sample_parameters
    from posture_id.learning.data.bodies import build_body
    from posture_id.simulation.batch import simulate_batch
    from posture_id.simulation.noise import MotorNoise
    from posture_id.simulation.stimulus import prts

    body = build_body(BodyDraw("winter", 2, 1.75, 70.0, ((1.0, 1.0),) * 2))
    profile = prts(0.5, 4, 80, 0.25)
    one = sample_parameters(body, 1, np.random.default_rng(2))
    params = ParameterArrays(**{f: np.repeat(getattr(one, f), draws, axis=0)
                                for f in ParameterArrays.FIELDS})
    clean = simulate_batch(body, params, profile, workers=1)
    motor = MotorNoise(0.3, cutoff_hz, 7) if shape is None else \
        MotorNoise(0.3, cutoff_hz, 7, shape)
    noisy = simulate_batch(body, params, profile, workers=1, motor_noise=motor)
    layout = harmonic_layout(clean.tilt, 50.0, profile.period_s, profile.periodic_from_s)
    locked = sway_harmonics(layout, np.moveaxis(clean.theta, 0, 1))
    noise = sway_harmonics(layout, np.moveaxis(noisy.theta, 0, 1)) - locked
    excited = layout.excited & (layout.frequencies_hz < 2.5)
    if with_frequencies:
        return noise[excited], locked[excited, 0], layout.frequencies_hz[excited]
    return noise[excited], locked[excited, 0]


def _locked_bias(noise: np.ndarray) -> float:
    """Mean over harmonics and channels of |mean over draws|² / (variance / draws): about
    1 for noise centred on zero, growing with the draws for a part locked to the stimulus."""
    draws = noise.shape[1]
    var = np.mean(np.abs(noise - noise.mean(1, keepdims=True)) ** 2, axis=1)
    return float(np.mean(np.abs(noise.mean(1)) ** 2 / (var / draws)))


def test_motor_noise_harmonics_are_centred_with_uniform_phases_so_turning_them_is_a_new_draw():
    """The premise of ``fresh_motor_noise`` (:func:`.samples.rotate_motor_noise`): over
    200 draws of the torque noise on one body and parameter set, what the noise adds at
    each excited harmonic has no part locked to the stimulus (the dead-band does not turn
    it into one) and a uniform phase (Rayleigh: draws × R² about 1). A locked part of a
    third of the noise's SD would show (the statistic is not blind)."""
    noise, locked = _motor_noise_harmonics(200)
    sd = np.sqrt(np.mean(np.abs(noise) ** 2, axis=1, keepdims=True))
    assert 0.2 < np.mean(np.abs(noise) ** 2) / np.mean(np.abs(locked) ** 2) < 5  # people-like
    assert _locked_bias(noise) < 2.0
    assert _locked_bias(noise + sd / 3) > 5.0
    phases = noise / np.abs(noise)
    assert np.mean(200 * np.abs(phases.mean(1)) ** 2) < 2.0


def test_turning_motor_noise_keeps_its_power_cross_spectra_and_the_locked_sway():
    from posture_id.learning.universal_samples import rotate_motor_noise

    rng = np.random.default_rng(4)
    locked = rng.standard_normal((30, 5, 3)) + 1j * rng.standard_normal((30, 5, 3))
    noise = rng.standard_normal((30, 5, 3)) + 1j * rng.standard_normal((30, 5, 3))
    noise[:, 2] = 0  # a clean trial
    y = locked + noise
    turned = rotate_motor_noise(y, locked, np.random.default_rng(0))
    new = turned - locked
    assert np.allclose(np.abs(new), np.abs(noise))  # the same power at every harmonic
    assert np.allclose(new[..., 0] * np.conj(new[..., 1]),  # the same cross-spectra
                       noise[..., 0] * np.conj(noise[..., 1]))
    assert np.allclose(turned[:, 2], y[:, 2])  # a clean trial as it was
    assert not np.allclose(new[:, 0], noise[:, 0])  # a new draw
    again = rotate_motor_noise(y, locked, np.random.default_rng(0))
    assert np.array_equal(turned, again)  # reproducible from the generator


@pytest.mark.slow("simulates 2 × 160 trials with motor noise")
def test_a_torque_noise_of_another_slope_moves_the_sway_noise_by_the_psd_ratio():
    """The premise of ``motor_noise_tilt`` (:func:`.samples.tilt_motor_noise`): the same
    body and controller under torque noise of PSD slope 2 and of slope 1 above the same
    0.2 Hz corner: the sway noise's mean power at each excited harmonic, over 160 draws,
    moves by the torque PSDs' ratio (a factor of about 12 over the band): the log of the
    measured ratio follows the log of the PSD ratio with a slope within 15 % of one and a
    scatter of what 160 draws of exponential powers leave. (Under a corner far below the
    first harmonic, 0.02 Hz, a steep noise's power below the harmonics leaks into the
    cycle average and the slope is about 0.75: the tilt is a shape of noise, not every
    one.) A prediction 1.5 times too steep would not pass."""
    from posture_id.simulation.noise import MotorShape

    steep, shallow = MotorShape(slope=2.0), MotorShape(slope=1.0)
    a, _, f = _motor_noise_harmonics(160, steep, with_frequencies=True)
    b, _ = _motor_noise_harmonics(160, shallow)
    measured = np.log(np.mean(np.abs(b) ** 2, axis=(1, 2)) / np.mean(np.abs(a) ** 2, axis=(1, 2)))
    predicted = np.log(shallow.psd(f, 0.2) / steep.psd(f, 0.2))
    assert np.ptp(predicted) > np.log(8)  # the shapes differ over the band
    slope, intercept = np.polyfit(predicted, measured, 1)
    assert 0.85 < slope < 1.15
    scatter = measured - (slope * predicted + intercept)
    assert np.sqrt(np.mean(scatter ** 2)) < 0.3
    assert not 0.85 < np.polyfit(1.5 * predicted, measured, 1)[0] < 1.15


def test_tilting_motor_noise_gives_each_trial_a_power_law_factor_and_keeps_its_power():
    from posture_id.learning.universal_samples import TILT_PIVOT_HZ, tilt_motor_noise

    rng = np.random.default_rng(5)
    f = np.geomspace(0.05, 2.5, 30)
    locked = rng.standard_normal((30, 200, 3)) + 1j * rng.standard_normal((30, 200, 3))
    noise = rng.standard_normal((30, 200, 3)) + 1j * rng.standard_normal((30, 200, 3))
    noise[:, 7] = 0  # a clean trial
    y = locked + noise
    tilted = tilt_motor_noise(y, locked, f, 1.5, np.random.default_rng(0))
    new = tilted - locked
    assert np.allclose(np.sum(np.abs(new) ** 2, axis=(0, 2)), np.sum(np.abs(noise) ** 2,
                                                                     axis=(0, 2)))
    assert np.array_equal(tilted[:, 7], y[:, 7])
    keep = np.arange(200) != 7
    factor = np.abs(new[:, keep, 0] / noise[:, keep, 0])  # (K, T): the same at every segment
    assert np.allclose(factor, np.abs(new[:, keep, 2] / noise[:, keep, 2]))
    assert np.allclose(np.angle(new[:, keep] / noise[:, keep]), 0)  # phases as they were
    slopes = [np.polyfit(np.log(f), np.log(factor[:, t] ** 2), 1) for t in range(199)]
    residual = [np.ptp(np.log(factor[:, t] ** 2) - np.polyval(p, np.log(f)))
                for t, p in enumerate(slopes)]
    assert max(residual) < 1e-9  # a power law in frequency
    s = -np.array([p[0] for p in slopes])  # the PSD slope added
    assert s.min() > -1.5 and s.max() < 1.5 and s.min() < -1.2 and s.max() > 1.2
    assert TILT_PIVOT_HZ[0] < TILT_PIVOT_HZ[1]
    assert tilt_motor_noise(y, locked, f, 0.0, rng) is y  # off


def test_fresh_motor_noise_is_off_unless_asked_and_the_command_line_passes_it(
        tmp_path, monkeypatch):
    """`universal train` hands the flag to the training configuration (what it would
    train with is caught, not run)."""
    from posture_id.cli import main
    from posture_id.learning import universal_training as training
    from posture_id.learning.universal_training import UniversalTrainingConfig

    assert UniversalTrainingConfig().fresh_motor_noise is False
    seen = []
    monkeypatch.setattr(training, "train_universal",
                        lambda data, out, config, *a, **k: seen.append(config))
    (tmp_path / "set").mkdir()
    argv = ["network", "universal", "train", str(tmp_path / "set"), "--quiet", "--out"]
    assert main([*argv, str(tmp_path / "m1")]) == 0
    assert main([*argv, str(tmp_path / "m2"), "--fresh-motor-noise"]) == 0
    assert main([*argv, str(tmp_path / "m3"), "--motor-noise-tilt", "1"]) == 0
    assert [c.fresh_motor_noise for c in seen] == [False, True, False]
    assert [c.motor_noise_tilt for c in seen] == [0.0, 0.0, 1.0]


def test_a_table_draws_its_own_sway_whatever_noise_the_model_was_trained_under():
    """The bundled network was fine-tuned over noise families; its table's cells are the
    same trials as a low-pass network's (the table's people-like sway is the low-pass
    motor noise): the cell's draws under the table scope of a model trained over the
    families equal those of one trained without them, and differ from the families' own."""
    from dataclasses import replace

    from posture_id.studies.universal_table import _cell, _cells, table_scope

    families = replace(UniversalScope(), noise_families=("low_pass", "shallow"))
    assert table_scope(families) == UniversalScope()
    index = next(i for i, (family, stim, sway) in enumerate(list(_cells()))
                 if family == "TIP" and stim == (80, 6, 1.0) and sway == "people-like")
    plain = _cell(index, 4, UniversalScope().to_dict())
    tabled = _cell(index, 4, table_scope(families).to_dict())
    drawn = _cell(index, 4, families.to_dict())
    assert np.array_equal(plain[0]["y"], tabled[0]["y"])
    assert "noise_family" not in tabled[0]
    assert not np.array_equal(plain[0]["y"], drawn[0]["y"])
    # a cell drawn over noise families (a scope of the user's own) keeps one family per
    # trial kept, however many batches it took
    assert all(len(g["noise_family"]) == len(g["targets"]) for g in drawn)


def test_universal_manifest_is_checked_like_a_paper_sets(tiny_set, tmp_path):
    """A universal set's manifest is read by the one manifest reader: a shard entry
    without its SHA-256, or a manifest without its shard list, is refused naming the file."""
    import json
    import shutil

    from posture_id.learning.data.drawn import UniversalSet
    from posture_id.learning.data.trial_config import DatasetError

    copy = tmp_path / "set"
    shutil.copytree(tiny_set.path, copy)
    manifest = json.loads((copy / "manifest.json").read_text())
    broken = {**manifest, "shards": [{k: v for k, v in e.items() if k != "sha256"}
                                     for e in manifest["shards"]]}
    (copy / "manifest.json").write_text(json.dumps(broken))
    with pytest.raises(DatasetError, match=r"manifest.json: shard entry 0 is not an object"):
        UniversalSet.open(copy)
    (copy / "manifest.json").write_text(json.dumps(
        {k: v for k, v in manifest.items() if k != "shards"}))
    with pytest.raises(DatasetError, match=r"manifest.json: the manifest is missing 'shards'"):
        UniversalSet.open(copy)
    (copy / "manifest.json").write_text(json.dumps({**manifest, "format": "other"}))
    with pytest.raises(DatasetError, match="not a universal training set manifest"):
        UniversalSet.open(copy)
