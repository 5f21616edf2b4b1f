"""The universal identifier's training set: shards of drawn bodies and stimuli.

A set is a directory::

    manifest.json       configuration, scope, shard list (SHA-256 each), package version
    shard-00000.npz     one drawn body and PRTS, ``trials`` parameter sets (nothing
                        pickled), written atomically

Shard k draws everything from ``SeedSequence([seed, UNIVERSAL_STREAM, k])``: its bytes
depend only on (configuration, k). A killed run started again keeps the shards the
manifest lists (after checking their SHA-256) and makes the rest.

Each trial is simulated three times (:func:`make_shard`): without motor noise (its
stimulus-locked response), with a small unit of motor noise (how much sway a level
makes), and with the level that leaves the drawn share of its body COM sway locked (as
:func:`posture_id.simulation.subjects.people_like`, batched). The stored sway is the
last one's harmonics (:mod:`~posture_id.learning.features.harmonics`); sensor noise and
drift are added to them when the features are made, afresh every epoch.

Shards with ``k % 10 == 0`` are the test split, ``k % 10 == 1`` calibration,
``k % 10 == 2`` validation (early stopping), the rest training: held-out trials are on
bodies and stimuli no training trial had.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import lru_cache
from pathlib import Path

import numpy as np

from posture_id._version import __version__
from posture_id.dec.parameters import ParameterArrays, default_parameters, normalise_arrays
from posture_id.dec.prior import sample_parameters
from posture_id.executors import executor_for
from posture_id.fileio import file_sha256, json_text
from posture_id.learning.data.bodies import build_body
from posture_id.learning.data.scope import (
    BodyDraw,
    StimulusDraw,
    UniversalScope,
    draw_body,
    draw_stimulus,
)
from posture_id.learning.data.store import (
    SET_KEYS,
    check_shard,
    read_manifest,
    save_npz,
    shard_name,
    write_manifest,
)
from posture_id.learning.data.trial_config import DatasetError
from posture_id.learning.features.harmonics import HarmonicLayout, harmonic_layout, sway_harmonics
from posture_id.learning.features.module_frfs import body_descriptors, com_weights
from posture_id.progress import Progress, report
from posture_id.simulation.batch import simulate_batch
from posture_id.simulation.noise import DEFAULT_SHAPE, MotorNoise, MotorShape
from posture_id.simulation.noise_families import NoiseFamily, draw_noise
from posture_id.simulation.options import SimulationOptions
from posture_id.simulation.subjects import UNIT_LEVEL_PER_DEG, motor_levels_for_share

__all__ = ["UniversalDataConfig", "shard_layout", "shard_com_weights", "make_shard",
           "simulate_trials", "generate_universal", "UniversalSet", "open_sets", "merged_scope",
           "split_of", "UNIVERSAL_STREAM"]

UNIVERSAL_STREAM = 0x554E49
FORMAT = "posture_id-universal-set"


@dataclass(frozen=True)
class UniversalDataConfig:
    """A universal training set: ``shards`` shards of ``trials`` parameter sets each."""

    shards: int
    trials: int = 64
    seed: int = 0
    scope: UniversalScope = field(default_factory=UniversalScope)
    simulation: SimulationOptions = field(default_factory=SimulationOptions)

    def __post_init__(self) -> None:
        if self.shards < 1 or self.trials < 1:
            raise DatasetError(f"shards and trials must be ≥ 1, got {self.shards}, {self.trials}")

    def identity(self) -> dict:
        return {"trials": self.trials, "seed": self.seed, "scope": self.scope.to_dict(),
                "simulation": dict(vars(self.simulation))}


def split_of(k: int) -> str:
    """The split of shard k (module docstring)."""
    return {0: "test", 1: "calibration", 2: "validation"}.get(k % 10, "train")


def _var(x: np.ndarray) -> np.ndarray:
    return np.var(x, axis=1)


def make_shard(config: UniversalDataConfig, k: int) -> dict[str, np.ndarray]:
    """Simulate shard k: a body and a PRTS drawn from the scope, then
    :func:`simulate_trials`."""
    rng = np.random.default_rng(np.random.SeedSequence([config.seed, UNIVERSAL_STREAM, k]))
    body_draw = draw_body(config.scope, rng)
    stim = draw_stimulus(config.scope, rng)
    return simulate_trials(body_draw, stim, config.trials, config.scope, rng,
                           config.simulation)


def simulate_trials(body_draw: BodyDraw, stim: StimulusDraw, trials: int,
                    scope: UniversalScope, rng: np.random.Generator,
                    options: SimulationOptions | None = None) -> dict[str, np.ndarray]:
    """Simulate ``trials`` parameter sets (docs/model.md §5's prior) of one body under one PRTS,
    with motor noise as the scope says. Keys: ``y`` (T, K, N) complex64 harmonics of the
    kept trials' sway (motor noise included), ``y_locked`` the same without motor noise,
    ``tilt`` (K,) complex, ``frequencies_hz`` (K,), ``excited`` (K,), ``targets`` (T, N, 5)
    normalised [K̃p, K̃i, K̃d, Δ̃, C], the parameter arrays (T, N), ``locked_share`` (T,)
    realised, ``motor_noise_deg`` (T,), ``body`` (N, 11) descriptors, and
    ``period_samples``, ``cycles``, ``sample_rate_hz``, ``amplitude_deg``,
    ``velocity_deg_s``, ``draw`` (JSON text of the body and stimulus drawn),
    ``simulated`` and ``kept`` counts."""
    options = options or SimulationOptions()
    body = build_body(body_draw)
    profile = stim.profile()
    params = sample_parameters(body, trials, rng)
    noisy_trial = rng.random(trials) >= scope.clean_share
    share = np.where(noisy_trial, rng.uniform(*scope.locked_share, trials), 1.0)
    seeds = rng.integers(0, 2**62, trials)
    family, cutoff, shapes = _noise_draws(scope, trials, rng)
    levels = motor_levels_for_share(body, params, profile, share, seeds,
                                    UNIT_LEVEL_PER_DEG * stim.amplitude_deg, cutoff,
                                    options, shapes)
    clean, usable, response = levels.clean, levels.usable, levels.response
    level = np.where(usable & noisy_trial, levels.level, 0.0)
    final = simulate_batch(body, params, profile, options, workers=1, motor_noise=[
        MotorNoise(float(v), c, int(s), m)
        for v, s, c, m in zip(level, seeds, cutoff, shapes, strict=True)])
    kept = usable & final.stable
    with np.errstate(invalid="ignore", divide="ignore"):
        realised = response / _var(final.alpha[:, :, 0])
    rate = options.sample_rate_hz
    layout = harmonic_layout(clean.tilt, rate, profile.period_s, profile.periodic_from_s)
    theta = np.moveaxis(final.theta[kept], 0, 1)  # (S, T, N)
    locked = np.moveaxis(clean.theta[kept], 0, 1)
    y = np.moveaxis(sway_harmonics(layout, theta), 1, 0)
    y_locked = np.moveaxis(sway_harmonics(layout, locked), 1, 0)
    targets = normalise_arrays(params, default_parameters(body))[kept]
    draw = {"body": vars(body_draw) | {"label": body_draw.label()}, "stimulus": vars(stim),
            "body_name": body.name, "n_segments": body.n_segments}
    out = {f: getattr(params, f)[kept] for f in ParameterArrays.FIELDS}
    out.update(
        y=y.astype(np.complex64), y_locked=y_locked.astype(np.complex64),
        tilt=layout.tilt.astype(np.complex128), frequencies_hz=layout.frequencies_hz,
        excited=layout.excited, targets=targets, locked_share=realised[kept],
        motor_noise_deg=level[kept], body=body_descriptors(body),
        period_samples=np.array(layout.period_samples), cycles=np.array(layout.cycles),
        sample_rate_hz=np.array(rate), amplitude_deg=np.array(layout.amplitude_deg),
        velocity_deg_s=np.array(layout.velocity_deg_s),
        draw=np.array(json.dumps(draw, default=float)),
        simulated=np.array(trials), kept=np.array(int(kept.sum())),
    )
    if scope.noise_families:  # which family each kept trial's motor noise is of
        out["noise_family"] = family[kept]
    return out


def _noise_draws(scope: UniversalScope, trials: int, rng: np.random.Generator
                 ) -> tuple[np.ndarray, list[float], list[MotorShape]]:
    """Each trial's noise family (index into ``scope.noise_families``; −1 without them),
    its motor noise's corner (Hz) and shape. Without families the scope's low-pass for
    all, drawing nothing from ``rng`` (a set made before families draws as it did)."""
    if not scope.noise_families:
        return (np.full(trials, -1), [scope.cutoff_hz] * trials, [DEFAULT_SHAPE] * trials)
    family = rng.integers(0, len(scope.noise_families), trials)
    draws = [draw_noise(NoiseFamily(scope.noise_families[f]), rng) for f in family]
    return family, [d.cutoff_hz for d in draws], [d.shape for d in draws]


def _make(k: int, config: UniversalDataConfig) -> dict[str, np.ndarray]:
    return make_shard(config, k)


def shard_layout(arrays: dict[str, np.ndarray]) -> HarmonicLayout:
    """The harmonic layout of a stored shard (no projection: its sway is stored as
    harmonics already)."""
    return HarmonicLayout(
        projection=None, frequencies_hz=arrays["frequencies_hz"], excited=arrays["excited"],
        tilt=arrays["tilt"], period_samples=int(arrays["period_samples"]),
        cycles=int(arrays["cycles"]), sample_rate_hz=float(arrays["sample_rate_hz"]),
        amplitude_deg=float(arrays["amplitude_deg"]),
        velocity_deg_s=float(arrays["velocity_deg_s"]))


@lru_cache(maxsize=64)
def _drawn_com(draw_json: str) -> bytes:
    body = json.loads(draw_json)["body"]
    draw = BodyDraw(body["kind"], int(body["segments"]), float(body["height_m"]),
                    float(body["mass_kg"]), tuple(tuple(f) for f in body["factors"]))
    return com_weights(build_body(draw)).tobytes()


def shard_com_weights(arrays: dict[str, np.ndarray]) -> np.ndarray:
    """(N, N) the COM weights (:func:`~posture_id.learning.features.module_frfs.com_weights`)
    of a shard's body, rebuilt from the body it drew."""
    n = int(arrays["y"].shape[2])
    return np.frombuffer(_drawn_com(str(arrays["draw"])), dtype=float).reshape(n, n)


def _manifest(config: UniversalDataConfig) -> dict:
    return {"format": FORMAT, "package_version": __version__, "config": config.identity(),
            "shards": [], "complete": False}


def _recorded_arguments(identity: dict) -> dict:
    """A set's recorded arguments, any scope field added since it was made at its default
    (every such field's default draws as the set did: ``preset_jitter`` 0 draws nothing)."""
    return {**identity, "scope": json.loads(json_text(
        UniversalScope.from_dict(identity["scope"]).to_dict()))}


def generate_universal(config: UniversalDataConfig, out: str | Path, workers: int | None = None,
                       progress: Progress | None = None) -> UniversalSet:
    """Generate (or finish) the set ``config`` into ``out``; resumable (module doc)."""
    out = Path(out)
    manifest = _read(out)
    if manifest is None:
        if out.exists() and any(out.iterdir()):
            raise DatasetError(f"{out}: exists, is not empty and holds no universal set")
        manifest = _manifest(config)
    elif _recorded_arguments(manifest["config"]) != json.loads(json_text(config.identity())):
        raise DatasetError(f"{out}: was made with other arguments; choose another directory "
                           "or repeat the original arguments")
    for entry in manifest["shards"]:
        check_shard(out, entry)
    out.mkdir(parents=True, exist_ok=True)
    entries = {e["index"]: e for e in manifest["shards"] if e["index"] < config.shards}
    todo = [k for k in range(config.shards) if k not in entries]
    write_manifest(out, manifest)
    report(progress, len(entries), config.shards, "shard")
    executor = executor_for(None, workers, processes=True)
    try:
        for k, arrays in executor.unordered(_make, todo, config):
            file = out / shard_name(k)
            save_npz(file, arrays)
            entries[k] = {"index": k, "file": file.name, "kept": int(arrays["kept"]),
                          "simulated": int(arrays["simulated"]), "split": split_of(k),
                          "sha256": file_sha256(file)}
            manifest["shards"] = [entries[i] for i in sorted(entries)]
            write_manifest(out, manifest)
            report(progress, len(entries), config.shards, "shard")
    finally:
        executor.close()
    manifest["shards"] = [entries[i] for i in sorted(entries)]
    manifest["complete"] = True
    manifest["counts"] = {"shards": len(entries),
                          "simulated": sum(e["simulated"] for e in entries.values()),
                          "kept": sum(e["kept"] for e in entries.values())}
    write_manifest(out, manifest)
    return UniversalSet(out, manifest)


def _read(out: Path) -> dict | None:
    return read_manifest(out, FORMAT, None, "a universal training set manifest", SET_KEYS)


@dataclass
class UniversalSet:
    """A finished universal set (read side)."""

    path: Path
    manifest: dict

    @classmethod
    def open(cls, path: str | Path) -> UniversalSet:
        path = Path(path)
        manifest = _read(path)
        if manifest is None:
            raise DatasetError(f"{path}: not a universal training set (no manifest.json)")
        if not manifest.get("complete"):
            raise DatasetError(f"{path}: generation did not finish; run the same command again")
        return cls(path, manifest)

    def shards(self, split: str | None = None) -> list[dict]:
        return [e for e in self.manifest["shards"] if split is None or e["split"] == split]

    def load(self, entry: dict) -> dict[str, np.ndarray]:
        check_shard(self.path, entry)
        with np.load(self.path / entry["file"], allow_pickle=False) as z:
            return {key: z[key] for key in z.files}


def open_sets(paths: str | Path | Sequence[str | Path]) -> list[UniversalSet]:
    """One or more finished sets, to be trained on together (for example the default set
    and a set of people-like sway only)."""
    if isinstance(paths, (str, Path)):
        paths = [paths]
    sets = [UniversalSet.open(p) for p in paths]
    if not sets:
        raise DatasetError("no universal set given")
    merged_scope(sets)
    return sets


#: Scope fields that may differ between sets trained on together: what share of the
#: trials has motor noise, how much, and of which families (a set drawing families
#: beside sets of the low-pass only; sets that draw families must draw the same: a shard
#: names its trials' family by its index in its set's list).
_SWAY_FIELDS = ("clean_share", "locked_share", "noise_families")
#: Scope fields of the mix of bodies drawn, which may differ too.
_MIX_FIELDS = ("proportion_jitter", "tip_share", "preset_share", "preset_jitter")
#: Scope ranges a later set may draw differently, overlapping the first set's: to draw
#: more of part of it, or a margin beyond it so that its edge is not the edge of what the
#: network saw (small tilts, where the dead-band weighs most, sit at the low edge).
_FOCUS_FIELDS = ("amplitude_deg",)


def merged_scope(sets: Sequence[UniversalSet]) -> UniversalScope:
    """The scope of sets trained on together: they must agree on bodies, stimuli, sensor
    noise and drift; the locked share spans all of theirs; the clean share is the
    largest; the mix of bodies may differ (the proportion and preset jitters are the
    largest, the TIP and preset shares the first set's: they say how bodies were drawn,
    not a range a recording is checked against); a later set may draw its tilt
    amplitudes over a range that overlaps the first set's (the merged range, which
    recordings are checked against, stays the first set's: what lies beyond it is a
    training margin)."""
    scopes = [UniversalScope.from_dict(d.manifest["config"]["scope"]) for d in sets]
    first = scopes[0]
    families = {s.noise_families for s in scopes if s.noise_families}
    if len(families) > 1:
        raise DatasetError(f"{', '.join(str(d.path) for d in sets)}: sets that draw noise "
                           "families must draw the same ones, in the same order; these draw "
                           + "; ".join(", ".join(f) for f in sorted(families)))
    for data, scope in zip(sets[1:], scopes[1:], strict=True):
        for name in _FOCUS_FIELDS:
            (lo, hi), (first_lo, first_hi) = getattr(scope, name), getattr(first, name)
            if hi < first_lo or lo > first_hi:
                raise DatasetError(
                    f"{data.path}: scope field {name} is {(lo, hi)}, apart from "
                    f"{sets[0].path}'s {(first_lo, first_hi)}; a later set's range must "
                    "overlap the first set's")
        for name in UniversalScope.__dataclass_fields__:
            if name not in _SWAY_FIELDS + _MIX_FIELDS + _FOCUS_FIELDS and \
                    getattr(scope, name) != getattr(first, name):
                raise DatasetError(
                    f"{data.path}: scope field {name} is {getattr(scope, name)}, but "
                    f"{sets[0].path} has {getattr(first, name)}; sets trained on together "
                    "may differ only in their motor noise (clean_share, locked_share, "
                    "noise_families), "
                    "their mix of bodies (proportion_jitter, tip_share, preset_share, "
                    "preset_jitter) and "
                    "an overlapping amplitude_deg")
    return replace(first,
                   noise_families=next(iter(families), ()),
                   proportion_jitter=max(s.proportion_jitter for s in scopes),
                   preset_jitter=max(s.preset_jitter for s in scopes),
                   clean_share=max(s.clean_share for s in scopes),
                   locked_share=(min(s.locked_share[0] for s in scopes),
                                 max(s.locked_share[1] for s in scopes)))
