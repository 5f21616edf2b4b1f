"""When should ``auto`` refine the network's answer by least squares? Part-locked subjects.

Run:  .venv/bin/python benchmarks/auto_rule.py [--subjects 40] [--workers 2]
      [--cycles 2] [--share 0.6 0.95] [--name auto_rule]

Subjects whose body COM sway is 60–95 % stimulus-locked (motor noise, not people-like:
the sway the old rule refined whenever the network's verdict was doubtful), parameters
from docs/model.md §5's prior, 0.05° sensor noise, the 242-state PRTS ×2 at 1°, on the TIP and
Winter bodies of 1, 2 and 3 segments (1.75 m, 70 kg), the subjects' own seeds. Each is
identified by the network alone, by the hybrid (least squares from the network's answer)
on the raw sway and on the stimulus-locked sway, by ``auto`` as it is now
(:func:`~posture_id.identify.core.auto_refinement`) and as it was (the raw hybrid for
every doubtful answer on sway that is not people-like). Per method: subjects with every
class right, the median and 90th percentile of |Kp error| over modules, and subjects
with a module's Kp off by more than 10 %. Written to
``docs/results/auto_rule.{json,md}``.

``--cycles 1`` records one cycle of the PRTS (60.5 s), where the locked share cannot be
measured (nothing to average over), and ``--share LO HI`` draws the locked share from
another range (``--share 1 1``: no motor noise at all, 0.05° sensor noise alone);
``--name`` names the result files.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from posture_id.bodies.body import load_body
from posture_id.dec.prior import sample_parameters
from posture_id.errors import PostureIdError
from posture_id.executors import executor_for
from posture_id.fileio import atomic_write_text, json_text
from posture_id.fitting.options import FitOptions
from posture_id.frf.locked import LockedOptions
from posture_id.identify.core import Identifier, Refinement, auto_refinement
from posture_id.identify.method import Method
from posture_id.identify.verdict import PEOPLE_LIKE_SHARE
from posture_id.learning.data.bodies import build_body
from posture_id.learning.data.scope import BodyDraw
from posture_id.simulation import simulate
from posture_id.simulation.stimulus import prts
from posture_id.simulation.subjects import people_like

SEED = 0x4155544F
BODIES = ("TIP", "Winter 1-seg", "Winter 2-seg", "Winter 3-seg")
METHODS = ("network alone", "hybrid, raw sway", "hybrid, locked sway", "auto (this rule)",
           "auto (before: every doubtful answer)")
OUT = Path(__file__).resolve().parents[1] / "docs" / "results"


def _body(name: str):
    if name == "TIP":
        return load_body()
    n = int(name.split()[1][0])
    return build_body(BodyDraw("winter", n, 1.75, 70.0, ((1.0, 1.0),) * n))


def _subject(index: int, subjects: int, cycles: int = 2,
             share_range: tuple[float, float] = (0.6, 0.95)) -> dict:
    """One subject, identified every way: its row."""
    rng = np.random.default_rng([SEED, index])
    name = BODIES[index % len(BODIES)]
    body = _body(name)
    stimulus = prts(1.0, cycles, 242)
    for _attempt in range(20):
        truth = sample_parameters(body, 1, rng).trial(0, body.joint_names)
        share = float(rng.uniform(*share_range))
        seed = int(rng.integers(2**31))
        if share >= 1.0:  # no motor noise: the sensor's alone
            clean = simulate(body, truth, stimulus)
            if clean.stable:
                recording, realised = clean.to_recording().with_sensor_noise(0.05, seed), 1.0
                break
            continue
        try:
            subject = people_like(body, truth, stimulus, share, seed=seed)
            recording, realised = subject.recording, subject.locked_share
            break
        except PostureIdError:
            continue
    else:
        return {"index": index, "body": name, "skipped": True}
    network = Identifier(body, Method.CNN)
    trial = network.prepare(recording, stimulus)
    answers, seconds = {}, {}
    began = time.perf_counter()
    answers["network alone"] = cnn = network.identify_trial(trial)
    seconds["network alone"] = time.perf_counter() - began
    for method, options in (("hybrid, raw sway", FitOptions()),
                            ("hybrid, locked sway", FitOptions(locked=LockedOptions()))):
        began = time.perf_counter()
        hybrid = Identifier(body, Method.HYBRID, fit_options=options)
        hybrid.cnn = network.cnn
        answers[method] = hybrid.identify_trial(trial)
        seconds[method] = time.perf_counter() - began
    how = auto_refinement(cnn.verdict)
    share = cnn.verdict.locked_share
    unlocked = share is not None and share < PEOPLE_LIKE_SHARE
    answers["auto (this rule)"] = {Refinement.KEEP: cnn,
                                   Refinement.RAW: answers["hybrid, raw sway"],
                                   Refinement.LOCKED: answers["hybrid, locked sway"]}[how]
    answers["auto (before: every doubtful answer)"] = (
        answers["hybrid, raw sway"] if cnn.verdict.doubtful and not unlocked else cnn)
    row = {"index": index, "body": name, "locked_share": realised,
           "verdict_doubtful": cnn.verdict.doubtful, "refinement": how.value,
           "noise_relative": cnn.verdict.noise.noise_relative, "seconds": seconds}
    for method, result in answers.items():
        row[method] = {
            "kp_error": [abs(result.parameters[j].kp / truth[j].kp - 1)
                         for j in body.joint_names],
            "classes_right": [result.parameters[j].controls == truth[j].controls
                              for j in body.joint_names]}
    return row


def _summary(rows: list[dict]) -> dict:
    out = {}
    for method in METHODS:
        kp = np.concatenate([r[method]["kp_error"] for r in rows])
        worst = np.array([max(r[method]["kp_error"]) for r in rows])
        out[method] = {
            "subjects": len(rows),
            "every_class_right_pct": 100 * float(np.mean(
                [all(r[method]["classes_right"]) for r in rows])),
            "kp_error_median_pct": 100 * float(np.median(kp)),
            "kp_error_p90_pct": 100 * float(np.percentile(kp, 90)),
            "kp_over_10pct": int(np.sum(worst > 0.10))}
    return out


def _markdown(summary: dict, rows: list[dict], cycles: int = 2,
              share_range: tuple[float, float] = (0.6, 0.95)) -> str:
    counts = {k: sum(r["refinement"] == k for r in rows) for k in ("keep", "raw", "locked")}
    doubtful = sum(r["verdict_doubtful"] for r in rows)
    lo, hi = (100 * v for v in share_range)
    who = "subjects without motor noise" if lo >= 100 else "part-locked subjects"
    locked = f"{lo:.0f} %" if lo == hi else f"{lo:.0f}–{hi:.0f} %"
    lines = [f"# `auto`'s rule on {who}", "",
             "Made by `.venv/bin/python benchmarks/auto_rule.py` (its docstring says what). "
             f"{len(rows)} subjects, the 242-state PRTS ×{cycles}, "
             f"{locked} of the body COM sway locked; the network's "
             f"verdict was doubtful for {doubtful}; this rule kept {counts['keep']} answers, "
             f"refined {counts['locked']} on the locked sway and {counts['raw']} on the raw "
             "sway.",
             "", "| method | every class right | median \\|Kp error\\| | 90th percentile | "
             "subjects with a Kp off by > 10 % |", "|---|---|---|---|---|"]
    for method, s in summary.items():
        lines.append(f"| {method} | {s['every_class_right_pct']:.0f} % | "
                     f"{s['kp_error_median_pct']:.1f} % | {s['kp_error_p90_pct']:.1f} % | "
                     f"{s['kp_over_10pct']} of {s['subjects']} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", type=int, default=40)
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--out", type=Path, default=OUT)
    parser.add_argument("--cycles", type=int, default=2, help="PRTS cycles recorded")
    parser.add_argument("--share", type=float, nargs=2, default=(0.6, 0.95),
                        metavar=("LO", "HI"), help="locked share of the body COM sway")
    parser.add_argument("--name", default="auto_rule", help="result files' name")
    parser.add_argument("--rewrite", action="store_true",
                        help="rewrite NAME.md from the earlier NAME.json, simulating nothing "
                        "(its --cycles and --share as the JSON records them; an older JSON "
                        "that does not: give the same flags)")
    args = parser.parse_args()
    share_range = tuple(args.share)
    if args.rewrite:
        earlier = json.loads((args.out / f"{args.name}.json").read_text())
        rows = earlier["rows"]
        # what made the rows, where the JSON says it (older ones do not: the flags then)
        cycles = earlier.get("cycles", args.cycles)
        share_range = tuple(earlier.get("share", share_range))
        text = _markdown(_summary(rows), rows, cycles, share_range)
        atomic_write_text(args.out / f"{args.name}.md", text)
        print(text)
        return
    executor = executor_for(None, args.workers, processes=True)
    rows = []
    try:
        for index, row in executor.unordered(_subject, range(args.subjects), args.subjects,
                                                args.cycles, share_range):
            rows.append(row)
            print(f"subject {index + 1}: done ({len(rows)}/{args.subjects})", flush=True)
    finally:
        executor.close()
    rows = sorted((r for r in rows if not r.get("skipped")), key=lambda r: r["index"])
    summary = _summary(rows)
    args.out.mkdir(parents=True, exist_ok=True)
    text = _markdown(summary, rows, args.cycles, share_range)
    atomic_write_text(args.out / f"{args.name}.json", json_text({
        "summary": summary, "rows": rows, "cycles": args.cycles, "share": list(share_range)}))
    atomic_write_text(args.out / f"{args.name}.md", text)
    print(text)
    print(json.dumps({m: s["kp_error_median_pct"] for m, s in summary.items()}))


if __name__ == "__main__":
    main()
