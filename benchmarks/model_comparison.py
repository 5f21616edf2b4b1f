"""DEC or IC: does ``posture-id compare`` prefer the model that made the recording?

Run:  .venv/bin/python benchmarks/model_comparison.py [--per-model 30] [--workers 2]
                                                      [--out docs/results/model_comparison]

``--per-model`` recordings of each model (docs/model.md §8), made by the project's simulators,
each compared as ``posture-id compare REC --body URDF`` compares it
(:func:`~posture_id.comparison.models.compare_models`, the held-out cycle included where there
are three or more cycles):

- bodies: Winter bodies of 1 and 2 segments (1.75 m, 70 kg), in turn (the IC model sees
  only the COM: the 2-segment body is as much as the comparison needs;
  ``benchmarks/compare_speed.py`` times 3-segment comparisons, ``benchmarks/ic_recovery.py``
  covers 3-segment IC fits);
- stimuli: the 242-state PRTS ×2 and the 80-state PRTS ×6 in turn, 0.5–2° peak to peak
  (one amplitude);
- DEC parameters from docs/model.md §5's prior; IC parameters drawn around the literature's
  (Kp 1.3–2.5·m·g·h, Kd 0.25–0.6·m·g·h·s, Δ 0.08–0.22 s, W 0.2–0.9, G 0–0.5, τ_f 5–40 s),
  redrawn until the closed loop is stable and the body stays up;
- sway: half clean (0.02° sensor noise), half people-like (motor noise leaving 15–40 % of
  the body COM sway locked, 0.05° sensor noise);
- a third of the subjects recorded at two amplitudes (1° and 3°; ``compare --second``): DEC
  with one set of parameters, the IC subject re-weighting (its W 0.1–0.3 lower at 3°),
  compared with a W per amplitude.

Writes ``report.md`` (the share preferring the right model, the wrong one and undecided,
by model and by sway) and ``rows.json``; a journal makes an interrupted run resumable.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
URDFS = [ROOT / "urdf" / f"winter_1.75m_70kg_{n}seg.urdf" for n in (1, 2)]
JOURNAL = "model_comparison.journal"
SEED = 8088


def _case(k: int) -> dict:
    """Recording k: its model, body, stimulus, sway and truth, then the comparison."""
    from posture_id import load_body
    from posture_id.comparison.models import compare_amplitudes, compare_models
    from posture_id.dec.prior import sample_parameters
    from posture_id.errors import SimulationError
    from posture_id.models.ic import IcPlant
    from posture_id.models.ic.subjects import draw_ic_parameters, ic_recording
    from posture_id.simulation.batch import simulate
    from posture_id.simulation.stimulus import prts
    from posture_id.simulation.subjects import people_like
    from posture_id.trials import prepare_trial

    rng = np.random.default_rng([SEED, k])
    model = "dec" if k % 2 == 0 else "ic"
    j = k // 2
    urdf = URDFS[j % len(URDFS)]
    body = load_body(urdf)
    states, cycles = ((242, 2), (80, 6))[(j // len(URDFS)) % 2]
    people = j % 2 == 1
    two = j % 3 == 2  # a third of the recordings: two amplitudes, 1° and 3°
    amplitudes = (1.0, 3.0) if two else (float(rng.uniform(0.5, 2.0)),)
    stimuli = [prts(a, cycles, states) for a in amplitudes]
    share = float(rng.uniform(0.15, 0.4)) if people else None
    recordings = []
    if model == "dec":
        while True:  # a subject who falls, or whose noise topples them, is drawn again
            params = sample_parameters(body, 1, rng).trial(0, body.joint_names)
            if not all(simulate(body, params, s).stable for s in stimuli):
                continue
            try:
                recordings = [
                    people_like(body, params, s, share, SEED + 100 * k + p).recording
                    if people else simulate(body, params, s).to_recording()
                    .with_sensor_noise(0.02, SEED + 100 * k + p)
                    for p, s in enumerate(stimuli)]
            except SimulationError:
                continue
            break
    else:
        plant = IcPlant.of(body)
        while True:  # a subject whose noise topples them is drawn again
            params = draw_ic_parameters(rng, plant)
            # with two amplitudes, the IC subject re-weights: W falls at the larger tilt
            ws = (params.w, max(0.0, params.w - rng.uniform(0.1, 0.3))) if two else (
                params.w,)
            recordings = [ic_recording(body, params.replace(w=w), s, share,
                                       SEED + 100 * k + p, 0.05 if people else 0.02)[0]
                          for p, (s, w) in enumerate(zip(stimuli, ws, strict=True))]
            if all(np.all(np.isfinite(r.theta)) for r in recordings):
                break
    trials = [prepare_trial(r, s) for r, s in zip(recordings, stimuli, strict=True)]
    started = time.perf_counter()
    if two:
        result = compare_amplitudes(trials, body)
        held = None
    else:
        result = compare_models(trials[0], body)
        held = result.held_out
    return {"k": k, "model": model, "body": urdf.stem, "states": states, "cycles": cycles,
            "amplitudes_deg": list(amplitudes), "sway": "people-like" if people else "clean",
            "locked_share": share, "preferred": result.preferred,
            "delta_bic_ic_minus_dec": result.bic["ic"] - result.bic["dec"],
            "held_out": held, "within_noise": result.within_noise,
            "w_by_part": list(result.fits["ic"].w_by_part) if two else None,
            "seconds": time.perf_counter() - started}


def _report(rows: list[dict], command: str) -> str:
    lines = ["# DEC or IC: the comparison on recordings of each model", "",
             f"Made by `{command}` ({len(rows)} recordings; the module doc of "
             "`benchmarks/model_comparison.py` says how they are made).", "",
             "| made by | sway | amplitudes | recordings | right | wrong | undecided |",
             "|---|---|---|---|---|---|---|"]
    def amplitudes(r: dict) -> str:
        return "two" if len(r["amplitudes_deg"]) == 2 else "one"

    for model in ("dec", "ic"):
        for sway, amps in (("clean", "one"), ("clean", "two"), ("people-like", "one"),
                           ("people-like", "two"), ("all", "all")):
            mine = [r for r in rows if r["model"] == model and sway in ("all", r["sway"])
                    and amps in ("all", amplitudes(r))]
            if not mine:
                continue
            right = sum(r["preferred"] == model for r in mine)
            undecided = sum(r["preferred"] == "undecided" for r in mine)
            wrong = len(mine) - right - undecided
            lines.append(f"| {model.upper()} | {sway} | {amps} | {len(mine)} | "
                         f"{right} ({100 * right / len(mine):.0f} %) | "
                         f"{wrong} ({100 * wrong / len(mine):.0f} %) | "
                         f"{undecided} ({100 * undecided / len(mine):.0f} %) |")
    wrong = [r for r in rows if r["preferred"] not in (r["model"], "undecided")]
    right = sum(r["preferred"] == r["model"] for r in rows)
    undecided = sum(r["preferred"] == "undecided" for r in rows)
    lines += ["", f"In all: {right} right, {len(wrong)} wrong "
              f"({100 * len(wrong) / max(len(rows), 1):.1f} %), {undecided} undecided. "
              f"Median time per comparison: "
              f"{np.median([r['seconds'] for r in rows]):.0f} s (both fits, and the two "
              "held-out fits where there are 6 cycles).", "",
              "| k | made by | body | stimulus | sway | ΔBIC (IC − DEC) | held-out χ²/dof "
              "DEC, IC | IC's W by part | preferred |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        held = ("–" if r["held_out"] is None else
                f"{r['held_out']['dec']:.2f}, {r['held_out']['ic']:.2f}")
        amps = " + ".join(f"{a:.2f}" for a in r["amplitudes_deg"])
        w = "–" if not r["w_by_part"] else ", ".join(f"{x:.2f}" for x in r["w_by_part"])
        lines.append(f"| {r['k']} | {r['model'].upper()} | {r['body']} | PRTS {r['states']}"
                     f"×{r['cycles']}, {amps}° | {r['sway']} | "
                     f"{r['delta_bic_ic_minus_dec']:.1f} | {held} | {w} | {r['preferred']} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--per-model", type=int, default=30)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, default=ROOT / "docs/results/model_comparison")
    args = parser.parse_args(argv)
    from posture_id.fileio import atomic_write_text, json_text

    args.out.mkdir(parents=True, exist_ok=True)
    journal = args.out / JOURNAL
    done = {}
    if journal.exists():
        for line in journal.read_text().splitlines():
            row = json.loads(line)
            done[row["k"]] = row
    todo = [k for k in range(2 * args.per_model) if k not in done]
    with ProcessPoolExecutor(args.workers) as pool:
        for row in pool.map(_case, todo):
            done[row["k"]] = row
            with journal.open("a") as out:
                out.write(json.dumps(row) + "\n")
            print(f"[{len(done)}/{2 * args.per_model}] {row['model']} {row['body']} "
                  f"{row['sway']}: {row['preferred']} ({row['seconds']:.0f} s)",
                  file=sys.stderr, flush=True)
    rows = [done[k] for k in sorted(done)]
    command = ".venv/bin/python benchmarks/model_comparison.py"
    atomic_write_text(args.out / "report.md", _report(rows, command))
    atomic_write_text(args.out / "rows.json", json_text(rows))
    journal.unlink()
    print(f"wrote {args.out / 'report.md'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
