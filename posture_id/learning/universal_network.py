"""The universal network: multilayer perceptrons over one module's features, one or an
ensemble of them trained together.

Input (B, :data:`~.features.module_frfs.N_INPUTS`) standardised; output (K, B, 9) for K members: the
four normalised continuous parameters [K̃p, K̃i, K̃d, Δ̃] standardised, the log SD the
member expects of its error on each (what the conformal intervals scale,
:mod:`.calibration`), and the class logit (positive: COM in space). The members differ
only by their initial weights and dropout; :meth:`~.model.UniversalModel.predict`
combines them (the mean of their means and logits; the SD of the mixture: their own SDs
and their disagreement, which is largest on inputs unlike the training set's).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import ClassVar

import torch
from torch import nn

from posture_id.errors import LearningError
from posture_id.learning.features.module_frfs import N_INPUTS

__all__ = ["UniversalNetworkConfig", "UniversalNetwork", "OUTPUTS", "register_network",
           "network_config_of"]

OUTPUTS = 9

#: Network configurations by their ``kind`` (:func:`register_network`).
_KINDS: dict[str, type] = {}
#: The kind of a model whose sidecar names none (every model saved before kinds).
_FIRST_KIND = "mlp"


def register_network(config: type) -> type:
    """Make a network configuration class known by its ``kind``, so that a model whose
    sidecar's ``architecture`` names it is read (trained, calibrated, checked and used
    to identify as any other).

    The class is a frozen dataclass with a class attribute ``kind``, fields ``inputs``
    and ``members``, ``build()`` returning the torch module (input (B, inputs)
    standardised, output (K, B, :data:`OUTPUTS`) for its K members: the four standardised
    normalised parameters, the log SD of each, the class logit), ``to_dict()`` (JSON,
    ``kind`` included) and a class method ``from_dict``."""
    _KINDS[config.kind] = config
    return config


def network_config_of(architecture: dict):
    """The network configuration a sidecar's ``architecture`` describes.

    Raises:
        LearningError: a kind no registered class builds, or fields that do not fit it.
    """
    kind = architecture.get("kind", _FIRST_KIND)
    if kind not in _KINDS:
        raise LearningError(f"a network of kind {kind!r} is not one this code builds "
                            f"(it builds {', '.join(sorted(_KINDS))})")
    try:
        return _KINDS[kind].from_dict(architecture)
    except (KeyError, TypeError, ValueError) as exc:
        raise LearningError(f"the {kind} network's architecture cannot be read ({exc})"
                            ) from None


@register_network
@dataclass(frozen=True)
class UniversalNetworkConfig:
    """Hidden widths of each perceptron, its dropout, and how many members."""

    kind: ClassVar[str] = _FIRST_KIND
    inputs: int = N_INPUTS
    hidden: tuple[int, ...] = (512, 512, 256)
    dropout: float = 0.1
    members: int = 1

    def build(self) -> UniversalNetwork:
        return UniversalNetwork(self)

    def to_dict(self) -> dict:
        return {"kind": self.kind, **asdict(self), "hidden": list(self.hidden)}

    @classmethod
    def from_dict(cls, data: dict) -> UniversalNetworkConfig:
        return cls(int(data["inputs"]), tuple(data["hidden"]), float(data["dropout"]),
                   int(data.get("members", 1)))

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
