"""The default command's timing of a tilt column off the sway's clock.

Run:  .venv/bin/python benchmarks/prts_timing.py [--recordings 24] [--controls 12]
      [--workers 2] [--seed 0]

Each recording is a simulated people-like subject recorded as a lab records the body COM
alone: a 1-segment Winter body (height 1.55–1.95 m, mass 50–100 kg), docs/model.md §5
parameters, the 80-state PRTS × 3 (1° peak to peak) started part-way into its sequence
(a state drawn from 0–80) after a level lead-in of 4.5–6 s and with 4.5–6 s of level
platform after it, motor noise scaled so that 25–40 % of the body COM sway is
stimulus-locked, 0.02° of sensor noise. Its tilt column is moved 1–4 s (either way, drawn)
off the sway's clock: the column says the platform moved later (or earlier) than it did.
The controls are the same with the column where the platform was.

Every recording goes through ``identify``'s default (``Method.AUTO``, the bundled
universal model), as ``posture-id identify FILE --body URDF`` runs it. Per recording: the
timing the answer is for (``stimulus_offset_s``) against the truth (minus the shift), the
verdict's level and whether it is within the noise or names the timing search
(``--max-offset-s``), and the time taken. Beside it, what the recording itself allows: the
true parameters' locked sway shifted over ±5 s against the recorded one (the weighted
distance least squares minimises), whose minimum is where even the right model puts the
timing (``ceiling_error_s``).

Writes ``docs/results/prts_timing/{report.md,rows.json}``; a journal makes an interrupted
run resumable.
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from posture_id import __version__
from posture_id.bodies.anthropometry import straight_links, winter_segments
from posture_id.bodies.body import load_body
from posture_id.bodies.urdf_writer import write_chain_urdf
from posture_id.dec.prior import sample_parameters
from posture_id.errors import SimulationError
from posture_id.executors import LocalExecutor
from posture_id.fileio import atomic_write_text, json_text
from posture_id.frf.locked import LockedOptions, LockedProjection
from posture_id.identify import identify
from posture_id.identify.core import ONSET_WINDOW_S
from posture_id.simulation.batch import simulate
from posture_id.simulation.stimulus import prts
from posture_id.simulation.subjects import people_like
from posture_id.studies.journal import Journal
from posture_id.trials import prepare_trial

ROOT = Path(__file__).resolve().parent.parent
SHIFT_RANGE_S = (1.0, 4.0)
LEAD_RANGE_S = (4.5, 6.0)
SHARE_RANGE = (0.25, 0.40)
WITHIN_S = 0.05
#: s, the range the ceiling's distance is searched over.
CEILING_REACH_S = 5.0


def recording(seed: int, index: int, control: bool, folder: Path):
    """(body, truth, the recording as the lab's file has it, the shift s) of one
    recording; the shift is 0 for a control."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, index, int(control), 6911]))
    height, mass = rng.uniform(1.55, 1.95), rng.uniform(50.0, 100.0)
    name = f"{'control' if control else 'shifted'}_{index}"
    urdf = write_chain_urdf(folder / f"{name}.urdf", name,
                            straight_links(winter_segments(height, mass, 1)))
    body = load_body(urdf)
    stimulus = prts(1.0, cycles=3, states=80, onset_s=rng.uniform(*LEAD_RANGE_S),
                    start_state=rng.uniform(0.0, 80.0))
    stimulus = stimulus.spanning(stimulus.duration + rng.uniform(*LEAD_RANGE_S))
    while True:
        truth = sample_parameters(body, 1, rng).trial(0, body.joint_names)
        try:
            subject = people_like(body, truth, stimulus, rng.uniform(*SHARE_RANGE),
                                  int(rng.integers(2**31)), sensor_noise_deg=0.02)
            break
        except SimulationError:
            continue
    shift = 0.0 if control else float(rng.uniform(*SHIFT_RANGE_S) * rng.choice([-1, 1]))
    rec = subject.recording
    return body, truth, replace(rec, tilt=stimulus.angle(rec.time - shift)), shift


def ceiling_error(body, truth, trial, shift: float) -> float:
    """s, where the true parameters' locked sway best matches the recorded one, from the
    truth: the timing error the recording leaves even to the right model; ``trial``: the
    recording prepared."""
    right = trial.shifted_whole(-shift)
    projection = LockedProjection.for_trial(right, LockedOptions())
    sway = simulate(body, truth, right.stimulus)
    fitted = np.degrees(sway.theta[: len(trial.recording.time)])
    return projection.best_offset(fitted, np.degrees(right.recording.theta),
                                  CEILING_REACH_S, step_s=0.005)


def smoothest_error(trial, shift: float) -> float:
    """s, the model-free start of the search (where the recording's locked FRF is
    smoothest, within a quarter cycle) from the truth; ``trial``: the recording
    prepared."""
    projection = LockedProjection.for_trial(trial, LockedOptions())
    found = projection.smoothest_offset(np.degrees(trial.recording.theta),
                                        np.degrees(trial.recording.tilt),
                                        trial.stimulus.period_s / 4)
    return found + shift


def _one(task: tuple) -> dict:
    seed, index, control, folder = task
    body, truth, rec, shift = recording(seed, index, control, Path(folder))
    began = time.perf_counter()
    result = identify(rec, body)
    seconds = time.perf_counter() - began
    verdict = result.verdict
    line = verdict.line()
    error = result.stimulus_offset_s + shift
    prepared = prepare_trial(rec)  # once, for the two references
    return {"index": index, "control": control, "shift_s": shift,
            "found_s": result.stimulus_offset_s, "error_s": error,
            "moved": abs(result.stimulus_offset_s) > 1e-9,
            "level": verdict.level.value, "noise_ratio": verdict.noise.ratio,
            "within_noise": bool(verdict.noise.consistent),
            "names_search": "--max-offset-s" in line or any(
                "--max-offset-s" in n for n in result.notices),
            "half_cycle": bool(abs(abs(error) - 10.0) < 1.0),
            "ceiling_error_s": ceiling_error(body, truth, prepared, shift),
            "smoothest_error_s": smoothest_error(prepared, shift),
            "seconds": seconds, "line": line}


def report(rows: list[dict]) -> str:
    shifted = [r for r in rows if not r["control"]]
    controls = [r for r in rows if r["control"]]

    def share(items, test) -> str:
        hits = sum(1 for r in items if test(r))
        return f"{hits}/{len(items)}" + (f" ({100 * hits / len(items):.0f} %)" if items else "")

    within = lambda r: abs(r["error_s"]) <= WITHIN_S  # noqa: E731
    start = lambda r: r.get("smoothest_error_s", math.inf)  # noqa: E731
    lines = [
        "# The default command's timing of a tilt column off the sway's clock",
        "",
        f"posture_id {__version__}. Made by `benchmarks/prts_timing.py` (its docstring says "
        "what the recordings are). Timing error: the offset the answer is for, against the "
        "truth.",
        "",
        "| | recordings |",
        "|---|---|",
        f"| shifted 1–4 s: timing within {1000 * WITHIN_S:.0f} ms | {share(shifted, within)} |",
        f"| shifted: within 100 ms | {share(shifted, lambda r: abs(r['error_s']) <= 0.1)} |",
        f"| shifted: not moved | {share(shifted, lambda r: not r['moved'])} |",
        f"| shifted: moved, more than 0.5 s off | "
        f"{share(shifted, lambda r: r['moved'] and abs(r['error_s']) > 0.5)} |",
        f"| shifted: by half a cycle | {share(shifted, lambda r: r['half_cycle'])} |",
        f"| shifted: verdict within the noise or naming the timing search | "
        f"{share(shifted, lambda r: r['within_noise'] or r['names_search'])} |",
        f"| shifted, the true parameters: their best timing within {1000 * WITHIN_S:.0f} ms "
        f"| {share(shifted, lambda r: abs(r['ceiling_error_s']) <= WITHIN_S)} |",
        f"| controls: moved | {share(controls, lambda r: r['moved'])} |",
        f"| shifted: the search's start (smoothest FRF) within 0.5 s | "
        f"{share(shifted, lambda r: abs(start(r)) <= 0.5)} |",
        f"| shifted: the search's start within {ONSET_WINDOW_S:g} s (the grid's reach) | "
        f"{share(shifted, lambda r: abs(start(r)) <= ONSET_WINDOW_S)} |",
        "",
        f"Median time per recording: {np.median([r['seconds'] for r in rows]):.1f} s "
        "(one process each).",
        "",
        "| # | shift s | found s | error ms | true model's error ms | level | noise ratio |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in shifted + controls:
        lines.append(f"| {'c' if r['control'] else 's'}{r['index']} | {r['shift_s']:+.2f} | "
                     f"{r['found_s']:+.3f} | {1000 * r['error_s']:+.0f} | "
                     f"{1000 * r['ceiling_error_s']:+.0f} | {r['level']} | "
                     f"{r['noise_ratio']:.2f} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--recordings", type=int, default=24)
    parser.add_argument("--controls", type=int, default=12)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "results" / "prts_timing")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    bodies = Path(tempfile.mkdtemp(prefix="prts_timing_"))  # the subjects' URDFs
    header = {"format": "posture_id-prts-timing-journal", "seed": args.seed,
              "recordings": args.recordings, "controls": args.controls}
    book = Journal(args.out / "prts_timing.journal.jsonl", header,
                   lambda r: (bool(r["control"]), int(r["index"])))
    done = book.read()
    tasks = [(args.seed, i, control, str(bodies))
             for control, count in ((False, args.recordings), (True, args.controls))
             for i in range(count) if (control, i) not in done]
    rows = list(done.values())
    print(f"{len(rows)} journalled, {len(tasks)} to do", flush=True)
    began = time.perf_counter()
    with LocalExecutor(args.workers, processes=True) as pool:
        for _, row in pool.unordered(_one, tasks):
            rows.append(row)
            book.append(row)
            print(f"[{len(rows)}/{len(done) + len(tasks)}] "
                  f"{'control' if row['control'] else 'shifted'} #{row['index']}: shift "
                  f"{row['shift_s']:+.2f} s, error {1000 * row['error_s']:+.0f} ms, "
                  f"{row['level']} ({time.perf_counter() - began:.0f} s)", flush=True)
    rows.sort(key=lambda r: (r["control"], r["index"]))
    atomic_write_text(args.out / "rows.json", json_text({"version": __version__,
                                                         "seed": args.seed, "rows": rows}))
    atomic_write_text(args.out / "report.md", report(rows))
    print(report(rows))


if __name__ == "__main__":
    main()
