"""What a posture-control model is to the stages above it (fitting, comparison, cohorts,
verdicts): one typed protocol that DEC and the independent-channel model implement, and that
a new model implements to be fitted, simulated, compared and run over a cohort.

A model is a stateless object (``DEC``, ``IC``; :func:`posture_id.models.model_named` finds
one by the ``"model"`` key of its parameter files). Its parameters are frozen and write
themselves as JSON with that key. Beside the core (parameters, prior and bounds, simulation,
a trial's predicted body COM sway) it declares what it supports in
:attr:`Model.capabilities`, and the stages pick their way of fitting it from them
(:func:`posture_id.fitting.models.fit_model`): a closed-loop frequency response gives the
exact frequency-domain fit (:mod:`posture_id.fitting.frequency`), per-joint modules the
locked time-domain least squares; a network that identifies it and experiment design are
declared the same way.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from posture_id.choices import Choice

if TYPE_CHECKING:
    from posture_id.recording import Recording
    from posture_id.simulation.options import SimulationOptions
    from posture_id.simulation.stimulus import TiltProfile

__all__ = ["Capability", "TrustLevel", "ModelParameters", "ModelFit", "Model",
           "FrequencyModel", "register", "registered"]


class TrustLevel(Choice):
    """How far an answer can be trusted (docs/identify.md, "Trust"): the same three levels
    for every model and every way of identifying it."""

    GOOD = "good"
    IMPRECISE = "imprecise"
    DOUBTFUL = "doubtful"



class Capability(enum.Enum):
    """What a model supports beyond simulation, prediction and fitting."""

    #: a closed-loop tilt-to-COM-sway response H(s) with its derivatives (the exact
    #: frequency-domain fit, :mod:`posture_id.fitting.frequency`)
    FREQUENCY_RESPONSE = "frequency response"
    #: per-joint modules identified by the locked time-domain least squares
    LOCKED_FIT = "locked least squares"
    #: a network that identifies it in milliseconds (:mod:`posture_id.learning`)
    NETWORK = "network"
    #: experiment design: which protocol identifies it best (:mod:`posture_id.design`)
    DESIGN = "design"


@runtime_checkable
class ModelParameters(Protocol):
    """A model's parameters: frozen, SI units, JSON out with the model's ``"model"`` key."""

    def to_dict(self) -> dict: ...

    def summary(self) -> str: ...


@runtime_checkable
class ModelFit(Protocol):
    """A model fitted to one recording, as a comparison and a cohort read it."""

    @property
    def parameters(self) -> ModelParameters: ...

    @property
    def fitted_com_deg(self) -> np.ndarray:
        """(S,) degrees: the fitted model's body COM sway on the recording's samples."""

    @property
    def identified_count(self) -> int:
        """k: the parameters the fit identified (for the information criteria)."""

    @property
    def falls(self) -> bool:
        """Whether the fitted model leaves the sway limit (a fit that failed)."""

    def comparison_dict(self) -> dict:
        """What a comparison's JSON keeps of this fit."""

    def to_dict(self) -> dict: ...


@runtime_checkable
class Model(Protocol):
    """A posture-control model (the module doc).

    Attributes:
        name: the ``"model"`` key of its parameter files and of a comparison's JSON.
        label: how reports name it ("DEC", "IC").
        capabilities: what it supports beyond the core (:class:`Capability`).
    """

    name: str
    label: str
    capabilities: frozenset[Capability]

    def parameters_from_dict(self, data: Mapping, body, name: str = "parameters"
                             ) -> ModelParameters:
        """Validate a parameter file's mapping (``ParameterError`` naming ``name``)."""

    def default_parameters(self, body) -> ModelParameters:
        """Typical parameters for ``body`` (the first start of a search)."""

    def bounds(self, body) -> dict[str, tuple[float, float]]:
        """Per identified parameter, its search range in SI units for ``body``."""

    def simulate(self, body, params: ModelParameters, stimulus: TiltProfile | None = None,
                 options: SimulationOptions | None = None, motor_sd_deg: float = 0.0,
                 seed: int = 0) -> Recording:
        """A recording of ``body`` balanced by the model on ``stimulus``: time (S,) s,
        tilt (S,) rad, segment angles (S, N) rad, NaN from where it leaves the sway
        limit; ``motor_sd_deg``: motor noise σ (degrees of lean), seeded by ``seed``."""

    def com_sway_deg(self, params: ModelParameters, body, trial) -> np.ndarray:
        """(S,) degrees: the model's body COM sway, from rest, on a prepared trial's tilt
        and samples (what a held-out cycle is predicted with)."""


@runtime_checkable
class FrequencyModel(Model, Protocol):
    """A model with a closed-loop frequency response (:attr:`Capability.FREQUENCY_RESPONSE`):
    what :mod:`posture_id.fitting.frequency` needs to fit it exactly.

    Attributes:
        parameter_order: the order of the derivatives :meth:`closed_loop` returns.
        typical: per parameter, the first start of every search, in search units.
        search_bounds: per parameter, (low, high) in search units.
        pinned: the parameters whose precision the verdict judges, with the interval
            half-width beyond which one is not pinned (relative to the value, or absolute
            where :attr:`absolute_pins` names it); one on a search bound makes the answer
            doubtful.
        identified: the parameters a fit identifies unless asked otherwise.
        per_part: the parameter each part of a several-part fit gets its own value of.
    """

    parameter_order: tuple[str, ...]
    identified: tuple[str, ...]
    per_part: str
    typical: Mapping[str, float]
    search_bounds: Mapping[str, tuple[float, float]]
    pinned: Mapping[str, float]
    absolute_pins: frozenset[str]

    def plant(self, body) -> Any:
        """What the closed loop needs of the body (its inertia, m·g·h...)."""

    def closed_loop(self, params: ModelParameters, plant, s: np.ndarray,
                    gradient: bool = False):
        """H(s), tilt to COM sway (rad/rad); with ``gradient`` also dH/dp in
        :attr:`parameter_order` (SI units)."""

    def is_stable(self, params: ModelParameters, plant) -> bool: ...

    def scale(self, name: str, plant) -> float:
        """The unit a parameter is searched in (m·g·h for gains, 1 for the rest)."""

    def search_start(self, plant) -> ModelParameters:
        """The parameters the search's unidentified ones are held at."""

    def with_values(self, params: ModelParameters, values: Mapping[str, float]
                    ) -> ModelParameters:
        """A copy of ``params`` with ``values`` (SI units), validated."""

    def interval_multiplier(self, name: str, level: float) -> tuple[float, bool]:
        """(the multiplier of a parameter's standard error for a ``level`` interval,
        whether it is calibrated)."""


_REGISTRY: dict[str, Model] = {}


def register(model: Model) -> Model:
    """Make ``model`` known by its name (:func:`posture_id.models.model_named`, the check
    suite)."""
    _REGISTRY[model.name] = model
    return model


def registered() -> tuple[Model, ...]:
    """The models registered so far."""
    return tuple(_REGISTRY.values())
