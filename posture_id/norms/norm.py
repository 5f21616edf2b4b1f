"""A normative set of FRFs, and one subject or robot tested against it.

A norm is built from its members' FRFs at common points (a lab's points,
:mod:`posture_id.frf.bands`), one or more channels each:

- each member's pseudo-impulse response (PIR, :func:`~posture_id.frf.bands.
  pseudo_impulse_response`), the channels' PIRs concatenated into one supervector x_i(t);
  their mean and SD over the members;
- **bootstrap constants** (B resamples of the members, with replacement, mean_b and SD_b
  of each): the prediction band's constant, the ``level`` quantile of every member's
  max_t |x_i(t) − mean_b(t)| / SD_b(t) over all resamples (the band mean ± c·SD holds a new
  member's whole PIR with that probability), and the confidence band's, the ``level``
  quantile over resamples of max_t |mean(t) − mean_b(t)| / SD_b(t) (a band for the group
  mean);
- the mean and covariance Σ of d = [Re H, Im H] (every point of every channel), and
  frequency weights w (default 1), for the **human-likeness** score
  sqrt(dᵀ·S·Σ⁻¹·S·d), d the tested FRF minus the mean, S = diag(w, w). **[decision]** Σ
  is the members' covariance shrunk towards its diagonal by Schäfer and Strimmer's
  (2005) estimate of the optimal intensity λ (the correlations times 1 − λ, the
  variances kept): a norm has tens of members for 2·F·M numbers (22 for Peterka's points
  on one channel), and the sample covariance of so few is singular or nearly so, its
  inverse blowing up every direction the members happen not to span (a left-out healthy
  subject then scores like a patient). λ is stored with the norm.

A norm may also be given as summary statistics only (``frequencies_hz``, ``mean_re_im``,
``covariance`` or ``inverse_covariance``, ``weights``), as labs publish them: it scores,
but has no bands.

:func:`against_norm` gives a tested FRF's PIR, whether it lies inside the prediction band,
its distance percentile (for each resample, the share of the resampled members whose
summed squared PIR distance to the resample's mean is below the tested one's; averaged)
and its human-likeness; :class:`NormTests` holds several subjects' tests (a table's or a
.mat's rows).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from posture_id.errors import PostureIdError
from posture_id.fileio import JsonFile, Result, read_json
from posture_id.frf.bands import pseudo_impulse_response

__all__ = ["Norm", "NormTest", "NormTests", "build_norm", "against_norm", "FrfSet",
           "tested_channels",
           "shrunk_covariance"]

#: The format of a norm file.
FORMAT = "posture_id-norm"


@dataclass(frozen=True)
class FrfSet:
    """FRFs of several subjects at common points: ``frequencies_hz`` (F,),
    ``response`` (N, F, M) complex, ``channels`` (M,), ``names`` (N,)."""

    frequencies_hz: np.ndarray
    response: np.ndarray
    channels: tuple[str, ...]
    names: tuple[str, ...]

    def __post_init__(self) -> None:
        r = np.asarray(self.response)
        if r.ndim != 3 or r.shape[1:] != (len(self.frequencies_hz), len(self.channels)):
            raise PostureIdError(f"FRFs of shape {r.shape}: expected (subjects, "
                                 f"{len(self.frequencies_hz)} frequencies, "
                                 f"{len(self.channels)} channels)")
        if not np.all(np.isfinite(r)):
            raise PostureIdError("FRFs hold values that are not finite")

    def __len__(self) -> int:
        return len(self.names)

    def pirs(self, rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
        """(t (S,), x (N, S·M)): every subject's channels' PIRs concatenated."""
        t, x = pseudo_impulse_response(self.frequencies_hz,
                                       np.moveaxis(np.asarray(self.response), 0, -1),
                                       rate_hz)  # (S, M, N)
        return t, np.moveaxis(x, -1, 0).transpose(0, 2, 1).reshape(len(self), -1)

    def re_im(self) -> np.ndarray:
        """(N, 2·F·M): [Re H, Im H], each F × M flattened frequency-major."""
        r = np.asarray(self.response).reshape(len(self), -1)
        return np.concatenate([r.real, r.imag], axis=1)


def shrunk_covariance(x: np.ndarray) -> tuple[np.ndarray, float]:
    """(Σ*, λ): the covariance of the rows of ``x`` (N, P) with its correlations shrunk
    towards 0 by Schäfer and Strimmer's (2005, target "D") optimal λ."""
    n = len(x)
    sd = x.std(axis=0, ddof=1)
    sd = np.where(sd > 0, sd, 1.0)
    z = (x - x.mean(axis=0)) / sd
    w = z[:, :, None] * z[:, None, :]  # (N, P, P)
    r = w.sum(axis=0) / (n - 1)
    variance = n / (n - 1) ** 3 * ((w - w.mean(axis=0)) ** 2).sum(axis=0)
    off = ~np.eye(x.shape[1], dtype=bool)
    denominator = float(np.sum(r[off] ** 2))
    lam = float(np.clip(np.sum(variance[off]) / denominator, 0, 1)) if denominator else 1.0
    shrunk = np.where(off, (1 - lam) * r, 1.0)
    return shrunk * np.outer(sd, sd), lam


def _bootstrap(x: np.ndarray, b: int, rng: np.random.Generator
               ) -> tuple[np.ndarray, np.ndarray]:
    """(B, D) means and SDs of B resamples (with replacement) of the rows of x."""
    idx = rng.integers(0, len(x), size=(b, len(x)))
    samples = x[idx]  # (B, N, D)
    return samples.mean(axis=1), samples.std(axis=1, ddof=1)


@dataclass(frozen=True)
class Norm(JsonFile):
    """A normative set (the module doc).

    Attributes:
        frequencies_hz: (F,). channels: (M,). weights: (F,).
        mean_re_im: (2FM,). covariance: (2FM, 2FM) or None; inverse_covariance: or given.
        members: (N,) names (empty for a summary-only norm). rate_hz: of the PIRs.
        pir_t: (S,) s; pir_mean, pir_sd: (S·M,); pir_members: (N, S·M).
        prediction_constant, confidence_constant, level, bootstrap: the bands'.
    """

    frequencies_hz: np.ndarray
    channels: tuple[str, ...]
    weights: np.ndarray
    mean_re_im: np.ndarray
    covariance: np.ndarray | None = None
    inverse_covariance: np.ndarray | None = None
    members: tuple[str, ...] = ()
    rate_hz: float = 22.0
    pir_t: np.ndarray | None = field(default=None, repr=False)
    pir_mean: np.ndarray | None = field(default=None, repr=False)
    pir_sd: np.ndarray | None = field(default=None, repr=False)
    pir_members: np.ndarray | None = field(default=None, repr=False)
    prediction_constant: float | None = None
    confidence_constant: float | None = None
    level: float = 0.95
    bootstrap: int = 0
    seed: int = 0
    lab_bands: dict | None = None
    shrinkage: float | None = None

    @property
    def has_bands(self) -> bool:
        """Whether the norm has PIR bands (its members' PIRs, at least 3 members); a norm of
        summary statistics only scores human-likeness."""
        return self.pir_members is not None and len(self.members) >= 3

    def precision(self) -> np.ndarray:
        """Σ⁻¹ (the pseudo-inverse of the members' covariance, or the one given)."""
        if self.inverse_covariance is not None:
            return np.asarray(self.inverse_covariance)
        if self.covariance is None:
            raise PostureIdError("the norm has neither a covariance nor its inverse")
        return np.linalg.pinv(np.asarray(self.covariance), rcond=1e-10, hermitian=True)

    def human_likeness(self, re_im: np.ndarray) -> float:
        """sqrt(dᵀ·S·Σ⁻¹·S·d), d = ``re_im`` (2FM,) − the mean, S = diag(w, w)."""
        d = np.asarray(re_im, dtype=float) - self.mean_re_im
        m = len(self.channels)
        w = np.concatenate([np.repeat(self.weights, m)] * 2)
        sd = w * d
        return float(math.sqrt(max(float(sd @ self.precision() @ sd), 0.0)))

    def to_dict(self) -> dict:
        """The norm file's format (JSON-ready, SI units): points, mean, covariance, members,
        PIRs, the bands' constants and the covariance's shrinkage; :meth:`from_json` reads
        it."""
        def arr(a):
            return None if a is None else np.asarray(a).tolist()

        return {"format": FORMAT, "frequencies_hz": arr(self.frequencies_hz),
                "channels": list(self.channels), "weights": arr(self.weights),
                "mean_re_im": arr(self.mean_re_im), "covariance": arr(self.covariance),
                "inverse_covariance": arr(self.inverse_covariance),
                "members": list(self.members), "rate_hz": self.rate_hz,
                "pir": None if self.pir_members is None else {
                    "t": arr(self.pir_t), "mean": arr(self.pir_mean), "sd": arr(self.pir_sd),
                    "members": arr(self.pir_members)},
                "prediction_band": {"constant": self.prediction_constant,
                                    "level": self.level, "bootstrap": self.bootstrap},
                "confidence_band": {"constant": self.confidence_constant,
                                    "level": self.level, "bootstrap": self.bootstrap},
                "seed": self.seed, "lab_bands": self.lab_bands,
                "covariance_shrinkage": self.shrinkage}

    @classmethod
    def from_json(cls, path: str | Path) -> Norm:
        """A norm file: one ``build_norm`` wrote, or summary statistics as labs publish
        them (``frequencies_hz``, ``mean_re_im``, ``covariance`` or
        ``inverse_covariance``, optional ``weights`` and ``channels``).

        Raises:
            PostureIdError: naming the file and the field: a field missing, of another
                type or shape, or holding numbers that are not finite.
        """
        data = read_json(path, "a norm file")
        if not isinstance(data, dict):
            raise PostureIdError(f"{path}: a norm is a JSON object")
        if "frequencies_hz" not in data or "mean_re_im" not in data:
            missing = [k for k in ("frequencies_hz", "mean_re_im") if k not in data]
            raise PostureIdError(f"{path}: a norm needs frequencies_hz and mean_re_im (no "
                                 f"{', '.join(missing)}; posture-id norm build writes one)")
        field_of = _NormFields(Path(path), data)
        f = field_of.array("frequencies_hz", 1)
        channels = field_of.names("channels", default=("COM",))
        mean = field_of.array("mean_re_im", 1)
        if mean.shape != (2 * len(f) * len(channels),):
            raise PostureIdError(f"{path}: mean_re_im holds {mean.size} numbers; "
                                 f"{len(f)} frequencies × {len(channels)} channel(s) need "
                                 f"{2 * len(f) * len(channels)} (Re then Im)")
        size = mean.size
        matrices = {}
        for key in ("covariance", "inverse_covariance"):
            if data.get(key) is not None:
                m = field_of.array(key, 2)
                if m.shape != (size, size):
                    raise PostureIdError(f"{path}: {key} must be {size} × {size}, got "
                                         f"{m.shape}")
                matrices[key] = m
        if not matrices:
            raise PostureIdError(f"{path}: a norm needs a covariance or inverse_covariance")
        weights = (field_of.array("weights", 1) if data.get("weights") is not None
                   else np.ones(len(f)))
        if weights.shape != f.shape:
            raise PostureIdError(f"{path}: weights must be one per frequency ({len(f)})")
        members = field_of.names("members", default=())
        rate_hz = field_of.number("rate_hz", data.get("rate_hz", 22.0))
        bands = field_of.object("prediction_band")
        confidence = field_of.object("confidence_band")
        pir = field_of.pir(f, len(channels), len(members), rate_hz)
        level = field_of.number("prediction_band.level", bands.get("level", 0.95))
        if not 0.5 <= level < 1:
            raise PostureIdError(f"{path}: prediction_band.level must be within 0.5–0.99 (a "
                                 f"share, not a percentage), got {level:g}")
        constants = [None if band.get("constant") is None
                     else field_of.number(f"{key}.constant", band["constant"])
                     for key, band in (("prediction_band", bands),
                                       ("confidence_band", confidence))]
        bootstrap = field_of.count("prediction_band.bootstrap", bands.get("bootstrap", 0))
        if pir[0] is not None and (constants[0] is None or bootstrap < 10):
            raise PostureIdError(f"{path}: a norm with PIRs needs its prediction band: "
                                 "prediction_band.constant and at least 10 bootstrap "
                                 f"resamples (prediction_band.bootstrap, got {bootstrap})")
        return cls(f, channels, weights, mean, matrices.get("covariance"),
                   matrices.get("inverse_covariance"), members, rate_hz, *pir,
                   *constants, level, bootstrap,
                   field_of.count("seed", data.get("seed", 0)), field_of.lab_bands(),
                   data.get("covariance_shrinkage"))


class _NormFields:
    """A norm file's fields read with their checks, each refusal naming the file and the
    field."""

    def __init__(self, path: Path, data: dict) -> None:
        self.path, self.data = path, data

    def array(self, key: str, ndim: int, value=None) -> np.ndarray:
        value = self.data[key] if value is None else value
        try:
            a = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise PostureIdError(f"{self.path}: {key} must be "
                                 f"{'a list' if ndim == 1 else 'a matrix'} of numbers") from None
        if a.ndim != ndim:
            raise PostureIdError(f"{self.path}: {key} must be "
                                 f"{'a list' if ndim == 1 else 'a matrix'} of numbers")
        if not np.all(np.isfinite(a)):
            where = tuple(int(i) for i in np.argwhere(~np.isfinite(a))[0])
            raise PostureIdError(f"{self.path}: {key} holds values that are not finite (at "
                                 f"{where[0] if ndim == 1 else where}): the norm cannot score")
        return a

    def names(self, key: str, default: tuple) -> tuple[str, ...]:
        value = self.data.get(key)
        if value is None or value == []:
            return default
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise PostureIdError(f"{self.path}: {key} must be a list of names, got "
                                 f"{value!r:.60}")
        return tuple(value)

    def number(self, key: str, value) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float) or \
                not math.isfinite(value):
            raise PostureIdError(f"{self.path}: {key} must be a finite number, got "
                                 f"{value!r:.60}")
        return float(value)

    def count(self, key: str, value) -> int:
        number = self.number(key, value)
        if number < 0 or number != int(number):
            raise PostureIdError(f"{self.path}: {key} must be a whole number ≥ 0, got "
                                 f"{value!r:.60}")
        return int(number)

    def object(self, key: str) -> dict:
        value = self.data.get(key) or {}
        if not isinstance(value, dict):
            raise PostureIdError(f"{self.path}: {key} must be an object")
        return value

    def lab_bands(self) -> dict | None:
        """The bands the members' FRFs were computed at (None: not said), readable."""
        from posture_id.frf.bands import FrequencyBands

        value = self.data.get("lab_bands")
        if value is None:
            return None
        try:
            FrequencyBands.from_dict(value)
        except (AttributeError, TypeError, ValueError, PostureIdError) as exc:
            raise PostureIdError(f"{self.path}: lab_bands is not a band set posture-id frf "
                                 f"writes ({exc})") from None
        return value

    def pir(self, f: np.ndarray, channels: int, members: int, rate_hz: float) -> list:
        """[t, mean, sd, members] of the norm's PIRs (None each when it has none), their
        lengths those of PIRs at its points and rate."""
        pir = self.object("pir")
        if all(pir.get(k) is None for k in ("t", "mean", "sd", "members")):
            return [None] * 4
        try:
            t, _ = pseudo_impulse_response(f, np.zeros(len(f), complex), rate_hz)
        except PostureIdError as exc:
            raise PostureIdError(f"{self.path}: rate_hz: {exc}") from None
        expected = {"t": (len(t),), "mean": (len(t) * channels,),
                    "sd": (len(t) * channels,), "members": (members, len(t) * channels)}
        out = []
        for key, shape in expected.items():
            if pir.get(key) is None:
                raise PostureIdError(f"{self.path}: pir.{key} is missing (the norm has the "
                                     "other PIR fields)")
            a = self.array(f"pir.{key}", len(shape), pir[key])
            if a.shape != shape:
                raise PostureIdError(f"{self.path}: pir.{key} is {a.shape}; PIRs of "
                                     f"{len(f)} frequencies at {rate_hz:g} Hz, "
                                     f"{channels} channel(s) and {members} member(s) make "
                                     f"{shape}: the file was edited or cut")
            out.append(a)
        return out


def build_norm(frfs: FrfSet, bootstrap: int = 1000, level: float = 0.95,
               rate_hz: float = 22.0, weights: np.ndarray | None = None,
               seed: int = 0, lab_bands: dict | None = None) -> Norm:
    """The norm of ``frfs`` (the module doc).

    Args:
        frfs: the members' FRFs at common points (:class:`FrfSet`, at least 3 members).
        bootstrap: B, the resamples of the members for the bands' constants (≥ 10).
        level: the bands' coverage, 0.5 ≤ level < 1 (default 0.95).
        rate_hz: the PIRs' sample rate, Hz (above twice the highest frequency).
        weights: (F,) the frequency weights w of the human-likeness score (default 1 each).
        seed: seeds the bootstrap resamples (stored with the norm; a test draws its
            distance percentile's resamples from ``seed + 1``).
        lab_bands: the lab bands the FRFs were computed at (:meth:`FrequencyBands.to_dict`
            form), stored with the norm, or None.
    Returns:
        :class:`Norm` with bands, its covariance shrunk towards its diagonal.
    Raises:
        PostureIdError: fewer than 3 members, a level or a bootstrap count out of range.
    """
    if len(frfs) < 3:
        raise PostureIdError(f"a norm needs at least 3 members, got {len(frfs)}")
    if not 0.5 <= level < 1:
        raise PostureIdError(f"the bands' level must be within 0.5–0.99, got {level}")
    if bootstrap < 10:
        raise PostureIdError(f"--bootstrap {bootstrap}: at least 10 resamples")
    t, x = frfs.pirs(rate_hz)
    mean, sd = x.mean(axis=0), x.std(axis=0, ddof=1)
    rng = np.random.default_rng(seed)
    means_b, sds_b = _bootstrap(x, bootstrap, rng)
    sds_b = np.where(sds_b > 0, sds_b, np.inf)
    member_max = np.concatenate([  # (B, N), in blocks: B·N·D numbers at once is too many
        (np.abs(x[None, :, :] - means_b[k : k + 64, None, :])
         / sds_b[k : k + 64, None, :]).max(axis=2) for k in range(0, bootstrap, 64)])
    prediction = float(np.quantile(member_max, level))
    confidence = float(np.quantile((np.abs(mean[None] - means_b) / sds_b).max(axis=1), level))
    re_im = frfs.re_im()
    w = np.ones(len(frfs.frequencies_hz)) if weights is None else np.asarray(weights, float)
    covariance, lam = shrunk_covariance(re_im)
    return Norm(np.asarray(frfs.frequencies_hz, float), tuple(frfs.channels), w,
                re_im.mean(axis=0), covariance, None,
                tuple(frfs.names), rate_hz, t, mean, sd, x, prediction, confidence, level,
                bootstrap, seed, lab_bands, lam)


@dataclass(frozen=True)
class NormTest(Result):
    """One FRF tested against a norm.

    Attributes:
        name: what was tested. human_likeness: the score (0 at the norm's mean).
        inside_prediction_band: its whole PIR within mean ± c·SD (None: the norm has no
        bands). distance_percentile: 0–100 (None: no bands). pir: (S·M,) its PIR.
        channels: the tested input's channels, one per norm channel (None: not said).
    """

    name: str
    norm: Norm = field(repr=False)
    response: np.ndarray = field(repr=False)
    human_likeness: float
    inside_prediction_band: bool | None
    distance_percentile: float | None
    pir: np.ndarray | None = field(default=None, repr=False)
    channels: tuple[str, ...] | None = None

    def entry(self) -> dict:
        """This test's own fields (to_dict without the norm and the provenance)."""
        return {"tested": self.name, "human_likeness": self.human_likeness,
                "inside_prediction_band": self.inside_prediction_band,
                "distance_percentile": self.distance_percentile,
                "tested_channels": None if self.channels is None else list(self.channels),
                "frf": {"re": self.response.real.tolist(), "im": self.response.imag.tolist()}}

    def to_dict(self) -> dict:
        from posture_id.provenance import provenance

        return {**self.entry(), "norm": _norm_summary(self.norm), "provenance": provenance()}

    def line(self) -> str:
        """The verdict in one line."""
        text = f"{self.name}: human-likeness {self.human_likeness:.2f}"
        if self.inside_prediction_band is not None:
            text += (f"; inside the prediction band: "
                     f"{'yes' if self.inside_prediction_band else 'NO'}; distance percentile "
                     f"{self.distance_percentile:.0f}")
        return text

    def summary(self) -> str:
        lines = [f"{self.name}: human-likeness {self.human_likeness:.2f} (0: the norm's mean)"]
        if self.inside_prediction_band is not None:
            lines.append(f"inside the norm's {100 * self.norm.level:.0f} % prediction band: "
                         f"{'yes' if self.inside_prediction_band else 'NO'}; distance "
                         f"percentile {self.distance_percentile:.0f} (of "
                         f"{len(self.norm.members)} members)")
        return "\n".join(lines)

    def plot(self, path=None, ax=None):
        """Gain and phase with the norm's members (top), the PIR in its bands (bottom)."""
        from posture_id.plotting import plot_norm_test

        return plot_norm_test(self, path=path, ax=ax)


def _norm_summary(norm: Norm) -> dict:
    return {"members": len(norm.members), "level": norm.level,
            "frequencies_hz": norm.frequencies_hz.tolist(), "channels": list(norm.channels)}


@dataclass(frozen=True)
class NormTests(Result):
    """Several subjects (a table's rows, a .mat's) each tested against one norm.

    Attributes:
        name: what was tested (the file). tests: one :class:`NormTest` per subject.
    """

    name: str
    tests: tuple[NormTest, ...]

    @property
    def norm(self) -> Norm:
        return self.tests[0].norm

    @property
    def inside_prediction_band(self) -> bool | None:
        """Every subject's PIR inside the prediction band (None: the norm has no bands)."""
        if any(t.inside_prediction_band is None for t in self.tests):
            return None
        return all(t.inside_prediction_band for t in self.tests)

    @property
    def outside(self) -> list[str]:
        """The subjects whose PIR leaves the prediction band."""
        return [t.name for t in self.tests if t.inside_prediction_band is False]

    def to_dict(self) -> dict:
        from posture_id.provenance import provenance

        return {"tested": self.name, "subjects": [t.entry() for t in self.tests],
                "outside_prediction_band": (None if self.inside_prediction_band is None
                                            else self.outside),
                "norm": _norm_summary(self.norm), "provenance": provenance()}

    def summary(self) -> str:
        norm = self.norm
        head = f"{self.name}: {len(self.tests)} subject(s) against the norm (human-likeness 0 "
        head += ("at its mean; no bands: a norm of summary statistics)"
                 if self.inside_prediction_band is None else
                 f"at its mean; distance percentiles of {len(norm.members)} members)")
        lines = [head, *(f"  {t.line()}" for t in self.tests)]
        if self.inside_prediction_band is not None:
            outside = self.outside
            lines.append(f"outside the norm's {100 * norm.level:.0f} % prediction band: "
                         + (f"{', '.join(outside)} ({len(outside)} of {len(self.tests)})"
                            if outside else "none"))
        return "\n".join(lines)

    def plot(self, path=None, ax=None):
        """Each subject's :meth:`NormTest.plot`, side by side (four subjects a row)."""
        from posture_id.plotting import _axes, _finished

        m = len(self.norm.channels)
        columns = min(4, len(self.tests))
        rows = -(-len(self.tests) // columns)
        fig, axes = _axes(ax, 3 * rows, columns * m, (5 * columns * m, 8 * rows))
        for k, test in enumerate(self.tests):
            r, c = divmod(k, columns)
            cell = axes[3 * r : 3 * r + 3, c * m : (c + 1) * m]
            test.plot(ax=cell)
            for j, channel in enumerate(self.norm.channels):
                cell[0, j].set_title(f"{test.name} ({channel}): {test.human_likeness:.2f}",
                                     fontsize=9)
                cell[2, j].set_visible(test.pir is not None)  # no bands: no PIR
        for k in range(len(self.tests), rows * columns):
            r, c = divmod(k, columns)
            for a in axes[3 * r : 3 * r + 3, c * m : (c + 1) * m].ravel():
                a.set_visible(False)
        fig.suptitle(f"{self.name}: {len(self.tests)} subject(s) against the norm")
        return _finished(fig, path)


def against_norm(norm: Norm, frequencies_hz: np.ndarray, response: np.ndarray,
                 name: str = "tested", channels: tuple[str, ...] | None = None) -> NormTest:
    """``response`` (F, M) at the norm's frequencies tested against ``norm`` (``channels``:
    the tested input's, one per norm channel, kept with the result).

    Args:
        norm: the norm tested against.
        frequencies_hz: (F,) the response's frequencies, Hz: the norm's points.
        response: (F, M) complex FRF, one column per norm channel (an (F,) one for one).
        name: names the tested FRF in the result and in errors.
        channels: (M,) the tested input's channel names, or None (not said).
    Returns:
        :class:`NormTest`: human-likeness, and with the norm's bands whether the PIR lies
        inside the prediction band and its distance percentile.
    Raises:
        PostureIdError: other frequencies or another number of channels than the norm's.
    """
    f = np.asarray(frequencies_hz, dtype=float)
    h = np.asarray(response, dtype=complex).reshape(len(f), -1)
    if f.shape != norm.frequencies_hz.shape or not np.allclose(f, norm.frequencies_hz,
                                                               atol=1e-6):
        raise PostureIdError(f"{name}: its FRF is at {np.round(f, 3).tolist()} Hz, the norm's "
                             f"at {np.round(norm.frequencies_hz, 3).tolist()} Hz: compute it "
                             "at the norm's points (posture-id frf --band-preset ...)")
    if h.shape[1] != len(norm.channels):
        raise PostureIdError(f"{name}: {h.shape[1]} channel(s), the norm has "
                             f"{len(norm.channels)} ({', '.join(norm.channels)})")
    re_im = np.concatenate([h.reshape(-1).real, h.reshape(-1).imag])
    score = norm.human_likeness(re_im)
    inside = percentile = None
    pir = None
    if norm.has_bands:
        _, x = pseudo_impulse_response(f, h, norm.rate_hz)
        pir = x.T.reshape(-1)
        inside = bool(np.all(np.abs(pir - norm.pir_mean)
                             <= norm.prediction_constant * norm.pir_sd))
        rng = np.random.default_rng(norm.seed + 1)
        members = norm.pir_members
        idx = rng.integers(0, len(members), size=(norm.bootstrap, len(members)))
        shares = []
        for rows in idx:
            sample = members[rows]
            centre = sample.mean(axis=0)
            mine = float(np.sum((pir - centre) ** 2))
            shares.append(np.mean(np.sum((sample - centre) ** 2, axis=1) < mine))
        percentile = float(100 * np.mean(shares))
    return NormTest(name, norm, h, score, inside, percentile, pir,
                    None if channels is None else tuple(channels))


def tested_channels(norm: Norm, available: tuple[str, ...], given: list[str] | None = None,
                    where: str = "", hint: str = "") -> tuple[str, ...]:
    """The channels of an input holding ``available`` that ``norm``'s channels are tested
    against, one each: ``given`` (``--channel``, one per norm channel); else the norm's own
    names; else, for a one-channel norm (a published norm's ``COM``), the input's only
    channel besides the body COM, or the body COM.

    Raises:
        PostureIdError: naming ``where``, the channels it has and what to give (``hint``
            adds to it).
    """
    listed = ", ".join(available)
    if given:
        if len(given) != len(norm.channels):
            raise PostureIdError(f"--channel: {len(given)} given for the norm's "
                                 f"{len(norm.channels)} channel(s) "
                                 f"({', '.join(norm.channels)}); give one per channel")
        missing = [c for c in given if c not in available]
        if missing:
            raise PostureIdError(f"{where}: no channel {', '.join(map(repr, missing))} "
                                 f"(--channel; it has {listed})")
        return tuple(given)
    if all(c in available for c in norm.channels):
        return tuple(norm.channels)
    if len(norm.channels) == 1:
        others = [c for c in available if c != "body COM"]
        if len(others) == 1:
            return (others[0],)
        if "body COM" in available:
            return ("body COM",)
        raise PostureIdError(f"{where}: no channel {norm.channels[0]!r} for the norm, and "
                             f"{len(available)} others (it has {listed}): name the one to "
                             "test with --channel NAME")
    missing = [c for c in norm.channels if c not in available]
    raise PostureIdError(f"{where}: no channel {', '.join(map(repr, missing))} for the norm "
                         f"(it has {listed}{hint}; --channel NAME, once per norm channel, "
                         "names the input's)")
