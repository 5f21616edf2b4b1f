"""Real sway answered honestly: noise of other shapes, mistakes, and the three-level verdict.

Run:  .venv/bin/python benchmarks/honest_verdict.py [--subjects 12] [--workers 2]
                                                    [--out docs/results/honest_verdict]

Every recording is identified as ``posture-id identify REC --body URDF`` identifies it
(:class:`~posture_id.identify.Identifier` with the default method, ``auto``, and the
bundled universal network), in three groups:

- **clean**: 0.02° white sensor noise, no motor noise;
- **people-like**, per noise family (:mod:`posture_id.simulation.noise_families`): 15–40 %
  of the body COM sway locked; the low-pass family is the project's own, the others are
  shapes the network was never trained on;
- **mistakes** (0.02° sensor noise; :mod:`posture_id.identify.mistakes`): another
  person's body (a 1.90 m, 95 kg subject identified with the URDF of a 1.55 m, 50 kg one),
  two segment columns exchanged, the tilt negated, a 1° step in one segment's angle, the
  control changed halfway (the ankle's and the hip's Kp ×1.35 and Kd ×0.7 from the middle
  on, the two simulations cross-faded over 2 s).

Bodies: the TIP and Winter bodies of 1, 2 and 3 segments (1.75 m, 70 kg), in turn (a
3-segment Winter body in the TIP's turn for another person's body, a 2-segment one in the
1-segment's turn for exchanged columns);
stimuli: the 242-state PRTS ×2 and the 80-state PRTS ×6, 0.5–2° peak to peak; parameters
from docs/model.md §5's prior (a seed no data set uses). A recording is **right** when every
class is right and every truth lies inside its 90 % interval, **wrong** when a class is
wrong or a Kp lies farther from the truth than twice its interval's half-width. Writes
``report.md`` and ``rows.json``; a journal makes an interrupted run resumable (removed
once ``rows.json`` is written).
"""

from __future__ import annotations

import argparse
import time
import zlib
from dataclasses import replace
from pathlib import Path

import numpy as np

from posture_id.bodies.body import Body, load_body
from posture_id.dec.parameters import TARGET_FIELDS, DecParameters, default_parameters
from posture_id.dec.prior import sample_parameters
from posture_id.errors import PostureIdError
from posture_id.executors import LocalExecutor
from posture_id.fileio import atomic_write_text, json_text
from posture_id.learning.data.bodies import build_body
from posture_id.learning.data.scope import BodyDraw
from posture_id.recording import Recording
from posture_id.simulation.batch import simulate
from posture_id.simulation.noise_families import NoiseFamily, draw_noise
from posture_id.simulation.stimulus import prts
from posture_id.simulation.subjects import people_like
from posture_id.studies.journal import Journal

SEED = 4141
#: The groups of recordings judged, and the report's default folder.
GROUPS = ("clean", "people-like", "mistakes")
DEFAULT_OUT = Path("docs/results/honest_verdict")
BODIES = ("TIP", "Winter 1-seg", "Winter 2-seg", "Winter 3-seg")
MISTAKES = ("other body", "columns exchanged", "tilt negated", "angle step",
            "control change")
LEVELS = ("good", "imprecise", "doubtful")
#: An answer's residual within this of the truth's (in units of the noise) counts as no
#: larger: both are re-simulated, so the last digits are the simulator's.
TRUTH_SLACK = 0.02


def _body(name: str, height: float = 1.75, mass: float = 70.0) -> Body:
    if name == "TIP":
        return load_body()
    n = int(name.split()[1][0])
    return build_body(BodyDraw("winter", n, height, mass, ((1.0, 1.0),) * n))


def _stimulus(rng: np.random.Generator):
    amplitude = float(np.exp(rng.uniform(np.log(0.5), np.log(2.0))))
    return prts(amplitude, 2, 242) if rng.random() < 0.5 else prts(amplitude, 6, 80)


def _truth(body: Body, rng: np.random.Generator) -> DecParameters:
    return sample_parameters(body, 1, rng).trial(0, body.joint_names)


def _clean(body, truth, stimulus, seed) -> tuple[Recording, object] | None:
    sim = simulate(body, truth, stimulus)
    return None if not sim.stable else (sim.to_recording().with_sensor_noise(0.02, seed), sim)


def _recording(group: str, kind: str, index: int, seed: int = SEED):
    """(recording, body it is identified with, truth, note) of one task, or None when
    the subject falls (drawn again by the caller)."""
    rng = np.random.default_rng([seed, zlib.crc32(f'{group}/{kind}'.encode()), index])
    name = BODIES[index % len(BODIES)]
    if group == "mistakes" and kind == "columns exchanged" and name == "Winter 1-seg":
        name = "Winter 2-seg"  # two columns to exchange
    if group == "mistakes" and kind == "other body" and name == "TIP":
        name = "Winter 3-seg"  # a body drawn for a height
    for _attempt in range(30):
        body = _body(name)
        stimulus = _stimulus(rng)
        truth = _truth(body, rng)
        seed = int(rng.integers(2**31))
        try:
            if group == "people-like":
                noise = draw_noise(NoiseFamily(kind), rng)
                subject = people_like(body, truth, stimulus, float(rng.uniform(0.15, 0.4)),
                                      seed, noise.sensor_noise_deg, noise.cutoff_hz,
                                      shape=noise.shape, measurement=noise.measurement)
                return subject.recording, body, truth, stimulus, {
                    "locked_share": subject.locked_share, **noise.to_dict()}
            if group == "clean":
                made = _clean(body, truth, stimulus, seed)
                if made is not None:
                    return made[0], body, truth, stimulus, {}
                continue
            if kind == "other body":
                tall = _body(name, 1.90, 95.0)
                short = _body(name, 1.55, 50.0)
                made = _clean(tall, _truth(tall, rng), stimulus, seed)
                if made is not None:
                    rec = replace(made[0], segments=short.segment_names)
                    return rec, short, None, stimulus, {}
                continue
            made = _clean(body, truth, stimulus, seed)
            if made is None:
                continue
            rec, sim = made
            if kind == "columns exchanged":
                theta = rec.theta.copy()
                theta[:, [0, 1]] = theta[:, [1, 0]]
                return replace(rec, theta=theta), body, None, None, {}
            if kind == "tilt negated":
                return replace(rec, tilt=-rec.tilt), body, None, None, {}
            if kind == "angle step":
                theta = rec.theta.copy()
                at = int(rng.uniform(0.2, 0.8) * len(theta))
                theta[at:, int(rng.integers(body.n_segments))] += np.radians(1.0)
                return replace(rec, theta=theta), body, None, stimulus, {}
            if kind == "control change":
                changed = truth
                for joint in (body.joint_names[0], body.joint_names[-1]):
                    changed = changed.replace(joint, kp=1.35 * truth[joint].kp,
                                              kd=0.7 * truth[joint].kd)
                other = simulate(body, changed, stimulus)
                if not other.stable:
                    continue
                fade = 1 / (1 + np.exp(-(rec.time - rec.time[-1] / 2) / 0.5))[:, None]
                theta = (1 - fade) * rec.theta + fade * (rec.theta - sim.theta + other.theta)
                return replace(rec, theta=theta), body, None, stimulus, {}
        except PostureIdError:
            continue
    return None


def _one(task: tuple) -> dict:
    group, kind, index, model, seed = task
    from posture_id.identify import Identifier

    made = _recording(group, kind, index, seed)
    row = {"group": group, "kind": kind, "index": index}
    if made is None:
        return {**row, "skipped": True}
    recording, body, truth, stimulus, extra = made
    began = time.perf_counter()
    identifier = Identifier(body, model=model)
    result = identifier.identify(recording, stimulus)
    row.update(extra)
    fields = result.verdict.benchmark_fields()
    row.update({"body": BODIES[index % len(BODIES)], "segments": body.n_segments,
                "seconds": time.perf_counter() - began, "level": result.verdict.level.value,
                "reasons": list(result.verdict.reasons), "fell": bool(result.fell),
                "method_used": result.method.value,
                "p_com": None if result.class_probability is None
                else [float(x) for x in result.class_probability],
                "joints": list(body.joint_names),
                "unpinned": list(result.verdict.unpinned),
                "notices": [n for n in result.notices if "refined" in n or "stimulus" in n],
                **{k: fields[k] for k in ("noise_ratio", "relative_residual",
                                          "noise_relative")},
                "locked_share_measured": result.verdict.locked_share,
                "typicality_p": None if result.cnn is None or result.cnn.typicality is None
                else float(result.cnn.typicality.p)})
    if truth is not None:
        iv = result.intervals
        truth_si = np.array([[getattr(truth[j], f) for f in TARGET_FIELDS]
                             for j in body.joint_names])
        found = np.array([[getattr(result.parameters[j], f) for f in TARGET_FIELDS]
                          for j in body.joint_names])
        body_defaults = default_parameters(body)
        defaults = np.array([[getattr(body_defaults[j], f) for f in TARGET_FIELDS]
                             for j in body.joint_names])
        inside = (iv.lower_si <= truth_si) & (truth_si <= iv.upper_si)
        half = (iv.upper_si - iv.lower_si) / 2
        row.update({
            "classes_right": [result.parameters[j].controls == truth[j].controls
                              for j in body.joint_names],
            "truth_com": [truth[j].sign > 0 for j in body.joint_names],
            "kp_error": (found[:, 0] / truth_si[:, 0] - 1).tolist(),
            "inside": inside.tolist(),
            "kp_far": (np.abs(found[:, 0] - truth_si[:, 0]) > 2 * half[:, 0]).tolist(),
            # normalised p/p_default − 1: the answer, the truth and the interval, so that
            # another rule for the intervals can be judged on these rows
            "estimate": (found / defaults - 1).tolist(),
            "truth_normalised": (truth_si / defaults - 1).tolist(),
            "lower": np.asarray(iv.lower).tolist(), "upper": np.asarray(iv.upper).tolist(),
            "relative_half_width": (half / np.abs(found)).tolist()})
        # how well the truth itself explains the recording, judged as the answer is: an
        # answer that leaves no more than the truth does cannot be told wrong by its fit
        truth_check = identifier.judge(identifier.prepare(recording, stimulus), body, truth)
        row.update({"truth_noise_ratio": truth_check.ratio,
                    "truth_relative_residual": truth_check.relative})
    return row


def family_cells(rows: list[dict], family: str) -> str:
    """Table cells of the people-like subjects of one noise family: the share of modules
    with their class right, the median |Kp error|, the share of true Kps and of all true
    parameters inside their 90 % intervals ("" cells when there are none)."""
    group = [r for r in rows if r["group"] == "people-like" and r["kind"] == family
             and not r.get("skipped")]
    if not group:
        return " | | "
    classes = np.concatenate([r["classes_right"] for r in group])
    kp = np.abs(np.concatenate([r["kp_error"] for r in group]))
    inside = np.concatenate([np.array(r["inside"]) for r in group])
    return (f"{100 * classes.mean():.1f} % | {100 * np.median(kp):.1f} % | "
            f"{100 * inside[:, 0].mean():.0f} % | {100 * inside.mean():.0f} %")


def _judged(row: dict) -> str:
    """right, wrong or neither (module docstring)."""
    if "classes_right" not in row:
        return "mistake"
    if not all(row["classes_right"]) or any(row["kp_far"]):
        return "wrong"
    return "right" if all(all(r) for r in row["inside"]) else "neither"


def _truth_com(row: dict) -> list[bool] | None:
    """Each module's true class (COM in space), from the row's ``truth_com``, or, for an
    answer whose classes are the network's (``method_used`` cnn), from its P(com) and
    whether its class is right; None when neither tells."""
    if row.get("truth_com") is not None:
        return row["truth_com"]
    if row.get("method_used") != "cnn" or row.get("p_com") is None:
        return None
    return [(p >= 0.5) == right for p, right in zip(row["p_com"], row["classes_right"],
                                                    strict=True)]


def _names_class(row: dict, module: int) -> bool:
    """The answer's verdict names ``module``'s class as what the recording does not pin
    (its ``unpinned`` list when the row has it; else the network's P(com) inside
    :data:`~posture_id.identify.verdict.NAMED_CLASS`, the rule that names it)."""
    from posture_id.identify.verdict import NAMED_CLASS

    if row.get("unpinned") is not None and row.get("joints") is not None:
        joint = row["joints"][module]
        return any(f"the {joint}'s class" in u for u in row["unpinned"])
    low, high = NAMED_CLASS
    return row.get("p_com") is not None and low < row["p_com"][module] < high


def class_lines(people: list[dict]) -> list[str]:
    """The report's section on the class probabilities of people-like answers: their
    calibration (ECE, the share right of those given ≥ 0.9, the reliability table) and
    how the verdict treats a wrong class and the right answers."""
    from posture_id.uncertainty.coverage import expected_calibration_error, reliability

    known = [(r, t) for r in people if (t := _truth_com(r)) is not None]
    if not known:
        return []
    p = np.concatenate([r["p_com"] for r, _ in known])
    truth = np.concatenate([t for _, t in known]).astype(bool)
    confidence = np.maximum(p, 1 - p)
    right = (p >= 0.5) == truth
    sure = confidence >= 0.9
    lines = ["", "## Class probabilities", "",
             f"People-like modules: {len(p)}. Expected calibration error of P(com) against "
             f"the true class (10 bins): {expected_calibration_error(p, truth):.3f}. Of the "
             f"{int(sure.sum())} modules given a class with probability ≥ 0.9, "
             f"{100 * right[sure].mean():.1f} % are right.", "",
             "| P(com) bin | modules | mean P(com) | share COM |", "|---|---|---|---|"]
    mean_p, freq, count = reliability(p, truth)
    for k in range(len(count)):
        if count[k]:
            lines.append(f"| {k / 10:.1f}–{(k + 1) / 10:.1f} | {count[k]} | {mean_p[k]:.3f} "
                         f"| {freq[k]:.3f} |")
    wrong = [(r, t) for r, t in known if not all(r["classes_right"])]
    flagged = [r for r, _ in wrong if r["level"] == "doubtful" or any(
        _names_class(r, m) for m, ok in enumerate(r["classes_right"]) if not ok)]
    lines += ["", f"People-like answers with a class wrong: {len(wrong)}; doubtful or "
                  f"imprecise naming that module's class: {len(flagged)} of {len(wrong)}."]
    good = [r for r in people if _judged(r) == "right"]
    doubted = [r for r in good if r["level"] == "doubtful"]
    lines += ["", f"Right answers (every class right, every truth inside its interval) "
                  f"called doubtful: {len(doubted)} of {len(good)}"
                  + ("" if not doubted else ", each for:")]
    lines += [f"- {r['kind']} #{r['index']}: " + "; ".join(r["reasons"]) for r in doubted]
    return lines


def reliability_figure(rows: list[dict], path: Path) -> None:
    """The reliability diagram of the people-like answers' P(com) (``reliability.png``)."""
    from posture_id.plotting import plot_reliability
    from posture_id.uncertainty.coverage import reliability

    known = [(r, t) for r in rows if r["group"] == "people-like" and not r.get("skipped")
             and (t := _truth_com(r)) is not None]
    p = np.concatenate([r["p_com"] for r, _ in known])
    truth = np.concatenate([t for _, t in known])
    mean_p, freq, count = reliability(p, truth)
    plot_reliability({f"people-like modules ({len(p)})": {
        "mean_probability": mean_p, "frequency": freq, "count": count}}, path)


def made_by(subjects: int, seed: int = SEED, model: str | None = None,
            groups: list[str] | None = None, families: list[str] | None = None,
            out: Path | None = None) -> str:
    """The command that makes a report: its flags where they are not the defaults."""
    command = f".venv/bin/python benchmarks/honest_verdict.py --subjects {subjects}"
    if seed != SEED:
        command += f" --seed {seed}"
    if model is not None:
        command += f" --model {model}"
    if groups is not None and list(groups) != list(GROUPS):
        command += " --groups " + " ".join(groups)
    if families is not None and list(families) != [f.value for f in NoiseFamily]:
        command += " --families " + " ".join(families)
    if out is not None and out != DEFAULT_OUT:
        command += f" --out {out}"
    return command


def report(rows: list[dict], command: str, model: str | None = None) -> str:
    rows = [r for r in rows if not r.get("skipped")]
    network = "the bundled universal network" if model is None else f"the model {model}"
    lines = ["# Real sway answered honestly", "",
             f"Made by `{command}`: "
             f"every recording through the default method (`auto`, {network}; about 4 min "
             "for the three groups of 24 here); what the groups, families and mistakes "
             "are: the script's docstring.",
             "", "## People-like sway, by noise family", "",
             "| family | recordings | modules: every class right | median \\|Kp error\\| | "
             "90 % intervals holding the truth (Kp) | (all parameters) | doubtful | "
             "locked share measured (median) |",
             "|---|---|---|---|---|---|---|---|"]
    for family in NoiseFamily:
        group = [r for r in rows if r["group"] == "people-like" and r["kind"] == family.value]
        if group:
            doubtful = sum(r["level"] == "doubtful" for r in group)
            shares = [r["locked_share_measured"] for r in group
                      if r.get("locked_share_measured") is not None]
            share = f"{100 * np.median(shares):.0f} %" if shares else ""
            lines.append(f"| {family.value} | {len(group)} | {family_cells(rows, family.value)}"
                         f" | {doubtful} | {share} |")
    lines += ["", "## The verdict against the truth", "",
              "| group | level | right | neither | wrong |", "|---|---|---|---|---|"]
    for group in ("clean", "people-like"):
        chosen = [r for r in rows if r["group"] == group]
        for level in LEVELS:
            counts = [sum(r["level"] == level and _judged(r) == j for r in chosen)
                      for j in ("right", "neither", "wrong")]
            lines.append(f"| {group} | {level} | " + " | ".join(map(str, counts)) + " |")
    judged = [r for r in rows if r["group"] != "mistakes"]
    for j in ("right", "wrong"):
        of = [r for r in judged if _judged(r) == j]
        lines.append("")
        lines.append(f"Doubtful: {sum(r['level'] == 'doubtful' for r in of)} of {len(of)} "
                     f"{j} answers.")
    people = [r for r in judged if r["group"] == "people-like" and r.get("p_com") is not None]
    if people:  # would an unsure class make a good sign of a wrong answer?
        lines.append("")
        for low, high in ((0.05, 0.95), (0.2, 0.8)):
            marked = {j: [any(low < p < high for p in r["p_com"]) for r in people
                          if _judged(r) == j] for j in ("right", "wrong")}
            lines.append(f"People-like answers with a class the network is unsure of (P(com) "
                         f"within {low:g}–{high:g}): {sum(marked['wrong'])} of "
                         f"{len(marked['wrong'])} wrong, {sum(marked['right'])} of "
                         f"{len(marked['right'])} right.")
    fitted = [r for r in people if r.get("truth_noise_ratio") is not None
              and r.get("noise_ratio") is not None]
    if fitted:  # can the recording tell a wrong answer from the truth at all?
        closer = {j: [r["noise_ratio"] <= r["truth_noise_ratio"] + TRUTH_SLACK for r in fitted
                      if _judged(r) == j] for j in ("right", "wrong")}
        lines += ["", f"People-like answers whose stimulus-locked residual is no larger than "
                      f"the truth's own (within {TRUTH_SLACK:g} of the noise; both re-simulated "
                      f"and judged alike): {sum(closer['wrong'])} of {len(closer['wrong'])} "
                      f"wrong, {sum(closer['right'])} of {len(closer['right'])} right. Such a "
                      "wrong answer explains the recording as well as the truth does: no "
                      "check of the fit can doubt it without doubting the truth."]
    lines += class_lines(people)
    lines += ["", "## Mistakes", "", "| mistake | recordings | good | imprecise | doubtful |",
              "|---|---|---|---|---|"]
    for kind in MISTAKES:
        group = [r for r in rows if r["group"] == "mistakes" and r["kind"] == kind]
        lines.append(f"| {kind} | {len(group)} | " + " | ".join(
            str(sum(r["level"] == level for r in group)) for level in LEVELS) + " |")
    mistakes = [r for r in rows if r["group"] == "mistakes"]
    lines += ["", f"Doubtful: {sum(r['level'] == 'doubtful' for r in mistakes)} of "
                  f"{len(mistakes)} mistakes. Every recording got an answer: "
                  f"{sum(r['fell'] for r in rows)} of {len(rows)} answers fall in "
                  "re-simulation."]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", type=int, default=12,
                        help="recordings per noise family, for clean sway and per mistake")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=SEED,
                        help="the draws' seed (default %(default)s, the benchmark's; another "
                             "gives other subjects, e.g. to calibrate on)")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    parser.add_argument("--model", type=Path,
                        help="a universal model directory (default: the bundled one)")
    parser.add_argument("--groups", nargs="+", default=list(GROUPS), choices=GROUPS)
    parser.add_argument("--families", nargs="+", default=[f.value for f in NoiseFamily],
                        choices=[f.value for f in NoiseFamily],
                        help="the people-like group's noise families")
    args = parser.parse_args()
    model = None if args.model is None else str(args.model)
    header = {"format": "posture_id-honest-verdict", "subjects": args.subjects, "seed": args.seed,
              "model": model}
    book = Journal(args.out / "journal.jsonl", header,
                   lambda r: (r["group"], r["kind"], int(r["index"])))
    done = book.read()
    tasks = []
    if "clean" in args.groups:
        tasks += [("clean", "clean", i) for i in range(args.subjects)]
    if "people-like" in args.groups:
        tasks += [("people-like", f, i) for f in args.families for i in range(args.subjects)]
    if "mistakes" in args.groups:
        tasks += [("mistakes", m, i) for m in MISTAKES for i in range(args.subjects)]
    tasks = [(*t, model, args.seed) for t in tasks if t not in done]
    rows = list(done.values())
    print(f"{len(rows)} done, {len(tasks)} to do", flush=True)
    with LocalExecutor(args.workers, processes=True) as pool:
        for _, row in pool.unordered(_one, tasks):
            rows.append(row)
            book.append(row)
            print(f"[{len(rows)}] {row['group']} {row['kind']} #{row['index']}: "
                  f"{row.get('level')} {row.get('kp_error', '')}", flush=True)
    rows.sort(key=lambda r: (r["group"], r["kind"], r["index"]))
    args.out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(args.out / "rows.json", json_text({"subjects": args.subjects,
                                                         "seed": args.seed, "model": model,
                                                         "rows": rows}))
    text = report(rows, made_by(args.subjects, args.seed, model, args.groups, args.families,
                                args.out), model)
    if any(r["group"] == "people-like" for r in rows):
        reliability_figure(rows, args.out / "reliability.png")
    atomic_write_text(args.out / "report.md", text)
    (args.out / "journal.jsonl").unlink(missing_ok=True)  # rows.json holds every row
    print(text)


if __name__ == "__main__":
    main()
