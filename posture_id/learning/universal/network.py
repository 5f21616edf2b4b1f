"""The universal network: multilayer perceptrons over one module's features, one or an
ensemble of them trained together.

Input (B, :data:`~.features.N_INPUTS`) standardised; output (K, B, 9) for K members: the
four normalised continuous parameters [K̃p, K̃i, K̃d, Δ̃] standardised, the log SD the
member expects of its error on each (what the conformal intervals scale,
:mod:`.calibration`), and the class logit (positive: COM in space). The members differ
only by their initial weights and dropout; :meth:`~.model.UniversalModel.predict`
combines them (the mean of their means and logits; the SD of the mixture: their own SDs
and their disagreement, which is largest on inputs unlike the training set's).
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

from posture_id.errors import LearningError
from posture_id.learning.universal.features import N_INPUTS

__all__ = ["UniversalNetworkConfig", "UniversalNetwork", "OUTPUTS"]

OUTPUTS = 9


@dataclass(frozen=True)
class UniversalNetworkConfig:
    """Hidden widths of each perceptron, its dropout, and how many members."""

    inputs: int = N_INPUTS
    hidden: tuple[int, ...] = (512, 512, 256)
    dropout: float = 0.1
    members: int = 1

    def __post_init__(self) -> None:
        if not (self.hidden and all(isinstance(h, int) and h >= 1 for h in self.hidden)):
            raise LearningError(f"hidden must be one or more positive integer widths, "
                             f"got {self.hidden!r}")
        if not (isinstance(self.members, int) and self.members >= 1):
            raise LearningError(f"members must be an integer ≥ 1, got {self.members!r}")


def _perceptron(config: UniversalNetworkConfig) -> nn.Sequential:
    layers: list[nn.Module] = []
    width = config.inputs
    for hidden in config.hidden:
        layers += [nn.Linear(width, hidden), nn.LayerNorm(hidden), nn.GELU(),
                   nn.Dropout(config.dropout)]
        width = hidden
    layers.append(nn.Linear(width, OUTPUTS))
    return nn.Sequential(*layers)


class UniversalNetwork(nn.Module):
    """The network of a :class:`UniversalNetworkConfig`."""

    def __init__(self, config: UniversalNetworkConfig) -> None:
        super().__init__()
        self.config = config
        self.members = nn.ModuleList(_perceptron(config) for _ in range(config.members))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """(B, inputs) → (K, B, 9)."""
        return torch.stack([member(x) for member in self.members])

    @staticmethod
    def upgrade_state(state: dict) -> dict:
        """A state dict of a one-perceptron network as saved before members existed
        (keys ``layers.*``) under today's keys (``members.0.*``)."""
        return {("members.0." + k.removeprefix("layers.") if k.startswith("layers.") else k): v
                for k, v in state.items()}
