"""The universal network over body families × stimuli × clean and people-like sway, on
trials simulated for the table alone (their own seeds: no training trial is among them).

Families: Winter 1-, 2- and 3-segment bodies (:data:`BODIES_PER_CELL` bodies per cell,
height and mass drawn from the scope's ranges, Winter's proportions, each with an equal
share of the cell's trials: a cell scores the family, not one body of it), the default TIP
and lumped TALOS (3 segments).
Stimuli: the 242-state PRTS ×2 (121 s) and the 80-state PRTS ×6 (120 s), 0.25 s states,
at 0.5, 1 and 3° peak to peak. Sway: clean (sensor noise uniform in 0–0.1°, no motor
noise) and people-like (motor noise leaving 15–40 % of the body COM sway locked, sensor
noise 0.02–0.1°, drift up to 0.5° per minute).

With ``cache`` the simulated cells are kept (one file per cell, with what made it) and a
run again with the same trials and scope reads them: an interrupted table resumes, and
another model is scored on the very same trials. A folder holding cells made otherwise
(other trials, seed, bodies per cell or scope) is refused before anything is simulated,
as a set's folder is: its cells took half an hour and are not overwritten. Like a set's
shards, a kept cell does not notice a change of the simulator's code: delete the folder
after one.
"""

from __future__ import annotations

import itertools
import json
import zipfile
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from posture_id.executors import executor_for
from posture_id.fileio import Result, atomic_write_text, json_text
from posture_id.learning.calibration import UniversalCalibration
from posture_id.learning.data.drawn import simulate_trials
from posture_id.learning.data.scope import BodyDraw, StimulusDraw, UniversalScope
from posture_id.learning.data.store import save_npz
from posture_id.learning.data.trial_config import DatasetError
from posture_id.learning.evaluation import GroupScore, plot_scores, score_samples
from posture_id.learning.universal_model import UniversalModel
from posture_id.learning.universal_samples import LoadedShard, Samples, make_samples
from posture_id.progress import Progress, report

__all__ = ["FAMILIES", "STIMULI", "SWAY", "FamilyTable", "family_table", "table_scope",
           "TABLE_SEED", "BODIES_PER_CELL", "cell_samples", "cached_samples"]

TABLE_SEED = 0x544142
#: Winter bodies drawn per cell (the TIP and TALOS are one body each).
BODIES_PER_CELL = 64
FAMILIES = ("Winter 1-seg", "Winter 2-seg", "Winter 3-seg", "TIP", "TALOS 3-seg")
STIMULI = tuple((states, cycles, amp) for states, cycles in ((242, 2), (80, 6))
                for amp in (0.5, 1.0, 3.0))
SWAY = {
    "clean": dict(clean_share=1.0, sensor_noise_deg=(0.0, 0.1), drift_deg=(0.0, 0.0)),
    "people-like": dict(clean_share=0.0, locked_share=(0.15, 0.4),
                        sensor_noise_deg=(0.02, 0.1), drift_deg=(0.0, 0.5)),
}


def _body(family: str, rng: np.random.Generator, scope: UniversalScope) -> BodyDraw:
    if family == "TIP":
        return BodyDraw("tip", 3)
    if family.startswith("TALOS"):
        return BodyDraw("talos", 3)
    n = int(family.split()[1][0])
    return BodyDraw("winter", n, float(rng.uniform(*scope.heights_m)),
                    float(rng.uniform(*scope.masses_kg)), ((1.0, 1.0),) * n)


#: Per-trial arrays of :func:`~.data.simulate_trials` (the rest is shared by the cell).
_PER_TRIAL = ("y", "y_locked", "targets", "locked_share", "motor_noise_deg", "kp", "ki", "kd",
              "delay_s", "sign", "kpas", "bpas")
#: Batches of ``trials`` drawn at most, until ``trials`` of them stay up.
_MAX_BATCHES = 8


def _group(body: BodyDraw, stimulus: StimulusDraw, trials: int, scope: UniversalScope,
           rng: np.random.Generator) -> dict:
    """``trials`` of one body: batches drawn until ``trials`` stay up (a lumped robot falls
    under many prior draws), cut to ``trials``."""
    batches = []
    while sum(int(b["kept"]) for b in batches) < trials and len(batches) < _MAX_BATCHES:
        batches.append(simulate_trials(body, stimulus, trials, scope, rng))
    out = dict(batches[0])
    for key in (*_PER_TRIAL, *(("noise_family",) if "noise_family" in out else ())):
        out[key] = np.concatenate([b[key] for b in batches])[:trials]
    out["simulated"] = np.array(trials * len(batches))
    out["kept"] = np.array(len(out["targets"]))
    return out


def _cell(index: int, trials: int, scope_dict: dict, seed: int = TABLE_SEED,
          bodies_per_cell: int = BODIES_PER_CELL) -> list[dict]:
    """One cell's trials, one dict per body (``bodies_per_cell`` for a Winter family,
    their trials split evenly; one for the TIP and TALOS), drawn from ``seed``."""
    family, (states, cycles, amp), sway = list(_cells())[index]
    scope = replace(UniversalScope.from_dict(scope_dict), **SWAY[sway])
    rng = np.random.default_rng(np.random.SeedSequence([seed, index]))
    stimulus = StimulusDraw(states, 0.25, amp, cycles)
    bodies = min(bodies_per_cell, trials) if family.startswith("Winter") else 1
    sizes = np.diff(np.linspace(0, trials, bodies + 1).round().astype(int))
    return [_group(_body(family, rng, scope), stimulus, int(size), scope, rng)
            for size in sizes]


def table_scope(model_scope: UniversalScope) -> UniversalScope:
    """The scope a table's cells are drawn from: the model's, without its noise families.
    A table's sway is its own (:data:`SWAY`: clean, and people-like under the low-pass
    motor noise), whatever noise the model was trained under, so that two models are
    tabled on the very same trials (and a model trained over noise families is not
    judged on sway it alone was trained for)."""
    return replace(model_scope, noise_families=())


def _cache_key(trials: int, scope: UniversalScope, seed: int = TABLE_SEED,
               bodies_per_cell: int = BODIES_PER_CELL) -> str:
    """What a cached cell was made with: a folder of cells made otherwise is refused."""
    return json_text({"seed": seed, "trials": trials, "bodies": bodies_per_cell,
                      "scope": scope.to_dict()})


class TableCacheError(DatasetError):
    """A table's cache folder holds cells made with other arguments."""


def _describe(made: dict) -> str:
    seed = "the default seed" if made["seed"] == TABLE_SEED else f"seed {made['seed']}"
    return f"{made['trials']} trials per cell, {seed}, {made['bodies']} bodies per Winter cell"


def _mismatch(path: Path, made_key: str, key: str) -> TableCacheError:
    made, asked = json.loads(made_key), json.loads(key)
    scope = " and another scope" if made["scope"] != asked["scope"] else ""
    return TableCacheError(
        f"{path}: a table cell made with {_describe(made)}{scope}; this table asks for "
        f"{_describe(asked)}. Give another --cache folder, or delete {path.parent} to make "
        "its cells again (it is not overwritten)")


def _cell_file(cache: str | Path, index: int) -> Path:
    """Where cell ``index`` is kept in the folder ``cache``."""
    return Path(cache) / f"cell-{index:02d}.npz"


def _save_cell(path: Path, groups: list[dict], key: str) -> None:
    arrays = {f"{j}/{name}": value for j, group in enumerate(groups)
              for name, value in group.items()}
    save_npz(path, {**arrays, "made_with": np.array(key)})


def _load_cell(path: Path, key: str) -> list[dict] | None:
    """The cached cell at ``path``, or None if there is none (or only a truncated or
    foreign file). Raises :class:`TableCacheError` for a cell made otherwise than
    ``key`` says."""
    if not path.exists():
        return None
    try:
        with np.load(path, allow_pickle=False) as z:
            if str(z["made_with"]) != key:
                raise _mismatch(path, str(z["made_with"]), key)
            groups: dict[int, dict] = {}
            for name in z.files:
                if name != "made_with":
                    j, field = name.split("/", 1)
                    groups.setdefault(int(j), {})[field] = z[name]
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
        # a truncated or foreign file: the cell is made again
        return None
    return [groups[j] for j in sorted(groups)]


def _cells():
    return itertools.product(FAMILIES, STIMULI, SWAY)


def _stimulus_label(states: int, cycles: int, amp: float) -> str:
    return f"{states}×{cycles}, {amp:g}°"


@dataclass(frozen=True)
class FamilyTable(Result):
    """Scores per (family, stimulus, sway) cell."""

    cells: dict
    bodies_per_cell: int = BODIES_PER_CELL

    def to_dict(self) -> dict:
        return {" | ".join(k): v.to_dict() for k, v in self.cells.items()}

    def markdown(self) -> str:
        lines = ["# The universal model over body families, stimuli and sway", "",
                 "Made by `posture-id network universal table` "
                 "(posture_id.studies.universal_table: trials simulated for the table alone, "
                 "their own seeds). A Winter cell's "
                 f"trials are spread over {self.bodies_per_cell} bodies of the family drawn from "
                 "the scope's heights and masses (table.json names them). Clean: sensor "
                 "noise 0–0.1°, no motor noise. People-like: motor noise leaving 15–40 % of "
                 "the body COM sway locked, sensor noise 0.02–0.1°, drift up to 0.5° per "
                 "minute. Errors: median |identified / true − 1| per module, from the ankle "
                 "up.", "",
                 "| body | stimulus | sway | trials | classes % | all right % | Kp err % | "
                 "Kd err % | delay err % | 90 % coverage Kp / Ki / Kd / delay |",
                 "|" + "---|" * 10]
        for (family, stim, sway), s in self.cells.items():
            def per(name, s=s):
                return " / ".join(f"{m[name]:.1f}" for m in s.by_module)

            lines.append(f"| {family} | {stim} | {sway} | {s.trials} | {s.classes_pct:.1f} | "
                         f"{s.trials_all_right_pct:.0f} | {per('kp')} | {per('kd')} | "
                         f"{per('delay_s')} | {s.coverage_text} |")
        return "\n".join(lines)

    def summary(self) -> str:
        return self.markdown()

    def plot(self, path=None, ax=None):
        rows = [f"{f}, {s}" for f in FAMILIES for s in SWAY]
        columns = [_stimulus_label(*s) for s in STIMULI]
        values = np.full((3, len(rows), len(columns)), np.nan)
        for (family, stim, sway), s in self.cells.items():
            values[:, rows.index(f"{family}, {sway}"), columns.index(stim)] = s.grid_values()
        return plot_scores(rows, columns, values, 0.9, path, ax)


def cell_samples(index: int, groups: list[dict], scope: UniversalScope,
                 seed: int = TABLE_SEED, bodies_per_cell: int = BODIES_PER_CELL) -> Samples:
    """The module samples of cell ``index`` from its simulated ``groups`` (one per body):
    the sensor noise and drift of its sway drawn as the table draws them. ``scope``: the
    table's (:func:`table_scope`). A body none of whose trials stayed up (a lumped robot,
    or a Winter body given one trial) adds none."""
    sway = list(_cells())[index][2]
    shards = []
    for j, arrays in enumerate(groups):
        if int(arrays["kept"]) == 0:
            continue
        arrays["index"] = index * bodies_per_cell + j
        shards.append(LoadedShard.of(arrays))
    return make_samples(shards, replace(scope, **SWAY[sway]),
                        np.random.default_rng([seed, index]))


def cached_samples(cache: str | Path, trials: int, scope: UniversalScope,
                   seed: int = TABLE_SEED, bodies_per_cell: int = BODIES_PER_CELL):
    """((family, stimulus, sway), module samples) of every cell kept in ``cache`` by a
    table of ``trials`` per cell (:func:`family_table` with ``cache``), without a model.

    Raises:
        TableCacheError: a cell missing, or made with other arguments."""
    table = table_scope(scope)
    made_with = _cache_key(trials, table, seed, bodies_per_cell)
    for index, (family, stim, sway) in enumerate(_cells()):
        groups = _load_cell(_cell_file(cache, index), made_with)
        if groups is None:
            raise TableCacheError(f"{_cell_file(cache, index)}: no table cell there; make "
                                  f"them with posture-id network universal table --trials {trials} "
                                  f"--cache {cache}")
        yield ((family, _stimulus_label(*stim), sway),
               cell_samples(index, groups, table, seed, bodies_per_cell))


def family_table(model_dir: str | Path, out: str | Path, trials: int = 64,
                 workers: int | None = None, cache: str | Path | None = None,
                 progress: Progress | None = None, seed: int = TABLE_SEED,
                 bodies_per_cell: int = BODIES_PER_CELL) -> FamilyTable:
    """Simulate every cell (or read it from ``cache``), score the model there, write
    table.{md,json,png} to ``out``. ``seed`` draws the cells' bodies, parameters and
    noise: the default is the documented table's; another gives the same table on
    other trials. ``bodies_per_cell``: the Winter bodies a cell's trials are spread over."""
    model = UniversalModel.load(model_dir)
    calibration = UniversalCalibration.load(model_dir)
    scope = table_scope(model.scope)
    cells = list(_cells())
    made_with = _cache_key(trials, scope, seed, bodies_per_cell)
    files = [_cell_file(cache, i) if cache else None for i in range(len(cells))]
    if cache:
        Path(cache).mkdir(parents=True, exist_ok=True)
    results = {i: groups for i, f in enumerate(files)
               if f is not None and (groups := _load_cell(f, made_with)) is not None}
    todo = [i for i in range(len(cells)) if i not in results]
    report(progress, len(results), len(cells), "cell")
    if todo:
        executor = executor_for(None, workers, processes=True)
        try:
            for index, groups in executor.unordered(_cell, todo, trials, scope.to_dict(), seed,
                                                        bodies_per_cell):
                if files[index] is not None:
                    _save_cell(files[index], groups, made_with)
                results[index] = groups
                report(progress, len(results), len(cells), "cell")
        finally:
            executor.close()
    scores: dict[tuple[str, str, str], GroupScore] = {}
    bodies: dict[str, list[dict]] = {}
    for index, (family, stim, sway) in enumerate(cells):
        samples = cell_samples(index, results[index], scope, seed, bodies_per_cell)
        key = (family, _stimulus_label(*stim), sway)
        scores[key] = score_samples(model, samples, calibration)["all"]
        bodies[" | ".join(key)] = [json.loads(str(g["draw"]))["body"] for g in results[index]]
    table = FamilyTable(scores, bodies_per_cell)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "table.json", json_text({
        "model": str(model_dir), "weights_sha256": model.sidecar.get("weights_sha256"),
        "trials_per_cell": trials, "bodies_per_winter_cell": bodies_per_cell,
        **({"seed": seed} if seed != TABLE_SEED else {}),
        "cells": table.to_dict(), "bodies": bodies}))
    atomic_write_text(out / "table.md", table.markdown() + "\n")
    table.plot(out / "table.png")
    return table
