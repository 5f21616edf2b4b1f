"""Paired (within-subject) comparisons of FRFs: the sign-flip test's false-positive rate
and its power, on populations of independent-channel (IC) model subjects.

Run:  .venv/bin/python benchmarks/paired_test.py [--null 4000] [--power 2000]
      [--out docs/results/paired_test]

The population: IC subjects (``posture_id/models/ic``) on the default TIP body's plant
(J, m·g·h of :meth:`IcPlant.of`), their parameters drawn by
:func:`~posture_id.models.ic.subjects.draw_ic_parameters` (uniform within its RANGES, the
literature's spread around TYPICAL: Kp 1.3–2.5 and Kd 0.25–0.6 m·g·h(·s), Δ 0.08–0.22 s,
W 0.2–0.9, G 0.0–0.5, τ_f 5–40 s; redrawn until the closed loop is stable); a pool of
``--pool`` of them, each data set ``n`` drawn from the pool without replacement. Each
subject's exact body-COM-to-tilt FRF H_i(f) (:func:`closed_loop`) at Peterka's 11 points
(0.05–2.2 Hz, ``PETERKA_11``).

Each data set: n subjects (10 and 20) measured in conditions A and B, every trial's FRF
the subject's true one plus complex Gaussian noise ε with E|ε|² = (σ·|H_i(f)|)², σ =
``--noise`` (0.15: the gain and the phase each with an SD of σ/√2 = 10.6 % and 6.1°,
which by Bendat and Piersol's random error of an FRF estimate, sqrt(1 − γ²)/(|γ|·sqrt(2·
n_d)), is a coherence γ² of 0.8 over about 11 averaged spectra), independent between
trials and frequencies. Null: B's true FRF is A's. Alternatives: B's gain × ``--change``
(1.2) at 0.3 Hz alone; and a sensory reweighting, B's proprioceptive weight W + 0.05 for
every subject (a change of the whole FRF, largest at the low frequencies). Each data set is
compared by :func:`posture_id.norms.paired.compare_paired` (``--permutations`` 2000: all
1024 sign patterns for n = 10, 2000 random ones for n = 20).

Reported: the share of data sets with whole-FRF p < 0.05 (the summed Q, and the largest Q),
the share of the per-frequency tests with p < 0.05 (pooled and frequency by frequency), the
coverage of the gain-ratio and phase-difference intervals, each share with its 95 % Wilson
interval; under the alternatives the same shares (power) and the intervals' coverage of
the true ratio. Writes ``report.md`` and ``results.json`` into ``--out``.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

from posture_id import load_body
from posture_id.fileio import atomic_write_text, json_text
from posture_id.frf.bands import PETERKA_11
from posture_id.models.ic.response import IcPlant, closed_loop
from posture_id.models.ic.subjects import RANGES, draw_ic_parameters
from posture_id.norms.norm import FrfSet
from posture_id.norms.paired import compare_paired

ROOT = Path(__file__).resolve().parents[1]
F = np.asarray(PETERKA_11.centres_hz)
#: The alternative that changes one frequency: its index in F (0.3 Hz).
AT = int(np.argmin(np.abs(F - 0.3)))
#: The reweighting alternative: B's proprioceptive weight W + this.
REWEIGHT = 0.05
#: The alternatives' names.
GAIN, REWEIGHTED = "gain at 0.3 Hz", f"W + {REWEIGHT:g}"


def population(rng: np.random.Generator, size: int) -> tuple[np.ndarray, np.ndarray]:
    """(H (size, F), H with W + REWEIGHT (size, F)): a pool of IC subjects' exact body-COM
    FRFs (rad/rad) at Peterka's points."""
    plant = IcPlant.of(load_body())
    s = 2j * np.pi * F
    base, reweighted = [], []
    for _ in range(size):
        params = draw_ic_parameters(rng, plant)
        base.append(closed_loop(params, plant, s))
        reweighted.append(closed_loop(params.replace(w=params.w + REWEIGHT), plant, s))
    return np.asarray(base), np.asarray(reweighted)


def measured(rng: np.random.Generator, h: np.ndarray, noise: float) -> np.ndarray:
    """``h`` plus complex Gaussian noise of E|ε|² = (noise·|h|)²."""
    eps = rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape)
    return h + noise * np.abs(h) * eps / math.sqrt(2)


def averages(noise: float, coherence: float = 0.8) -> float:
    """n_d, the averaged spectra at which an FRF estimate of coherence γ² has the gain's
    relative random error noise/√2: ε = sqrt(1 − γ²)/(|γ|·sqrt(2·n_d)) (Bendat and
    Piersol)."""
    return (1 - coherence) / (coherence * 2 * (noise / math.sqrt(2)) ** 2)


def wilson(hits: int, count: int) -> tuple[float, float]:
    """The 95 % Wilson interval of a share hits/count."""
    z = 1.959964
    p = hits / count
    centre = (p + z * z / (2 * count)) / (1 + z * z / count)
    half = z * math.sqrt(p * (1 - p) / count + z * z / (4 * count * count)) / (1 + z * z / count)
    return centre - half, centre + half


def share(flags) -> dict:
    """{"rate", "low", "high", "count"} of boolean ``flags``."""
    flags = np.asarray(flags, dtype=bool).ravel()
    low, high = wilson(int(flags.sum()), flags.size)
    return {"rate": float(flags.mean()), "low": low, "high": high, "count": int(flags.size)}


def run(pool: tuple[np.ndarray, np.ndarray], n: int, datasets: int, alternative: str,
        args: argparse.Namespace, rng: np.random.Generator) -> dict:
    """``datasets`` data sets of n subjects under ``alternative`` ("null", GAIN or
    REWEIGHTED); the shares the report tables."""
    base, reweighted = pool
    true_ratio = np.ones(len(F))
    if alternative == GAIN:
        true_ratio[AT] = args.change
    # what the intervals estimate: the population's geometric mean gain ratio B/A (%) and
    # mean phase difference B − A (°), per frequency
    if alternative == REWEIGHTED:
        gain_truth = 100 * np.exp(np.mean(np.log(np.abs(reweighted / base)), axis=0))
        phase_truth = np.degrees(np.angle(np.mean(reweighted / base / np.abs(
            reweighted / base), axis=0)))
    else:
        gain_truth, phase_truth = 100 * true_ratio, np.zeros(len(F))
    whole, whole_max, per_f, adjusted, gain_cover, phase_cover, exact = ([] for _ in range(7))
    for _ in range(datasets):
        idx = rng.choice(len(base), size=n, replace=False)
        ha = base[idx]
        hb = reweighted[idx] if alternative == REWEIGHTED else ha * true_ratio
        names = tuple(f"s{i}" for i in range(n))
        result = compare_paired(
            FrfSet(F, measured(rng, ha, args.noise)[:, :, None], ("COM",), names),
            FrfSet(F, measured(rng, hb, args.noise)[:, :, None], ("COM",), names),
            permutations=args.permutations, level=0.95, seed=int(rng.integers(2**31)))
        whole.append(result.p_value < 0.05)
        whole_max.append(result.p_value_max < 0.05)
        per_f.append(result.p_values[:, 0] < 0.05)
        adjusted.append(result.p_adjusted[:, 0] < 0.05)
        exact.append(result.exact)
        gain_cover.append((result.gain_ratio_low[:, 0] <= gain_truth)
                          & (gain_truth <= result.gain_ratio_high[:, 0]))
        phase_cover.append((result.phase_low[:, 0] <= phase_truth)
                           & (phase_truth <= result.phase_high[:, 0]))
    per_f, adjusted = np.asarray(per_f), np.asarray(adjusted)
    others = np.delete(per_f, AT, axis=1) if alternative == GAIN else per_f
    return {"subjects": n, "data_sets": datasets, "alternative": alternative,
            "exact": bool(all(exact)), "whole_frf": share(whole),
            "whole_frf_largest_q": share(whole_max),
            "per_frequency_pooled": share(others),
            "per_frequency": {f"{f:g}": share(per_f[:, k]) for k, f in enumerate(F)},
            "per_frequency_adjusted": {f"{f:g}": share(adjusted[:, k])
                                       for k, f in enumerate(F)},
            "gain_interval_coverage": share(gain_cover),
            "phase_interval_coverage": share(phase_cover)}


def percent(s: dict) -> str:
    return f"{100 * s['rate']:.2f} % [{100 * s['low']:.2f}, {100 * s['high']:.2f}]"


def report(results: list[dict], args: argparse.Namespace, seconds: float,
           command: str) -> str:
    """The report's markdown."""
    null = [r for r in results if r["alternative"] == "null"]
    power = [r for r in results if r["alternative"] != "null"]
    at = f"{F[AT]:g}"
    lines = [
        "# Paired comparisons: the sign-flip test's level and power", "",
        f"Made by `{command}` ({seconds:.0f} s on this 2-core machine; what it does: the "
        "script's docstring).", "",
        f"IC subjects (a pool of {args.pool} drawn within `models/ic/subjects.py`'s RANGES: "
        + ", ".join(f"{k} {lo:g}–{hi:g}" for k, (lo, hi) in RANGES.items())
        + "; gains in m·g·h), their exact body-COM FRFs at Peterka's 11 points; every "
        f"trial's FRF with complex Gaussian noise of SD {100 * args.noise:.0f} % of the gain "
        f"(gain and phase SDs {100 * args.noise / math.sqrt(2):.1f} % and "
        f"{math.degrees(args.noise / math.sqrt(2)):.1f}°: by Bendat and Piersol's random "
        f"error, coherence 0.8 over about {averages(args.noise):.0f} averaged spectra); "
        f"`compare_paired` with {args.permutations} permutations (exact "
        "enumeration of the 1024 sign patterns for 10 subjects, 2000 random ones for 20). "
        "Each share with its 95 % Wilson interval.", "",
        "## False positives (both conditions from the same true FRFs)", "",
        "| subjects | data sets | test | whole FRF p < 0.05 (Σ Q) | whole FRF, largest Q | "
        "per frequency (all 11 pooled) | per frequency, range over the 11 | gain-ratio "
        "interval covers 100 % | phase interval covers 0° |",
        "|---|---|---|---|---|---|---|---|---|"]
    for r in null:
        rates = [100 * s["rate"] for s in r["per_frequency"].values()]
        lines.append(f"| {r['subjects']} | {r['data_sets']} | "
                     f"{'exact' if r['exact'] else 'random'} | {percent(r['whole_frf'])} | "
                     f"{percent(r['whole_frf_largest_q'])} | "
                     f"{percent(r['per_frequency_pooled'])} | {min(rates):.2f}–"
                     f"{max(rates):.2f} % | {percent(r['gain_interval_coverage'])} | "
                     f"{percent(r['phase_interval_coverage'])} |")
    lines += ["", "Per frequency (the share of data sets with p < 0.05):", "",
              "| subjects | " + " | ".join(f"{f:g} Hz" for f in F) + " |",
              "|---|" + "---|" * len(F)]
    for r in null:
        lines.append(f"| {r['subjects']} | " + " | ".join(
            f"{100 * s['rate']:.2f} %" for s in r["per_frequency"].values()) + " |")
    lines += ["", "## Power", "",
              f"`gain at {at} Hz`: condition B's gain × {args.change:g} at {at} Hz alone. "
              f"`W + {REWEIGHT:g}`: every subject's proprioceptive weight {REWEIGHT:g} higher "
              "in B (the whole FRF changes, most at the low frequencies).", "",
              f"| subjects | data sets | alternative | p < 0.05 at {at} Hz | the same, "
              f"max-T adjusted | whole FRF (Σ Q) | whole FRF, largest Q | other frequencies "
              "p < 0.05 | gain-ratio interval covers the population's | phase interval covers the "
              "population's |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for r in power:
        other = ("(every one changed)" if r["alternative"] != GAIN
                 else percent(r["per_frequency_pooled"]))
        lines.append(f"| {r['subjects']} | {r['data_sets']} | {r['alternative']} | "
                     f"{percent(r['per_frequency'][at])} | "
                     f"{percent(r['per_frequency_adjusted'][at])} | "
                     f"{percent(r['whole_frf'])} | {percent(r['whole_frf_largest_q'])} | "
                     f"{other} | {percent(r['gain_interval_coverage'])} | "
                     f"{percent(r['phase_interval_coverage'])} |")
    lines += ["", "The whole-FRF test sums the 11 frequencies' standardised statistics: a "
              "change at one frequency is diluted by the ten that did not change (the largest"
              " Q, or the per-frequency and max-T adjusted p-values, find it), while a change"
              " spread over the FRF is what the sum is for.", ""]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--null", type=int, default=4000,
                        help="null data sets per number of subjects (default %(default)d)")
    parser.add_argument("--power", type=int, default=2000,
                        help="data sets per alternative and number of subjects "
                             "(default %(default)d)")
    parser.add_argument("--subjects", type=int, nargs="+", default=[10, 20])
    parser.add_argument("--noise", type=float, default=0.15,
                        help="complex noise SD per trial, a share of the gain (default "
                             "%(default)g)")
    parser.add_argument("--change", type=float, default=1.2,
                        help="condition B's gain factor at 0.3 Hz (default %(default)g)")
    parser.add_argument("--permutations", type=int, default=2000)
    parser.add_argument("--pool", type=int, default=3000,
                        help="IC subjects drawn once, each data set's taken from them")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "results" / "paired_test")
    args = parser.parse_args()
    start = time.perf_counter()
    rng = np.random.default_rng(args.seed)
    pool = population(rng, args.pool)
    results = []
    for n in args.subjects:
        for alternative, count in (("null", args.null), (GAIN, args.power),
                                   (REWEIGHTED, args.power)):
            results.append(run(pool, n, count, alternative, args, rng))
            r = results[-1]
            print(f"{n} subjects, {alternative}: whole FRF {percent(r['whole_frf'])}, "
                  f"{F[AT]:g} Hz {percent(r['per_frequency'][f'{F[AT]:g}'])}", flush=True)
    seconds = time.perf_counter() - start
    defaults = parser.parse_args([])
    flags = [f"--{k.replace('_', '-')} {' '.join(map(str, v)) if isinstance(v, list) else v}"
             for k, v in vars(args).items() if k != "out" and v != getattr(defaults, k)]
    command = " ".join([".venv/bin/python benchmarks/paired_test.py", *flags])
    args.out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(args.out / "report.md", report(results, args, seconds, command))
    atomic_write_text(args.out / "results.json", json_text({
        "command": command, "seconds": seconds, "noise": args.noise, "change": args.change,
        "permutations": args.permutations, "pool": args.pool, "seed": args.seed,
        "frequencies_hz": F, "results": results}))
    print(f"wrote {args.out / 'report.md'} and results.json")


if __name__ == "__main__":
    main()
