"""Identify a recording with a trained CNN: features, prediction, parameters.

    >>> from posture_id import load_body, Recording
    >>> from posture_id.learning import CnnIdentifier
    >>> body = load_body()
    >>> identifier = CnnIdentifier.bundled(body)           # the bundled model
    >>> trial = prepare_trial(Recording.from_csv("rec.csv", body.segment_names))
    >>> result = identifier.identify(trial)
    >>> result.parameters                                  # DecParameters, SI units

A CNN is only valid for the stimulus and body it was trained on: the recording's tilt
must be that stimulus (the same PRTS, amplitude and length) and its segments the body's;
otherwise the error says so (least squares, ``posture-id fit``, takes any tilt).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from posture_id.bodies.body import Body
from posture_id.dec.parameters import (
    TARGET_FIELDS,
    DecParameters,
    default_parameters,
    denormalise_arrays,
    parameter_block,
)
from posture_id.errors import RecordingError
from posture_id.fileio import Result
from posture_id.learning.bundled import bundled_model_dir
from posture_id.learning.calibration import CnnCalibration
from posture_id.learning.checkpoint import FORMAT, LoadedModel, load_model
from posture_id.learning.config import Layout, LearningError
from posture_id.learning.data.store import stimulus_of
from posture_id.learning.features.spectrograms import FS_HZ
from posture_id.learning.inputs import sway_features
from posture_id.learning.model_files import SIDECAR
from posture_id.learning.prediction import predict_images
from posture_id.plotting import plot_intervals
from posture_id.provenance import body_identity, provenance
from posture_id.simulation.stimulus import TiltProfile
from posture_id.trials import PreparedTrial
from posture_id.uncertainty.identifiability import prior_interval
from posture_id.uncertainty.intervals import ParameterIntervals
from posture_id.uncertainty.noise import sensor_noise_deg

if TYPE_CHECKING:
    from posture_id.learning.typicality import Typicality

__all__ = ["NetworkIdentifier", "CnnIdentifier", "CnnIdentification", "DEFAULT_LEVEL", "register",
           "identifier_class"]

#: The intervals' nominal coverage unless asked otherwise.
DEFAULT_LEVEL = 0.9


@dataclass(frozen=True)
class CnnIdentification(Result):
    """What the CNN says about one recording.

    Attributes:
        parameters: every module's Kp, Ki, Kd, Δ and class (passive terms: the body's
            defaults), SI units: the parameter-file format.
        normalised: (N, 5) [K̃p, K̃i, K̃d, Δ̃, C]. class_probability: (N,) P(C = +1, COM).
        joints: module names. model: the model directory and what made it.
        intervals: conformal intervals of Kp, Ki, Kd, Δ (None for a model without a
            calibration); the class probability is then temperature-scaled too.
        notices: things to know. provenance: version, body identity, recording name.
        outside: ways the recording lies outside what the network was trained or
            calibrated on (another body; more sensor noise than the calibration saw).
        typicality: how typical the recording's inputs are of the training distribution
            (:mod:`posture_id.learning.typicality`; None without a reference).
    """

    parameters: DecParameters
    normalised: np.ndarray
    class_probability: np.ndarray
    joints: tuple[str, ...]
    model: dict
    intervals: ParameterIntervals | None = None
    notices: tuple[str, ...] = ()
    provenance: dict = field(default_factory=dict, repr=False)
    outside: tuple[str, ...] = ()
    typicality: Typicality | None = None

    @property
    def classes(self) -> tuple[str, ...]:
        return tuple(self.parameters[j].controls for j in self.joints)

    def to_dict(self) -> dict:
        return {
            **parameter_block(self.parameters, self.normalised, self.class_probability),
            "method": "cnn",
            "model": self.model,
            "intervals": None if self.intervals is None else self.intervals.to_dict(),
            "outside": list(self.outside),
            "typicality": None if self.typicality is None else self.typicality.to_dict(),
            "notices": list(self.notices),
            "provenance": self.provenance,
        }

    def plot(self, path=None, ax=None):
        """Each parameter's estimate relative to the defaults with its interval against
        the prior's (estimates alone for a model without a calibration)."""
        estimate = np.asarray(self.normalised)[:, :4]
        if self.intervals is not None:
            return self.intervals.plot(estimate, path=path, ax=ax)
        unknown = [["no interval"] * estimate.shape[1]] * len(self.joints)
        return plot_intervals(self.joints, estimate, estimate, estimate, unknown,
                              prior_interval(DEFAULT_LEVEL), DEFAULT_LEVEL,
                              "the model has no calibration: estimates only", path, ax)

    def summary(self) -> str:
        lines = self.parameters.identified_table(self.class_probability)
        lines.append(f"model: {self.model['path']} ({self.model['layout']})")
        if self.intervals is not None:
            lines += self.intervals.table()
        lines += [f"note: {n}" for n in self.notices]
        return "\n".join(lines)


#: Identifier classes by the sidecar format of the models they read (:func:`register`).
_KINDS: dict[str, type[NetworkIdentifier]] = {}


def register(cls: type[NetworkIdentifier]) -> type[NetworkIdentifier]:
    """Make an identifier class known by its models' sidecar ``format``, so that
    :meth:`NetworkIdentifier.load` (``identify --network``) reads them."""
    _KINDS[cls.format] = cls
    return cls


def identifier_class(folder: str | Path) -> type[NetworkIdentifier]:
    """The registered class that reads the model in ``folder``, by its sidecar's
    ``format`` (the paper CNN's for a folder whose sidecar cannot be read: its loader
    says precisely what is wrong)."""
    try:
        kind = json.loads((Path(folder) / SIDECAR).read_text(encoding="utf-8")).get("format")
    except (OSError, ValueError, AttributeError):
        kind = None
    return _KINDS.get(kind, CnnIdentifier)


class NetworkIdentifier:
    """A trained network and the body it identifies: what an identification asks of any
    architecture (the paper's spectrogram CNN, :class:`CnnIdentifier`; the universal
    network, :class:`~posture_id.learning.universal_identifier.UniversalIdentifier`).

    Attributes:
        format: the sidecar format of the models the class reads (:func:`register`).
        reads_people_like: trained on people-like sway (the verdict's people-like rules).
        reads_any_body: identifies bodies of any size (the alternatives' other sizes).
        model: the loaded weights and sidecar (``path``, ``sidecar``). body: the body
        identified. notices: what loading it had to say (one line each). calibration:
        its intervals' and class probabilities' calibration, or None. trained_on: the
        body (or scope) it was trained on, in words. trained_on_this_body: whether it was
        trained on this very body (its hybrid's calibration applies).
    """

    format: ClassVar[str] = ""
    reads_people_like: ClassVar[bool] = False
    reads_any_body: ClassVar[bool] = False
    trained_on_this_body: bool = False
    trained_on: str = ""
    calibration: Any = None

    def __init__(self, model: Any, body: Body, notices: tuple[str, ...] = ()) -> None:
        self.model = model
        self.body = body
        self.notices = tuple(notices)
        self.defaults = default_parameters(body)

    @classmethod
    def load(cls, folder: str | Path, body: Body) -> NetworkIdentifier:
        """The model in ``folder`` as an identifier for ``body``, read by the class its
        sidecar's format names (:func:`identifier_class`)."""
        return identifier_class(folder).load(folder, body)

    @classmethod
    def bundled(cls, body: Body) -> NetworkIdentifier:
        """The bundled model of this kind for ``body``."""
        raise NotImplementedError

    @classmethod
    def resolve(cls, model: str | Path | NetworkIdentifier | None, body: Body
                ) -> NetworkIdentifier:
        """``model`` as an identifier for ``body``: one already loaded, a model directory,
        or None for this kind's bundled model."""
        if isinstance(model, NetworkIdentifier):
            return model
        return cls.bundled(body) if model is None else cls.load(model, body)

    def for_body(self, body: Body) -> NetworkIdentifier:
        """This kind of network for another body."""
        raise NotImplementedError

    def identify(self, trial: PreparedTrial, level: float = DEFAULT_LEVEL
                 ) -> CnnIdentification:
        """The network's answer on a prepared trial: parameters, class probabilities and
        intervals at ``level``."""
        raise NotImplementedError

    def _own(self, loaded, refused: str):
        """``loaded`` (what was read beside the model: a calibration, a widening, a
        typicality reference, or None) if it was made for this model's weights; else
        None, and the notice ``refused``."""
        if loaded is not None and loaded.weights_sha256 != self.model.sidecar.get(
                "weights_sha256"):
            self.notices += (f"{self.model.path}: {refused}",)
            return None
        return loaded

    @property
    def layout(self) -> str:
        """The architecture's name in answers (``model.layout``)."""
        raise NotImplementedError

    def _intervals(self, normalised: np.ndarray, half: np.ndarray, level: float, label: str,
                   noise: float) -> ParameterIntervals:
        """Intervals of half widths ``half`` (N, 4) about the normalised estimates."""
        defaults = np.column_stack([self.defaults.array(f) for f in TARGET_FIELDS])
        return ParameterIntervals.around(normalised[:, :4], half, defaults, level, label,
                                         noise, self.body.joint_names)

    def _answer(self, trial: PreparedTrial, normalised: np.ndarray, probability: np.ndarray,
                intervals: ParameterIntervals | None, notices: tuple[str, ...],
                outside: list[str], model_extra: dict | None = None,
                typicality: Typicality | None = None) -> CnnIdentification:
        """The answer of normalised estimates (N, 5) and class probabilities (N,)."""
        arrays = denormalise_arrays(normalised[None], self.defaults)
        model_info = {"path": str(self.model.path), "layout": self.layout,
                      "weights_sha256": self.model.sidecar.get("weights_sha256"),
                      "trained_on": self.trained_on,
                      "package_version": self.model.sidecar.get("package_version"),
                      **(model_extra or {})}
        return CnnIdentification(
            parameters=arrays.trial(0, self.body.joint_names), normalised=normalised,
            class_probability=probability, joints=self.body.joint_names, model=model_info,
            intervals=intervals, notices=notices, outside=tuple(outside),
            typicality=typicality,
            provenance={**provenance(None, self.body, recording=trial.name),
                        "body": body_identity(self.body)})


@register
class CnnIdentifier(NetworkIdentifier):
    """A loaded model of the paper's spectrogram CNN and the body it identifies."""

    format = FORMAT

    #: the specialists are trained on sensor noise only: people-like sway is outside them
    reads_people_like = False

    def __init__(self, model: LoadedModel, body: Body, notices: tuple[str, ...] = ()) -> None:
        super().__init__(model, body, notices)
        sidecar = model.sidecar
        trained = sidecar.get("body", {})
        if trained.get("n_segments") != body.n_segments:
            raise LearningError(
                f"{model.path}: trained for a {trained.get('n_segments')}-segment body, "
                f"'{body.name}' has {body.n_segments}")
        if model.config.layout is not Layout.MODULAR and model.config.modules != body.n_segments:
            raise LearningError(f"{model.path}: {model.config.layout.value} model for "
                                f"{model.config.modules} modules, body has {body.n_segments}")
        calibration = CnnCalibration.load(model.path)
        self.calibration = self._own(calibration, "its calibration was made for other "
                                     "weights and is not used: no intervals (posture-id "
                                     "calibration makes one)")
        if calibration is None:
            self.notices += (f"{model.path}: the model has no calibration, so the CNN's own "
                             "answer has no intervals (posture-id network cnn calibrate MODEL_DIR "
                             "DATASET makes one)",)
        #: the network was trained (and calibrated) on this very body
        self.trained_on_this_body = trained.get("sha256") == body.sha256
        self.trained_on = str(trained.get("name"))
        if not self.trained_on_this_body:
            self.notices += (f"the model was trained on body '{trained.get('name')}', not on "
                             f"this URDF ('{body.name}'); its gains are normalised by this "
                             "body's m·g·h",)
        stim = sidecar.get("stimulus", {})
        self.stimulus = stim
        self.profile = stimulus_of(stim)
        self.n_samples = int(round(self.profile.duration * FS_HZ)) + 1
        #: the trained stimulus at the sample times (rad), what a recording's tilt must be
        self.expected_tilt = self.profile.angle(np.arange(self.n_samples) / FS_HZ)

    @classmethod
    def load(cls, model_dir: str | Path, body: Body) -> CnnIdentifier:
        return cls(load_model(model_dir), body)

    @classmethod
    def bundled(cls, body: Body) -> CnnIdentifier:
        """The bundled model for ``body`` (see :func:`~.bundled.bundled_model_dir`)."""
        folder, notices = bundled_model_dir(body)
        return cls(load_model(folder), body, notices)

    def for_body(self, body: Body) -> CnnIdentifier:
        """A specialist for another body: the bundled one of that body (a network trained
        on one body identifies that body only)."""
        return self if body is self.body else CnnIdentifier.bundled(body)

    def features(self, trial: PreparedTrial) -> np.ndarray:
        """(M, C, 51, 51) images of a prepared trial, or (1, 3N, 1, F) FRF features for an
        FRF model: checked against the model's stimulus."""
        tilt, theta = self._window(trial)
        return self._features(tilt, theta)

    def _features(self, tilt: np.ndarray, theta: np.ndarray) -> np.ndarray:
        out = sway_features(self.model.config.layout, self.profile, tilt, theta[None])
        return out if self.model.config.layout is not Layout.MODULAR else out.reshape(
            -1, *out.shape[2:])

    def _window(self, trial: PreparedTrial) -> tuple[np.ndarray, np.ndarray]:
        """(tilt (S,), segment angles (S, N)) rad of the model's window at 50 Hz, checked
        against the model's body and stimulus."""
        trial.require_segments(self.body.segment_names)
        recording = trial.recording
        if abs(trial.rate_hz - FS_HZ) > 1e-6 * FS_HZ:
            raise LearningError(f"{trial.name}: prepared at {trial.rate_hz:g} Hz; the CNN "
                                f"reads {FS_HZ:g} Hz (prepare_trial(..., rate_hz={FS_HZ:g}))")
        try:
            if len(recording.time) < self.n_samples:
                raise RecordingError(
                    f"{trial.name}: {recording.duration_s:.2f} s of sway; the CNN was trained "
                    f"on {(self.n_samples - 1) / FS_HZ:g} s ({self._stimulus_text()}): use "
                    "posture-id fit for other lengths")
            cut = slice(0, self.n_samples)
            self._check_stimulus(trial.stimulus, recording.tilt[cut], trial.name)
        except RecordingError as error:
            # a wrong time column shows as a wrong stimulus: say so when it is that
            if trial.rate_hint is None:
                raise
            raise RecordingError(
                f"{error}; and {trial.rate_hint.removeprefix(trial.name + ': ')}") from None
        return recording.tilt[cut], recording.theta[cut]

    def _stimulus_text(self) -> str:
        s = self.stimulus
        return f"PRTS {s['states']} states ×{s['cycles']}, {s['amplitude_deg']:g}° p-p"

    def _check_stimulus(self, stimulus: TiltProfile, tilt: np.ndarray, name: str) -> None:
        """Refuse a tilt that is not the trained PRTS (within 1 % of its amplitude);
        ``stimulus`` is the one the trial was prepared with, named in the message."""
        tolerance = 0.01 * math.radians(self.stimulus["amplitude_deg"])
        if np.max(np.abs(self.expected_tilt - tilt)) <= tolerance:
            return
        what = (f"a {stimulus.description}" if stimulus.description.startswith("PRTS")
                else "not a PRTS")
        raise RecordingError(
            f"{name}: the tilt is {what}; the CNN was trained on {self._stimulus_text()} "
            "and is valid for that stimulus only: use posture-id fit, which takes any tilt")

    def identify(self, trial: PreparedTrial, level: float = DEFAULT_LEVEL
                 ) -> CnnIdentification:
        """The CNN's parameters for one prepared trial (at 50 Hz), with intervals at
        ``level`` when the model is calibrated."""
        tilt, theta = self._window(trial)
        images = self._features(tilt, theta)
        notices = self.notices + trial.notices
        outside = [] if self.trained_on_this_body else [
            f"the network was trained on body '{self.trained_on}', not on this one"]
        prediction = predict_images(self.model, images)
        # the modules of the one trial: one sample per module (modular), or its one sample
        trial_modules = (slice(None), 0) if self.model.config.layout is Layout.MODULAR else 0
        normalised = prediction.targets[trial_modules]
        probability = prediction.class_probability[trial_modules]
        logit = prediction.class_logit[trial_modules]
        intervals = None
        if self.calibration is not None:
            if self.calibration.temperature is not None:
                probability = self.calibration.class_probability(logit)
            noise = sensor_noise_deg(theta)
            conformal = self.calibration.intervals
            label = ("conformal, CNN (validation split)" if self.trained_on_this_body else
                     f"conformal, CNN, calibrated on body '{self.trained_on}', not on this "
                     "one (coverage not checked here)")
            intervals = self._intervals(normalised, conformal.scale(level, noise), level,
                                        label, noise)
            if conformal.beyond(noise):
                beyond = (f"its sensor noise (about {noise:.3f}°) is above the "
                          f"{conformal.noise_deg[-1]:.3f}° the intervals were calibrated "
                          "for: they are likely too narrow")
                notices += (f"{trial.name}: {beyond}",)
                outside.append(beyond)
        return self._answer(trial, normalised, probability, intervals, notices, outside)

    @property
    def layout(self) -> str:
        return self.model.config.layout.value
