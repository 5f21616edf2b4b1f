"""Which network of the bundled model answers which sway: the noise gate's share on the
table's trials and on the noise-family set's held-out shards.

Run:  .venv/bin/python benchmarks/gate_shares.py [--cache data/table_cells]
                                                 [--families data/universal_families]

For each module sample, the coloured-noise network's share w of the answer
(:meth:`posture_id.learning.noise_gate.NoiseGate.coloured_share`, the bundled model's
gate) from the sample's noise ratio and colour, as the identifier measures them. Prints,
per kind of sway, how many samples go to the white-noise network alone (w = 0), to the
coloured-noise one alone (w = 1) and between, the mean w, and the noise colour's and
ratio's quantiles (on the table, also the ratio of the samples whose noise reads
coloured). The table's cells: ``posture-id network universal table --trials 2048 --cache
data/table_cells`` (its clean and low-pass people-like sway); the family set: ``make
noise-families`` (its test split, per family, clean and noisy trials apart).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from posture_id.learning.calibration import COLOUR_EDGE
from posture_id.learning.data.drawn import merged_scope, open_sets
from posture_id.learning.data.scope import UniversalScope
from posture_id.learning.universal_model import UniversalModel
from posture_id.learning.universal_samples import load_split, make_samples
from posture_id.studies.universal_table import cached_samples

BUNDLED = Path("posture_id/learning/models/universal")


def _line(name: str, w: np.ndarray, colour: np.ndarray, ratio: np.ndarray) -> str:
    return (f"{name:28s} {len(w):7d} samples: white alone {100 * np.mean(w == 0):5.1f} %, "
            f"coloured alone {100 * np.mean(w == 1):5.1f} %, between "
            f"{100 * np.mean((w > 0) & (w < 1)):4.1f} %, mean w {w.mean():.3f}; colour "
            f"5/50/95 % {np.round(np.quantile(colour, [0.05, 0.5, 0.95]), 2).tolist()}, "
            f"ratio {np.round(np.quantile(ratio, [0.05, 0.5, 0.95]), 4).tolist()}")


def _table(gate, scope: UniversalScope, cache: Path, trials: int) -> None:
    found: dict[str, list[np.ndarray]] = {}
    for (_family, _stimulus, sway), samples in cached_samples(cache, trials, scope):
        found.setdefault(sway, []).append(np.column_stack([samples.noise_colour,
                                                           samples.noise_ratio]))
    for sway, parts in found.items():
        both = np.concatenate(parts)
        w = gate.coloured_share(both[:, 1], both[:, 0])
        print(_line(f"table, {sway}", w, both[:, 0], both[:, 1]))
        coloured = both[both[:, 0] > COLOUR_EDGE, 1]
        if len(coloured):
            print(f"{'':28s} {len(coloured):7d} of them coloured (above {COLOUR_EDGE:g}): "
                  f"their ratio 50/90 % {np.round(np.quantile(coloured, [0.5, 0.9]), 4).tolist()}")


def _families(gate, path: Path) -> None:
    sets = open_sets([path])
    shards = load_split(sets, "test")
    scope = merged_scope(sets)
    samples = make_samples(shards, scope, np.random.default_rng(0))
    family = np.concatenate([np.repeat(s.arrays["noise_family"], s.n_segments)
                             for s in shards])
    clean = np.concatenate([np.repeat(s.arrays["motor_noise_deg"] == 0, s.n_segments)
                            for s in shards])
    w = gate.coloured_share(samples.noise_ratio, samples.noise_colour)
    names = scope.noise_families  # a trial's family: its index in the set's scope
    for k in np.unique(family):
        for is_clean, what in ((True, "clean"), (False, "noisy")):
            sel = (family == k) & (clean == is_clean)
            if sel.any():
                print(_line(f"{names[int(k)]}, {what}", w[sel],
                            samples.noise_colour[sel], samples.noise_ratio[sel]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", type=Path, default=BUNDLED)
    parser.add_argument("--cache", type=Path, default=Path("data/table_cells"))
    parser.add_argument("--trials", type=int, default=2048)
    parser.add_argument("--families", type=Path, default=Path("data/universal_families"))
    args = parser.parse_args()
    model = UniversalModel.load(args.model)
    if model.gate is None:
        raise SystemExit(f"{args.model}: not gated by the noise")
    _table(model.gate, model.scope, args.cache, args.trials)
    _families(model.gate, args.families)


if __name__ == "__main__":
    main()
