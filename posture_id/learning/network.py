"""The CNN (torch): blocks of convolution, batch normalisation, ReLU and pooling, a head.

Input (B, C, 51, 51) standardised images; output (B, 5M): for each of the M modules
[K̃p, K̃i, K̃d, Δ̃] standardised, then the class (standardised C, or a logit), in the
order module 1's five, module 2's five, ….
"""

from __future__ import annotations

import torch
from torch import nn

from posture_id.learning.config import NetworkConfig

__all__ = ["IdentifierNetwork"]


class IdentifierNetwork(nn.Module):
    """The network of a :class:`~posture_id.learning.config.NetworkConfig`."""

    def __init__(self, config: NetworkConfig) -> None:
        super().__init__()
        self.config = config
        layers: list[nn.Module] = []
        channels = config.in_channels
        for width in config.widths:
            layers += [
                nn.Conv2d(channels, width, kernel_size=3, padding=1, bias=False),
                nn.BatchNorm2d(width),
                nn.ReLU(inplace=True),
                nn.MaxPool2d(2, ceil_mode=True),
            ]
            channels = width
        self.features = nn.Sequential(*layers)
        self.pool = nn.AdaptiveAvgPool2d(1)
        head: list[nn.Module] = [nn.Flatten()]
        for width in config.head:
            head += [nn.Linear(channels, width), nn.ReLU(inplace=True)]
            channels = width
        head.append(nn.Linear(channels, config.outputs))
        self.head = nn.Sequential(*head)

    def forward(self, images: torch.Tensor) -> torch.Tensor:
        """(B, C, H, W) → (B, 5M)."""
        return self.head(self.pool(self.features(images)))
