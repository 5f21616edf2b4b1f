"""What the typicality score catches: people-like subjects as recorded and mistaken.

Run:  .venv/bin/python benchmarks/typicality_power.py [--out docs/results/typicality_power.md]

For people-like subjects (30 % of the body sway locked, the body's default gains) of the
default TIP, a Winter 3-segment body and the bent TALOS, under two cycles of the 242-state
PRTS and six of the 80-state one, each recording as recorded and with one mistake made to
it, the bundled universal network's typicality p (``posture_id/learning/universal/
typicality.py``; doubted below 0.001). The mistakes: the angles 5 and 10 times too large
(a file in other units), the middle segment's column in radians among degrees, the top
segment's channel dead (zero), the bottom segment's column negated, the bottom and top
columns exchanged, the sway time-reversed, and noise alone (a random walk, no response).
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np

from posture_id import load_body
from posture_id.dec.parameters import default_parameters
from posture_id.fileio import atomic_write_text
from posture_id.learning.typicality import ATYPICAL_P
from posture_id.learning.universal_identifier import UniversalIdentifier
from posture_id.simulation import prts
from posture_id.simulation.subjects import people_like
from posture_id.trials import prepare_trial

ROOT = Path(__file__).resolve().parents[1]
BODIES = (("TIP", None), ("Winter 3-seg", ROOT / "urdf" / "winter_1.75m_70kg_3seg.urdf"),
          ("TALOS (bent)", ROOT / "urdf" / "talos_tip.urdf"))
STIMULI = (("242 × 2", prts(states=242, cycles=2)), ("80 × 6", prts(states=80, cycles=6)))


def mistakes(theta: np.ndarray, seed: int) -> dict[str, np.ndarray]:
    """(name, angles) of the recording as recorded and of each mistake; ``theta`` (S, N) rad."""
    out = {"as recorded": theta, "angles ×5": 5 * theta, "angles ×10": 10 * theta}
    middle = theta.copy()
    middle[:, theta.shape[1] // 2] /= np.degrees(1.0)
    out["a column in radians"] = middle
    dead = theta.copy()
    dead[:, -1] = 0.0
    out["top channel dead"] = dead
    negated = theta.copy()
    negated[:, 0] *= -1
    out["bottom column negated"] = negated
    out["bottom and top exchanged"] = theta[:, ::-1].copy()
    out["time-reversed"] = theta[::-1].copy()
    walk = np.cumsum(np.random.default_rng(seed).standard_normal(theta.shape), axis=0)
    out["noise alone"] = np.radians(0.3) * walk / np.sqrt(len(theta))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path,
                        default=ROOT / "docs" / "results" / "typicality_power.md")
    args = parser.parse_args()
    p: dict[str, list[float]] = {}
    for name, urdf in BODIES:
        body = load_body() if urdf is None else load_body(urdf)
        identifier = UniversalIdentifier.bundled(body)
        for k, (_, stimulus) in enumerate(STIMULI):
            seed = 1 + k
            rec = people_like(body, default_parameters(body), stimulus, 0.3, seed=seed).recording
            for mistake, theta in mistakes(rec.theta, seed).items():
                answer = identifier.identify(prepare_trial(replace(rec, theta=theta)))
                p.setdefault(mistake, []).append(answer.typicality.p)
            print(f"{name}, {STIMULI[k][0]}: done", flush=True)
    columns = [f"{b}, {s}" for b, _ in BODIES for s, _ in STIMULI]
    lines = ["# What the typicality score catches", "",
             "Made by `.venv/bin/python benchmarks/typicality_power.py` (what it does: its "
             f"docstring). Each cell: the recording's typicality p (doubted below "
             f"{ATYPICAL_P:g}; the smallest p the bundled reference gives is "
             f"{min(min(v) for v in p.values()):.4f}).", "",
             "| recording | " + " | ".join(columns) + " | doubted |",
             "|---|" + "---|" * (len(columns) + 1)]
    for mistake, values in p.items():
        doubted = sum(v < ATYPICAL_P for v in values)
        lines.append(f"| {mistake} | " + " | ".join(f"{v:.4f}" for v in values)
                     + f" | {doubted} of {len(values)} |")
    text = "\n".join(lines) + "\n"
    atomic_write_text(args.out, text)
    print(text)


if __name__ == "__main__":
    main()
