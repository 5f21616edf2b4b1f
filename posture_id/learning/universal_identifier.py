"""Identify a recording with the universal network: any body of 1 to 3 segments, any PRTS
a lab runs, clean or people-like sway (docs/universal.md).

    >>> from posture_id import load_body, Recording
    >>> from posture_id.trials import prepare_trial
    >>> from posture_id.learning.universal_identifier import UniversalIdentifier
    >>> body = load_body("subject.urdf")
    >>> identifier = UniversalIdentifier.bundled(body)
    >>> result = identifier.identify(prepare_trial(Recording.from_csv("rec.csv")))

It reads the stimulus-locked harmonics of whole stimulus cycles, so the stimulus must be
periodic (a PRTS of any length, state duration, amplitude and cycles); a recording
outside what it was trained on (body, amplitude, period, noise) is identified with a
notice saying so.
"""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np

from posture_id.bodies.body import Body
from posture_id.dec.parameters import default_parameters
from posture_id.errors import PostureIdError, RecordingError
from posture_id.learning.calibration import (
    UniversalCalibration,
    regime_of,
    regime_text,
    trend_terms,
)
from posture_id.learning.config import LearningError
from posture_id.learning.data.scope import UniversalScope
from posture_id.learning.features.harmonics import (
    HarmonicLayout,
    harmonic_layout,
    sway_harmonics,
)
from posture_id.learning.features.module_frfs import (
    DESCRIPTORS,
    body_descriptors,
    com_weights,
)
from posture_id.learning.identifier import (
    DEFAULT_LEVEL,
    CnnIdentification,
    NetworkIdentifier,
    register,
)
from posture_id.learning.typicality import TypicalityReference
from posture_id.learning.universal_model import FORMAT, SIDECAR, ModelError, UniversalModel
from posture_id.learning.universal_samples import inputs_and_noise
from posture_id.simulation.stimulus import LAB_STATE_RANGE_S
from posture_id.trials import PreparedTrial
from posture_id.uncertainty.noise import sensor_noise_deg
from posture_id.uncertainty.widening import RecordingWidening

__all__ = ["UniversalIdentifier", "BUNDLED_DIR", "stimulus_outside"]

#: The bundled universal model (made by ``make models``).
BUNDLED_DIR = Path(__file__).resolve().parent / "models" / "universal"
#: The body's descriptors (:func:`~.features.module_frfs.body_descriptors`) in words.
_DESCRIPTOR_NAMES = ("ankle column", "knee column", "hip column", "1 segment", "2 segments",
                     "3 segments", "time scale", "coupling below", "coupling above",
                     "m·g·h ratio below", "m·g·h ratio above")


@register
class UniversalIdentifier(NetworkIdentifier):
    """The universal model and the body it identifies (never the network's "own" body: the
    hybrid scales no least-squares intervals by it)."""

    format = FORMAT
    #: trained on people-like sway (motor noise, drift): such a recording is inside its scope
    reads_people_like = True
    reads_any_body = True
    layout = "universal"

    def __init__(self, model: UniversalModel, body: Body, notices: tuple[str, ...] = ()) -> None:
        _refuse_size(body)
        super().__init__(model, body, notices)
        self.trained_on = "the universal scope"
        calibration = UniversalCalibration.load(model.path) if model.path else None
        self.calibration = self._own(
            calibration, "its calibration was made for other weights and is not used: "
            "no intervals")
        if calibration is None:
            self.notices += (f"{model.path}: the model has no calibration, so its answer has "
                             "no intervals",)
        self.widening = self._own(
            RecordingWidening.load(model.path) if model.path else None,
            "its recording widening was made for other weights and is not used: "
            "python -m posture_id.studies.widening makes it again")
        self.typicality = self._own(
            TypicalityReference.load(model.path) if model.path else None,
            "its typicality reference was made for other weights and is not used")
        self.scope = model.scope
        self._take_body(body)

    def _take_body(self, body: Body) -> None:
        """Identify ``body``: its descriptors, COM weights and defaults, what of it lies
        outside the training bodies, no stimulus layout kept from another body."""
        _refuse_size(body)
        self.body = body
        self.defaults = default_parameters(body)
        self.descriptors = body_descriptors(body)
        self.com = com_weights(body)
        self._layouts: dict = {}
        self.body_outside = self._outside(self.descriptors, range(0, DESCRIPTORS - 4),
                                          f"body '{body.name}'")

    @classmethod
    def load(cls, folder: str | Path, body: Body) -> UniversalIdentifier:
        return cls(UniversalModel.load(folder), body)

    def for_body(self, body: Body) -> UniversalIdentifier:
        """The same model and calibration for another body (nothing read again)."""
        other = copy.copy(self)
        other._take_body(body)
        return other

    @classmethod
    def bundled(cls, body: Body) -> UniversalIdentifier:
        """The bundled universal model for ``body``."""
        if not (BUNDLED_DIR / SIDECAR).exists():
            raise ModelError(f"{BUNDLED_DIR}: the universal model is not built (make models)")
        return cls.load(BUNDLED_DIR, body)

    def _outside(self, values: np.ndarray, columns: range, what: str) -> list[str]:
        """What of ``values`` (…, len(columns)), the descriptors ``columns``, lies outside
        the training inputs' 0.5–99.5 % range (the body's: drawn bodies have no simpler
        bounds; the stimulus is checked against the scope, :func:`stimulus_outside`)."""
        ranges = self.model.sidecar.get("ranges", {})
        low, high = ranges.get("descriptors_low"), ranges.get("descriptors_high")
        if low is None:
            return []
        values = np.atleast_2d(values)
        out = []
        for c in columns:
            v = values[:, c - columns.start]
            if np.any(v < low[c] - 1e-9) or np.any(v > high[c] + 1e-9):
                out.append(f"{what}: {_DESCRIPTOR_NAMES[c]} outside what the universal "
                           "model was trained on")
        return out

    def _layout(self, trial: PreparedTrial):
        stimulus = trial.stimulus
        if stimulus.period_s is None:
            lo, hi = LAB_STATE_RANGE_S
            raise RecordingError(
                f"{trial.name}: the universal network reads the stimulus-locked response to "
                f"a periodic stimulus (a PRTS); this tilt ({stimulus.description}) is not "
                f"periodic over the {trial.recording.duration_s:.1f} s recorded. A PRTS is "
                f"recognised from at least one whole cycle ({80 * lo:.0f}–{80 * hi:.0f} s "
                f"for 80 states, {242 * lo:.0f}–{242 * hi:.0f} s for 242, at the "
                f"{lo}–{hi} s states labs run): record one, or use --method fit, which "
                "takes any tilt")
        trial.require_whole_cycle()
        rec = trial.recording
        # the recordings of a study share their stimulus: its layout is made once
        key = (hash(rec.tilt.tobytes()), len(rec.tilt), rec.sample_rate_hz, stimulus.period_s,
               stimulus.periodic_from_s, stimulus.cycles)
        if key not in self._layouts:
            try:
                layout = harmonic_layout(rec.tilt, rec.sample_rate_hz, stimulus.period_s,
                                         stimulus.periodic_from_s, trial.name, stimulus.cycles)
            except PostureIdError as error:
                raise RecordingError(f"{error} (the universal network needs whole cycles of "
                                     "its stimulus)") from None
            if len(self._layouts) >= _LAYOUTS_KEPT:
                self._layouts.pop(next(iter(self._layouts)))
            self._layouts[key] = layout
        return self._layouts[key]

    def features(self, trial: PreparedTrial) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The network's inputs for a prepared trial, (N, N_INPUTS), and each module's
        noise ratio and colour (N,) (what a gated model weighs its networks by)."""
        trial.require_segments(self.body.segment_names)
        layout = self._layout(trial)
        y = sway_harmonics(layout, trial.recording.theta)[:, None, :]
        return inputs_and_noise(layout, y, self.descriptors, self.com)

    def identify(self, trial: PreparedTrial, level: float = DEFAULT_LEVEL
                 ) -> CnnIdentification:
        """Every module's parameters for one prepared trial, with intervals at ``level``."""
        inputs, ratios, colours = self.features(trial)  # (the segments checked there)
        layout = self._layout(trial)
        theta = trial.recording.theta
        n = self.body.n_segments
        prediction = self.model.predict(inputs, ratios, colours)
        typicality = (None if self.typicality is None
                      else self.typicality.of(self.model.standardised(inputs)))
        ratio, colour = float(ratios[0]), float(colours[0])
        regime = str(regime_of(n, ratio, colour))
        outside = list(self.body_outside) + stimulus_outside(
            self.scope, layout, trial.stimulus.states, f"{trial.name}, stimulus")
        if trial.stimulus.states is None:
            outside.append(f"{trial.name}: the stimulus ({trial.stimulus.description}) is "
                           "periodic but not a PRTS; the model was trained on PRTSs only")
        if ratio > self.model.sidecar.get("ranges", {}).get("noise_ratio_high", math.inf):
            outside.append(f"{trial.name}: {100 * ratio:.0f} % of its locked harmonics is "
                           "noise, more than in any recording the model was trained on")
        # a parameter is positive: an estimate below 1 % of its default is held there
        normalised = np.column_stack([np.maximum(prediction.mean, FLOOR - 1.0), np.zeros(n)])
        intervals = None
        noise = sensor_noise_deg(theta)
        if self.calibration is not None:
            probability = self.calibration.probability(regime, prediction.logit)
            if not 0.5 <= level <= LEVEL_MAX:
                raise PostureIdError(f"interval level {level:g} is outside the calibrated "
                                     f"0.5–{LEVEL_MAX:g}")
            half = self.calibration.half_width(regime, level, prediction.sd,
                                               trend_terms(n, ratio, colour, inputs))
            intervals = self._intervals(
                normalised, half, level, f"conformal, universal network (regime "
                f"{regime_text(regime)}, held-out bodies and stimuli)", noise)
        else:
            probability = 1.0 / (1.0 + np.exp(-prediction.logit))
        normalised[:, 4] = np.where(probability >= 0.5, 1.0, -1.0)
        notices = self.notices + trial.notices + tuple(outside)
        return self._answer(trial, normalised, probability, intervals, notices, outside,
                            {"regime": regime, "noise_ratio": ratio,
                             "noise_colour": colour}, typicality)


def _refuse_size(body: Body) -> None:
    if not 1 <= body.n_segments <= 3:
        raise LearningError(f"the universal model identifies bodies of 1 to 3 segments; "
                            f"'{body.name}' has {body.n_segments}")


#: Relative slack of the stimulus checks: a lab's 4° is 4° however it was rounded or
#: sampled (samples miss a PRTS's corners: 4.5° reads 4.46°).
_SCOPE_SLACK = 0.02


def stimulus_outside(scope: UniversalScope, layout: HarmonicLayout, states: int | None,
                     what: str) -> list[str]:
    """What of a recording's stimulus lies outside the scope the model was trained on,
    in sentences: the peak-to-peak tilt, the PRTS's length and state duration (for a
    periodic tilt of unknown states, its period), and the whole cycles analysed (training
    drew a recording's length within ``scope.duration_s`` and analysed the whole cycles in
    it, at least one). Each is checked against the scope's own range (with
    :data:`_SCOPE_SLACK`), so a stimulus at its edge (a 4° or a 0.5° tilt, 0.2 s states)
    is inside."""
    def within(value: float, low: float, high: float) -> bool:
        return low * (1 - _SCOPE_SLACK) <= value <= high * (1 + _SCOPE_SLACK)

    out = []
    lo, hi = scope.amplitude_deg
    if not within(layout.amplitude_deg, lo, hi):
        out.append(f"{what}: peak-to-peak tilt {layout.amplitude_deg:.3g}° outside the "
                   f"{lo:g}–{hi:g}° the universal model was trained on")
    period = layout.period_samples / layout.sample_rate_hz
    lo, hi = scope.state_s
    if states is not None and states not in scope.states:
        out.append(f"{what}: a PRTS of {states} states; the universal model was trained on "
                   f"{' and '.join(str(n) for n in scope.states)} states")
    elif states is not None and not within(period / states, lo, hi):
        out.append(f"{what}: states of {period / states:.3g} s outside the {lo:g}–{hi:g} s "
                   "the universal model was trained on")
    elif states is None and not within(period, min(scope.states) * lo, max(scope.states) * hi):
        out.append(f"{what}: a cycle of {period:.3g} s outside the "
                   f"{min(scope.states) * lo:.3g}–{max(scope.states) * hi:.3g} s the universal "
                   "model was trained on")
    shortest, longest = scope.duration_s
    fewest = max(1, math.floor(shortest / period * (1 + _SCOPE_SLACK)))
    most = max(1, math.floor(longest / period * (1 + _SCOPE_SLACK)))
    if not fewest <= layout.cycles <= most:
        out.append(f"{what}: {layout.cycles} whole cycle{'s' if layout.cycles > 1 else ''} "
                   f"of {period:.3g} s analysed; the universal model was trained on "
                   f"{fewest}–{most} of them (recordings of {shortest:g}–{longest:g} s)")
    return out


#: Stimulus layouts an identifier keeps (a study has few stimuli).
_LAYOUTS_KEPT = 8
#: The smallest parameter the identifier gives, as a share of the body's default.
FLOOR = 0.01
#: The highest interval level calibrated.
LEVEL_MAX = 0.99
