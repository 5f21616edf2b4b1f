"""Do the design's predictions hold? Predicted against realised errors of least squares.

Run:  .venv/bin/python benchmarks/design_check.py [--subjects 50] [--workers 2]
          [--body URDF] [--out docs/results/design]

For each of 4 protocols × 2 noise regimes (sensor noise 0.05° only; people-like: motor
noise leaving 30 % of the body COM sway locked, plus 0.05° sensor noise), ``--subjects``
subjects drawn from docs/model.md §5's prior (a seed no other run uses; subjects who fall are
drawn again) are simulated and identified by the locked least-squares fit
(``FitOptions.locked``), started at their true parameters with their classes known (the
design predicts the noise's effect on the estimate, not the search's failures, which
``posture-id network cnn benchmark`` measures). Subjects are simulated and fitted at the design's
integration step (5 ms), so that the comparison is of statistics, not of step sizes.

The design (:func:`posture_id.design.predict.predict_protocols`) predicts, for the same
subjects, the standard error of every normalised parameter. Per protocol and regime:

- per parameter (module × Kp, Ki, Kd, delay): the predicted RMS error (the design's
  ``rms_error``: the linearised fit held within its bounds, :mod:`posture_id.design.
  bounded`) against the realised RMS error of the fits; the median ratio over all
  parameters (the issue's reading), and over the parameters the design calls determined
  (predicted 90 % width under half the prior's); the unbounded prediction √(mean SE²),
  for comparison;
- the predicted interval width against the fit's own (Gauss-Newton) interval width;
- the ranking of the protocols by predicted score (geometric mean width) against their
  ranking by realised RMS error (Spearman's ρ).

Writes ``design_check.{md,json}`` to ``--out``; a journal makes a run resumable.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr

from posture_id.bodies.body import DEFAULT_URDF, load_body
from posture_id.dec.parameters import ParameterArrays, default_parameters, normalise_arrays
from posture_id.dec.prior import sample_parameters
from posture_id.design.noise import SwayNoise
from posture_id.design.predict import DesignOptions, predict_protocols, prior_width
from posture_id.design.report import UNDETERMINED
from posture_id.errors import SimulationError
from posture_id.executors import executor_for
from posture_id.fileio import atomic_write_text, json_text
from posture_id.fitting import FitOptions, fit_recording
from posture_id.fitting.options import FixedClasses
from posture_id.frf.locked import LockedOptions
from posture_id.simulation.batch import simulate, simulate_batch
from posture_id.simulation.options import SimulationOptions
from posture_id.simulation.protocols import (
    MultisineProtocol,
    PrtsProtocol,
    protocol_from_dict,
)
from posture_id.simulation.subjects import people_like
from posture_id.trials import prepare_trial

PROTOCOLS = [PrtsProtocol(242, 0.25, 1.0, 2), PrtsProtocol(80, 0.25, 1.0, 6),
             PrtsProtocol(80, 0.25, 3.0, 6),
             MultisineProtocol(60.0, (1, 2, 3, 5, 8, 12, 18, 27, 40, 60, 90), 2.0, cycles=2)]
REGIMES = {"sensor only": SwayNoise(0.05), "people-like": SwayNoise(0.05, locked_share=0.3)}
SUBJECT_SEED = 0x44434B
#: parameters determined for fewer subjects than this are left out of the per-subject ratio
MIN_SUBJECTS = 10


def _subject(task: tuple) -> dict:
    """Simulate and fit one subject (runs in a worker process)."""
    urdf, protocol_dict, noise_dict, params_row, seed, dt = task
    body = load_body(urdf)
    protocol = protocol_from_dict(protocol_dict)
    noise = SwayNoise(**noise_dict)
    sim = SimulationOptions(dt=dt)
    params = ParameterArrays(**{k: np.asarray(v)[None] for k, v in params_row.items()}
                             ).trial(0, body.joint_names)
    profile = protocol.profile()
    started = time.perf_counter()
    try:
        if noise.locked_share is not None:
            recording = people_like(body, params, profile, noise.locked_share, seed,
                                    noise.sensor_noise_deg, noise.cutoff_hz, sim).recording
        else:
            result = simulate(body, params, profile, sim)
            if not result.stable:
                raise SimulationError("the subject falls")
            recording = result.to_recording().with_sensor_noise(noise.sensor_noise_deg, seed)
    except SimulationError as exc:
        return {"fell": str(exc)}
    trial = prepare_trial(recording, profile)
    options = FitOptions(simulation=sim, locked=LockedOptions(), classes=FixedClasses(),
                         warm_start=False, threads=1)
    fit = fit_recording(trial, body, init=params, options=options)
    return {"estimate": fit.normalised[:, :4].tolist(),
            "se": np.where(np.isfinite(fit.standard_errors_normalised),
                           fit.standard_errors_normalised, 1e9).tolist(),
            "converged": bool(fit.converged), "seconds": time.perf_counter() - started}


def _draw_subjects(body, count: int, rng: np.random.Generator) -> ParameterArrays:
    """``count`` subjects who stay up under every protocol, without noise."""
    kept: list[ParameterArrays] = []
    while sum(p.kp.shape[0] for p in kept) < count:
        batch = sample_parameters(body, 2 * count, rng)
        ok = np.ones(2 * count, bool)
        for protocol in PROTOCOLS:
            ok &= simulate_batch(body, batch, protocol.profile(),
                                 SimulationOptions(dt=DesignOptions().dt), workers=1).stable
        kept.append(_rows(batch, np.flatnonzero(ok)))
    whole = ParameterArrays(**{f: np.concatenate([getattr(p, f) for p in kept])
                               for f in ParameterArrays.FIELDS})
    return _rows(whole, np.arange(count))


def _rows(params: ParameterArrays, rows: np.ndarray) -> ParameterArrays:
    return ParameterArrays(**{f: np.asarray(getattr(params, f))[rows]
                              for f in ParameterArrays.FIELDS})


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", type=int, default=50)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--body", type=Path, default=DEFAULT_URDF)
    parser.add_argument("--out", type=Path, default=Path("docs/results/design"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    body = load_body(args.body)
    options = DesignOptions()
    subjects = _draw_subjects(body, args.subjects, np.random.default_rng(SUBJECT_SEED))
    truth = normalise_arrays(subjects, default_parameters(body))[:, :, :4]  # (S, N, 4)
    journal_file = args.out / "design_check_journal.json"
    journal = json.loads(journal_file.read_text()) if journal_file.exists() else {}
    rows = {}
    started = time.perf_counter()
    for regime, noise in REGIMES.items():
        t0 = time.perf_counter()
        predictions = predict_protocols(body, PROTOCOLS, noise, options, params=subjects)
        predict_seconds = time.perf_counter() - t0
        for k, (protocol, pred) in enumerate(zip(PROTOCOLS, predictions, strict=True)):
            key = f"{regime}|{k}"
            if key not in journal:
                tasks = [(str(args.body), protocol.to_dict(), noise.to_dict(),
                          {f: getattr(subjects, f)[s].tolist()
                           for f in ParameterArrays.FIELDS}, SUBJECT_SEED * 1000 + s,
                          options.dt) for s in range(args.subjects)]
                executor = executor_for(None, args.workers, processes=True)
                try:
                    out = [None] * len(tasks)
                    for task, result in executor.unordered(_subject, tasks):
                        out[tasks.index(task)] = result
                finally:
                    executor.close()
                journal[key] = out
                atomic_write_text(journal_file, json_text(journal))
                print(f"{regime}, {protocol.label()}: fitted "
                      f"({time.perf_counter() - started:.0f} s)", flush=True)
            rows[key] = _row(regime, protocol, pred, journal[key], truth, predict_seconds)
    report = _report(rows, args)
    atomic_write_text(args.out / "design_check.json", json_text(report))
    atomic_write_text(args.out / "design_check.md", _markdown(report) + "\n")
    print(_markdown(report))


def _row(regime, protocol, pred, fits, truth, predict_seconds) -> dict:
    ok = np.array([f is not None and "estimate" in f for f in fits])
    ok &= np.all(np.isfinite(pred.standard_errors), axis=(1, 2))
    est = np.array([f["estimate"] if "estimate" in f else np.full(truth.shape[1:], np.nan)
                    for f in fits])
    fit_se = np.array([f["se"] if "se" in f else np.full(truth.shape[1:], np.nan)
                       for f in fits])
    err = (est - truth)[ok]
    realised = np.sqrt(np.mean(err**2, axis=0))  # (N, 4)
    robust = 1.4826 * np.median(np.abs(err - np.median(err, axis=0)), axis=0)
    se = pred.standard_errors[ok]  # (S, N, 4)
    predicted = np.sqrt(np.mean(pred.bounded_rms[ok] ** 2, axis=0))
    unbounded = np.sqrt(np.mean(se**2, axis=0))
    width0 = prior_width()
    widths = 2 * 1.645 * se / width0  # (S, N, 4) each subject's predicted width
    predicted_width = np.median(widths, axis=0)
    fit_width = np.median(2 * 1.645 * fit_se[ok], axis=0) / width0
    determined = predicted_width < UNDETERMINED
    ratio = predicted / realised
    # per subject: only where that subject's prediction calls the parameter determined
    # (its own 90 % width under UNDETERMINED of the prior's); elsewhere the fit's bounds,
    # not the noise, limit the error, and one such subject dominates an RMS
    own = widths < UNDETERMINED
    counts = own.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        own_predicted = np.sqrt(np.sum(np.where(own, se, 0.0) ** 2, axis=0) / counts)
        own_realised = np.sqrt(np.sum(np.where(own, err, 0.0) ** 2, axis=0) / counts)
        z = np.where(own, err / se, np.nan)
        z_rms = np.sqrt(np.nansum(z**2, axis=0) / counts)
        # robust: the SD that the median |z| implies (1 for Gaussian errors that match)
        z_robust = np.full(counts.shape, np.nan)
        z_robust[counts > 0] = np.nanmedian(np.abs(z[:, counts > 0]), axis=0) / 0.6745
    enough = counts >= MIN_SUBJECTS
    own_ratio = own_predicted / own_realised
    return {"regime": regime, "protocol": protocol.label(), "subjects": int(ok.sum()),
            "predicted_rms": predicted.tolist(), "realised_rms": realised.tolist(),
            "predicted_rms_unbounded": unbounded.tolist(),
            "median_ratio_unbounded": float(np.median(unbounded / realised)),
            "realised_robust_sd": robust.tolist(), "ratio": ratio.tolist(),
            "determined": determined.tolist(),
            "median_ratio_determined": float(np.median(ratio[determined]))
            if determined.any() else None,
            "median_ratio_all": float(np.median(ratio)),
            "subject_determined_counts": counts.tolist(),
            "subject_determined_ratio": np.where(enough, own_ratio, np.nan).tolist(),
            "subject_determined_z_rms": np.where(enough, z_rms, np.nan).tolist(),
            "median_subject_determined_ratio": float(np.median(own_ratio[enough]))
            if enough.any() else None,
            "median_z_rms": float(np.median(z_rms[enough])) if enough.any() else None,
            "median_z_robust": float(np.median(z_robust[enough])) if enough.any() else None,
            "predicted_se": np.where(np.isfinite(se), se, None).tolist(),
            "errors": err.tolist(),
            "subject_determined_params": int(enough.sum()),
            "median_width_ratio": float(np.median(predicted_width / fit_width)),
            "predicted_score": float(np.exp(np.mean(np.log(predicted_width)))),
            "realised_score": float(np.exp(np.mean(np.log(realised)))),
            "fit_seconds_median": float(np.median([f["seconds"] for f in fits
                                                   if f and "seconds" in f])),
            "predict_seconds_all_protocols": predict_seconds}


def _report(rows: dict, args) -> dict:
    out = {"subjects": args.subjects, "body": str(args.body), "rows": list(rows.values()),
           "spearman": {}}
    for regime in REGIMES:
        these = [r for r in rows.values() if r["regime"] == regime]
        rho = spearmanr([r["predicted_score"] for r in these],
                        [r["realised_score"] for r in these]).statistic
        out["spearman"][regime] = float(rho)
    every = list(rows.values())
    out["spearman"]["all 8 cells"] = float(spearmanr(
        [r["predicted_score"] for r in every], [r["realised_score"] for r in every]).statistic)
    return out


def _markdown(report: dict) -> str:
    lines = ["# Predicted against realised: the design's check", "",
             f"Made by `benchmarks/design_check.py --subjects {report['subjects']}` on "
             f"{Path(report['body']).name}. Ratio: predicted / realised RMS error of the "
             "normalised parameters, the prediction being the linearised fit held within "
             "its bounds (median over all 4N parameters, the issue's reading; and over the "
             f"parameters predicted as determined, 90 % width < {UNDETERMINED} of the "
             "prior's). Unbounded: the same with the prediction √(mean SE²), which ignores "
             "the fit's bounds. Width ratio: "
             "predicted / the fit's own Gauss-Newton 90 % width (median over parameters). "
             "Per subject: the same ratio over the subjects whose own prediction calls the "
             f"parameter determined (parameters with at least {MIN_SUBJECTS} such subjects), "
             "and the RMS of the standardised errors z = error / predicted SE there (1 when "
             "the prediction holds), and robust z, the SD that their median |z| implies "
             "(insensitive to a few fits that went far). "
             "Scores: geometric mean over parameters of the predicted width and of the "
             "realised RMS error.", "",
             "| regime | protocol | subjects | ratio (all) | ratio (determined) | "
             "unbounded | ratio (per subject) | RMS z | robust z | width ratio | "
             "predicted score | realised score | fit s |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in report["rows"]:
        det, own = r["median_ratio_determined"], r["median_subject_determined_ratio"]
        own_text = "– | – | –" if own is None else (
            f"{own:.2f} ({r['subject_determined_params']} params) | {r['median_z_rms']:.2f} | "
            f"{r['median_z_robust']:.2f}")
        lines.append(f"| {r['regime']} | {r['protocol']} | {r['subjects']} | "
                     f"**{r['median_ratio_all']:.2f}** | "
                     f"{'–' if det is None else f'{det:.2f}'} ({sum(map(sum, r['determined']))}"
                     f" params) | {r['median_ratio_unbounded']:.2f} | "
                     f"{own_text} | "
                     f"{r['median_width_ratio']:.2f} | "
                     f"{r['predicted_score']:.3g} | {r['realised_score']:.3g} | "
                     f"{r['fit_seconds_median']:.1f} |")
    lines += ["", "Spearman's ρ between the predicted and the realised ranking: "
              + ", ".join(f"{k} {v:.2f}" for k, v in report["spearman"].items()) + "."]
    return "\n".join(lines)


if __name__ == "__main__":
    main()
