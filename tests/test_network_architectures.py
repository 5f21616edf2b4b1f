"""A network architecture of one's own plugs into the learning stack: this module is the
whole of a third architecture (a linear read-out of the module features, one member per
seed), and nothing outside it is changed for it to go through the training set, training,
calibration, the held-out check and ``posture-id identify --network``."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest
import torch
from torch import nn

from posture_id.cli import main
from posture_id.dec import sample_parameters
from posture_id.fileio import json_text
from posture_id.learning.features.module_frfs import N_INPUTS
from posture_id.learning.universal_model import UniversalModel
from posture_id.learning.universal_network import OUTPUTS, network_config_of, register_network
from posture_id.learning.universal_training import (
    UniversalTrainer,
    UniversalTrainingConfig,
    train_universal,
)
from posture_id.recording import Recording
from posture_id.simulation import prts, simulate
from posture_id.studies.universal_check import calibrate_model, reference_from_sets


class LinearReadout(nn.Module):
    """(B, inputs) → (K, B, 9): one affine map of the features per member."""

    def __init__(self, config: LinearReadoutConfig) -> None:
        super().__init__()
        self.config = config
        self.members = nn.ModuleList(nn.Linear(config.inputs, OUTPUTS)
                                     for _ in range(config.members))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return torch.stack([member(x) for member in self.members])


@register_network
@dataclass(frozen=True)
class LinearReadoutConfig:
    """The third architecture's configuration."""

    kind: ClassVar[str] = "linear-readout"
    inputs: int = N_INPUTS
    members: int = 1

    def build(self) -> LinearReadout:
        return LinearReadout(self)

    def to_dict(self) -> dict:
        return {"kind": self.kind, "inputs": self.inputs, "members": self.members}

    @classmethod
    def from_dict(cls, data: dict) -> LinearReadoutConfig:
        return cls(int(data["inputs"]), int(data["members"]))


@pytest.mark.slow("generates a training set and trains a network")
def test_a_third_architecture_goes_through_data_training_calibration_check_and_identify(
        tip, tmp_path):
    # data: the training set, by the command line
    data = tmp_path / "set"
    assert main(["network", "universal", "data", "--out", str(data), "--shards", "20", "--trials",
                "40",
                 "--seed", "5", "--quiet"]) == 0
    # training, by the API (its network is this module's)
    model_dir = tmp_path / "linear"
    trainer = UniversalTrainer(data, model_dir, UniversalTrainingConfig(
        epochs=3, batch_size=64, threads=1), network=LinearReadoutConfig())
    training = trainer.run()  # a TrainingResult, its model the trained one
    result = training.model
    assert isinstance(result, UniversalModel) and isinstance(result.network, LinearReadout)
    sidecar = json.loads((model_dir / "model.json").read_text())
    assert sidecar["architecture"] == {"kind": "linear-readout", "inputs": N_INPUTS,
                                       "members": 1}
    assert network_config_of(sidecar["architecture"]) == LinearReadoutConfig()
    loaded = UniversalModel.load(model_dir)
    assert isinstance(loaded.network, LinearReadout)
    x = np.random.default_rng(0).standard_normal((4, N_INPUTS))
    assert np.allclose(loaded.predict(x).mean, result.predict(x).mean)
    # calibration on the calibration split, the check on the held-out test split
    assert main(["network", "universal", "calibrate", str(model_dir), str(data)]) == 0
    check = json.loads((model_dir / "check.json").read_text())
    assert check["overall"]["modules"] > 0
    assert all(0 <= check["overall"]["coverage_pct"][p] <= 100 for p in ("kp", "kd"))
    # the same check by the API, a result of the Result family; the typicality reference
    report = calibrate_model(model_dir, data)
    assert json.loads(json_text(report.to_dict())) == check
    assert "held-out test shards" in report.summary()
    report.plot(tmp_path / "check.png")
    typicality = reference_from_sets(model_dir, data)
    assert typicality.test_recordings > 0 and "Typicality reference" in typicality.summary()
    typicality.plot(tmp_path / "typicality.png")
    training.plot(tmp_path / "loss.png")
    assert all((tmp_path / f).stat().st_size > 5_000
               for f in ("check.png", "typicality.png", "loss.png"))
    assert training.epochs_run == 3 and "3 epochs" in training.summary()
    assert train_universal(data, model_dir, UniversalTrainingConfig(  # done: resumed, no epoch run
        epochs=3, batch_size=64, threads=1), network=LinearReadoutConfig()).sidecar[
            "weights_sha256"] == sidecar["weights_sha256"]
    # identification of a recording by the command line, with this model's intervals
    rng = np.random.default_rng(4)
    while True:
        truth = sample_parameters(tip, 1, rng).trial(0, tip.joint_names)
        trial = simulate(tip, truth, prts(states=80, cycles=3))
        if trial.stable:
            break
    csv = tmp_path / "trial.csv"
    Recording(trial.time, trial.tilt, trial.theta, trial.segments).to_csv(csv)
    answer = tmp_path / "answer.json"
    assert main(["identify", str(csv), "--network", str(model_dir), "--method", "cnn",
                 "--out", str(answer)]) in (0, 1)
    out = json.loads(answer.read_text())
    assert out["cnn"]["model"]["weights_sha256"] == sidecar["weights_sha256"]
    assert out["intervals"]["method"].startswith("conformal, universal network")
    assert set(out["parameters"]) >= set(tip.joint_names)
