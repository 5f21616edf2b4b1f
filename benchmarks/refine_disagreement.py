"""Does least squares tell a wrong network answer on people-like sway from a right one?

Run:  .venv/bin/python benchmarks/refine_disagreement.py [--subjects 8] [--workers 2]

The people-like subjects of ``benchmarks/honest_verdict.py`` (the same seed and draws:
every noise family, 15–40 % of the sway locked, 1–3-segment bodies, both PRTSs), each
identified by the network alone (``--method cnn``) and then by the locked fit from the
network's answer with its calibrated spread as the prior (what ``auto`` runs on
people-like sway that falls or leaves more than the noise). The network's answer is judged
as ``honest_verdict.py`` judges it (right: every class right and every truth inside its
90 % interval; wrong: a class wrong or a Kp farther from the truth than twice its
interval's half-width), and so is the refined one. Candidate signs of a wrong network
answer, counted among the wrong and the right ones: the refinement flips a class; it
moves a Kp by more than the network's interval half-width; the network is unsure of a
class (P(com) within 0.05–0.95); any of them. Writes docs/results/refine_disagreement/
report.md and rows.json.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import honest_verdict  # noqa: E402  (the same subjects)

from posture_id.dec.parameters import TARGET_FIELDS  # noqa: E402
from posture_id.executors import LocalExecutor  # noqa: E402
from posture_id.fileio import atomic_write_text, json_text  # noqa: E402
from posture_id.simulation.noise_families import NoiseFamily  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
UNSURE = (0.05, 0.95)


def _judge(result, truth, body) -> tuple[str, np.ndarray]:
    """(right | wrong | neither, (N, 4) the answer in SI units)."""
    iv = result.intervals
    true = np.array([[getattr(truth[j], f) for f in TARGET_FIELDS] for j in body.joint_names])
    found = np.array([[getattr(result.parameters[j], f) for f in TARGET_FIELDS]
                      for j in body.joint_names])
    classes = all(result.parameters[j].controls == truth[j].controls for j in body.joint_names)
    half = (iv.upper_si - iv.lower_si) / 2
    if not classes or np.any(np.abs(found[:, 0] - true[:, 0]) > 2 * half[:, 0]):
        return "wrong", found
    inside = (iv.lower_si <= true) & (true <= iv.upper_si)
    return ("right" if inside.all() else "neither"), found


def _one(task: tuple[str, int]) -> dict | None:
    from posture_id.frf.locked import LockedOptions
    from posture_id.identify import Identifier, Method
    from posture_id.identify.core import network_prior

    family, index = task
    made = honest_verdict._recording("people-like", family, index)
    if made is None:
        return None
    recording, body, truth, stimulus, _ = made
    network = Identifier(body, Method.CNN).identify(recording, stimulus)
    hybrid = Identifier(body, Method.HYBRID)
    hybrid.fit_options = replace(hybrid.fit_options, locked=LockedOptions(),
                                 **network_prior(network, 0.9))
    began = time.perf_counter()
    refined = hybrid.identify(recording, stimulus)
    judged, found = _judge(network, truth, body)
    judged_refined, found_refined = _judge(refined, truth, body)
    half = (network.intervals.upper_si - network.intervals.lower_si) / 2
    return {"family": family, "index": index, "segments": body.n_segments,
            "network": judged, "refined": judged_refined,
            "class_flipped": [network.parameters[j].controls != refined.parameters[j].controls
                              for j in body.joint_names],
            "kp_moved": (np.abs(found_refined[:, 0] - found[:, 0]) / half[:, 0]).tolist(),
            "p_com": [float(p) for p in network.class_probability],
            "refined_fell": bool(refined.fell), "seconds": time.perf_counter() - began}


SIGNS = {
    "the refinement flips a class": lambda r: any(r["class_flipped"]),
    "it moves a Kp beyond the network's half-width": lambda r: any(m > 1 for m in r["kp_moved"]),
    "the network is unsure of a class": lambda r: any(UNSURE[0] < p < UNSURE[1]
                                                      for p in r["p_com"]),
}


def report(rows: list[dict], subjects: int) -> str:
    def count(rows_, key):
        from collections import Counter

        return Counter(r[key] for r in rows_)

    network, refined = count(rows, "network"), count(rows, "refined")
    lines = [
        "# Does least squares tell a wrong network answer from a right one?",
        "",
        f"Made by `.venv/bin/python benchmarks/refine_disagreement.py --subjects {subjects}`: "
        f"{len(rows)} people-like subjects ({subjects} per noise family, "
        "`benchmarks/honest_verdict.py`'s draws), each by the network alone and by the locked "
        "fit from its answer with its calibrated spread as the prior.",
        "",
        "| answer | right | neither | wrong |",
        "|---|---|---|---|",
        f"| the network's | {network['right']} | {network['neither']} | {network['wrong']} |",
        f"| refined by least squares | {refined['right']} | {refined['neither']} | "
        f"{refined['wrong']} |",
        "",
        "| sign of a wrong network answer | wrong answers showing it | right answers showing it |",
        "|---|---|---|",
    ]
    wrong = [r for r in rows if r["network"] == "wrong"]
    right = [r for r in rows if r["network"] == "right"]
    signs = {**SIGNS, "any of them": lambda r: any(s(r) for s in SIGNS.values())}
    for name, sign in signs.items():
        lines.append(f"| {name} | {sum(map(sign, wrong))} of {len(wrong)} | "
                     f"{sum(map(sign, right))} of {len(right)} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", type=int, default=8, help="per noise family")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "results" /
                        "refine_disagreement")
    args = parser.parse_args()
    tasks = [(f.value, i) for f in NoiseFamily for i in range(args.subjects)]
    rows = []
    with LocalExecutor(args.workers, processes=True) as executor:
        for _, row in executor.unordered(_one, tasks):
            if row is not None:
                rows.append(row)
                print(f"{row['family']} {row['index']}: network {row['network']}, refined "
                      f"{row['refined']}", flush=True)
    rows.sort(key=lambda r: (r["family"], r["index"]))
    args.out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(args.out / "rows.json", json_text({"subjects": args.subjects,
                                                         "rows": rows}))
    text = report(rows, args.subjects)
    atomic_write_text(args.out / "report.md", text)
    print(text)


if __name__ == "__main__":
    main()
