"""Noise the network never saw: leave one noise family out, fine-tune on the others, and
report on the one left out.

Run:  .venv/bin/python benchmarks/noise_lofo.py [--set data/universal_families]
          [--beside SET ...] [--base data/models/universal] [--epochs 6]
          [--learning-rate 3e-4] [--motor-noise-tilt 0]
          [--held-out F ...] [--subjects 24] [--gated [--widen 24]] [--no-bundled]
          [--out docs/results/noise_lofo]

The set: ``make noise-families`` (``posture-id network universal data --out
data/universal_families --shards 900 --seed 11 --clean-share 0.1 --locked-share 0.1 0.6
--noise-families low_pass two_corners shallow correlated drifting changing``). The base:
the universal network trained under the low-pass motor noise alone (``make
universal-model``'s first stage, ``data/models/universal``; the bundled network is its
fine-tune on every family, so it cannot be the start here). For each family but
``low_pass``, a model is fine-tuned from the base on the set's trials of the *other*
families (``posture-id network universal train SET --init BASE --exclude-families F
--fresh-motor-noise [--motor-noise-tilt T]``), calibrated on them (``posture-id network
universal calibrate``: the calibration leaves F out too; ``--beside``: other sets trained
and calibrated on beside it, as the bundled network's recipe has the fifth of the five sets, ``make
universal-fifth``), and judged on 24 people-like subjects of F
made outside any set (``benchmarks/honest_verdict.py --model ... --groups people-like
--families F``; ``--gated``: each fine-tune first put in one model with the base, gated
by the noise, as the bundled model is: ``posture-id network universal ensemble BASE FINE
--by-noise``, then calibrated; ``--widen N``: then given its recording widening, fitted on
its own answers to N people-like subjects of each family it saw, drawn with another seed,
as ``make recording-widening`` fits the bundled model's, so that F is judged with intervals
widened by a widening that never saw F). With all five held out in turn, the bundled model (the
base fine-tuned on every family) is judged on all six beside them. Writes ``report.md`` (the
leave-one-family-out table beside the base network's) and each run's folder; every stage
is skipped when its output is there (resumable; a family judged already needs no model).
Without ``data/models/universal``, the base is written there from the bundled model: its
white-noise member, checked byte for byte against the SHA-256 the bundled sidecar names.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from posture_id.fileio import atomic_write_text
from posture_id.simulation.noise_families import NoiseFamily

sys.path.insert(0, str(Path(__file__).resolve().parent))
from honest_verdict import family_cells  # noqa: E402  (a sibling script)

HELD_OUT = [f.value for f in NoiseFamily if f is not NoiseFamily.LOW_PASS]
HERE = Path(__file__).resolve().parent
#: The network trained on the low-pass noise alone (``make universal-model``'s first stage).
BASE = Path("data/models/universal")
#: The seed of the subjects a held-out family's widening is fitted on (``make
#: recording-widening``'s for the bundled model).
WIDENING_SEED = 777


def _fine_tune(data: list[Path], out: Path, exclude: tuple[str, ...], epochs: int,
               learning_rate: float, base: Path, tilt: float) -> None:
    from posture_id.learning.universal_training import UniversalTrainingConfig, train_universal
    from posture_id.studies.universal_check import calibrate_model

    if not (out / "model.json").exists():
        # patience = epochs: the one-cycle schedule runs to its end, as the bundled
        # network's fine-tune did (its validation loss was best at the last epochs; a
        # held-out family's run stopped at epoch 13 on its first epoch's weights)
        config = UniversalTrainingConfig(epochs=epochs, init=str(base), patience=epochs,
                                         max_learning_rate=learning_rate,
                                         exclude_families=exclude, fresh_motor_noise=True,
                                         motor_noise_tilt=tilt)
        train_universal(data, out, config, progress=lambda u: u.message and print(
            f"  {out.name}: {u.message}", flush=True))
    if not (out / "calibration.json").exists():
        calibrate_model(out, data)


def _gated(data: list[Path], fine: Path, base: Path) -> Path:
    """The base and the fine-tune ``fine`` in one model gated by the noise (the bundled
    recipe's last step), calibrated on ``data``: ``fine`` + ``_gated``."""
    from posture_id.learning.universal_model import UniversalModel, ensemble_of
    from posture_id.studies.universal_check import calibrate_model

    out = fine.with_name(fine.name + "_gated")
    if not (out / "calibration.json").exists():
        ensemble_of([UniversalModel.load(base), UniversalModel.load(fine)],
                    by_noise=True).save(out)
        calibrate_model(out, data)
    return out


def _judge(model: Path | None, families: list[str], groups: list[str], subjects: int,
           out: Path, seed: int | None = None) -> list[dict]:
    if not (out / "report.md").exists():
        command = [sys.executable, str(HERE / "honest_verdict.py"), "--subjects", str(subjects),
                   "--groups", *groups, "--families", *families, "--out", str(out)]
        if seed is not None:
            command += ["--seed", str(seed)]
        if model is not None:
            command += ["--model", str(model)]
        subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    return json.loads((out / "rows.json").read_text(encoding="utf-8"))["rows"]


def _widen(model: Path, family: str, subjects: int) -> None:
    """Fit ``model``'s recording widening (:mod:`posture_id.uncertainty.widening`) on its
    own answers to ``subjects`` people-like subjects of each family but ``family``, drawn
    with :data:`WIDENING_SEED` (others than the judged ones, as ``make recording-widening``
    draws the bundled model's), and write it beside the model: the held-out family is
    then judged with intervals widened by a widening that never saw it."""
    from posture_id.studies.widening import people_rows, widening_for
    from posture_id.uncertainty.widening import WIDENING_FILE

    if (model / WIDENING_FILE).exists():
        return
    others = [f.value for f in NoiseFamily if f.value != family]
    calibration = model / "widening_calibration"
    _judge(model, others, ["people-like"], subjects, calibration, WIDENING_SEED)
    made_by = (f"benchmarks/noise_lofo.py: {subjects} people-like subjects of each family "
               f"but {family}, seed {WIDENING_SEED}")
    widening_for(model, people_rows(calibration / "rows.json"), made_by=made_by).save(model)


def _bundled_base(out: Path) -> None:
    """Write the base (``make universal-model``'s first stage) at ``out`` as the bundled
    model holds it: its white-noise member, checked byte for byte against the SHA-256 its
    sidecar names."""
    from posture_id.learning.universal_identifier import BUNDLED_DIR
    from posture_id.learning.universal_model import UniversalModel

    bundled = UniversalModel.load(BUNDLED_DIR)
    base = bundled.member(0)
    base.save(out)
    if base.sidecar["weights_sha256"] != bundled.member_sha256(0):
        raise SystemExit(f"{out}: the bundled model's first member is not the base its "
                         "sidecar names (another SHA-256)")
    print(f"{out}: the base, the bundled model's white-noise member", flush=True)


def _oracle(folder: Path) -> tuple[dict, dict] | None:
    """Median |Kp error| per family of the oracle's fits without and with the prior
    (``benchmarks/recording_limit.py``'s rows), or None when they are not there."""
    from recording_limit import oracle_medians

    file = folder / "rows.json"
    if not file.is_file():
        return None
    rows = json.loads(file.read_text(encoding="utf-8"))["rows"]
    return oracle_medians(rows), oracle_medians(rows, prior=True)


def _against(oracle: tuple[dict, dict] | None, rows: list[dict], family: str) -> str:
    """The oracle's cells of a row: its median |Kp error| (with the prior), and the
    network's median over each."""
    if oracle is None or family not in oracle[0]:
        return " | "
    plain, prior = oracle[0][family], oracle[1][family]
    kp = np.median(np.abs(np.concatenate([
        r["kp_error"] for r in rows if r["group"] == "people-like" and r["kind"] == family
        and not r.get("skipped")])))
    return (f"{100 * plain:.1f} % ({100 * prior:.1f} %) | {kp / plain:.2f} "
            f"({kp / prior:.2f})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--set", type=Path, default=Path("data/universal_families"))
    parser.add_argument("--beside", type=Path, nargs="+", default=[],
                        help="sets fine-tuned and calibrated on beside --set (their trials "
                             "of the held-out family left out too; default none)")
    parser.add_argument("--base", type=Path, default=BASE,
                        help="the network to fine-tune from, trained on the low-pass noise "
                             f"alone (default {BASE}: make universal-model's first stage)")
    parser.add_argument("--models", type=Path, default=Path("data/models/noise_lofo"))
    parser.add_argument("--epochs", type=int, default=6)
    parser.add_argument("--learning-rate", type=float, default=3e-4)
    parser.add_argument("--motor-noise-tilt", type=float, default=0.0,
                        help="the fine-tunes' motor-noise tilt (posture-id network universal train "
                             "--motor-noise-tilt; default 0)")
    parser.add_argument("--held-out", nargs="+", default=HELD_OUT, choices=HELD_OUT,
                        help="the families to hold out, one at a time (default: all five)")
    parser.add_argument("--subjects", type=int, default=24)
    parser.add_argument("--gated", action="store_true",
                        help="judge each fine-tune in one model with the base, gated by the "
                             "noise (the bundled recipe)")
    parser.add_argument("--widen", type=int, metavar="SUBJECTS", default=0,
                        help="with --gated: before judging a held-out family, fit the model's "
                             "recording widening on its answers to SUBJECTS people-like "
                             f"subjects of each other family (seed {WIDENING_SEED}), as the "
                             "bundled model's is fitted (default 0: none)")
    parser.add_argument("--no-bundled", action="store_true",
                        help="leave out the bundled model's table (judged otherwise when "
                             "all five families are held out)")
    parser.add_argument("--out", type=Path, default=Path("docs/results/noise_lofo"))
    parser.add_argument("--oracle", type=Path, default=Path("docs/results/recording_limit"),
                        help="benchmarks/recording_limit.py's output: the error of the "
                             "locked fit started at the truth on the same subjects, the "
                             "table's last columns (default %(default)s; left out when "
                             "missing)")
    args = parser.parse_args()
    if args.widen and not args.gated:
        parser.error("--widen fits the gated model's widening: give --gated too")
    if not (args.base / "model.json").is_file():
        if args.base != BASE:
            raise SystemExit(f"{args.base}: no universal model there (name one trained on "
                             "the low-pass noise alone with --base)")
        _bundled_base(args.base)
    base = _judge(args.base, [f.value for f in NoiseFamily], ["people-like"], args.subjects,
                  args.out / "base")
    tilt = (f" --motor-noise-tilt {args.motor_noise_tilt:g}" if args.motor_noise_tilt
            else "")
    held = "" if list(args.held_out) == HELD_OUT else " --held-out " + " ".join(args.held_out)
    beside = "".join(f" {p}" for p in args.beside)
    beside = f" --beside{beside}" if beside else ""
    gated = " --gated" if args.gated else ""
    gated += f" --widen {args.widen}" if args.widen else ""
    gated += " --no-bundled" if args.no_bundled else ""
    fine = "fine-tuned without it" + (", gated with the base" if args.gated else "")
    lines = ["# Noise the network never saw: leave one family out", "",
             f"Made by `.venv/bin/python benchmarks/noise_lofo.py --set {args.set}{beside} --base "
             f"{args.base} --epochs {args.epochs} --learning-rate {args.learning_rate:g}{tilt}"
             f"{held} --subjects {args.subjects}{gated} --models {args.models} --out {args.out}` "
             "(the set and the stages: its docstring). Each row: "
             f"{args.subjects} people-like subjects (15–40 % locked) of one noise family, "
             "identified by the default method with the base network (trained on the "
             "low-pass noise alone), and with it fine-tuned on the set's other families "
             "(the family never simulated for it)"
             + ("; that fine-tune in one model with the base, gated by the recording's "
                "noise, as the bundled model is" if args.gated else "")
             + (f"; its intervals widened by the recording's own noise, the widening fitted "
                f"on its answers to {args.widen} people-like subjects of each other family "
                f"(seed {WIDENING_SEED}), as the bundled model's is" if args.widen else "")
             + ".", "",
             "| held-out family | network | modules: every class right | median \\|Kp error\\| "
             "| 90 % intervals holding the true Kp | all parameters | the oracle's median "
             "\\|Kp error\\| (with the prior) | network / oracle (with the prior) |",
             "|---|---|---|---|---|---|---|---|"]
    oracle = _oracle(args.oracle)
    for family in args.held_out:
        model = args.models / f"without_{family}"
        if not (args.out / family / "rows.json").exists():  # judged already: no model needed
            print(f"{family}: fine-tuning without it", flush=True)
            _fine_tune([*args.beside, args.set], model, (family,), args.epochs,
                       args.learning_rate, args.base, args.motor_noise_tilt)
            if args.gated:
                model = _gated([*args.beside, args.set], model, args.base)
            if args.widen:
                _widen(model, family, args.widen)
        rows = _judge(model, [family], ["people-like"], args.subjects, args.out / family)
        lines.append(f"| {family} | base | {family_cells(base, family)} | "
                     f"{_against(oracle, base, family)} |")
        lines.append(f"| {family} | {fine} | {family_cells(rows, family)} | "
                     f"{_against(oracle, rows, family)} |")
    if list(args.held_out) == HELD_OUT and not args.no_bundled:  # every family seen
        bundled = _judge(None, [f.value for f in NoiseFamily], ["people-like"],
                         args.subjects, args.out / "bundled")
        lines += ["", "The bundled model (`make universal-noise-model`: the base fine-tuned on "
                  "every family, beside the first fifth of its own five sets, gated with the "
                  "base by the noise; each row's family seen):", "",
                  "| family | modules: every class right | median \\|Kp error\\| | 90 % "
                  "intervals holding the true Kp | all parameters | the oracle's median "
                  "\\|Kp error\\| (with the prior) | network / oracle (with the prior) |",
                  "|---|---|---|---|---|---|---|"]
        lines += [f"| {f.value} | {family_cells(bundled, f.value)} | "
                  f"{_against(oracle, bundled, f.value)} |" for f in NoiseFamily]
        if oracle is not None:
            lines += ["", "The oracle: the locked least-squares fit started at the truth "
                      "with the true classes, on the same subjects, without a prior (and "
                      "with docs/model.md §5's, `--prior-sd 0.5`): what an estimator that "
                      "knew the answer would still miss "
                      f"(`benchmarks/recording_limit.py`, {args.oracle}/report.md)."]
    atomic_write_text(args.out / "report.md", "\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
