"""``posture-id fit``: identify DEC parameters from a recording by least squares."""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

from posture_id.bodies.body import DEFAULT_URDF
from posture_id.cli.arguments import (
    check_out_and_plot,
    default_of,
    non_negative_float,
    non_negative_int,
    positive_float,
    positive_int,
    say,
    write_result,
)
from posture_id.cli.exit_status import answered
from posture_id.cli.markers import recording_body
from posture_id.cli.progress import TerminalProgress
from posture_id.cli.stimulus import (
    add_recording_arguments,
    prepared_trial,
)
from posture_id.dec.parameters import MAX_DELAY_S, PAPER_TABLE, DecParameters
from posture_id.errors import PostureIdError
from posture_id.fitting.options import (
    Compilation,
    ExhaustiveClasses,
    FitOptions,
    FixedClasses,
    RelaxedClasses,
)
from posture_id.frf.locked import LockedOptions

__all__ = ["add_parser", "run", "add_search_arguments", "search_keywords", "ic_answer"]


def add_parser(sub) -> None:
    fit = sub.add_parser("fit", help="identify DEC (or IC) parameters from a recording "
                                     "(least squares)")
    fit.add_argument("recording", type=Path, nargs="+",
                     help="recording CSV (time_s,tilt_deg,<seg>_deg...); several: one joint "
                          "fit of one subject's trials (docs/fit.md, \"One subject, several "
                          "trials\")")
    fit.add_argument("--body", type=Path, help="URDF (default: the TIP)")
    fit.add_argument("--model", choices=("dec", "ic"), default="dec",
                     help="dec (default) or ic: the independent-channel model fitted to the "
                          "stimulus-locked body COM sway (docs/model.md §8; seconds, no "
                          "simulation)")
    fit.add_argument("--fit-ki", action="store_true",
                     help="--model ic: also identify Ki (else 0, as the classic fits)")
    fit.add_argument("--init", type=Path, help="initial guess, parameter JSON (e.g. the CNN's)")
    fit.add_argument("--out", type=Path, required=True, help="fit result JSON to write")
    fit.add_argument("--plot", type=Path, help="recorded versus fitted sway (PNG)")
    fit.add_argument("--classes", choices=("relaxed", "exhaustive", "fixed"), default="relaxed",
                     help="how to find the classes (default: relaxed, then polished)")
    fit.add_argument("--starts", type=positive_int, default=default_of(RelaxedClasses, "starts"),
                     help="--classes relaxed: fits from the guess and from STARTS−1 prior "
                          "draws; the best is polished (guards against local minima)")
    fit.add_argument("--seed", type=non_negative_int, default=default_of(RelaxedClasses, "seed"),
                     help="--classes relaxed: seed of the prior draws (default %(default)d)")
    fit.add_argument("--no-compile", action="store_true",
                     help="run CasADi in its virtual machine (no C compiler)")
    fit.add_argument("--per-trial", nargs="+", metavar="NAME",
                     help="several recordings: the parameters that take one value per "
                          "condition (IC: W; DEC: a module's kp, ki, kd or delay_s, e.g. "
                          "ankle.kp); the rest are shared (default: every one shared)")
    fit.add_argument("--conditions", nargs="+", metavar="LABEL",
                     help="several recordings: one condition label per recording, in their "
                          "order (e.g. open open open closed closed closed; default: each "
                          "recording its own condition)")
    add_search_arguments(fit)
    add_recording_arguments(fit)
    fit.set_defaults(func=run)


def add_search_arguments(parser: argparse.ArgumentParser) -> None:
    """What the fit compares and where it searches: --locked [--max-frequency-hz
    --max-offset-s --prior-sd], --fit-passive, --gain-range and --delay-range (multiples of the
    defaults)."""
    parser.add_argument("--locked", action="store_true",
                        help="fit only the stimulus-locked sway (cycle average without offset "
                             "and drift, at the stimulated frequencies, weighted by the "
                             "recording's noise there): for real, noisy sway")
    parser.add_argument("--max-frequency-hz", type=positive_float,
                        default=default_of(LockedOptions, "max_frequency_hz"),
                        help="--locked: highest stimulated frequency compared "
                             "(default %(default)g Hz)")
    parser.add_argument("--max-offset-s", type=non_negative_float, default=0.0,
                        help="--locked: also fit a time offset of the stimulus within ±this, "
                             "at most half a cycle (a platform lag nobody measured, or a "
                             "lab's onset off its nominal one; default 0: none)")
    parser.add_argument("--prior-sd", type=positive_float,
                        help="--locked: maximum a posteriori with a Gaussian prior of this SD "
                             "on every normalised gain and delay, centred on the defaults "
                             "(docs/model.md §5 draws have 0.5)")
    parser.add_argument("--fit-passive", action="store_true",
                        help="also fit each module's passive stiffness and damping")
    low, high = _range_default("gain_bounds")
    parser.add_argument("--gain-range", type=non_negative_float, nargs=2, metavar=("MIN", "MAX"),
                        default=[low, high],
                        help="Kp, Ki and Kd are searched between MIN× and MAX× the body's "
                             f"default gains (default {low:g} {high:g})")
    low, high = _range_default("delay_bounds")
    parser.add_argument("--delay-range", type=non_negative_float, nargs=2,
                        metavar=("MIN", "MAX"), default=[low, high],
                        help="delays are searched between MIN× and MAX× the default delay "
                             f"(default {low:g} {high:g})")


def _range_default(bounds: str) -> list[float]:
    """--gain-range's or --delay-range's default: FitOptions' ``bounds`` as factors."""
    return [1 + b for b in default_of(FitOptions, bounds)]


def search_flags_given(args: argparse.Namespace) -> list[str]:
    """The flags of :func:`add_search_arguments` given a value other than their default."""
    defaults = {"--locked": False,
                "--max-frequency-hz": default_of(LockedOptions, "max_frequency_hz"),
                "--max-offset-s": 0.0, "--prior-sd": None, "--fit-passive": False,
                "--gain-range": _range_default("gain_bounds"),
                "--delay-range": _range_default("delay_bounds")}
    return [flag for flag, default in defaults.items()
            if getattr(args, flag[2:].replace("-", "_")) != default]  # a range: a list


def search_keywords(args: argparse.Namespace) -> dict:
    """FitOptions keywords of --locked, --prior-sd, --fit-passive, --gain-range and
    --delay-range (bounds normalised: factor − 1)."""
    if (args.prior_sd is not None or args.max_offset_s) and not args.locked:
        raise PostureIdError("--prior-sd and --max-offset-s go with --locked")
    out = {"locked": (LockedOptions(max_frequency_hz=args.max_frequency_hz,
                                    max_offset_s=args.max_offset_s) if args.locked
                      else None),
           "prior_sd": args.prior_sd, "fit_passive": args.fit_passive}
    for flag, key in (("--gain-range", "gain_bounds"), ("--delay-range", "delay_bounds")):
        low, high = getattr(args, key.replace("bounds", "range"))
        if not low < high:
            raise PostureIdError(f"{flag}: MIN must be below MAX, got {low:g} {high:g}")
        out[key] = (low - 1.0, high - 1.0)
    longest = args.delay_range[1] * max(m["delay_s"] for m in PAPER_TABLE.values())
    if longest > MAX_DELAY_S:
        raise PostureIdError(f"--delay-range: MAX {args.delay_range[1]:g}× the default delays "
                             f"reaches {longest:g} s, beyond the {MAX_DELAY_S:g} s a DEC delay "
                             "may be (a parameter file refuses it too)")
    return out


def options_from(args: argparse.Namespace) -> FitOptions:
    classes = {"relaxed": RelaxedClasses(starts=args.starts, seed=args.seed),
               "exhaustive": ExhaustiveClasses(), "fixed": FixedClasses()}[args.classes]
    return FitOptions(classes=classes,
                      compilation=Compilation.NEVER if args.no_compile else Compilation.AUTO,
                      **search_keywords(args))


def run(args: argparse.Namespace) -> int:
    recordings = list(args.recording)
    if len(recordings) > 1:
        return _fit_joint(args, recordings)
    given = [f for f, v in (("--per-trial", args.per_trial), ("--conditions", args.conditions))
             if v]
    if given:
        raise PostureIdError(f"{', '.join(given)}: go with several recordings (one recording "
                             "is one condition, every parameter its own)")
    args.recording = recordings[0]
    check_out_and_plot(args, (args.recording, args.body, args.init, args.tilt))
    if args.model == "ic":
        return ic_answer(args, _ic_options(args))
    options = _dec_options(args)
    body = recording_body(args, DEFAULT_URDF)
    trial = prepared_trial(args, body, options.simulation.sample_rate_hz)
    init = DecParameters.from_json(args.init, body) if args.init else None
    from posture_id.fitting.least_squares import fit_recording  # CasADi loads here

    with TerminalProgress(prefix="posture-id fit", quiet=True) as progress:
        result = fit_recording(trial, body, init, options, progress=progress)
    result = at_the_noise(result)
    write_result(result, args.out, args.plot)
    return answered(not result.converged)


#: The DEC fit's flags that mean nothing to the IC fit (it always compares the locked
#: harmonics and has its own bounds, docs/model.md §8).
_DEC_ONLY = ("--init", "--classes", "--no-compile", "--locked", "--max-offset-s",
             "--prior-sd", "--gain-range", "--delay-range")


def _ic_options(args: argparse.Namespace):
    """``fit --model ic``'s options (:class:`~posture_id.fitting.frequency.IcFitOptions`):
    the IC parameters of the recordings' locked COM sway; DEC's flags refused."""
    given = [f for f in search_flags_given(args) if f in _DEC_ONLY]
    given += [f for f, on in (("--init", args.init is not None),
                              ("--classes", args.classes != "relaxed"),
                              ("--no-compile", args.no_compile)) if on]
    if given:
        raise PostureIdError(f"{', '.join(given)}: DEC's fit only; --model ic fits the "
                             "stimulus-locked COM sway within docs/model.md §8's bounds")
    from posture_id.fitting.frequency import IcFitOptions

    return IcFitOptions(fit_ki=args.fit_ki, fit_passive=args.fit_passive, starts=args.starts,
                        seed=args.seed,
                        locked=LockedOptions(max_frequency_hz=args.max_frequency_hz))


def _dec_options(args: argparse.Namespace) -> FitOptions:
    """The DEC fit's options (:func:`options_from`); --fit-ki refused."""
    if args.fit_ki:
        raise PostureIdError("--fit-ki goes with --model ic (DEC's Ki is always identified)")
    return options_from(args)


def _fit_joint(args: argparse.Namespace, recordings: list[Path]) -> int:
    """``fit REC REC ... [--per-trial NAME ...] [--conditions LABEL ...]``: one joint fit
    of every recording (:func:`~posture_id.fitting.joint_conditions.fit_joint`), written to
    ``--out`` and ``--plot``."""
    from copy import copy

    from posture_id.fitting.joint_conditions import fit_joint, resolve_parameter
    from posture_id.models import model_named
    from posture_id.models.protocol import TrustLevel

    _each_trial_once(recordings)
    check_out_and_plot(args, (*recordings, args.body, args.tilt))
    if args.conditions is not None and len(args.conditions) != len(recordings):
        raise PostureIdError(f"--conditions: {len(args.conditions)} label(s) for "
                             f"{len(recordings)} recordings: give one label per recording")
    alone = [f for f, on in (("--init", args.init is not None),
                             ("--max-offset-s", bool(args.max_offset_s)),
                             ("--part", args.part is not None)) if on]
    if alone:
        raise PostureIdError(f"{', '.join(alone)}: go with one recording (a joint fit of "
                             "several starts from the first's own fit)")
    model = model_named(args.model)
    if args.model == "ic":
        options = _ic_options(args)  # --init: refused above, with the other one-recording flags
    else:
        options = _dec_options(args)
        if options.locked is None:  # the joint fit compares the locked harmonics
            options = replace(options, locked=LockedOptions(
                max_frequency_hz=args.max_frequency_hz))
    first = copy(args)
    first.recording = recordings[0]
    body = recording_body(first, DEFAULT_URDF)
    per = tuple(dict.fromkeys(resolve_parameter(model, body, name, options)
                              for name in args.per_trial or ()))
    names = [p.name for p in recordings]
    labels = list(args.conditions) if args.conditions is not None else (
        names if len(set(names)) == len(names) else [str(p) for p in recordings])
    trials = []
    for path in recordings:
        one = copy(args)
        one.recording = path
        trials.append(prepared_trial(one, body))
    with TerminalProgress(prefix="posture-id fit", quiet=True) as progress:
        result = fit_joint(model, trials, body, labels, per, options, progress=progress)
    for notice in (n for trial in trials for n in trial.notices):  # a refusal says its own
        say(notice)
    if not per:
        say(f"no --per-trial: every parameter is shared by the {len(trials)} trials, so "
            "nothing differs between them (one fit of them all); name what changes with the "
            "condition, e.g. --per-trial w")
    elif len(set(labels)) == 1:
        say(f"every trial is condition {labels[0]!r}: one condition, so nothing differs "
            f"between the trials ({', '.join(per)} take one value, as the shared ones); give "
            "each trial its condition (--conditions)")
    write_result(result, args.out, args.plot)
    return answered(result.trust_level is TrustLevel.DOUBTFUL)


def _each_trial_once(recordings: list[Path]) -> None:
    """Refuse a file given twice (by any path) and two files of the same bytes: a joint
    fit would count one trial twice."""
    from posture_id.fileio import file_sha256

    seen: dict[Path, Path] = {}
    contents: dict[str, Path] = {}
    for path in recordings:
        key = path.resolve()
        if key in seen:
            raise PostureIdError(f"{path}: given twice (as {seen[key]} and {path}): a joint "
                                 "fit counts each trial once")
        seen[key] = path
        if path.is_file():
            digest = file_sha256(path)
            if digest in contents:
                raise PostureIdError(f"{path}: the same bytes as {contents[digest]}: the same "
                                     "trial twice (a copied file?); a joint fit counts each "
                                     "trial once")
            contents[digest] = path


def ic_answer(args: argparse.Namespace, options) -> int:
    """The IC fit (``options``: :class:`~posture_id.fitting.frequency.IcFitOptions`) of
    ``args.recording``
    for its body, written to ``--out`` and ``--plot`` (the recording printed without)."""
    from posture_id.fitting.frequency import fit_ic

    body = recording_body(args, DEFAULT_URDF)
    trial = prepared_trial(args, body)
    result = fit_ic(trial, body, options)
    for notice in trial.notices:  # what was found on the way in (a refusal says its own)
        say(notice)
    write_result(result, args.out, args.plot)
    return answered(result.trust_level == "doubtful")


def at_the_noise(result):
    """A fit that stopped short of its tolerance with a residual the recording's own noise
    explains (:func:`~posture_id.identify.noise_check.noise_check`) is converged as far as
    the recording can tell: said so, exit status 0 (issue 46: a locked fit whose residual
    was the recording's 0.05° exited 1, "NOT converged")."""
    if result.converged:
        return result
    from posture_id.identify.noise_check import noise_check  # loads torch: only here

    check = noise_check(result.trial, result.fitted)
    if not check.consistent:
        return result
    return replace(result, converged=True, notices=(*result.notices, (
        f"the optimiser stopped short of its tolerance, with a residual the recording's own "
        f"noise explains ({check.basis}, {check.ratio:.2f}× the noise): converged as far as "
        "the recording can tell")))
