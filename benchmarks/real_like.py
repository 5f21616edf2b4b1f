"""Identification of people-like subjects: most of their sway is not the stimulus's.

Run:  .venv/bin/python benchmarks/real_like.py [--subjects 30] [--workers 2]
      (the networks first: ``make real-like-models``, docs/real_recordings.md)

``--subjects`` simulated subjects of the TIP (or of ``--body``), each recorded with the
242-state PRTS (2 cycles, 121 s) and with the 80-state PRTS (6 cycles, 120 s), both 1°
peak-to-peak: docs/model.md §5 parameters (from a seed no data set uses; subjects that fall
under either stimulus are drawn again), motor noise scaled so that a share drawn
uniformly from [10 %, 30 %] of their body COM sway's variance is stimulus-locked
(:func:`posture_id.simulation.subjects.people_like`), 0.05° sensor noise. Every recording
is identified by:

- ``raw LS``: least squares on every sample of the sway (relaxed classes, from defaults);
- ``locked LS``: least squares on the stimulus-locked sway (``FitOptions.locked``);
- ``locked LS, prior``: the same with a Gaussian prior of SD 0.5 on the normalised
  parameters (``--locked --prior-sd 0.5``);
- ``CNN``: the spectrogram network trained on motor-noisy data of that stimulus;
- ``FRF net``: the FRF-feature network trained on the same data;
- ``hybrid``: :class:`~posture_id.identify.Identifier` with :attr:`Method.HYBRID`, raw
  sway: least squares from a CNN's answer, its short route accepted when the residual is
  consistent with the recording's own noise (docs/identify.md);
- ``locked hybrid``: the same on the stimulus-locked sway (``--locked``);
- ``universal``: ``posture-id identify``'s default, the bundled universal network
  (docs/universal.md), for any body.
The hybrids start from the ``CNN`` network when ``--models`` holds it, otherwise from the
bundled model (trained on sensor noise only, the 242-state PRTS only); the report says
which.

Per method: the share of subjects with every class right, the median |relative error| of
each parameter per module, E_rel of the stimulus-locked response (the identified
parameters simulated without noise against the subject's noise-free response, body COM),
and the time. Writes ``docs/results/real_like.{md,json,png}``; a journal makes an
interrupted run resumable.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from pathlib import Path

import numpy as np

from posture_id import __version__
from posture_id.bodies.body import load_body
from posture_id.dec.parameters import DecParameters
from posture_id.dec.prior import sample_parameters
from posture_id.errors import SimulationError
from posture_id.executors import LocalExecutor
from posture_id.fileio import atomic_write_text, json_text
from posture_id.fitting import FitOptions
from posture_id.frf.locked import LockedOptions
from posture_id.identify import Identifier, Method
from posture_id.learning.config import LearningError
from posture_id.learning.identifier import CnnIdentifier
from posture_id.plotting import plot_benchmark
from posture_id.simulation import prts, simulate
from posture_id.simulation.metrics import sway_errors
from posture_id.simulation.subjects import people_like
from posture_id.studies.benchmark import FAR_E_REL
from posture_id.studies.journal import Journal
from posture_id.trials import prepare_trial

ROOT = Path(__file__).resolve().parent.parent
STIMULI = {"242": dict(states=242, cycles=2), "80": dict(states=80, cycles=6)}
METHODS = ("raw LS", "locked LS", "locked LS, prior", "CNN", "FRF net", "hybrid",
           "locked hybrid", "universal")
FIELDS = ("kp", "ki", "kd", "delay_s")
SHARE_RANGE = (0.10, 0.30)
_LOADED: dict = {}


def subjects(body, n: int, seed: int) -> list[dict]:
    """``n`` subjects (parameters, share, noise seed) that stay up with their noise under
    every stimulus."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, 4242]))
    out = []
    while len(out) < n:
        params = sample_parameters(body, 1, rng).trial(0, body.joint_names)
        share = float(rng.uniform(*SHARE_RANGE))
        noise_seed = int(rng.integers(0, 2**31))
        try:
            for spec in STIMULI.values():
                people_like(body, params, prts(**spec), share, noise_seed)
        except SimulationError:
            continue
        out.append({"params": params.to_dict(), "share": share, "seed": noise_seed})
    return out


def hybrid_start(folders: dict) -> str:
    """The model the hybrids start from: the people-like CNN when it exists, else the
    bundled one."""
    return folders["cnn"] if (Path(folders["cnn"]) / "model.json").exists() else "bundled"


def _models(stimulus_key: str, folders: dict, urdf: str):
    if (urdf, stimulus_key) not in _LOADED:
        body = load_body(urdf)
        nets = {kind: CnnIdentifier.load(folders[kind], body)
                for kind in ("cnn", "frf") if (Path(folders[kind]) / "model.json").exists()}
        try:  # the bundled specialist for the body's segment count, where there is one
            start = nets.get("cnn") or CnnIdentifier.resolve(None, body)
        except LearningError:
            start = None  # the hybrids start from the universal model
        raw, locked = FitOptions(threads=1), FitOptions(threads=1, locked=LockedOptions())
        nets["raw LS"] = Identifier(body, Method.FIT, fit_options=raw)
        nets["locked LS"] = Identifier(body, Method.FIT, fit_options=locked)
        nets["locked LS, prior"] = Identifier(body, Method.FIT, fit_options=FitOptions(
            threads=1, locked=LockedOptions(), prior_sd=0.5))
        nets["hybrid"] = Identifier(body, Method.HYBRID, start, raw)
        nets["locked hybrid"] = Identifier(body, Method.HYBRID, start, locked)
        # the default's network: the bundled universal model, or the one --universal names
        nets["universal"] = Identifier(body, Method.CNN, folders.get("universal"))
        _LOADED[urdf, stimulus_key] = (body, nets)
    return _LOADED[urdf, stimulus_key]


def _one(task: tuple) -> dict:
    """Identify one subject with one method (a worker process, one thread)."""
    stimulus_key, index, spec, method, folders, urdf = task
    body, nets = _models(stimulus_key, folders, urdf)
    stim = prts(**STIMULI[stimulus_key])
    truth = DecParameters.from_dict(spec["params"], body)
    subject = people_like(body, truth, stim, spec["share"], spec["seed"])
    rec = subject.recording
    start = time.perf_counter()
    verdict = None
    if method == "CNN":
        params = nets["cnn"].identify(prepare_trial(rec, stim)).parameters
    elif method == "FRF net":
        params = nets["frf"].identify(prepare_trial(rec, stim)).parameters
    else:  # least squares and the hybrids: identify, with its trust verdict
        result = nets[method].identify(rec, stim)
        params, verdict = result.parameters, result.verdict
    seconds = time.perf_counter() - start
    again = simulate(body, params, stim)
    reference = subject.locked.alpha[:, 0]
    got = again.alpha[: len(reference), 0]
    e_rel = float(sway_errors(reference, got)[1])
    rel = np.column_stack([params.array(f) / truth.array(f) - 1 for f in FIELDS])
    row = {"stimulus": stimulus_key, "index": index, "method": method, "seconds": seconds,
           "share": subject.locked_share, "motor_noise_deg": subject.motor_noise.sd_deg,
           "relative_error": rel.tolist(), "e_rel": e_rel,
           "classes_correct": [params[j].controls == truth[j].controls
                               for j in body.joint_names]}
    if verdict is not None:
        row.update(verdict.benchmark_fields(), suggestion=verdict.suggestion,
                   estimated_locked_share=verdict.locked_share, relaxed=result.relaxed_refit)
    return row


def statistics(rows: list[dict], joints) -> dict:
    out = {}
    for stimulus_key in STIMULI:
        for method in METHODS:
            mine = [r for r in rows if r["stimulus"] == stimulus_key and r["method"] == method]
            if not mine:
                continue
            rel = np.abs(np.array([r["relative_error"] for r in mine]))  # (R, N, 4)
            correct = np.array([r["classes_correct"] for r in mine])
            e_rel = np.array([r["e_rel"] for r in mine])
            out[f"{stimulus_key}|{method}"] = {
                "subjects": len(mine),
                "all_classes_right": float(correct.all(axis=1).mean()),
                "modules_right": float(correct.mean()),
                "median_abs_relative_error": {
                    j: {f: float(np.median(rel[:, m, k])) for k, f in enumerate(FIELDS)}
                    for m, j in enumerate(joints)},
                "median_abs_kp_error_all_modules": float(np.median(rel[:, :, 0])),
                "e_rel_median": float(np.median(e_rel)),
                "seconds_median": float(np.median([r["seconds"] for r in mine])),
                "locked_share_median": float(np.median([r["share"] for r in mine])),
            }
            if all("doubtful" in r for r in mine):
                far = ~correct.all(axis=1) | ~(e_rel <= FAR_E_REL)
                doubtful = np.array([r["doubtful"] for r in mine])
                out[f"{stimulus_key}|{method}"].update(
                    far=int(far.sum()), doubtful_far=int((doubtful & far).sum()),
                    doubtful_right=int((doubtful & ~far).sum()),
                    relaxed=sum(bool(r.get("relaxed")) for r in mine))
    return out


def markdown(stats: dict, joints, n_subjects: int, workers: int, models: dict,
             body_name: str = "the TIP") -> str:
    lines = ["# People-like subjects: raw and locked least squares, the networks, the hybrids",
             "",
             f"{n_subjects} simulated subjects of {body_name} (drawn so that they stay up "
             "under both "
             "stimuli; docs/model.md §5 "
             "parameters; motor noise scaled so that "
             f"{100 * SHARE_RANGE[0]:g}–{100 * SHARE_RANGE[1]:g} % of "
             "the body COM sway's variance is stimulus-locked, drawn per subject; 0.05° "
             "sensor noise). Errors are |identified / true − 1|, medians over subjects. "
             "E_rel: the identified parameters simulated without noise against the subject's "
             "noise-free (stimulus-locked) body sway. Made by `benchmarks/real_like.py` "
             f"(posture_id {__version__}, {workers} subjects at a time, one thread each). "
             + ("The networks were trained on motor-noisy data sets of "
                + ", ".join(f"{m['trials']} trials ({k.replace('_', ' PRTS, ')})"
                            for k, m in models.items() if "trials" in m)
                + " (`make real-like-models`). "
                if any("trials" in m for m in models.values()) else "")
             + ("The hybrids started from: "
                + ", ".join(f"{k.split('_')[0]}-state PRTS: {m['start']}"
                            for k, m in models.items() if "start" in m) + "."
                if any("start" in m for m in models.values()) else ""), ""]
    for stimulus_key, spec in STIMULI.items():
        if not any(k.startswith(stimulus_key + "|") for k in stats):
            continue  # this stimulus was not run
        lines += [f"## PRTS {spec['states']} states × {spec['cycles']}", "",
                  "| method | every class right | Kp error (all modules) | Kp error "
                  + " / ".join(joints) + " | Kd error " + " / ".join(joints)
                  + " | Δ error " + " / ".join(joints) + " | E_rel locked | s |",
                  "|---|---|---|---|---|---|---|---|"]
        for method in METHODS:
            s = stats.get(f"{stimulus_key}|{method}")
            if s is None:
                continue
            med = s["median_abs_relative_error"]

            def per(field, med=med):
                return " / ".join(f"{100 * med[j][field]:.0f} %" for j in joints)

            lines.append(f"| {method} | {100 * s['all_classes_right']:.0f} % "
                         f"({s['subjects']}) | "
                         f"{100 * s['median_abs_kp_error_all_modules']:.1f} % | {per('kp')} | "
                         f"{per('kd')} | {per('delay_s')} | {100 * s['e_rel_median']:.1f} % | "
                         f"{s['seconds_median']:.3g} |")
        share = next((s["locked_share_median"] for k, s in stats.items()
                      if k.startswith(stimulus_key + "|")), float("nan"))
        lines += ["", f"Median realised locked share: {100 * share:.1f} %.", ""]
        judged = [(m, stats[f"{stimulus_key}|{m}"]) for m in METHODS
                  if "doubtful_far" in stats.get(f"{stimulus_key}|{m}", {})]
        if judged:
            lines += ["The trust verdict (far: a wrong class or E_rel of the locked response "
                      f"above {100 * FAR_E_REL:g} %; want doubtful for ≥ 90 % of the far "
                      "answers and ≤ 10 % of the others):", "",
                      "| method | far: doubtful | right: doubtful | fitted again, classes "
                      "relaxed |", "|---|---|---|---|"]
            for m, st in judged:
                right = st["subjects"] - st["far"]
                lines.append(f"| {m} | {st['doubtful_far']}/{st['far']} | "
                             f"{st['doubtful_right']}/{right} | "
                             + (f"{st['relaxed']}/{st['subjects']}" if "hybrid" in m else "")
                             + " |")
            lines.append("")
    lines += ["![E_rel of the locked response per method](real_like.png)", ""]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", type=int, default=30)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--body", type=Path, default=None,
                        help="the subjects' body URDF (default: the TIP); the CNN, FRF net "
                             "and hybrid rows need the TIP")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--models", type=Path, default=ROOT / "data" / "models",
                        help="folder of real_<states>_<cnn|frf> model directories")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "results")
    parser.add_argument("--stimuli", nargs="+", choices=list(STIMULI), default=list(STIMULI),
                        help="PRTS lengths to run (default: both)")
    parser.add_argument("--methods", nargs="*", choices=METHODS, default=list(METHODS),
                        help="methods to run (default: all; none, with --reuse: rewrite the "
                             "report from the earlier rows)")
    parser.add_argument("--universal", type=Path,
                        help="a universal model directory for the universal rows (default: "
                             "the bundled one)")
    parser.add_argument("--reuse", type=Path,
                        help="an earlier real_like.json of the same subjects and seed: the "
                             "rows of the methods not run now are taken from it (e.g. the "
                             "least-squares rows after retraining a network)")
    args = parser.parse_args()
    body = load_body(args.body) if args.body else load_body()
    urdf = str(body.urdf_path)
    journal = args.out / "real_like.journal.jsonl"
    header = {"format": "posture_id-real-like-journal", "subjects": args.subjects,
              "seed": args.seed, "body_sha256": body.sha256, "stimuli": args.stimuli,
              "methods": args.methods}
    key = lambda r: (r["stimulus"], int(r["index"]), r["method"])  # noqa: E731
    book = Journal(journal, header, key)
    done = book.read()
    tasks = []
    specs = subjects(body, args.subjects, args.seed)
    for stimulus_key in args.stimuli:
        folders = {kind: str(args.models / f"real_{stimulus_key}_{kind}")
                   for kind in ("cnn", "frf")}
        folders["universal"] = str(args.universal) if args.universal else None
        for method, kind in (("CNN", "cnn"), ("FRF net", "frf")):
            if method in args.methods and not (Path(folders[kind]) / "model.json").exists():
                raise SystemExit(f"{folders[kind]}: no model for the {method} rows; make it "
                                 "with `make real-like-models`, or leave the method out "
                                 "(--methods)")
        for index, spec in enumerate(specs):
            for method in args.methods:
                if (stimulus_key, index, method) not in done:
                    tasks.append((stimulus_key, index, spec, method, folders, urdf))
    rows = list(done.values())
    if args.reuse is not None:
        earlier = json.loads(args.reuse.read_text(encoding="utf-8"))
        if (earlier["subjects"], earlier["seed"]) != (args.subjects, args.seed):
            raise SystemExit(f"{args.reuse}: made for other subjects or another seed")
        reused = [r for r in earlier["rows"]
                  if r["method"] not in args.methods and r["stimulus"] in args.stimuli]
        for r in reused:  # JSON writes an infinite E_rel (the body fell) as null
            r["e_rel"] = math.inf if r["e_rel"] is None else r["e_rel"]
        rows += reused
    total = len(rows) + len(tasks)
    print(f"{len(rows)} identifications journalled, {len(tasks)} to do", flush=True)
    began = time.perf_counter()
    with LocalExecutor(args.workers, processes=True) as pool:
        for _, row in pool.unordered(_one, tasks):
            rows.append(row)
            book.append(row)
            print(f"[{len(rows)}/{total}] "
                  f"{row['stimulus']} #{row['index']} {row['method']}: classes "
                  f"{sum(row['classes_correct'])}/{len(row['classes_correct'])}, Kp "
                  + ", ".join(f"{100 * e[0]:+.0f} %" for e in row["relative_error"])
                  + f", {row['seconds']:.1f} s ({time.perf_counter() - began:.0f} s)",
                  flush=True)
    rows.sort(key=lambda r: (r["stimulus"], r["index"], METHODS.index(r["method"])))
    stats = statistics(rows, body.joint_names)
    args.out.mkdir(parents=True, exist_ok=True)
    models = {}
    if args.reuse is not None:
        models.update(json.loads(args.reuse.read_text(encoding="utf-8"))["models"])
    for stimulus_key in args.stimuli:
        folders = {kind: args.models / f"real_{stimulus_key}_{kind}" for kind in ("cnn", "frf")}
        for kind, folder in folders.items():
            if not (folder / "model.json").exists():
                continue
            sidecar = json.loads((folder / "model.json").read_text(encoding="utf-8"))
            models[f"{stimulus_key}_{kind}"] = {"trials": sidecar["dataset"]["trials"],
                                                "weights_sha256": sidecar["weights_sha256"]}
        if any("hybrid" in m for m in args.methods):
            start = hybrid_start({k: str(v) for k, v in folders.items()})
            models[f"{stimulus_key}_hybrid"] = {
                "start": "the people-like CNN" if start != "bundled"
                else "the bundled model (sensor noise only)"}
    atomic_write_text(args.out / "real_like.json", json_text(
        {"subjects": args.subjects, "seed": args.seed, "share_range": SHARE_RANGE,
         "models": models, "statistics": stats, "rows": rows}))
    atomic_write_text(args.out / "real_like.md",
                      markdown(stats, body.joint_names, args.subjects, args.workers, models,
                               "the TIP" if args.body is None else f"body '{body.name}'"))
    groups = {}
    for stimulus_key in STIMULI:
        for method in METHODS:
            mine = [r for r in rows if r["stimulus"] == stimulus_key and r["method"] == method]
            if mine:
                groups[f"{method}\n{stimulus_key}"] = ([min(r["e_rel"], 10.0) for r in mine],
                                                       [r["seconds"] for r in mine])
    plot_benchmark(groups, path=args.out / "real_like.png")
    journal.unlink(missing_ok=True)
    print(f"wrote {args.out / 'real_like.md'}")


if __name__ == "__main__":
    main()
