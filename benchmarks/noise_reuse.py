"""What drawing a trial's motor noise once saves when making universal shards.

Run:  .venv/bin/python benchmarks/noise_reuse.py [--set data/universal_people] [--shards 20]

A universal shard simulates every noisy trial twice with the same noise seed (a unit
level, then the level that gives the drawn locked share; ``motor_levels_for_share``),
and :func:`posture_id.simulation.noise.motor_noise_torques` keeps each seed's unit noise
so it is drawn once. This makes ``--shards`` shards of the set's own configuration twice
each, alternately with the kept noise and with it drawn afresh every time (the same
function unwrapped), in one process, and prints both totals and their ratio. The shards
are the same bytes either way (the set's manifest holds their SHA-256).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import posture_id.simulation.noise as noise_module
from posture_id.learning.data.drawn import UniversalDataConfig, make_shard
from posture_id.learning.data.scope import UniversalScope
from posture_id.simulation.options import SimulationOptions


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--set", type=Path, default=Path("data/universal_people"))
    parser.add_argument("--shards", type=int, default=20)
    args = parser.parse_args()
    config = json.loads((args.set / "manifest.json").read_text())["config"]
    data = UniversalDataConfig(shards=10**6, trials=config["trials"], seed=config["seed"],
                               scope=UniversalScope.from_dict(config["scope"]),
                               simulation=SimulationOptions(**config["simulation"]))
    kept = noise_module._unit_noise
    ways = {"kept": kept, "drawn twice": kept.__wrapped__}
    make_shard(data, 100)  # compiled kernels warm
    seconds = {name: 0.0 for name in ways}
    try:
        for k in range(101, 101 + args.shards):
            order = list(ways) if k % 2 else list(reversed(ways))
            for name in order:
                noise_module._unit_noise = ways[name]
                kept.cache_clear()
                started = time.perf_counter()
                make_shard(data, k)
                seconds[name] += time.perf_counter() - started
    finally:
        noise_module._unit_noise = kept
    for name, total in seconds.items():
        print(f"{name}: {total:.1f} s for {args.shards} shards")
    print(f"drawn twice / kept: {seconds['drawn twice'] / seconds['kept']:.3f}")


if __name__ == "__main__":
    main()
