"""The CNN identifier: training end to end, checkpoints, resuming, refusals, identify."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys

import numpy as np
import pytest
import torch
from safetensors.torch import load_file

from posture_id.cli import main
from posture_id.learning.checkpoint import load_model
from posture_id.learning.config import (
    AdamWOneCycle,
    ClassOutput,
    Layout,
    LearningError,
    NetworkConfig,
    SgdMomentum,
    TrainingConfig,
)
from posture_id.learning.data import DatasetConfig, generate_dataset
from posture_id.learning.prediction import predict_images
from posture_id.learning.samples import SplitSamples
from posture_id.learning.training import train
from posture_id.trials import prepare_trial

SMALL = (8, 8, 12, 12, 16)


@pytest.fixture(scope="module")
def tiny_set(tmp_path_factory, tip):
    out = tmp_path_factory.mktemp("learning") / "set"
    generate_dataset(DatasetConfig(trials=48, body=str(tip.urdf_path), shard_size=16,
                                   seed=3), out, workers=2)
    return out


def _small(layout=Layout.MODULAR, class_output=ClassOutput.LOGIT, n=3):
    return NetworkConfig.for_body(layout, n, widths=SMALL, head=(16,),
                                  class_output=class_output)


def _one_thread(**kw):
    return TrainingConfig(threads=1, batch_size=16, **kw)


@pytest.fixture(scope="module")
def trained(tiny_set, tmp_path_factory):
    out = tmp_path_factory.mktemp("learning") / "model"
    result = train(tiny_set, out, _small(), _one_thread(epochs=3,
                   optimiser=AdamWOneCycle(max_learning_rate=3e-3)))
    return out, result


@pytest.mark.parametrize("layout", [Layout.MODULAR, Layout.MONOLITHIC, Layout.FRF])
@pytest.mark.parametrize("optimiser", [SgdMomentum(learning_rate=0.02), AdamWOneCycle()])
def test_tiny_training_reduces_the_loss(tiny_set, tmp_path, layout, optimiser):
    import torch

    threads = torch.get_num_threads()
    result = train(tiny_set, tmp_path / "m", _small(layout, ClassOutput.REGRESSION),
                   _one_thread(epochs=4, optimiser=optimiser))
    assert torch.get_num_threads() == threads  # the training's one thread, not the process's
    losses = [r["train_loss"] for r in result.history]
    assert len(losses) == 4 and losses[-1] < losses[0]
    assert result.plot(tmp_path / "m" / "loss.png") is not None
    assert (tmp_path / "m" / "loss.png").stat().st_size > 5_000
    log = [json.loads(line) for line in (tmp_path / "m" / "log.jsonl").read_text().splitlines()]
    assert [r["epoch"] for r in log] == [1, 2, 3, 4]


def test_checkpoint_round_trips_to_identical_predictions(trained, tiny_set):
    out, _ = trained
    from posture_id.learning.data import Dataset

    model = load_model(out)
    samples = SplitSamples(Dataset.open(tiny_set), "test", Layout.MODULAR, model.standardiser)
    images, _ = samples.arrays()
    first = predict_images(model, images, standardised_input=True)
    again = predict_images(load_model(out), images, standardised_input=True)
    np.testing.assert_array_equal(first.standardised, again.standardised)
    sidecar = json.loads((out / "model.json").read_text())
    assert sidecar["body"]["sha256"] and sidecar["dataset"]["manifest_sha256"]
    assert sidecar["architecture"]["widths"] == list(SMALL)
    assert [t["name"] for t in sidecar["targets"]] == ["kp", "ki", "kd", "delay_s", "class"]


def test_resume_after_an_interrupted_epoch_gives_the_same_weights(tiny_set, tmp_path):
    config = _one_thread(epochs=3)
    train(tiny_set, tmp_path / "whole", _small(), config)
    calls = []

    def stop_in_epoch_two(update):
        calls.append(update)
        if update.message.startswith("epoch 1/"):
            calls.append("epoch 1 done")
        if "epoch 1 done" in calls and update.done >= 32 and not update.message:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        train(tiny_set, tmp_path / "cut", _small(), config, progress=stop_in_epoch_two)
    state = json.loads((tmp_path / "cut" / "training" / "state.json").read_text())
    assert len(state["history"]) == 1  # killed inside epoch 2
    train(tiny_set, tmp_path / "cut", _small(), config)
    whole = load_file(str(tmp_path / "whole" / "training" / "epoch-0003.safetensors"))
    resumed = load_file(str(tmp_path / "cut" / "training" / "epoch-0003.safetensors"))
    assert whole.keys() == resumed.keys()
    for key in whole:
        assert torch.equal(whole[key], resumed[key]), key


def test_other_arguments_are_refused_on_resume(trained, tiny_set):
    out, _ = trained
    with pytest.raises(LearningError, match="other arguments"):
        train(tiny_set, out, _small(), _one_thread(epochs=5))


def _copy(trained, tmp_path):
    folder = tmp_path / "copy"
    shutil.copytree(trained[0], folder)
    return folder


def _edit_sidecar(folder, change):
    data = json.loads((folder / "model.json").read_text())
    change(data)
    (folder / "model.json").write_text(json.dumps(data))


@pytest.mark.parametrize(("damage", "message"), [
    (lambda f: (f / "model.safetensors").unlink(), "model.safetensors: missing"),
    (lambda f: (f / "model.json").unlink(), "model.json: missing"),
    (lambda f: (f / "model.safetensors").write_bytes(
        (f / "model.safetensors").read_bytes()[:5000]), "corrupt or truncated"),
    (lambda f: (f / "model.json").write_text("{"), "not valid JSON"),
    (lambda f: _edit_sidecar(f, lambda d: d.update(format_version=99)),
     "format version 99 is newer"),
    (lambda f: _edit_sidecar(f, lambda d: d["features"].update(window=256)),
     "another feature definition"),
    (lambda f: _edit_sidecar(f, lambda d: d["architecture"].update(widths=[8, 8, 8, 8, 8])),
     "the weights do not fit the architecture"),
    (lambda f: _edit_sidecar(f, lambda d: d["architecture"].update(layout="spiral")),
     "architecture is not one this code builds"),
])
def test_a_checkpoint_that_does_not_fit_is_refused_in_one_line(trained, tmp_path, damage,
                                                                message, capsys):
    folder = _copy(trained, tmp_path)
    damage(folder)
    with pytest.raises(LearningError, match=message):
        load_model(folder)
    assert main(["identify", "rec.csv", "--network", str(folder), "--out",
                 str(tmp_path / "r.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message.split()[0] in err


def test_training_never_pickles(trained):
    out, _ = trained
    suffixes = {p.suffix for p in out.rglob("*") if p.is_file()}
    assert suffixes <= {".safetensors", ".json", ".jsonl", ".png"}


def test_the_command_line_does_not_import_torch_to_start():
    code = "import sys, posture_id.cli; print('torch' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.stdout.strip() == "False", out.stderr


def test_frf_network_round_trips_and_identifies(tiny_set, tmp_path, tip):
    """An FRF-feature network: trained by the same machinery, its checkpoint names the FRF
    features, and the identifier computes them from a recording exactly as training did."""
    from posture_id.frf.features import FRF_FEATURE_DEFINITION
    from posture_id.learning.data import Dataset
    from posture_id.learning.identifier import CnnIdentifier
    from posture_id.learning.samples import frf_inputs
    from posture_id.recording import Recording

    out = tmp_path / "frf"
    train(tiny_set, out, _small(Layout.FRF), _one_thread(epochs=2))
    sidecar = json.loads((out / "model.json").read_text())
    assert sidecar["features"] == FRF_FEATURE_DEFINITION
    model = load_model(out)
    assert model.config.in_channels == 9 and model.config.image_size == 76  # odd harmonics ≤ 2.5 Hz
    data = Dataset.open(tiny_set)
    arrays = data.load_shard(0)
    arrays["sensor_noise_deg"][:] = 0.0  # the recording below is noise-free
    features = frf_inputs(data, arrays, 0)[0]
    identifier = CnnIdentifier.load(out, tip)
    time = np.arange(arrays["theta"].shape[1]) / 50.0
    recording = Recording(time, identifier.expected_tilt, arrays["theta"][0].astype(float),
                          tip.segment_names)
    np.testing.assert_allclose(identifier.features(prepare_trial(recording))[0], features,
                               rtol=1e-5, atol=1e-5)
    result = identifier.identify(prepare_trial(recording))
    assert result.parameters.joints == tip.joint_names


def test_evaluate_puts_the_universal_model_beside_a_specialist(trained, tiny_set, tip,
                                                                tmp_path):
    """``evaluate --universal``: the universal model on the specialist's own test trials;
    its class accuracy is what identifying each test trial's recording gives."""
    from posture_id.cli import main
    from posture_id.learning.data import Dataset
    from posture_id.learning.universal_identifier import UniversalIdentifier
    from posture_id.recording import Recording
    from posture_id.simulation import prts

    out, _ = trained
    report = tmp_path / "report"
    assert main(["network", "cnn", "evaluate", str(out), str(tiny_set), "--out", str(report),
                "--resimulate",
                 "0", "--universal"]) == 0
    comparison = json.loads((report / "universal_comparison.json").read_text())
    assert "| universal |" in (report / "universal_comparison.md").read_text()
    data = Dataset.open(tiny_set)
    identifier = UniversalIdentifier.bundled(tip)
    stimulus = prts()
    right = []
    for k, local in enumerate(data.split_local("test")):
        arrays = data.load_shard(k)
        for i in local:  # the set has no sensor noise: the same sway both ways
            theta = arrays["theta"][i].astype(float)
            t = np.arange(len(theta)) / 50.0
            rec = Recording(t, stimulus.angle(t), theta, tip.segment_names, f"trial{i}")
            got = identifier.identify(prepare_trial(rec, stimulus))
            right += list(np.sign(got.normalised[:, 4]) == arrays["targets"][i, :, 4])
    assert comparison["test_trials"] * 3 == len(right)
    assert comparison["class_accuracy"] == pytest.approx(np.mean(right))
    assert comparison["specialist"]["layout"] == "modular"
