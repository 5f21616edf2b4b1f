"""The calibration of a network's answers: conformal intervals and temperature-scaled
class probabilities, kept beside the weights as ``calibration.json``, bound to them by
their SHA-256 (beside other weights a calibration is ignored, with a notice). One module
for both architectures:

**The paper's CNN** (:class:`CnnCalibration`). Made on a data set's validation split
(never trained on) by :func:`calibrate_cnn`, at several sensor-noise levels (white noise
added to the stored noise-free sway, seeded per shard and level):

- the continuous outputs' conformal half-widths per module and parameter
  (:class:`~posture_id.uncertainty.conformal.ConformalCalibration`, scores |p̃ − p̂̃|);
- the temperature T_m of each module's class logits (:func:`~posture_id.uncertainty.
  coverage.fit_temperature`), so that P(C_m = +1) = sigmoid(logit_m / T_m).

**The universal network** (:class:`UniversalCalibration`, made by :func:`calibrate`),
per regime. A regime is (segment count, noise-ratio bin, noise colour): the noise ratio
is the share of the recording's stimulus-locked harmonics that is noise
(:func:`~.features.module_frfs.noise_ratio`), and the colour whether that noise is white,
as a sensor's, or shaped by the body, as motor noise and drift are
(:func:`~.features.module_frfs.noise_colour` below or above
:data:`COLOUR_EDGE`); both are measured on the recording itself, so they tell a clean
recording from a people-like one, and one with a little motor noise from one with none,
at identification time. On the calibration split (shards no training or validation
trial came from, their noise drawn as in training) the calibration keeps, per regime and
parameter, the conformal quantiles of the score |t − μ| / σ̂ (σ̂: the network's own SD):
an interval μ ± q_level·σ̂·d covers the truth with probability ≥ level in that regime
(split-conformal, normalised scores). d = exp(x·β) is the recording's difficulty: how
much larger than σ̂ the network's errors run on such a recording, x being what the
recording shows (:func:`trend_terms`: segment count, log noise ratio per segment count
from :data:`TREND_RATIO_FLOOR` up, coloured noise, the stimulus's peak to peak, velocity,
period and cycles), β the least-squares fit of log score on x on the validation split
(shards apart from the calibration split's, so the conformal guarantee stands). Within
one regime the network's σ̂ runs wide on some stimuli and narrow on others (a 1-segment
body's clean sway under long, large tilts was covered 94–95 % at 90 % without it); d
evens that out, the regimes' quantiles make the level. Class probabilities get a
temperature per regime (minimum negative log-likelihood). A regime with fewer than
:data:`MIN_CELL` samples uses its noise-ratio bin's values over both colours, then its
segment count's, and a segment count with fewer (a set of 2- and 3-segment bodies only)
the values pooled over every sample (:data:`POOLED`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from posture_id.fileio import atomic_write_text, json_text
from posture_id.learning.checkpoint import LoadedModel
from posture_id.learning.config import ClassOutput, Layout, LearningError
from posture_id.learning.data.store import Dataset, with_sensor_noise
from posture_id.learning.inputs import sway_features
from posture_id.learning.prediction import predict_images
from posture_id.learning.universal_model import ModelError, UniversalModel, UniversalPrediction
from posture_id.learning.universal_samples import STIMULUS_COLUMNS, Samples
from posture_id.progress import Progress, report
from posture_id.uncertainty.conformal import ConformalCalibration, Normaliser, conformal_quantile
from posture_id.uncertainty.coverage import fit_temperature
from posture_id.uncertainty.noise import sensor_noise_deg

__all__ = ["CALIBRATION", "CnnCalibration", "HeldOutPredictions", "calibrate_cnn",
           "held_out_predictions", "noise_levels_of", "RATIO_EDGES", "COLOUR_EDGE", "LEVELS",
           "MIN_CELL", "POOLED", "TREND_TERMS", "TREND_RATIO_FLOOR", "UniversalCalibration",
           "calibrate", "regime_of", "Regime", "regime_text", "trend_terms"]

CALIBRATION = "calibration.json"
#: Second word of the seed of the sensor noise added to held-out sway.
_NOISE_STREAM = 0xCA1B


@dataclass(frozen=True)
class HeldOutPredictions:
    """The CNN on T trials of a split at one sensor-noise level.

    Attributes:
        noise_deg: the white noise SD added, °. estimate, truth: (T, N, 5) normalised
        [K̃p, K̃i, K̃d, Δ̃, C]. logit: (T, N) class logits. noise_estimate_deg: (T,).
    """

    noise_deg: float
    estimate: np.ndarray
    truth: np.ndarray
    logit: np.ndarray
    noise_estimate_deg: np.ndarray


def held_out_predictions(model: LoadedModel, data: Dataset, split: str, noise_deg: float,
                         progress: Progress | None = None) -> HeldOutPredictions:
    """The CNN's answers on every trial of ``split`` with white sensor noise of
    ``noise_deg``° added to the stored noise-free sway (seeded by shard and level)."""
    layout = model.config.layout
    locals_ = data.split_local(split)
    profile = data.stimulus
    estimate, truth, logit, noise = [], [], [], []
    shards = [k for k, local in enumerate(locals_) if len(local)]
    for done, k in enumerate(shards):
        report(progress, done, len(shards), f"{split} split at {noise_deg:g}°")
        arrays = data.load_shard(k, keys=("theta", "targets"))
        local = locals_[k]
        theta = with_sensor_noise(arrays["theta"][local].astype(np.float64), noise_deg,
                                  np.random.SeedSequence([k, int(round(1e6 * noise_deg)),
                                                          _NOISE_STREAM]))
        features = sway_features(layout, profile, data.tilt(theta.shape[1]), theta)
        n = theta.shape[2]
        if layout is Layout.MODULAR:
            features = features.reshape(-1, *features.shape[2:])
        prediction = predict_images(model, features)
        estimate.append(prediction.targets.reshape(len(local), n, 5))
        logit.append(prediction.class_logit.reshape(len(local), n))
        truth.append(np.asarray(arrays["targets"][local], dtype=np.float64))
        noise.append(sensor_noise_deg(theta))
    report(progress, len(shards), len(shards), f"{split} split at {noise_deg:g}°")
    return HeldOutPredictions(float(noise_deg), np.concatenate(estimate), np.concatenate(truth),
                              np.concatenate(logit), np.concatenate(noise))


def noise_levels_of(data: Dataset, count: int = 5) -> tuple[float, ...]:
    """``count`` evenly spaced sensor-noise levels from 0 to the data set's training noise
    (just 0 for a set made without it)."""
    top = float(data.manifest["config"].get("sensor_noise_deg", 0.0) or 0.0)
    if top == 0:
        return (0.0,)
    return tuple(float(x) for x in np.round(np.linspace(0.0, top, count), 6))


@dataclass(frozen=True)
class CnnCalibration:
    """See the module doc. ``temperature``: (N,) per module, or None for the paper's
    regression class output (its 0/1 class probability cannot be calibrated).
    ``least_squares``: the scales of the Gauss-Newton standard errors of least squares
    refining this model's answers (:mod:`posture_id.identify.calibration`), or None when
    not measured."""

    weights_sha256: str
    intervals: ConformalCalibration
    temperature: tuple[float, ...] | None
    dataset: str
    least_squares: ConformalCalibration | None = None

    def class_probability(self, logit: np.ndarray) -> np.ndarray:
        """Calibrated P(C = +1) from (..., N) logits."""
        t = np.asarray(self.temperature if self.temperature is not None else 1.0)
        return 1.0 / (1.0 + np.exp(-np.asarray(logit) / t))

    def to_dict(self) -> dict:
        return {"format": "posture_id-calibration", "format_version": 1,
                "weights_sha256": self.weights_sha256, "dataset": self.dataset,
                "temperature": self.temperature, "intervals": self.intervals.to_dict(),
                "least_squares": (None if self.least_squares is None
                                  else self.least_squares.to_dict())}

    def save(self, model_dir: str | Path) -> Path:
        return atomic_write_text(Path(model_dir) / CALIBRATION, json_text(self.to_dict()))

    @classmethod
    def load(cls, model_dir: str | Path) -> CnnCalibration | None:
        """The calibration in ``model_dir``, or None when there is none."""
        path = Path(model_dir) / CALIBRATION
        if not path.exists():
            return None
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
            if data.get("format") != "posture_id-calibration":
                raise ValueError("not a posture_id calibration file")
            return cls(str(data["weights_sha256"]),
                       ConformalCalibration.from_dict(data["intervals"], str(path)),
                       None if data["temperature"] is None else
                       tuple(float(t) for t in data["temperature"]),
                       str(data.get("dataset", "")),
                       None if data.get("least_squares") is None else
                       ConformalCalibration.from_dict(data["least_squares"], str(path)))
        except (OSError, ValueError, KeyError, TypeError) as error:
            raise LearningError(f"{path}: unreadable calibration ({error}); make it again "
                                "with posture-id network cnn calibrate") from None


def calibrate_cnn(model: LoadedModel, data: Dataset, noise_levels: tuple[float, ...],
                  progress: Progress | None = None) -> CnnCalibration:
    """Calibrate ``model`` on the validation split of ``data`` (see the module doc)."""
    if not noise_levels:
        raise LearningError("calibration needs at least one sensor-noise level")
    runs = [held_out_predictions(model, data, "validation", level, progress)
            for level in noise_levels]
    scores = np.stack([np.abs(r.truth[..., :4] - r.estimate[..., :4]) for r in runs])
    intervals = ConformalCalibration.from_scores(
        Normaliser.ABSOLUTE, scores,
        np.array([np.median(r.noise_estimate_deg) for r in runs]), np.array(noise_levels))
    temperature = None
    if model.config.class_output is ClassOutput.LOGIT:
        logits = np.concatenate([r.logit for r in runs])
        outcomes = np.concatenate([r.truth[..., 4] > 0 for r in runs])
        temperature = tuple(fit_temperature(logits[:, m], outcomes[:, m])
                            for m in range(logits.shape[1]))
    return CnnCalibration(str(model.sidecar.get("weights_sha256")), intervals, temperature,
                          str(data.path))


#: Bin edges of the noise ratio: clean below 0.02, in four bins there (the network's own
#: SD shrinks less than its error does on the cleanest sway, a large tilt's, so one clean
#: bin gave a 1-segment body's intervals 95–98 % coverage at 90 %); people-like sway
#: mostly above 0.1.
RATIO_EDGES = (0.001, 0.003, 0.01, 0.02, 0.1, 0.3)
#: Noise colour (:func:`~.features.module_frfs.noise_colour`) from which noise counts as
#: shaped by the body (white sensor noise reads about 0): a noise-ratio bin below 0.1
#: holds trials with sensor noise only and trials with a little motor noise, which this tells apart
#: (docs/universal.md, "Training and calibration", for what it changed).
COLOUR_EDGE = 0.8
#: The words of a regime by the upper edge of its noise-ratio bin.
_RATIO_WORDS = ((0.02, "clean"), (0.1, "a little noisy"), (0.3, "noisy"), (1.0, "mostly noise"))
#: Nominal levels the quantiles are kept for.
LEVELS = tuple(np.round(np.arange(0.5, 0.995, 0.005), 3).tolist())
MIN_CELL = 100
#: The key of the values pooled over every calibration sample.
POOLED = "all"
#: The terms of the difficulty trend (:func:`trend_terms`), in order.
TREND_TERMS = ("1-seg", "2-seg", "3-seg", "1-seg x log10 ratio", "2-seg x log10 ratio",
               "3-seg x log10 ratio", "coloured noise", "log10 p-p deg",
               "log10 RMS velocity deg/s", "log10 period s", "log10 cycles")
#: Noise ratios below this count as this in the trend: below it the "noise" is mostly
#: the sway's own nonlinearity (the dead band), the network's errors stop shrinking with
#: the ratio, and a trend carried further made the intervals of noise-free recordings too
#: narrow (docs/universal.md, "The recording's difficulty d").
TREND_RATIO_FLOOR = 1e-4
#: Scores below this are held there before their log is taken (a perfect estimate).
_SCORE_FLOOR = 1e-3


def regime_of(segments: np.ndarray | int, ratio: np.ndarray | float,
              colour: np.ndarray | float) -> np.ndarray:
    """Regime keys 'N:bw' or 'N:bc' (segment count, noise-ratio bin 0..len(RATIO_EDGES),
    white or coloured noise)."""
    bins = np.searchsorted(RATIO_EDGES, np.asarray(ratio, dtype=float))
    tint = np.where(np.asarray(colour, dtype=float) < COLOUR_EDGE, "w", "c")
    return np.char.add(np.char.add(np.char.add(np.asarray(segments).astype(str), ":"),
                                   bins.astype(str)), tint)


def trend_terms(segments: np.ndarray, ratio: np.ndarray, colour: np.ndarray,
                inputs: np.ndarray) -> np.ndarray:
    """(M, len(TREND_TERMS)) what M module samples' recordings show (:data:`TREND_TERMS`):
    ``segments``, ``ratio``, ``colour`` (M,) (or scalars, one recording), ``inputs``
    (M, N_INPUTS) the network's inputs (their stimulus descriptors)."""
    inputs = np.atleast_2d(inputs)
    m = len(inputs)
    segments = np.broadcast_to(np.asarray(segments), (m,))
    one_hot = (segments[:, None] == np.arange(1, 4)[None, :]).astype(float)
    log_ratio = np.log10(np.maximum(np.broadcast_to(np.asarray(ratio, dtype=float), (m,)),
                                    TREND_RATIO_FLOOR))
    coloured = np.broadcast_to(np.asarray(colour, dtype=float), (m,)) >= COLOUR_EDGE
    return np.column_stack([one_hot, one_hot * log_ratio[:, None], coloured,
                            inputs[:, STIMULUS_COLUMNS].astype(float)])


@dataclass(frozen=True)
class Regime:
    """A calibration regime: the segment count, the noise-ratio bin (0..len(RATIO_EDGES))
    and whether the noise is shaped by the body (None: either). Its :attr:`key` is how
    ``calibration.json`` names it ('3:2w', '3:2c', '3:2', '3')."""

    segments: int
    ratio_bin: int | None = None
    coloured: bool | None = None

    @classmethod
    def parse(cls, key: str) -> Regime:
        segments, _, rest = key.partition(":")
        if not rest:
            return cls(int(segments))
        colour = {"w": False, "c": True}.get(rest[-1])
        return cls(int(segments), int(rest.rstrip("wc")), colour)

    @property
    def key(self) -> str:
        if self.ratio_bin is None:
            return str(self.segments)
        tint = "" if self.coloured is None else "c" if self.coloured else "w"
        return f"{self.segments}:{self.ratio_bin}{tint}"

    def broader(self) -> list[Regime]:
        """This regime, its noise-ratio bin over both colours, its segment count."""
        return [self, Regime(self.segments, self.ratio_bin), Regime(self.segments)]

    def text(self) -> str:
        """In words: '3 segments, clean, white noise'."""
        n = self.segments
        upper = RATIO_EDGES[self.ratio_bin] if self.ratio_bin < len(RATIO_EDGES) else 1.0
        words = next(w for edge, w in _RATIO_WORDS if upper <= edge)
        tint = {False: ", white noise", True: ", noise shaped by the body"}.get(
            self.coloured, "")
        return f"{n} segment{'s' if n != 1 else ''}, {words}{tint}"


def regime_text(regime: str) -> str:
    """A regime key in words: '3 segments, clean, white noise'."""
    return Regime.parse(regime).text()


def _conformal(scores: np.ndarray) -> list[list[float]]:
    """(levels, 4) conformal quantiles at :data:`LEVELS`, capped at the largest score
    (:func:`~posture_id.uncertainty.conformal.conformal_quantile`)."""
    return [conformal_quantile(scores, level, capped=True).tolist() for level in LEVELS]


def _temperature(logit: np.ndarray, truth: np.ndarray) -> float:
    """The class's temperature (:func:`~posture_id.uncertainty.coverage.fit_temperature`),
    searched for within e^±3."""
    return fit_temperature(logit, truth > 0, log_bounds=(-3.0, 3.0), xatol=1e-5)


@dataclass(frozen=True)
class UniversalCalibration:
    """Per regime: the score quantiles (levels × 4) and the class temperature; ``counts``
    the calibration samples behind each; ``weights_sha256`` of the model calibrated;
    ``trend`` the difficulty's β, (len(TREND_TERMS), 4) (empty: d = 1)."""

    quantiles: dict
    temperature: dict
    counts: dict
    weights_sha256: str
    trend: tuple = ()

    def _key(self, regime: str, table: dict) -> str:
        """The regime, else its noise-ratio bin over both colours, else its segment count,
        else :data:`POOLED`, whichever has values."""
        for key in (*(r.key for r in Regime.parse(regime).broader()), POOLED):
            if key in table:
                return key
        raise ModelError(f"the universal calibration has no values for {regime_text(regime)} "
                         f"nor pooled ones (its samples: {self.counts}); calibrate the "
                         "model on sets with such bodies (posture-id network universal calibrate)")

    def scale(self, regime: str, level: float) -> np.ndarray:
        """(4,) the score quantile at ``level`` (nearest kept level at or above it)."""
        table = self.quantiles[self._key(regime, self.quantiles)]
        row = min(int(np.searchsorted(LEVELS, level - 1e-9)), len(LEVELS) - 1)
        return np.asarray(table[row])

    def difficulty(self, terms: np.ndarray) -> np.ndarray:
        """(M, 4) d = exp(x·β) of samples whose :func:`trend_terms` are ``terms``."""
        if not len(self.trend):
            return np.ones((len(terms), 4))
        return np.exp(terms @ np.asarray(self.trend))

    def half_width(self, regime: str, level: float, sd: np.ndarray, terms: np.ndarray
                   ) -> np.ndarray:
        """(M, 4) the half width q_level·σ̂·d of the intervals of M samples of one
        regime, normalised units; ``sd`` (M, 4) the network's σ̂."""
        return sd * self.scale(regime, level) * self.difficulty(terms)

    def probability(self, regime: str, logit: np.ndarray) -> np.ndarray:
        t = self.temperature[self._key(regime, self.temperature)]
        return 1.0 / (1.0 + np.exp(-np.asarray(logit) / t))

    def to_dict(self) -> dict:
        return {"levels": list(LEVELS), "ratio_edges": list(RATIO_EDGES),
                "colour_edge": COLOUR_EDGE,
                "quantiles": self.quantiles, "temperature": self.temperature,
                "counts": self.counts, "weights_sha256": self.weights_sha256,
                "trend_terms": list(TREND_TERMS),
                "trend_ratio_floor": TREND_RATIO_FLOOR, "trend": [list(r) for r in self.trend]}

    def save(self, folder: str | Path) -> Path:
        return atomic_write_text(Path(folder) / CALIBRATION, json_text(self.to_dict()))

    @classmethod
    def load(cls, folder: str | Path) -> UniversalCalibration | None:
        file = Path(folder) / CALIBRATION
        if not file.exists():
            return None
        try:
            data = json.loads(file.read_text(encoding="utf-8"))
            if data["levels"] != list(LEVELS) or data["ratio_edges"] != list(RATIO_EDGES) \
                    or data.get("colour_edge") != COLOUR_EDGE \
                    or data.get("trend_terms") != list(TREND_TERMS) \
                    or data.get("trend_ratio_floor") != TREND_RATIO_FLOOR:
                raise ModelError(f"{file}: made for other levels or regimes than this code's "
                                 "(before the noise's colour or the recording's difficulty "
                                 "was part of it, say); "
                                 "calibrate the model again: posture-id network universal "
                                 "calibrate MODEL_DIR SETS...")
            trend = tuple(tuple(float(v) for v in row) for row in data["trend"])
            if trend and np.shape(trend) != (len(TREND_TERMS), 4):
                raise ModelError(f"{file}: its trend is {np.shape(trend)}, not "
                                 f"({len(TREND_TERMS)}, 4); calibrate the model again: "
                                 "posture-id network universal calibrate MODEL_DIR SETS...")
            return cls(data["quantiles"], data["temperature"], data["counts"],
                       data["weights_sha256"], trend)
        except (json.JSONDecodeError, KeyError, TypeError) as exc:
            raise ModelError(f"{file}: not a universal calibration ({exc})") from None


def _scores(model: UniversalModel, samples: Samples) -> tuple[UniversalPrediction, np.ndarray]:
    """The prediction and (M, 4) scores |t − μ| / σ̂ of module samples."""
    pred: UniversalPrediction = model.predict(samples.inputs, samples.noise_ratio,
                                              samples.noise_colour)
    return pred, np.abs(samples.targets[:, :4] - pred.mean) / pred.sd


def _terms(samples: Samples) -> np.ndarray:
    """(M, len(TREND_TERMS)) :func:`trend_terms` of module samples."""
    return trend_terms(samples.segments, samples.noise_ratio, samples.noise_colour,
                       samples.inputs)


def _fit_trend(model: UniversalModel, samples: Samples) -> tuple:
    """β (len(TREND_TERMS), 4): least squares of log max(score, _SCORE_FLOOR) on
    :func:`trend_terms` over ``samples`` (the validation split)."""
    _, scores = _scores(model, samples)
    beta = np.linalg.lstsq(_terms(samples), np.log(np.maximum(scores, _SCORE_FLOOR)),
                           rcond=None)[0]
    return tuple(tuple(float(v) for v in row) for row in beta)


def calibrate(model: UniversalModel, samples: Samples, trend_samples: Samples
              ) -> UniversalCalibration:
    """The calibration of ``model`` from held-out module samples, its difficulty trend
    fitted on ``trend_samples`` (other held-out samples: the validation split)."""
    trend = _fit_trend(model, trend_samples)
    pred, scores = _scores(model, samples)
    scores = scores / np.exp(_terms(samples) @ np.asarray(trend))
    regimes = regime_of(samples.segments, samples.noise_ratio, samples.noise_colour)
    quantiles, temperature, counts = {}, {}, {}
    # each sample's keys from narrow to broad, as Regime.broader gives them, and the pooled one
    levels = (regimes, np.char.rstrip(regimes, "wc"), samples.segments.astype(str),
              np.full(len(regimes), POOLED))
    for key, sel in ((k, level == k) for level in levels for k in np.unique(level)):
        if sel.sum() < MIN_CELL:
            continue
        quantiles[key] = _conformal(scores[sel])
        temperature[key] = _temperature(pred.logit[sel], samples.targets[sel, 4])
        counts[key] = int(sel.sum())
    return UniversalCalibration(quantiles, temperature, counts,
                                str(model.sidecar.get("weights_sha256")), trend)
