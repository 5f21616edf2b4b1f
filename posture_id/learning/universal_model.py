"""A trained universal model on disk: ``model.safetensors`` (weights and standardisation)
and ``model.json`` (what made it: scope, features, training; the weights' SHA-256).
Nothing is unpickled; a directory whose parts do not match is refused in one line."""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import torch

from posture_id._version import __version__
from posture_id.errors import LearningError
from posture_id.fileio import json_text
from posture_id.learning.data.scope import UniversalScope
from posture_id.learning.features.module_frfs import UNIVERSAL_FEATURE_DEFINITION
from posture_id.learning.model_files import (
    SIDECAR,
    WEIGHTS,
    load_weights,
    network_tensors,
    prefixed,
    read_model_files,
    write_model_files,
)
from posture_id.learning.noise_gate import NoiseGate
from posture_id.learning.universal_network import (
    OUTPUTS,
    UniversalNetwork,
    network_config_of,
)

__all__ = ["UniversalModel", "UniversalPrediction", "ModelError", "FORMAT", "WEIGHTS",
           "SIDECAR", "ensemble_of"]

FORMAT = "posture_id-universal-model"


class ModelError(LearningError):
    """A universal model directory is missing, corrupt or of another kind."""


@dataclass(frozen=True)
class UniversalPrediction:
    """Per module sample: normalised [K̃p, K̃i, K̃d, Δ̃] (M, 4), the network's own SD of
    each (M, 4) in the same units, and the class logit (M,)."""

    mean: np.ndarray
    sd: np.ndarray
    logit: np.ndarray


def _averaged(means: np.ndarray, sds: np.ndarray, logits: np.ndarray) -> UniversalPrediction:
    """Members' (K, M, 4) means and SDs and (K, M) logits as one answer: the mean of their
    means and logits, the SD of their mixture."""
    sd = np.sqrt(np.mean(sds**2, axis=0) + np.var(means, axis=0))
    return UniversalPrediction(means.mean(axis=0), sd, logits.mean(axis=0))


@dataclass
class UniversalModel:
    """The network and its standardisation.

    Attributes:
        network: a torch module of a registered network kind
            (:func:`~.universal_network.register_network`; the perceptrons of
            :class:`~.universal_network.UniversalNetwork` unless its configuration says otherwise).
        input_mean, input_std: (N_INPUTS,). target_mean, target_std: (4,).
        sidecar: what made it (``model.json``). path: where it was loaded from.
    """

    network: torch.nn.Module
    input_mean: np.ndarray
    input_std: np.ndarray
    target_mean: np.ndarray
    target_std: np.ndarray
    sidecar: dict = field(default_factory=dict)
    path: Path | None = None

    @property
    def scope(self) -> UniversalScope:
        return UniversalScope.from_dict(self.sidecar["scope"])

    def standardised(self, inputs: np.ndarray) -> np.ndarray:
        """(M, N_INPUTS) inputs as the network reads them: less the mean, over the SD."""
        return (inputs - self.input_mean) / self.input_std

    def standardise(self, inputs: np.ndarray) -> torch.Tensor:
        """:meth:`standardised` as a float32 tensor."""
        return torch.from_numpy(self.standardised(inputs).astype(np.float32))

    @property
    def gate(self) -> NoiseGate | None:
        """Which members answer which recording (:mod:`~.noise_gate`), or None: all, averaged."""
        data = self.sidecar.get("gate")
        return None if data is None else NoiseGate.from_dict(data)

    @torch.inference_mode()
    def predict(self, inputs: np.ndarray, noise_ratio: np.ndarray | None = None,
                noise_colour: np.ndarray | None = None, batch_size: int = 8192
                ) -> UniversalPrediction:
        """Predictions for (M, N_INPUTS) unstandardised inputs (the network in evaluation
        mode: no dropout). An ensemble's members are combined: the mean of their means and
        logits, and the SD of their mixture, √(mean of their variances + the variance of
        their means). A gated model (:attr:`gate`) mixes its white-noise and its
        coloured-noise members' answers by each sample's ``noise_ratio`` and
        ``noise_colour`` (M,) (:meth:`~.gate.NoiseGate.coloured_share`; required then,
        ignored otherwise): the mixture's mean and SD, and the logit of its probability.

        Raises:
            ModelError: a gated model without the samples' noise ratio and colour.
        """
        if self.network.training:
            self.network.eval()
        members = self.network.config.members
        outs = [self.network(self.standardise(inputs[i : i + batch_size])).numpy()
                for i in range(0, len(inputs), batch_size)]
        out = (np.concatenate(outs, axis=1) if outs
               else np.zeros((members, 0, OUTPUTS), np.float32)).astype(np.float64)
        means = out[..., :4] * self.target_std + self.target_mean
        sds = np.exp(np.clip(out[..., 4:8], -12, 6)) * self.target_std
        gate = self.gate
        if gate is None:
            return _averaged(means, sds, out[..., 8])
        if noise_ratio is None or noise_colour is None:
            raise ModelError(f"{self.path or 'this model'}: a gated model answers by each "
                             "recording's noise ratio and colour; none were given")
        k = gate.white_members
        white, coloured = (_averaged(means[:k], sds[:k], out[:k, :, 8]),
                           _averaged(means[k:], sds[k:], out[k:, :, 8]))
        w = gate.coloured_share(noise_ratio, noise_colour)[:, None]
        mean = (1 - w) * white.mean + w * coloured.mean
        second = ((1 - w) * (white.sd**2 + white.mean**2)
                  + w * (coloured.sd**2 + coloured.mean**2))
        sd = np.sqrt(np.maximum(second - mean**2, 0.0))
        # the mixture's P(C = +1) and P(C = −1), as logs, then its logit
        with np.errstate(divide="ignore"):
            lw, lc = np.log(1 - w[:, 0]), np.log(w[:, 0])
        log_p = np.logaddexp(lw - np.logaddexp(0, -white.logit),
                             lc - np.logaddexp(0, -coloured.logit))
        log_q = np.logaddexp(lw - np.logaddexp(0, white.logit),
                             lc - np.logaddexp(0, coloured.logit))
        return UniversalPrediction(mean, sd, log_p - log_q)

    def member(self, index: int) -> UniversalModel:
        """The model an ensemble (:func:`ensemble_of`) took its member ``index`` from: that
        network alone with the ensemble's standardisation, its sidecar the ensemble's less
        the gate and the members, with that model's training and fine-tune origin. Saved,
        its weights are byte for byte the model's it came from when that model was one
        network (:meth:`member_sha256` names their hash).

        Raises:
            ModelError: not an ensemble, or no such member.
        """
        made_of = self.sidecar.get("ensemble_of")
        members = self.network.config.members
        if not made_of or members < 2:
            raise ModelError(f"{self.path or 'this model'}: one network, not an ensemble")
        if not 0 <= index < members:
            raise ModelError(f"{self.path or 'this model'}: no member {index} (it has "
                             f"{members})")
        network = replace(self.network.config, members=1).build()
        network.members[0].load_state_dict(self.network.members[index].state_dict())
        network.eval()
        source = self._member_source(index)
        sidecar = {k: v for k, v in self.sidecar.items()
                   if k not in ("weights_sha256", "ensemble_of", "gate", "calibration",
                                "training", "fine_tuned_from")}
        sidecar["training"] = source.get("training")
        if source.get("fine_tuned_from"):
            sidecar["fine_tuned_from"] = source["fine_tuned_from"]
        return UniversalModel(network, self.input_mean.copy(), self.input_std.copy(),
                              self.target_mean.copy(), self.target_std.copy(), sidecar)

    def member_sha256(self, index: int) -> str | None:
        """The SHA-256 of the weights of the model member ``index`` came from (None when
        that model was itself several networks)."""
        source = self._member_source(index)
        return source.get("weights_sha256") if source.get("members", 1) == 1 else None

    def _member_source(self, index: int) -> dict:
        """The ``ensemble_of`` entry member ``index`` came from."""
        first = 0
        for entry in self.sidecar.get("ensemble_of") or []:
            count = int(entry.get("members", 1))
            if first <= index < first + count:
                return entry
            first += count
        raise ModelError(f"{self.path or 'this model'}: its sidecar does not say where "
                         f"member {index} came from")

    def tensors(self) -> dict[str, torch.Tensor]:
        out = network_tensors(self.network)
        for name in ("input_mean", "input_std", "target_mean", "target_std"):
            out[f"standardiser.{name}"] = torch.from_numpy(
                np.ascontiguousarray(getattr(self, name), dtype=np.float64))
        return out

    def save(self, folder: str | Path, extra: dict | None = None) -> Path:
        """Write the model atomically (weights, then the sidecar naming their hash)."""
        sidecar = {k: v for k, v in {**self.sidecar, **(extra or {})}.items()
                   if k != "weights_sha256"}
        self.sidecar = write_model_files(folder, self.tensors(), {
            **sidecar, "format": FORMAT, "package_version": __version__,
            "architecture": self.network.config.to_dict(),
            "features": UNIVERSAL_FEATURE_DEFINITION})
        self.path = Path(folder)
        return self.path

    @classmethod
    def load(cls, folder: str | Path) -> UniversalModel:
        folder = Path(folder)
        sidecar, tensors = read_model_files(folder, ModelError, _check_sidecar)
        sidecar_file = folder / SIDECAR
        arch = sidecar["architecture"]
        try:
            config = network_config_of(arch)
        except LearningError as exc:
            raise ModelError(f"{sidecar_file}: {exc}") from None
        if "gate" in sidecar:
            try:
                gate = NoiseGate.from_dict(sidecar["gate"])
            except (KeyError, TypeError, ValueError, LearningError) as exc:
                raise ModelError(f"{sidecar_file}: its gate cannot be read ({exc})") from None
            if gate.white_members >= config.members:
                raise ModelError(f"{sidecar_file}: its gate gives {gate.white_members} of "
                                 f"{config.members} members to white noise, none to the rest")
        network = config.build()
        state = prefixed(tensors, "network.")
        if isinstance(network, UniversalNetwork):
            state = UniversalNetwork.upgrade_state(state)
        load_weights(network, state, folder, ModelError)
        network.eval()
        std = {k: v.numpy() for k, v in prefixed(tensors, "standardiser.").items()}
        return cls(network, std["input_mean"], std["input_std"], std["target_mean"],
                   std["target_std"], sidecar, folder)


def _check_sidecar(sidecar: dict, path: Path) -> None:
    """Refuse a sidecar of another format, or of features this code does not compute."""
    if sidecar.get("format") != FORMAT:
        raise ModelError(f"{path}: not a universal model's sidecar")
    if sidecar.get("features") != json.loads(json_text(UNIVERSAL_FEATURE_DEFINITION)):
        raise ModelError(f"{path}: made for other features than this code's; train it "
                         "again (make models)")


def ensemble_of(models: list[UniversalModel], by_noise: bool = False) -> UniversalModel:
    """One model whose members are all of ``models``' members (a deep ensemble of networks
    trained apart: :meth:`UniversalModel.predict` averages their means and logits and
    widens the SD by their disagreement). They must read the same inputs the same way: one
    architecture but for the members, one standardisation. The sidecar is the last model's
    (its scope, sets and training; list the widest last) with ``ensemble_of`` naming each
    model (path, weights' SHA-256, training); calibrate the result anew
    (``posture-id network universal calibrate``): its spread is not any member's.

    With ``by_noise``, the members are not averaged but gated (:mod:`~.noise_gate`): the first
    model's answer recordings whose noise is white or nearly none, the others' those
    whose noise is shaped by the body.

    Raises:
        ModelError: fewer than two models, a gated one among them, or two that differ in
            architecture (but for the members) or standardisation (named by path).
    """
    if len(models) < 2:
        raise ModelError("an ensemble needs two or more models")
    for model in models:
        if model.gate is not None:
            raise ModelError(f"{model.path or 'a model'}: gated by the noise already; "
                             "give the models it was made of")
    first = models[0]
    shape = replace(first.network.config, members=1)
    for other in models[1:]:
        name = other.path or "a model"
        if replace(other.network.config, members=1) != shape:
            raise ModelError(f"{name}: another architecture than {first.path} "
                             f"({other.network.config} against {first.network.config})")
        for attr in ("input_mean", "input_std", "target_mean", "target_std"):
            if not np.array_equal(getattr(other, attr), getattr(first, attr)):
                raise ModelError(f"{name}: standardised otherwise than {first.path} "
                                 f"({attr} differs): its members read other inputs")
    members = [member for model in models for member in model.network.members]
    network = replace(shape, members=len(members)).build()
    for mine, theirs in zip(network.members, members, strict=True):
        mine.load_state_dict(theirs.state_dict())
    network.eval()
    last = models[-1].sidecar
    sidecar = {k: v for k, v in last.items()
               if k not in ("weights_sha256", "ensemble_of", "gate")}
    if by_noise:
        sidecar["gate"] = NoiseGate(first.network.config.members).to_dict()
    sidecar["ensemble_of"] = [
        {"path": str(m.path), "weights_sha256": m.sidecar.get("weights_sha256"),
         "members": m.network.config.members, "training": m.sidecar.get("training"),
         "fine_tuned_from": {k: v for k, v in (m.sidecar.get("fine_tuned_from") or {}).items()
                             if k in ("path", "weights_sha256")} or None}
        for m in models]
    return UniversalModel(network, first.input_mean.copy(), first.input_std.copy(),
                          first.target_mean.copy(), first.target_std.copy(), sidecar)
