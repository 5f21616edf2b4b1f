"""What the recording allows: an estimator that knew the answer, on people-like sway.

Run:  .venv/bin/python benchmarks/recording_limit.py [--subjects 24] [--workers 2] [--clean]
                                                     [--out docs/results/recording_limit]

The people-like subjects of every noise family that ``benchmarks/honest_verdict.py``
judges (the same draws: its ``_recording``; the same subjects the leave-one-family-out
table, ``benchmarks/noise_lofo.py``, judges each network on), each fitted by the locked
least squares (``posture-id identify --method fit --locked``: the stimulus-locked sway
only) started at the truth with the true classes held (``FixedClasses``), twice: without
a prior, and with docs/model.md §5's (``--prior-sd 0.5`` about the body's defaults, as the
project recommends the locked fit). Its error is what the recording's own noise leaves to
an estimator that needs no search and no class decision: a proxy for the recording's
limit, beside which a network's error reads as a ratio (the leave-one-family-out table's
last columns). Writes ``rows.json`` (per subject: the family, the body, the locked share,
each fit's relative error per module and parameter, its normalised estimate, the truth and
its standard errors as reported and as Gauss-Newton's alone) and ``report.md`` (the median
|Kp error| per family, and how often the fits' own 90 % intervals hold the truth, per
family; ``--clean``: on the clean subjects too); resumable (a journal, removed once
``rows.json`` is written).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from statistics import NormalDist

import numpy as np

from posture_id.dec.parameters import TARGET_FIELDS
from posture_id.errors import PostureIdError
from posture_id.executors import LocalExecutor
from posture_id.fileio import atomic_write_text, json_text
from posture_id.simulation.noise_families import NoiseFamily
from posture_id.studies.journal import Journal
from posture_id.uncertainty.coverage import coverage

sys.path.insert(0, str(Path(__file__).resolve().parent))
from honest_verdict import _recording  # noqa: E402  (a sibling script: the same subjects)

COMMAND = ".venv/bin/python benchmarks/recording_limit.py"
#: The task family of honest_verdict.py's clean subjects (sensor noise alone).
CLEAN = "clean"
#: z of a 90 % interval.
Z90 = NormalDist().inv_cdf(0.95)


def _one(task: tuple[str, int]) -> dict:
    """The oracle's fit of one people-like subject (family, index)."""
    from posture_id.fitting.least_squares import fit_recording
    from posture_id.fitting.options import FitOptions, FixedClasses
    from posture_id.frf.locked import LockedOptions
    from posture_id.trials import prepare_trial

    family, index = task
    row = {"family": family, "index": index}
    made = _recording(*(("clean", "clean") if family == CLEAN else ("people-like", family)),
                      index)
    if made is None:
        return {**row, "skipped": True}
    recording, body, truth, stimulus, extra = made
    began = time.perf_counter()
    trial = prepare_trial(recording, stimulus)
    truth_si = np.array([[getattr(truth[j], f) for f in TARGET_FIELDS]
                         for j in body.joint_names])
    row.update(segments=body.n_segments, locked_share=extra.get("locked_share"))
    for name, prior in (("", None), ("prior_", 0.5)):
        options = FitOptions(locked=LockedOptions(), classes=FixedClasses(), prior_sd=prior)
        try:
            fit = fit_recording(trial, body, truth, options)
        except PostureIdError as error:
            row[f"{name}failed"] = str(error)
            continue
        found = np.array([[getattr(fit.parameters[j], f) for f in TARGET_FIELDS]
                          for j in body.joint_names])
        row[f"{name}kp_error"] = (found[:, 0] / truth_si[:, 0] - 1).tolist()
        row[f"{name}errors"] = (found / np.where(truth_si == 0, np.nan, truth_si) - 1).tolist()
        defaults = np.array([[getattr(fit.defaults[j], f) for f in TARGET_FIELDS]
                             for j in body.joint_names])
        row[f"{name}intervals"] = {
            "estimate": fit.normalised[:, :4].tolist(),
            "truth": (truth_si / defaults - 1).tolist(),
            "se": fit.standard_errors_normalised.tolist(),
            "white_se": fit.white_standard_errors_normalised.tolist()}
    return {**row, "seconds": time.perf_counter() - began}


def oracle_medians(rows: list[dict], prior: bool = False) -> dict[str, float]:
    """Median |Kp error| of the oracle's fits per noise family (``prior``: the fits with
    docs/model.md §5's prior, ``--prior-sd 0.5``)."""
    key = "prior_kp_error" if prior else "kp_error"
    out = {}
    for family in NoiseFamily:
        kp = [abs(e) for r in rows if r["family"] == family.value and key in r
              for e in r[key]]
        if kp:
            out[family.value] = float(np.median(kp))
    return out


def interval_coverage(rows: list[dict], prior: bool, white: bool) -> tuple[float, float, int]:
    """(Kp, every parameter) shares of the truths inside the fits' 90 % intervals
    (estimate ± z·SE, normalised, cut at −1), and the modules: with the standard errors
    as the fit reports them (the cluster-robust ones where larger), or ``white``: the
    Gauss-Newton ones of independent residuals alone."""
    key = "prior_intervals" if prior else "intervals"
    parts = [row[key] for row in rows if key in row]
    if not parts:
        return np.nan, np.nan, 0
    estimate, truth, se = (np.concatenate([p[k] for p in parts]).astype(float)
                           for k in ("estimate", "truth", "white_se" if white else "se"))
    share = coverage(truth, np.maximum(estimate - Z90 * se, -1.0), estimate + Z90 * se)
    return float(share[0]), float(share.mean()), len(truth)


def coverage_lines(rows: list[dict]) -> list[str]:
    """The report's section on the fits' own intervals, when the rows carry them."""
    families = list(dict.fromkeys(r["family"] for r in rows if "intervals" in r))
    if not families:
        return []
    lines = ["", "The fits' own 90 % intervals (estimate ± 1.645·SE): the truth inside, Kp / "
             "every parameter, with the Gauss-Newton standard errors of independent "
             "residuals, and as the fit reports them (the cluster-robust ones where larger: "
             "the noise each harmonic shares between channels, read from the residual; "
             "docs/fit.md):", "",
             "| family | modules | no prior: independent | no prior: as reported | with the "
             "prior: independent | with the prior: as reported |", "|---|---|---|---|---|---|"]

    for family in [*families, None]:
        chosen = [r for r in rows if family is None and r["family"] != CLEAN
                  or r["family"] == family]
        cells = [interval_coverage(chosen, prior, white)
                 for prior, white in ((False, True), (False, False), (True, True),
                                      (True, False))]
        lines.append(f"| {family or 'every noise family'} | {cells[1][2]} | " + " | ".join(
            f"{100 * kp:.0f} % / {100 * every:.0f} %" for kp, every, _ in cells) + " |")
    return lines


def report(rows: list[dict], command: str) -> str:
    plain, prior = oracle_medians(rows), oracle_medians(rows, prior=True)
    lines = ["# What the recording allows", "",
             f"Made by `{command}` (what it does: the script's "
             "docstring): the locked least-squares fit started at the truth with the true "
             "classes, on the people-like subjects of each noise family that the honest "
             "verdict and the leave-one-family-out table judge; without a prior and with "
             "docs/model.md §5's (`--prior-sd 0.5`, about the body's defaults).", "",
             "| family | subjects | modules | median \\|Kp error\\|, no prior | 90th "
             "percentile | median, with the prior | 90th percentile |",
             "|---|---|---|---|---|---|---|"]
    for family, median in plain.items():
        group = [r for r in rows if r["family"] == family and "kp_error" in r]
        kp = np.abs(np.concatenate([r["kp_error"] for r in group]))
        with_prior = np.abs(np.concatenate([r["prior_kp_error"] for r in rows
                                            if r["family"] == family
                                            and "prior_kp_error" in r]))
        lines.append(f"| {family} | {len(group)} | {len(kp)} | {100 * median:.1f} % | "
                     f"{100 * np.percentile(kp, 90):.1f} % | {100 * prior[family]:.1f} % | "
                     f"{100 * np.percentile(with_prior, 90):.1f} % |")
    lines += coverage_lines(rows)
    failed = [r for r in rows if "failed" in r or "prior_failed" in r]
    if failed:
        lines += ["", f"{len(failed)} subjects with a fit that failed: " + "; ".join(
            f"{r['family']} #{r['index']}: {r.get('failed') or r.get('prior_failed')}"
            for r in failed)]
    skipped = [r for r in rows if r.get("skipped")]
    if skipped:
        lines += ["", f"{len(skipped)} subjects not drawn (each draw fell)."]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", type=int, default=24)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--clean", action="store_true",
                        help="the honest verdict's clean subjects too (sensor noise alone): "
                             "the intervals' coverage where the noise is what the fit assumes")
    parser.add_argument("--out", type=Path, default=Path("docs/results/recording_limit"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    tasks = [(f.value, i) for f in NoiseFamily for i in range(args.subjects)]
    if args.clean:
        tasks += [(CLEAN, i) for i in range(args.subjects)]
    command = (f"{COMMAND} --subjects {args.subjects}" + (" --clean" if args.clean else "")
               + ("" if args.out == Path("docs/results/recording_limit")
                  else f" --out {args.out}"))
    book = Journal(args.out / "journal.jsonl",
                   {"format": "posture_id-recording-limit", "subjects": args.subjects},
                   lambda r: (r["family"], int(r["index"])))
    done = book.read()
    todo = [t for t in tasks if t not in done]
    print(f"{len(done)} done, {len(todo)} to do", flush=True)
    with LocalExecutor(args.workers, processes=True) as pool:
        for k, (_, row) in enumerate(pool.unordered(_one, todo), 1):
            book.append(row)
            done[(row["family"], row["index"])] = row
            print(f"[{k} of {len(todo)}] {row['family']} #{row['index']}: "
                  f"{row.get('kp_error', 'skipped')} / {row.get('prior_kp_error')}",
                  flush=True)
    rows = [done[t] for t in tasks]
    atomic_write_text(args.out / "rows.json", json_text({"subjects": args.subjects,
                                                         "rows": rows}))
    text = report(rows, command)
    atomic_write_text(args.out / "report.md", text)
    (args.out / "journal.jsonl").unlink(missing_ok=True)  # rows.json holds every row
    print(text)


if __name__ == "__main__":
    main()
