"""The universal network: a multilayer perceptron over one module's features.

Input (B, :data:`~.features.N_INPUTS`) standardised; output (B, 9): the four normalised
continuous parameters [K̃p, K̃i, K̃d, Δ̃] standardised, the log SD the network expects of
its error on each (what the conformal intervals scale, :mod:`.calibration`), and the
class logit (positive: COM in space).
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

from posture_id.learning.universal.features import N_INPUTS

__all__ = ["UniversalNetworkConfig", "UniversalNetwork", "OUTPUTS"]

OUTPUTS = 9


@dataclass(frozen=True)
class UniversalNetworkConfig:
    """Hidden widths of the perceptron and its dropout."""

    inputs: int = N_INPUTS
    hidden: tuple[int, ...] = (512, 512, 256)
    dropout: float = 0.1


class UniversalNetwork(nn.Module):
    """The network of a :class:`UniversalNetworkConfig`."""

    def __init__(self, config: UniversalNetworkConfig) -> None:
        super().__init__()
        self.config = config
        layers: list[nn.Module] = []
        width = config.inputs
        for hidden in config.hidden:
            layers += [nn.Linear(width, hidden), nn.LayerNorm(hidden), nn.GELU(),
                       nn.Dropout(config.dropout)]
            width = hidden
        layers.append(nn.Linear(width, OUTPUTS))
        self.layers = nn.Sequential(*layers)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """(B, inputs) → (B, 9)."""
        return self.layers(x)
