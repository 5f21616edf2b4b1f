"""Universal models on the test shards of one set, per body kind: how they do on bodies
of the set's own proportions.

Run:  .venv/bin/python benchmarks/universal_bodies.py SET MODEL [MODEL ...]

For example ``data/universal_varied`` (Winter segments ×U(0.65, 1.35), docs/universal.md)
against the bundled model (``bundled``) and one trained on that set too. Every model
reads the same test-split module samples (the checks' own noise seed,
:data:`~posture_id.studies.universal_check.TEST_SEED`); per body kind (Winter, TIP,
each lumped humanoid) and sway (people-like: under 60 % of the body COM sway locked, as
the check's), it prints the share of classes right and the median |Kp error|.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from posture_id.learning.data.drawn import open_sets
from posture_id.learning.universal_identifier import BUNDLED_DIR
from posture_id.learning.universal_model import UniversalModel
from posture_id.learning.universal_samples import load_split, make_samples
from posture_id.studies.universal_check import TEST_SEED

PEOPLE_LIKE_BELOW = 0.6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("set", type=Path)
    parser.add_argument("models", nargs="+", help="model directories, or 'bundled'")
    args = parser.parse_args()
    shards = load_split(open_sets([args.set]), "test")
    kind = {int(s.arrays["index"]): json.loads(str(s.arrays["draw"]))["body"]["kind"]
            for s in shards}
    models = {m: UniversalModel.load(BUNDLED_DIR if m == "bundled" else m)
              for m in args.models}
    test = make_samples(shards, next(iter(models.values())).scope,
                        np.random.default_rng(TEST_SEED))
    kinds = np.array([kind[int(s)] for s in test.shard])
    people = test.locked_share < PEOPLE_LIKE_BELOW
    truth_kp = test.targets[:, 0] + 1
    for name, model in models.items():
        pred = model.predict(test.inputs, test.noise_ratio, test.noise_colour)
        kp_error = 100 * np.abs((pred.mean[:, 0] + 1) / truth_kp - 1)
        right = (pred.logit > 0) == (test.targets[:, 4] > 0)
        print(name)
        for body in sorted(set(kinds.tolist())):
            for sway, sel in (("clean or part-locked", ~people), ("people-like", people)):
                group = (kinds == body) & sel
                if group.sum():
                    print(f"  {body:7s} {sway:21s} {int(group.sum()):6d} modules: classes "
                          f"{100 * right[group].mean():5.1f} %, Kp median "
                          f"{np.median(kp_error[group]):5.1f} %")


if __name__ == "__main__":
    main()
